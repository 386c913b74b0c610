//! The unit tests of `contact::penetration` (`src/contact/penetration.rs`).

// The source module's own imports.
use parry2d_f64::shape::{Shape, SupportMap};
use ricochet::math::{Pose, Real, Vec2};

use parry2d_f64::query;
use parry2d_f64::shape::{Ball, Capsule, ConvexPolygon, Cuboid};

use ricochet::contact::penetration::*;

/// Compares with parry's EPA on overlapping poses of several pairs where EPA works.
fn agree_with_parry<A, B>(a: &A, b: &B)
where
    A: Shape + SupportMap,
    B: Shape + SupportMap,
{
    let mut compared = 0;
    for k in 0..400 {
        let s = k as Real;
        let pa = Pose::new(Vec2::new((0.7 * s).sin(), (1.3 * s).cos()), 0.37 * s);
        let pb = Pose::new(Vec2::new((1.1 * s).cos(), (0.5 * s).sin()), -0.23 * s);
        let Ok(Some(parry)) = query::contact(&pa, a, &pb, b, Real::INFINITY) else {
            continue;
        };
        if parry.dist >= -1e-6 {
            continue;
        }
        let mut normals = Vec::new();
        face_normals(a, &pa, &mut normals);
        face_normals(b, &pb, &mut normals);
        let ours = penetration(&pa, a, &pb, b, &normals);
        assert!(
            (ours.gap - parry.dist).abs() < 1e-9,
            "#{k}: {} vs {}",
            ours.gap,
            parry.dist
        );
        assert!((ours.normal - parry.normal1).length() < 1e-6, "#{k}");
        compared += 1;
    }
    assert!(compared > 50, "only {compared} overlapping poses");
}

#[test]
fn depth_agrees_with_parry_where_parry_succeeds() {
    let boxed = Cuboid::new(Vec2::new(1.0, 0.5));
    let capsule = Capsule::new_x(0.4, 0.1);
    let ball = Ball::new(0.3);
    let triangle = ConvexPolygon::from_convex_polyline(vec![
        Vec2::new(-0.5, -0.2),
        Vec2::new(0.6, -0.1),
        Vec2::new(0.0, 0.7),
    ])
    .unwrap();
    agree_with_parry(&boxed, &capsule);
    agree_with_parry(&boxed, &ball);
    agree_with_parry(&boxed, &triangle);
    agree_with_parry(&capsule, &triangle);
}
