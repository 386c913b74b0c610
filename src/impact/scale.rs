//! The scale invariance of the impact laws, used to solve every problem at order one.
//!
//! The laws are homogeneous: if `(I, v^S)` solves `(W, v^A, e, μ)`, then for `s, c > 0`
//! `((c/s) I, c v^S)` solves `(s W, c v^A, e, μ)`. Eqs. (22)–(23), `v^S − v^A = W I`,
//! hold with `c v^S − c v^A = (s W)((c/s) I)`; Coulomb's cone and the directions of the
//! phases of Routh's path (`dI_t = ∓μ dI_n`, `dI_t = −(m_nt/m_tt) dI_n`) are linear in
//! `I` and unchanged by `W → s W`; Newton's end condition `v_n^S = −e v_n^A` is linear in
//! the velocities, Poisson's `I_n = (1 + e) I_c` in the impulses, and Stronge's works
//! `∫ v_n dI_n` scale by `c · c/s` on both sides of `W_r = −e² W_c`. Hence:
//!
//! | quantity | scales by |
//! |---|---|
//! | `I_n`, `I_t` (and along the phases) | `c/s` |
//! | `v^S`, the velocities along the phases | `c` |
//! | `ΔE` [P, Eq. (29)], `work_n`, `work_t` | `c²/s` |
//! | g, h, p, q [P, Eq. (35)] | `s` |
//! | `Δ` [P, Eq. (24)] | `s²` |
//! | α, r_m, r_p, the type, the sign case | 1 |
//!
//! [`solve`](super::solve) divides `W` by `s = 2^a` and `v^A` by `c = 2^b`, the powers of
//! two at or below their largest entries, solves that problem of order one, and scales the
//! answer back. Products by powers of two are exact in binary floating point, so where
//! nothing over- or underflows the answer is bit for bit what the unscaled formulas give;
//! elsewhere (`Δ` overflowed beyond `|W| ≈ 1e154`, `V²` underflowed below `|v| ≈ 1e-154`)
//! it is the answer the formulas would give in exact arithmetic, rounded once (results in
//! the subnormal range, below 2.2e-308, keep fewer digits). An answer beyond the range of
//! doubles, or an impulse `I_n > 0` that rounds to 0, is an error
//! ([`ImpactError::OutOfRange`]).

use super::coefficients::Coefficients;
use super::coefficients::SignCase;
use super::outcome::Outcome;
use super::path::PathPoint;
use super::problem::{ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem, Impulse};
use super::{Law, LawSolution};
use crate::math::Real;

/// The powers of two `s = 2^w` and `c = 2^v` of a problem's `W` and `v^A`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[doc(hidden)]
pub struct Scale {
    /// `log2 s`.
    w: i32,
    /// `log2 c`.
    v: i32,
}

impl Scale {
    /// The scales of `W` and `v^A`: the powers of two at or below their largest entries
    /// (both nonzero for valid data: `m_nn > 0`, `v_n^A < 0`), given as the bit patterns
    /// of the largest magnitudes `max |m_ij|` and `max |v_i^A|` (finite).
    #[inline(always)]
    pub(super) fn of_magnitudes(w_max: u64, v_max: u64) -> Self {
        Self {
            w: exponent_of_magnitude(w_max),
            v: exponent_of_magnitude(v_max),
        }
    }

    /// [`Scale::of_magnitudes`] when both powers of two lie in `[2^-340, 2^340]` (biased
    /// exponents within `1023 ± 340`).
    #[inline(always)]
    pub(super) fn of_moderate_magnitudes(w_max: u64, v_max: u64) -> Option<Self> {
        let biased = |bits: u64| (bits >> 52) as u32;
        let moderate = |bits: u64| biased(bits).wrapping_sub(1023 - MODERATE) <= 2 * MODERATE;
        (moderate(w_max) & moderate(v_max)).then(|| Self {
            w: biased(w_max) as i32 - 1023,
            v: biased(v_max) as i32 - 1023,
        })
    }

    /// [`Scale::down`] of [`Scale::matrix_down`] at moderate scales: the same products by
    /// `2^-log2 s` and `2^-log2 c` (normal doubles), without [`ldexp`]'s test of the range.
    #[doc(hidden)]
    pub fn down_moderate(&self, pb: &ImpactProblem) -> ImpactProblem {
        let (s, c) = (pow2(-self.w), pow2(-self.v));
        let w = &pb.w;
        ImpactProblem {
            w: ImpactMatrix::new(w.nn * s, w.nt * s, w.tt * s),
            v_a: ContactVelocity::new(pb.v_a.n * c, pb.v_a.t * c),
            ..*pb
        }
    }

