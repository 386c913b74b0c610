//! The data of a one-point impact problem: the matrix `W`, the velocity of approach, `e`
//! and `μ`; their validation; the impulse and velocity pairs in the contact frame.

use serde::{Deserialize, Serialize};

use super::scale::{Factors, Scale};
use crate::math::{Real, Shown};

/// The 2×2 matrix `W = [[m_nn, m_nt], [m_nt, m_tt]]` of [P, Eq. (20)], mapping the
/// impulses `(I_n, I_t)` to the jump of the contact velocity: `v^S − v^A = W I`
/// [P, Eqs. (22)–(23)]. Symmetric positive definite (`W = J M⁻¹ Jᵀ` with the usual
/// positive definite `M`). Units: 1/kg for a particle, in general (m/s)/(N·s).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactMatrix {
    /// `m_nn`: normal velocity change per unit normal impulse (> 0).
    #[serde(rename = "mnn")]
    pub nn: Real,
    /// `m_nt`: normal velocity change per unit tangential impulse (either sign).
    #[serde(rename = "mnt")]
    pub nt: Real,
    /// `m_tt`: tangential velocity change per unit tangential impulse (> 0).
    #[serde(rename = "mtt")]
    pub tt: Real,
}

impl ImpactMatrix {
    /// The matrix from its three distinct entries.
    pub fn new(nn: Real, nt: Real, tt: Real) -> Self {
        Self { nn, nt, tt }
    }

    /// `Δ = m_nn m_tt − m_nt²` [P, Eq. (24)], positive for a positive definite `W`.
    #[inline(always)]
    pub fn det(&self) -> Real {
        self.nn * self.tt - self.nt * self.nt
    }

    /// The velocity jump `W I` produced by the impulse `I` [P, Eqs. (22)–(23)]:
    /// `Δv_n = m_nn I_n + m_nt I_t`, `Δv_t = m_nt I_n + m_tt I_t`.
    #[inline(always)]
    pub fn apply(&self, i: Impulse) -> ContactVelocity {
        ContactVelocity {
            n: self.nn * i.n + self.nt * i.t,
            t: self.nt * i.n + self.tt * i.t,
        }
    }

    /// Whether `W` is singular to working precision: `Δ ≤ 16 ε m_nn m_tt` (rank 1, or
    /// `m_tt = 0`).
    ///
    /// DEVIATION from [P, Eq. (24)]: the paper takes `Δ > 0` for granted, which holds only
    /// when the 2×p matrix `C` of partial velocities has rank 2. With minimal coordinates
    /// it often has rank 1: a pendulum (p = 1), a ball on a vertical slide. Then the contact
    /// velocity moves along a line, `W` is positive *semi*definite, and the laws here are
    /// extended to it (see [`crate::impact`]).
    #[inline(always)]
    pub fn is_singular(&self) -> bool {
        self.det() <= SINGULAR_RELATIVE_DET * self.nn * self.tt
    }

    /// The same matrix in the frame whose tangent is `−t`: `m_nt` changes sign.
    #[inline(always)]
    pub fn mirrored(&self) -> Self {
        Self {
            nt: -self.nt,
            ..*self
        }
    }
}

/// A contact velocity in the frame `(n, t)` (m/s): the velocity of approach `v^A`, of
/// separation `v^S`, or any velocity along the collision [P, Eq. (21)].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactVelocity {
    /// Normal component `v·n` (m/s); negative while the points approach.
    pub n: Real,
    /// Tangential component `v·t` (m/s).
    pub t: Real,
}

impl ContactVelocity {
    /// The velocity from its normal and tangential components.
    pub fn new(n: Real, t: Real) -> Self {
        Self { n, t }
    }
}

/// An impulse in the frame `(n, t)` (N·s) [P, Eq. (13)].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Impulse {
    /// Normal impulse `I_n` (N·s), positive: the surfaces only push.
    pub n: Real,
    /// Tangential impulse `I_t` (N·s).
    pub t: Real,
}

impl Impulse {
    /// The impulse from its normal and tangential components.
    pub fn new(n: Real, t: Real) -> Self {
        Self { n, t }
    }
}

