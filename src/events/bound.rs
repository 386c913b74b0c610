//! A step bound from the closing speed: the earliest time a gap can close.

use crate::math::Real;

/// The earliest time `τ ≥ 0` at which a function with value `g`, rate `ġ = g_dot` and
/// `|g̈| ≤ g_ddot_max` can reach zero, from the lower bound
///
/// ```text
///   g(t + τ) ≥ g + ġ τ − ½ a τ²,   a = g_ddot_max
///   τ* = 2 g / (√(ġ² + 2 a g) − ġ)        (the positive root, in a cancellation-free form)
/// ```
///
/// `∞` when it can never close (`a = 0`, `ġ ≥ 0`), `0` when `g ≤ 0`. A loop that caps the
/// step with [`Stepper::set_h_max`](crate::integrate::Stepper::set_h_max) at (a fraction
/// of) the smallest `τ*` over its armed contacts cannot step over a contact, however thin
/// or fast, as long as `a` bounds `|g̈|` over the step; it is the guaranteed complement of
/// the locator's sampling. With `a = 0` it is only a first-order estimate.
pub fn closing_time_bound(g: Real, g_dot: Real, g_ddot_max: Real) -> Real {
    if g <= 0.0 {
        return 0.0;
    }
    let a = g_ddot_max.abs();
    let disc = (g_dot * g_dot + 2.0 * a * g).sqrt();
    let den = disc - g_dot;
    if den > 0.0 {
        2.0 * g / den
    } else {
        Real::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
