//! Stronge's energetic hypothesis on Routh's path.

use super::coefficients::Coefficients;
use super::path::RouthPath;
use super::problem::ImpactProblem;
use super::{Failure, LawSolution};

/// Solves the problem (paper's frame, `v_t^A ≥ 0`) under Stronge's hypothesis: the work
/// of the normal impulse during restitution is `e²` times minus its work during
/// compression, on Routh's path [S].
///
/// Derivation (Part B of [P] is not available to us): compression ends at `I_c` where
/// `v_n = 0` (as for Poisson); its normal work is `W_c = ∫₀^{I_c} v_n dĨ_n < 0`. The
/// collision ends at the `I_n > I_c` with `∫_{I_c}^{I_n} v_n dĨ_n = −e² W_c`. On each
/// phase `v_n = v_n0 + s x` is linear in the normal impulse `x` since the phase began, so
/// the restitution work is `v_n0 x + ½ s x²`: a quadratic, solved phase by phase.
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients) -> LawSolution {
    let path = RouthPath::with_coefficients(&pb.w, pb.mu, pb.v_a, c);
    let Some(i_c) = path.reach_normal_velocity(0.0) else {
        return LawSolution::failed(if c.det == 0.0 {
            Failure::Jam
        } else {
            Failure::Incoherent("compression never ends")
        });
    };
    let compression = path.at(i_c);
    let restitution_work = -pb.e * pb.e * compression.work_n;
    // With a singular W, sticking after G freezes v_n (dv_n/dI_n = Δ/m_tt = 0): if the
    // path sticks at v_n = 0 the restitution does no work, and no finite impulse ends the
    // collision (the jam of Newton's law and of Poisson's compression).
    let Some(i_n) = path.reach_normal_work(&compression, restitution_work) else {
        return LawSolution::failed(if c.det == 0.0 {
            Failure::Jam
        } else {
            Failure::Incoherent("restitution work never reached")
        });
    };
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