/// A one-point planar impact problem: everything an impact law needs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactProblem {
    /// `W = J M⁻¹ Jᵀ` in the contact frame [P, Eq. (20)].
    pub w: ImpactMatrix,
    /// Velocity of approach `v^A` (m/s): `v_n^A < 0`; `v_t^A` of either sign (for
    /// `v_t^A < 0` the laws mirror `t` and report in the caller's frame).
    pub v_a: ContactVelocity,
    /// Coefficient of restitution `e ∈ [0, 1]` (kinematic, kinetic or energetic
    /// according to the law).
    pub e: Real,
    /// Coulomb's coefficient of friction `μ ≥ 0`, static and dynamic alike [P, Sect. 3].
    pub mu: Real,
}

/// Why an impact problem cannot be solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ImpactError {
    /// An input is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NonFinite {
        /// The input's name (`m_nn`, `v_n^A`, `e`, …).
        what: &'static str,
        /// Its value.
        value: Real,
    },
    /// `W` is not symmetric positive semidefinite with `m_nn > 0`.
    #[error(
        "W is not positive semidefinite with m_nn > 0: m_nn = {nn}, m_nt = {nt}, m_tt = {tt}, \
         Δ = m_nn m_tt − m_nt² = {det}",
        nn = Shown(*.nn), nt = Shown(*.nt), tt = Shown(*.tt), det = Shown(*.det)
    )]
    NotPositiveDefinite {
        /// `m_nn`.
        nn: Real,
        /// `m_nt`.
        nt: Real,
        /// `m_tt`.
        tt: Real,
        /// `Δ`.
        det: Real,
    },
    /// The points do not approach: `v_n^A ≥ 0`.
    #[error("the points do not approach: v_n^A = {vn} must be negative", vn = Shown(*.vn))]
    NotApproaching {
        /// `v_n^A` (m/s).
        vn: Real,
    },
    /// `e` outside `[0, 1]`.
    #[error("the coefficient of restitution e = {e} is outside [0, 1]", e = Shown(*.e))]
    RestitutionOutOfRange {
        /// `e`.
        e: Real,
    },
    /// `μ < 0`.
    #[error("the coefficient of friction μ = {mu} is negative", mu = Shown(*.mu))]
    NegativeFriction {
        /// `μ`.
        mu: Real,
    },
    /// `W` is singular and friction holds the contact while it still approaches: the
    /// impulse would grow without bound before the law's end condition is met (Cases 2
    /// and 4 of Table 1 with `Δ = 0`). A jam of rigid-body contact, like Painlevé's.
    #[error(
        "the contact jams under {law}: W is singular (the contact velocity can only move \
         along a line) and friction holds it while it still approaches, so no finite \
         impulse meets the end condition"
    )]
    Jam {
        /// The law's name.
        law: &'static str,
    },
    /// A number of the answer is beyond the range of doubles (it overflows, or `I_n`
    /// underflows to 0): the impulses scale as `|v^A| / |W|`, the energies as
    /// `|v^A|² / |W|` (see [`crate::impact`]'s scale invariance), and the data's scales
    /// are too far apart.
    #[error(
        "the answer is beyond the range of doubles: {what} ≈ {} (impulses scale as \
         |v^A|/|W|, energies as |v^A|²/|W|)",
        power_of_ten(*log10)
    )]
    OutOfRange {
        /// The quantity, e.g. `I_n`.
        what: &'static str,
        /// `log10 |value|`, the value that doubles cannot hold.
        log10: Real,
    },
    /// The data are valid but their scales are too far apart for doubles: at order one
    /// (see [`crate::impact`]'s scale invariance) an entry of `W` or of `v^A` loses digits
    /// (it is more than 2^1022 times smaller than the largest), or `μ` is so large that
    /// products of g, h, p, q overflow; and the law's solution fails on that account.
    #[error("{law}: the data are beyond the precision of doubles ({why}): {detail}")]
    IllConditioned {
        /// The law's name.
        law: &'static str,
        /// What in the data is out of scale.
        why: String,
        /// How the solution failed.
        detail: String,
    },
    /// The law's solution fails a coherence condition of [P, Sect. 4.2] beyond rounding:
    /// a bug, never an expected outcome.
    #[error("incoherent {law} solution: {detail}")]
    Incoherent {
        /// The law's name.
        law: &'static str,
        /// The failed condition.
        detail: String,
    },
}

