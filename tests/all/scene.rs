//! Scene files: every scene of `scenes/` loads into the model it describes, and a table of
//! bad snippets each yields an error naming the field and its line.
#![allow(clippy::needless_range_loop)]

use std::path::{Path, PathBuf};

use nalgebra::DMatrix;
use ricochet::contact::signed_gap;
use ricochet::dynamics::{energy, mass_matrix};
use ricochet::kinematics::{forward_kinematics, point_velocity, point_world, update_positions};
use ricochet::math::{Real, Vec2};
use ricochet::scene::{self, Scene, SceneError};
use ricochet::state::Data;

const DEG: Real = std::f64::consts::PI / 180.0;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn load(name: &str) -> Scene {
    let path = scenes_dir().join(format!("{name}.toml"));
    scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

const SCENES: [(&str, &[&str]); 14] = [
    ("kane_double_pendulum", &["rodA.q", "rodB.q"]),
    ("pendulum_wall", &["pendulum.q"]),
    ("falling_rod", &["rod.x", "rod.y", "rod.theta"]),
    ("bouncing_ball", &["ball.q"]),
    ("rocking_block", &["block.x", "block.y", "block.theta"]),
    ("rimless_wheel", &["wheel.x", "wheel.y", "wheel.theta"]),
    ("painleve_rod", &["rod.x", "rod.y", "rod.theta"]),
    ("spinning_disk_particle", &["particle.x", "particle.y"]),
    (
        "chaplygin_sleigh",
        &["sleigh.x", "sleigh.y", "sleigh.theta"],
    ),
    (
        "wagon_curb",
        &["wagon.x", "wagon.y", "wagon.theta", "front.q"],
    ),
    ("sled_rock", &["sled.x", "sled.y", "sled.theta"]),
    (
        "chain_floor",
        &[
            "link1.q", "link2.q", "link3.q", "link4.q", "link5.q", "link6.q", "link7.q", "link8.q",
            "link9.q", "link10.q", "link11.q", "link12.q", "link13.q", "link14.q", "link15.q",
            "link16.q", "link17.q", "link18.q", "link19.q", "link20.q", "link21.q", "link22.q",
            "link23.q", "link24.q", "link25.q", "link26.q", "link27.q", "link28.q", "link29.q",
            "link30.q", "link31.q", "link32.q",
        ],
    ),
    (
        "newtons_cradle",
        &["ball1.q", "ball2.q", "ball3.q", "ball4.q", "ball5.q"],
    ),
    (
        "chain",
        &[
            "link1.q", "link2.q", "link3.q", "link4.q", "link5.q", "link6.q", "link7.q", "link8.q",
        ],
    ),
];

/// The smallest signed gap over the scene's pairs at its initial state.
fn min_gap(s: &Scene) -> Real {
    let mut data = Data::new(&s.model);
    update_positions(&s.model, &mut data, 0.0, s.initial.q.as_slice()).unwrap();
    s.model
        .pair_ids()
        .map(|p| {
            signed_gap(&s.model, &data, p, Real::INFINITY)
                .unwrap()
                .unwrap()
        })
        .fold(Real::INFINITY, Real::min)
}

#[test]
fn every_scene_loads_with_its_coordinates_and_a_positive_definite_mass_matrix() {
    // All .toml files of scenes/ are in the table.
    let mut files: Vec<String> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .filter_map(|e| e.ok()?.path().file_stem()?.to_str().map(String::from))
        .filter(|n| n != "README")
        .collect();
    files.sort();
    let mut listed: Vec<String> = SCENES.iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(files, listed);

    let mut seed = 12345u64;
    let mut random = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as Real / (1u64 << 53) as Real * 6.0 - 3.0
    };
    for (name, coordinates) in SCENES {
        let s = load(name);
        assert_eq!(s.name, name);
        assert!(
            !s.description.is_empty() && s.text.starts_with('#'),
            "{name}: describe the scene"
        );
        let names: Vec<&str> = s
            .model
            .coordinates()
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(names, coordinates, "{name}");
        assert!(s.model.pairs().next().is_some(), "{name}: no contact pair");
        let gap = min_gap(&s);
        assert!(gap >= -1e-12, "{name}: overlapping at the start ({gap})");
        println!(
            "{name}: nq = {}, {} pairs, smallest initial gap {gap:.3e} m",
            s.model.nq(),
            s.model.pair_count()
        );

        let mut data = Data::new(&s.model);
        let e = energy(
            &s.model,
            &mut data,
            0.0,
            s.initial.q.as_slice(),
            s.initial.u.as_slice(),
        )
        .unwrap();
        assert!(e.kinetic.is_finite() && e.potential.is_finite());
        // M symmetric positive definite at the initial state and at random states.
        let mut qs = vec![s.initial.q.as_slice().to_vec()];
        for _ in 0..20 {
            qs.push((0..s.model.nq()).map(|_| random()).collect());
        }
        for q in qs {
            update_positions(&s.model, &mut data, random().abs(), &q).unwrap();
            mass_matrix(&s.model, &mut data);
            let m = data.mass.to_dense();
            assert_eq!(m, m.transpose(), "{name}");
            let eig = m.symmetric_eigenvalues();
            assert!(
                eig.min() > 0.0,
                "{name}: M not positive definite at {q:?}: {eig}"
            );
        }
    }
}

