//! The one-point planar impact laws with Coulomb friction of \[P\], as pure functions of
//! `(W, v^A, e, μ)`. Nothing here knows about bodies.
//!
//! ## Singular W (a departure from the paper)
//!
//! [P, Eq. (24)] asserts `Δ = m_nn m_tt − m_nt² > 0`, which holds only when the normal and
//! tangential partial velocities of the contact are independent. With minimal coordinates
//! they often are not: a pendulum has one speed, a ball on a vertical slide cannot move
//! sideways. Then `W` is positive *semi*definite, the contact velocity moves along a line,
//! and the laws are extended as follows (derived from Eqs. (22)–(23) on Routh's path;
//! tested against a march in the impulse plane):
//! - forward and reverse sliding keep their closed forms, which never divide by `Δ`;
//! - with `m_tt = m_nt = 0` the tangential impulse does nothing: without tangential
//!   approach the contact sticks with the least impulse, `I_t = 0`;
//! - with rank 1 and `m_tt > 0`, sticking (feasible when `|m_nt| ≤ μ m_tt`) freezes the
//!   normal velocity (`dv_n/dI_n = Δ/m_tt = 0`): if the path reaches it while the contact
//!   still approaches, no finite impulse meets the end condition, and the law reports
//!   [`ImpactError::Jam`] instead of dividing by zero.
//!
//! ```
//! use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};
//!
//! // The double pendulum of [P, Sect. 5], Table 2 row 1 (e = 0.5, μ = 0.2).
//! let w = ImpactMatrix::new(0.33652, -0.50710, 0.81345);
//! let pb = ImpactProblem::new(w, ContactVelocity::new(-0.26840, 0.53435), 0.5, 0.2);
//! let out = impact::solve(Law::Newton, &pb)?;
//! assert_eq!(out.kind.name(), "reverse_sliding");
//! assert_eq!(out.case.number(), 3);
//! assert!((out.v_s.t - -0.078).abs() < 5e-4);
//! # Ok::<(), impact::ImpactError>(())
//! ```

#[doc(hidden)]
pub mod coefficients;
pub mod kane_levinson;
pub mod newton;
#[doc(hidden)]
pub mod outcome;
#[doc(hidden)]
pub mod path;
mod poisson;
#[doc(hidden)]
pub mod problem;
#[doc(hidden)]
pub mod scale;
#[doc(hidden)]
pub mod stronge;

pub use coefficients::{Coefficients, SignCase};
pub use outcome::{CollisionType, Outcome, energy_change};
pub use path::{PathPoint, Phase, Phases, RouthPath};
pub use problem::{ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem, Impulse};

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::math::Real;

/// The hypothesis that ends the collision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Law {
    /// Newton's kinematic restitution `v_n^S = −e v_n^A` on Routh's path, with the
    /// bisection of the collision time [P, Sect. 3–4, Table 1].
    Newton,
    /// Newton's restitution without the bisection of the collision time: one phase, the
    /// coherent one of three candidates [P, Appendix C].
    KaneLevinson,
    /// Poisson's kinetic restitution: the collision ends at `(1 + e)` times the
    /// compression impulse, on Routh's path.
    Poisson,
    /// Stronge's energetic restitution: the restitution work of the normal impulse is
    /// `e²` times minus its compression work, on Routh's path.
    Stronge,
}

impl Law {
    /// Every law, in the order shown to users.
    pub const ALL: [Law; 4] = [Law::Newton, Law::KaneLevinson, Law::Poisson, Law::Stronge];

    /// The name used on the command line, in scene files and in logs.
    pub fn name(self) -> &'static str {
        match self {
            Law::Newton => "newton",
            Law::KaneLevinson => "kane-levinson",
            Law::Poisson => "poisson",
            Law::Stronge => "stronge",
        }
    }
}

impl fmt::Display for Law {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A law name that is not known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown impact law `{0}` (expected one of: newton, kane-levinson, poisson, stronge)")]
pub struct UnknownLaw(pub String);

impl FromStr for Law {
    type Err = UnknownLaw;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Law::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| UnknownLaw(s.to_owned()))
    }
}

/// What a law computes in the paper's frame, before the energy bookkeeping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawSolution {
    /// The type of the collision.
    pub kind: CollisionType,
    /// The impulses.
    pub impulse: Impulse,
    /// The velocity of separation.
    pub v_s: ContactVelocity,
    /// The phases along the law's path in the impulse plane.
    pub phases: Phases,
    /// Why the law found no solution.
    pub failure: Option<Failure>,
}

