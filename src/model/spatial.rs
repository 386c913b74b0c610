//! Planar spatial algebra: twists, wrenches and rigid-body inertias in world coordinates,
//! referred to the world origin `O` [F, ch. 2, planar vectors].
//!
//! A planar rigid motion has three components, one angular and two linear, and so has a
//! planar force system. All three types here are expressed in the world frame and referred
//! to the world origin `O` (Featherstone's "world coordinates"): this keeps every
//! propagation step a plain addition and makes the only frame-dependent operation the
//! projection of an *absolute* revolute joint (see [`Twist::projected_at`]).
//!
//! | type | components | meaning |
//! |---|---|---|
//! | [`Twist`] | `(ω, v_O)` | angular velocity (rad/s) and velocity (m/s) of the body point at `O` |
//! | [`Wrench`] | `(n_O, f)` | moment about `O` (N·m) and resultant force (N) |
//! | [`Inertia`] | `(m, m c, I_O)` | mass (kg), first moment (kg·m), moment of inertia about `O` (kg·m²) |
//!
//! The velocity of the body point at `p` is `v(p) = v_O + ω perp(p)`; the power of a wrench
//! on a twist is `ω n_O + v_O·f`.

use std::ops::{Add, AddAssign, Mul, Neg, Sub};

use crate::math::{Real, Vec2, cross, perp};

/// A planar twist (spatial motion vector) `(ω, v_O)` in world coordinates, referred to the
/// world origin `O`. As a velocity: rad/s and m/s; as an acceleration (its time
/// derivative): rad/s² and m/s²; as a joint motion subspace column: per unit rate of the
/// joint coordinate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    /// Angular component `ω` (rad/s), about the world `z` axis, counter-clockwise positive.
    pub w: Real,
    /// Linear component `v_O` (m/s, world frame): the velocity of the body point that is at
    /// the world origin at this instant.
    pub v: Vec2,
}

impl Twist {
    /// The zero twist.
    pub const ZERO: Twist = Twist {
        w: 0.0,
        v: Vec2::ZERO,
    };

    /// A twist from its angular and linear components.
    #[inline]
    pub const fn new(w: Real, v: Vec2) -> Self {
        Twist { w, v }
    }

    /// The twist of a rotation at unit rate about the world point `a`: `(1, −perp(a))`,
    /// so that `v(p) = perp(p − a)`.
    #[inline]
    pub fn rotation_about(a: Vec2) -> Self {
        Twist::new(1.0, -perp(a))
    }

    /// The twist of a translation at unit rate along the world direction `d`: `(0, d)`.
    #[inline]
    pub fn translation_along(d: Vec2) -> Self {
        Twist::new(0.0, d)
    }

    /// The velocity of the body point at the world position `p`: `v(p) = v_O + ω perp(p)`
    /// (m/s, world frame).
    #[inline]
    pub fn velocity_at(&self, p: Vec2) -> Vec2 {
        self.v + perp(p) * self.w
    }

    /// The projection `P(a)` of an absolute revolute joint at the world point `a`:
    /// `P(a) (ω, v_O) = (0, v_O + ω perp(a))`, the pure translation with the velocity that
    /// this twist gives to the point `a`.
    ///
    /// A body hinged at `a` whose angle is measured from the world (an *absolute* revolute
    /// joint) is carried along by its parent's motion without being turned by it, so the
    /// parent's twist reaches it through `P(a)`.
    #[inline]
    pub fn projected_at(&self, a: Vec2) -> Twist {
        Twist::new(0.0, self.velocity_at(a))
    }

    /// The power `ω n_O + v_O·f` (W) of the wrench `f` on this twist (or the generalized
    /// force of `f` along this motion subspace column).
    #[inline]
    pub fn dot(&self, f: &Wrench) -> Real {
        self.w * f.n + self.v.dot(f.f)
    }

    /// The spatial cross product for motions, `(ω₁, v₁) ×ₘ (ω₂, v₂) = (0, ω₁ perp(v₂) −
    /// ω₂ perp(v₁))` ([F, ch. 2], planar form): the rate of change of a twist `m₂` fixed in a
    /// body that moves with this twist.
    #[inline]
    pub fn cross_motion(&self, m: &Twist) -> Twist {
        Twist::new(0.0, perp(m.v) * self.w - perp(self.v) * m.w)
    }

    /// The spatial cross product for forces, `(ω, v) ×* (n, f) = (v × f, ω perp(f))`
    /// ([F, ch. 2], planar form), with `v × f = v_x f_y − v_y f_x`.
    #[inline]
    pub fn cross_force(&self, f: &Wrench) -> Wrench {
        Wrench::new(cross(self.v, f.f), perp(f.f) * self.w)
    }

    /// `true` if both components are finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.w.is_finite() && self.v.is_finite()
    }
}

impl Add for Twist {
    type Output = Twist;
    #[inline]
    fn add(self, o: Twist) -> Twist {
        Twist::new(self.w + o.w, self.v + o.v)
    }
}

impl AddAssign for Twist {
    #[inline]
    fn add_assign(&mut self, o: Twist) {
        self.w += o.w;
        self.v += o.v;
    }
}

impl Sub for Twist {
    type Output = Twist;
    #[inline]
    fn sub(self, o: Twist) -> Twist {
        Twist::new(self.w - o.w, self.v - o.v)
    }
}

impl Neg for Twist {
    type Output = Twist;
    #[inline]
    fn neg(self) -> Twist {
        Twist::new(-self.w, -self.v)
    }
}

