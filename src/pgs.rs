//! A projected (nonsmooth) Gauss–Seidel solver of the contact problem of several contacts
//! with Coulomb friction: the iterative counterpart of the exact enumeration of
//! [`crate::lcp`], for many contacts. Pure numerics on `(A, b, μ)`.
//!
//! The problem is that of [`crate::lcp`] at the velocity level: with `n` contacts, the
//! unknown impulses `x = (x_n0, x_t0, x_n1, x_t1, …)` and `w = A x + b` (`A` symmetric
//! positive semidefinite, `2n × 2n`), every contact `i` satisfies
//!
//! ```text
//! 0 ≤ x_ni ⊥ w_ni ≥ 0                                  (unilateral contact)
//! |x_ti| ≤ μ_i x_ni,  w_ti ≠ 0 ⇒ x_ti = −μ_i x_ni sign(w_ti)   (Coulomb)
//! ```
//!
//! The solver sweeps the contacts in order; for contact `i` it freezes the others and
//! solves its own 2×2 problem `w_i = A_ii x_i + r_i`, `r_i = b_i + Σ_{j≠i} A_ij x_j`,
//! exactly (open, stick, or slide either way: [`solve_one`]). This is the nonsmooth
//! Gauss–Seidel of Jean and Moreau [J; AB], which Siconos calls NSGS. It converges for frictionless problems with positive diagonal blocks (a projected
//! Gauss–Seidel on a symmetric LCP); with friction convergence is not guaranteed, so the
//! result carries a [`PgsStatus`].
//!
//! The stopping test is the natural-map residual in velocity units: with
//! `κ_i = max(A_nn,i, A_tt,i)` (a velocity per impulse),
//!
//! ```text
//! r_ni = min(κ_i x_ni, w_ni)
//! r_ti = κ_i x_ti − proj_[−κ_i μ_i x_ni, κ_i μ_i x_ni](κ_i x_ti − w_ti)
//! ```
//!
//! which vanish exactly at a solution; the solver stops when `max_i |r_i| ≤ tol · s`, with
//! `s = max(‖b‖_∞, κ ‖x‖_∞)` the velocity scale of the problem.
//!
//! References: **\[J\]** M. Jean, *The non-smooth contact dynamics method*, Comput. Methods
//! Appl. Mech. Engrg. 177 (1999) 235–257. **\[AB\]** V. Acary, B. Brogliato, *Numerical
//! Methods for Nonsmooth Dynamical Systems*, Springer (2008).

use crate::math::Real;

/// Settings of the solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PgsSettings {
    /// The most sweeps over the contacts.
    pub max_iterations: usize,
    /// Relative tolerance of the residual (dimensionless, against the velocity scale).
    pub tolerance: Real,
}

impl Default for PgsSettings {
    fn default() -> Self {
        Self {
            max_iterations: 1000,
            tolerance: 1e-12,
        }
    }
}

/// Whether the solver converged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PgsStatus {
    /// The residual fell below the tolerance.
    Converged {
        /// Sweeps done.
        iterations: usize,
        /// The final residual, relative to the velocity scale.
        residual: Real,
    },
    /// The sweeps ran out first; `x` is the last iterate.
    MaxIterations {
        /// Sweeps done.
        iterations: usize,
        /// The final residual, relative to the velocity scale.
        residual: Real,
    },
    /// A number is not finite (in `A`, `b`, `μ`, or the iterate).
    NonFinite,
}

impl PgsStatus {
    /// `true` if the solver converged.
    pub fn converged(&self) -> bool {
        matches!(self, PgsStatus::Converged { .. })
    }
}

/// Solves the contact problem `w = A x + b` with Coulomb friction by nonsmooth
/// Gauss–Seidel, starting from `x` (a warm start; zeros for none) and leaving the
/// solution in `x`.
///
/// `a` is `A` in column-major order (`2n × 2n`, entry `(r, c)` at `c·2n + r`), `b` has `2n`
/// entries, `mu` has `n` (`μ_i ≥ 0`), `x` has `2n`. Allocates nothing.
///
/// # Panics
///
/// Never for consistent sizes; `debug_assert`s check them.
pub fn solve(
    a: &[Real],
    b: &[Real],
    mu: &[Real],
    x: &mut [Real],
    settings: &PgsSettings,
) -> PgsStatus {
    let n = mu.len();
    let m = 2 * n;
    debug_assert_eq!(a.len(), m * m);
    debug_assert_eq!(b.len(), m);
    debug_assert_eq!(x.len(), m);
    if !(a
        .iter()
        .chain(b)
        .chain(mu)
        .chain(x.iter())
        .all(|v| v.is_finite()))
    {
        return PgsStatus::NonFinite;
    }
    let at = |r: usize, c: usize| a[c * m + r];
    let mut residual = Real::INFINITY;
    for iteration in 1..=settings.max_iterations {
        for (i, &mu_i) in mu.iter().enumerate() {
            let (rn, rt) = (2 * i, 2 * i + 1);
            // r_i = b_i + Σ_{j≠i} A_ij x_j.
            let (mut r_n, mut r_t) = (b[rn], b[rt]);
            for c in (0..m).filter(|&c| c != rn && c != rt) {
                r_n += at(rn, c) * x[c];
                r_t += at(rt, c) * x[c];
            }
            let block = Block {
                nn: at(rn, rn),
                nt: 0.5 * (at(rn, rt) + at(rt, rn)),
                tt: at(rt, rt),
            };
            let (x_n, x_t) = solve_one(&block, r_n, r_t, mu_i);
            x[rn] = x_n;
            x[rt] = x_t;
        }
        residual = natural_residual(a, b, mu, x);
        if !residual.is_finite() {
            return PgsStatus::NonFinite;
        }
        if residual <= settings.tolerance {
            return PgsStatus::Converged {
                iterations: iteration,
                residual,
            };
        }
    }
    PgsStatus::MaxIterations {
        iterations: settings.max_iterations,
        residual,
    }
}