    /// [`Scale::down_moderate`] in the frame whose tangent is `−t` when `mirrored`:
    /// `m_nt` and `v_t^A` times `−2^-log2 s` and `−2^-log2 c` (exact: minus the products
    /// of [`Scale::down_moderate`]), the sign set in the bits of the powers of two.
    #[inline(always)]
    pub(super) fn down_moderate_mirrored(
        &self,
        pb: &ImpactProblem,
        mirrored: bool,
    ) -> ImpactProblem {
        let sign = u64::from(mirrored) << 63;
        let (s, c) = (pow2(-self.w), pow2(-self.v));
        let (s_t, c_t) = (
            Real::from_bits(s.to_bits() | sign),
            Real::from_bits(c.to_bits() | sign),
        );
        let w = &pb.w;
        ImpactProblem {
            w: ImpactMatrix::new(w.nn * s, w.nt * s_t, w.tt * s),
            v_a: ContactVelocity::new(pb.v_a.n * c, pb.v_a.t * c_t),
            ..*pb
        }
    }

    /// The powers of two of [`exponents`](Scale::exponents) as numbers, for moderate
    /// scales ([`Scale::of_moderate_magnitudes`]), whose exponents are those of normal
    /// doubles.
    #[inline(always)]
    pub(super) fn factors(&self) -> Factors {
        let k = self.exponents();
        debug_assert!(self.w.unsigned_abs() <= MODERATE && self.v.unsigned_abs() <= MODERATE);
        Factors {
            impulse: pow2(k.impulse),
            velocity: pow2(k.velocity),
            work: pow2(k.work),
            coefficient: pow2(k.coefficient),
            det: pow2(k.det),
            limit: pow2(1023 - k.impulse.max(k.work).max(0)),
        }
    }

    /// `W / s`, whose largest entry lies in `[1, 2)`.
    #[inline(always)]
    pub(super) fn matrix_down(&self, w: &ImpactMatrix) -> ImpactMatrix {
        ImpactMatrix::new(
            ldexp(w.nn, -self.w),
            ldexp(w.nt, -self.w),
            ldexp(w.tt, -self.w),
        )
    }

    /// The problem `(W/s, v^A/c, e, μ)`, with `w = W/s` already computed
    /// ([`Scale::matrix_down`]).
    #[inline(always)]
    pub(super) fn down(&self, pb: &ImpactProblem, w: ImpactMatrix) -> ImpactProblem {
        ImpactProblem {
            w,
            v_a: ContactVelocity::new(ldexp(pb.v_a.n, -self.v), ldexp(pb.v_a.t, -self.v)),
            ..*pb
        }
    }

    /// Why the problem `unit = self.down(original)` is beyond the precision of doubles,
    /// if it is: an entry of `W` or `v^A` more than `2^511` times smaller than the largest
    /// of its kind (at order one its square, which the laws form — `m_nt²` in `Δ`, the
    /// velocities' squares in the works — is below the normal doubles and has lost its
    /// digits; an entry 2^1022 times smaller lost them already on the way down, or was a
    /// subnormal in the caller's data), a product `μ m_nt` or `μ m_tt` of g, h, p, q
    /// [P, Eq. (35)] below the normal doubles (a tiny `μ`), or a coefficient g, h, p, q
    /// beyond 1e150 (a large `μ`), whose products with another overflow. Asked only when a
    /// law's solution has failed: such data often solve well.
    pub(super) fn out_of_scale(
        &self,
        original: &ImpactProblem,
        unit: &ImpactProblem,
    ) -> Option<String> {
        let (w, v) = (&original.w, original.v_a);
        let entries = [
            ("m_nn", w.nn, unit.w.nn, self.w),
            ("m_nt", w.nt, unit.w.nt, self.w),
            ("m_tt", w.tt, unit.w.tt, self.w),
            ("v_n^A", v.n, unit.v_a.n, self.v),
            ("v_t^A", v.t, unit.v_a.t, self.v),
        ];
        // At order one the largest entry of each kind is in [1, 2); an entry that lost
        // digits on the way down (to 0, even) no longer gives the caller's back.
        let tiny = |u: Real| u != 0.0 && u.abs() < ldexp(1.0, -511);
        if let Some((what, x, _, _)) =
            (entries.iter()).find(|&&(_, x, u, k)| tiny(u) || ldexp(u, k) != x)
        {
            let (of, largest) = if what.starts_with('m') {
                ("W", ldexp(1.0, self.w))
            } else {
                ("v^A", ldexp(1.0, self.v))
            };
            return Some(format!(
                "{what} = {x:e} is more than 2^511 times smaller than the largest entry of \
                 {of} (about {largest:e}): its products in the law lose their digits"
            ));
        }
        // μ m_ij in g, h, p, q (Eq. 35) below the normal doubles: μ tiny against W.
        let mu = unit.mu;
        let under = |m: Real| m != 0.0 && mu != 0.0 && (mu * m).abs() < Real::MIN_POSITIVE;
        if let Some((what, m)) = [("m_nt", unit.w.nt), ("m_tt", unit.w.tt)]
            .into_iter()
            .find(|&(_, m)| under(m))
        {
            return Some(format!(
                "μ = {mu:e} times {what} = {m:e} at order one, in g, h, p, q, is below the \
                 normal doubles"
            ));
        }
        let c = Coefficients::new(&unit.w, unit.mu, unit.v_a);
        let largest = c.g.abs().max(c.h.abs()).max(c.p.abs()).max(c.q.abs());
        (largest > 1e150).then(|| {
            format!(
                "μ = {:e} makes g, h, p, q as large as {largest:e} against W, and their products \
                 overflow",
                original.mu
            )
        })
    }

