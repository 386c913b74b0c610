//! The unit tests of `dynamics` (`src/dynamics.rs`).

// The source module's own imports.
use nalgebra::{Cholesky, DMatrix, DVectorViewMut};
use ricochet::math::Real;
use ricochet::state::Data;

use ricochet::dynamics::*;

/// Where [`has_power`] says a model's dampers, efforts and drives have no power, [`power`]
/// is `+0` in each component, bit for bit, at random states of every bundled scene (so
/// the right-hand side may take [`Power::default`] instead); and at least one scene
/// has power and two have none.
#[test]
fn no_power_is_plus_zero_to_the_bit() {
    let mut rng = crate::unit::linalg::Lcg(27);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let (mut with, mut without, mut checked) = (0, 0, 0);
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let scene = ricochet::scene::load(&path).unwrap();
        let model = &scene.model;
        if has_power(model) {
            with += 1;
            continue;
        }
        without += 1;
        let mut data = Data::new(model);
        let (q0, u0) = (&scene.initial.q, &scene.initial.u);
        for k in 0..200 {
            let q: Vec<Real> = q0.iter().map(|x| x + 0.5 * rng.next()).collect();
            // Speeds of both signs, exact zeros of both signs among them.
            let u: Vec<Real> = (0..u0.len())
                .map(|i| match (k + i) % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    _ => 5.0 * rng.next(),
                })
                .collect();
            let t = 0.01 * k as Real;
            if forward_dynamics(model, &mut data, t, &q, &u).is_err() {
                continue;
            }
            let p = power(model, &mut data);
            let bits = [p.damping, p.applied, p.drives].map(Real::to_bits);
            assert_eq!(
                bits,
                [(0.0 as Real).to_bits(); 3],
                "{}: {p:?}",
                path.display()
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 150 * without,
        "{checked} states of {without} scenes"
    );
    assert!(
        with >= 1 && without >= 2,
        "{with} scenes with power, {without} without"
    );
}

use crate::unit::linalg::Lcg;

fn same_bits(a: &[Real], b: &[Real]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// [`cholesky_2x2`] and its solves give nalgebra's dense [`Cholesky`] numbers to the
/// bit: the factor, `L⁻¹ b`, `L⁻ᵀ b` and `M⁻¹ b`, on random symmetric positive definite
/// matrices of spread scales and conditioning (`A Aᵀ + δ I`), right-hand sides with
/// zeros of both signs, and the same failures on matrices that are not positive definite
/// (zero, negative and NaN pivots).
#[test]
fn the_2x2_cholesky_is_nalgebras_to_the_bit() {
    let mut rng = Lcg(16);
    let mut factored = 0;
    for case in 0..200_000 {
        let scale = 10f64.powi((case % 17) as i32 - 8);
        let (a, b, c, d) = (rng.next(), rng.next(), rng.next(), rng.next());
        let delta = 10f64.powi(-((case % 15) as i32));
        let mut m = [
            (a * a + b * b + delta) * scale,
            (a * c + b * d) * scale,
            (c * c + d * d + delta) * scale,
        ];
        match case % 11 {
            // Singular or indefinite, and non-finite.
            1 => m[2] = m[1] * m[1] / m[0],
            2 => m[0] = 0.0,
            3 => m[2] = -m[2],
            4 => m[case % 3] = Real::NAN,
            5 => m[0] = -0.0,
            _ => {}
        }
        let mut rhs = [rng.next() * scale, rng.next()];
        match case % 7 {
            1 => rhs = [0.0, -0.0],
            2 => rhs[0] = -0.0,
            3 => rhs[1] = 0.0,
            4 => rhs = [-0.0, 0.0],
            5 => rhs = [-0.0, -0.0],
            _ => {}
        }
        let dense = DMatrix::from_row_slice(2, 2, &[m[0], m[1], m[1], m[2]]);
        let fast = cholesky_2x2(m[0], m[1], m[2]);
        let slow = Cholesky::new(dense.clone());
        assert_eq!(fast.is_some(), slow.is_some(), "{dense}");
        let (Some(l), Some(chol)) = (fast, slow) else {
            continue;
        };
        factored += 1;
        let lc = chol.l_dirty();
        assert!(
            same_bits(&l, &[lc[(0, 0)], lc[(1, 0)], lc[(1, 1)]]),
            "{dense}: {l:?} vs {lc}"
        );
        let (mut x, mut y) = (rhs, rhs);
        solve_lower_2x2(&l, &mut x);
        lc.solve_lower_triangular_unchecked_mut(&mut DVectorViewMut::from_slice(&mut y, 2));
        assert!(same_bits(&x, &y), "{dense} {rhs:?}: {x:?} vs {y:?}");
        let (mut x, mut y) = (rhs, rhs);
        solve_upper_2x2(&l, &mut x);
        lc.ad_solve_lower_triangular_unchecked_mut(&mut DVectorViewMut::from_slice(&mut y, 2));
        assert!(same_bits(&x, &y), "{dense} {rhs:?}: {x:?} vs {y:?}");
        let (mut x, mut y) = (rhs, rhs);
        solve_lower_2x2(&l, &mut x);
        solve_upper_2x2(&l, &mut x);
        chol.solve_mut(&mut DVectorViewMut::from_slice(&mut y, 2));
        assert!(same_bits(&x, &y), "{dense} {rhs:?}: {x:?} vs {y:?}");
    }
    assert!(factored > 100_000, "only {factored} matrices factored");
}