/// The natural-map residual of `x` (see the module doc), relative to the velocity scale
/// of the problem: zero exactly at a solution.
pub fn natural_residual(a: &[Real], b: &[Real], mu: &[Real], x: &[Real]) -> Real {
    let n = mu.len();
    let m = 2 * n;
    let w = |r: usize| b[r] + (0..m).map(|c| a[c * m + r] * x[c]).sum::<Real>();
    let mut worst: Real = 0.0;
    let mut scale = b.iter().fold(0.0, |s: Real, v| s.max(v.abs()));
    for (i, &mu_i) in mu.iter().enumerate() {
        let (rn, rt) = (2 * i, 2 * i + 1);
        let kappa = a[rn * m + rn].max(a[rt * m + rt]).max(Real::MIN_POSITIVE);
        let (x_n, x_t) = (x[rn], x[rt]);
        let (w_n, w_t) = (w(rn), w(rt));
        let r_n = (kappa * x_n).min(w_n);
        let bound = kappa * mu_i * x_n.max(0.0);
        let r_t = kappa * x_t - (kappa * x_t - w_t).clamp(-bound, bound);
        worst = worst.max(r_n.abs()).max(r_t.abs());
        scale = scale.max(kappa * x_n.abs()).max(kappa * x_t.abs());
    }
    if worst == 0.0 {
        0.0
    } else {
        worst / scale.max(Real::MIN_POSITIVE)
    }
}

/// A symmetric 2×2 block `[[nn, nt], [nt, tt]]` of `A` (positive semidefinite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// `A_nn` (≥ 0).
    pub nn: Real,
    /// `A_nt`.
    pub nt: Real,
    /// `A_tt` (≥ 0).
    pub tt: Real,
}

/// Relative tolerance of the sign tests of [`solve_one`].
const LOCAL_TOL: Real = 1e-12;

/// The exact solution `(x_n, x_t)` of one contact, `w = A x + r` with `A` the block `a`,
/// under unilateral contact and Coulomb friction; the modes are tried in the order of
/// [`crate::lcp`]: open, stick, slide `+1`, slide `−1` (the slip direction `s` is that of
/// `w_t`, the friction `x_t = −μ s x_n`):
///
/// ```text
/// open     x = 0                                      if r_n ≥ 0
/// stick    A x = −r                                   if x_n ≥ 0, |x_t| ≤ μ x_n
/// slide s  x_t = −μ s x_n, (A_nn − μ s A_nt) x_n = −r_n   if x_n ≥ 0, s w_t ≥ 0
/// ```
///
/// A singular `A` (no tangential mobility, `A_tt = 0`; or rank one) sticks with the
/// least-norm tangential impulse when it can. If no mode fits (a Painlevé-like block,
/// `A_nn − μ s A_nt ≤ 0`), the projection `x_n = max(0, −r_n/A_nn)`, `x_t = 0` is returned.
pub fn solve_one(a: &Block, r_n: Real, r_t: Real, mu: Real) -> (Real, Real) {
    let scale = r_n.abs() + r_t.abs();
    let tol_v = LOCAL_TOL * scale;
    // Open.
    if r_n >= 0.0 {
        return (0.0, 0.0);
    }
    // Stick: A x = −r.
    let det = a.nn * a.tt - a.nt * a.nt;
    let singular = det <= 16.0 * Real::EPSILON * a.nn * a.tt;
    let stick = if !singular {
        Some((
            (-r_n * a.tt + r_t * a.nt) / det,
            (-r_t * a.nn + r_n * a.nt) / det,
        ))
    } else if a.tt <= Real::EPSILON * a.nn {
        // No tangential mobility: w_t = r_t whatever x_t; sticking needs r_t = 0.
        (r_t.abs() <= tol_v).then(|| (-r_n / a.nn, 0.0))
    } else {
        // Rank one, A = a aᵀ-like: the rows are proportional; least-norm solution of
        // A x = −r if consistent (r_t A_nn = r_n A_nt).
        let consistent = (r_t * a.nn - r_n * a.nt).abs() <= tol_v * (a.nn + a.nt.abs());
        consistent.then(|| {
            let norm2 = a.nn * a.nn + a.nt * a.nt;
            let k = -r_n / norm2;
            (k * a.nn, k * a.nt)
        })
    };
    if let Some((x_n, x_t)) = stick
        && x_n >= 0.0
        && x_t.abs() <= mu * x_n * (1.0 + LOCAL_TOL) + LOCAL_TOL * x_n.abs()
    {
        return (x_n, x_t);
    }
    // Slide s = ±1.
    for s in [1.0, -1.0] {
        let h = a.nn - mu * s * a.nt;
        if h <= 0.0 {
            continue;
        }
        let x_n = -r_n / h;
        let x_t = -mu * s * x_n;
        let w_t = a.nt * x_n + a.tt * x_t + r_t;
        if s * w_t >= -tol_v {
            return (x_n, x_t);
        }
    }
    ((-r_n / a.nn).max(0.0), 0.0)
}
