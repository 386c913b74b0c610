//! The broad phase of the loop (issue 15, `src/sim/broad.rs`): each step samples only the
//! pairs whose boxes, swept over the step, overlap. It must miss no contact: every run
//! here equals, bit for bit (impacts, transitions, final state, counters), the same run
//! with the broad phase off (`Simulation::set_broad_phase(false)`: every pair sampled at
//! every step, as before it existed), and its first impacts meet their closed forms.

use std::f64::consts::FRAC_PI_2;

use ricochet::math::Real;
use ricochet::model::PairId;
use ricochet::scene::Scene;
use ricochet::sim::{MaterialOverride, Recorder, RunSummary, Simulation, StopReason};

fn load(text: &str) -> Scene {
    ricochet::scene::load_str(text, "broad.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene, broad_phase: bool) -> (Recorder, RunSummary) {
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    sim.set_broad_phase(broad_phase);
    let mut rec = Recorder {
        keep_samples: true,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary)
}

/// Runs `scene` with and without the broad phase and asserts the two runs are the same to
/// the last bit; returns the run.
fn same_with_and_without(scene: &Scene) -> (Recorder, RunSummary) {
    let (rec, summary) = run(scene, true);
    let (oracle, oracle_summary) = run(scene, false);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{:?}",
        summary.stop
    );
    assert_eq!(format!("{summary:?}"), format!("{oracle_summary:?}"));
    assert_eq!(rec.impacts.len(), oracle.impacts.len());
    for (k, (a, b)) in rec.impacts.iter().zip(&oracle.impacts).enumerate() {
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "impact #{k}");
    }
    assert_eq!(
        format!("{:?}", rec.transitions),
        format!("{:?}", oracle.transitions)
    );
    assert_eq!(rec.samples, oracle.samples);
    (rec, summary)
}

fn pair(scene: &Scene, a: &str, b: &str) -> PairId {
    let c = |name| scene.model.collider_by_name(name).unwrap();
    scene.model.pair_between(c(a), c(b)).unwrap()
}

/// A small deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: Real, hi: Real) -> Real {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as Real / (1u64 << 53) as Real)
    }
}

const WALLS: &str = r#"
[[obstacle]]
name = "floor"
type = "halfspace"
point = [0.0, 0.0]
normal = [0.0, 1.0]
[[obstacle]]
name = "ceiling"
type = "halfspace"
point = [0.0, 1.0]
normal = [0.0, -1.0]
[[obstacle]]
name = "left"
type = "halfspace"
point = [0.0, 0.0]
normal = [1.0, 0.0]
[[obstacle]]
name = "right"
type = "halfspace"
point = [1.0, 0.0]
normal = [-1.0, 0.0]
"#;

/// Forty small fast balls (radius 1 cm, up to 50 m/s, no gravity, e = 1) in a 1 m box:
/// in 0.1 s each crosses the box a few times, striking the walls and each other and
/// passing close to many more. The same run as with every pair sampled.
#[test]
fn fast_small_balls_in_a_box_miss_nothing() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut text = String::from(
        "version = 1\nname = \"fast_balls\"\ngravity = [0.0, 0.0]\n[run]\nt_end = 0.1\n\
         output_rate = 100.0\n[contact]\ne = 1.0\nmu = 0.0\n",
    );
    for k in 0..40 {
        let (x, y) = (0.1 + 0.125 * (k % 7) as Real, 0.1 + 0.13 * (k / 7) as Real);
        let (x, y) = (x + rng.uniform(-0.02, 0.02), y + rng.uniform(-0.02, 0.02));
        let (vx, vy) = (rng.uniform(-50.0, 50.0), rng.uniform(-50.0, 50.0));
        text.push_str(&format!(
            "[[body]]\nname = \"b{k}\"\nmass = 0.01\ninertia = 1e-6\n\
             joint = {{ type = \"planar\", x = {x}, y = {y}, vx = {vx}, vy = {vy} }}\n\
             [[body.shape]]\ntype = \"ball\"\nradius = 0.01\n"
        ));
    }
    text.push_str(WALLS);
    let scene = load(&text);
    let (rec, _) = same_with_and_without(&scene);
    let balls = |ev: &&ricochet::sim::ImpactEvent| {
        let p = scene.model.pair_of(ev.frame.pair);
        scene.model.colliders()[p.b.index()].body.is_some()
    };
    let between_balls = rec.impacts.iter().filter(balls).count();
    println!(
        "{} impacts, {between_balls} between balls",
        rec.impacts.len()
    );
    assert!(rec.impacts.len() > 200, "{} impacts", rec.impacts.len());
    assert!(between_balls >= 5, "{between_balls} between balls");
}

