//! The unit tests of `model::spatial` (`src/model/spatial.rs`).

// The source module's own imports.
use ricochet::math::{Vec2, perp};

use ricochet::model::spatial::*;

#[test]
fn kinetic_energy_is_that_of_the_centre_of_mass_plus_spin() {
    // ½ m |v_c|² + ½ I_c ω²  [P, Eq. (70)] for one rigid body.
    let (m, c, i_c) = (2.5, Vec2::new(0.7, -1.3), 0.4);
    let inertia = Inertia::from_body(m, c, i_c);
    let v = Twist::new(1.7, Vec2::new(-0.2, 0.9));
    let vc = v.velocity_at(c);
    let expected = 0.5 * m * vc.length_squared() + 0.5 * i_c * v.w * v.w;
    assert!((inertia.kinetic_energy(&v) - expected).abs() < 1e-13);
}

#[test]
fn projection_and_its_transpose_are_adjoint() {
    // f · P(a) s = P(a)ᵀ f · s for every twist s and wrench f.
    let a = Vec2::new(0.3, -2.0);
    let s = Twist::new(-0.8, Vec2::new(1.1, 0.4));
    let f = Wrench::new(2.2, Vec2::new(-0.5, 3.0));
    let lhs = s.projected_at(a).dot(&f);
    let rhs = s.dot(&f.projected_at(a));
    assert!((lhs - rhs).abs() < 1e-14);
    // and Pᵀ I P is the point mass at a: s·(Pᵀ I P s) = m |v(a)|².
    let inertia = Inertia::from_body(1.5, Vec2::new(0.2, 0.1), 0.3);
    let ps = s.projected_at(a);
    let quad = ps.dot(&inertia.mul_twist(&ps));
    let point = inertia.projected_at(a);
    assert!((quad - s.dot(&point.mul_twist(&s))).abs() < 1e-13);
}

#[test]
fn cross_products_match_the_time_derivative_of_a_rotation_twist() {
    // A unit rotation twist about the point a that moves with velocity ȧ changes at the
    // rate (0, −perp(ȧ)); if a is fixed in a body moving with V, ȧ = V.velocity_at(a)
    // and the rate is V ×ₘ S.
    let a = Vec2::new(0.4, 1.2);
    let big_v = Twist::new(0.9, Vec2::new(-0.3, 0.5));
    let s = Twist::rotation_about(a);
    let rate = big_v.cross_motion(&s);
    let expected = Twist::new(0.0, -perp(big_v.velocity_at(a)));
    assert!((rate.v - expected.v).length() < 1e-14 && rate.w == 0.0);
}