/// Why a law found no solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// `W` is singular and friction holds the approaching contact: [`ImpactError::Jam`].
    Jam,
    /// A condition that cannot fail for valid data failed (a bug):
    /// [`ImpactError::Incoherent`].
    Incoherent(&'static str),
}

impl LawSolution {
    /// A law's report that it found no solution.
    fn failed(why: Failure) -> Self {
        let nowhere = PathPoint::default();
        Self {
            kind: CollisionType::Sticking,
            impulse: Impulse::default(),
            v_s: ContactVelocity::default(),
            phases: Phases::one(ContactVelocity::default(), CollisionType::Sticking, nowhere),
            failure: Some(why),
        }
    }
}

fn incoherent(law: &'static str, detail: String) -> ImpactError {
    ImpactError::Incoherent { law, detail }
}

/// Solves one impact problem under the given law.
///
/// The steps of [P, Sect. 4.2]: check the data; orient `t` so that `v_t^A ≥ 0`
/// (Eq. 10; for `v_t^A < 0` the problem is mirrored, `m_nt → −m_nt`, and the results are
/// mirrored back); compute g, h, p, q, r_m, r_p, Δ, α (Eqs. 24, 34–36) and the sign case
/// (Table 1); apply the law; check the coherence of the solution (`I_n > 0`,
/// `v_n^S ≥ 0`, `|I_t| ≤ μ I_n`, the sign of `v_t^S` matching the type, and
/// Eqs. (22)–(23)); compute `ΔE` (Eq. 29) and its split into the works of the normal and
/// tangential impulses along the law's path.
///
/// The problem is solved at order one: `W` and `v^A` are divided by the powers of two of
/// their largest entries and the answer is scaled back (the laws are homogeneous; see
/// `scale.rs`), so that it holds over the whole range of finite doubles. An answer beyond
/// that range is [`ImpactError::OutOfRange`].
///
/// Usual problems (valid, with the largest entries of `W` and `v^A` within `2^±340` and
/// `μ < 2^500`) are solved in one pass, checked and scaled back without leaving the
/// registers; the others, and the rare answers that the one pass cannot accept at once,
/// take the general path. Both give the same numbers, bit for bit.
pub fn solve(law: Law, problem: &ImpactProblem) -> Result<Outcome, ImpactError> {
    // The law's kernel inlined in each arm: each arm is a straight line for the registers.
    match law {
        Law::Newton => solve_by(Law::Newton, problem, newton::solve),
        Law::KaneLevinson => solve_by(Law::KaneLevinson, problem, |pb, c, _| {
            kane_levinson::solve(pb, c)
        }),
        Law::Poisson => solve_by(Law::Poisson, problem, |pb, c, _| poisson::solve(pb, c)),
        Law::Stronge => solve_by(Law::Stronge, problem, |pb, c, _| stronge::solve(pb, c)),
    }
}

/// [`solve`] with the law's solution in the paper's frame given by `apply`.
#[inline(always)]
fn solve_by(
    law: Law,
    problem: &ImpactProblem,
    apply: impl Fn(&ImpactProblem, &Coefficients, SignCase) -> LawSolution,
) -> Result<Outcome, ImpactError> {
    // The usual case in one pass: valid data of moderate scales, the law's answer
    // clearly coherent and within the range of doubles at the caller's scales.
    if let Some((f, pb, mirrored)) = problem.at_moderate_scale_in_paper_frame() {
        let c = Coefficients::new(&pb.w, pb.mu, pb.v_a);
        let case = c.sign_case();
        let sol = apply(&pb, &c, case);
        // ΔE (Eq. 29) in the paper's frame: the same number as in the caller's frame,
        // where both factors of its tangential term change sign.
        let delta_e = energy_change(sol.impulse, pb.v_a, sol.v_s);
        if sol.failure.is_none() && is_clearly_coherent(&pb, &sol) && f.keep_in_range(&sol, delta_e)
        {
            return Ok(f.outcome(law, case, &c, &sol, delta_e, mirrored));
        }
    }
    solve_in_general(law, problem)
}

/// [`solve`] for the cases its one pass declines: invalid data, extreme scales, answers
/// beyond the range of doubles, and the errors of the law.
#[cold]
#[inline(never)]
fn solve_in_general(law: Law, problem: &ImpactProblem) -> Result<Outcome, ImpactError> {
    let (scale, unit) = problem.at_order_one()?;
    match solve_at_order_one(law, &unit) {
        Ok(out) => scale.up(out),
        // Not a bug of the law when the data do not fit in doubles at order one.
        Err(ImpactError::Incoherent { law, detail }) => match scale.out_of_scale(problem, &unit) {
            Some(why) => Err(ImpactError::IllConditioned { law, why, detail }),
            None => Err(ImpactError::Incoherent { law, detail }),
        },
        Err(e) => Err(e),
    }
}