/// Two small balls (radius 1 cm) fly at each other at 100 m/s each along x, their paths
/// `b` apart: they strike when their centres are `2r` apart, at
/// `t = (d − √(4r² − b²)) / 200` (`d` the initial distance along x); at `b = 2.05 r` they
/// pass 0.5 mm apart and never touch.
#[test]
fn fast_small_balls_passing_close_strike_on_time_or_not_at_all() {
    let (r, d): (Real, Real) = (0.01, 1.0);
    for (offset, strikes) in [(1.9 * r, true), (1.5 * r, true), (2.05 * r, false)] {
        let text = format!(
            "version = 1\nname = \"pass\"\ngravity = [0.0, 0.0]\n[run]\nt_end = 0.02\n\
             [contact]\ne = 1.0\nmu = 0.0\n\
             [[body]]\nname = \"a\"\nmass = 0.01\ninertia = 1e-6\n\
             joint = {{ type = \"planar\", x = 0.0, y = 0.0, vx = 100.0 }}\n\
             [[body.shape]]\ntype = \"ball\"\nradius = {r}\n\
             [[body]]\nname = \"b\"\nmass = 0.01\ninertia = 1e-6\n\
             joint = {{ type = \"planar\", x = {d}, y = {offset}, vx = -100.0 }}\n\
             [[body.shape]]\ntype = \"ball\"\nradius = {r}\n"
        );
        let scene = load(&text);
        let (rec, _) = same_with_and_without(&scene);
        if strikes {
            let t = (d - (4.0 * r * r - offset * offset).sqrt()) / 200.0;
            assert_eq!(rec.impacts.len(), 1, "offset {offset}");
            assert!((rec.impacts[0].t - t).abs() < 1e-12, "offset {offset}");
        } else {
            assert!(rec.impacts.is_empty(), "offset {offset}");
        }
    }
}

/// A rod (1 m, a capsule of radius 2 cm) spinning at −50 rad/s about its end, from
/// upright, sweeps a ball (radius 5 cm) at rest 0.8 m from the pivot, no gravity: their
/// boxes are far apart at the start. The rod's surface reaches the ball when its axis is
/// `r_b + r_r` from the ball's centre, `0.8 sin θ = r_b + r_r`, at
/// `t = (π/2 − θ) / 50` (the rod turns freely until then).
#[test]
fn a_spinning_rod_sweeps_a_ball() {
    let text = r#"
version = 1
name = "sweep"
gravity = [0.0, 0.0]
[run]
t_end = 0.1
[contact]
e = 0.5
mu = 0.2
[[body]]
name = "rod"
mass = 1.0
com = [0.5, 0.0]
inertia = 0.0833333333333333
joint = { type = "revolute", angle = "90 deg", rate = "-50 rad/s" }
[[body.shape]]
type = "capsule"
a = [0.0, 0.0]
b = [1.0, 0.0]
radius = 0.02
[[body]]
name = "ball"
mass = 0.1
inertia = 1e-4
joint = { type = "planar", x = 0.8, y = 0.0 }
[[body.shape]]
type = "ball"
radius = 0.05
"#;
    let scene = load(text);
    let (rec, _) = same_with_and_without(&scene);
    let theta = (0.07 / 0.8 as Real).asin();
    let t = (FRAC_PI_2 - theta) / 50.0;
    assert!(!rec.impacts.is_empty());
    assert_eq!(rec.impacts[0].frame.pair, pair(&scene, "rod", "ball"));
    assert!(
        (rec.impacts[0].t - t).abs() < 1e-10,
        "{} against {t}",
        rec.impacts[0].t
    );
}

/// A ball (radius 0.1 m) dropped from 1 m into a gap 0.12 m wide between two fixed blocks
/// whose tops are at y = 0: it lands on both top corners at once, when its centre is
/// `√(r² − (w/2)²) = 0.08` m above them, at `t = √(2 · 0.92 / g)`; both pairs get their
/// impulse at that instant (Moreau's law, the two points together); it bounces between
/// them (to 1.5 s: at 1.707 s the run stalls, "1000 events without the time advancing",
/// as it did before the broad phase: a ball coming to rest on two corners, not the
/// broad phase's doing).
#[test]
fn a_ball_dropped_into_a_gap_between_two_bodies() {
    let text = r#"
version = 1
name = "gap"
gravity = [0.0, -9.81]
[run]
t_end = 1.5
[contact]
e = 0.5
mu = 0.3
[[body]]
name = "left"
mass = 10.0
inertia = 1.0
joint = { type = "fixed", at = [-0.56, -0.5] }
[[body.shape]]
type = "cuboid"
half_extents = [0.5, 0.5]
[[body]]
name = "right"
mass = 10.0
inertia = 1.0
joint = { type = "fixed", at = [0.56, -0.5] }
[[body.shape]]
type = "cuboid"
half_extents = [0.5, 0.5]
[[body]]
name = "ball"
mass = 1.0
inertia = 0.004
joint = { type = "planar", x = 0.0, y = 1.0 }
[[body.shape]]
type = "ball"
radius = 0.1
"#;
    let scene = load(text);
    let (rec, _) = same_with_and_without(&scene);
    let t = (2.0 * 0.92 / 9.81 as Real).sqrt();
    let first: Vec<_> = (rec.impacts.iter())
        .filter(|ev| (ev.t - t).abs() < 1e-9)
        .map(|ev| ev.frame.pair)
        .collect();
    assert!(
        first.contains(&pair(&scene, "ball", "left"))
            && first.contains(&pair(&scene, "ball", "right")),
        "impacts {:?}",
        (rec.impacts.iter())
            .map(|ev| (ev.t, ev.frame.pair))
            .collect::<Vec<_>>()
    );
    assert!((rec.impacts[0].t - t).abs() < 1e-9, "{}", rec.impacts[0].t);
    assert!(rec.impacts.len() > 2, "it bounces");
}

