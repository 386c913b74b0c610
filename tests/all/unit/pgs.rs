//! The unit tests of `pgs` (`src/pgs.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::pgs::*;

#[test]
fn one_contact_modes() {
    let a = Block {
        nn: 1.0,
        nt: 0.0,
        tt: 1.0,
    };
    // Pulled away: open.
    assert_eq!(solve_one(&a, 1.0, 3.0, 0.5), (0.0, 0.0));
    // Pressed, no push: sticks.
    assert_eq!(solve_one(&a, -2.0, 0.0, 0.5), (2.0, 0.0));
    // Pressed and pushed beyond the cone: slides along the push, x_t = −μ x_n.
    let (x_n, x_t) = solve_one(&a, -1.0, 3.0, 0.5);
    assert!((x_n - 1.0).abs() < 1e-15 && (x_t + 0.5).abs() < 1e-15);
    // No tangential mobility (a ball on a vertical slide): w_t = 0 needs no impulse.
    let slide = Block {
        nn: 10.0,
        nt: 0.0,
        tt: 0.0,
    };
    assert_eq!(solve_one(&slide, -5.0, 0.0, 0.0), (0.5, 0.0));
}

#[test]
fn frictionless_pgs_solves_a_two_contact_lcp() {
    // A = [[2, ·, 1, ·], …] frictionless: x_n solves the 2×2 LCP [[2, 1], [1, 2]] x + b.
    let mut a = [0.0; 16];
    let set = |a: &mut [Real; 16], r: usize, c: usize, v: Real| a[c * 4 + r] = v;
    set(&mut a, 0, 0, 2.0);
    set(&mut a, 2, 2, 2.0);
    set(&mut a, 0, 2, 1.0);
    set(&mut a, 2, 0, 1.0);
    set(&mut a, 1, 1, 1.0);
    set(&mut a, 3, 3, 1.0);
    let b = [-3.0, 0.0, -3.0, 0.0];
    let mut x = [0.0; 4];
    let status = solve(&a, &b, &[0.0, 0.0], &mut x, &PgsSettings::default());
    assert!(status.converged(), "{status:?}");
    assert!(
        (x[0] - 1.0).abs() < 1e-10 && (x[2] - 1.0).abs() < 1e-10,
        "{x:?}"
    );
}
