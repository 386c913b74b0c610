//! Building models: coordinates, contact pairs and the validation errors.

use parry2d_f64::shape::SharedShape;
use ricochet::impact::Law;
use ricochet::math::{Pose, Vec2};
use ricochet::model::{
    Body, Collider, Joint, JointForce, JointKind, Material, Model, ModelBuilder, ModelError,
    PrescribedMotion,
};

fn body(name: &str) -> Body {
    Body::new(name, 1.0, Vec2::new(0.0, -0.5), 0.1)
}

fn ball(name: &str, on: Option<ricochet::model::BodyId>) -> Collider {
    Collider::new(name, on, SharedShape::ball(0.1), Pose::identity())
}

#[test]
fn coordinates_are_named_after_joints_in_body_order() {
    let mut b = Model::builder();
    let base = b.add_body(
        body("cart"),
        Joint::prismatic("cart", None, Pose::identity(), Vec2::new(3.0, 0.0)),
    );
    b.add_body(
        body("arm"),
        Joint::revolute_absolute("arm", Some(base), Pose::identity()),
    );
    b.add_body(
        body("disk"),
        Joint::revolute("disk", Some(base), Pose::identity())
            .with_drive(PrescribedMotion::constant_rate(0.0, 2.0)),
    );
    b.add_body(
        body("weld"),
        Joint::fixed("weld", Some(base), Pose::translation(0.1, 0.0)),
    );
    b.add_body(
        body("particle"),
        Joint::translation("particle", None, Pose::identity()),
    );
    b.add_body(body("rod"), Joint::planar("rod", None, Pose::identity()));
    let model = b.build().unwrap();
    let names: Vec<&str> = model
        .coordinates()
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "cart.q",
            "arm.q",
            "particle.x",
            "particle.y",
            "rod.x",
            "rod.y",
            "rod.theta"
        ]
    );
    let angles: Vec<bool> = model.coordinates().iter().map(|c| c.is_angle).collect();
    assert_eq!(angles, [false, true, false, false, false, false, true]);
    assert_eq!(model.nq(), 7);
    assert!(model.has_prescribed_motion());
    // The prismatic axis was normalized.
    assert_eq!(
        model.joints()[0].kind,
        JointKind::Prismatic { axis: Vec2::X }
    );
    // Prescribed and fixed joints have no coordinate.
    let disk = model.body_by_name("disk").unwrap();
    assert_eq!(model.q_index(disk.joint()), None);
    let rod = model.body_by_name("rod").unwrap();
    assert_eq!(model.q_index(rod.joint()), Some(4));
    assert_eq!(model.ancestors(disk).collect::<Vec<_>>(), vec![base]);
}

#[test]
fn default_pairs_skip_parent_and_child_and_rules_override_them() {
    let mut b = Model::builder();
    let a = b.add_body(body("a"), Joint::revolute("a", None, Pose::identity()));
    let c = b.add_body(
        body("c"),
        Joint::revolute("c", Some(a), Pose::translation(0.0, -1.0)),
    );
    let d = b.add_body(
        body("d"),
        Joint::revolute("d", Some(c), Pose::translation(0.0, -1.0)),
    );
    let ca = b.add_collider(ball("a", Some(a)));
    let cc = b.add_collider(ball("c", Some(c)));
    let cd = b.add_collider(ball("d", Some(d)));
    let floor = b.add_collider(Collider::new(
        "floor",
        None,
        SharedShape::halfspace(Vec2::Y),
        Pose::translation(0.0, -5.0),
    ));
    b.add_collider(Collider::new(
        "wall",
        None,
        SharedShape::halfspace(Vec2::X),
        Pose::translation(-5.0, 0.0),
    ));
    let base = Material {
        law: Law::Newton,
        e: 0.5,
        mu: 0.2,
    };
    b.default_material(base);
    let model = b.clone().build().unwrap();
    let names = |m: &Model| -> Vec<String> {
        m.pairs()
            .iter()
            .map(|p| {
                format!(
                    "{}-{}",
                    m.colliders()[p.a.index()].name,
                    m.colliders()[p.b.index()].name
                )
            })
            .collect()
    };
    // a–c and c–d are parent–child; floor–wall are both in the world.
    assert_eq!(
        names(&model),
        [
            "a-d", "a-floor", "a-wall", "c-floor", "c-wall", "d-floor", "d-wall"
        ]
    );
    assert!(model.pairs().iter().all(|p| p.material == base));

    let rough = Material {
        law: Law::Stronge,
        e: 0.9,
        mu: 1.0,
    };
    b.pair(ca, cc, None)
        .pair(cd, floor, Some(rough))
        .disable_pair(floor, ca);
    let model = b.clone().build().unwrap();
    assert_eq!(
        names(&model),
        [
            "a-c", "a-d", "a-wall", "c-floor", "c-wall", "d-floor", "d-wall"
        ]
    );
    let d_floor = model
        .pairs()
        .iter()
        .find(|p| p.a == cd && p.b == floor)
        .unwrap();
    assert_eq!(d_floor.material, rough);
    // pair_between finds each pair from its colliders, in either order, and no other.
    for (k, p) in model.pairs().iter().enumerate() {
        assert_eq!(model.pair_between(p.a, p.b).map(|id| id.index()), Some(k));
        assert_eq!(model.pair_between(p.b, p.a).map(|id| id.index()), Some(k));
    }
    assert_eq!(model.pair_between(cc, cd), None, "parent and child");
    assert_eq!(model.pair_between(floor, ca), None, "disabled");

    // Several rules on one pair: the last one wins, whatever the other pairs' rules.
    let mut b2 = b.clone();
    b2.disable_pair(cd, floor)
        .pair(ca, cd, Some(rough))
        .pair(floor, cd, None)
        .disable_pair(ca, cd)
        .pair(cd, ca, None);
    let model = b2.build().unwrap();
    let material = |x, y| {
        model
            .pair(model.pair_between(x, y).unwrap())
            .unwrap()
            .material
    };
    assert_eq!(material(cd, floor), base);
    assert_eq!(material(ca, cd), base);
}

