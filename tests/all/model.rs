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
    assert!(model.pairs().all(|p| p.material == base));

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
    let d_floor = model.pairs().find(|p| p.a == cd && p.b == floor).unwrap();
    assert_eq!(d_floor.material, rough);
    // pair_between finds each pair from its colliders, in either order, and no other.
    for (id, p) in model.pair_ids().zip(model.pairs()) {
        assert_eq!(model.pair_between(p.a, p.b), Some(id));
        assert_eq!(model.pair_between(p.b, p.a), Some(id));
        assert_eq!(model.pair(id), Some(p));
    }
    assert_eq!(model.pair_count(), 7);
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

/// Issue 15 (pairs in linear memory): the model lists no pairs; what it answers on demand
/// — `pair_ids`, `pairs`, `pair_between`, `pair`, `pair_count` — equals an `n × n` table
/// built the obvious way (the default rule, then every rule in order, the last one on a
/// pair winning), on 200 random trees with colliders on bodies and in the world and random
/// rules. Pair ids are stable: `i · 2³² + j` for the colliders `i < j`.
#[test]
fn pairs_on_demand_equal_a_table_of_the_rules() {
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut next = |k: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % k as u64) as usize
    };
    let base = Material {
        law: Law::Newton,
        e: 0.5,
        mu: 0.2,
    };
    for case in 0..200 {
        let mut b = Model::builder();
        b.default_material(base);
        let nbody = 1 + next(8);
        let mut bodies = Vec::new();
        let mut parent_of = Vec::new();
        for k in 0..nbody {
            let parent = if k == 0 || next(3) == 0 {
                None
            } else {
                Some(next(k))
            };
            let id = b.add_body(
                body(&format!("b{k}")),
                Joint::revolute(format!("b{k}"), parent.map(|p| bodies[p]), Pose::identity()),
            );
            bodies.push(id);
            parent_of.push(parent);
        }
        // Colliders interleaved: on a body (its index) or in the world (None).
        let mut owner: Vec<Option<usize>> = Vec::new();
        let mut ids = Vec::new();
        for c in 0..2 + next(10) {
            let on = (next(4) != 0).then(|| next(nbody));
            ids.push(b.add_collider(ball(&format!("c{c}"), on.map(|k| bodies[k]))));
            owner.push(on);
        }
        let n = ids.len();
        let mut table = vec![vec![None; n]; n];
        for i in 0..n {
            for j in i + 1..n {
                let touch = match (owner[i], owner[j]) {
                    (None, None) => false,
                    (Some(_), None) | (None, Some(_)) => true,
                    (Some(x), Some(y)) => {
                        x != y && parent_of[x] != Some(y) && parent_of[y] != Some(x)
                    }
                };
                table[i][j] = touch.then_some(base);
            }
        }
        for r in 0..next(12) {
            let (x, y) = (next(n), next(n));
            let valid = x != y
                && !(owner[x].is_none() && owner[y].is_none())
                && (owner[x].is_none() || owner[x] != owner[y]);
            if !valid {
                continue;
            }
            let (i, j) = (x.min(y), x.max(y));
            match next(3) {
                0 => {
                    b.disable_pair(ids[x], ids[y]);
                    table[i][j] = None;
                }
                1 => {
                    b.pair(ids[x], ids[y], None);
                    table[i][j] = Some(base);
                }
                _ => {
                    let m = Material {
                        law: Law::Poisson,
                        e: 0.1 * (r % 10) as f64,
                        mu: r as f64,
                    };
                    b.pair(ids[x], ids[y], Some(m));
                    table[i][j] = Some(m);
                }
            }
        }
        let model = b.build().unwrap_or_else(|e| panic!("case {case}: {e}"));
        let mut expected = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                let id = model.pair_between(ids[i], ids[j]);
                assert_eq!(id, model.pair_between(ids[j], ids[i]), "case {case}");
                assert_eq!(
                    id.is_some(),
                    table[i][j].is_some(),
                    "case {case} ({i}, {j})"
                );
                if let (Some(id), Some(m)) = (id, table[i][j]) {
                    assert_eq!(
                        id.index(),
                        (i << 32) | j,
                        "case {case}: the id of ({i}, {j})"
                    );
                    assert_eq!(id.colliders(n), Some((ids[i], ids[j])), "case {case}");
                    let p = model.pair(id).unwrap();
                    // `a` on a body, `b` the other one.
                    let (a, b) = if owner[i].is_some() { (i, j) } else { (j, i) };
                    assert_eq!((p.a, p.b, p.material), (ids[a], ids[b], m), "case {case}");
                    assert_eq!(model.pair_of(id), p, "case {case}");
                    expected.push(id);
                }
            }
        }
        assert_eq!(
            model.pair_ids().collect::<Vec<_>>(),
            expected,
            "case {case}"
        );
        assert_eq!(model.pair_count(), expected.len(), "case {case}");
        assert_eq!(model.pairs().count(), expected.len(), "case {case}");
    }
}