/// A ball (radius 0.1 m, 1 kg) on a stiff spring (a prismatic joint along x, `k = 1e4`
/// N/m, rest at x = 2 m) released at rest 10 µm from a wall (a block whose face is at
/// x = 1; a half-space's box is the whole plane, always a candidate), no gravity. Contact
/// at `x + r = 1`, `x(t) = 2 − 1.10001 cos ωt`, `ω = √(k/m)`, at 43 µs. Under RK4 with
/// `dt = 1 ms` the first step starts at rest: the speeds and gravity bound no motion, so
/// the pair is not a candidate before it, and the spring takes the ball 5 mm within it,
/// through the wall; the boxes at the locator's samples make the pair a candidate (without
/// them this run had no impact). Under DOPRI5 the first steps are short and the speed
/// bound covers the next ones.
#[test]
fn a_ball_thrown_by_a_spring_is_seen_by_the_swept_boxes() {
    let text = r#"
version = 1
name = "spring"
gravity = [0.0, 0.0]
[run]
t_end = 0.001
[run.integrator]
method = "METHOD"
dt = 1e-3
[contact]
e = 0.5
mu = 0.0
[[body]]
name = "ball"
mass = 1.0
inertia = 0.004
joint = { type = "prismatic", axis = [1.0, 0.0], stiffness = 1e4, rest = 2.0, position = 0.89999 }
[[body.shape]]
type = "ball"
radius = 0.1
[[obstacle]]
name = "wall"
type = "cuboid"
half_extents = [0.5, 0.5]
at = [1.5, 0.0]
"#;
    let omega = (1e4 as Real).sqrt();
    let t = (1.1 / 1.10001 as Real).acos() / omega;
    for (method, tol) in [("dopri5", 1e-12), ("rk4", 1e-8)] {
        let scene = load(&text.replace("METHOD", method));
        let (rec, _) = same_with_and_without(&scene);
        assert!(!rec.impacts.is_empty(), "{method}: no impact");
        assert!(
            (rec.impacts[0].t - t).abs() < tol,
            "{method}: {} against {t}",
            rec.impacts[0].t
        );
    }
}

/// Half-spaces have boxes that fill the plane; the broad phase pairs each with the
/// colliders whose boxes reach its region `n·x ≤ n·p + margin` alone. Twenty balls and
/// spinning boxes dropped from heights 0.1–5 m onto a tilted floor beside a wall (both
/// half-spaces), bouncing and sliding down to the wall for 1.5 s: the same run, bit for
/// bit, as with every pair sampled, and every body comes to the floor.
#[test]
fn bodies_dropped_on_tilted_half_spaces_miss_nothing() {
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut text = String::from(
        "version = 1\nname = \"drops\"\ngravity = [0.0, -9.81]\n[run]\nt_end = 1.5\n\
         output_rate = 50.0\n[contact]\ne = 0.6\nmu = 0.3\n",
    );
    for k in 0..20 {
        let (x, y) = (
            0.2 + 0.3 * k as Real,
            rng.uniform(0.1, 3.0) + 0.1 * k as Real,
        );
        let (w, vx) = (rng.uniform(-30.0, 30.0), rng.uniform(-2.0, 2.0));
        let shape = if k % 2 == 0 {
            "type = \"ball\"\nradius = 0.05\n"
        } else {
            "type = \"cuboid\"\nhalf_extents = [0.08, 0.03]\n"
        };
        text.push_str(&format!(
            "[[body]]\nname = \"b{k}\"\nmass = 0.1\ninertia = 1e-4\n\
             joint = {{ type = \"planar\", x = {x}, y = {y}, vx = {vx}, rate = \"{w} rad/s\" }}\n\
             [[body.shape]]\n{shape}"
        ));
    }
    text.push_str(
        "[[obstacle]]\nname = \"floor\"\ntype = \"halfspace\"\npoint = [0.0, 0.0]\n\
         normal = [0.1, 0.995]\n[[obstacle]]\nname = \"wall\"\ntype = \"halfspace\"\n\
         point = [-0.5, 0.0]\nnormal = [1.0, 0.0]\n",
    );
    let scene = load(&text);
    let (rec, _) = same_with_and_without(&scene);
    let struck: std::collections::BTreeSet<usize> = (rec.impacts.iter())
        .map(|ev| scene.model.pair_of(ev.frame.pair).a.index())
        .collect();
    println!(
        "{} impacts, {} bodies struck",
        rec.impacts.len(),
        struck.len()
    );
    assert_eq!(struck.len(), 20, "{struck:?}");
}
