//! The unit tests of `contact::manifold` (`src/contact/manifold.rs`).

// The source module's own imports.
use ricochet::math::{Pose, Real, Vec2};

use crate::unit::linalg::Lcg;
use parry2d_f64::shape::{
    Capsule, ConvexPolygon, Cuboid, HalfSpace, RoundShape, Segment, SharedShape, Triangle,
};
use ricochet::contact::manifold::*;

/// Whether two contacts are the same to the bit (`Debug` prints the shortest string
/// that reads back to the same `f64`, and tells `−0` from `0`).
pub(crate) fn bitwise<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

/// The polygonal shapes of the contact tests, named: a segment, a cuboid, a triangle, a
/// convex pentagon, a capsule and a rounded cuboid (`plane_points_are_the_query_s`,
/// `gap::tests::halfspace_contact_is_the_query_s`).
pub(crate) fn polygonal_shapes() -> Vec<(&'static str, SharedShape)> {
    let pentagon: Vec<Vec2> = (0..5)
        .map(|k| {
            let a = 0.3 + k as Real * std::f64::consts::TAU / 5.0;
            Vec2::new(0.7 * a.cos(), 0.5 * a.sin())
        })
        .collect();
    vec![
        (
            "segment",
            SharedShape::new(Segment::new(Vec2::new(0.0, 0.0), Vec2::new(0.3, -2.0))),
        ),
        (
            "cuboid",
            SharedShape::new(Cuboid::new(Vec2::new(0.4, 0.25))),
        ),
        (
            "triangle",
            SharedShape::new(Triangle::new(
                Vec2::new(-0.5, -0.2),
                Vec2::new(0.6, -0.3),
                Vec2::new(0.1, 0.8),
            )),
        ),
        (
            "pentagon",
            SharedShape::new(ConvexPolygon::from_convex_hull(&pentagon).unwrap()),
        ),
        (
            "capsule",
            SharedShape::new(Capsule::new(
                Vec2::new(-0.6, 0.0),
                Vec2::new(0.6, 0.1),
                0.15,
            )),
        ),
        (
            "round cuboid",
            SharedShape::new(RoundShape {
                inner_shape: Cuboid::new(Vec2::new(0.3, 0.2)),
                border_radius: 0.05,
            }),
        ),
    ]
}

/// [`plane_points`] gives the points of parry's dispatcher and manifold
/// ([`query_points`], in the same order) to the bit, for every polygonal shape it takes
/// (a segment, a cuboid, a triangle, a convex pentagon, a capsule, a rounded cuboid) on
/// a tilted half-space, at 20,000 random poses each: turns of `±π` (a box's support
/// face changes at every 90°), heights from inside the half-space to beyond the
/// tolerance. Where the query finds no point within the tolerance, it gives none (the
/// caller's fallback).
#[test]
fn plane_points_are_the_query_s() {
    let shapes = polygonal_shapes();
    let plane = SharedShape::new(HalfSpace::new(Vec2::new(0.0, 1.0)));
    let pose_b = Pose::new(Vec2::new(0.3, -0.7), 0.2);
    let mut rng = Lcg(7);
    let mut ws = ManifoldWorkspace::default();
    for (name, shape) in &shapes {
        let (a, b) = (&*shape.0, &*plane.0);
        assert!(is_plane_pair(a, b), "{name}");
        let mut counts = [0usize; 3];
        for _ in 0..20_000 {
            let angle = std::f64::consts::PI * (2.0 * rng.unit() - 1.0);
            let at = Vec2::new(4.0 * rng.unit() - 2.0, 3.0 * rng.unit() - 1.5);
            let pose_a = pose_b * Pose::new(at, angle);
            let tolerance = [0.05, 0.5, 2.0][(3.0 * rng.unit()) as usize];
            let fast = plane_points(a, b, (&pose_a, &pose_b), tolerance);
            let mut query = query_points((a, b), (&pose_a, &pose_b), tolerance, &mut ws);
            order_along_tangent(&mut query);
            counts[query.len()] += 1;
            match fast {
                None => assert!(query.is_empty(), "{name}: {query:?}"),
                Some(fast) => assert!(bitwise(&fast, &query), "{name}: {fast:?} {query:?}"),
            }
        }
        // None, one and two points all met.
        assert!(counts.iter().all(|&k| k > 100), "{name}: {counts:?}");
    }
    // Pairs that keep the query: a ball, a body's shape against another's.
    let ball = SharedShape::ball(0.3);
    assert!(!is_plane_pair(&*ball.0, &*plane.0));
    assert!(!is_plane_pair(&*shapes[1].1.0, &*shapes[0].1.0));
    assert!(!is_plane_pair(&*plane.0, &*shapes[1].1.0));
}