    /// The powers of two of an impulse, a velocity, a work, a coefficient g, h, p, q and
    /// `Δ`, in this order (see the module's table).
    #[inline(always)]
    pub(super) fn exponents(&self) -> Exponents {
        Exponents {
            impulse: self.v - self.w,
            velocity: self.v,
            work: 2 * self.v - self.w,
            coefficient: self.w,
            det: 2 * self.w,
        }
    }

    /// The outcome of the problem scaled down by [`Scale::down`], brought back to the
    /// caller's scales; an error if a number of it is beyond the range of doubles. (The
    /// general path; [`Factors::outcome`] is the usual one.)
    #[inline(never)]
    #[doc(hidden)]
    pub fn up(&self, mut out: Outcome) -> Result<Outcome, ImpactError> {
        let k = self.exponents();
        // Checked at order one: which number leaves the range, and by how much.
        if let Some((what, x, e)) = beyond_range(&out, &k) {
            return Err(ImpactError::OutOfRange {
                what,
                log10: x.abs().log10() + Real::from(e) * std::f64::consts::LOG10_2,
            });
        }
        out.impulse.n = ldexp(out.impulse.n, k.impulse);
        out.impulse.t = ldexp(out.impulse.t, k.impulse);
        out.v_s = ContactVelocity::new(ldexp(out.v_s.n, k.velocity), ldexp(out.v_s.t, k.velocity));
        out.delta_e = ldexp(out.delta_e, k.work);
        out.work_n = ldexp(out.work_n, k.work);
        out.work_t = ldexp(out.work_t, k.work);
        out.coefficients = out.coefficients.scaled(&k);
        out.phases = out.phases.scaled(&k);
        Ok(out)
    }
}

/// How each kind of quantity of an answer at order one is brought back to the caller's
/// scales (see the module's table).
#[doc(hidden)]
pub trait Rescale {
    /// An impulse: times `c/s`.
    fn impulse(&self, x: Real) -> Real;
    /// A velocity: times `c`.
    fn velocity(&self, x: Real) -> Real;
    /// A work or an energy: times `c²/s`.
    fn work(&self, x: Real) -> Real;
    /// g, h, p, q: times `s`.
    fn coefficient(&self, x: Real) -> Real;
    /// `Δ`: times `s²`.
    fn det(&self, x: Real) -> Real;
}

impl Rescale for Exponents {
    #[inline(always)]
    fn impulse(&self, x: Real) -> Real {
        ldexp(x, self.impulse)
    }
    #[inline(always)]
    fn velocity(&self, x: Real) -> Real {
        ldexp(x, self.velocity)
    }
    #[inline(always)]
    fn work(&self, x: Real) -> Real {
        ldexp(x, self.work)
    }
    #[inline(always)]
    fn coefficient(&self, x: Real) -> Real {
        ldexp(x, self.coefficient)
    }
    #[inline(always)]
    fn det(&self, x: Real) -> Real {
        ldexp(x, self.det)
    }
}

