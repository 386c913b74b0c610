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
    let (rec, summary, used) = run(scene, true);
    let (oracle, oracle_summary, none) = run(scene, false);
    assert_eq!(none.used, 0, "{name}: stand-ins used while forbidden");
    assert_eq!(none.taken, 0, "{name}: an evaluation taken while forbidden");
    assert_eq!(none.samples, used.samples, "{name}: other samples");
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

    let mut chain = scene("scenes/chain_floor.toml");
    chain.settings.t_end = 1.0;
    let c = same_with_and_without("chain_floor 1 s", &chain);
    println!("chain_floor 1 s: {c:?}");
    assert!(c.used > 0, "chain_floor 1 s: {c:?}");
}
