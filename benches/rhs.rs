//! Right-hand side of the equations of motion — kinematics, the mass matrix by the composite
//! rigid body algorithm, the bias forces by Newton–Euler, the Cholesky factorization and
//! the solve, i.e. one `forward_dynamics` — for `scenes/chain.toml` with 1 to 32 links
//! (from 9 links the articulated-body factor replaces the mass matrix and its Cholesky
//! factorization). `rhs_factor`: both factors side by side on the rope of
//! `scenes/chain_floor.toml` cut into 4 to 256 links.
//!
//! Expected growth: O(n²) for the mass matrix (a chain has depth n), O(n³/6) for the
//! factorization, O(n) for the rest and for the articulated-body factor.
//!
//! `cargo bench -p ricochet-benches --bench rhs`; criterion reports the time per evaluation
//! for each n.

use std::hint::black_box;
use std::path::Path;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use ricochet::dynamics::{
    MassFactor, bias_forces, factor_mass_matrix, forward_dynamics, mass_matrix, mass_pattern,
    solve_mass,
};
use ricochet::kinematics::{forward_kinematics, update_positions, update_velocities};
use ricochet::model::Model;
use ricochet::scene;
use ricochet::state::Data;

const LINKS: [usize; 6] = [1, 2, 4, 8, 16, 32];

fn chain_state(n: usize) -> (ricochet::model::Model, Vec<f64>, Vec<f64>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/chain.toml");
    let s = scene::load_chain(&path, n).expect("scenes/chain.toml");
    // A generic state: bent links moving.
    let q: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
    let u: Vec<f64> = (0..n).map(|i| 0.5 - 0.07 * i as f64).collect();
    (s.model, q, u)
}

/// Times one `forward_dynamics` of `model` at `(q, u)` with the workspace `data`.
fn bench_forward_dynamics(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: BenchmarkId,
    model: &Model,
    data: &mut Data,
    q: &[f64],
    u: &[f64],
) {
    group.bench_function(id, |b| {
        b.iter(|| {
            forward_dynamics(model, data, black_box(0.0), black_box(q), black_box(u))
                .expect("forward dynamics");
            black_box(data.udot[0])
        })
    });
}

fn rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    for n in LINKS {
        let (model, q, u) = chain_state(n);
        let mut data = Data::new(&model);
        bench_forward_dynamics(
            &mut group,
            BenchmarkId::new("chain", n),
            &model,
            &mut data,
            &q,
            &u,
        );
    }
    group.finish();

    // The stages alone, to see where the time goes.
    let mut group = c.benchmark_group("rhs_stages");
    for n in LINKS {
        let (model, q, u) = chain_state(n);
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, 0.0, &q, &u).expect("kinematics");
        group.bench_with_input(BenchmarkId::new("mass_matrix", n), &n, |b, _| {
            b.iter(|| {
                mass_matrix(&model, &mut data);
                black_box(data.mass[(0, 0)])
            })
        });
        group.bench_with_input(BenchmarkId::new("bias_forces", n), &n, |b, _| {
            b.iter(|| {
                bias_forces(&model, &mut data);
                black_box(data.bias[0])
            })
        });
        group.bench_with_input(BenchmarkId::new("kinematics", n), &n, |b, _| {
            b.iter(|| {
                update_positions(&model, &mut data, 0.0, black_box(&q)).expect("positions");
                update_velocities(&model, &mut data, black_box(&u)).expect("velocities");
                black_box(data.body_twist[0].w)
            })
        });
        mass_matrix(&model, &mut data);
        let mut x = vec![1.0; n];
        group.bench_with_input(BenchmarkId::new("factor_and_solve", n), &n, |b, _| {
            b.iter(|| {
                factor_mass_matrix(&mut data, 0.0).expect("factor");
                solve_mass(&mut data, black_box(&mut x)).expect("solve");
                black_box(x[0])
            })
        });
    }
    group.finish();
}

/// `forward_dynamics` of an `n`-link chain with each factor of the mass matrix: the dense
/// Cholesky factorization of the CRBA's `M` (`O(n³)`) and the articulated-body one (`O(n)`),
/// for [`ricochet::dynamics::ARTICULATED_MIN_SPEEDS`].
fn factors(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs_factor");
    for n in [4, 8, 12, 16, 24, 32, 64, 128, 256] {
        let (model, q, u) = chain_state_scaled(n);
        for (name, factor) in [
            ("dense", MassFactor::new(mass_pattern(&model), true)),
            ("articulated", MassFactor::articulated(&model)),
        ] {
            let mut data = Data::new(&model);
            data.mass_factor = factor;
            bench_forward_dynamics(
                &mut group,
                BenchmarkId::new(name, n),
                &model,
                &mut data,
                &q,
                &u,
            );
        }
    }
    group.finish();
}

/// [`chain_state`] for any `n`: the chain of `scenes/chain_floor.toml` cut into `n` links.
fn chain_state_scaled(n: usize) -> (ricochet::model::Model, Vec<f64>, Vec<f64>) {
    let model = ricochet::workprec::chain_floor::scene(n)
        .expect("the rope of scenes/chain_floor.toml")
        .model;
    let q: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * (i % 7) as f64).collect();
    let u: Vec<f64> = (0..n).map(|i| 0.5 - 0.07 * (i % 5) as f64).collect();
    (model, q, u)
}

criterion_group!(benches, rhs, factors);
criterion_main!(benches);
