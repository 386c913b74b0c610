//! Signed gaps of contact pairs against closed forms.

use parry2d_f64::math::Vector;
use parry2d_f64::shape::SharedShape;
use ricochet::contact::{ContactError, signed_gap};
use ricochet::kinematics::update_positions;
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{Body, Collider, Joint, Model};
use ricochet::state::Data;

/// A ball of radius `r` sliding on a vertical prismatic joint above the floor `y = 0`, a
/// capsule on a planar joint, and a second ball on a translation joint.
fn model() -> Model {
    let mut b = Model::builder();
    let ball = b.add_body(
        Body::new("ball", 1.0, Vec2::ZERO, 0.01),
        Joint::prismatic("ball", None, Pose::identity(), Vec2::Y),
    );
    b.add_collider(Collider::new(
        "ball",
        Some(ball),
        SharedShape::ball(0.25),
        Pose::identity(),
    ));
    let rod = b.add_body(
        Body::new("rod", 1.0, Vec2::ZERO, 0.1),
        Joint::planar("rod", None, Pose::identity()),
    );
    b.add_collider(Collider::new(
        "rod",
        Some(rod),
        SharedShape::capsule_x(0.5, 0.1),
        Pose::identity(),
    ));
    let other = b.add_body(
        Body::new("other", 1.0, Vec2::ZERO, 0.01),
        Joint::translation("other", None, Pose::identity()),
    );
    b.add_collider(Collider::new(
        "other",
        Some(other),
        SharedShape::ball(0.5),
        Pose::identity(),
    ));
    b.add_collider(Collider::new(
        "floor",
        None,
        SharedShape::halfspace(Vector::Y),
        Pose::identity(),
    ));
    let m = b.build().unwrap();
    // ball-rod, ball-other, ball-floor, rod-other, rod-floor, other-floor
    assert_eq!(m.pair_count(), 6);
    m
}

fn pair(model: &Model, a: &str, b: &str) -> ricochet::model::PairId {
    let (a, b) = (
        model.collider_by_name(a).unwrap(),
        model.collider_by_name(b).unwrap(),
    );
    model
        .pair_ids()
        .find(|&p| {
            let p = model.pair(p).unwrap();
            (p.a, p.b) == (a, b) || (p.a, p.b) == (b, a)
        })
        .unwrap()
}

#[test]
fn gaps_are_signed_distances() {
    let model = model();
    let mut data = Data::new(&model);
    let ball_floor = pair(&model, "ball", "floor");
    let rod_floor = pair(&model, "rod", "floor");
    let ball_other = pair(&model, "ball", "other");
    for (y, theta) in [(1.0, 0.3), (0.25, -0.7), (0.1, 1.2), (-0.2, 2.0)] {
        // q = [ball.q, rod.x, rod.y, rod.theta, other.x, other.y]
        let q = [y, 0.0, y, theta, 1.5, y + 0.2];
        update_positions(&model, &mut data, 0.0, &q).unwrap();
        let g = signed_gap(&model, &data, ball_floor, Real::INFINITY)
            .unwrap()
            .unwrap();
        assert!(
            (g - (y - 0.25)).abs() < 1e-12,
            "ball: g = {g}, expected {}",
            y - 0.25
        );
        // Capsule (half-length 0.5, radius 0.1) tilted by θ: lowest point y − ½|sin θ| − 0.1.
        let g = signed_gap(&model, &data, rod_floor, Real::INFINITY)
            .unwrap()
            .unwrap();
        let expected = y - 0.5 * theta.sin().abs() - 0.1;
        assert!(
            (g - expected).abs() < 1e-9,
            "capsule: g = {g}, expected {expected}"
        );
        // Two balls: centre distance − r1 − r2.
        let g = signed_gap(&model, &data, ball_other, Real::INFINITY)
            .unwrap()
            .unwrap();
        let expected = Vec2::new(1.5, 0.2).length() - 0.75;
        assert!(
            (g - expected).abs() < 1e-12,
            "balls: g = {g}, expected {expected}"
        );
    }
    // Beyond the prediction distance: None.
    update_positions(&model, &mut data, 0.0, &[3.0, 0.0, 3.0, 0.0, 0.0, 3.0]).unwrap();
    assert_eq!(signed_gap(&model, &data, ball_floor, 1.0).unwrap(), None);
    assert!(
        signed_gap(&model, &data, ball_floor, 3.0)
            .unwrap()
            .is_some()
    );
}

