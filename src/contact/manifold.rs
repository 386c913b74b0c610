//! The contact points of a pair in persistent contact: a box standing on its base or a rod
//! lying flat touches at two points, which one closest-point query cannot see.

use arrayvec::ArrayVec;
use parry2d_f64::query::{
    ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry2d_f64::shape::{PolygonalFeature, Shape, ShapeType};

use super::gap::{ContactError, PairContact, pair_contact};
use crate::kinematics::collider_pose;
use crate::math::{Pose, Real, Vec2, perp};
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
    // A polygonal shape on a half-space: the manifold written out (the same numbers).
    if let Some(points) = plane_points(&*ca.shape.0, &*cb.shape.0, (&pose_a, &pose_b), tolerance) {
        return Ok(points);
    }
    let mut points = query_points(
        (&*ca.shape.0, &*cb.shape.0),
        (&pose_a, &pose_b),
        tolerance,
        ws,
    );
    if points.is_empty()
        && let Some(c) = pair_contact(model, data, pair, Real::INFINITY)?
        && c.gap <= tolerance
    {
        points.push(c);
    }
    order_along_tangent(&mut points);
    Ok(points)
}

/// The points of parry's contact manifolds of the shapes `(a, b)` at the collider poses
/// `(pose_a, pose_b)` within `tolerance` (m), in parry's order (none where parry has no
/// manifold for the shapes).
#[doc(hidden)]
#[inline]
pub fn query_points(
    (a, b): (&dyn Shape, &dyn Shape),
    (pose_a, pose_b): (&Pose, &Pose),
    tolerance: Real,
    ws: &mut ManifoldWorkspace,
) -> ContactPoints {
    let pos_ab = pose_a.inv_mul(pose_b);
    // parry's workspace holds indices into the manifolds of the last call (composite
    // shapes: a polyline's segments); with the manifolds cleared, it must go too, or parry
    // indexes past them (a ball coming to rest on a polyline panicked, issue 12).
    ws.manifolds.clear();
    ws.workspace = None;
    let found = DefaultQueryDispatcher.contact_manifolds(
        &pos_ab,
        a,
        b,
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
    points
}

/// Sorts two points of one manifold along the tangent `perp(n)` (see [`contact_points`]).
#[doc(hidden)]
pub fn order_along_tangent(points: &mut ContactPoints) {
    if points.len() == 2 {
        let t = perp(points[0].normal);
        if points[0].point_a.dot(t) > points[1].point_a.dot(t) {
            points.swap(0, 1);
        }
    }
}

/// Whether parry's dispatcher sends a pair of shapes `(a, b)` to its manifold of a
/// polygonal shape on a half-space (`contact_manifold_halfspace_pfm`, with `a` the
/// polygonal one), which `plane_points` computes itself: `b` a half-space, `a` a segment,
/// a cuboid, a triangle, a convex polygon, or one of them rounded (a capsule is a rounded
/// segment). Every other pair (a ball, a polyline, two bodies' shapes) keeps parry's query.
pub fn is_plane_pair(a: &dyn Shape, b: &dyn Shape) -> bool {
    let polygonal = matches!(
        a.shape_type(),
        ShapeType::Segment
            | ShapeType::Cuboid
            | ShapeType::Triangle
            | ShapeType::ConvexPolygon
            | ShapeType::Capsule
            | ShapeType::RoundCuboid
            | ShapeType::RoundTriangle
            | ShapeType::RoundConvexPolygon
    );
    polygonal && b.shape_type() == ShapeType::HalfSpace && a.as_polygonal_feature_map().is_some()
}

/// parry's manifold of a polygonal shape `a` on a half-space `b` ([`is_plane_pair`]) at the
/// collider poses `(pose_a, pose_b)`: its `contact_manifold_halfspace_pfm` (flipped: the
/// half-space is parry's second shape) written out with the same operations in the same
/// order, so the same numbers bit for bit (test `plane_points_are_the_query_s`). In the
/// frame of `a`, with `n` the half-space's normal in its own frame and `r` the rounding
/// of `a`,
///
/// ```text
/// pos_ba = (pose_a⁻¹ pose_b)⁻¹,   n_a = pos_ba.R⁻¹ n
/// for each vertex v of a's support feature towards −n_a:
///     d = (pos_ba v)·n − r,   a point if d ≤ tolerance, with
///     p_a = pose_a (v − r n_a),   p_b = pose_b (pos_ba v − n (d + r)),   normal = pose_a.R (−n_a)
/// ```
///
/// The support feature is parry's own (`local_support_feature`): constant for a segment
/// or a capsule (its two ends), the face nearest `−n_a` for a cuboid, a triangle or a
/// polygon, so a box rocking past 45° or a polygon rolling onto its next face takes its
/// new feature as the query does.
struct PlaneManifold {
    radius: Real,
    n: Vec2,
    n_a: Vec2,
    pos_ba: Pose,
    normal: Vec2,
    feature: PolygonalFeature,
}

impl PlaneManifold {
    /// The manifold's frame and feature; `None` unless [`is_plane_pair`]`(a, b)`.
    #[inline]
    fn new(a: &dyn Shape, b: &dyn Shape, (pose_a, pose_b): (&Pose, &Pose)) -> Option<Self> {
        if !is_plane_pair(a, b) {
            return None;
        }
        let ((pfm, radius), halfspace) = (a.as_polygonal_feature_map()?, b.as_halfspace()?);
        let mut m = Self::frame((pose_a, pose_b), halfspace.normal, radius);
        pfm.local_support_feature(-m.n_a, &mut m.feature);
        Some(m)
    }

    /// The manifold's frame for a half-space of normal `n` (in its own frame) and a
    /// rounding `radius` of `a`, with no feature yet.
    #[inline]
    fn frame((pose_a, pose_b): (&Pose, &Pose), n: Vec2, radius: Real) -> Self {
        let pos_ba = pose_a.inv_mul(pose_b).inverse();
        let n_a = pos_ba.rotation.inverse() * n;
        Self {
            radius,
            n,
            n_a,
            pos_ba,
            normal: pose_a.rotation * -n_a,
            feature: PolygonalFeature::default(),
        }
    }

    /// The vertices of the support feature (in the frame of `a`'s shape).
    #[inline]
    fn vertices(&self) -> &[Vec2] {
        let k = self.feature.num_vertices.min(self.feature.vertices.len());
        &self.feature.vertices[..k]
    }

    /// The point of vertex `v` of the feature, if its gap is within `tolerance` (m).
    #[inline]
    fn point(
        &self,
        (pose_a, pose_b): (&Pose, &Pose),
        v: Vec2,
        tolerance: Real,
    ) -> Option<PairContact> {
        let v_b = self.pos_ba * v;
        let to_plane = v_b.dot(self.n);
        let gap = to_plane - self.radius;
        (gap <= tolerance).then(|| PairContact {
            gap,
            point_a: pose_a.transform_point(v - self.n_a * self.radius),
            point_b: pose_b.transform_point(v_b - self.n * to_plane),
            normal: self.normal,
        })
    }
}

/// The contact points of [`contact_points`] for a pair of a polygonal shape `a` on a
/// half-space `b` ([`is_plane_pair`]) at the collider poses `(pose_a, pose_b)`, from
/// [`PlaneManifold`] without parry's dispatcher, its manifold vectors and their contact
/// tracking. `None` for any other pair, or when no vertex is within `tolerance`, where
/// [`contact_points`] falls back on the closest points of the query.
#[doc(hidden)]
#[inline]
pub fn plane_points(
    a: &dyn Shape,
    b: &dyn Shape,
    poses: (&Pose, &Pose),
    tolerance: Real,
) -> Option<ContactPoints> {
    let m = PlaneManifold::new(a, b, poses)?;
    let mut points = ContactPoints::new();
    for &v in m.vertices() {
        if let Some(c) = m.point(poses, v, tolerance)
            && !points.is_full()
        {
            points.push(c);
        }
    }
    if points.is_empty() {
        return None;
    }
    order_along_tangent(&mut points);
    Some(points)
}

/// A closed contact point that is a vertex of a polygonal shape with no rounding (a
/// segment, a cuboid, a triangle, a convex polygon) of a body on a half-space, found once
/// per set of closed points ([`ClosedVertex::of`]): its contact at a state is the vertex's
/// alone ([`ClosedVertex::contact`]), the same numbers as the query's point nearest the
/// closed point, without the pair's other point, their order and the nearest search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosedVertex {
    /// The vertex in the frame of its shape (m), as parry's support features give it.
    v: Vec2,
    /// The half-space's normal in its own frame.
    n: Vec2,
    /// Whether every support feature of the shape holds the vertex (a segment's is its
    /// two ends): no feature to check.
    always: bool,
}

