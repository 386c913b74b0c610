//! The articulated-body factor of the mass matrix (`ricochet::articulated`, [F, §7.3]):
//! its solve and half-solves against nalgebra's dense Cholesky factorization of the
//! composite-rigid-body `M` on random trees of every joint kind and on long mixed chains;
//! the dynamics of a long chain, which take it, against their defining equation
//! `M u̇ + h = 0` (inverse dynamics by Newton–Euler).

use crate::common::model_fixtures as fixtures;

use fixtures::{Rng, TreeOptions, chain, random_tree};
use nalgebra::{Cholesky, DMatrix, DVector};
use ricochet::articulated::{ArticulatedFactor, NotPositiveDefinite};
use ricochet::dynamics::{
    ARTICULATED_MIN_SPEEDS, factor_mass_matrix, forward_dynamics, inverse_dynamics, mass_matrix,
    solve_mass,
};
use ricochet::kinematics::update_positions;
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::spatial::Inertia;
use ricochet::model::{Body, Joint, Model};
use ricochet::state::Data;

/// A chain of `n` links on a free (planar) root body, every third hinge absolute, links
/// of random mass, length and centre of mass.
fn mixed_chain(n: usize, seed: u64) -> Model {
    let mut rng = Rng::new(seed);
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.3, -9.81));
    let root = b.add_body(
        Body::new("root", 2.0, Vec2::new(0.1, 0.05), 0.3),
        Joint::planar("root", None, Pose::identity()),
    );
    let mut parent = root;
    for i in 0..n {
        let name = format!("link{i}");
        let l = rng.uniform(0.05, 0.3);
        let placement = Pose::new(Vec2::new(0.0, -l), rng.uniform(-0.5, 0.5));
        let joint = if i % 3 == 2 {
            Joint::revolute_absolute(&name, Some(parent), placement)
        } else {
            Joint::revolute(&name, Some(parent), placement)
        };
        let m = rng.uniform(0.02, 0.5);
        parent = b.add_body(
            Body::new(&name, m, Vec2::new(0.0, -l / 2.0), m * l * l / 12.0),
            joint,
        );
    }
    b.build().expect("mixed chain")
}

/// The worst relative error of the articulated factor's solves of `model` at random
/// positions against nalgebra's Cholesky factorization of the CRBA's `M`: `M⁻¹ b`,
/// `F⁻ᵀ (F⁻¹ b)`, and `Yᵀ Y` for `J M⁻¹ Jᵀ` with `Y = F⁻¹ Jᵀ` (three random rows `J`,
/// one of them zero on the second half of the speeds).
fn articulated_error(model: &Model, seed: u64) -> Real {
    let mut rng = Rng::new(seed);
    let (nq, n) = (model.nq(), model.nu());
    let mut data = Data::new(model);
    update_positions(model, &mut data, 0.4, &rng.vector(nq, 2.0)).unwrap();
    mass_matrix(model, &mut data);
    let dense = data.mass.to_dense();
    let chol = Cholesky::new(dense.clone()).expect("M positive definite");
    let mut factor = ArticulatedFactor::new(model);
    factor
        .factor(model, &data.joint_frame, &data.subspace, &data.body_inertia)
        .unwrap();
    assert_eq!(factor.nrows(), n);
    let rel = |x: &[Real], expected: &DVector<Real>| {
        (DVector::from_column_slice(x) - expected).amax() / (1.0 + expected.amax())
    };
    let mut worst: Real = 0.0;
    // The last row zero beyond the first half of the speeds, as the Jacobian row of a
    // point on a body halfway down a chain (the backward sweep starts at its body).
    let j = DMatrix::from_fn(3, n, |r, c| {
        let x = rng.uniform(-1.0, 1.0);
        if r == 2 && c >= n.div_ceil(2) { 0.0 } else { x }
    });
    let mut y = DMatrix::zeros(n, 3);
    for c in 0..3 {
        let b: Vec<Real> = j.row(c).iter().copied().collect();
        let expected = chol.solve(&DVector::from_column_slice(&b));
        let mut x = b.clone();
        factor.solve_in_place(&mut x);
        worst = worst.max(rel(&x, &expected));
        let mut x = b;
        factor.solve_factor_in_place(&mut x);
        y.column_mut(c).copy_from_slice(&x);
        factor.solve_factor_transpose_in_place(&mut x);
        worst = worst.max(rel(&x, &expected));
    }
    let w = y.transpose() * &y;
    let expected = &j * chol.solve(&j.transpose());
    worst.max((&w - &expected).amax() / (1.0 + expected.amax()))
}