#[test]
fn unsupported_pairs_are_errors() {
    // A body carrying a half-space against a world half-space: parry has no query.
    let mut b = Model::builder();
    let plate = b.add_body(
        Body::new("plate", 1.0, Vec2::ZERO, 0.1),
        Joint::planar("plate", None, Pose::identity()),
    );
    b.add_collider(Collider::new(
        "plate",
        Some(plate),
        SharedShape::halfspace(-Vector::Y),
        Pose::identity(),
    ));
    b.add_collider(Collider::new(
        "floor",
        None,
        SharedShape::halfspace(Vector::Y),
        Pose::identity(),
    ));
    let model = b.build().unwrap();
    let mut data = Data::new(&model);
    update_positions(&model, &mut data, 0.0, &[0.0, 1.0, 0.0]).unwrap();
    let err = signed_gap(&model, &data, model.pair_ids().next().unwrap(), 1.0).unwrap_err();
    println!("{err}");
    assert!(matches!(err, ContactError::Unsupported { ref shape_a, .. } if shape_a == "HalfSpace"));
}

#[test]
fn gaps_against_every_obstacle_shape() {
    // A cuboid and a ball (planar joints) against a half-space, a segment and a polyline
    // lying on y = 0: the gap is the height of the lowest point, whichever shape is
    // queried first.
    let obstacles = [
        SharedShape::halfspace(Vector::Y),
        SharedShape::segment(Vector::new(-5.0, 0.0), Vector::new(5.0, 0.0)),
        SharedShape::polyline(
            vec![
                Vector::new(-5.0, 0.0),
                Vector::new(0.0, 0.0),
                Vector::new(5.0, 0.0),
            ],
            None,
        ),
        SharedShape::cuboid(5.0, 1.0),
    ];
    for (k, obstacle) in obstacles.into_iter().enumerate() {
        // The cuboid obstacle is centred 1 m below the origin so that its top is y = 0.
        let pose = if k == 3 {
            Pose::translation(0.0, -1.0)
        } else {
            Pose::identity()
        };
        let mut b = Model::builder();
        let block = b.add_body(
            Body::new("block", 1.0, Vec2::ZERO, 0.1),
            Joint::planar("block", None, Pose::identity()),
        );
        let cblock = b.add_collider(Collider::new(
            "block",
            Some(block),
            SharedShape::cuboid(0.3, 0.2),
            Pose::identity(),
        ));
        let ball = b.add_body(
            Body::new("ball", 1.0, Vec2::ZERO, 0.1),
            Joint::planar("ball", None, Pose::identity()),
        );
        let cball = b.add_collider(Collider::new(
            "ball",
            Some(ball),
            SharedShape::ball(0.1),
            Pose::identity(),
        ));
        b.add_collider(Collider::new("ground", None, obstacle, pose));
        b.disable_pair(cblock, cball);
        let model = b.build().unwrap();
        assert_eq!(model.pair_count(), 2);
        let mut data = Data::new(&model);
        for (y, theta) in [(0.8, 0.4), (0.3, -1.0), (0.15, 0.1)] {
            update_positions(&model, &mut data, 0.0, &[0.5, y, theta, -0.7, y, 0.0]).unwrap();
            let block_gap = signed_gap(
                &model,
                &data,
                pair(&model, "block", "ground"),
                Real::INFINITY,
            )
            .unwrap()
            .unwrap();
            let expected = y - 0.3 * theta.sin().abs() - 0.2 * theta.cos().abs();
            assert!(
                (block_gap - expected).abs() < 1e-9,
                "obstacle {k}: cuboid gap {block_gap}, expected {expected}"
            );
            let ball_gap = signed_gap(
                &model,
                &data,
                pair(&model, "ball", "ground"),
                Real::INFINITY,
            )
            .unwrap()
            .unwrap();
            assert!(
                (ball_gap - (y - 0.1)).abs() < 1e-9,
                "obstacle {k}: ball gap {ball_gap}, expected {}",
                y - 0.1
            );
        }
    }
}

/// The convex quadrilateral of the query tests.
fn quadrilateral() -> SharedShape {
    SharedShape::convex_polyline(vec![
        Vector::new(0.0, 0.0),
        Vector::new(0.6, 0.1),
        Vector::new(0.4, 0.5),
        Vector::new(-0.1, 0.3),
    ])
    .unwrap()
}

/// A pose with its origin uniform in the square of half-side `half` and any angle.
fn random_pose(rng: &mut crate::common::rng::Rng, half: Real) -> Pose {
    Pose::new(
        Vec2::new(rng.range(-half, half), rng.range(-half, half)),
        rng.range(-3.2, 3.2),
    )
}

