//! The mass matrix with the tree's sparsity and its `LᵀL` factorization [F, §6.5]
//! (`ricochet::tree_matrix`): the solve against nalgebra's dense Cholesky on random trees
//! (chains, stars, free bodies, mixed), the factor against the `L` a matrix was built
//! from, and the storage against the ancestor pattern (no entry beyond it).

use crate::common::model_fixtures as fixtures;

use fixtures::{Rng, TreeOptions, chain, random_tree};
use nalgebra::{Cholesky, DMatrix, DVector};
use ricochet::dynamics::{forward_dynamics, mass_pattern, solve_mass};
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{Body, Joint, Model};
use ricochet::state::Data;
use ricochet::tree_matrix::{TreeMatrix, TreePattern};

/// A random parent array of `n` indices of the given shape.
fn parents(shape: &str, n: usize, rng: &mut Rng) -> Vec<Option<usize>> {
    (0..n)
        .map(|i| match (shape, i) {
            (_, 0) => None,
            ("chain", _) => Some(i - 1),
            ("star", _) => Some(0),
            ("free", _) => None,
            // Mixed: a root now and then, else any earlier index.
            _ if rng.below(5) == 0 => None,
            _ => Some(rng.below(i)),
        })
        .collect()
}

/// The ancestors of `i` (itself included), nearest first.
fn path(parent: &[Option<usize>], i: usize) -> Vec<usize> {
    let mut out = vec![i];
    while let Some(p) = parent[*out.last().unwrap()] {
        out.push(p);
    }
    out
}

/// A random lower triangular `L` with the pattern's sparsity (diagonal in [0.5, 2]).
fn random_factor(parent: &[Option<usize>], rng: &mut Rng) -> DMatrix<Real> {
    let n = parent.len();
    let mut l = DMatrix::zeros(n, n);
    for i in 0..n {
        for (d, &j) in path(parent, i).iter().enumerate() {
            l[(i, j)] = if d == 0 {
                rng.uniform(0.5, 2.0)
            } else {
                rng.uniform(-1.0, 1.0)
            };
        }
    }
    l
}

#[test]
fn ltl_solves_like_a_dense_cholesky_on_random_trees() {
    let mut rng = Rng::new(15);
    let mut worst: Real = 0.0;
    for shape in ["chain", "star", "free", "mixed"] {
        for trial in 0..40 {
            let n = 1 + rng.below(if trial < 30 { 12 } else { 60 });
            let parent = parents(shape, n, &mut rng);
            let pattern = TreePattern::new(&parent).unwrap();
            // M = Lᵀ L has the tree's sparsity: (LᵀL)_ij sums over k below both i and j.
            let l = random_factor(&parent, &mut rng);
            let product = l.transpose() * &l;
            let dense = DMatrix::from_fn(n, n, |i, j| product[(i.max(j), i.min(j))]);
            let mut m = TreeMatrix::zeros(pattern.clone());
            m.copy_lower_from(&dense);
            assert_eq!(m.to_dense(), dense, "{shape} n = {n}");

            let mut factor = TreeMatrix::zeros(pattern);
            factor.factor_ltl_from(&m).unwrap();
            // The LᵀL factor with a positive diagonal is unique: it is the L we built.
            let l_err = (factor.to_dense_lower() - &l).amax();
            assert!(l_err < 1e-10, "{shape} n = {n}: |ΔL| = {l_err:e}");

            let b = DVector::from_vec(rng.vector(n, 1.0));
            let mut x = b.as_slice().to_vec();
            factor.solve_ltl(&mut x);
            let expected = Cholesky::new(dense.clone()).unwrap().solve(&b);
            let err = (DVector::from_vec(x.clone()) - &expected).amax() / (1.0 + expected.amax());
            worst = worst.max(err);
            assert!(err < 1e-10, "{shape} n = {n}: |Δx| = {err:e}");
            // And the defining equation, through the sparse product.
            let mut r = vec![0.0; n];
            m.mul_vec(&x, &mut r);
            let res = (DVector::from_vec(r) - &b).amax();
            assert!(
                res < 1e-10 * (1.0 + dense.amax() * expected.amax()),
                "{shape} n = {n}"
            );
        }
    }
    println!("worst relative difference from nalgebra's Cholesky: {worst:e}");
}

#[test]
fn a_matrix_that_is_not_positive_definite_is_refused() {
    let pattern = TreePattern::new(&[None, Some(0), Some(1)]).unwrap();
    let mut m = TreeMatrix::zeros(pattern.clone());
    // [[1, 2, 0], [2, 1, 0], [0, 0, 1]]: eigenvalues 3, −1, 1. The last pivot (index 0)
    // is 1 − 4 = −3 after eliminating index 1.
    for (i, j, v) in [(0, 0, 1.0), (1, 0, 2.0), (1, 1, 1.0), (2, 2, 1.0)] {
        assert!(m.set(i, j, v));
    }
    let mut factor = TreeMatrix::zeros(pattern);
    assert_eq!(factor.factor_ltl_from(&m), Err(0));
}

/// `n` free bodies (planar joints, three speeds each) on the world.
fn free_bodies(n: usize) -> Model {
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.0, -9.81));
    for k in 0..n {
        b.add_body(
            Body::new(format!("b{k}"), 1.0 + k as Real, Vec2::new(0.1, 0.0), 0.5),
            Joint::planar(format!("b{k}"), None, Pose::identity()),
        );
    }
    b.build().unwrap()
}

