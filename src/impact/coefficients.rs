//! The configuration coefficients of [P, Sect. 3]: g, h, p, q, r_m, r_p, Δ, α, and the
//! sign case of Table 1.

use serde::{Deserialize, Serialize};

use super::problem::{ContactVelocity, ImpactMatrix};
use super::scale::Rescale;
use crate::math::Real;

/// The coefficients that decide the type of a collision [P, Eqs. (24), (34)–(36)], in the
/// paper's frame (`t` oriented so that `v_t^A ≥ 0`). The ratios `r_m`, `r_p` and `α` are
/// computed on demand: the laws themselves compare products and never divide by them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// `g = μ m_tt − m_nt`: the rate at which forward sliding slows, `dv_t/dI_n = −g`.
    pub g: Real,
    /// `h = m_nn − μ m_nt`: `dv_n/dI_n` during forward sliding.
    pub h: Real,
    /// `p = μ m_tt + m_nt`: `dv_t/dI_n = p` during reverse sliding.
    pub p: Real,
    /// `q = m_nn + μ m_nt`: `dv_n/dI_n` during reverse sliding.
    pub q: Real,
    /// `Δ = m_nn m_tt − m_nt²` [P, Eq. (24)]; exactly 0 when `W` is singular to working
    /// precision ([`ImpactMatrix::is_singular`]). In an [`Outcome`](super::Outcome) it is
    /// computed at order one and scaled back by `s²`, so it may overflow for `|W|` beyond
    /// about 1e154.
    pub det: Real,
    /// `|v_n^A|` (m/s).
    v_n: Real,
    /// `v_t^A ≥ 0` (m/s).
    v_t: Real,
}

impl Coefficients {
    /// Computes the coefficients for `W`, `μ` and a velocity of approach with
    /// `v_n^A < 0 ≤ v_t^A`.
    ///
    /// Implements [P, Eqs. (24), (35)]:
    /// `g = μ m_tt − m_nt`, `h = m_nn − μ m_nt`, `p = μ m_tt + m_nt`, `q = m_nn + μ m_nt`,
    /// `Δ = m_nn m_tt − m_nt²`. Identities (used by the tests): `g + p = 2μ m_tt`,
    /// `h + q = 2 m_nn`, `g q + h p = 2μΔ` [P, Eq. (37)].
    #[inline(always)]
    pub fn new(w: &ImpactMatrix, mu: Real, v_a: ContactVelocity) -> Self {
        Self {
            g: mu * w.tt - w.nt,
            h: w.nn - mu * w.nt,
            p: mu * w.tt + w.nt,
            q: w.nn + mu * w.nt,
            det: if w.is_singular() { 0.0 } else { w.det() },
            v_n: -v_a.n,
            v_t: v_a.t,
        }
    }

    /// The coefficients of the problem `(s W, c v^A)` from those of `(W, v^A)`, with the
    /// powers of two of [`Scale::exponents`](super::scale::Scale::exponents): g, h, p, q
    /// scale by `s`, `Δ` by `s²`, the velocities by `c`.
    #[inline(always)]
    pub(super) fn scaled<R: Rescale>(&self, k: &R) -> Self {
        Self {
            g: k.coefficient(self.g),
            h: k.coefficient(self.h),
            p: k.coefficient(self.p),
            q: k.coefficient(self.q),
            det: k.det(self.det),
            v_n: k.velocity(self.v_n),
            v_t: k.velocity(self.v_t),
        }
    }

    /// `r_m = g / h` [P, Eq. (36)] (infinite when `h = 0`).
    pub fn r_m(&self) -> Real {
        self.g / self.h
    }

    /// `r_p = p / q` [P, Eq. (36)] (infinite when `q = 0`).
    pub fn r_p(&self) -> Real {
        self.p / self.q
    }

    /// `α = v_t^A / |v_n^A|` [P, Eq. (34)], ≥ 0.
    pub fn alpha(&self) -> Real {
        self.v_t / self.v_n
    }

    /// The sign case 1–5 of (g, h, p, q) [P, Table 1, columns 2–5].
    ///
    /// At most one of g, h, p, q is negative, because `g + p = 2μ m_tt ≥ 0`,
    /// `h + q = 2 m_nn > 0` and `g q + h p = 2μΔ ≥ 0`. A zero is counted as positive: by
    /// [P, Comment g] the equal signs can be added to the inequalities of the table and
    /// the solution stays the same on either side.
    #[inline(always)]
    pub fn sign_case(&self) -> SignCase {
        if self.g < 0.0 {
            SignCase::Five
        } else if self.h < 0.0 {
            SignCase::Four
        } else if self.p < 0.0 {
            SignCase::Three
        } else if self.q < 0.0 {
            SignCase::Two
        } else {
            SignCase::One
        }
    }
}

/// The admissible sign variations of (g, h, p, q) [P, Table 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SignCase {
    /// g, h, p, q > 0: sticking for `α < (1+e) r_m`, forward sliding above.
    One = 1,
    /// q < 0: sticking for `α < (1+e) r_m`, forward sliding above.
    Two = 2,
    /// p < 0: reverse sliding for `α < (1+e) r_m`, forward sliding above.
    Three = 3,
    /// h < 0: sticking for every `α`.
    Four = 4,
    /// g < 0: forward sliding for every `α`.
    Five = 5,
}

impl SignCase {
    /// The case number 1–5 of Table 1.
    pub fn number(self) -> u8 {
        self as u8
    }
}