/// `10^x` written as `±m.me±k`, for any `x` (beyond the range of doubles too).
fn power_of_ten(x: Real) -> String {
    let k = x.floor();
    format!("{:.1}e{k}", (10.0 as Real).powf(x - k))
}

/// The relative determinant `Δ / (m_nn m_tt)` at or below which `W` is singular to
/// working precision: the closed forms would divide by rounding noise.
const SINGULAR_RELATIVE_DET: Real = 16.0 * Real::EPSILON;

/// The largest `μ` that [`ImpactProblem::at_moderate_scale`] takes (exclusive): `2^500`.
const MODERATE_FRICTION: Real = Real::from_bits((1023 + 500) << 52);

/// `|x|` as its bit pattern, which orders like `|x|` (NaN above infinity).
#[inline(always)]
fn magnitude(x: Real) -> u64 {
    x.to_bits() & !(1 << 63)
}

impl ImpactProblem {
    /// The problem from its four data.
    pub fn new(w: ImpactMatrix, v_a: ContactVelocity, e: Real, mu: Real) -> Self {
        Self { w, v_a, e, mu }
    }

    /// Checks the data: finite numbers, `W` positive semidefinite with `m_nn > 0` (the
    /// normal direction must be mobile; see [`ImpactMatrix::is_singular`]), `v_n^A < 0`,
    /// `e ∈ [0, 1]`, `μ ≥ 0`. The sign of `Δ` is tested on `W` divided by the power of
    /// two of its largest entry, so that `m_nn m_tt` neither overflows nor underflows.
    pub fn validate(&self) -> Result<(), ImpactError> {
        self.at_order_one().map(|_| ())
    }

    /// [`validate`](Self::validate), returning the powers of two of `W` and `v^A` it
    /// computes on the way and the problem brought to order one with them
    /// ([`Scale::down`]), which the solver solves.
    #[inline(always)]
    #[doc(hidden)]
    pub fn at_order_one(&self) -> Result<(Scale, ImpactProblem), ImpactError> {
        // The magnitudes as bit patterns, which order like the numbers: the largest of all
        // is infinite or NaN exactly when an input is not finite.
        let (w, v) = (&self.w, self.v_a);
        let w_max = magnitude(w.nn).max(magnitude(w.nt)).max(magnitude(w.tt));
        let v_max = magnitude(v.n).max(magnitude(v.t));
        let max = w_max
            .max(v_max)
            .max(magnitude(self.e))
            .max(magnitude(self.mu));
        if max >= Real::INFINITY.to_bits() {
            return Err(self.first_non_finite());
        }
        let scale = Scale::of_magnitudes(w_max, v_max);
        let unit = scale.matrix_down(&self.w);
        if !(unit.nn > 0.0
            && unit.tt >= 0.0
            && unit.det() >= -SINGULAR_RELATIVE_DET * unit.nn * unit.tt)
        {
            return Err(self.not_positive_definite());
        }
        if self.v_a.n >= 0.0 {
            return Err(ImpactError::NotApproaching { vn: self.v_a.n });
        }
        if !(0.0..=1.0).contains(&self.e) {
            return Err(ImpactError::RestitutionOutOfRange { e: self.e });
        }
        if self.mu < 0.0 {
            return Err(ImpactError::NegativeFriction { mu: self.mu });
        }
        Ok((scale, scale.down(self, unit)))
    }