/// The powers of two of [`Exponents`] as numbers, each a normal double: a product by one
/// of them is exact unless it over- or underflows, and equals [`ldexp`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[doc(hidden)]
pub struct Factors {
    impulse: Real,
    velocity: Real,
    work: Real,
    coefficient: Real,
    det: Real,
    /// `2^(1023 − k)` for the largest `k ≥ 0` of the impulses and the works: a number of
    /// these kinds below it at order one stays below `2^1023` once scaled.
    limit: Real,
}

impl Rescale for Factors {
    #[inline(always)]
    fn impulse(&self, x: Real) -> Real {
        x * self.impulse
    }
    #[inline(always)]
    fn velocity(&self, x: Real) -> Real {
        x * self.velocity
    }
    #[inline(always)]
    fn work(&self, x: Real) -> Real {
        x * self.work
    }
    #[inline(always)]
    fn coefficient(&self, x: Real) -> Real {
        x * self.coefficient
    }
    #[inline(always)]
    fn det(&self, x: Real) -> Real {
        x * self.det
    }
}

impl Factors {
    /// The outcome in the caller's frame and scales of a law's solution `sol` in the
    /// paper's frame at order one, with its `ΔE`: the tangential components change sign
    /// where `t` was mirrored (Eq. 10), and each kind of quantity is multiplied by its
    /// power of two. A product by `±2^k` is exact, and the same number as the mirrored
    /// component times `2^k`: bit for bit [`Scale::up`] (with its [`ldexp`]) of the
    /// mirrored solution, where [`keep_in_range`](Self::keep_in_range) holds.
    #[inline(always)]
    #[doc(hidden)]
    pub fn outcome(
        &self,
        law: Law,
        case: SignCase,
        c: &Coefficients,
        sol: &LawSolution,
        delta_e: Real,
        mirrored: bool,
    ) -> Outcome {
        let sign = if mirrored { -1.0 } else { 1.0 };
        let (impulse_t, velocity_t) = (sign * self.impulse, sign * self.velocity);
        let impulse = |i: Impulse| Impulse::new(self.impulse(i.n), i.t * impulse_t);
        let velocity =
            |v: ContactVelocity| ContactVelocity::new(self.velocity(v.n), v.t * velocity_t);
        let point = |p: &PathPoint| PathPoint {
            i: impulse(p.i),
            v: velocity(p.v),
            work_n: self.work(p.work_n),
            work_t: self.work(p.work_t),
        };
        let end = sol.phases.end();
        Outcome {
            law,
            kind: sol.kind,
            case,
            coefficients: c.scaled(self),
            impulse: impulse(sol.impulse),
            v_s: velocity(sol.v_s),
            phases: sol.phases.map(point, velocity),
            delta_e: self.work(delta_e),
            work_n: self.work(end.work_n),
            work_t: self.work(end.work_t),
            mirrored,
        }
    }

    /// Whether [`outcome`](Self::outcome) keeps the solution `sol` at order one, of a
    /// problem from [`ImpactProblem::at_moderate_scale`], in the range of doubles where
    /// [`Scale::up`] checks it (`beyond_range`): the numbers it checks stay finite, and
    /// `I_n > 0` does not become 0. The impulses and works are compared at order one with
    /// `limit`, so that the check does not wait for the products (their magnitudes are
    /// the same in either frame); g, h, p, q stay finite at moderate scales.
    #[inline(always)]
    #[doc(hidden)]
    pub fn keep_in_range(&self, sol: &LawSolution, delta_e: Real) -> bool {
        // The last phase ends at the impulse with the works, so the end of the first phase
        // stands for the phases.
        let i = sol.impulse;
        let (end, first) = (sol.phases.end(), sol.phases.first_end());
        debug_assert!(end.i == i, "the phase ends at I");
        let small = |x: Real| x.abs() < self.limit;
        let finite = small(i.n)
            & small(i.t)
            & small(delta_e)
            & small(end.work_n)
            & small(end.work_t)
            & small(first.i.n)
            & small(first.i.t)
            & small(first.work_n)
            & small(first.work_t);
        finite && !(i.n > 0.0 && self.impulse(i.n) == 0.0)
    }
}

/// The powers of two by which each kind of quantity scales (see [`Scale::exponents`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Exponents {
    /// Impulses: `c/s`.
    pub(super) impulse: i32,
    /// Velocities: `c`.
    pub(super) velocity: i32,
    /// Works and energies: `c²/s`.
    pub(super) work: i32,
    /// g, h, p, q: `s`.
    pub(super) coefficient: i32,
    /// `Δ`: `s²`.
    pub(super) det: i32,
}

