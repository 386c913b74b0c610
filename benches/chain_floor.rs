//! Issue 15's target: the 32-link chain falling on the floor (`scenes/chain_floor.toml`:
//! impacts of up to 45 coupled points, then ~35 points lying on the floor in stick and
//! slip), 5 s event-driven with no observer, under 10 s of wall time. Ten samples.
//! `cargo bench -p ricochet-benches --bench chain_floor`

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use ricochet::sim::{MaterialOverride, NullObserver, Simulation, StopReason};

fn chain_floor(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chain_floor.toml");
    let s = ricochet::scene::load(&path).expect("scenes/chain_floor.toml");
    let run = || {
        let mut sim = Simulation::new(&s.model, &s.settings, MaterialOverride::default()).unwrap();
        sim.run(&s.initial, &mut NullObserver, None)
    };
    let summary = run();
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    println!(
        "\nchain_floor 5 s: {} impacts, {} steps ({} rejected), {} rhs evaluations",
        summary.counters.impacts,
        summary.counters.steps,
        summary.counters.rejected,
        summary.counters.rhs_evals
    );
    let mut group = c.benchmark_group("chain_floor");
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(90));
    group.bench_function("run 5 s no log", |b| b.iter(|| black_box(run())));
    group.finish();
}

criterion_group!(benches, chain_floor);
criterion_main!(benches);