/// The problem in the paper's frame, `t` oriented so that `v_t^A ≥ 0` [P, Eq. (10)]: for
/// `v_t^A < 0`, `m_nt → −m_nt` and `v_t^A → −v_t^A`; and whether it was mirrored.
#[inline(always)]
#[doc(hidden)]
pub fn paper_frame(problem: &ImpactProblem) -> (ImpactProblem, bool) {
    // A product by ±1 is exact: −m_nt and −v_t^A when mirrored, the same numbers otherwise.
    let mirrored = problem.v_a.t < 0.0;
    let sign = if mirrored { -1.0 } else { 1.0 };
    let pb = ImpactProblem {
        w: ImpactMatrix::new(problem.w.nn, problem.w.nt * sign, problem.w.tt),
        v_a: ContactVelocity::new(problem.v_a.n, problem.v_a.t * sign),
        ..*problem
    };
    (pb, mirrored)
}

/// The law's solution of a problem in the paper's frame.
#[inline(always)]
#[doc(hidden)]
pub fn apply(law: Law, pb: &ImpactProblem, c: &Coefficients, case: SignCase) -> LawSolution {
    match law {
        Law::Newton => newton::solve(pb, c, case),
        Law::KaneLevinson => kane_levinson::solve(pb, c),
        Law::Poisson => poisson::solve(pb, c),
        Law::Stronge => stronge::solve(pb, c),
    }
}

/// [`solve`] for a valid problem whose `W` and `v^A` have their largest entries in
/// `[1, 2)`.
#[inline(never)]
#[doc(hidden)]
pub fn solve_at_order_one(law: Law, problem: &ImpactProblem) -> Result<Outcome, ImpactError> {
    let (pb, mirrored) = paper_frame(problem);
    let c = Coefficients::new(&pb.w, pb.mu, pb.v_a);
    let case = c.sign_case();
    let mut sol = apply(law, &pb, &c, case);
    match sol.failure {
        None => {}
        Some(Failure::Jam) => return Err(ImpactError::Jam { law: law.name() }),
        Some(Failure::Incoherent(why)) => return Err(incoherent(law.name(), why.to_owned())),
    }
    check_coherence(law, &pb, &sol)?;
    if mirrored {
        sol.impulse.t = -sol.impulse.t;
        sol.v_s.t = -sol.v_s.t;
        sol.phases.mirror();
    }
    let end = *sol.phases.end();
    Ok(Outcome {
        law,
        kind: sol.kind,
        case,
        coefficients: c,
        impulse: sol.impulse,
        v_s: sol.v_s,
        delta_e: energy_change(sol.impulse, problem.v_a, sol.v_s),
        work_n: end.work_n,
        work_t: end.work_t,
        phases: sol.phases,
        mirrored,
    })
}

/// Relative tolerance of the coherence checks: a safety net against wrong branches
/// (errors of order one), far above rounding.
const COHERENCE_TOL: Real = 1e-7;

/// Checks a solution (paper's frame) against the coherence conditions of [P, Sect. 4.2]
/// and the momentum relations (22)–(23): `I_n > 0`, `v_n^S ≥ 0`, `|I_t| ≤ μ I_n`, the sign
/// of `v_t^S` matching the type, `v^S − v^A = W I`.
fn check_coherence(law: Law, pb: &ImpactProblem, sol: &LawSolution) -> Result<(), ImpactError> {
    if is_coherent(pb, sol) {
        Ok(())
    } else {
        Err(incoherence(law, pb, sol, coherence_tolerance(pb, sol)))
    }
}

/// The absolute tolerance of the coherence checks: [`COHERENCE_TOL`] times the sum of the
/// magnitudes of the terms of Eqs. (22)–(23).
#[inline(always)]
fn coherence_tolerance(pb: &ImpactProblem, sol: &LawSolution) -> Real {
    let (i, v_a, w) = (sol.impulse, pb.v_a, &pb.w);
    let scale = v_a.n.abs()
        + v_a.t.abs()
        + (w.nn * i.n).abs()
        + (w.nt * i.t).abs()
        + (w.nt * i.n).abs()
        + (w.tt * i.t).abs();
    COHERENCE_TOL * scale
}

/// Whether a solution passes the checks of [`check_coherence`].
#[inline(always)]
fn is_coherent(pb: &ImpactProblem, sol: &LawSolution) -> bool {
    is_coherent_within(pb, sol, coherence_tolerance(pb, sol))
}

