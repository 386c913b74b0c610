//! The unit tests of `integrate::control` (`src/integrate/control.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::integrate::control::*;

#[test]
fn clip_lands_on_the_stop_time() {
    assert_eq!(clip_step(0.1, 1.0, 0.05), (0.05, true));
    assert_eq!(clip_step(0.1, 1.0, 0.3), (0.1, false));
    // A sliver of 0.5 % is absorbed.
    assert_eq!(clip_step(0.1, 1.0, 0.1005), (0.1005, true));
    // ... unless that would exceed h_max: two halves instead.
    assert_eq!(clip_step(0.1, 0.1, 0.1005), (0.05025, false));
    // h_max caps the trial step.
    assert_eq!(clip_step(0.5, 0.2, 1.0), (0.2, false));
}

#[test]
fn controller_grows_at_most_fac_max_and_shrinks_after_rejection() {
    let mut c = PiController::new((0.2, 0.75), 0.9, 0.04, 0.2, 10.0);
    let v = c.judge(1.0, 0.0);
    assert!(v.accept);
    assert_eq!(v.h_new, 10.0);
    let v = c.judge(1.0, 1e6);
    assert!(!v.accept);
    assert_eq!(v.h_new, 0.2);
    // After a rejection the next accepted step does not grow.
    let v = c.judge(0.2, 1e-3);
    assert!(v.accept);
    assert_eq!(v.h_new, 0.2);
    let v = c.judge(0.2, Real::NAN);
    assert!(!v.accept);
    assert!((v.h_new - 0.04).abs() < 1e-16);
}

#[test]
fn error_norm_is_a_weighted_rms() {
    let e = [1e-6, -2e-6];
    let y = [1.0, 0.0];
    // sk = (1e-6 + 1e-6·1, 1e-6) → ratios (0.5, −2) → √((0.25 + 4)/2)
    let n = error_norm(&e, &y, &y, 1e-6, 1e-6);
    assert!((n - (4.25f64 / 2.0).sqrt()).abs() < 1e-12);
}