fn expect_error(b: ModelBuilder, expected: ModelError) {
    let err = b.build().unwrap_err();
    println!("{err}");
    assert_eq!(err, expected);
}

#[test]
fn validation_errors_carry_evidence() {
    // Masses and inertias.
    let mut b = Model::builder();
    b.add_body(
        Body::new("rod", 0.0, Vec2::ZERO, 0.1),
        Joint::planar("rod", None, Pose::identity()),
    );
    expect_error(
        b,
        ModelError::BadMass {
            body: "rod".into(),
            mass: 0.0,
        },
    );
    let mut b = Model::builder();
    b.add_body(
        Body::new("rod", 1.0, Vec2::ZERO, -0.1),
        Joint::planar("rod", None, Pose::identity()),
    );
    expect_error(
        b,
        ModelError::BadInertia {
            body: "rod".into(),
            inertia: -0.1,
        },
    );
    let mut b = Model::builder();
    b.add_body(
        Body::new("rod", 1.0, Vec2::new(f64::NAN, 0.0), 0.1),
        Joint::planar("rod", None, Pose::identity()),
    );
    assert!(matches!(b.build(), Err(ModelError::NonFinite { .. })));

    // Names.
    let mut b = Model::builder();
    b.add_body(body("x"), Joint::planar("x", None, Pose::identity()));
    b.add_body(body("x"), Joint::planar("y", None, Pose::identity()));
    expect_error(
        b,
        ModelError::DuplicateName {
            what: "body",
            name: "x".into(),
        },
    );

    // A parent that is not an earlier body (here: an id from a larger model).
    let mut other = Model::builder();
    other.add_body(body("p"), Joint::planar("p", None, Pose::identity()));
    let late = other.add_body(body("q"), Joint::planar("q", None, Pose::identity()));
    let mut b = Model::builder();
    b.add_body(
        body("a"),
        Joint::revolute("a", Some(late), Pose::identity()),
    );
    expect_error(
        b,
        ModelError::BadParent {
            joint: "a".into(),
            parent: 1,
            child: 0,
        },
    );

    // Axes, drives and force elements.
    let mut b = Model::builder();
    b.add_body(
        body("s"),
        Joint::prismatic("s", None, Pose::identity(), Vec2::ZERO),
    );
    expect_error(
        b,
        ModelError::BadAxis {
            joint: "s".into(),
            x: 0.0,
            y: 0.0,
        },
    );
    let mut b = Model::builder();
    b.add_body(
        body("p"),
        Joint::planar("p", None, Pose::identity())
            .with_drive(PrescribedMotion::constant_rate(0.0, 1.0)),
    );
    expect_error(
        b,
        ModelError::DriveOnMultiDof {
            joint: "p".into(),
            kind: "planar",
        },
    );
    let spring = JointForce {
        stiffness: 2.0,
        ..Default::default()
    };
    let mut b = Model::builder();
    b.add_body(
        body("d"),
        Joint::revolute("d", None, Pose::identity())
            .with_drive(PrescribedMotion::constant_rate(0.0, 1.0))
            .with_force(spring),
    );
    assert!(matches!(b.build(), Err(ModelError::ForceNotAllowed { .. })));
    let mut b = Model::builder();
    b.add_body(
        body("p"),
        Joint::planar("p", None, Pose::identity()).with_force(spring),
    );
    assert!(matches!(b.build(), Err(ModelError::ForceNotAllowed { .. })));
    let mut b = Model::builder();
    b.add_body(
        body("r"),
        Joint::revolute("r", None, Pose::identity()).with_force(JointForce {
            damping: -1.0,
            ..Default::default()
        }),
    );
    expect_error(
        b,
        ModelError::NegativeCoefficient {
            joint: "r".into(),
            what: "damping",
            value: -1.0,
        },
    );

    // Materials and pairs.
    let mut b = Model::builder();
    let r = b.add_body(body("r"), Joint::revolute("r", None, Pose::identity()));
    let cr = b.add_collider(ball("ball", Some(r)));
    let floor = b.add_collider(Collider::new(
        "floor",
        None,
        SharedShape::halfspace(Vec2::Y),
        Pose::translation(0.0, -2.0),
    ));
    let mut bad_e = b.clone();
    bad_e.pair(
        cr,
        floor,
        Some(Material {
            law: Law::Newton,
            e: 1.5,
            mu: 0.1,
        }),
    );
    expect_error(
        bad_e,
        ModelError::BadMaterial {
            a: "ball".into(),
            b: "floor".into(),
            what: "e",
            value: 1.5,
            range: "0 ≤ e ≤ 1",
        },
    );
    let mut bad_mu = b.clone();
    bad_mu.default_material(Material {
        law: Law::Newton,
        e: 0.5,
        mu: -0.1,
    });
    assert!(matches!(
        bad_mu.build(),
        Err(ModelError::BadMaterial { what: "mu", .. })
    ));
    let mut self_pair = b.clone();
    self_pair.pair(cr, cr, None);
    assert!(matches!(self_pair.build(), Err(ModelError::BadPair { .. })));
}