/// `ricochet::contact::query::contact` (parry's query with its EPA kept between calls: no
/// allocation in the loop, issue 16) gives parry's `query::contact` bit for bit: 20,000
/// random placements of every pair of shape kinds the scenes use (balls, capsules, boxes,
/// convex polygons, segments, half-spaces), overlapping, touching and apart, with and
/// without a finite prediction — the penetrating support-map pairs go through the kept EPA.
#[test]
fn the_query_with_a_kept_epa_is_parrys_bit_for_bit() {
    use parry2d_f64::query;
    use ricochet::contact::query::contact as kept;
    let mut rng = crate::common::rng::Rng(0x9e37_79b9_7f4a_7c15);
    let shapes = [
        SharedShape::ball(0.3),
        SharedShape::capsule(Vector::new(-0.4, 0.0), Vector::new(0.4, 0.0), 0.1),
        SharedShape::cuboid(0.5, 0.2),
        quadrilateral(),
        SharedShape::segment(Vector::new(-0.5, 0.0), Vector::new(0.5, 0.1)),
        SharedShape::halfspace(Vector::Y),
    ];
    let mut penetrating = 0;
    for case in 0..20_000 {
        let (i, j) = (rng.pick(shapes.len()), rng.pick(shapes.len()));
        let (p1, p2) = (random_pose(&mut rng, 0.6), random_pose(&mut rng, 0.6));
        let prediction = if case % 3 == 0 { 0.05 } else { Real::INFINITY };
        let ours = kept(&p1, &*shapes[i].0, &p2, &*shapes[j].0, prediction);
        let parry = query::contact(&p1, &*shapes[i].0, &p2, &*shapes[j].0, prediction);
        assert_eq!(
            format!("{ours:?}"),
            format!("{parry:?}"),
            "case {case}: shapes {i}, {j}"
        );
        if let Ok(Some(c)) = parry
            && c.dist < 0.0
            && shapes[i].as_ball().is_none()
            && shapes[j].as_ball().is_none()
        {
            penetrating += 1;
        }
    }
    assert!(penetrating > 2_000, "{penetrating} penetrating cases");
}

/// The kept EPA never grows (`contact::query`'s `grown_epa`): after the thread's first
/// query, 5,000 deep overlaps of support-mapped pairs — capsules and a 200-gon, whose round
/// Minkowski differences run parry's EPA to its last expansion, boxes, a convex polygon,
/// segments — allocate nothing. (With an EPA built empty, as before stop 39, they allocate:
/// the buffers grow the first time a problem needs more.)
#[test]
fn the_kept_epa_never_grows() {
    use crate::common::alloc::allocations_in;
    use ricochet::contact::query::contact as kept;
    let mut rng = crate::common::rng::Rng(0x2545_f491_4f6c_dd1d);
    let gon: Vec<Vector> = (0..200)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 200.0;
            Vector::new(0.4 * a.cos(), 0.4 * a.sin())
        })
        .collect();
    let shapes = [
        SharedShape::capsule(Vector::new(-0.4, 0.0), Vector::new(0.4, 0.0), 0.1),
        SharedShape::capsule(Vector::new(-0.1, 0.0), Vector::new(0.1, 0.0), 0.3),
        SharedShape::convex_polyline(gon).unwrap(),
        SharedShape::cuboid(0.5, 0.2),
        quadrilateral(),
        SharedShape::segment(Vector::new(-0.5, 0.0), Vector::new(0.5, 0.1)),
    ];
    // The thread's first query builds its EPA.
    let at = Pose::new(Vec2::new(0.05, 0.02), 0.3);
    assert!(
        kept(
            &Pose::IDENTITY,
            &*shapes[0].0,
            &at,
            &*shapes[1].0,
            Real::INFINITY
        )
        .is_ok()
    );
    let mut penetrating = 0;
    let allocated = allocations_in(|| {
        for _ in 0..5_000 {
            let (i, j) = (rng.pick(shapes.len()), rng.pick(shapes.len()));
            let (p1, p2) = (random_pose(&mut rng, 0.15), random_pose(&mut rng, 0.15));
            if let Ok(Some(c)) = kept(&p1, &*shapes[i].0, &p2, &*shapes[j].0, Real::INFINITY)
                && c.dist < 0.0
            {
                penetrating += 1;
            }
        }
    });
    assert!(penetrating > 3_000, "{penetrating} penetrating cases");
    assert_eq!(allocated, 0, "the kept EPA grew: {allocated} allocations");
}
