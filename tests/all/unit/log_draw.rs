//! The unit tests of `log::draw` (`src/log/draw.rs`).

// The source module's own imports.
use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::{Pose as Pose2, Vector};
use parry2d_f64::shape::Shape;
use ricochet::log::LogError;
use ricochet::log::foxglove::{Color, LineType, Pose, SceneEntity, rgba};

use parry2d_f64::shape::{Ball, Capsule, ConvexPolygon, Cuboid, HalfSpace, RoundShape};

use ricochet::log::draw::*;
use ricochet::log::foxglove::Quaternion;

const RED: Color = rgba(1.0, 0.0, 0.0, 1.0);

fn drawn(shape: &dyn Shape, pose: Pose2) -> SceneEntity {
    let mut e = SceneEntity::default();
    add_shape(&mut e, shape, &pose, RED, &DrawStyle::default()).unwrap();
    e
}

/// The angle of a z-rotation quaternion (rad).
fn angle(q: Option<Quaternion>) -> f64 {
    let q = q.unwrap();
    2.0 * q.z.atan2(q.w)
}

/// `(x, y)` of a pose's position.
fn xy(pose: &Option<Pose>) -> (f64, f64) {
    let p = pose.unwrap().position.unwrap();
    (p.x, p.y)
}

/// `(x, y)` of a size.
fn size(size: &Option<ricochet::log::foxglove::Vector3>) -> (f64, f64) {
    let s = size.unwrap();
    (s.x, s.y)
}

#[test]
fn ball_is_a_disc_at_the_composed_pose() {
    let e = drawn(&Ball::new(0.5), Pose2::new(Vector::new(1.0, 2.0), 0.3));
    let c = &e.cylinders[0];
    assert_eq!(size(&c.size), (1.0, 1.0));
    assert_eq!(xy(&c.pose), (1.0, 2.0));
    assert!((angle(c.pose.unwrap().orientation) - 0.3).abs() < 1e-15);
    // The radius marker goes from the centre to the rim along the local x axis.
    assert_eq!(e.lines[0].points[1].x, 0.5);
}

#[test]
fn capsule_discs_sit_on_its_segment_ends() {
    // A vertical capsule (half height 1) turned by 90°: its ends are at x = ∓1.
    let pose = Pose2::new(Vector::new(0.0, 3.0), std::f64::consts::FRAC_PI_2);
    let e = drawn(&Capsule::new_y(1.0, 0.25), pose);
    let ends: Vec<(f64, f64)> = e.cylinders.iter().map(|c| xy(&c.pose)).collect();
    assert!((ends[0].0 - 1.0).abs() < 1e-15 && (ends[0].1 - 3.0).abs() < 1e-15);
    assert!((ends[1].0 + 1.0).abs() < 1e-15 && (ends[1].1 - 3.0).abs() < 1e-15);
    // The rectangle spans the segment (length 2) and the diameter (0.5).
    assert_eq!(size(&e.cubes[0].size), (2.0, 0.5));
}

#[test]
fn half_space_lies_on_the_solid_side() {
    // Ground y ≤ 0: the square is centred straight below the origin, unrotated.
    let side = DrawStyle::default().half_space_size;
    let e = drawn(&HalfSpace::new(Vector::Y), Pose2::IDENTITY);
    let cube = &e.cubes[0];
    assert!(xy(&cube.pose).0.abs() < 1e-12);
    assert_eq!(xy(&cube.pose).1, -0.5 * side);
    assert!(angle(cube.pose.unwrap().orientation).abs() < 1e-15);
    // A wall x ≥ 0 solid (outward normal −x): centred at +x.
    let e = drawn(&HalfSpace::new(-Vector::X), Pose2::IDENTITY);
    assert_eq!(xy(&e.cubes[0].pose).0, 0.5 * side);
}

