//! A whole simulation: Kane and Levinson's double pendulum (`scenes/kane_double_pendulum.toml`)
//! for 10 simulated seconds with its impacts, without a log and with the MCAP log at
//! 100 Hz, to see what logging costs.
//!
//! The scene as written (e = 0.5) ends its bouncing in an accumulation of impacts at
//! t ≈ 0.19 s and then slides and swings in persistent contact: few impacts in 10 s. To
//! keep it bouncing the bench overrides the restitution to **e = 1** and keeps the scene's
//! friction (μ = 0.2, Newton's law): the normal rebound never decays, friction still takes
//! energy (about 3.6 J of 108 J), and the impacts go through both forward and reverse
//! sliding (Routh's path with a slip reversal), like the scene's own impacts; 93 impacts
//! in the 10 s. (An elastic frictionless override, e = 1 and μ = 0, also runs 10 s but
//! makes every impact a single frictionless phase; a variant scene with a lower floor
//! would change the paper's geometry.) The `[run]` output rate is set to 100 Hz.
//!
//! Three runs of the same simulation:
//! - `no log`: a [`NullObserver`], which asks for no samples: the simulation alone;
//! - `samples only`: a [`Recorder`] keeping the samples in memory: the cost of sampling at
//!   100 Hz (dense output, energies, gaps, body poses), without encoding;
//! - `mcap log 100 Hz`: the [`RunLogger`] writing log format 2 (`/state` and `/impacts` as
//!   JSON; `/geometry`, `/scene`, `/tf`, `/log` as protobuf; the metadata) in LZ4 chunks to
//!   an in-memory `Cursor<Vec<u8>>` (what `ricochet run` does, minus the disk). The
//!   simulation's thread copies each sample and each impact into a batch; the log's own
//!   thread encodes them, compresses the chunks and writes them: on a machine with a
//!   second core free the two overlap.
//!
//! Criterion's throughput is set to the simulated time, so its `thrpt` line reads
//! *simulated seconds per wall second*. The work counters (steps, right-hand-side
//! evaluations, impacts, samples, log size) do not depend on the timing; they are printed
//! once, before the measurements, with the median wall time of 15 rounds of 5 plain runs,
//! the three variants interleaved in each round (the machine may be shared).
//!
//! `cargo bench -p ricochet-benches --bench simulate`

use std::hint::black_box;
use std::io::Cursor;
use std::path::Path;
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ricochet::log::{LogOptions, LogWriter, RunLogger};
use ricochet::scene::Scene;
use ricochet::sim::{
    MaterialOverride, NullObserver, Observer, Recorder, RunSummary, Simulation, StopReason,
};

/// Simulated time of a run (s).
const T_END: f64 = 10.0;
/// Rate of the logged samples (Hz).
const RATE: f64 = 100.0;

/// The double pendulum for 10 s at 100 Hz.
fn scene() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/kane_double_pendulum.toml");
    let mut s = ricochet::scene::load(&path).expect("scenes/kane_double_pendulum.toml");
    s.settings.t_end = T_END;
    s.settings.output_rate = RATE;
    s
}

/// e = 1, the scene's μ and law: see the module doc.
fn elastic() -> MaterialOverride {
    MaterialOverride {
        e: Some(1.0),
        ..MaterialOverride::default()
    }
}

/// One run with `observer`.
fn simulate(s: &Scene, observer: &mut dyn Observer) -> RunSummary {
    let mut sim = Simulation::new(&s.model, &s.settings, elastic()).expect("simulation");
    sim.run(&s.initial, observer, None)
}

/// One run with the MCAP log in memory; the summary and the log's size (bytes).
fn simulate_logged(s: &Scene) -> (RunSummary, usize) {
    let mut sim = Simulation::new(&s.model, &s.settings, elastic()).expect("simulation");
    let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).expect("log");
    let mut log = RunLogger::for_scene(writer, s, &elastic(), sim.scales().gap_tol).expect("log");
    let summary = sim.run(&s.initial, &mut log, None);
    let bytes = log.finish(&summary).expect("finish").into_inner();
    (summary, bytes.len())
}

