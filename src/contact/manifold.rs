//! The contact points of a pair in persistent contact: a box standing on its base or a rod
//! lying flat touches at two points, which one closest-point query cannot see.

use arrayvec::ArrayVec;
use parry2d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};

use super::gap::{ContactError, PairContact, pair_contact};
use crate::kinematics::collider_pose;
use crate::math::{Real, perp};
use crate::model::{ContactPair, Model, PairId};
use crate::state::Data;

/// The most contact points of one pair in the plane: two (the ends of a flat contact).
pub const MAX_CONTACT_POINTS: usize = 2;

/// The contact points of a pair.
pub type ContactPoints = ArrayVec<PairContact, MAX_CONTACT_POINTS>;

/// Scratch of [`contact_points`], kept between calls so that they allocate nothing.
#[derive(Default)]
pub struct ManifoldWorkspace {
    manifolds: Vec<ContactManifold<(), ()>>,
    workspace: Option<ContactManifoldsWorkspace>,
}

/// The points where the shapes of `pair` are closer than `tolerance` (m), from parry2d's
/// contact manifold, oriented from `a` to `b` like [`pair_contact`], and sorted along the
/// tangent `perp(n)` so that the two ends of a flat contact keep their order (index 0 is
/// the end towards `−perp(n)`). When parry gives no manifold for the shapes, the single
/// closest point of [`pair_contact`] within `tolerance`.
///
/// Requires [`crate::kinematics::update_positions`].
pub fn contact_points(
    model: &Model,
    data: &Data,
    pair: PairId,
    tolerance: Real,
    ws: &mut ManifoldWorkspace,
) -> Result<ContactPoints, ContactError> {
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    contact_points_of(model, data, (pair, &p), tolerance, ws)
}

/// [`contact_points`] of a pair already resolved (`model.pair(pair)`): the callers that
/// query one pair many times (the central differences of the persistent contact's
/// velocity products, five queries per right-hand side) look its colliders up once.
pub fn contact_points_of(
    model: &Model,
    data: &Data,
    (pair, p): (PairId, &ContactPair),
    tolerance: Real,
    ws: &mut ManifoldWorkspace,
) -> Result<ContactPoints, ContactError> {
    let (ca, cb) = (
        &model.colliders()[p.a.index()],
        &model.colliders()[p.b.index()],
    );
    let pose_a = collider_pose(model, data, p.a)?;
    let pose_b = collider_pose(model, data, p.b)?;
    let pos_ab = pose_a.inv_mul(&pose_b);
    // parry's workspace holds indices into the manifolds of the last call (composite
    // shapes: a polyline's segments); with the manifolds cleared, it must go too, or parry
    // indexes past them (a ball coming to rest on a polyline panicked, issue 12).
    ws.manifolds.clear();
    ws.workspace = None;
    let found = DefaultQueryDispatcher.contact_manifolds(
        &pos_ab,
        &*ca.shape.0,
        &*cb.shape.0,
        tolerance,
        &mut ws.manifolds,
        &mut ws.workspace,
    );
    let mut points = ContactPoints::new();
    if found.is_ok() {
        for m in &ws.manifolds {
            let normal = pose_a.rotation * m.local_n1;
            for c in &m.points {
                if c.dist <= tolerance && !points.is_full() {
                    points.push(PairContact {
                        gap: c.dist,
                        point_a: pose_a.transform_point(c.local_p1),
                        point_b: pose_b.transform_point(c.local_p2),
                        normal,
                    });
                }
            }
        }
    }
    if points.is_empty()
        && let Some(c) = pair_contact(model, data, pair, Real::INFINITY)?
        && c.gap <= tolerance
    {
        points.push(c);
    }
    if points.len() == 2 {
        let t = perp(points[0].normal);
        if points[0].point_a.dot(t) > points[1].point_a.dot(t) {
            points.swap(0, 1);
        }
    }
    Ok(points)
}
