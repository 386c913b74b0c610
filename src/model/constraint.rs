//! Nonholonomic constraints and the generalized speeds they leave: the *simple
//! nonholonomic* systems of [P, Sect. 2].
//!
//! ## The constraints
//!
//! A [`Constraint`] is a blade on a body: the velocity of a body point `P` across a
//! body-fixed direction `d` is zero,
//!
//! ```text
//! n · v^P = 0,      n = perp(d) (world),   v^P = Σ_r v_r^P v_r + v_t^P
//! ```
//!
//! linear in the tree speeds `v` (the joint rates) with the remainder `n · v_t^P` of the
//! prescribed motions: one row of `C(q, t) v + c(q, t) = 0`. A knife edge (a skate, a
//! sled's runner) and a wheel that rolls without side slip on the plane impose the same
//! constraint in a planar model; [`ConstraintKind`] keeps what the user wrote.
//!
//! ## The speeds
//!
//! The tree has one *tree speed* per coordinate (`nv = nq`): the joint rates, except that
//! the planar joint of a body that carries a constraint is given **body-frame speeds**
//! `(vx_body, vy_body, omega)`, the velocity of the body's origin relative to its parent
//! along the body's own axes and its rate of turn, so that `q̇ = (R(θ) (vx, vy), ω)`. In
//! these speeds a blade on its own body has constant coefficients whatever the body's
//! heading (with world-frame rates `ẋ, ẏ` the sleigh's blade would make `ẏ` unsolvable
//! whenever it points along `y`).
//!
//! Each constraint removes one speed of its own body's joint, the one with the largest
//! constant coefficient after the earlier constraints of that joint (a translation before
//! a rotation), or the speed named by [`Constraint::removes`] (any speed of the body's
//! joint or of an ancestor's). The `p = nv − m` speeds left are the generalized speeds
//! `u` of the model, in tree order; the removed ones follow from them,
//!
//! ```text
//! v = S(q, t) u + s(q, t),    S = [I; −C_d⁻¹ C_i],  s = [0; −C_d⁻¹ c]   (rows permuted)
//! q̇ = T(q) v = A(q, t) u + b(q, t),   A = T S,  b = T s
//! ```
//!
//! the kinematic equations `q̇ = A u + b` of [P, Eq. (1)]. Holonomic models have no
//! constraint: `u = v = q̇`, `A = I`.

use crate::math::{Real, Vec2};

use super::{BodyId, JointId};

/// How a constraint came to be written; the kinematics is the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConstraintKind {
    /// A knife edge: a skate, a sled's runner, the Chaplygin sleigh's blade.
    KnifeEdge,
    /// A wheel that rolls without side slip on the plane (its spin adds no coordinate).
    Wheel,
}

impl ConstraintKind {
    /// `knife_edge` or `wheel`, as in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            ConstraintKind::KnifeEdge => "knife_edge",
            ConstraintKind::Wheel => "wheel",
        }
    }
}

/// A nonholonomic constraint: the point `point` of `body` moves only along `direction`
/// (see the documentation of `src/model/constraint.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Unique name among constraints.
    pub name: String,
    /// What it is.
    pub kind: ConstraintKind,
    /// The body that carries it.
    pub body: BodyId,
    /// The blade's contact point `P` (m, body frame).
    pub point: Vec2,
    /// The blade's direction `d` (body frame): `P` moves along it, never across. Any
    /// non-zero length; normalized by the builder.
    pub direction: Vec2,
    /// The speed this constraint removes, by name; `None` for the default rule.
    pub removes: Option<String>,
}

impl Constraint {
    /// A knife edge on `body` at `point` along `direction` (body frame).
    pub fn knife_edge(name: impl Into<String>, body: BodyId, point: Vec2, direction: Vec2) -> Self {
        Constraint {
            name: name.into(),
            kind: ConstraintKind::KnifeEdge,
            body,
            point,
            direction,
            removes: None,
        }
    }

    /// A wheel on `body` rolling without side slip at `point` along `direction`.
    pub fn wheel(name: impl Into<String>, body: BodyId, point: Vec2, direction: Vec2) -> Self {
        Constraint {
            kind: ConstraintKind::Wheel,
            ..Constraint::knife_edge(name, body, point, direction)
        }
    }

    /// This constraint removing the speed named `speed`.
    pub fn removing(mut self, speed: impl Into<String>) -> Self {
        self.removes = Some(speed.into());
        self
    }

    /// The unit normal `n = perp(d)` of the blade (body frame).
    #[inline]
    pub fn normal(&self) -> Vec2 {
        crate::math::perp(self.direction)
    }
}

/// One tree speed (see the documentation of `src/model/constraint.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct Speed {
    /// `"<joint>.<suffix>"`: the coordinate's name for a joint rate, `"<joint>.vx_body"`,
    /// `"<joint>.vy_body"`, `"<joint>.omega"` for body-frame speeds.
    pub name: String,
    /// The joint it belongs to.
    pub joint: JointId,
    /// Its index among the joint's speeds.
    pub dof: usize,
    /// `true` for a rate of turn (rad/s), `false` for a velocity (m/s).
    pub is_angle: bool,
    /// The constraint that removes it, if any (then it is not a generalized speed).
    pub removed_by: Option<usize>,
}

/// The role of a tree speed in the model's speeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpeedRole {
    /// The generalized speed `u[i]`.
    Independent(usize),
    /// Removed by constraint `k`.
    Dependent(usize),
}

/// The smallest constant coefficient (m/s per unit speed, or m per rad/s) a constraint
/// may remove a speed by: below it the blade does not involve the speed.
pub(crate) const MIN_COEFFICIENT: Real = 1e-9;