#[test]
fn kane_double_pendulum_is_at_the_instant_of_impact() {
    let s = load("kane_double_pendulum");
    assert_eq!(s.initial.q.as_slice(), &[20.0 * DEG, 30.0 * DEG]);
    assert_eq!(s.initial.u.as_slice(), &[-0.1, -0.2]);
    let pair = s.model.pairs().next().unwrap();
    assert_eq!(s.model.pair_count(), 1);
    assert_eq!((pair.material.e, pair.material.mu), (0.5, 0.2));
    let gap = min_gap(&s);
    assert!(gap.abs() < 1e-15, "the tip must touch the floor: gap {gap}");

    let mut data = Data::new(&s.model);
    forward_kinematics(
        &s.model,
        &mut data,
        0.0,
        s.initial.q.as_slice(),
        s.initial.u.as_slice(),
    )
    .unwrap();
    let rod_b = s.model.body_by_name("rodB").unwrap();
    let tip = point_world(&s.model, &data, rod_b, Vec2::new(0.0, -2.0)).unwrap();
    let v = point_velocity(&s.model, &data, rod_b, tip).unwrap().total;
    // v^A = −0.2684 n + 0.5343 t, n = +y, t = −x.
    assert!(
        (v.y - -0.2684).abs() < 5e-5 && (-v.x - 0.5343).abs() < 5e-5,
        "v^A = {v:?}"
    );
    mass_matrix(&s.model, &mut data);
    let c = (10.0 * DEG).cos();
    let closed = DMatrix::from_row_slice(2, 2, &[4.0 / 3.0, 0.5 * c, 0.5 * c, 1.0 / 3.0]) * 12.0;
    assert!((data.mass.to_dense() - closed).amax() < 1e-13);
}

#[test]
fn scenes_start_where_their_comments_say() {
    // bouncing_ball: lowest point 1 m above the floor, at rest.
    let s = load("bouncing_ball");
    assert!((min_gap(&s) - 1.0).abs() < 1e-12);
    assert_eq!(
        (s.settings.t_end, s.model.pairs().next().unwrap().material.e),
        (5.0, 0.8)
    );
    // rocking_block and rimless_wheel and painleve_rod: on a corner, a spoke, an end.
    for name in ["rocking_block", "rimless_wheel", "painleve_rod"] {
        let gap = min_gap(&load(name));
        assert!(gap.abs() < 1e-12, "{name}: initial gap {gap}");
    }
    // spinning_disk_particle: the disk is prescribed; its top point moves at Ω R = 5 m/s
    // along −x whatever u is — the remainder velocity of [P, Eq. (2)].
    let s = load("spinning_disk_particle");
    assert!(s.model.has_prescribed_motion());
    let mut data = Data::new(&s.model);
    forward_kinematics(
        &s.model,
        &mut data,
        0.3,
        s.initial.q.as_slice(),
        s.initial.u.as_slice(),
    )
    .unwrap();
    let disk = s.model.body_by_name("disk").unwrap();
    let v = point_velocity(&s.model, &data, disk, Vec2::new(0.0, 0.5)).unwrap();
    assert!((v.remainder - Vec2::new(-5.0, 0.0)).length() < 1e-12 && v.total == v.remainder);
    assert!((min_gap(&s) - 0.3).abs() < 1e-12);
}