fn recorder() -> Recorder {
    Recorder {
        keep_samples: true,
        ..Recorder::default()
    }
}

/// One variant of the run for [`report`]: a label and a run returning its summary and
/// log size (bytes).
type Variant<'a> = (&'a str, Box<dyn Fn() -> (RunSummary, usize) + 'a>);

/// Prints the counters of one run of each variant and its wall time: the median over
/// `rounds` rounds of the mean of `reps` runs, the variants interleaved within each round
/// so that a change of the machine's load hits them alike.
fn report(variants: &[Variant<'_>], rounds: usize, reps: u32) {
    let mut walls = vec![Vec::new(); variants.len()];
    for _ in 0..rounds {
        for (k, (_, run)) in variants.iter().enumerate() {
            let start = Instant::now();
            for _ in 0..reps {
                black_box(run());
            }
            walls[k].push(start.elapsed().as_secs_f64() / f64::from(reps));
        }
    }
    let mut base = None;
    for ((label, run), walls) in variants.iter().zip(&mut walls) {
        let (summary, log_bytes) = run();
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "{label}: the run stopped early: {}",
            summary.stop
        );
        walls.sort_by(f64::total_cmp);
        let wall = walls[walls.len() / 2];
        let (lo, hi) = (walls[0], walls[walls.len() - 1]);
        let base = *base.get_or_insert(wall);
        let c = summary.counters;
        let t = summary.state.t;
        println!(
            "{label:<16} wall {:>6.2} ms (rounds {:.2}–{:.2}, {:>4.0} % of no log) | \
             {:>5.0} simulated s per wall s | {} steps ({} rejected), {} rhs evaluations \
             ({:.0} per simulated s, {:.2e} per wall s) | {} impacts ({:.1} per simulated s, \
             {:.0} per wall s) | {} samples | log {} bytes",
            1e3 * wall,
            1e3 * lo,
            1e3 * hi,
            100.0 * wall / base,
            t / wall,
            c.steps,
            c.rejected,
            c.rhs_evals,
            c.rhs_evals as f64 / t,
            c.rhs_evals as f64 / wall,
            c.impacts,
            c.impacts as f64 / t,
            c.impacts as f64 / wall,
            c.samples,
            log_bytes,
        );
    }
}

fn simulate_bench(c: &mut Criterion) {
    let s = scene();
    println!(
        "\nkane_double_pendulum, e = 1 (override), μ = {}, t_end = {T_END} s, output {RATE} Hz, \
         {:?} rtol {:e} atol {:e}",
        s.model.pairs().next().unwrap().material.mu,
        s.settings.integrator.method,
        s.settings.integrator.rtol,
        s.settings.integrator.atol,
    );
    let variants: [Variant<'_>; 3] = [
        ("no log", Box::new(|| (simulate(&s, &mut NullObserver), 0))),
        (
            "samples only",
            Box::new(|| (simulate(&s, &mut recorder()), 0)),
        ),
        ("mcap log 100 Hz", Box::new(|| simulate_logged(&s))),
    ];
    report(&variants, 15, 5);
    println!();

    let mut group = c.benchmark_group("simulate_double_pendulum_10s");
    group.throughput(Throughput::Elements(T_END as u64));
    group.bench_function("no log", |b| {
        b.iter(|| simulate(black_box(&s), &mut NullObserver))
    });
    group.bench_function("samples only", |b| {
        b.iter(|| simulate(black_box(&s), &mut recorder()))
    });
    group.bench_function("mcap log 100 Hz", |b| {
        b.iter(|| simulate_logged(black_box(&s)))
    });
    group.finish();
}

criterion_group!(benches, simulate_bench);
criterion_main!(benches);
