//! Issue 11: long runs do not slow down. The rimless wheel's 1,000 s took 66 times the
//! wall time of its 100 s: the velocity products of the closed contacts were central
//! differences with a tiny step, which divided the rounding of the positions (growing with
//! the distance from the origin, 740 m after 1000 s) by that step, and the noise grew into
//! the integrator's error estimate. The cost per simulated second is now flat, counted in
//! steps and right-hand-side evaluations (deterministic, unlike a timing).

use ricochet::sim::{MaterialOverride, NullObserver, RunSummary, Simulation, StopReason};

fn wheel(t_end: f64) -> RunSummary {
    let mut scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/rimless_wheel.toml"
    ))
    .unwrap();
    scene.settings.t_end = t_end;
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let summary = sim.run(&scene.initial, &mut NullObserver, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    summary
}

#[test]
fn the_rimless_wheel_costs_the_same_per_second_after_1000_s() {
    let (short, long) = (wheel(100.0), wheel(1000.0));
    let per_second =
        |s: &RunSummary, t: f64| (s.counters.steps as f64 / t, s.counters.rhs_evals as f64 / t);
    let (steps_100, rhs_100) = per_second(&short, 100.0);
    // The last 900 s on their own.
    let steps_900 = (long.counters.steps - short.counters.steps) as f64 / 900.0;
    let rhs_900 = (long.counters.rhs_evals - short.counters.rhs_evals) as f64 / 900.0;
    println!(
        "rimless wheel: {steps_100:.1} steps/s, {rhs_100:.1} rhs/s over [0, 100] s; \
         {steps_900:.1} steps/s, {rhs_900:.1} rhs/s over [100, 1000] s; {} rejected steps \
         in 1000 s; x = {:.0} m",
        long.counters.rejected, long.state.q[0]
    );
    assert!(
        long.state.q[0].abs() > 500.0,
        "it rolled far: {}",
        long.state.q[0]
    );
    assert!(steps_900 <= 1.05 * steps_100, "{steps_900} vs {steps_100}");
    assert!(rhs_900 <= 1.05 * rhs_100, "{rhs_900} vs {rhs_100}");
    // Almost no rejected steps: no noise in the error estimate.
    assert!(
        (long.counters.rejected as f64) < 0.01 * long.counters.steps as f64,
        "{} of {}",
        long.counters.rejected,
        long.counters.steps
    );
}
