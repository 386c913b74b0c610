//! Joints: how a body moves relative to its parent, the generalized coordinates this
//! introduces, prescribed (rheonomic) motions and joint force elements.

use crate::math::{Pose, Real, Vec2};

use super::BodyId;

/// The kind of a joint and the coordinates it introduces. The motion of the child's frame
/// relative to the joint frame is, for the joint coordinates `q`:
///
/// | kind | coordinates | child frame in the joint frame |
/// |---|---|---|
/// | `Revolute` | angle `q` (rad) | `Rot(q)` |
/// | `Prismatic` | displacement `q` (m) | `Trans(q a)`, `a` the unit axis |
/// | `Translation` | `x, y` (m) | `Trans(x, y)` |
/// | `Planar` | `x, y` (m), `θ` (rad) | `Trans(x, y) · Rot(θ)` |
/// | `Fixed` | none | identity |
///
/// For every kind the generalized speeds are the coordinate rates, `u = q̇`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointKind {
    /// A pin: one angle (rad), counter-clockwise positive.
    Revolute {
        /// If `true`, the angle is measured from the world's axes (turned by the
        /// placement's rotation) instead of the parent's, as the paper's double pendulum
        /// does [P, Sect. 5]: the body's world orientation is `φ = φ_placement + q`
        /// whatever the parent's orientation. Physically the same pin; only the coordinate
        /// differs. A spring, damper or effort on an absolute joint acts on the absolute
        /// angle, i.e. between the body and the world.
        absolute: bool,
    },
    /// A slider along a fixed axis of the joint frame: one displacement (m).
    Prismatic {
        /// Unit direction of the slide (joint frame).
        axis: Vec2,
    },
    /// Free translation without rotation: `x, y` (m) along the joint frame's axes. A
    /// particle needs no more.
    Translation,
    /// Free planar motion: `x, y` (m) of the body frame's origin along the joint frame's
    /// axes, then its rotation `θ` (rad).
    Planar,
    /// A weld: no coordinate.
    Fixed,
}

impl JointKind {
    /// The number of joint coordinates (0 to 3).
    #[inline]
    pub fn ndof(&self) -> usize {
        match self {
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
            JointKind::Translation => 2,
            JointKind::Planar => 3,
            JointKind::Fixed => 0,
        }
    }

    /// `true` for a revolute joint whose angle is measured from the world.
    #[inline]
    pub fn is_absolute(&self) -> bool {
        matches!(self, JointKind::Revolute { absolute: true })
    }

    /// The suffixes of the coordinate names (`"<joint>.<suffix>"`).
    pub fn coordinate_suffixes(&self) -> &'static [&'static str] {
        match self {
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => &["q"],
            JointKind::Translation => &["x", "y"],
            JointKind::Planar => &["x", "y", "theta"],
            JointKind::Fixed => &[],
        }
    }

    /// Whether joint coordinate `k` is an angle (rad) rather than a length (m).
    pub fn is_angle(&self, k: usize) -> bool {
        match self {
            JointKind::Revolute { .. } => k == 0,
            JointKind::Planar => k == 2,
            _ => false,
        }
    }

    /// A short lowercase name: `revolute`, `prismatic`, `translation`, `planar`, `fixed`.
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Translation => "translation",
            JointKind::Planar => "planar",
            JointKind::Fixed => "fixed",
        }
    }
}

/// A prescribed (rheonomic) motion of a one-coordinate joint,
///
/// ```text
/// q(t) = q₀ + ω t + A sin(Ω t + φ)
/// ```
///
/// (rad or m). Its coordinate is not a generalized coordinate of the model: it is a known
/// function of time, and its rate is the source of the remainder velocity `v_t` of
/// [P, Eq. (2)] (the paper's Appendix B spins a disk at a constant rate this way).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PrescribedMotion {
    /// Position at `t = 0` (without the harmonic term) `q₀` (rad or m).
    pub q0: Real,
    /// Constant rate `ω` (rad/s or m/s).
    pub rate: Real,
    /// Amplitude of the harmonic term `A` (rad or m).
    pub amplitude: Real,
    /// Angular frequency of the harmonic term `Ω` (rad/s).
    pub angular_frequency: Real,
    /// Phase of the harmonic term `φ` (rad).
    pub phase: Real,
}

impl PrescribedMotion {
    /// The motion at constant rate, `q(t) = q₀ + ω t`.
    pub fn constant_rate(q0: Real, rate: Real) -> Self {
        PrescribedMotion {
            q0,
            rate,
            ..Default::default()
        }
    }

    /// The position `q(t) = q₀ + ω t + A sin(Ω t + φ)` (rad or m).
    #[inline]
    pub fn position(&self, t: Real) -> Real {
        self.q0 + self.rate * t + self.amplitude * (self.angular_frequency * t + self.phase).sin()
    }

    /// The rate `q̇(t) = ω + A Ω cos(Ω t + φ)` (rad/s or m/s).
    #[inline]
    pub fn velocity(&self, t: Real) -> Real {
        let w = self.angular_frequency;
        self.rate + self.amplitude * w * (w * t + self.phase).cos()
    }

    /// The acceleration `q̈(t) = −A Ω² sin(Ω t + φ)` (rad/s² or m/s²).
    #[inline]
    pub fn acceleration(&self, t: Real) -> Real {
        let w = self.angular_frequency;
        -self.amplitude * w * w * (w * t + self.phase).sin()
    }

