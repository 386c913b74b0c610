//! Colliders (parry2d shapes placed on bodies or in the world), contact materials and the
//! pairs of colliders that may touch.

use parry2d_f64::shape::SharedShape;

use crate::impact::Law;
use crate::math::{Pose, Real};

use super::{BodyId, ColliderId};

/// A shape attached to a body, or fixed in the world.
#[derive(Clone, Debug)]
pub struct Collider {
    /// Unique name (a scene names body shapes `"<body>"` or `"<body>/<k>"`, obstacles by
    /// their own name).
    pub name: String,
    /// The body carrying the shape; `None` for a static obstacle of the world.
    pub body: Option<BodyId>,
    /// The parry2d shape, in its own local frame.
    pub shape: SharedShape,
    /// Pose of the shape's local frame in the body frame (the world frame for an obstacle).
    pub pose: Pose,
}

impl Collider {
    /// A collider named `name` with `shape` at `pose` on `body` (`None`: the world).
    pub fn new(
        name: impl Into<String>,
        body: Option<BodyId>,
        shape: SharedShape,
        pose: Pose,
    ) -> Self {
        Collider {
            name: name.into(),
            body,
            shape,
            pose,
        }
    }
}

/// The contact material of a pair: the impact law and its coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// The impact law.
    pub law: Law,
    /// Coefficient of restitution `e` (dimensionless), `0 ≤ e ≤ 1` [P, Eq. (30)].
    pub e: Real,
    /// Coulomb's coefficient of friction `μ` (dimensionless), `μ ≥ 0` [P, Eq. (31)].
    pub mu: Real,
}

impl Default for Material {
    /// Newton's law, `e = 0`, `μ = 0`.
    fn default() -> Self {
        Material {
            law: Law::Newton,
            e: 0.0,
            mu: 0.0,
        }
    }
}

/// Two colliders that may touch, with their material. `a` is on a body; `b` is on another
/// body or in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPair {
    /// First collider (on a body).
    pub a: ColliderId,
    /// Second collider (on another body, or an obstacle of the world).
    pub b: ColliderId,
    /// The material of the pair.
    pub material: Material,
}
