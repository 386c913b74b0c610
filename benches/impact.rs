//! Time per call of each impact law (`ricochet::impact::solve`), on inputs that end in
//! each collision type: the Sect. 5 pendulum (reverse sliding under Newton), a sticking
//! and a forward-sliding case.
//!
//! Each call's `Result<Outcome, ImpactError>` (240 bytes, every field computed and stored)
//! stays where `solve` wrote it and is shown to the optimiser by reference. Returned to
//! criterion by value (`b.iter(|| impact::solve(…))`, until stop 30), it was copied once
//! more, by a `memcpy` whose wide loads wait for the law's narrower stores to reach the
//! cache: the harness's cost, not the law's (issue 16; ARCHITECTURE.md, Speed).
//!
//! `cargo bench -p ricochet-benches --bench impact`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};

fn problems() -> [(&'static str, ImpactProblem); 3] {
    let pendulum = ImpactMatrix::new(0.33652, -0.50710, 0.81345);
    [
        (
            "reverse",
            ImpactProblem::new(pendulum, ContactVelocity::new(-0.2684, 0.5343), 0.5, 0.2),
        ),
        (
            "stick",
            ImpactProblem::new(
                ImpactMatrix::new(1.0, 0.2, 2.0),
                ContactVelocity::new(-1.0, 0.3),
                0.6,
                0.8,
            ),
        ),
        (
            "forward",
            ImpactProblem::new(
                ImpactMatrix::new(1.0, 0.2, 2.0),
                ContactVelocity::new(-1.0, -5.0),
                0.6,
                0.2,
            ),
        ),
    ]
}

fn bench_laws(c: &mut Criterion) {
    let mut group = c.benchmark_group("impact");
    for law in Law::ALL {
        for (name, pb) in problems() {
            group.bench_function(format!("{law}/{name}"), |b| {
                b.iter(|| {
                    let out = impact::solve(black_box(law), black_box(&pb));
                    black_box(&out);
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_laws);
criterion_main!(benches);
