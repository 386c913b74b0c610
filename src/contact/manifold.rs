//! The contact points of a pair: its closest features ([`pair_contact`]) and, when a flat
//! feature lies on the other shape (a rod lying on the floor, a block on its face), the
//! other ends of that feature. A time-stepping scheme needs them all: with the closest
//! point alone a rod lying flat is held at one end, and its other end sinks.

use parry2d_f64::shape::Shape;

use super::gap::{ContactError, PairContact, pair_contact};
use crate::kinematics::collider_pose;
use crate::math::{Pose, Real, Vec2};
use crate::model::{Model, PairId};
use crate::state::Data;

/// The most contact points of one pair: the closest one and the ends of the flat features
/// of both shapes (two vertices each in the plane).
pub const MAX_CONTACT_POINTS: usize = 5;

/// Relative tolerance (against the shapes' size) under which two contact points are the
/// same, and under which a point's offset to the other shape counts as along the normal.
const SAME_POINT: Real = 1e-6;

/// The contact points of `pair` at the poses in `data`, in `out` (cleared first; at most
/// [`MAX_CONTACT_POINTS`]): the closest features of [`pair_contact`] first (always, even
/// when apart), then every vertex of either shape whose gap to the other shape, measured
/// along the same normal, is at most `margin` (m).
///
/// Every point shares the closest features' normal `ν` (from `a` towards `b`). A vertex
/// `v` of `a` (its surface point `x = v + r_a ν`, `r_a` the shape's rounding: a capsule's
/// radius) is a contact point if the point of `b` closest to `x` lies along `ν` from it
/// (`x` is over the same flat feature of `b`, not beyond its end); its gap is the signed
/// distance from `x` to `b`. Likewise for the vertices of `b` against `a`. Vertices come
/// from segments, capsules, cuboids and convex polygons; balls, half-spaces and
/// polylines have none (a ball touches at one point; a polyline's vertices are not
/// checked). Points closer than `1e-6` times the size of the shapes on bodies to one
/// already found are dropped.
///
/// Requires [`crate::kinematics::update_positions`].
pub fn contact_points(
    model: &Model,
    data: &Data,
    pair: PairId,
    margin: Real,
    out: &mut Vec<PairContact>,
) -> Result<(), ContactError> {
    out.clear();
    let Some(first) = pair_contact(model, data, pair, Real::INFINITY)? else {
        return Ok(());
    };
    out.push(first);
    if first.gap > margin {
        return Ok(());
    }
    let p = model
        .pair(pair)
        .ok_or(ContactError::UnknownPair { pair: pair.index() })?;
    let (ca, cb) = (
        &model.colliders()[p.a.index()],
        &model.colliders()[p.b.index()],
    );
    let pose_a = collider_pose(model, data, p.a)?;
    let pose_b = collider_pose(model, data, p.b)?;
    // The size of the shapes on bodies (an obstacle may be unbounded: a half-space).
    let size = [ca, cb]
        .iter()
        .filter(|c| c.body.is_some())
        .map(|c| c.shape.compute_local_bounding_sphere().radius())
        .filter(|r| r.is_finite())
        .fold(0.0, Real::max);
    let tol = SAME_POINT * size.max(Real::MIN_POSITIVE);
    let nu = first.normal;
    // Vertices of a against b (towards b: +ν), then of b against a (towards a: −ν).
    for (from_a, shape, pose, other, other_pose) in [
        (true, &*ca.shape.0, &pose_a, &*cb.shape.0, &pose_b),
        (false, &*cb.shape.0, &pose_b, &*ca.shape.0, &pose_a),
    ] {
        let dir = if from_a { nu } else { -nu };
        let radius = rounding(shape);
        for v in (0..).map_while(|k| vertex(shape, k)) {
            if out.len() == MAX_CONTACT_POINTS {
                return Ok(());
            }
            let x = pose.transform_point(v) + radius * dir;
            // Estimated from the closest features: the plane through them.
            let estimate =
                first.gap - dir.dot(x - if from_a { first.point_a } else { first.point_b });
            if estimate > margin + tol {
                continue;
            }
            let Some((y, gap)) = along_normal(other, other_pose, x, dir, tol) else {
                continue;
            };
            if gap > margin {
                continue;
            }
            let (point_a, point_b) = if from_a { (x, y) } else { (y, x) };
            if out.iter().any(|c| (c.point_a - point_a).length() <= tol) {
                continue;
            }
            out.push(PairContact {
                gap,
                point_a,
                point_b,
                normal: nu,
            });
        }
    }
    Ok(())
}

/// The point `y` of `shape` closest to `x` and the signed distance from `x` (negative
/// inside) if `y − x` is along `dir` (within `tol` plus 1% of the distance: a feature
/// tilted by less than 0.6° from the normal), ahead of `x` when outside, behind when
/// inside; `None` if `x` is not over a feature of `shape` that faces `−dir`.
fn along_normal(
    shape: &dyn Shape,
    pose: &Pose,
    x: Vec2,
    dir: Vec2,
    tol: Real,
) -> Option<(Vec2, Real)> {
    let proj = shape.project_point(pose, x, false);
    let d = proj.point - x;
    let along = d.dot(dir);
    let lateral = (d - along * dir).length();
    if lateral > tol + 1e-2 * d.length() {
        return None;
    }
    // Outside, the closest point lies ahead (along dir); inside, behind.
    let gap = if proj.is_inside {
        -d.length()
    } else {
        d.length()
    };
    if d.length() > tol && (along > 0.0) == proj.is_inside {
        return None;
    }
    Some((proj.point, gap))
}

/// The rounding radius of a shape (m): a capsule's radius, 0 for the others.
fn rounding(shape: &dyn Shape) -> Real {
    shape.as_capsule().map_or(0.0, |c| c.radius)
}

/// Vertex `k` of a polygonal shape in its own frame (m): the ends of a segment or of a
/// capsule's segment, the corners of a cuboid, the points of a convex polygon; `None`
/// past the last one and for the other shapes.
fn vertex(shape: &dyn Shape, k: usize) -> Option<Vec2> {
    if let Some(c) = shape.as_capsule() {
        return [c.segment.a, c.segment.b].get(k).copied();
    }
    if let Some(s) = shape.as_segment() {
        return [s.a, s.b].get(k).copied();
    }
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        let corners = [
            Vec2::new(h.x, h.y),
            Vec2::new(-h.x, h.y),
            Vec2::new(-h.x, -h.y),
            Vec2::new(h.x, -h.y),
        ];
        return corners.get(k).copied();
    }
    shape
        .as_convex_polygon()
        .and_then(|p| p.points().get(k).copied())
}
