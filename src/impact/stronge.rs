//! Stronge's energetic hypothesis on Routh's path.

use super::coefficients::Coefficients;
use super::path::{RouthPath, rising_root};
use super::problem::ImpactProblem;
use super::{Failure, LawSolution};
use crate::math::Real;

/// Solves the problem (paper's frame, `v_t^A ≥ 0`) under Stronge's hypothesis: the work
/// of the normal impulse during restitution is `e²` times minus its work during
/// compression, on Routh's path [S].
///
/// Derivation (Part B of [P] is not available to us): compression ends at `I_c` where
/// `v_n = 0` (as for Poisson); its normal work is `W_c = ∫₀^{I_c} v_n dĨ_n < 0`. The
/// collision ends at the `I_n > I_c` with `∫_{I_c}^{I_n} v_n dĨ_n = −e² W_c`. On each
/// phase `v_n = v_n0 + s x` is linear in the normal impulse `x` since the phase began
/// (Eqs. (22)–(23) along the phase's direction), so the works are quadratics in `x`,
/// solved in [`end_of_collision`].
#[inline(always)]
pub fn solve(pb: &ImpactProblem, c: &Coefficients) -> LawSolution {
    let path = RouthPath::with_coefficients(&pb.w, pb.mu, pb.v_a, c);
    // The closed forms square quantities that the march does not (`x_c²`, `(e I_c)²`):
    // with entries of W far apart they over- or underflow where the march still solves
    // (a fuzz over 1e-320…1e308 lost 5 % of the march's answers): then the march.
    let i_n = match end_of_collision(&path, pb.e, -pb.v_a.n) {
        Ok(i_n) if i_n.is_finite() && i_n > 0.0 => Ok(i_n),
        _ => by_the_march(&path, pb.e),
    };
    let i_n = match i_n {
        Ok(i_n) => i_n,
        Err(why) => {
            return LawSolution::failed(if c.det == 0.0 {
                Failure::Jam
            } else {
                Failure::Incoherent(why)
            });
        }
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

/// The normal impulse `I_n` at which Stronge's collision ends on the path, by the march
/// of the general method: the point of compression ([`RouthPath::reach_normal_velocity`]),
/// then the restitution work phase by phase ([`RouthPath::reach_normal_work`]). Why there
/// is none otherwise. With a singular W, sticking after G freezes `v_n`
/// (`dv_n/dI_n = Δ/m_tt = 0`): if the path sticks at `v_n = 0` the restitution does no
/// work, and no finite impulse ends the collision (the jam of Newton's law).
#[cold]
#[doc(hidden)]
pub fn by_the_march(path: &RouthPath, e: Real) -> Result<Real, &'static str> {
    let i_c = path
        .reach_normal_velocity(0.0)
        .ok_or("compression never ends")?;
    let compression = path.at(i_c);
    path.reach_normal_work(&compression, -e * e * compression.work_n)
        .ok_or("restitution work never reached")
}

/// The normal impulse `I_n` at which Stronge's collision ends on the path, with
/// `V = |v_n^A|`; why there is none otherwise (then, for a regular `W`, a bug).
///
/// From Eqs. (22)–(23) on Routh's path, with `h` the slope `dv_n/dĨ_n` of the first phase
/// (forward sliding, until `Ĩ_n(G)`) and `s` that of the phase after G:
/// - compression ends in the first phase when `h > 0` and `I_c = V/h ≤ Ĩ_n(G)`; there
///   `v_n = h (Ĩ_n − I_c)`, so `W_c = −½ h I_c²`, and the restitution work from `I_c`,
///   `½ h x²` while the phase lasts, reaches `−e² W_c` at `x = e I_c`: the collision ends
///   at `I_n = (1 + e) I_c` (Poisson's impulse) if that is before G;
/// - else it goes on after G with `v_n(G) = v_n^A + h Ĩ_n(G)` (the path's, `= h d` with
///   `d = Ĩ_n(G) − I_c`), the work left being `R = ½ e² h I_c² − ½ h d²
///   = ½ h (e I_c − d)(e I_c + d)`, and `v_n(G) x + ½ s x² = R` gives
///   `x = 2R / (v_n(G) + √(v_n(G)² + 2 s R))` (the root without cancellation);
/// - compression ends after G (`h ≤ 0`, or `V/h > Ĩ_n(G)`) at `I_c = Ĩ_n(G) + x_c`,
///   `x_c = −v_n(G)/s`, with `W_c = W_G − ½ s x_c²` (`W_G ≤ 0` the work until G), and the
///   restitution work `½ s x²` reaches `−e² W_c` at `x = e √(x_c² − 2 W_G / s)`.
///
/// DEPARTURE from the general march (kept as [`by_the_march`], which the tests compare
/// against and [`solve`] falls back on): the same roots in closed form,
/// with `v_n = 0` at `I_c` taken exactly instead of its rounding residue; fewer roundings,
/// and one square root and one division fewer on the way. The last bits of `I_n` differ
/// from the march's (see the tests, against a double-double evaluation of the march).
#[inline(always)]
#[doc(hidden)]
pub fn end_of_collision(path: &RouthPath, e: Real, big_v: Real) -> Result<Real, &'static str> {
    let (h, s, i_g) = (path.slide_dv_n(), path.after_dv_n(), path.i_g());
    // Compression in the first phase: the same quotient as `reach_normal_velocity(0)`.
    let i_c = big_v / h;
    if h > 0.0 && i_c <= i_g {
        let i_n = i_c + e * i_c;
        if i_n <= i_g {
            return Ok(i_n);
        }
        let d = i_g - i_c;
        let a = e * i_c;
        let left = 0.5 * h * ((a - d) * (a + d));
        let x = rising_root(path.at_g().v.n, s, left).ok_or("restitution work never reached")?;
        return Ok(i_g + x);
    }
    // Compression after G.
    if !i_g.is_finite() || s <= 0.0 {
        return Err("compression never ends");
    }
    let at_g = path.at_g();
    // −v_n(G) for 0 − v_n(G): the same I_n (see `RouthPath::end_of_compression`).
    let x_c = -at_g.v.n / s;
    if x_c >= 0.0 {
        let x = e * (x_c * x_c - 2.0 * at_g.work_n / s).sqrt();
        Ok((i_g + x_c) + x)
    } else {
        // x_c < 0, or NaN (0/0).
        Err("compression never ends")
    }
}
