//! Time per call of the contact problem's solvers: Lemke's algorithm (`lcp::Solver`)
//! against the enumeration (`lcp::solve`) for 1 to 6 contacts, and Lemke alone for 8 to 64
//! contacts. Problems: `A = J M⁻¹ Jᵀ` of a random mechanism with `d = 3n` degrees of
//! freedom (regular `A`), slips unknown, `μ` in [0.2, 1], `b` random: a simultaneous
//! impact's problem. Fixed seed.
//!
//! `lemke_resting`: problems shaped like a chain lying on the floor (issue 15; as
//! `resting_problem` of `tests/all/lcp_lemke.rs`): `A` rank deficient (`d = 3n/2`), every
//! other contact a duplicate of its neighbour's normal row, `b_n = 0` but for one point in
//! five, `b_t` random, `μ` in [0, 1], slips unknown.
//!
//! `cargo bench -p ricochet-benches --bench lcp`

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

/// A chain lying on the floor (module doc): a lifting velocity `u` (`J_n u = 1`,
/// `J_t u = 0`), pairs of points at one place, most at rest.
fn resting(n: usize) -> (DMatrix<f64>, DVector<f64>, Vec<Allowed>) {
    let mut s = 0x2e57_0015_u64 + n as u64;
    let d = 3 * n / 2;
    let mut u = DVector::from_fn(d, |_, _| uniform(&mut s, -1.0, 1.0));
    u.normalize_mut();
    let r = DMatrix::from_fn(d, d, |_, _| uniform(&mut s, -1.0, 1.0));
    let m = &r * r.transpose() + DMatrix::identity(d, d) * 0.1;
    let mut j = DMatrix::from_fn(2 * n, d, |_, _| uniform(&mut s, -1.0, 1.0));
    let mut b = DVector::zeros(2 * n);
    for i in 0..n {
        if i % 2 == 1 {
            for k in 0..d {
                j[(2 * i, k)] = j[(2 * i - 2, k)];
                j[(2 * i + 1, k)] = j[(2 * i - 1, k)] + 1e-3 * uniform(&mut s, -1.0, 1.0);
            }
            b[2 * i] = b[2 * i - 2];
        } else {
            let c = 1.0 - j.row(2 * i).dot(&u.transpose());
            for k in 0..d {
                j[(2 * i, k)] += c * u[k];
            }
            if uniform(&mut s, 0.0, 1.0) < 0.2 {
                b[2 * i] = uniform(&mut s, -1.0, -0.1);
            }
        }
        let c = -j.row(2 * i + 1).dot(&u.transpose());
        for k in 0..d {
            j[(2 * i + 1, k)] += c * u[k];
        }
        b[2 * i + 1] = uniform(&mut s, -1.0, 1.0);
    }
    let a = &j * m.try_inverse().expect("SPD") * j.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let allowed = (0..n)
        .map(|_| Allowed {
            mu: uniform(&mut s, 0.0, 1.0),
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
    for n in [8, 16, 32, 64] {
        let (a, b, allowed) = resting(n);
        let mut solver = Solver::new();
        let outcome = solver.solve(&a, &b, &allowed).map(|_| solver.pivots());
        println!("lemke_resting/{n}: {outcome:?}");
        group.bench_with_input(BenchmarkId::new("lemke_resting", n), &n, |bench, _| {
            bench.iter(|| solver.solve(black_box(&a), black_box(&b), black_box(&allowed)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_lcp);
criterion_main!(benches);
