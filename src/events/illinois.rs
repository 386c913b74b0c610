//! The Illinois method: regula falsi on a bracket, with the retained end's value halved
//! when the same end is kept twice in a row, which restores superlinear convergence
//! (order ≈ 1.44) [M. Dowell, P. Jarratt, *A modified regula falsi method for computing
//! the root of an equation*, BIT 11, 168–174 (1971)]. Safeguards: each new point stays
//! half a tolerance inside the bracket, and a bisection step is taken when the bracket
//! has not halved in three iterations, so the bracket always shrinks to the tolerance.

use crate::math::Real;

/// What the function being solved reports at a trial point.
#[derive(Clone, Copy, Debug, PartialEq)]
#[doc(hidden)]
pub enum Probe {
    /// Its value (finite).
    Value(Real),
    /// The caller found what it was looking for at this point: stop.
    Stop,
}

/// The result of [`illinois`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[doc(hidden)]
pub enum Solved {
    /// `f(lo) > 0 ≥ f(hi)` and `hi − lo ≤ tol`.
    Bracket { lo: Real, hi: Real, iters: usize },
    /// The function asked to stop at `t`.
    Stopped { t: Real, iters: usize },
    /// No convergence within the iteration budget; the last bracket.
    NotConverged { lo: Real, hi: Real, iters: usize },
}

/// Shrinks the bracket `[lo, hi]` with `f(lo) = f_lo > 0 ≥ f(hi) = f_hi` around a root of
/// `f` until `hi − lo ≤ tol(lo, hi)`.
#[doc(hidden)]
pub fn illinois<E>(
    mut f: impl FnMut(Real) -> Result<Probe, E>,
    (mut lo, mut f_lo): (Real, Real),
    (mut hi, mut f_hi): (Real, Real),
    tol: impl Fn(Real, Real) -> Real,
    max_iter: usize,
) -> Result<Solved, E> {
    debug_assert!(lo <= hi && f_lo > 0.0 && f_hi <= 0.0);
    // +1: `lo` was replaced last (so `hi` was retained), −1: `hi` was replaced last.
    let mut side = 0i8;
    let mut width_ref = hi - lo;
    let mut slow = 0u32;
    for iter in 1..=max_iter {
        let tol_now = tol(lo, hi);
        if hi - lo <= tol_now {
            return Ok(Solved::Bracket {
                lo,
                hi,
                iters: iter - 1,
            });
        }
        // False position; f_hi − f_lo < 0, so x ∈ [lo, hi].
        // (With f(hi) = 0 exactly, false position would return hi itself: bisect, to
        // bracket the first zero rather than any zero.)
        let mut x = hi - f_hi * (hi - lo) / (f_hi - f_lo);
        if slow >= 3 || f_hi == 0.0 || !x.is_finite() {
            x = 0.5 * (lo + hi);
            slow = 0;
            width_ref = hi - lo;
        }
        let margin = 0.5 * tol_now;
        x = x.clamp(lo + margin, hi - margin);
        match f(x)? {
            Probe::Stop => return Ok(Solved::Stopped { t: x, iters: iter }),
            Probe::Value(fx) if fx > 0.0 => {
                lo = x;
                f_lo = fx;
                if side == 1 {
                    f_hi *= 0.5;
                }
                side = 1;
            }
            Probe::Value(fx) => {
                hi = x;
                f_hi = fx;
                if side == -1 {
                    f_lo *= 0.5;
                }
                side = -1;
            }
        }
        if hi - lo <= 0.5 * width_ref {
            width_ref = hi - lo;
            slow = 0;
        } else {
            slow += 1;
        }
    }
    Ok(Solved::NotConverged {
        lo,
        hi,
        iters: max_iter,
    })
}