#[test]
fn the_articulated_factor_solves_like_a_dense_cholesky_on_random_trees() {
    // Every joint kind (relative and absolute revolute, prismatic, translation, planar,
    // fixed, prescribed), 1 to 7 bodies.
    let mut worst: Real = 0.0;
    for seed in 0..80 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let err = articulated_error(&model, 500 + seed);
        assert!(err < 1e-12, "seed {seed}: {err:e}");
        worst = worst.max(err);
    }
    println!("random trees: worst relative difference {worst:e}");
}

#[test]
fn the_articulated_factor_solves_like_a_dense_cholesky_on_long_mixed_chains() {
    // A free root and up to 120 hinges, relative and absolute: the projections of the
    // absolute joints, and 3 × 3 and 1 × 1 blocks D.
    for (n, tol) in [(1, 1e-12), (5, 1e-12), (40, 1e-10), (120, 1e-9)] {
        let model = mixed_chain(n, 70 + n as u64);
        let err = articulated_error(&model, 7 + n as u64);
        println!("{n} links: {err:e}");
        assert!(err < tol, "{n} links: {err:e}");
    }
}

#[test]
fn a_long_chain_takes_the_articulated_factor_and_obeys_its_equations_of_motion() {
    // From 9 links on (ARTICULATED_MIN_SPEEDS speeds and five entries of M per speed), the
    // workspace holds the articulated factor and no mass matrix; the accelerations it
    // gives satisfy M u̇ + h = 0 by Newton–Euler, and agree with the dense Cholesky solve
    // of the CRBA's M. Up to 8 links the dense factor stays.
    assert_eq!(ARTICULATED_MIN_SPEEDS, 8);
    let small = chain(8, 0.1, 0.25, 9.81);
    assert!(!Data::new(&small).mass_factor.is_articulated());
    for n in [9, 64, 200] {
        let model = chain(n, 0.05, 0.1, 9.81);
        let mut data = Data::new(&model);
        assert!(data.mass_factor.is_articulated(), "{n} links");
        assert!(data.mass.values().is_empty(), "{n} links: no storage for M");
        let mut rng = Rng::new(n as u64);
        let (q, u) = (rng.vector(n, 1.0), rng.vector(n, 3.0));
        forward_dynamics(&model, &mut data, 0.0, &q, &u).unwrap();
        let udot = data.udot.clone();
        let h = data.bias.clone();
        inverse_dynamics(&model, &mut data, udot.as_slice()).unwrap();
        let residual = data.tau.amax() / h.amax();
        assert!(
            residual < 1e-11,
            "{n} links: |M u̇ + h| / |h| = {residual:e}"
        );
        mass_matrix(&model, &mut data);
        let expected = Cholesky::new(data.mass.to_dense()).unwrap().solve(&(-&h));
        let err = (&udot - &expected).amax() / expected.amax();
        inverse_dynamics(&model, &mut data, expected.as_slice()).unwrap();
        let cholesky_residual = data.tau.amax() / h.amax();
        println!(
            "{n} links: residual {residual:e} (Cholesky's {cholesky_residual:e}), \
             against Cholesky {err:e}"
        );
        assert!(err < 1e-8, "{n} links: {err:e}");
        // Asked to factor the M it now holds, the workspace takes a factor of M.
        factor_mass_matrix(&mut data, 0.0).unwrap();
        assert!(!data.mass_factor.is_articulated());
        let mut x: Vec<Real> = h.iter().map(|v| -v).collect();
        solve_mass(&mut data, &mut x).unwrap();
        let err = (DVector::from_vec(x) - &expected).amax() / expected.amax();
        assert!(err < 1e-12, "{n} links: {err:e}");
    }
}

#[test]
fn a_joint_with_no_inertia_behind_it_is_reported() {
    // A chain whose last two bodies have no inertia: D of the last joint is 0.
    let model = chain(4, 0.1, 0.25, 9.81);
    let mut data = Data::new(&model);
    update_positions(&model, &mut data, 0.0, &[0.1, 0.2, 0.3, 0.4]).unwrap();
    let mut inertia = data.body_inertia.clone();
    inertia[2] = Inertia::ZERO;
    inertia[3] = Inertia::ZERO;
    let mut factor = ArticulatedFactor::new(&model);
    let err = factor
        .factor(&model, &data.joint_frame, &data.subspace, &inertia)
        .unwrap_err();
    assert_eq!(err, NotPositiveDefinite { joint: 3 });
}
