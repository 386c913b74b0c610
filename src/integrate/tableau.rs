//! Butcher tableaux of the explicit Runge–Kutta methods.
//!
//! ## DOPRI5(4): Dormand–Prince 5(4), seven stages, FSAL
//!
//! J. R. Dormand, P. J. Prince, *A family of embedded Runge–Kutta formulae*, J. Comput.
//! Appl. Math. 6(1), 19–26 (1980); [HNW, II.5, Table 5.2]. The 5th-order solution `b`
//! propagates (local extrapolation); the 4th-order `b̂` only estimates the error. The
//! last row of `A` equals `b` and `c₇ = 1`, so the 7th stage is `f(t + h, y₁)`: it is the
//! first stage of the next step (First Same As Last) and costs nothing there.
//!
//! ```text
//!   0    |
//!   1/5  | 1/5
//!   3/10 | 3/40        9/40
//!   4/5  | 44/45      −56/15       32/9
//!   8/9  | 19372/6561 −25360/2187  64448/6561  −212/729
//!   1    | 9017/3168  −355/33      46732/5247   49/176   −5103/18656
//!   1    | 35/384      0           500/1113     125/192  −2187/6784    11/84
//!  ------+------------------------------------------------------------------------
//!   b    | 35/384      0           500/1113     125/192  −2187/6784    11/84     0
//!   b̂    | 5179/57600  0           7571/16695   393/640  −92097/339200 187/2100  1/40
//!   e=b−b̂| 71/57600    0          −71/16695     71/1920  −17253/339200 22/525   −1/40
//! ```
//!
//! The continuous extension of order 4 is Shampine's [L. F. Shampine, *Some practical
//! Runge–Kutta formulas*, Math. Comp. 46(173), 135–150 (1986)] in the form of
//! [HNW, II.6, Eq. (6.12)] and Hairer's code `DOPRI5` (`CONTD5`): with `θ = (t − t₀)/h`,
//!
//! ```text
//!   u(θ) = r₁ + θ (r₂ + (1−θ) (r₃ + θ (r₄ + (1−θ) r₅)))
//!   r₁ = y₀,  r₂ = y₁ − y₀,  r₃ = h k₁ − r₂,  r₄ = r₂ − h k₇ − r₃,
//!   r₅ = h (d₁ k₁ + d₃ k₃ + d₄ k₄ + d₅ k₅ + d₆ k₆ + d₇ k₇)
//!   d  = (−12715105075/11282082432, 0, 87487479700/32700410799,
//!         −10690763975/1880347072, 701980252875/199316789632,
//!         −1453857185/822651844, 69997945/29380423)
//! ```
//!
//! `u` interpolates `y₀, y₁` and the slopes `k₁ = f(t₀, y₀)`, `k₇ = f(t₁, y₁)` at the ends
//! (with `r₅ = 0` it is the cubic Hermite interpolant, which RK4 uses).
//!
//! ## RK4: the classical Runge–Kutta method [HNW, II.1, Table 1.2, left]
//!
//! ```text
//!   0   |
//!   1/2 | 1/2
//!   1/2 | 0    1/2
//!   1   | 0    0    1
//!  -----+--------------------
//!   b   | 1/6  1/3  1/3  1/6
//! ```

use crate::math::Real;

/// DOPRI5 nodes `c₂ … c₆` (`c₁ = 0`, `c₇ = 1`).
pub(crate) const C2: Real = 1.0 / 5.0;
pub(crate) const C3: Real = 3.0 / 10.0;
pub(crate) const C4: Real = 4.0 / 5.0;
pub(crate) const C5: Real = 8.0 / 9.0;

/// DOPRI5 coupling coefficients `a_ij`, row by row.
pub(crate) const A21: Real = 1.0 / 5.0;

pub(crate) const A31: Real = 3.0 / 40.0;
pub(crate) const A32: Real = 9.0 / 40.0;

pub(crate) const A41: Real = 44.0 / 45.0;
pub(crate) const A42: Real = -56.0 / 15.0;
pub(crate) const A43: Real = 32.0 / 9.0;

