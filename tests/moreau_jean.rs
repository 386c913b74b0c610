//! The Moreau–Jean time-stepping (`src/sim/moreau_jean/`) and its contact solvers.
//!
//! - Nonsmooth Gauss–Seidel (`ricochet::pgs`) against the exact enumeration of
//!   `ricochet::lcp` on random problems of two to four contacts.

use nalgebra::{DMatrix, DVector};
use ricochet::lcp::{self, Allowed};
use ricochet::pgs::{self, PgsSettings, PgsStatus};

/// A small deterministic generator (xorshift64*), so that every run sees the same
/// problems.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A random contact problem: `A = J M⁻¹ Jᵀ` (2m × 2m) from a random `J` (2m × nu) and a
/// random diagonal `M`, `b` in [−1, 1], `μ` in [0, mu_max].
fn problem(
    rng: &mut Rng,
    m: usize,
    nu: usize,
    mu_max: f64,
) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
    let j = DMatrix::from_fn(2 * m, nu, |_, _| rng.range(-1.0, 1.0));
    let m_inv = DMatrix::from_diagonal(&DVector::from_fn(nu, |_, _| 1.0 / rng.range(0.2, 5.0)));
    let a = &j * m_inv * j.transpose();
    let b = DVector::from_fn(2 * m, |_, _| rng.range(-1.0, 1.0));
    let mu = (0..m).map(|_| rng.range(0.0, mu_max)).collect();
    (a, b, mu)
}

fn exact(a: &DMatrix<f64>, b: &DVector<f64>, mu: &[f64]) -> Vec<(DVector<f64>, DVector<f64>)> {
    let allowed: Vec<Allowed> = (mu.iter())
        .map(|&mu| Allowed {
            mu,
            open: true,
            slip: None,
        })
        .collect();
    (lcp::solve(a, b, &allowed).all.into_iter())
        .map(|s| (s.x, s.w))
        .collect()
}

fn gauss_seidel(a: &DMatrix<f64>, b: &DVector<f64>, mu: &[f64]) -> (PgsStatus, DVector<f64>) {
    let mut x = vec![0.0; b.len()];
    let settings = PgsSettings {
        max_iterations: 20_000,
        ..PgsSettings::default()
    };
    let status = pgs::solve(a.as_slice(), b.as_slice(), mu, &mut x, &settings);
    (status, DVector::from_vec(x))
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax()).max(1e-300)
}

#[test]
fn gauss_seidel_agrees_with_the_enumeration_without_friction() {
    // μ = 0 and A positive definite (nu ≥ 2m): a symmetric positive definite LCP in the
    // normal impulses, whose solution is unique and to which projected Gauss–Seidel
    // converges (projected SOR for symmetric LCPs with a positive diagonal: Cottle, Pang,
    // Stone, The Linear Complementarity Problem, Academic Press 1992, ch. 5). Also
    // rank-deficient A (nu < 2m, as a rod on two contacts): x may not be unique, but
    // w = A x + b is (a monotone symmetric LCP).
    let mut rng = Rng(0x5eed_0001);
    let mut worst: f64 = 0.0;
    for case in 0..300 {
        let m = 2 + case % 3;
        let nu = if case % 2 == 0 { 2 * m + 1 } else { 2 * m - 1 };
        let (a, b, mu) = problem(&mut rng, m, nu, 0.0);
        let all = exact(&a, &b, &mu);
        assert!(
            !all.is_empty(),
            "case {case}: the enumeration found no solution"
        );
        let (status, x) = gauss_seidel(&a, &b, &mu);
        assert!(status.converged(), "case {case}: {status:?}");
        let w = &a * &x + &b;
        let err = rel(&all[0].1, &w);
        assert!(
            err < 1e-8,
            "case {case} (m = {m}, nu = {nu}): velocities differ by {err:e}"
        );
        if nu >= 2 * m {
            let err_x = rel(&all[0].0, &x);
            assert!(err_x < 1e-8, "case {case}: impulses differ by {err_x:e}");
        }
        worst = worst.max(err);
    }
    println!("frictionless: 300 problems, worst relative velocity difference {worst:.1e}");
}

#[test]
fn gauss_seidel_agrees_with_the_enumeration_with_friction() {
    // μ ∈ [0, 1), A positive definite. Convergence is not guaranteed with friction; every
    // converged result must be one of the enumeration's solutions (impulses and
    // velocities), and most problems of this size converge.
    let mut rng = Rng(0x5eed_0002);
    let (mut converged, mut total, mut worst) = (0, 0, 0.0f64);
    for case in 0..300 {
        let m = 2 + case % 3;
        let (a, b, mu) = problem(&mut rng, m, 2 * m + 1, 1.0);
        let all = exact(&a, &b, &mu);
        let (status, x) = gauss_seidel(&a, &b, &mu);
        total += 1;
        if !status.converged() {
            continue;
        }
        converged += 1;
        let w = &a * &x + &b;
        let best = (all.iter())
            .map(|(xe, we)| rel(xe, &x).max(rel(we, &w)))
            .fold(f64::INFINITY, f64::min);
        assert!(
            best < 1e-7,
            "case {case} (m = {m}): Gauss–Seidel's solution is none of the {} exact ones \
             (closest {best:e})",
            all.len()
        );
        worst = worst.max(best);
    }
    println!(
        "with friction: {converged} of {total} converged, worst relative difference {worst:.1e}"
    );
    assert!(
        converged * 10 >= total * 9,
        "{converged} of {total} converged"
    );
}
