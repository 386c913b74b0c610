//! Issue 16's targets on Kane's double pendulum (`scenes/kane_double_pendulum.toml`, the
//! paper's Sect. 5: e = 0.5, μ = 0.2): its impacts, the accumulation at t ≈ 0.19 s, then
//! the tip sliding in persistent contact.
//!
//! - `run 5 s no log`: the whole simulation to 5 s at rtol 1e-10 with no observer (target
//!   ≤ 0.3 ms), with the scene's method, DOPRI5;
//! - `run 5 s no log dop853`: the same with DOP853;
//! - `run 5 s log 100 Hz`: the same with the MCAP log at 100 Hz into memory (target ≤ 1.2 ×
//!   the unlogged run);
//! - `run 5 s log 100 Hz uncompressed`: the same log with uncompressed chunks (what LZ4
//!   costs: ~0.3 ms of CPU per run, half the unlogged run, on the log's thread);
//! - `rhs free flight`: one right-hand side of the 2-DOF pendulum with no closed point
//!   (target ≤ 150 ns);
//! - `rhs one sliding point`: one right-hand side with the tip closed and sliding, the
//!   state and closed point of the run at t = 1 s (target ≤ 400 ns).
//!
//! The work counters of the run (steps, right-hand sides) are printed once.
//! `cargo bench -p ricochet-benches --bench kane`

use std::hint::black_box;
use std::io::Cursor;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use ricochet::integrate::{Method, OdeSystem};
use ricochet::log::{Compression, LogOptions, LogWriter, RunLogger};
use ricochet::scene::Scene;
use ricochet::sim::{MaterialOverride, MotionSystem, NullObserver, RunSummary, Simulation};

fn scene(t_end: f64) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/kane_double_pendulum.toml");
    let mut s = ricochet::scene::load(&path).expect("scenes/kane_double_pendulum.toml");
    s.settings.t_end = t_end;
    s.settings.integrator.rtol = 1e-10;
    s.settings.output_rate = 100.0;
    s
}

fn run(s: &Scene) -> RunSummary {
    let mut sim = Simulation::new(&s.model, &s.settings, MaterialOverride::default()).unwrap();
    sim.run(&s.initial, &mut NullObserver, None)
}

fn run_logged(s: &Scene, options: LogOptions) -> usize {
    let mut sim = Simulation::new(&s.model, &s.settings, MaterialOverride::default()).unwrap();
    let writer = LogWriter::new(Cursor::new(Vec::new()), options).unwrap();
    let mut log = RunLogger::for_scene(
        writer,
        s,
        &MaterialOverride::default(),
        sim.scales().gap_tol,
    )
    .unwrap();
    let summary = sim.run(&s.initial, &mut log, None);
    log.finish(&summary).unwrap().into_inner().len()
}

fn kane(c: &mut Criterion) {
    let s = scene(5.0);
    let summary = run(&s);
    println!(
        "\nkane_double_pendulum 5 s, rtol 1e-10: {} — {} impacts, {} steps ({} rejected), \
         {} rhs evaluations, {} events",
        summary.stop,
        summary.counters.impacts,
        summary.counters.steps,
        summary.counters.rejected,
        summary.counters.rhs_evals,
        summary.counters.events
    );
    let mut group = c.benchmark_group("kane");
    group.bench_function("run 5 s no log", |b| b.iter(|| black_box(run(&s))));
    // The same run with DOP853, the method for tight tolerances (issue 16): its extra
    // stages of the dense output are evaluated only for the steps read inside.
    let mut s853 = s.clone();
    s853.settings.integrator.method = Method::Dop853;
    let summary = run(&s853);
    println!(
        "the same with DOP853: {} steps ({} rejected), {} rhs evaluations, drift {:.3e} J",
        summary.counters.steps,
        summary.counters.rejected,
        summary.counters.rhs_evals,
        summary.audit.drift()
    );
    group.bench_function("run 5 s no log dop853", |b| {
        b.iter(|| black_box(run(&s853)))
    });
    group.bench_function("run 5 s log 100 Hz", |b| {
        b.iter(|| black_box(run_logged(&s, LogOptions::default())))
    });
    // The same log with its chunks not compressed (LZ4 is the default): what compression
    // costs the logged run.
    let uncompressed = LogOptions {
        compression: Compression::None,
        ..LogOptions::default()
    };
    group.bench_function("run 5 s log 100 Hz uncompressed", |b| {
        b.iter(|| black_box(run_logged(&s, uncompressed)))
    });

    // The right-hand side alone: free flight at the initial state, and with the tip
    // closed and sliding at the state of the run at t = 1 s.
    let mut system = MotionSystem::new(
        &s.model,
        Simulation::new(&s.model, &s.settings, MaterialOverride::default())
            .unwrap()
            .scales(),
    );
    let y0: Vec<f64> = (s.initial.q.iter().chain(s.initial.u.iter()).copied())
        .chain([0.0; 4])
        .collect();
    let mut dy = vec![0.0; system.dim()];
    group.bench_function("rhs free flight", |b| {
        b.iter(|| system.rhs(0.0, black_box(&y0), &mut dy).unwrap())
    });
    let at_1s = scene(1.0);
    let mut sim =
        Simulation::new(&at_1s.model, &at_1s.settings, MaterialOverride::default()).unwrap();
    let end = sim.run(&at_1s.initial, &mut NullObserver, None);
    let closed = sim.closed_points().to_vec();
    assert_eq!(closed.len(), 1, "one closed point at t = 1 s: {closed:?}");
    let mu = vec![0.2; closed.len()];
    system.persistent.set(closed, mu);
    let y1: Vec<f64> = (end.state.q.iter().chain(end.state.u.iter()).copied())
        .chain([0.0; 4])
        .collect();
    group.bench_function("rhs one sliding point", |b| {
        b.iter(|| system.rhs(1.0, black_box(&y1), &mut dy).unwrap())
    });
    group.finish();
}

criterion_group!(benches, kane);
criterion_main!(benches);