impl ClosedVertex {
    /// The vertex of the shape of `a` that a closed point of the pair `p` at `local` (in
    /// the frame of `a`'s body, m) is, when the pair is a polygonal shape with no rounding
    /// on a half-space ([`is_plane_pair`]) and [`Self::contact`] can stand for the query's
    /// nearest point: `local` within `eps` of the vertex and every other vertex of the
    /// shape farther than `2 eps + spacing` (m), so that the query's nearest point is
    /// always this vertex's while the support feature holds it. `None` for any other pair
    /// or point.
    pub fn of(
        model: &Model,
        p: &ContactPair,
        local: Vec2,
        eps: Real,
        spacing: Real,
    ) -> Option<Self> {
        let (ca, cb) = (
            &model.colliders()[p.a.index()],
            &model.colliders()[p.b.index()],
        );
        let (shape, halfspace) = (&*ca.shape.0, cb.shape.as_halfspace()?);
        if ca.body.is_none() || !is_plane_pair(shape, &*cb.shape.0) {
            return None;
        }
        let local = ca.pose.inverse_transform_point(local);
        let (mut best, mut d_best, mut d_next) = (None, Real::INFINITY, Real::INFINITY);
        let mut visit = |v: Vec2| {
            let d = (v - local).length();
            if d < d_best {
                (best, d_next, d_best) = (Some(v), d_best, d);
            } else {
                d_next = d_next.min(d);
            }
        };
        match shape.shape_type() {
            ShapeType::Segment => {
                let s = shape.as_segment()?;
                [s.a, s.b].into_iter().for_each(&mut visit);
            }
            ShapeType::Cuboid => {
                // The corners as parry's `support_face` builds them: `±he` exactly.
                let he = shape.as_cuboid()?.half_extents;
                for (x, y) in [(he.x, he.y), (-he.x, he.y), (-he.x, -he.y), (he.x, -he.y)] {
                    visit(Vec2::new(x, y));
                }
            }
            ShapeType::Triangle => shape
                .as_triangle()?
                .vertices()
                .iter()
                .copied()
                .for_each(visit),
            ShapeType::ConvexPolygon => shape
                .as_convex_polygon()?
                .points()
                .iter()
                .copied()
                .for_each(visit),
            _ => return None,
        }
        (d_best <= eps && d_next > 2.0 * eps + spacing).then_some(Self {
            v: best?,
            n: halfspace.normal,
            always: shape.shape_type() == ShapeType::Segment,
        })
    }

