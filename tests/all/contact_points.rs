//! `contact::contact_points`: the points of a pair within a tolerance, from parry's contact
//! manifolds — both ends of a flat feature lying on the other shape, what persistent
//! contact and time-stepping need to hold a rod or a block lying flat. Checked against the
//! geometry worked out by hand in each case.

use ricochet::contact::{ManifoldWorkspace, PairContact, contact_points};
use ricochet::kinematics::update_positions;
use ricochet::scene::load_str;
use ricochet::state::Data;

/// A scene with one planar body carrying `shape` and the obstacle `obstacle`.
fn scene(shape: &str, obstacle: &str) -> ricochet::scene::Scene {
    let text = format!(
        r#"
version = 1
name = "points"
[run]
t_end = 1.0
[contact]
e = 0.5
mu = 0.0
overlap_tolerance = 1.0
[[body]]
name = "body"
mass = 1.0
inertia = 0.1
joint = {{ type = "planar" }}
[[body.shape]]
{shape}
[[obstacle]]
name = "below"
{obstacle}
"#
    );
    load_str(&text, "points.toml").unwrap()
}

const FLOOR: &str = r#"type = "halfspace"
point = [0.0, 0.0]
normal = [0.0, 1.0]"#;

/// The contact points with a gap of at most 0 at the body pose `(x, y, θ)`, sorted by
/// `point_a.x`.
fn points(s: &ricochet::scene::Scene, q: [f64; 3]) -> Vec<PairContact> {
    points_within(s, q, 0.0)
}

/// The contact points with a gap of at most `tolerance` (m).
fn points_within(s: &ricochet::scene::Scene, q: [f64; 3], tolerance: f64) -> Vec<PairContact> {
    let mut data = Data::new(&s.model);
    update_positions(&s.model, &mut data, 0.0, &q).unwrap();
    let pair = s.model.pair_ids().next().unwrap();
    let mut ws = ManifoldWorkspace::default();
    let mut out = contact_points(&s.model, &data, pair, tolerance, &mut ws)
        .unwrap()
        .to_vec();
    out.sort_by(|a, b| a.point_a.x.total_cmp(&b.point_a.x));
    out
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12
}

#[test]
fn a_rod_lying_on_the_floor_touches_at_both_ends() {
    // A capsule from (−0.5, 0) to (0.5, 0), radius 0.01: with its centre at height
    // y = 0.005 and θ = 0 both end caps dip 0.005 m into the floor.
    let s = scene(
        r#"type = "capsule"
a = [-0.5, 0.0]
b = [0.5, 0.0]
radius = 0.01"#,
        FLOOR,
    );
    let p = points(&s, [0.0, 0.005, 0.0]);
    assert_eq!(p.len(), 2, "{p:?}");
    for (c, x) in p.iter().zip([-0.5, 0.5]) {
        assert!(close(c.gap, -0.005) && close(c.point_a.x, x), "{c:?}");
        assert!(
            close(c.point_a.y, -0.005) && close(c.point_b.y, 0.0),
            "{c:?}"
        );
        assert!(close(c.normal.y, -1.0), "{c:?}");
    }
    // Tilted by θ = 0.01 rad with its centre at y = 0: the left end is 0.5 sin θ lower,
    // gaps 0.5 sin θ·(∓1) − 0.01 (the caps' lowest points).
    let th: f64 = 0.01;
    let p = points(&s, [0.0, 0.0, th]);
    assert_eq!(p.len(), 2, "{p:?}");
    assert!(close(p[0].gap, -0.5 * th.sin() - 0.01), "{:?}", p[0]);
    assert!(close(p[1].gap, 0.5 * th.sin() - 0.01), "{:?}", p[1]);
    // Raised so that only the left end touches: one point; apart: none, unless the
    // tolerance reaches that far (then both ends, level, with their positive gap).
    assert_eq!(points(&s, [0.0, 0.01, th]).len(), 1);
    assert!(points(&s, [0.0, 1.0, 0.0]).is_empty());
    let p = points_within(&s, [0.0, 1.0, 0.0], 2.0);
    assert!(
        !p.is_empty() && p.iter().all(|c| close(c.gap, 0.99)),
        "{p:?}"
    );
}

#[test]
fn a_block_on_a_wider_block_touches_at_its_two_corners_only() {
    // A 0.4 × 0.2 block (half extents 0.2, 0.1) on a 2 × 1 table whose top is y = 0,
    // sunk 1 mm: its two lower corners (±0.2, −0.001) are contact points; the table's
    // corners (±1, 0) are not under the block, so they are not.
    let table = r#"type = "cuboid"
half_extents = [1.0, 0.5]
at = [0.0, -0.5]"#;
    let s = scene(
        r#"type = "cuboid"
half_extents = [0.2, 0.1]"#,
        table,
    );
    let p = points(&s, [0.0, 0.099, 0.0]);
    assert_eq!(p.len(), 2, "{p:?}");
    for (c, x) in p.iter().zip([-0.2, 0.2]) {
        assert!(close(c.point_a.x, x) && close(c.gap, -0.001), "{c:?}");
    }
    // Overhanging the table's right edge (x = 1) by 0.1: its right corner is beyond the
    // table; the table's corner (1, 0) is under the block instead.
    let p = points(&s, [0.9, 0.099, 0.0]);
    assert_eq!(p.len(), 2, "{p:?}");
    assert!(
        close(p[0].point_a.x, 0.7) && close(p[0].gap, -0.001),
        "{:?}",
        p[0]
    );
    assert!(
        close(p[1].point_b.x, 1.0) && close(p[1].point_b.y, 0.0),
        "{:?}",
        p[1]
    );
    assert!(close(p[1].gap, -0.001), "{:?}", p[1]);
}

#[test]
fn a_ball_touches_at_one_point() {
    let s = scene(
        r#"type = "ball"
radius = 0.1"#,
        FLOOR,
    );
    let p = points(&s, [0.3, 0.09, 0.0]);
    assert_eq!(p.len(), 1);
    assert!(close(p[0].gap, -0.01) && close(p[0].point_a.x, 0.3));
}
