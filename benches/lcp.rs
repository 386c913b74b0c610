//! Time per call of the contact problem's solvers: Lemke's algorithm (`lcp::Solver`)
//! against the enumeration (`lcp::solve`) for 1 to 6 contacts, and Lemke alone for 8 to 64
//! contacts. Problems: `A = J M⁻¹ Jᵀ` of a random mechanism with `d = 3n` degrees of
//! freedom (regular `A`), slips unknown, `μ` in [0.2, 1], `b` random: a simultaneous
//! impact's problem. Fixed seed.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector};
use ricochet::lcp::{self, Allowed, Solver};

/// xorshift64*, uniform in [lo, hi).
fn uniform(state: &mut u64, lo: f64, hi: f64) -> f64 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    let u = (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
    lo + (hi - lo) * u
}

fn problem(n: usize) -> (DMatrix<f64>, DVector<f64>, Vec<Allowed>) {
    let mut s = 0x1e3e_0015_u64 + n as u64;
    let d = 3 * n;
    let r = DMatrix::from_fn(d, d, |_, _| uniform(&mut s, -1.0, 1.0));
    let m = &r * r.transpose() + DMatrix::identity(d, d) * 0.1;
    let j = DMatrix::from_fn(2 * n, d, |_, _| uniform(&mut s, -1.0, 1.0));
    let a = &j * m.try_inverse().expect("SPD") * j.transpose();
    let b = DVector::from_fn(2 * n, |_, _| uniform(&mut s, -1.0, 1.0));
    let allowed = (0..n)
        .map(|_| Allowed {
            mu: uniform(&mut s, 0.2, 1.0),
            open: true,
            slip: None,
        })
        .collect();
    (a, b, allowed)
}

fn bench_lcp(c: &mut Criterion) {
    let mut group = c.benchmark_group("lcp");
    for n in [1, 2, 3, 4, 5, 6, 8, 16, 32, 64] {
        let (a, b, allowed) = problem(n);
        let mut solver = Solver::new();
        solver.solve(&a, &b, &allowed).expect("solvable");
        group.bench_with_input(BenchmarkId::new("lemke", n), &n, |bench, _| {
            bench.iter(|| solver.solve(black_box(&a), black_box(&b), black_box(&allowed)))
        });
        if n <= lcp::MAX_ENUMERATED {
            group.bench_with_input(BenchmarkId::new("enumeration", n), &n, |bench, _| {
                bench.iter(|| lcp::solve(black_box(&a), black_box(&b), black_box(&allowed)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_lcp);
criterion_main!(benches);