/// The first number of an outcome at order one that the powers of two `k` take beyond
/// the range of doubles (infinite), or `I_n > 0` that they bring to 0, with its name, its
/// value at order one and its power of two. (`Δ`, which no answer reports, may overflow
/// for `|W|` beyond 1e154 and is not checked; the velocities scale as `v^A` and cannot.)
#[cold]
#[inline(never)]
fn beyond_range(out: &Outcome, k: &Exponents) -> Option<(&'static str, Real, i32)> {
    let c = &out.coefficients;
    let numbers = [
        ("I_n", out.impulse.n, k.impulse),
        ("I_t", out.impulse.t, k.impulse),
        ("ΔE", out.delta_e, k.work),
        ("work_n", out.work_n, k.work),
        ("work_t", out.work_t, k.work),
        ("g", c.g, k.coefficient),
        ("h", c.h, k.coefficient),
        ("p", c.p, k.coefficient),
        ("q", c.q, k.coefficient),
    ];
    let phases = out.phases.iter().flat_map(|ph| {
        let end = ph.end;
        [
            ("I_n at the end of a phase", end.i.n, k.impulse),
            ("I_t at the end of a phase", end.i.t, k.impulse),
            ("work_n at the end of a phase", end.work_n, k.work),
            ("work_t at the end of a phase", end.work_t, k.work),
        ]
    });
    let overflow = (numbers.into_iter().chain(phases)).find(|&(_, x, e)| !ldexp(x, e).is_finite());
    let underflow = || {
        let i_n = out.impulse.n;
        (i_n > 0.0 && ldexp(i_n, k.impulse) == 0.0).then_some(("I_n", i_n, k.impulse))
    };
    overflow.or_else(underflow)
}

/// The largest `|log2 s|` and `|log2 c|` of the scales that [`solve`](super::solve) takes
/// in one pass: every power of two of [`Scale::exponents`] (at most `3 · 340 = 1020` in
/// magnitude, for the works' `c²/s`) is then that of a normal double.
const MODERATE: u32 = 340;

/// The exponent `k` of a finite `x ≠ 0`: `2^k ≤ |x| < 2^(k+1)` (subnormals included); 0
/// for 0 and non-finite `x`.
#[inline(always)]
#[doc(hidden)]
pub fn exponent(x: Real) -> i32 {
    if x == 0.0 || !x.is_finite() {
        return 0;
    }
    let biased = ((x.to_bits() >> 52) & 0x7FF) as i32;
    if biased == 0 {
        // Subnormal: bring it into the normal range first (exact).
        exponent(x * pow2(64)) - 64
    } else {
        biased - 1023
    }
}

/// [`exponent`] of the finite number `|x| ≥ 0` given by its bits: the biased exponent field
/// of a normal number, less its bias.
#[inline(always)]
fn exponent_of_magnitude(bits: u64) -> i32 {
    let biased = (bits >> 52) as i32;
    if biased == 0 {
        exponent_of_subnormal(Real::from_bits(bits))
    } else {
        biased - 1023
    }
}

/// [`exponent`] of 0 or a subnormal number (the slow path).
#[cold]
#[inline(never)]
fn exponent_of_subnormal(x: Real) -> i32 {
    exponent(x)
}

/// `x · 2^k`, exact unless the result is subnormal (then rounded, at most twice) or beyond
/// the range of doubles (then infinite).
#[inline(always)]
#[doc(hidden)]
pub fn ldexp(x: Real, k: i32) -> Real {
    if (-1022..=1023).contains(&k) {
        x * pow2(k)
    } else {
        ldexp_far(x, k)
    }
}

/// [`ldexp`] for `k` beyond the exponents of the normal doubles: in steps of `2^±1022`.
#[cold]
fn ldexp_far(mut x: Real, mut k: i32) -> Real {
    while k > 1023 {
        x *= pow2(1023);
        k -= 1023;
    }
    while k < -1022 {
        x *= pow2(-1022);
        k += 1022;
    }
    x * pow2(k)
}

/// `2^k` for `k ∈ [−1022, 1023]`, from its bits.
#[inline(always)]
#[doc(hidden)]
pub fn pow2(k: i32) -> Real {
    debug_assert!((-1022..=1023).contains(&k));
    Real::from_bits(((k + 1023) as u64) << 52)
}