impl Mul<Real> for Twist {
    type Output = Twist;
    #[inline]
    fn mul(self, s: Real) -> Twist {
        Twist::new(self.w * s, self.v * s)
    }
}

/// A planar wrench (spatial force vector) `(n_O, f)` in world coordinates, referred to the
/// world origin `O`. As a force: N·m and N; as a rate of momentum: the same units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench {
    /// Moment about the world origin `n_O` (N·m), counter-clockwise positive.
    pub n: Real,
    /// Resultant force `f` (N, world frame).
    pub f: Vec2,
}

impl Wrench {
    /// The zero wrench.
    pub const ZERO: Wrench = Wrench {
        n: 0.0,
        f: Vec2::ZERO,
    };

    /// A wrench from its moment about `O` and its resultant.
    #[inline]
    pub const fn new(n: Real, f: Vec2) -> Self {
        Wrench { n, f }
    }

    /// The wrench of the force `f` applied at the world point `p`: `(p × f, f)`.
    #[inline]
    pub fn force_at(f: Vec2, p: Vec2) -> Self {
        Wrench::new(cross(p, f), f)
    }

    /// The transpose of the projection [`Twist::projected_at`]: `P(a)ᵀ (n, f) = (a × f, f)`.
    /// A wrench acting on a body behind an absolute revolute joint at `a` reaches the
    /// ancestors as its resultant applied at `a`; its moment is taken by the coordinate of
    /// the absolute joint.
    #[inline]
    pub fn projected_at(&self, a: Vec2) -> Wrench {
        Wrench::new(cross(a, self.f), self.f)
    }
}

impl Add for Wrench {
    type Output = Wrench;
    #[inline]
    fn add(self, o: Wrench) -> Wrench {
        Wrench::new(self.n + o.n, self.f + o.f)
    }
}

impl AddAssign for Wrench {
    #[inline]
    fn add_assign(&mut self, o: Wrench) {
        self.n += o.n;
        self.f += o.f;
    }
}

impl Sub for Wrench {
    type Output = Wrench;
    #[inline]
    fn sub(self, o: Wrench) -> Wrench {
        Wrench::new(self.n - o.n, self.f - o.f)
    }
}

/// The planar spatial inertia of a rigid body (or of a group of bodies) in world
/// coordinates, referred to the world origin `O` [F, ch. 2, planar vectors]:
///
/// ```text
///        ⎡ I_O        m perp(c)ᵀ ⎤
///   I =  ⎢                       ⎥ ,   I_O = I_c + m |c|²
///        ⎣ m perp(c)  m 1₂       ⎦
/// ```
///
/// so that the kinetic energy of a body moving with the twist `V` is `½ Vᵀ I V`
/// `= ½ m |v_c|² + ½ I_c ω²` [P, Eq. (70)], with `v_c = v_O + ω perp(c)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inertia {
    /// Mass `m` (kg).
    pub m: Real,
    /// First moment of mass about the world origin `m c` (kg·m, world frame), `c` the
    /// centre of mass.
    pub h: Vec2,
    /// Moment of inertia about the world origin `I_O = I_c + m |c|²` (kg·m²).
    pub i_o: Real,
}

impl Inertia {
    /// The zero inertia.
    pub const ZERO: Inertia = Inertia {
        m: 0.0,
        h: Vec2::ZERO,
        i_o: 0.0,
    };

    /// The inertia of a body of mass `m` (kg) with its centre of mass at the world point
    /// `c` (m) and the moment of inertia `i_c` (kg·m²) about it.
    #[inline]
    pub fn from_body(m: Real, c: Vec2, i_c: Real) -> Self {
        Inertia {
            m,
            h: c * m,
            i_o: i_c + m * c.length_squared(),
        }
    }

    /// `P(a)ᵀ I P(a)`: the inertia that a group of bodies behind an absolute revolute joint
    /// at `a` presents to its ancestors. Since the ancestors only translate it, it is that
    /// of a point of mass `m` at `a`: `(m, m a, m |a|²)`.
    #[inline]
    pub fn projected_at(&self, a: Vec2) -> Inertia {
        Inertia {
            m: self.m,
            h: a * self.m,
            i_o: self.m * a.length_squared(),
        }
    }

    /// The momentum `I V = (I_O ω + (m c) × v_O, m v_O + ω perp(m c))`: angular momentum
    /// about `O` (kg·m²/s) and linear momentum (kg·m/s). Also the product of the inertia
    /// with a motion subspace column or an acceleration.
    #[inline]
    pub fn mul_twist(&self, s: &Twist) -> Wrench {
        Wrench::new(
            self.i_o * s.w + cross(self.h, s.v),
            s.v * self.m + perp(self.h) * s.w,
        )
    }

    /// The kinetic energy `½ Vᵀ I V` (J) of this inertia moving with the twist `V`.
    #[inline]
    pub fn kinetic_energy(&self, v: &Twist) -> Real {
        0.5 * v.dot(&self.mul_twist(v))
    }
}

impl Add for Inertia {
    type Output = Inertia;
    #[inline]
    fn add(self, o: Inertia) -> Inertia {
        Inertia {
            m: self.m + o.m,
            h: self.h + o.h,
            i_o: self.i_o + o.i_o,
        }
    }
}

impl AddAssign for Inertia {
    #[inline]
    fn add_assign(&mut self, o: Inertia) {
        self.m += o.m;
        self.h += o.h;
        self.i_o += o.i_o;
    }
}