#[test]
fn the_mass_matrix_stores_the_ancestor_pattern_alone() {
    // Free bodies: one 3 × 3 block each (its speeds x, y, θ in a row), 6 entries; no
    // coupling between bodies.
    for n in [1, 7, 300] {
        let model = free_bodies(n);
        let data = Data::new(&model);
        assert_eq!(data.mass.values().len(), 6 * n);
        assert!(data.mass_factor.tree_factor().is_none(), "not factored yet");
    }
    // A chain of n links: the whole triangle, n(n+1)/2.
    for n in [1, 8, 100] {
        let model = chain(n, 0.1, 0.25, 9.81);
        assert_eq!(mass_pattern(&model).entries(), n * (n + 1) / 2);
    }
    // A workspace for the kinematics has no storage for M.
    assert!(
        Data::for_kinematics(&chain(100, 0.1, 0.25, 9.81))
            .mass
            .values()
            .is_empty()
    );
}

#[test]
fn the_dense_mass_matrix_has_no_entry_outside_the_pattern() {
    // Random trees of every joint kind, and free bodies: the CRBA's dense M (through the
    // dynamics) is zero wherever the pattern has no entry, and the solve (sparse where the
    // pattern is not full) equals nalgebra's Cholesky.
    let mut sparse = 0;
    for seed in 0..40 {
        let model = if seed % 4 == 3 {
            free_bodies(1 + seed as usize / 4)
        } else {
            random_tree(seed, TreeOptions::EVERYTHING, Pose::identity())
        };
        let mut rng = Rng::new(100 + seed);
        let n = model.nu();
        let mut data = Data::new(&model);
        let (q, u) = (rng.vector(n, 2.0), rng.vector(n, 2.0));
        forward_dynamics(&model, &mut data, 0.3, &q, &u).unwrap();
        let dense = data.mass.to_dense();
        let pattern = mass_pattern(&model);
        for i in 0..n {
            let mut ancestors = vec![i];
            while let Some(p) = pattern.parent(*ancestors.last().unwrap()) {
                ancestors.push(p);
            }
            for j in 0..=i {
                if !ancestors.contains(&j) {
                    assert_eq!(dense[(i, j)], 0.0, "seed {seed}: M[{i}][{j}]");
                }
            }
        }
        let b = DVector::from_vec(rng.vector(n, 1.0));
        let mut x = b.as_slice().to_vec();
        solve_mass(&mut data, &mut x).unwrap();
        let expected = Cholesky::new(dense.clone()).unwrap().solve(&b);
        let err = (DVector::from_vec(x) - &expected).amax();
        assert!(
            err < 1e-11 * (1.0 + expected.amax()),
            "seed {seed}: {err:e}"
        );
        sparse += usize::from(data.mass_factor.tree_factor().is_some());
    }
    assert!(sparse >= 10, "{sparse} models with a sparse factor");
}

#[test]
fn the_half_solves_compose_to_the_solve_and_give_w_as_a_gram_matrix() {
    // For M = F Fᵀ (F = Lᵀ of the tree factor, L of the dense one): F⁻ᵀ (F⁻¹ b) is the
    // solve of M x = b, and with Y = F⁻¹ Jᵀ, Yᵀ Y = J M⁻¹ Jᵀ (what persistent contact
    // builds its W from). Checked against nalgebra's dense Cholesky of M on random trees
    // (both kinds of factor) and an 8-link chain (a full pattern, the dense factor; from 9
    // links on a chain takes the articulated-body factor, tests/all/articulated.rs).
    let (mut sparse, mut dense_factors) = (0, 0);
    for seed in 0..30 {
        let model = if seed == 29 {
            chain(8, 1.0, 0.5, 9.81)
        } else {
            random_tree(seed, TreeOptions::EVERYTHING, Pose::identity())
        };
        let mut rng = Rng::new(300 + seed);
        let n = model.nu();
        let mut data = Data::new(&model);
        let (q, u) = (rng.vector(n, 2.0), rng.vector(n, 2.0));
        forward_dynamics(&model, &mut data, 0.1, &q, &u).unwrap();
        let chol = Cholesky::new(data.mass.to_dense()).unwrap();
        // Three rows of a "Jacobian".
        let j = DMatrix::from_fn(3, n, |_, _| rng.vector(1, 1.0)[0]);
        let mut y = DMatrix::zeros(n, 3);
        for c in 0..3 {
            let mut col: Vec<Real> = j.row(c).iter().copied().collect();
            data.mass_factor.solve_factor_in_place(&mut col).unwrap();
            y.column_mut(c).copy_from_slice(&col);
            data.mass_factor
                .solve_factor_transpose_in_place(&mut col)
                .unwrap();
            let expected = chol.solve(&j.row(c).transpose());
            let err = (DVector::from_vec(col) - &expected).amax();
            assert!(
                err < 1e-11 * (1.0 + expected.amax()),
                "seed {seed}: {err:e}"
            );
        }
        let w = y.transpose() * &y;
        let expected = &j * chol.solve(&j.transpose());
        let err = (&w - &expected).amax();
        assert!(
            err < 1e-11 * (1.0 + expected.amax()),
            "seed {seed}: W {err:e}"
        );
        if data.mass_factor.tree_factor().is_some() {
            sparse += 1;
        } else {
            dense_factors += 1;
        }
    }
    assert!(
        sparse >= 5 && dense_factors >= 1,
        "{sparse} sparse, {dense_factors} dense"
    );
}
