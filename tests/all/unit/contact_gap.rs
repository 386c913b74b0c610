//! The unit tests of `contact::gap` (`src/contact/gap.rs`).

// The source module's own imports.
use parry2d_f64::shape::HalfSpace;
use ricochet::contact::query as kept;
use ricochet::math::{Pose, Real, Vec2};

use crate::unit::contact_manifold::{bitwise, polygonal_shapes};
use crate::unit::linalg::Lcg;
use parry2d_f64::shape::{Ball, SharedShape};
use ricochet::contact::gap::*;

/// [`halfspace_contact`] gives the contact of `kept::contact` (parry's dispatch) to the
/// bit — `Debug` strings equal, `−0` told from `0`, `None` where it gives `None` — for a
/// ball, a segment, a cuboid, a triangle, a convex pentagon, a capsule and a rounded
/// cuboid against a tilted half-space, at 20,000 random poses each (turns of `±π`,
/// heights from inside the half-space to beyond the prediction, finite and infinite
/// predictions).
#[test]
fn halfspace_contact_is_the_query_s() {
    // A ball (no polygonal shape, but a support map), then the polygonal shapes.
    let ball = SharedShape::new(Ball::new(0.35));
    let shapes: Vec<SharedShape> = std::iter::once(ball)
        .chain(polygonal_shapes().into_iter().map(|(_, shape)| shape))
        .collect();
    let plane = HalfSpace::new(Vec2::new(0.6, 0.8));
    let pose_h = Pose::new(Vec2::new(0.3, -0.7), 0.2);
    let mut rng = Lcg(11);
    for shape in &shapes {
        let s = shape.as_support_map().unwrap();
        let (mut some, mut none) = (0, 0);
        for _ in 0..20_000 {
            let angle = std::f64::consts::PI * (2.0 * rng.unit() - 1.0);
            let at = Vec2::new(4.0 * rng.unit() - 2.0, 3.0 * rng.unit() - 1.5);
            let pose_s = pose_h * Pose::new(at, angle);
            let prediction = [0.05, 0.5, Real::INFINITY][(3.0 * rng.unit()) as usize];
            let direct = halfspace_contact((&pose_h, &plane), (&pose_s, s), prediction);
            let query = kept::contact(&pose_h, &plane, &pose_s, &*shape.0, prediction)
                .expect("parry takes a half-space and a support map");
            assert!(bitwise(&direct, &query), "{direct:?} vs {query:?}");
            match direct {
                Some(_) => some += 1,
                None => none += 1,
            }
        }
        // Both outcomes met: contacts and shapes beyond the prediction.
        assert!(some > 1000 && none > 1000, "{some} {none}");
    }
}
