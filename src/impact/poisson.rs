//! Poisson's kinetic hypothesis on Routh's path.

use super::coefficients::Coefficients;
use super::path::RouthPath;
use super::problem::ImpactProblem;
use super::{Failure, LawSolution};

/// Solves the problem (paper's frame, `v_t^A ≥ 0`) under Poisson's hypothesis: the
/// restitution impulse is `e` times the compression impulse, on Routh's path.
///
/// Derivation (Part B of [P] is not available to us; this is derived from
/// Eqs. (22)–(23) and Sect. 4.1): compression ends where `v_n = 0`, at `I_c`, found on the
/// path (phase 1: `I_c = V/h` if `h > 0` and `V/h ≤ Ĩ_n(G)`; else
/// `I_c = Ĩ_n(G) + (0 − v_n(G)) / (dv_n/dĨ_n)`), and the collision ends at
/// `I_n = (1 + e) I_c`, where the path gives `I_t`, `v^S` and the type.
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients) -> LawSolution {
    let path = RouthPath::with_coefficients(&pb.w, pb.mu, pb.v_a, c);
    let Some(i_c) = path.end_of_compression() else {
        return LawSolution::failed(if c.det == 0.0 {
            Failure::Jam
        } else {
            Failure::Incoherent("compression never ends")
        });
    };
    let i_n = (1.0 + pb.e) * i_c;
    let phases = path.phases_until(i_n);
    let end = phases.end();
    LawSolution {
        kind: path.kind_at(i_n),
        impulse: end.i,
        v_s: end.v,
        phases,
        failure: None,
    }
}
