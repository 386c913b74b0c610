//! Right-hand side of the equations of motion — kinematics, the mass matrix by the composite
//! rigid body algorithm, the bias forces by Newton–Euler, the Cholesky factorization and
//! the solve, i.e. one `forward_dynamics` — for `scenes/chain.toml` with 1 to 32 links.
//!
//! Expected growth: O(n²) for the mass matrix (a chain has depth n), O(n³/6) for the
//! factorization, O(n) for the rest; below ~32 links the O(n²) terms dominate.
//!
//! `cargo bench --bench rhs`; criterion reports the time per evaluation for each n.

use std::hint::black_box;
use std::path::Path;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ricochet::dynamics::{
    bias_forces, factor_mass_matrix, forward_dynamics, mass_matrix, solve_mass,
};
use ricochet::kinematics::{forward_kinematics, update_positions, update_velocities};
use ricochet::scene;
use ricochet::state::Data;

const LINKS: [usize; 6] = [1, 2, 4, 8, 16, 32];

fn chain_state(n: usize) -> (ricochet::model::Model, Vec<f64>, Vec<f64>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/chain.toml");
    let s = scene::load_chain(&path, n).expect("scenes/chain.toml");
    // A generic state: bent links moving.
    let q: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
    let u: Vec<f64> = (0..n).map(|i| 0.5 - 0.07 * i as f64).collect();
    (s.model, q, u)
}

fn rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    for n in LINKS {
        let (model, q, u) = chain_state(n);
        let mut data = Data::new(&model);
        group.bench_with_input(BenchmarkId::new("chain", n), &n, |b, _| {
            b.iter(|| {
                forward_dynamics(
                    &model,
                    &mut data,
                    black_box(0.0),
                    black_box(&q),
                    black_box(&u),
                )
                .expect("forward dynamics");
                black_box(data.udot[0])
            })
        });
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
                solve_mass(&data, black_box(&mut x)).expect("solve");
                black_box(x[0])
            })
        });
    }
    group.finish();
}

criterion_group!(benches, rhs);
criterion_main!(benches);