    /// `true` if every parameter is finite.
    pub fn is_finite(&self) -> bool {
        [
            self.q0,
            self.rate,
            self.amplitude,
            self.angular_frequency,
            self.phase,
        ]
        .iter()
        .all(|x| x.is_finite())
    }
}

/// Force elements of a one-coordinate joint: a linear spring, a linear damper and a
/// constant effort. Their generalized force on the joint coordinate is
///
/// ```text
/// Q = −k (q − q_rest) − c q̇ + τ
/// ```
///
/// and the spring stores the potential energy `½ k (q − q_rest)²`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointForce {
    /// Spring stiffness `k` (N·m/rad for an angle, N/m for a length), non-negative.
    pub stiffness: Real,
    /// Rest position of the spring `q_rest` (rad or m).
    pub rest: Real,
    /// Damping coefficient `c` (N·m·s/rad or N·s/m), non-negative.
    pub damping: Real,
    /// Constant applied effort `τ` (N·m or N), along the coordinate.
    pub effort: Real,
}

impl JointForce {
    /// `true` if the joint carries no force element.
    pub fn is_zero(&self) -> bool {
        self.stiffness == 0.0 && self.damping == 0.0 && self.effort == 0.0
    }

    /// The generalized force `Q = −k (q − q_rest) − c q̇ + τ` (N·m or N) at the coordinate
    /// `q` and rate `q̇`.
    #[inline]
    pub fn generalized_force(&self, q: Real, qd: Real) -> Real {
        -self.stiffness * (q - self.rest) - self.damping * qd + self.effort
    }

    /// The spring's potential energy `½ k (q − q_rest)²` (J).
    #[inline]
    pub fn potential_energy(&self, q: Real) -> Real {
        0.5 * self.stiffness * (q - self.rest) * (q - self.rest)
    }
}

/// The joint that attaches a body to its parent (a body or the world).
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Unique name; coordinates are named `"<name>.<suffix>"` (see
    /// [`JointKind::coordinate_suffixes`]). A scene names a joint after its body.
    pub name: String,
    /// The kind of joint.
    pub kind: JointKind,
    /// The parent body, `None` for the world.
    pub parent: Option<BodyId>,
    /// Pose of the joint frame in the parent's frame (the world frame for the world): its
    /// translation is the joint's position (m), its rotation the orientation at which the
    /// joint coordinates are zero. For an absolute revolute joint the rotation is taken
    /// relative to the world.
    pub placement: Pose,
    /// A prescribed motion of the joint's coordinate (one-coordinate joints only); `None`
    /// if its coordinate is a generalized coordinate.
    pub drive: Option<PrescribedMotion>,
    /// Spring, damper and constant effort (one-coordinate, free joints only).
    pub force: JointForce,
}

impl Joint {
    /// A joint of kind `kind` to `parent` (`None`: the world) at `placement`, free, with
    /// no force element.
    pub fn new(
        name: impl Into<String>,
        kind: JointKind,
        parent: Option<BodyId>,
        placement: Pose,
    ) -> Self {
        Joint {
            name: name.into(),
            kind,
            parent,
            placement,
            drive: None,
            force: JointForce::default(),
        }
    }

    /// A revolute joint whose angle is measured from the parent's frame.
    pub fn revolute(name: impl Into<String>, parent: Option<BodyId>, placement: Pose) -> Self {
        Joint::new(
            name,
            JointKind::Revolute { absolute: false },
            parent,
            placement,
        )
    }

    /// A revolute joint whose angle is measured from the world's axes (see
    /// [`JointKind::Revolute`]).
    pub fn revolute_absolute(
        name: impl Into<String>,
        parent: Option<BodyId>,
        placement: Pose,
    ) -> Self {
        Joint::new(
            name,
            JointKind::Revolute { absolute: true },
            parent,
            placement,
        )
    }

    /// A prismatic joint along the unit `axis` (joint frame).
    pub fn prismatic(
        name: impl Into<String>,
        parent: Option<BodyId>,
        placement: Pose,
        axis: Vec2,
    ) -> Self {
        Joint::new(name, JointKind::Prismatic { axis }, parent, placement)
    }

    /// A planar (x, y, θ) joint.
    pub fn planar(name: impl Into<String>, parent: Option<BodyId>, placement: Pose) -> Self {
        Joint::new(name, JointKind::Planar, parent, placement)
    }

    /// A translation (x, y) joint.
    pub fn translation(name: impl Into<String>, parent: Option<BodyId>, placement: Pose) -> Self {
        Joint::new(name, JointKind::Translation, parent, placement)
    }

    /// A fixed joint (weld).
    pub fn fixed(name: impl Into<String>, parent: Option<BodyId>, placement: Pose) -> Self {
        Joint::new(name, JointKind::Fixed, parent, placement)
    }

    /// This joint with its coordinate driven by `motion`.
    pub fn with_drive(mut self, motion: PrescribedMotion) -> Self {
        self.drive = Some(motion);
        self
    }

    /// This joint with the force elements `force`.
    pub fn with_force(mut self, force: JointForce) -> Self {
        self.force = force;
        self
    }

    /// `true` for a revolute joint whose angle is measured from the world.
    #[inline]
    pub fn is_absolute(&self) -> bool {
        self.kind.is_absolute()
    }
}
