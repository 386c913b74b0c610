//! Newton's hypothesis with the bisection of the collision time [P, Sects. 3–4].

use super::coefficients::{Coefficients, SignCase};
use super::outcome::CollisionType;
use super::path::RouthPath;
use super::problem::{ContactVelocity, ImpactProblem, Impulse};
use super::{Failure, LawSolution};
use crate::math::Real;

/// The type of a collision under Newton's hypothesis on Routh's path.
///
/// Implements [P, Table 1]. With `V = |v_n^A|`, the boundary `α = (1+e) r_m` is written
/// without division as `h v_t^A = (1+e) g V` (`h > 0` in Cases 1–3):
/// - Cases 1, 2: sticking for `α < (1+e) r_m`, forward sliding for `α ≥ (1+e) r_m`;
/// - Case 3: reverse sliding for `α < (1+e) r_m`, forward sliding for `α ≥ (1+e) r_m`;
/// - Case 4: sticking; Case 5: forward sliding.
///
/// On the boundary both sides give the same impulses [P, Comment a]; it is given to
/// forward sliding (the slip stops exactly as the collision ends, `v_t^S = 0`).
#[inline(always)]
pub fn collision_type(
    c: &Coefficients,
    case: SignCase,
    e: Real,
    v_a: ContactVelocity,
) -> CollisionType {
    let big_v = -v_a.n;
    let beyond_boundary = || c.h * v_a.t >= (1.0 + e) * c.g * big_v;
    match case {
        SignCase::One | SignCase::Two if beyond_boundary() => CollisionType::ForwardSliding,
        SignCase::One | SignCase::Two => CollisionType::Sticking,
        SignCase::Three if beyond_boundary() => CollisionType::ForwardSliding,
        SignCase::Three => CollisionType::ReverseSliding,
        SignCase::Four => CollisionType::Sticking,
        SignCase::Five => CollisionType::ForwardSliding,
    }
}

/// Solves the problem (paper's frame, `v_t^A ≥ 0`) under Newton's hypothesis with the
/// bisection of the collision time: the type by Table 1, then the closed forms.
///
/// Implements [P, Eqs. (47), (49)–(50), (52)–(53)], with `V = |v_n^A|`, `v_n^S = e V`:
/// - sticking, Eq. (47) corrected (`paper/ERRATA.md` item 1):
///   `I_n = [(1+e) m_tt V + m_nt v_t^A] / Δ`, `I_t = −[m_nn v_t^A + (1+e) m_nt V] / Δ`,
///   `v_t^S = 0`;
/// - reverse sliding, Eqs. (49)–(50): `I_n = [(1+e) V + 2μ m_nt v_t^A / g] / q`,
///   `I_t = μ [(1+e) V − 2 m_nn v_t^A / g] / q`,
///   `v_t^S = −(r_p/r_m)[α − (1+e) r_m] V = p [(1+e) g V − h v_t^A] / (q g)`;
/// - forward sliding, Eqs. (52)–(53): `I_n = (1+e) V / h`, `I_t = −μ I_n`,
///   `v_t^S = [α − (1+e) r_m] V = v_t^A − (1+e) g V / h`.
///
/// All three are derived again from Eqs. (22)–(23) and the phase conditions (46), (48),
/// (51) in `tests/all/impact_laws.rs`, which checks Eqs. (22)–(23) on the result.
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients, case: SignCase) -> LawSolution {
    let (e, mu) = (pb.e, pb.mu);
    let big_v = -pb.v_a.n;
    let vt = pb.v_a.t;
    let w = &pb.w;
    // With m_tt = 0 (then m_nt = 0) the tangent is immobile: without tangential approach
    // the contact sticks with the least friction impulse, I_t = 0.
    let kind = if w.tt == 0.0 && vt == 0.0 {
        CollisionType::Sticking
    } else {
        collision_type(c, case, e, pb.v_a)
    };
    let (impulse, v_st) = match kind {
        // DEVIATION from Eq. (47), which needs Δ > 0: with a singular W the sticking phase
        // cannot raise v_n (dv_n/dI_n = Δ/m_tt = 0), so the contact jams, unless m_tt = 0
        // (I_n = (1+e) V / m_nn, I_t = 0).
        CollisionType::Sticking if c.det == 0.0 => {
            if w.tt > 0.0 {
                return LawSolution::failed(Failure::Jam);
            }
            (Impulse::new((1.0 + e) * big_v / w.nn, 0.0), 0.0)
        }
        CollisionType::Sticking => (
            Impulse::new(
                ((1.0 + e) * w.tt * big_v + w.nt * vt) / c.det,
                -(w.nn * vt + (1.0 + e) * w.nt * big_v) / c.det,
            ),
            0.0,
        ),
        CollisionType::ReverseSliding => (
            Impulse::new(
                ((1.0 + e) * big_v + 2.0 * mu * w.nt * vt / c.g) / c.q,
                mu * ((1.0 + e) * big_v - 2.0 * w.nn * vt / c.g) / c.q,
            ),
            c.p * ((1.0 + e) * c.g * big_v - c.h * vt) / (c.q * c.g),
        ),
        // DEVIATION from Eq. (52), which needs h > 0: h = 0 on the forward-sliding side
        // means g = h = 0 as well (Case 1 with g q + h p = 2μΔ, hence Δ = 0): the
        // boundary α = (1+e) r_m is 0/0, and neither forward sliding (dv_n/dI_n = h = 0)
        // nor sticking after G (dv_n/dI_n = Δ/m_tt = 0) raises v_n: the contact jams, as
        // it does on Routh's path under the other laws.
        CollisionType::ForwardSliding if c.h <= 0.0 => {
            return LawSolution::failed(Failure::Jam);
        }
        CollisionType::ForwardSliding => {
            let i_n = (1.0 + e) * big_v / c.h;
            (
                Impulse::new(i_n, -mu * i_n),
                vt - (1.0 + e) * c.g * big_v / c.h,
            )
        }
    };
    let v_s = ContactVelocity::new(e * big_v, v_st);
    let path = RouthPath::with_coefficients(w, mu, pb.v_a, c);
    LawSolution {
        kind,
        impulse,
        v_s,
        phases: path.phases_until(impulse.n).ending_at(impulse, v_s),
        failure: None,
    }
}
