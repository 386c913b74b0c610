//! The broad phase of the loop (issue 15): a chain of `scenes/chain.toml` (8 to 64 links)
//! in free fall for 10 ms, with the broad phase (the candidate pairs of each step) and
//! without it (every pair sampled at every step, `Simulation::set_broad_phase(false)`).
//! The two runs take the same steps; the difference is the cost of the event functions.
//!
//! `cargo bench -p ricochet-benches --bench broad_phase`; criterion reports the time per run
//! for each n.

use std::hint::black_box;
use std::path::Path;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ricochet::scene;
use ricochet::sim::{MaterialOverride, NullObserver, Simulation};

const LINKS: [usize; 4] = [8, 16, 32, 64];

fn free_fall(c: &mut Criterion) {
    let mut group = c.benchmark_group("chain_free_fall_10ms");
    group.sample_size(10);
    for n in LINKS {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chain.toml");
        let mut s = scene::load_chain(&path, n).expect("scenes/chain.toml");
        s.settings.t_end = 0.01;
        for (name, on) in [("broad_phase", true), ("every_pair", false)] {
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| {
                    let mut sim =
                        Simulation::new(&s.model, &s.settings, MaterialOverride::default())
                            .expect("settings");
                    sim.set_broad_phase(on);
                    black_box(sim.run(&s.initial, &mut NullObserver, None))
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, free_fall);
criterion_main!(benches);
