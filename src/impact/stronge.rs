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
fn by_the_march(path: &RouthPath, e: Real) -> Result<Real, &'static str> {
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
fn end_of_collision(path: &RouthPath, e: Real, big_v: Real) -> Result<Real, &'static str> {
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

#[cfg(test)]
mod tests {
    use super::super::double_double::{Dd, ulps};
    use super::super::problem::{ContactVelocity, ImpactMatrix};
    use super::*;

    /// Stronge's `I_n` by the march of the general method (compression point, then the
    /// rising root of the work phase by phase, spending a phase's work when it ends first),
    /// evaluated in double-double on the doubles that fix the path: the slopes `h` (first
    /// phase), `s` (after G), `g` (the slip's), `V`, `v_t^A` and `e`.
    fn march(h: Real, s: Real, g: Real, big_v: Real, vt: Real, e: Real) -> Option<Dd> {
        let (h, s, big_v, e) = (Dd::from(h), Dd::from(s), Dd::from(big_v), Dd::from(e));
        let zero = Dd::from(0.0);
        let half = Dd::from(0.5);
        let i_g = if vt == 0.0 {
            (g >= 0.0).then_some(zero)
        } else {
            (g > 0.0).then(|| Dd::from(vt) / Dd::from(g))
        };
        let first = h.hi > 0.0 && i_g.is_none_or(|i_g| big_v / h <= i_g);
        // The point of compression: its impulse, v_n, work, slope and the room to G.
        let (i_c, v0, work, slope, room) = if first {
            let i_c = big_v / h;
            (
                i_c,
                -big_v + h * i_c,
                i_c * (-big_v + half * h * i_c),
                h,
                i_g,
            )
        } else {
            let i_g = i_g?;
            let v_g = -big_v + h * i_g;
            let x = -v_g / s;
            let w_g = i_g * (-big_v + half * h * i_g);
            (
                i_g + x,
                v_g + s * x,
                w_g + x * (v_g + half * s * x),
                s,
                None,
            )
        };
        let root = |v0: Dd, s: Dd, r: Dd| {
            let two = Dd::from(2.0);
            two * r / (v0 + (v0 * v0 + two * s * r).sqrt())
        };
        let r = -(e * e * work);
        let x = root(v0, slope, r);
        match room {
            Some(i_g) if i_c + x > i_g => {
                let d = i_g - i_c;
                let r = r - d * (v0 + half * slope * d);
                Some(i_g + root(-big_v + h * i_g, s, r))
            }
            _ => Some(i_c + x),
        }
    }

    /// A reproducible stream of numbers in `[0, 1)` (xorshift64*).
    fn uniform(state: &mut u64) -> Real {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as Real / (1u64 << 53) as Real
    }

