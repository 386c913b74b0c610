//! The signed gap of a contact pair.

use parry2d_f64::query;

use crate::kinematics::{KinematicsError, collider_pose};
use crate::math::Real;
use crate::model::{Model, PairId};
use crate::state::Data;

/// A gap that cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// The pair id is not in the model.
    #[error("contact pair #{pair} is not in the model")]
    UnknownPair {
        /// The index given.
        pair: usize,
    },
    /// parry2d has no contact query for these two shapes (e.g. two half-spaces).
    #[error(
        "contact pair `{a}`–`{b}`: parry2d cannot compute the contact of a {shape_a} with a {shape_b}"
    )]
    Unsupported {
        /// First collider.
        a: String,
        /// Second collider.
        b: String,
        /// Its shape type.
        shape_a: String,
        /// Second shape type.
        shape_b: String,
    },
    /// A kinematics query failed.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
}

/// The signed gap `g` (m) of the contact pair `pair` at the poses in `data`: the distance
/// between the two shapes when apart, minus the penetration depth when they overlap.
/// Returns `Ok(None)` if the shapes are farther apart than `prediction` (m); pass
/// `Real::INFINITY` to always get the value.
///
/// `g = parry2d::query::contact(X_a, shape_a, X_b, shape_b, prediction).dist`
/// (`query::distance` is unsigned and cannot tell touching from overlapping).
///
/// Requires [`crate::kinematics::update_positions`].
pub fn signed_gap(
    model: &Model,
    data: &Data,
    pair: PairId,
    prediction: Real,
) -> Result<Option<Real>, ContactError> {
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    let (ca, cb) = (
        &model.colliders()[p.a.index()],
        &model.colliders()[p.b.index()],
    );
    let pose_a = collider_pose(model, data, p.a)?;
    let pose_b = collider_pose(model, data, p.b)?;
    // WORKAROUND (parry2d-f64 0.31.1): `query::contact(shape, half-space)` passes the pose
    // of the half-space relative to the shape where the pose of the shape relative to the
    // half-space is expected (`contact_support_map_halfspace` forgets `pos12.inverse()`),
    // so the distance is wrong; `query::contact(half-space, shape)` is right. The distance
    // is symmetric, so query with the half-space first.
    let result = if cb.shape.as_halfspace().is_some() {
        query::contact(&pose_b, &*cb.shape.0, &pose_a, &*ca.shape.0, prediction)
    } else {
        query::contact(&pose_a, &*ca.shape.0, &pose_b, &*cb.shape.0, prediction)
    };
    match result {
        Ok(contact) => Ok(contact.map(|c| c.dist)),
        Err(_) => Err(ContactError::Unsupported {
            a: ca.name.clone(),
            b: cb.name.clone(),
            shape_a: format!("{:?}", ca.shape.shape_type()),
            shape_b: format!("{:?}", cb.shape.shape_type()),
        }),
    }
}
