//! The unit tests of `impact::stronge` (`src/impact/stronge.rs`).

// The source module's own imports.
use ricochet::impact::coefficients::Coefficients;
use ricochet::impact::path::RouthPath;
use ricochet::impact::problem::ImpactProblem;
use ricochet::math::Real;

use crate::unit::impact_double_double::{Dd, ulps};
use ricochet::impact::stronge::*;
use ricochet::impact::{ContactVelocity, ImpactMatrix};

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
    let out = ricochet::impact::solve(ricochet::impact::Law::Stronge, &pb).expect("solved");
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
    let out = ricochet::impact::solve(ricochet::impact::Law::Stronge, &pb).expect("solved");
    assert_eq!(out.kind, ricochet::impact::CollisionType::ForwardSliding);
    let want = -pb.e * pb.v_a.n;
    assert!(
        (out.v_s.n - want).abs() <= 4.0 * f64::EPSILON * want,
        "{:e}",
        out.v_s.n
    );
}