pub(crate) const A51: Real = 19372.0 / 6561.0;
pub(crate) const A52: Real = -25360.0 / 2187.0;
pub(crate) const A53: Real = 64448.0 / 6561.0;
pub(crate) const A54: Real = -212.0 / 729.0;

pub(crate) const A61: Real = 9017.0 / 3168.0;
pub(crate) const A62: Real = -355.0 / 33.0;
pub(crate) const A63: Real = 46732.0 / 5247.0;
pub(crate) const A64: Real = 49.0 / 176.0;
pub(crate) const A65: Real = -5103.0 / 18656.0;

/// Last row = 5th-order weights `b` (`b₂ = b₇ = 0`).
pub(crate) const A71: Real = 35.0 / 384.0;
pub(crate) const A73: Real = 500.0 / 1113.0;
pub(crate) const A74: Real = 125.0 / 192.0;
pub(crate) const A75: Real = -2187.0 / 6784.0;
pub(crate) const A76: Real = 11.0 / 84.0;

/// Error weights `e = b − b̂` (`e₂ = 0`).
pub(crate) const E1: Real = 71.0 / 57600.0;
pub(crate) const E3: Real = -71.0 / 16695.0;
pub(crate) const E4: Real = 71.0 / 1920.0;
pub(crate) const E5: Real = -17253.0 / 339200.0;
pub(crate) const E6: Real = 22.0 / 525.0;
pub(crate) const E7: Real = -1.0 / 40.0;

/// Dense-output weights `d` of `r₅` (`d₂ = 0`).
pub(crate) const D1: Real = -12715105075.0 / 11282082432.0;
pub(crate) const D3: Real = 87487479700.0 / 32700410799.0;
pub(crate) const D4: Real = -10690763975.0 / 1880347072.0;
pub(crate) const D5: Real = 701980252875.0 / 199316789632.0;
pub(crate) const D6: Real = -1453857185.0 / 822651844.0;
pub(crate) const D7: Real = 69997945.0 / 29380423.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// Row sums of `A` equal the nodes `c` (the stages are consistent).
    #[test]
    fn row_sums_are_the_nodes() {
        let eps = 4.0 * Real::EPSILON;
        assert!((A21 - C2).abs() <= eps);
        assert!((A31 + A32 - C3).abs() <= eps);
        assert!((A41 + A42 + A43 - C4).abs() <= eps);
        assert!((A51 + A52 + A53 + A54 - C5).abs() <= 16.0 * eps);
        assert!((A61 + A62 + A63 + A64 + A65 - 1.0).abs() <= 16.0 * eps);
        assert!((A71 + A73 + A74 + A75 + A76 - 1.0).abs() <= eps);
    }

    /// The order conditions of the 5th-order weights up to order 5 along the "bushy"
    /// trees `Σ bᵢ cᵢ^(q−1) = 1/q`, and `Σ eᵢ = 0` (both weights are consistent).
    #[test]
    fn quadrature_conditions() {
        let b = [A71, 0.0, A73, A74, A75, A76, 0.0];
        let c = [0.0, C2, C3, C4, C5, 1.0, 1.0];
        for q in 1..=5 {
            let s: Real = b.iter().zip(c).map(|(b, c)| b * c.powi(q - 1)).sum();
            assert!((s - 1.0 / q as Real).abs() < 1e-15, "q = {q}: {s}");
        }
        let e = [E1, 0.0, E3, E4, E5, E6, E7];
        assert!(e.iter().sum::<Real>().abs() < 1e-16);
        // b̂ = b − e integrates polynomials up to degree 3 exactly (order 4).
        for q in 1..=4 {
            let s: Real = b
                .iter()
                .zip(e)
                .zip(c)
                .map(|((b, e), c)| (b - e) * c.powi(q - 1))
                .sum();
            assert!((s - 1.0 / q as Real).abs() < 1e-15, "q = {q}: {s}");
        }
    }

    /// `Σ dᵢ = 0`: `r₅` vanishes on a constant slope, so the dense output of `ẏ = c` is
    /// exactly linear.
    #[test]
    fn dense_weights_sum_to_zero() {
        let s = D1 + D3 + D4 + D5 + D6 + D7;
        assert!(s.abs() < 1e-14, "{s}");
    }
}