#[test]
fn the_chain_takes_its_number_of_links_from_the_file_or_the_caller() {
    let path = scenes_dir().join("chain.toml");
    for n in [1, 2, 4, 8, 16, 32] {
        let s = scene::load_chain(&path, n).unwrap();
        assert_eq!(s.model.nq(), n);
        assert_eq!(s.model.coordinates()[n - 1].name, format!("link{n}.q"));
        // Each link with the floor, and every non-adjacent pair of links.
        let non_adjacent = if n >= 2 { (n - 1) * (n - 2) / 2 } else { 0 };
        assert_eq!(s.model.pair_count(), n + non_adjacent, "{n} links");
    }
    assert_eq!(load("chain").model.nq(), 8);
}

/// A small valid scene; the bad snippets are variations of it.
const BASE: &str = r#"
version = 1
name = "base"
gravity = [0.0, -9.81]

[run]
t_end = 1.0

[contact]
e = 0.5
mu = 0.2

[[body]]
name = "rod"
mass = 1.0
com = [0.0, -0.5]
inertia = 0.1
joint = { type = "revolute", angle = "10 deg" }

[[body.shape]]
type = "ball"
radius = 0.1
at = [0.0, -1.0]

[[obstacle]]
name = "floor"
type = "halfspace"
point = [0.0, -2.0]
normal = [0.0, 1.0]
"#;

/// `BASE` with each line containing `find` replaced by `replace`, then `extra` appended.
fn variant(edits: &[(&str, &str)], extra: &str) -> String {
    let mut text = BASE.to_owned();
    for (find, replace) in edits {
        let line = text
            .lines()
            .find(|l| l.contains(find))
            .unwrap_or_else(|| panic!("{find}"))
            .to_owned();
        text = text.replacen(&line, replace, 1);
    }
    text + extra
}

/// One bad snippet: what it shows, its text, a string on the line the error must point at,
/// the field the error must name, and a part of its message.
struct Bad {
    what: &'static str,
    text: String,
    line_of: &'static str,
    field: &'static str,
    message: &'static str,
}

