//! Newton's hypothesis without the bisection of the collision time: the theory of Kane
//! and Levinson [P, Appendix C].

use super::coefficients::Coefficients;
use super::outcome::CollisionType;
use super::path::{PathPoint, Phases};
use super::problem::{ContactVelocity, ImpactProblem, Impulse};
use super::{Failure, LawSolution};
use crate::math::Real;

/// One single-phase candidate and whether it is coherent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// Its type.
    pub kind: CollisionType,
    /// Its impulses.
    pub impulse: Impulse,
    /// Its velocity of separation.
    pub v_s: ContactVelocity,
    /// Whether its coherence inequality holds.
    pub coherent: bool,
}

/// The three single-phase candidates of [P, Appendix C] (paper's frame, `v_t^A ≥ 0`),
/// each with its coherence condition. With `V = |v_n^A|`, `v_n^S = e V`:
/// - sticking, Eq. (73) (= Eq. (47) corrected, `paper/ERRATA.md` items 1–2):
///   `I_n = [(1+e) m_tt V + m_nt v_t^A]/Δ`, `I_t = −[m_nn v_t^A + (1+e) m_nt V]/Δ`,
///   coherent iff `|I_t| ≤ μ I_n`, i.e. Eq. (74):
///   `(h/Δ)[α − (1+e) r_m] < 0` and `(q/Δ)[α + (1+e) r_p] ≥ 0`, written
///   `h v_t^A − (1+e) g V < 0` and `q v_t^A + (1+e) p V ≥ 0`;
/// - reverse sliding, Eqs. (75)–(76): `I_n = (1+e) V / q`, `I_t = μ I_n`,
///   `v_t^S = [α + (1+e) r_p] V`, coherent iff `q > 0` and `v_t^S < 0` (Eq. 77);
/// - forward sliding, Eqs. (78)–(79): `I_n = (1+e) V / h`, `I_t = −μ I_n`,
///   `v_t^S = [α − (1+e) r_m] V`, coherent iff `h > 0` and `v_t^S ≥ 0` (Eq. 80).
///
/// The boundaries are closed on the side of forward sliding (`v_t^S = 0`) and of
/// sticking (against reverse sliding), where the candidates coincide.
#[inline(always)]
pub fn candidates(pb: &ImpactProblem, c: &Coefficients) -> [Candidate; 3] {
    let sides = Sides::of(pb, c);
    [
        candidate(CollisionType::Sticking, pb, c, &sides),
        candidate(CollisionType::ReverseSliding, pb, c, &sides),
        candidate(CollisionType::ForwardSliding, pb, c, &sides),
    ]
}

/// The two products whose signs place `α` against the boundaries of [P, Appendix C]:
/// `h v_t^A − (1+e) g V` (Eqs. 74, 80) and `q v_t^A + (1+e) p V` (Eqs. 74, 77).
struct Sides {
    forward: Real,
    reverse: Real,
}

impl Sides {
    #[inline(always)]
    fn of(pb: &ImpactProblem, c: &Coefficients) -> Self {
        let (e, big_v, vt) = (pb.e, -pb.v_a.n, pb.v_a.t);
        Self {
            forward: c.h * vt - (1.0 + e) * c.g * big_v,
            reverse: c.q * vt + (1.0 + e) * c.p * big_v,
        }
    }
}

/// Whether the candidate of the given type is coherent (see [`candidates`]); computes no
/// impulse.
#[inline(always)]
fn is_coherent(kind: CollisionType, pb: &ImpactProblem, c: &Coefficients, s: &Sides) -> bool {
    match kind {
        CollisionType::Sticking if c.det > 0.0 => s.forward < 0.0 && s.reverse >= 0.0,
        CollisionType::Sticking => pb.w.tt == 0.0 && pb.v_a.t == 0.0,
        CollisionType::ReverseSliding => c.q > 0.0 && s.reverse < 0.0,
        CollisionType::ForwardSliding => c.h > 0.0 && s.forward >= 0.0,
    }
}

/// The candidate of the given type (see [`candidates`]).
#[inline(always)]
fn candidate(kind: CollisionType, pb: &ImpactProblem, c: &Coefficients, s: &Sides) -> Candidate {
    let (e, mu, w) = (pb.e, pb.mu, &pb.w);
    let big_v = -pb.v_a.n;
    let vt = pb.v_a.t;
    let v_n_s = e * big_v;
    let (impulse, v_t_s) = match kind {
        CollisionType::Sticking if c.det > 0.0 => (
            Impulse::new(
                ((1.0 + e) * w.tt * big_v + w.nt * vt) / c.det,
                -(w.nn * vt + (1.0 + e) * w.nt * big_v) / c.det,
            ),
            0.0,
        ),
        // DEVIATION from Eq. (73), which needs Δ > 0: with a singular W,
        // W I = ((1+e)V, −v_t^A) has (generically) no solution when m_tt > 0; when m_tt = 0
        // it has one with I_t free if v_t^A = 0, and the least is I_t = 0.
        CollisionType::Sticking => (Impulse::new((1.0 + e) * big_v / w.nn, 0.0), 0.0),
        CollisionType::ReverseSliding => {
            let i_rev = (1.0 + e) * big_v / c.q;
            (
                Impulse::new(i_rev, mu * i_rev),
                vt + (1.0 + e) * c.p * big_v / c.q,
            )
        }
        CollisionType::ForwardSliding => {
            let i_fwd = (1.0 + e) * big_v / c.h;
            (
                Impulse::new(i_fwd, -mu * i_fwd),
                vt - (1.0 + e) * c.g * big_v / c.h,
            )
        }
    };
    Candidate {
        kind,
        impulse,
        v_s: ContactVelocity::new(v_n_s, v_t_s),
        coherent: is_coherent(kind, pb, c, s),
    }
}

/// Solves the problem (paper's frame) by the theory of [P, Appendix C]: the coherent one
/// of the three single-phase candidates (the first, in the order of [`candidates`], when
/// they coincide on a boundary). Its phase is the straight segment from the origin of the
/// impulse plane to `(I_n, I_t)`, along which the works are `½ I_n (v_n^A + v_n^S)` and
/// `½ I_t (v_t^A + v_t^S)`, the two terms of Eq. (29).
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients) -> LawSolution {
    // Only the coherent candidate is computed.
    let sides = Sides::of(pb, c);
    let Some(kind) = [
        CollisionType::Sticking,
        CollisionType::ReverseSliding,
        CollisionType::ForwardSliding,
    ]
    .into_iter()
    .find(|&kind| is_coherent(kind, pb, c, &sides)) else {
        return LawSolution::failed(if c.det == 0.0 {
            Failure::Jam
        } else {
            Failure::Incoherent("no coherent candidate (Appendix C says there always is one)")
        });
    };
    let chosen = candidate(kind, pb, c, &sides);
    let (i, v_a, v_s) = (chosen.impulse, pb.v_a, chosen.v_s);
    let end = PathPoint {
        i,
        v: v_s,
        work_n: 0.5 * i.n * (v_a.n + v_s.n),
        work_t: 0.5 * i.t * (v_a.t + v_s.t),
    };
    LawSolution {
        kind: chosen.kind,
        impulse: i,
        v_s,
        phases: Phases::one(v_a, chosen.kind, end),
        failure: None,
    }
}