    /// The closed forms of `end_of_collision` against the march in double-double, and the
    /// march in doubles (the former code, [`by_the_march`]) against the same, on 200,000 problems at order one covering
    /// the three ways (compression and restitution before G; restitution across G;
    /// compression after G): on every problem the closed forms are at most 2 ulps farther
    /// from the reference than the march in doubles, and on average within 0.05 ulp of it.
    /// (Both are far from it, up to ~30 ulps, where the collision ends or compression ends
    /// just after G: there `I_n` is sensitive to the rounding of `Ĩ_n(G)`, which both use.)
    #[test]
    fn closed_forms_are_the_march_within_ulps() {
        let mut state = 0x9e37_79b9_7f4a_7c15;
        // Per way: the number of problems, the worst and the summed distances in ulps of
        // the closed forms and of the march in doubles.
        let (mut count, mut worst, mut sum) = ([0usize; 3], [[0.0 as Real; 2]; 3], [[0.0; 2]; 3]);
        let mut excess = [Real::NEG_INFINITY; 3];
        for k in 0..200_000 {
            let mut u = || uniform(&mut state);
            let (nn, tt) = (0.05 + 1.9 * u(), 0.05 + 1.9 * u());
            let nt = (2.0 * u() - 1.0) * 0.999 * (nn * tt).sqrt();
            let w = ImpactMatrix::new(nn, nt, tt);
            let vt = if k % 50 == 0 { 0.0 } else { 1.9 * u() };
            let v_a = ContactVelocity::new(-(0.05 + 1.9 * u()), vt);
            let (e, mu) = (if k % 40 == 1 { 1.0 } else { u() }, 2.0 * u());
            let c = Coefficients::new(&w, mu, v_a);
            let path = RouthPath::with_coefficients(&w, mu, v_a, &c);
            let (h, s, big_v) = (path.slide_dv_n(), path.after_dv_n(), -v_a.n);
            let Some(reference) = march(h, s, c.g, big_v, v_a.t, e) else {
                assert!(end_of_collision(&path, e, big_v).is_err());
                continue;
            };
            let new = end_of_collision(&path, e, big_v).expect("the march ends");
            let old = by_the_march(&path, e).expect("the march ends");
            let way = if h > 0.0 && big_v / h <= path.i_g() {
                usize::from(big_v / h * (1.0 + e) > path.i_g())
            } else {
                2
            };
            count[way] += 1;
            excess[way] = excess[way].max(ulps(new, reference) - ulps(old, reference));
            for (j, x) in [new, old].into_iter().enumerate() {
                let d = ulps(x, reference);
                worst[way][j] = worst[way][j].max(d);
                sum[way][j] += d;
            }
        }
        println!(
            "problems per way {count:?}; worst ulps (closed forms, march) {worst:?}; excess {excess:?}"
        );
        for way in 0..3 {
            let n = count[way] as Real;
            let mean = [sum[way][0] / n, sum[way][1] / n];
            println!("way {way}: mean ulps (closed forms, march) {mean:?}");
            assert!(count[way] > 10_000, "{count:?}");
            assert!(
                excess[way] <= 2.0,
                "way {way}: {} ulps farther",
                excess[way]
            );
            assert!(mean[0] <= mean[1] + 0.05, "way {way}: {mean:?}");
        }
    }

    /// A problem whose closed forms overflow (`W` with entries 2^330 apart: a fuzz line):
    /// the march takes over and its answer is the law's.
    #[test]
    fn the_march_takes_over_where_the_closed_forms_overflow() {
        let pb = ImpactProblem::new(
            ImpactMatrix::new(1e-200, 2.0431825828376793e-102, 1.0102392521768253),
            ContactVelocity::new(-1.5413498077500208e-62, -3e-308),
            0.5,
            1.0,
        );
        let out = crate::impact::solve(crate::impact::Law::Stronge, &pb).expect("solved");
        // The same problem at order one and in the paper's frame, as `solve` takes it.
        let (w, v) = (pb.w, pb.v_a);
        let k = 2f64.powi(-(v.n.abs().log2().floor() as i32));
        let unit = ImpactProblem::new(w, ContactVelocity::new(v.n * k, -v.t * k), 0.5, 1.0);
        let c = Coefficients::new(&unit.w, unit.mu, unit.v_a);
        let path = RouthPath::with_coefficients(&unit.w, unit.mu, unit.v_a, &c);
        let closed = end_of_collision(&path, unit.e, -unit.v_a.n);
        assert!(
            !closed.is_ok_and(|i| i.is_finite() && i > 0.0),
            "{closed:?}"
        );
        let marched = by_the_march(&path, unit.e).expect("the march solves it");
        assert_eq!(out.impulse.n, marched / k);
        assert!(out.impulse.n > 0.0 && out.impulse.n.is_finite());
    }

    /// Where the slip never stops, Stronge's hypothesis is Newton's: `v_n^S = −e v_n^A`
    /// [S]. With `W`'s entries 2^1000 apart (a fuzz line) the march's compression work
    /// `½ h I_c²` underflows and it loses the restitution (`v_n^S = 0` at `e = 1`); the
    /// closed form keeps it.
    #[test]
    fn restitution_is_kept_at_extreme_scales() {
        let pb = ImpactProblem::new(
            ImpactMatrix::new(
                3.417675451969397e122,
                1.5486250870771582e-158,
                8.227060739928631e-201,
            ),
            ContactVelocity::new(-5.493176800851235e-66, -2.1559190073971355e116),
            1.0,
            0.3,
        );
        let out = crate::impact::solve(crate::impact::Law::Stronge, &pb).expect("solved");
        assert_eq!(out.kind, crate::impact::CollisionType::ForwardSliding);
        let want = -pb.e * pb.v_a.n;
        assert!(
            (out.v_s.n - want).abs() <= 4.0 * f64::EPSILON * want,
            "{:e}",
            out.v_s.n
        );
    }
}