fn bad(
    what: &'static str,
    edits: &[(&str, &'static str)],
    line_of: &'static str,
    field: &'static str,
    message: &'static str,
) -> Bad {
    Bad {
        what,
        text: variant(edits, ""),
        line_of,
        field,
        message,
    }
}

fn bad_extra(
    what: &'static str,
    extra: &str,
    line_of: &'static str,
    field: &'static str,
    message: &'static str,
) -> Bad {
    Bad {
        what,
        text: variant(&[], extra),
        line_of,
        field,
        message,
    }
}

#[test]
fn the_base_snippet_is_valid() {
    let s = scene::load_str(BASE, "base.toml").unwrap();
    assert_eq!(s.model.nq(), 1);
    assert_eq!(s.initial.q[0], 10.0 * DEG);
}

#[test]
fn a_drift_budget_is_read_from_the_run_table() {
    assert_eq!(
        scene::load_str(BASE, "base.toml")
            .unwrap()
            .settings
            .max_drift,
        None
    );
    let text = variant(&[("t_end = 1.0", "t_end = 1.0\nmax_drift = 1e-9")], "");
    let s = scene::load_str(&text, "base.toml").unwrap();
    assert_eq!(s.settings.max_drift, Some(1e-9));
}

#[test]
fn bad_scenes_are_rejected_with_the_field_and_its_line() {
    const J: &str = "joint = ";
    let cases = vec![
        bad(
            "unknown top-level field",
            &[("gravity =", "gravty = [0.0, -9.81]")],
            "gravty",
            "gravty",
            "unknown field `gravty`",
        ),
        bad(
            "unknown body field",
            &[("inertia = 0.1", "inerta = 0.1")],
            "inerta",
            "body[\"rod\"].inerta",
            "unknown field `inerta`",
        ),
        bad(
            "wrong type",
            &[("mass = 1.0", "mass = \"heavy\"")],
            "heavy",
            "body[\"rod\"].mass",
            "invalid type",
        ),
        bad(
            "missing field",
            &[("mass = 1.0", "")],
            "[[body]]",
            "body[\"rod\"]",
            "missing field `mass`",
        ),
        bad(
            "syntax error",
            &[("mass = 1.0", "mass = 1.0.0")],
            "1.0.0",
            "body[\"rod\"].mass",
            "",
        ),
        bad(
            "negative mass",
            &[("mass = 1.0", "mass = -1.0")],
            "mass",
            "body[\"rod\"].mass",
            "the mass must be within [1e-9, 1e9] kg, got -1 kg",
        ),
        bad(
            "not-a-number mass",
            &[("mass = 1.0", "mass = nan")],
            "mass",
            "body[\"rod\"].mass",
            "the mass must be a finite number within [1e-9, 1e9] kg, got NaN",
        ),
        bad(
            "zero inertia",
            &[("inertia = 0.1", "inertia = 0.0")],
            "inertia",
            "body[\"rod\"].inertia",
            "the moment of inertia must be within [1e-21, 1e21] kg·m², got 0 kg·m²",
        ),
        bad(
            "infinite centre of mass",
            &[("com = ", "com = [inf, 0.0]")],
            "com",
            "body[\"rod\"].com",
            "finite",
        ),
        bad(
            "angle without unit",
            &[(J, "joint = { type = \"revolute\", angle = 10 }")],
            J,
            "body[\"rod\"].joint.angle",
            "needs its unit",
        ),
        bad(
            "unknown unit",
            &[(J, "joint = { type = \"revolute\", angle = \"10 degrees\" }")],
            J,
            "body[\"rod\"].joint.angle",
            "unknown unit `degrees`",
        ),
        bad(
            "rate in degrees",
            &[(J, "joint = { type = \"revolute\", rate = \"10 deg\" }")],
            J,
            "body[\"rod\"].joint.rate",
            "angular rate",
        ),
        bad(
            "unit on a length",
            &[(
                J,
                "joint = { type = \"prismatic\", axis = [0.0, 1.0], position = \"3 deg\" }",
            )],
            J,
            "body[\"rod\"].joint.position",
            "plain number",
        ),
        bad(
            "field of another joint type",
            &[(J, "joint = { type = \"revolute\", axis = [1.0, 0.0] }")],
            J,
            "body[\"rod\"].joint.axis",
            "a revolute joint has no field `axis`",
        ),
        bad(
            "prismatic without axis",
            &[(J, "joint = { type = \"prismatic\" }")],
            J,
            "body[\"rod\"].joint.type",
            "needs its `axis`",
        ),
        bad(
            "zero axis",
            &[(J, "joint = { type = \"prismatic\", axis = [0.0, 0.0] }")],
            J,
            "body[\"rod\"].joint.axis",
            "must not be zero",
        ),
        bad(
            "unknown joint type",
            &[(J, "joint = { type = \"hinge\" }")],
            J,
            "body[\"rod\"].joint.type",
            "unknown variant `hinge`",
        ),
        bad(
            "unknown parent",
            &[(J, "joint = { type = \"revolute\", parent = \"nobody\" }")],
            J,
            "body[\"rod\"].joint.parent",
            "unknown parent body `nobody`",
        ),
        bad(
            "negative stiffness",
            &[(J, "joint = { type = \"revolute\", stiffness = -2.0 }")],
            J,
            "body[\"rod\"].joint.stiffness",
            "non-negative",
        ),
        bad(
            "driven joint with a rate",
            &[(
                J,
                "joint = { type = \"revolute\", rate = \"1 rad/s\", drive = { rate = \"2 rad/s\" } }",
            )],
            J,
            "body[\"rod\"].joint.rate",
            "driven joint",
        ),
        bad(
            "restitution out of range",
            &[("e = 0.5", "e = 1.5")],
            "e = 1.5",
            "contact.e",
            "0 ≤ e ≤ 1, got 1.5",
        ),
        bad(
            "negative friction",
            &[("mu = 0.2", "mu = -0.2")],
            "mu",
            "contact.mu",
            "mu must be within [0, 1e6], got -0.2",
        ),
        bad(
            "unknown law",
            &[("e = 0.5", "law = \"hooke\"\ne = 0.5")],
            "hooke",
            "contact.law",
            "unknown variant `hooke`",
        ),
        bad(
            "overlap at the start",
            &[("point = [0.0, -2.0]", "point = [0.0, -0.5]")],
            "type = \"ball\"",
            "body[\"rod\"].shape[0].type",
            "`rod` and `floor` overlap by",
        ),
        bad(
            "zero radius",
            &[("radius = 0.1", "radius = 0.0")],
            "radius",
            "body[\"rod\"].shape[0].radius",
            "the radius must be within [1e-6, 1e6] m, got 0 m",
        ),
        bad(
            "field of another shape",
            &[("radius = 0.1", "half_extents = [0.1, 0.1]")],
            "half_extents",
            "body[\"rod\"].shape[0].half_extents",
            "a ball has no field `half_extents`",
        ),
        bad(
            "non-convex polygon",
            &[
                ("type = \"ball\"", "type = \"polygon\""),
                (
                    "radius = 0.1",
                    "points = [[0.0, 0.0], [1.0, 0.0], [0.2, 0.2], [0.0, 1.0]]",
                ),
            ],
            "points",
            "body[\"rod\"].shape[0].points",
            "convex polygon",
        ),
        bad(
            "zero normal",
            &[("normal = ", "normal = [0.0, 0.0]")],
            "normal",
            "obstacle[\"floor\"].normal",
            "must not be zero",
        ),
        bad(
            "unsupported version",
            &[("version = 1", "version = 2")],
            "version",
            "version",
            "unsupported scene version 2",
        ),
        bad(
            "zero end time",
            &[("t_end = 1.0", "t_end = 0.0")],
            "t_end",
            "run.t_end",
            "the end time must be within [1e-9, 1e9] s, got 0 s",
        ),
        bad(
            "zero drift budget",
            &[("t_end = 1.0", "t_end = 1.0\nmax_drift = 0.0")],
            "max_drift",
            "run.max_drift",
            "the drift budget max_drift must be within [1e-16, 1000], got 0",
        ),
        bad(
            "negative drift budget",
            &[("t_end = 1.0", "t_end = 1.0\nmax_drift = -1e-9")],
            "max_drift",
            "run.max_drift",
            "max_drift must be within [1e-16, 1000], got -1e-9",
        ),
        bad(
            "infinite drift budget",
            &[("t_end = 1.0", "t_end = 1.0\nmax_drift = inf")],
            "max_drift",
            "run.max_drift",
            "max_drift must be a finite number within [1e-16, 1000], got inf",
        ),
        bad(
            "NaN drift budget",
            &[("t_end = 1.0", "t_end = 1.0\nmax_drift = nan")],
            "max_drift",
            "run.max_drift",
            "max_drift must be a finite number within [1e-16, 1000], got NaN",
        ),
        bad(
            "drift budget as a string",
            &[("t_end = 1.0", "t_end = 1.0\nmax_drift = \"1e-9\"")],
            "max_drift",
            "run.max_drift",
            "invalid type",
        ),
        bad_extra(
            "unknown method",
            "\n[run.integrator]\nmethod = \"euler\"\n",
            "euler",
            "run.integrator.method",
            "unknown variant `euler`",
        ),
        bad_extra(
            "name used twice",
            "\n[[obstacle]]\nname = \"rod\" # twice\ntype = \"segment\"\na = [0.0, -3.0]\nb = [1.0, -3.0]\n",
            "# twice",
            "obstacle[\"rod\"].name",
            "the name `rod` is used twice",
        ),
        bad_extra(
            "pair of two obstacles",
            "\n[[obstacle]]\nname = \"wall\"\ntype = \"segment\"\na = [5.0, -3.0]\nb = [5.0, 3.0]\n\
             [[contact.pair]]\nbetween = [\"floor\", \"wall\"] # obstacles\n",
            "# obstacles",
            "contact.pair[0].between",
            "two obstacles of the world never touch",
        ),
        bad_extra(
            "pair with an unknown name",
            "\n[[contact.pair]]\nbetween = [\"rod\", \"ceiling\"]\n",
            "ceiling",
            "contact.pair[0].between[1]",
            "no body or obstacle is named `ceiling`",
        ),
        bad_extra(
            "cycle of parents",
            "\n[[body]]\nname = \"a\"\nmass = 1.0\ninertia = 0.1\njoint = { type = \"revolute\", parent = \"b\" }\n\
             [[body]]\nname = \"b\"\nmass = 1.0\ninertia = 0.1\njoint = { type = \"revolute\", parent = \"a\" }\n",
            "parent = \"b\"",
            "body[\"a\"].joint.parent",
            "the parents of a, b form a cycle",
        ),
        // Issue 12: hostile input that was accepted.
        bad(
            "a vector with five elements (the extra ones were dropped)",
            &[("gravity =", "gravity = [0.0, -9.81, 5.0, 1.0, 2.0]")],
            "gravity =",
            "gravity",
            "invalid length 5, expected a list of exactly two values",
        ),
        bad(
            "a vector with one element",
            &[("com = ", "com = [0.5]")],
            "com = ",
            "body[\"rod\"].com",
            "invalid length 1, expected a list of exactly two values",
        ),
        bad_extra(
            "a pair rule naming three",
            "\n[[contact.pair]]\nbetween = [\"rod\", \"floor\", \"rod\"]\n",
            "between = [",
            "contact.pair[0].between",
            "invalid length 3, expected a list of exactly two values",
        ),
        bad(
            "a subnormal mass",
            &[("mass = 1.0", "mass = 1e-320")],
            "mass =",
            "body[\"rod\"].mass",
            "the mass must be within [1e-9, 1e9] kg, got 1e-320 kg",
        ),
        bad(
            "a huge inertia",
            &[("inertia = 0.1", "inertia = 1e300")],
            "inertia =",
            "body[\"rod\"].inertia",
            "within [1e-21, 1e21] kg·m², got 1e300 kg·m²",
        ),
        bad(
            "a position beyond the range",
            &[("at = [0.0, -1.0]", "at = [1e7, -1.0]")],
            "at = [1e7",
            "body[\"rod\"].shape[0].at",
            "each component must be a finite number within ±1e6",
        ),
        bad(
            "an absurd angle",
            &[(J, "joint = { type = \"revolute\", angle = \"1e30 deg\" }")],
            "1e30 deg",
            "body[\"rod\"].joint.angle",
            "beyond ±1e6",
        ),
        bad(
            "an absurd end time",
            &[("t_end =", "t_end = 1e300")],
            "t_end =",
            "run.t_end",
            "the end time must be within [1e-9, 1e9] s, got 1e300 s",
        ),
        bad(
            "more samples than a run can write",
            &[("t_end =", "t_end = 1000.0\noutput_rate = 1e9")],
            "output_rate",
            "run.output_rate",
            "samples, more than 1e8",
        ),
        bad(
            "a tolerance the integrator cannot meet",
            &[("t_end =", "t_end = 1.0\n[run.integrator]\nrtol = 1e-20")],
            "rtol",
            "run.integrator.rtol",
            "rtol must be within [1e-14, 0.1], got 1e-20",
        ),
        bad(
            "more fixed steps than a run can take",
            &[(
                "t_end =",
                "t_end = 1e6\n[run.integrator]\nmethod = \"rk4\"\ndt = 1e-9",
            )],
            "dt = 1e-9",
            "run.integrator.dt",
            "steps, more than 1e10",
        ),
        bad(
            "a NUL in a name",
            &[("name = \"rod\"", "name = \"ro\\u0000d\"")],
            "name = \"ro",
            "body[\"ro\\0d\"].name",
            "a name must be printable, got the control character '\\0'",
        ),
        bad(
            "a newline in the scene's name",
            &[("name = \"base\"", "name = \"two\\nlines\"")],
            "name = \"two",
            "name",
            "a name must be printable",
        ),
        bad(
            // serde quotes the number with all its 309 digits; the file said 1e308.
            "a huge number for a name",
            &[("name = \"base\"", "name = 1e308")],
            "name = 1e308",
            "name",
            "invalid type: floating point `1e308`, expected a string",
        ),
        bad(
            "a slash in an obstacle's name",
            &[("name = \"floor\"", "name = \"../floor\"")],
            "../floor",
            "obstacle[\"../floor\"].name",
            "a name cannot contain `/`",
        ),
        bad(
            "a huge spring",
            &[(J, "joint = { type = \"revolute\", stiffness = 1e200 }")],
            "stiffness",
            "body[\"rod\"].joint.stiffness",
            "beyond ±1e12 (a force element)",
        ),
    ];
    let mut failures = Vec::new();
    for case in cases {
        let line = case
            .text
            .lines()
            .position(|l| l.contains(case.line_of))
            .unwrap_or_else(|| panic!("{}", case.line_of))
            + 1;
        match scene::load_str(&case.text, "bad.toml") {
            Ok(_) => failures.push(format!("{}: accepted", case.what)),
            Err(err) => {
                println!("{}: {err}", case.what);
                let shown = err.to_string();
                let ok = err.field() == Some(case.field)
                    && err.line() == Some(line)
                    && shown.contains(case.message)
                    && shown.starts_with(&format!("bad.toml:{line}:"));
                if !ok {
                    failures.push(format!(
                        "{}: expected `{}` at line {line} saying \"{}\", got {err:?}",
                        case.what, case.field, case.message
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_scene_with_shapes_needs_a_contact_table_and_io_errors_name_the_file() {
    let text = BASE.replace("[contact]\ne = 0.5\nmu = 0.2\n", "");
    let err = scene::load_str(&text, "bad.toml").unwrap_err();
    println!("{err}");
    assert!(err.to_string().contains("no [contact] table"), "{err}");
    let err = scene::load("no/such/scene.toml").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().starts_with("no/such/scene.toml: "), "{err}");
}

#[test]
fn pair_rules_drives_springs_and_bodies_hung_on_a_chain() {
    // A 3-link chain with a bob welded to its last link, a driven slider with a spring-free
    // joint, and pair rules: the bob may touch link2's parent–child neighbour link3 only
    // because the file says so; link1–floor is disabled; link2–floor has its own material.
    let text = r#"
version = 1
name = "rules"
[run]
t_end = 1.0
[contact]
law = "poisson"
e = 0.5
mu = 0.2
[[contact.pair]]
between = ["bob", "link3"]
enabled = true
[[contact.pair]]
between = ["link1", "floor"]
enabled = false
[[contact.pair]]
between = ["link2", "floor"]
law = "stronge"
e = 0.9
[chain]
links = 3
length = 0.5
mass = 0.2
radius = 0.01
[[body]]
name = "bob"
mass = 1.0
inertia = 0.001
joint = { type = "fixed", parent = "link3", at = [0.0, -0.6] }
[[body.shape]]
type = "ball"
radius = 0.05
[[body]]
name = "slider"
mass = 2.0
inertia = 0.1
joint = { type = "prismatic", axis = [1.0, 0.0], position = 0.1, drive = { rate = 0.5, amplitude = 0.2, angular_frequency = "1 Hz", phase = "90 deg" } }
[[body]]
name = "arm"
mass = 0.5
com = [0.0, -0.2]
inertia = 0.01
joint = { type = "revolute", parent = "slider", stiffness = 10.0, rest = "-30 deg", damping = 0.1, torque = 0.5 }
[[obstacle]]
name = "floor"
type = "halfspace"
point = [0.0, -3.0]
normal = [0.0, 1.0]
"#;
    let s = scene::load_str(text, "rules.toml").unwrap_or_else(|e| panic!("{e}"));
    let m = &s.model;
    let names: Vec<&str> = m.coordinates().iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["link1.q", "link2.q", "link3.q", "arm.q"]);
    let pairs: Vec<(String, String, &str, Real)> = m
        .pairs()
        .map(|p| {
            (
                m.colliders()[p.a.index()].name.clone(),
                m.colliders()[p.b.index()].name.clone(),
                p.material.law.name(),
                p.material.e,
            )
        })
        .collect();
    let has = |a: &str, b: &str| {
        pairs
            .iter()
            .find(|p| (p.0 == a && p.1 == b) || (p.0 == b && p.1 == a))
    };
    assert!(has("link1", "floor").is_none(), "{pairs:?}");
    assert_eq!(
        has("link2", "floor").map(|p| (p.2, p.3)),
        Some(("stronge", 0.9))
    );
    assert_eq!(
        has("link3", "floor").map(|p| (p.2, p.3)),
        Some(("poisson", 0.5))
    );
    assert!(
        has("bob", "link3").is_some(),
        "parent–child pair enabled by the file"
    );
    assert!(has("link1", "link3").is_some() && has("link1", "link2").is_none());
    // The drive: q(t) = 0.1 + 0.5 t + 0.2 sin(2π t + π/2).
    let slider = m.joint(m.body_by_name("slider").unwrap().joint()).unwrap();
    let drive = slider.drive.unwrap();
    assert_eq!((drive.q0, drive.rate, drive.amplitude), (0.1, 0.5, 0.2));
    assert!((drive.angular_frequency - 2.0 * std::f64::consts::PI).abs() < 1e-15);
    assert!((drive.phase - 90.0 * DEG).abs() < 1e-15);
    let arm = m.joint(m.body_by_name("arm").unwrap().joint()).unwrap();
    assert_eq!(
        (arm.force.stiffness, arm.force.damping, arm.force.effort),
        (10.0, 0.1, 0.5)
    );
    assert!((arm.force.rest - -30.0 * DEG).abs() < 1e-15);
}
