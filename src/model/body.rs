//! Rigid bodies: mass, centre of mass and rotational inertia.

use crate::math::{Real, Vec2};

/// A rigid body of the kinematic tree. Its frame is attached to it; its joint
/// ([`super::Joint`]) places that frame relative to the parent.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Unique name, used in scene files, coordinate names and logs.
    pub name: String,
    /// Mass `m` (kg), positive.
    pub mass: Real,
    /// Centre of mass `c` (m, body frame).
    pub com: Vec2,
    /// Moment of inertia about the centre of mass `I_c` (kg·m²), positive.
    pub inertia: Real,
}

impl Body {
    /// A body named `name` of mass `mass` (kg), centre of mass `com` (m, body frame) and
    /// moment of inertia `inertia` (kg·m²) about its centre of mass.
    pub fn new(name: impl Into<String>, mass: Real, com: Vec2, inertia: Real) -> Self {
        Body {
            name: name.into(),
            mass,
            com,
            inertia,
        }
    }
}
