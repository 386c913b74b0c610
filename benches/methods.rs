//! The two ways to run a scene, side by side: the event-driven loop (`Simulation`, DOPRI5
//! with the scene's tolerances, rtol 1e-10, atol 1e-12) and the Moreau–Jean time-stepping
//! (`MoreauJean`, θ = ½, h = 1e-3 s), on
//!
//! - `bouncing_ball` (e = 0.8) to 10 s (at rest from t∞ = 4.0637 s);
//! - `falling_rod` (e = 0.5, μ = 0.4) to rest, 1.5 s (Moreau–Jean at h = 1e-3 has it at
//!   rest, every speed below 1e-10 √(g L), from 1.03 s; the event-driven loop from the end
//!   of its accumulation of impacts, 1.009 s).
//!
//! Both methods run to the end time: the event-driven loop ends each accumulation of
//! impacts and goes on in persistent contact.
//!
//! Moreau–Jean runs twice: with its default solver (the exact enumeration of
//! `ricochet::lcp` for up to 2 contacts, which allocates and tries 4^m mode combinations)
//! and with nonsmooth Gauss–Seidel alone (`exact_up_to = 0`; the enumeration still
//! rescues an unconverged step of up to 4 contacts).
//!
//! No log: a `NullObserver` (the simulation alone). The counters (steps, right-hand-side
//! evaluations, impacts) do not depend on the timing; they are printed once with the
//! median wall time of 15 rounds of 3 runs (the variants interleaved in each round, as
//! the machine is shared: the spread is printed, and the load average before and after),
//! then criterion measures each variant (the report gives the simulated seconds per wall
//! second of each).
//!
//! `cargo bench -p ricochet-benches --bench methods`

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use ricochet::scene::Scene;
use ricochet::sim::{
    MaterialOverride, MoreauJean, MoreauJeanSettings, NullObserver, RunSummary, Simulation,
};

/// The Moreau–Jean step (s).
const H: f64 = 1e-3;

fn scene(name: &str, t_end: f64) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
    let mut s = ricochet::scene::load(&path).expect("scene");
    s.settings.t_end = t_end;
    s.settings.integrator.dt = H;
    s
}

fn event_driven(s: &Scene) -> RunSummary {
    let mut sim = Simulation::new(&s.model, &s.settings, MaterialOverride::default()).unwrap();
    sim.run(&s.initial, &mut NullObserver, None)
}

fn moreau_jean(s: &Scene, exact_up_to: usize) -> RunSummary {
    let settings = MoreauJeanSettings {
        exact_up_to,
        ..MoreauJeanSettings::default()
    };
    let mut mj =
        MoreauJean::with_settings(&s.model, &s.settings, MaterialOverride::default(), settings)
            .unwrap();
    mj.run(&s.initial, &mut NullObserver, None)
}

/// One variant: a label and a run.
type Variant<'a> = (&'static str, Box<dyn Fn() -> RunSummary + 'a>);

fn variants(s: &Scene) -> [Variant<'_>; 3] {
    [
        ("event-driven dopri5", Box::new(|| event_driven(s))),
        ("moreau-jean h 1e-3 exact", Box::new(|| moreau_jean(s, 2))),
        (
            "moreau-jean h 1e-3 gauss-seidel",
            Box::new(|| moreau_jean(s, 0)),
        ),
    ]
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".to_owned())
}

/// Prints each variant's counters and its wall time: the median over `rounds` rounds of
/// the mean of `reps` runs, with the fastest and slowest rounds.
fn report(name: &str, variants: &[Variant<'_>], rounds: usize, reps: u32) {
    println!("\n{name} (load average before: {})", load_average());
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
    for ((label, run), walls) in variants.iter().zip(&mut walls) {
        let s = run();
        walls.sort_by(f64::total_cmp);
        let wall = walls[walls.len() / 2];
        let (lo, hi) = (walls[0], walls[walls.len() - 1]);
        let c = s.counters;
        let e0 = s.audit.initial.total();
        println!(
            "  {label:<32} wall {:>8.3} ms (rounds {:.3}–{:.3}) | stopped at {:.4} s: {} | \
             {:>5.0} simulated s per wall s | {} steps, {} rhs evaluations, {} impacts | \
             E_end/E_0 {:.4}, drift {:.1e} J",
            1e3 * wall,
            1e3 * lo,
            1e3 * hi,
            s.state.t,
            s.stop.name(),
            s.state.t / wall,
            c.steps,
            c.rhs_evals,
            c.impacts,
            s.audit.end.total() / e0,
            s.audit.drift(),
        );
    }
    println!("  (load average after: {})", load_average());
}

fn methods_bench(c: &mut Criterion) {
    for (name, t_end) in [("bouncing_ball", 10.0), ("falling_rod", 1.5)] {
        let s = scene(name, t_end);
        let vs = variants(&s);
        report(name, &vs, 15, 3);
        let mut group = c.benchmark_group(format!("methods_{name}"));
        for (label, run) in &vs {
            group.bench_function(*label, |b| b.iter(run));
        }
        group.finish();
    }
}

criterion_group!(benches, methods_bench);
criterion_main!(benches);