    /// [`at_order_one`](Self::at_order_one) for the usual problems: valid, with the
    /// largest entries of `W` and `v^A` in `[2^-340, 2^341)` and `μ < 2^500`. Then every
    /// power of two by which an answer scales (`c/s`, `c`, `c²/s`, `s`, `s²`) is a normal
    /// double, and the powers of two come as [`Factors`]; and g, h, p, q, below `2^502` at
    /// order one (the entries of `W` are below 2), stay below `2^842` at the caller's
    /// scale. `None` for the others, invalid data included
    /// ([`at_order_one`](Self::at_order_one) tells which error). Kept for the tests, as
    /// the oracle of [`at_moderate_scale_in_paper_frame`](Self::at_moderate_scale_in_paper_frame),
    /// which [`solve`](super::solve) takes.
    #[doc(hidden)]
    pub fn at_moderate_scale(&self) -> Option<(Factors, ImpactProblem)> {
        // The exponents of the largest magnitudes, from their bits (0 and subnormals,
        // infinities and NaN fall outside ±340).
        let (w, v) = (&self.w, self.v_a);
        let w_max = magnitude(w.nn).max(magnitude(w.nt)).max(magnitude(w.tt));
        let v_max = magnitude(v.n).max(magnitude(v.t));
        let scale = Scale::of_moderate_magnitudes(w_max, v_max)?;
        let unit = scale.down_moderate(self);
        let w = &unit.w;
        let valid = (w.nn > 0.0)
            & (w.tt >= 0.0)
            & (w.det() >= -SINGULAR_RELATIVE_DET * w.nn * w.tt)
            & (self.v_a.n < 0.0)
            & (0.0..=1.0).contains(&self.e)
            & (self.mu >= 0.0)
            & (self.mu < MODERATE_FRICTION);
        valid.then(|| (scale.factors(), unit))
    }

    /// [`at_moderate_scale`](Self::at_moderate_scale) followed by the paper's frame
    /// (`t` oriented so that `v_t^A ≥ 0`, [P, Eq. (10)]), and whether `t` was mirrored:
    /// the same numbers as `paper_frame` of the problem at order one, bit for bit, but the
    /// sign of the mirror is folded into the powers of two (`m_nt · (−2^-a)`,
    /// `v_t^A · (−2^-b)`: a product by `−2^k` is exact and is minus the product by `2^k`),
    /// decided on the caller's `v_t^A` instead of the scaled one. The mirror then waits
    /// for neither the scaled `v_t^A` nor a product by `±1`: it was on the dependency
    /// chain of every coefficient (issue 16). The two decisions differ only where
    /// `v_t^A · 2^-b` underflows to −0 (then the scaled number is not mirrored): those
    /// problems are declined (`None`), and the general path solves them as before.
    #[inline(always)]
    #[doc(hidden)]
    pub fn at_moderate_scale_in_paper_frame(&self) -> Option<(Factors, ImpactProblem, bool)> {
        let (w, v) = (&self.w, self.v_a);
        let w_max = magnitude(w.nn).max(magnitude(w.nt)).max(magnitude(w.tt));
        let v_max = magnitude(v.n).max(magnitude(v.t));
        let scale = Scale::of_moderate_magnitudes(w_max, v_max)?;
        // v_t^A < 0: its sign bit set and its magnitude not 0 (NaN is not moderate).
        let mirrored = v.t.to_bits() > (1 << 63);
        let unit = scale.down_moderate_mirrored(self, mirrored);
        let u = &unit.w;
        let valid = (u.nn > 0.0)
            & (u.tt >= 0.0)
            & (u.det() >= -SINGULAR_RELATIVE_DET * u.nn * u.tt)
            & (self.v_a.n < 0.0)
            & (0.0..=1.0).contains(&self.e)
            & (self.mu >= 0.0)
            & (self.mu < MODERATE_FRICTION)
            & ((unit.v_a.t != 0.0) | (v.t == 0.0));
        valid.then(|| (scale.factors(), unit, mirrored))
    }

    /// The error of a `W` that is not positive semidefinite (the slow path of `validate`).
    #[cold]
    fn not_positive_definite(&self) -> ImpactError {
        ImpactError::NotPositiveDefinite {
            nn: self.w.nn,
            nt: self.w.nt,
            tt: self.w.tt,
            det: self.w.det(),
        }
    }

    /// The error naming the first non-finite input (the slow path of `validate`).
    #[cold]
    fn first_non_finite(&self) -> ImpactError {
        let named = [
            ("m_nn", self.w.nn),
            ("m_nt", self.w.nt),
            ("m_tt", self.w.tt),
            ("v_n^A", self.v_a.n),
            ("v_t^A", self.v_a.t),
            ("e", self.e),
            ("μ", self.mu),
        ];
        let (what, value) = named
            .into_iter()
            .find(|(_, v)| !v.is_finite())
            .unwrap_or(("?", Real::NAN));
        ImpactError::NonFinite { what, value }
    }
}
