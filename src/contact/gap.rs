//! The signed gap of a contact pair.

use std::cell::RefCell;

use parry2d_f64::query;

use super::query as kept;
use parry2d_f64::shape::{HalfSpace, Shape, SupportMap};

use crate::kinematics::{KinematicsError, collider_pose};
use crate::math::{Pose, Real, Vec2};
use crate::model::{ContactPair, Model, PairId};
use crate::state::Data;

thread_local! {
    /// The face normals of the last penetration by support functions (`pair_contact_of`,
    /// when the queries find the shapes overlapping), kept between calls so that the
    /// loop allocates nothing once it has held the most (tests/all/sim_alloc.rs).
    static KEPT_NORMALS: RefCell<Vec<Vec2>> = const { RefCell::new(Vec::new()) };
}

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
    /// parry2d found no contact of two overlapping shapes (its penetration algorithm gave
    /// up), so the gap cannot be signed.
    #[error(
        "contact pair `{a}`–`{b}`: parry2d cannot compute the penetration of this {shape_a} \
         and {shape_b} (they overlap)"
    )]
    PenetrationFailed {
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

/// The closest features of a contact pair: witness points, normal and signed gap, in the
/// world frame, oriented from the pair's collider `a` towards `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairContact {
    /// Signed gap `g` (m): the distance when apart, minus the penetration depth when
    /// overlapping.
    pub gap: Real,
    /// Witness point on the shape of `a` (m, world frame).
    pub point_a: Vec2,
    /// Witness point on the shape of `b` (m, world frame).
    pub point_b: Vec2,
    /// Unit normal from `a` towards `b` (world frame): `b` approaches `a` when the relative
    /// velocity `v_b − v_a` has a negative component along it.
    pub normal: Vec2,
}

/// The closest features of the contact pair `pair` at the poses in `data`, or `Ok(None)` if
/// the shapes are farther apart than `prediction` (m; pass `Real::INFINITY` to always get
/// them).
///
/// `parry2d::query::contact(X_a, shape_a, X_b, shape_b, prediction)` (`query::distance` is
/// unsigned and cannot tell touching from overlapping). Requires
/// [`crate::kinematics::update_positions`].
pub fn pair_contact(
    model: &Model,
    data: &Data,
    pair: PairId,
    prediction: Real,
) -> Result<Option<PairContact>, ContactError> {
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    pair_contact_of(model, data, &p, prediction)
}

/// [`pair_contact`] of the pair `p` (`model.pair(id)`, looked up by the caller).
pub fn pair_contact_of(
    model: &Model,
    data: &Data,
    p: &ContactPair,
    prediction: Real,
) -> Result<Option<PairContact>, ContactError> {
    let (ca, cb) = (
        &model.colliders()[p.a.index()],
        &model.colliders()[p.b.index()],
    );
    let pose_a = collider_pose(model, data, p.a)?;
    let pose_b = collider_pose(model, data, p.b)?;
    // WORKAROUND (parry2d-f64 0.31.1): `query::contact(shape, half-space)` passes the pose
    // of the half-space relative to the shape where the pose of the shape relative to the
    // half-space is expected (`contact_support_map_halfspace` forgets `pos12.inverse()`),
    // so the distance is wrong; `query::contact(half-space, shape)` is right. Query with
    // the half-space first and swap the result back.
    let halfspace = cb.shape.as_halfspace();
    let halfspace_b = halfspace.is_some();
    let query_ab = || kept::contact(&pose_a, &*ca.shape.0, &pose_b, &*cb.shape.0, prediction);
    let query_ba = || match (halfspace, ca.shape.as_support_map()) {
        (Some(h), Some(s)) => Ok(halfspace_contact((&pose_b, h), (&pose_a, s), prediction)),
        _ => kept::contact(&pose_b, &*cb.shape.0, &pose_a, &*ca.shape.0, prediction),
    };
    let (mut result, mut swapped) = if halfspace_b {
        (query_ba(), true)
    } else {
        (query_ab(), false)
    };
    if matches!(result, Ok(None)) && prediction == Real::INFINITY {
        // With an infinite prediction parry only returns no contact when its GJK–EPA
        // gives up, which happens for thin polygons exactly touching or crossing (cf.
        // dimforge/parry#415). The other order starts GJK elsewhere and usually succeeds;
        // if not, apart shapes still have closest points.
        if !halfspace_b {
            result = query_ba();
            swapped = true;
        }
        if matches!(result, Ok(None)) {
            return closest_points_fallback(ca, cb, &pose_a, &pose_b);
        }
    }
    match result {
        Ok(None) => Ok(None),
        Ok(Some(c)) => {
            let mut contact = if swapped {
                PairContact {
                    gap: c.dist,
                    point_a: c.point2,
                    point_b: c.point1,
                    normal: -c.normal1,
                }
            } else {
                PairContact {
                    gap: c.dist,
                    point_a: c.point1,
                    point_b: c.point2,
                    normal: c.normal1,
                }
            };
            if let (Some(sa), Some(sb)) = (ca.shape.as_support_map(), cb.shape.as_support_map()) {
                refine_witnesses(
                    &mut contact,
                    (&pose_a, sa, &*ca.shape.0),
                    (&pose_b, sb, &*cb.shape.0),
                );
            }
            Ok(Some(contact))
        }
        Err(_) => Err(ContactError::Unsupported {
            a: ca.name.clone(),
            b: cb.name.clone(),
            shape_a: format!("{:?}", ca.shape.shape_type()),
            shape_b: format!("{:?}", cb.shape.shape_type()),
        }),
    }
}