    /// The vertex in the frame of its shape (m).
    pub fn vertex(&self) -> Vec2 {
        self.v
    }

    /// The vertex's contact with the half-space of the pair `p` (the pair it was found
    /// for) at the poses of `data`: `PlaneManifold`'s point of the vertex, the same
    /// operations (with no rounding), so the same numbers as the query's point. `None` —
    /// take the query — when the support feature of the shape towards the half-space no
    /// longer holds the vertex (a box tipped over past its side), or when its gap exceeds
    /// `tolerance` (m). Requires [`crate::kinematics::update_positions`].
    #[inline]
    pub fn contact(
        &self,
        model: &Model,
        data: &Data,
        p: &ContactPair,
        tolerance: Real,
    ) -> Result<Option<PairContact>, ContactError> {
        let pose_a = collider_pose(model, data, p.a)?;
        let pose_b = collider_pose(model, data, p.b)?;
        let poses = (&pose_a, &pose_b);
        // The vertex has no rounding: `PlaneManifold` with `r = 0`.
        let mut m = PlaneManifold::frame(poses, self.n, 0.0);
        let mut v = self.v;
        if !self.always {
            let shape = &*model.colliders()[p.a.index()].shape.0;
            let Some((pfm, _)) = shape.as_polygonal_feature_map() else {
                return Ok(None);
            };
            pfm.local_support_feature(-m.n_a, &mut m.feature);
            // The feature's own vertex (its signed zeros, as the query takes it).
            match m.vertices().iter().find(|w| **w == v) {
                Some(&w) => v = w,
                None => return Ok(None),
            }
        }
        Ok(m.point(poses, v, tolerance))
    }
}
