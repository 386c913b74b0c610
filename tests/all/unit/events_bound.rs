//! The unit tests of `events::bound` (`src/events/bound.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::events::bound::*;

#[test]
fn free_fall_and_uniform_motion() {
    // Uniform approach: g = 2, ġ = −4 → τ = 0.5.
    assert_eq!(closing_time_bound(2.0, -4.0, 0.0), 0.5);
    // Receding without acceleration: never.
    assert_eq!(closing_time_bound(2.0, 1.0, 0.0), Real::INFINITY);
    // Dropped from rest at height h under gravity g: τ = √(2h/g) exactly.
    let (h, grav) = (1.25, 9.81);
    let tau = closing_time_bound(h, 0.0, grav);
    assert!((tau - (2.0 * h / grav).sqrt()).abs() < 1e-15);
    // Thrown up at v: lands after (v + √(v² + 2 a h)) / a.
    let v = 3.0;
    let tau = closing_time_bound(h, v, grav);
    let exact = (v + (v * v + 2.0 * grav * h).sqrt()) / grav;
    assert!((tau - exact).abs() < 1e-14, "{tau} {exact}");
    assert_eq!(closing_time_bound(-1e-3, 1.0, 1.0), 0.0);
}