/// Whether a solution passes the checks of [`check_coherence`] with the least tolerance,
/// [`COHERENCE_TOL`] `(|v_n^A| + |v_t^A|)`, which is known before the solution, all but
/// the finiteness of `I_n` (which [`Factors::keep_in_range`](scale::Factors) implies):
/// then, with a finite `I_n`, it passes them (and [`is_coherent`] is true) without the long
/// chain of sums of the full tolerance after the solution; when it does not,
/// [`is_coherent`] decides.
///
/// The full tolerance is a sum of non-negative terms that starts with
/// `|v_n^A| + |v_t^A|`, rounded at each step, times a positive constant: rounding is
/// monotone, so it is never below the least one, unless it is NaN; and it is NaN only
/// where a product of `W` and `I` is not finite, which makes a residual of Eqs. (22)–(23)
/// infinite or NaN, so that the checks fail with any tolerance. Every check that holds for
/// a tolerance holds for a larger one.
#[inline(always)]
#[doc(hidden)]
pub fn is_clearly_coherent(pb: &ImpactProblem, sol: &LawSolution) -> bool {
    let (i, v_s, v_a, w) = (sol.impulse, sol.v_s, pb.v_a, &pb.w);
    let tol = COHERENCE_TOL * (v_a.n.abs() + v_a.t.abs());
    let wi = w.apply(i);
    // The sign of v_t^S, as bounds: |v_t^S| ≤ tol, v_t^S ≥ −tol, v_t^S ≤ tol.
    let (lo, hi) = match sol.kind {
        CollisionType::Sticking => (-tol, tol),
        CollisionType::ForwardSliding => (-tol, Real::INFINITY),
        CollisionType::ReverseSliding => (Real::NEG_INFINITY, tol),
    };
    // I_n finite is left to `Factors::keep_in_range`, which bounds |I_n|.
    (i.n > 0.0)
        & (v_s.n >= -tol)
        & ((v_s.n - v_a.n - wi.n).abs() <= tol)
        & ((v_s.t - v_a.t - wi.t).abs() <= tol)
        & (i.t.abs() <= pb.mu * i.n * (1.0 + COHERENCE_TOL))
        & (lo <= v_s.t)
        & (v_s.t <= hi)
}

/// The checks of [`check_coherence`] with the absolute tolerance `tol`.
#[inline(always)]
fn is_coherent_within(pb: &ImpactProblem, sol: &LawSolution, tol: Real) -> bool {
    let (i, v_s, v_a, w) = (sol.impulse, sol.v_s, pb.v_a, &pb.w);
    let wi = w.apply(i);
    let sign_ok = match sol.kind {
        CollisionType::Sticking => v_s.t.abs() <= tol,
        CollisionType::ForwardSliding => v_s.t >= -tol,
        CollisionType::ReverseSliding => v_s.t <= tol,
    };
    (i.n > 0.0)
        & i.n.is_finite()
        & (v_s.n >= -tol)
        & ((v_s.n - v_a.n - wi.n).abs() <= tol)
        & ((v_s.t - v_a.t - wi.t).abs() <= tol)
        & (i.t.abs() <= pb.mu * i.n * (1.0 + COHERENCE_TOL))
        & sign_ok
}

/// The error naming the first coherence condition that failed (the slow path).
#[cold]
#[inline(never)]
fn incoherence(law: Law, pb: &ImpactProblem, sol: &LawSolution, tol: Real) -> ImpactError {
    let (i, v_s, v_a) = (sol.impulse, sol.v_s, pb.v_a);
    let wi = pb.w.apply(i);
    let (r_n, r_t) = (v_s.n - v_a.n - wi.n, v_s.t - v_a.t - wi.t);
    let detail = if !(i.n > 0.0 && i.n.is_finite()) {
        format!("I_n = {} is not positive and finite", i.n)
    } else if v_s.n < -tol {
        format!("v_n^S = {} is negative", v_s.n)
    } else if r_n.abs() > tol || r_t.abs() > tol {
        format!("Eqs. (22)–(23) do not hold: residuals {r_n:e}, {r_t:e}")
    } else if i.t.abs() > pb.mu * i.n * (1.0 + COHERENCE_TOL) {
        format!("|I_t| = {} exceeds μ I_n = {}", i.t.abs(), pb.mu * i.n)
    } else {
        format!(
            "v_t^S = {} does not match the type {}",
            v_s.t,
            sol.kind.name()
        )
    };
    incoherent(law.name(), detail)
}
