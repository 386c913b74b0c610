//! The unit tests of `impact::path` (`src/impact/path.rs`).

// The source module's own imports.
use ricochet::impact::coefficients::Coefficients;
use ricochet::impact::problem::{ContactVelocity, ImpactMatrix};
use ricochet::math::Real;

use ricochet::impact::path::*;

#[test]
fn rising_root_solves_the_quadratic() {
    for &(v0, s, r) in &[
        (1.0, 2.0, 3.0),
        (0.0, 2.0, 1.0),
        (2.0, 0.0, 1.0),
        (1e-9, 4.0, 2.0),
    ] {
        let x = rising_root(v0, s, r).unwrap();
        assert!((v0 * x + 0.5 * s * x * x - r).abs() <= 1e-14 * r.max(1.0));
    }
    assert_eq!(rising_root(0.0, 0.0, 0.0), Some(0.0));
    assert_eq!(rising_root(0.0, 0.0, 1.0), None);
}

/// `end_of_compression` is `reach_normal_velocity(0)` bit for bit, on random paths of
/// every kind (singular W, zero slip, v_n(G) = ±0 by construction among them).
#[test]
fn end_of_compression_is_reach_normal_velocity_at_zero() {
    let mut u = crate::unit::uniform_numbers(0x9e37_79b9_7f4a_7c15);
    let mut at_g_zero = 0;
    for k in 0..200_000 {
        let (a, b, d) = (u() * 2.0 - 1.0, u() * 2.0 - 1.0, u());
        let d = if k % 7 == 0 { 0.0 } else { d };
        let w = ImpactMatrix::new(a * a + 1e-3, a * b, b * b + d * d);
        let mu = [0.0, 0.3, u() * 2.0][k % 3];
        let vt = if k % 11 == 0 { 0.0 } else { u() };
        // Every fifth problem: v_n^A = −h Ĩ_n(G), so that v_n(G) rounds to ±0 or near.
        let c = Coefficients::new(&w, mu, ContactVelocity::new(-1.0, vt));
        let vn = if k % 5 == 0 && c.g > 0.0 && c.h > 0.0 && vt > 0.0 {
            -(c.h * (vt / c.g))
        } else {
            -(u() + 1e-3)
        };
        if vn >= 0.0 {
            continue;
        }
        let path = RouthPath::new(&w, mu, ContactVelocity::new(vn, vt));
        at_g_zero += usize::from(path.at_g().v.n == 0.0);
        let (a, b) = (path.end_of_compression(), path.reach_normal_velocity(0.0));
        assert_eq!(
            a.map(Real::to_bits),
            b.map(Real::to_bits),
            "{w:?} {mu} {vn} {vt}"
        );
    }
    assert!(at_g_zero > 100, "{at_g_zero}");
}

#[test]
fn path_is_continuous_at_g() {
    let w = ImpactMatrix::new(0.34, -0.51, 0.81);
    let path = RouthPath::new(&w, 0.5, ContactVelocity::new(-0.27, 0.53));
    let ig = path.i_g();
    let (a, b) = (path.at(ig * (1.0 - 1e-12)), path.at(ig * (1.0 + 1e-12)));
    assert!((a.v.n - b.v.n).abs() < 1e-12);
    assert!((a.i.t - b.i.t).abs() < 1e-12);
    assert!((a.work_n - b.work_n).abs() < 1e-12);
}
