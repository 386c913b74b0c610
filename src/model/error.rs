//! Errors found while building a [`super::Model`].

use crate::math::{Real, Shown};

/// A model that cannot be built, with the evidence.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// Two bodies, joints or colliders share a name.
    #[error("duplicate {what} name `{name}`")]
    DuplicateName {
        /// `"body"`, `"joint"` or `"collider"`.
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A body's mass is not a positive finite number.
    #[error("body `{body}`: the mass must be positive and finite, got {mass} kg", mass = Shown(*.mass))]
    BadMass {
        /// The body.
        body: String,
        /// The mass (kg).
        mass: Real,
    },
    /// A body's moment of inertia is not a positive finite number.
    #[error(
        "body `{body}`: the moment of inertia must be positive and finite, got {inertia} kg·m²",
        inertia = Shown(*.inertia)
    )]
    BadInertia {
        /// The body.
        body: String,
        /// The moment of inertia (kg·m²).
        inertia: Real,
    },
    /// A number of the model is not finite.
    #[error("{what} is not finite ({value})")]
    NonFinite {
        /// What the number is, e.g. "body `rod` centre of mass".
        what: String,
        /// The offending value, printed.
        value: String,
    },
    /// A joint's parent is not a body added before its child (unknown body, or a cycle).
    #[error(
        "joint `{joint}`: parent body #{parent} is not a body added before it (bodies #0..#{child}); parents come before children, so the tree has no cycle"
    )]
    BadParent {
        /// The joint.
        joint: String,
        /// Index of the parent body given.
        parent: usize,
        /// Index of the child body.
        child: usize,
    },
    /// A prismatic joint's axis is zero or not finite.
    #[error(
        "joint `{joint}`: the prismatic axis must be a finite non-zero vector, got ({x}, {y})",
        x = Shown(*.x), y = Shown(*.y)
    )]
    BadAxis {
        /// The joint.
        joint: String,
        /// Axis x component.
        x: Real,
        /// Axis y component.
        y: Real,
    },
    /// A prescribed motion on a joint that does not have exactly one coordinate.
    #[error("joint `{joint}`: only revolute and prismatic joints can be prescribed, not {kind}")]
    DriveOnMultiDof {
        /// The joint.
        joint: String,
        /// Its kind.
        kind: &'static str,
    },
    /// Force elements on a joint that is not a free one-coordinate joint.
    #[error(
        "joint `{joint}`: springs, dampers and efforts act on free revolute or prismatic joints only ({reason})"
    )]
    ForceNotAllowed {
        /// The joint.
        joint: String,
        /// Why.
        reason: &'static str,
    },
    /// A negative spring stiffness or damping coefficient.
    #[error("joint `{joint}`: {what} must be non-negative, got {value}", value = Shown(*.value))]
    NegativeCoefficient {
        /// The joint.
        joint: String,
        /// `"stiffness"` or `"damping"`.
        what: &'static str,
        /// The value.
        value: Real,
    },
    /// A collider refers to a body that does not exist.
    #[error("collider `{collider}`: body #{body} does not exist")]
    UnknownBody {
        /// The collider.
        collider: String,
        /// Index of the body given.
        body: usize,
    },
    /// A pair rule refers to a collider that does not exist.
    #[error("contact pair: collider #{collider} does not exist")]
    UnknownCollider {
        /// Index of the collider given.
        collider: usize,
    },
    /// A pair rule names two colliders that cannot form a pair.
    #[error("contact pair `{a}`–`{b}`: {reason}")]
    BadPair {
        /// First collider.
        a: String,
        /// Second collider.
        b: String,
        /// Why the pair is impossible.
        reason: &'static str,
    },
    /// A material coefficient out of range.
    #[error(
        "contact pair `{a}`–`{b}`: {what} = {value} is out of range ({range})",
        value = Shown(*.value)
    )]
    BadMaterial {
        /// First collider.
        a: String,
        /// Second collider.
        b: String,
        /// `"e"` or `"mu"`.
        what: &'static str,
        /// The value.
        value: Real,
        /// The allowed range.
        range: &'static str,
    },
    /// A nonholonomic constraint that cannot be built.
    #[error("constraint `{constraint}`: {reason}")]
    BadConstraint {
        /// The constraint.
        constraint: String,
        /// The body that carries it (empty if unknown).
        body: String,
        /// Why.
        reason: String,
    },
}