/// `kept::contact(pose_h, half-space, pose_s, shape, prediction)` of a shape with a support
/// map: what it and parry's dispatcher call for this couple (a half-space is no ball, and
/// the dispatcher's half-space case comes before its support-map pair),
/// `contact_halfspace_support_map` on the relative pose, then the contact moved to the
/// world — called directly, without the shape-type tests of the dispatch (the same
/// function on the same arguments; the test `halfspace_contact_is_the_query_s`).
#[doc(hidden)]
#[inline]
pub fn halfspace_contact(
    (pose_h, h): (&Pose, &HalfSpace),
    (pose_s, s): (&Pose, &dyn SupportMap),
    prediction: Real,
) -> Option<query::Contact> {
    let pos12 = pose_h.inv_mul(pose_s);
    let mut c = query::details::contact_halfspace_support_map(&pos12, h, s, prediction);
    if let Some(c) = &mut c {
        c.transform_by_mut(pose_h, pose_s);
    }
    c
}

/// The signed gap `g` (m) of the contact pair `pair` at the poses in `data`: the distance
/// between the two shapes when apart, minus the penetration depth when they overlap.
/// Returns `Ok(None)` if the shapes are farther apart than `prediction` (m); pass
/// `Real::INFINITY` to always get the value. See [`pair_contact`].
///
/// Requires [`crate::kinematics::update_positions`].
pub fn signed_gap(
    model: &Model,
    data: &Data,
    pair: PairId,
    prediction: Real,
) -> Result<Option<Real>, ContactError> {
    Ok(pair_contact(model, data, pair, prediction)?.map(|c| c.gap))
}

/// Replaces the witness points of two support-mapped shapes by a contact point that lies on
/// both surfaces (up to the gap), keeping parry's gap and normal.
///
/// GJK returns an exact distance, but when the closest features are two nearly parallel
/// edges (capsules side by side, a rod landing almost flat) every pair of points along the
/// overlap is nearly as close, and the witness points it stops at can lie anywhere along
/// it: the contact velocity would then be taken at the wrong material points. The support
/// points `s_a` of `a` along `n` and `s_b` of `b` along `−n` are the extreme points of each
/// shape towards the other: unique for a vertex, and the first end to touch for nearly
/// parallel edges. The one that lies on the other shape (its distance to it is the gap,
/// the smaller of the two) is the contact point; the other witness is `gap · n` away.
fn refine_witnesses(
    c: &mut PairContact,
    (pose_a, sup_a, shape_a): (&Pose, &dyn SupportMap, &dyn Shape),
    (pose_b, sup_b, shape_b): (&Pose, &dyn SupportMap, &dyn Shape),
) {
    let n = c.normal;
    let s_a = sup_a.support_point(pose_a, n);
    let s_b = sup_b.support_point(pose_b, -n);
    let d_a = shape_b.distance_to_point(pose_b, s_a, true);
    let d_b = shape_a.distance_to_point(pose_a, s_b, true);
    if d_a <= d_b {
        c.point_a = s_a;
        c.point_b = s_a + c.gap * n;
    } else {
        c.point_b = s_b;
        c.point_a = s_b - c.gap * n;
    }
}

/// The contact of two shapes when `query::contact` gave up: from their closest points when
/// they are apart, from their support functions when they overlap (both convex), else a
/// typed error.
fn closest_points_fallback(
    ca: &crate::model::Collider,
    cb: &crate::model::Collider,
    pose_a: &Pose,
    pose_b: &Pose,
) -> Result<Option<PairContact>, ContactError> {
    let unsupported = |_| ContactError::Unsupported {
        a: ca.name.clone(),
        b: cb.name.clone(),
        shape_a: format!("{:?}", ca.shape.shape_type()),
        shape_b: format!("{:?}", cb.shape.shape_type()),
    };
    let cp = query::closest_points(pose_a, &*ca.shape.0, pose_b, &*cb.shape.0, Real::MAX)
        .map_err(unsupported)?;
    match cp {
        query::ClosestPoints::WithinMargin(pa, pb) => {
            let (normal, gap) = (pb - pa).normalize_and_length();
            if gap > 0.0 && normal.is_finite() {
                return Ok(Some(PairContact {
                    gap,
                    point_a: pa,
                    point_b: pb,
                    normal,
                }));
            }
        }
        query::ClosestPoints::Intersecting => {
            if let (Some(sa), Some(sb)) = (ca.shape.as_support_map(), cb.shape.as_support_map()) {
                let mut c = kept::with_kept(&KEPT_NORMALS, Vec::new, |normals| {
                    normals.clear();
                    super::penetration::face_normals(&*ca.shape.0, pose_a, normals);
                    super::penetration::face_normals(&*cb.shape.0, pose_b, normals);
                    super::penetration::penetration(pose_a, sa, pose_b, sb, normals)
                });
                // The support points along the minimizing direction need not touch: a
                // segment crossing the thin end face of a box has its far end deepest
                // along that face's normal (drop 7509 of tests/all/spin_drops.rs: the witness
                // 0.41 m from the contact, an impact taken at the wrong point).
                refine_witnesses(
                    &mut c,
                    (pose_a, sa, &*ca.shape.0),
                    (pose_b, sb, &*cb.shape.0),
                );
                return Ok(Some(c));
            }
        }
        query::ClosestPoints::Disjoint => {}
    }
    Err(ContactError::PenetrationFailed {
        a: ca.name.clone(),
        b: cb.name.clone(),
        shape_a: format!("{:?}", ca.shape.shape_type()),
        shape_b: format!("{:?}", cb.shape.shape_type()),
    })
}
