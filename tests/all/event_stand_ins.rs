//! The stand-ins of the force functions at the interior samples of the event location
//! (issues 15 and 16, `src/sim/gaps.rs`, `StandIns`): a step whose force functions
//! (`λ_n`, the friction margins, the Painlevé coefficients of the closed points) cannot
//! reach zero, by their values at the step's start and stages, samples only the kinematic
//! functions inside it instead of solving the constrained dynamics at each sample; and the
//! sample at a step's end takes the forces the right-hand side solved at DOPRI5's last
//! stage, the same state (`GapFunctions::take_end_evaluation`). Neither may
//! change anything: every run here equals, bit for bit (impacts, messages, transitions,
//! samples, final state, counters), the same run with every sample computed
//! (`Simulation::set_stand_ins(false)`), and the stand-ins were used.

use std::path::Path;

use ricochet::integrate::Method;
use ricochet::scene::Scene;
use ricochet::sim::gaps::StandInCounts;
use ricochet::sim::{MaterialOverride, Recorder, RunSummary, Simulation};

fn scene(path: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    ricochet::scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// One run, and what the stand-ins did.
fn run(scene: &Scene, stand_ins: bool) -> (Recorder, RunSummary, StandInCounts) {
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    sim.set_stand_ins(stand_ins);
    let mut rec = Recorder {
        keep_samples: true,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary, sim.stand_in_counts())
}

/// Runs `scene` with and without the stand-ins, asserts the runs are the same to the last
/// bit, and returns what they did.
fn same_with_and_without(name: &str, scene: &Scene) -> StandInCounts {
    let (rec, mut summary, used) = run(scene, true);
    let (oracle, oracle_summary, none) = run(scene, false);
    assert_eq!(none.used, 0, "{name}: stand-ins used while forbidden");
    assert_eq!(none.taken, 0, "{name}: an evaluation taken while forbidden");
    assert_eq!(none.samples, used.samples, "{name}: other samples");
    // DOP853 completes a step's dense output (3 evaluations) only where the location reads
    // the step inside, which the stand-ins spare: fewer evaluations, by threes, nothing
    // else. The other methods evaluate the same.
    let (n, n_oracle) = (
        summary.counters.rhs_evals,
        oracle_summary.counters.rhs_evals,
    );
    if scene.settings.integrator.method == Method::Dop853 {
        assert!(
            n <= n_oracle && (n_oracle - n).is_multiple_of(3),
            "{name}: {n} vs {n_oracle}"
        );
        summary.counters.rhs_evals = n_oracle;
    }
    assert_eq!(
        format!("{summary:?}"),
        format!("{oracle_summary:?}"),
        "{name}: summary"
    );
    let fields = [
        (
            format!("{:?}", rec.impacts),
            format!("{:?}", oracle.impacts),
        ),
        (
            format!("{:?}", rec.messages),
            format!("{:?}", oracle.messages),
        ),
        (
            format!("{:?}", rec.transitions),
            format!("{:?}", oracle.transitions),
        ),
        (
            format!("{:?}", rec.samples),
            format!("{:?}", oracle.samples),
        ),
    ];
    for (k, (a, b)) in fields.iter().enumerate() {
        assert!(a == b, "{name}: record {k} differs");
    }
    used
}

/// The bundled scenes with persistent contact, under the three Runge–Kutta methods (the
/// stand-ins rest on the stages of any method; RK4's 7,248 interior samples of Kane's
/// pendulum all used them).
#[test]
fn bundled_scenes_are_the_same_bit_for_bit() {
    let scenes = [
        "kane_double_pendulum",
        "falling_rod",
        "rocking_block",
        "rimless_wheel",
        "painleve_rod",
        "chain",
    ];
    for name in scenes {
        let mut s = scene(&format!("scenes/{name}.toml"));
        for method in [Method::Dopri5, Method::Dop853, Method::Rk4] {
            s.settings.integrator.method = method;
            let c = same_with_and_without(&format!("{name} {method:?}"), &s);
            println!("{name} {method:?}: {c:?}");
            assert!(c.used > 0, "{name} {method:?}: no stand-in used");
        }
    }
}

/// Kane's pendulum for 5 s at rtol 1e-10 (issue 16's benchmark), and the 32-link chain
/// falling on the floor through its first whip and the first links lying down (issue 15):
/// up to 45 coupled points.
#[test]
fn the_pendulum_and_the_chain_on_the_floor_are_the_same_bit_for_bit() {
    let mut kane = scene("scenes/kane_double_pendulum.toml");
    kane.settings.t_end = 5.0;
    kane.settings.integrator.rtol = 1e-10;
    let c = same_with_and_without("kane 5 s", &kane);
    println!("kane 5 s: {c:?}");
    // Sliding on the floor from 0.19 s on, far from lift-off: most interior samples skip
    // the constrained dynamics (measured: all 664).
    assert!(4 * c.used >= 3 * c.samples, "kane 5 s: {c:?}");
    // DOPRI5's last stage is the step's end: each step of the sliding phase takes it.
    assert!(c.taken > 100, "kane 5 s: {c:?}");
    // The far end of rod B metres above the floor, the tip sliding far from a stop: most
    // interior samples compute nothing at all (measured: 600 of the 784, 664 of them
    // with the tip closed).
    assert!(10 * c.skipped >= 8 * c.samples, "kane 5 s: {c:?}");

    let mut chain = scene("scenes/chain_floor.toml");
    chain.settings.t_end = 1.0;
    let c = same_with_and_without("chain_floor 1 s", &chain);
    println!("chain_floor 1 s: {c:?}");
    assert!(c.used > 0, "chain_floor 1 s: {c:?}");
}

/// The bundled scenes of free flight and impacts (no or few closed points): the gaps'
/// stand-ins (far pairs, bodies that cannot reach each other within the step) change
/// nothing, and some interior samples compute nothing.
#[test]
fn scenes_of_impacts_are_the_same_bit_for_bit() {
    let scenes = [
        "bouncing_ball",
        "newtons_cradle",
        "pendulum_wall",
        "spinning_disk_particle",
        "sled_rock",
        "wagon_curb",
    ];
    let mut skipped = 0;
    for name in scenes {
        let mut s = scene(&format!("scenes/{name}.toml"));
        for method in [Method::Dopri5, Method::Dop853, Method::Rk4] {
            s.settings.integrator.method = method;
            let c = same_with_and_without(&format!("{name} {method:?}"), &s);
            println!("{name} {method:?}: {c:?}");
            skipped += c.skipped;
        }
    }
    assert!(skipped > 0);
}

/// A capsule spinning at 300 rad/s thrown down at the floor at 20 m/s, one spinning at
/// 80 rad/s just above it, and a ball at 60 m/s: a gap gets no stand-in in a step where
/// the spin or the approach can close it (the rotation bound `|v| + |ω| r` of the step's
/// start and the fall refuse it; `gaps::tests` checks the rule on the exact gap of a
/// spinning, falling segment). The first impact is where the body's lowest point
/// `y − r|sin θ| − ρ` (from the free flight, exactly) reaches the floor, the same with and
/// without stand-ins, bit for bit.
#[test]
fn a_fast_spin_or_approach_within_the_step_gets_no_stand_in() {
    let g = 9.81;
    let throws = [
        // (shape, half-length r, radius ρ, y0, vy0, θ0, ω)
        (
            "type = \"capsule\"\na = [-0.5, 0.0]\nb = [0.5, 0.0]\nradius = 0.02",
            0.5,
            0.02,
            3.0,
            -20.0,
            0.3,
            300.0,
        ),
        (
            "type = \"capsule\"\na = [-0.5, 0.0]\nb = [0.5, 0.0]\nradius = 0.02",
            0.5,
            0.02,
            1.2,
            -1.0,
            1.0,
            -80.0,
        ),
        (
            "type = \"ball\"\nradius = 0.1",
            0.0,
            0.1,
            4.0,
            -60.0,
            0.0,
            0.0,
        ),
    ];
    for (k, &(shape, r, rho, y0, vy0, th0, w)) in throws.iter().enumerate() {
        let lowest = |t: f64| y0 + vy0 * t - 0.5 * g * t * t - r * (th0 + w * t).sin().abs() - rho;
        // The first contact: a fine scan, then bisection.
        let dt = 1e-6;
        let mut t = 0.0;
        while lowest(t + dt) > 0.0 {
            t += dt;
        }
        let (mut lo, mut hi) = (t, t + dt);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if lowest(mid) > 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let text = format!(
            "version = 1\nname = \"throw_{k}\"\ngravity = [0.0, {}]\n[run]\nt_end = {}\n\
             output_rate = 100.0\n[contact]\nlaw = \"newton\"\ne = 0.5\nmu = 0.3\n\
             [[body]]\nname = \"body\"\nmass = 1.0\ninertia = 0.05\ncom = [0.0, 0.0]\n\
             joint = {{ type = \"planar\", x = 0.0, y = {y0}, angle = \"{th0} rad\", vx = 0.0, \
             vy = {vy0}, rate = \"{w} rad/s\" }}\n[[body.shape]]\n{shape}\n[[obstacle]]\n\
             name = \"floor\"\ntype = \"halfspace\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n",
            -g,
            hi + 1e-3
        );
        let s = ricochet::scene::load_str(&text, format!("throw_{k}.toml"))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        let c = same_with_and_without(&format!("throw {k}"), &s);
        println!("throw {k}: first contact {hi}, {c:?}");
        assert!(c.gaps_refused > 0, "throw {k}: no gap refused: {c:?}");
        let (rec, _, _) = run(&s, true);
        let first = rec.impacts.first().map(|i| i.t);
        assert!(
            first.is_some_and(|t| (t - hi).abs() < 1e-9),
            "throw {k}: first impact {first:?}, the first contact at {hi}"
        );
    }
}
