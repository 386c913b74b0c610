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
