//! Newton's hypothesis without the bisection of the collision time: the theory of Kane
//! and Levinson [P, Appendix C].

use super::coefficients::Coefficients;
use super::outcome::CollisionType;
use super::path::{PathPoint, Phases};
use super::problem::{ContactVelocity, ImpactProblem, Impulse};
use super::{Failure, LawSolution};

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
    let (e, mu, w) = (pb.e, pb.mu, &pb.w);
    let big_v = -pb.v_a.n;
    let vt = pb.v_a.t;
    let v_n_s = e * big_v;
    let forward_side = c.h * vt - (1.0 + e) * c.g * big_v;
    let reverse_side = c.q * vt + (1.0 + e) * c.p * big_v;
    // DEVIATION from Eq. (73), which needs Δ > 0: with a singular W, W I = ((1+e)V, −v_t^A)
    // has (generically) no solution when m_tt > 0; when m_tt = 0 it has one with I_t free
    // if v_t^A = 0, and the least is I_t = 0.
    let stick = if c.det > 0.0 {
        Candidate {
            kind: CollisionType::Sticking,
            impulse: Impulse::new(
                ((1.0 + e) * w.tt * big_v + w.nt * vt) / c.det,
                -(w.nn * vt + (1.0 + e) * w.nt * big_v) / c.det,
            ),
            v_s: ContactVelocity::new(v_n_s, 0.0),
            coherent: forward_side < 0.0 && reverse_side >= 0.0,
        }
    } else {
        Candidate {
            kind: CollisionType::Sticking,
            impulse: Impulse::new((1.0 + e) * big_v / w.nn, 0.0),
            v_s: ContactVelocity::new(v_n_s, 0.0),
            coherent: w.tt == 0.0 && vt == 0.0,
        }
    };
    let i_rev = (1.0 + e) * big_v / c.q;
    let reverse = Candidate {
        kind: CollisionType::ReverseSliding,
        impulse: Impulse::new(i_rev, mu * i_rev),
        v_s: ContactVelocity::new(v_n_s, vt + (1.0 + e) * c.p * big_v / c.q),
        coherent: c.q > 0.0 && reverse_side < 0.0,
    };
    let i_fwd = (1.0 + e) * big_v / c.h;
    let forward = Candidate {
        kind: CollisionType::ForwardSliding,
        impulse: Impulse::new(i_fwd, -mu * i_fwd),
        v_s: ContactVelocity::new(v_n_s, vt - (1.0 + e) * c.g * big_v / c.h),
        coherent: c.h > 0.0 && forward_side >= 0.0,
    };
    [stick, reverse, forward]
}

/// Solves the problem (paper's frame) by the theory of [P, Appendix C]: the coherent one
/// of the three single-phase candidates. Its phase is the straight segment from the
/// origin of the impulse plane to `(I_n, I_t)`, along which the works are
/// `½ I_n (v_n^A + v_n^S)` and `½ I_t (v_t^A + v_t^S)`, the two terms of Eq. (29).
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients) -> LawSolution {
    let Some(chosen) = candidates(pb, c).into_iter().find(|k| k.coherent) else {
        return LawSolution::failed(if c.det == 0.0 {
            Failure::Jam
        } else {
            Failure::Incoherent("no coherent candidate (Appendix C says there always is one)")
        });
    };
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