#[test]
fn polygon_is_a_fan_and_an_outline() {
    let square = Cuboid::new(Vector::new(1.0, 1.0));
    let poly = ConvexPolygon::from_convex_polyline(vec![
        Vector::new(0.0, 0.0),
        Vector::new(2.0, 0.0),
        Vector::new(2.0, 1.0),
        Vector::new(0.0, 1.0),
    ])
    .unwrap();
    let e = drawn(&poly, Pose2::IDENTITY);
    assert_eq!(e.triangles[0].points.len(), 6);
    assert_eq!(e.lines[0].points.len(), 4);
    assert_eq!(e.lines[0].r#type, LineType::LineLoop as i32);
    assert_eq!(size(&drawn(&square, Pose2::IDENTITY).cubes[0].size).0, 2.0);
}

#[test]
fn unsupported_shapes_are_errors() {
    let round = RoundShape {
        inner_shape: Cuboid::new(Vector::new(1.0, 1.0)),
        border_radius: 0.1,
    };
    let mut e = SceneEntity::default();
    let err = add_shape(&mut e, &round, &Pose2::IDENTITY, RED, &DrawStyle::default());
    assert!(matches!(err, Err(LogError::UnsupportedShape { .. })));
}

#[test]
fn transform_quaternion_is_about_z() {
    let tf = body_transform(0.5, "rod", &Pose2::new(Vector::new(1.0, -2.0), 1.2)).unwrap();
    assert_eq!(tf.child_frame_id, "body_rod");
    assert_eq!(tf.parent_frame_id, "world");
    let (p, r) = (tf.translation.unwrap(), tf.rotation.unwrap());
    assert_eq!((p.x, p.y, p.z), (1.0, -2.0, 0.0));
    assert_eq!((r.x, r.y), (0.0, 0.0));
    assert!((r.z - 0.6f64.sin()).abs() < 1e-15);
    assert!((r.w - 0.6f64.cos()).abs() < 1e-15);
}

#[test]
fn skeleton_bars_reach_the_children_and_the_centre_of_mass() {
    // Kane's rod A: hinged at its origin, rod B at (0, −2), centre of mass (0, −1).
    let e = skeleton_entity(
        0.0,
        "rodA",
        &[Vector::new(0.0, -2.0)],
        (Vector::new(0.0, -1.0), true),
        RED,
        &DrawStyle::default(),
    )
    .unwrap();
    assert_eq!(
        (e.id.as_str(), e.frame_id.as_str()),
        ("visual/rodA", "body_rodA")
    );
    assert!(e.frame_locked);
    // Each bar is centred halfway to its end, along it, and as long as it.
    let bars: Vec<((f64, f64), (f64, f64))> = e
        .cubes
        .iter()
        .map(|c| (xy(&c.pose), size(&c.size)))
        .collect();
    assert_eq!(bars[0].0, (0.0, -1.0));
    assert_eq!(bars[0].1, (2.0, 0.1));
    assert_eq!(bars[1].0, (0.0, -0.5));
    assert_eq!(bars[1].1.0, 1.0);
    assert!(
        (angle(e.cubes[0].pose.unwrap().orientation) + std::f64::consts::FRAC_PI_2).abs() < 1e-15
    );
    // The disc at the centre of mass.
    assert_eq!(xy(&e.cylinders[0].pose), (0.0, -1.0));
    assert!(
        e.cubes.iter().all(|c| c.color.unwrap().a < 1.0),
        "translucent"
    );
}

#[test]
fn view_stays_while_the_mechanism_is_in_its_dead_zone_and_follows_it_out() {
    let aabb =
        |x0: f64, y0: f64, x1: f64, y1: f64| Aabb::new(Vector::new(x0, y0), Vector::new(x1, y1));
    let mut view = ViewTracker::new(&aabb(-1.0, -2.0, 1.0, 0.0));
    assert_eq!(view.center, Vector::new(0.0, -1.0));
    assert_eq!(view.margin, 0.75);
    // A swing within the zone: no motion.
    assert_eq!(
        view.follow(&aabb(-0.7, -1.5, 0.5, -0.3)),
        Vector::new(0.0, -1.0)
    );
    // The box leaves on the right by 0.5: the centre moves by 0.5 along x only.
    assert_eq!(
        view.follow(&aabb(0.0, -1.5, 1.25, -0.5)),
        Vector::new(0.5, -1.0)
    );
    // A box larger than the zone is centred.
    assert_eq!(
        view.follow(&aabb(-5.0, -1.5, 5.0, -0.5)),
        Vector::new(0.0, -1.0)
    );
    // A box with a NaN or an infinity leaves the view where it is, and no panic.
    let here = view.center;
    assert_eq!(view.follow(&aabb(f64::NAN, 0.0, 1.0, 1.0)), here);
    assert_eq!(view.follow(&aabb(0.0, 0.0, f64::INFINITY, 1.0)), here);
    // A box beyond f64's range at the start: the origin and the smallest zone.
    let lost = ViewTracker::new(&aabb(-1e308, 0.0, 1e308, 1.0));
    assert_eq!((lost.center, lost.margin), (Vector::new(0.0, 0.5), 0.25));
    assert_eq!(ArrowStyle::for_size(f64::INFINITY).length, 0.5);
}

#[test]
fn arrows_scale_to_the_largest_impulse_so_far_with_a_floor() {
    let style = ArrowStyle::for_size(2.0);
    assert_eq!(style.length, 0.8);
    let mut scale = ArrowScale::default();
    assert_eq!(scale.length(2.0, &style), 0.8);
    assert_eq!(scale.length(1.0, &style), 0.4);
    // 1e-4 of the largest: the floor, 0.2 of the full length.
    assert!((scale.length(2e-4, &style) - 0.16).abs() < 1e-15);
    // A new largest impulse takes the full length.
    assert_eq!(scale.length(4.0, &style), 0.8);
    assert_eq!(scale.largest, 4.0);
}

#[test]
fn significant_keeps_three_digits() {
    assert_eq!(significant(1.0242), "1.02");
    assert_eq!(significant(0.045_12), "0.0451");
    assert_eq!(significant(123.4), "123");
    assert_eq!(significant(3.2e-7), "3.20e-7");
    assert_eq!(significant(0.0), "0.00");
}
