//! The valid range of every number and name of a scene (`scenes/README.md`, "Valid
//! ranges"). A value outside its range is an error naming the file, the line and the field.
//!
//! The bounds keep a run inside what double precision resolves: contacts are closed within
//! `1e-9 L` (L the largest shape), so a coordinate beyond `1e6 L` has no digits left for
//! the gap; masses and inertias stay far from subnormal numbers, whose products and
//! inverses overflow or lose every digit (a mass of 1e-320 kg reached nalgebra's SVD as
//! NaN); the tolerances stay where the integrator can meet them; and the number of output
//! samples and fixed steps stays what a run can write and take.

use crate::math::Real;

/// `|x| ≤ 1e6` for every length (m), speed (m/s), angle (rad), angular rate (rad/s) and
/// acceleration (m/s², gravity) of a scene.
pub(super) const KINEMATIC: Real = 1e6;
/// Every body starts within `1e4 L` of the world origin, `L` the largest shape of a body.
pub(super) const REACH: Real = 1e4;
/// `|x| ≤ 1e12` for the force elements of a joint: stiffness, damping, torque, force.
pub(super) const FORCE_ELEMENT: Real = 1e12;
/// A size (m): a radius, a half extent, a chain link's length and radius.
pub(super) const SIZE: (Real, Real) = (1e-6, 1e6);
/// A mass (kg).
#[doc(hidden)]
pub const MASS: (Real, Real) = (1e-9, 1e9);
/// A moment of inertia (kg·m²): `m L²` over the ranges of the mass and of the size.
pub(super) const INERTIA: (Real, Real) = (1e-21, 1e21);
/// The coefficient of friction `μ`.
pub(super) const FRICTION: (Real, Real) = (0.0, 1e6);
/// The overlap tolerance at the start (m).
pub(super) const OVERLAP: (Real, Real) = (0.0, 1.0);
/// The end time (s).
pub(super) const T_END: (Real, Real) = (1e-9, 1e9);
/// The output rate (Hz).
pub(super) const OUTPUT_RATE: (Real, Real) = (1e-9, 1e9);
/// The most output samples of a run, `t_end · output_rate`.
pub(super) const SAMPLES: Real = 1e8;
/// The relative tolerance of the adaptive methods.
pub(super) const RTOL: (Real, Real) = (1e-14, 0.1);
/// The absolute tolerance of the adaptive methods.
pub(super) const ATOL: (Real, Real) = (1e-20, 1.0);
/// The step of the fixed-step methods (s).
pub(super) const DT: (Real, Real) = (1e-12, 1.0);
/// The most steps of a fixed-step run, `t_end / dt`.
pub(super) const FIXED_STEPS: Real = 1e10;
/// The largest adaptive step (s).
pub(super) const H_MAX: (Real, Real) = (1e-12, 1e9);
/// The energy-drift budget `max_drift`, relative to the run's energy scale.
pub(super) const MAX_DRIFT: (Real, Real) = (1e-16, 1e3);
/// The longest name (characters).
pub(super) const NAME_LENGTH: usize = 64;

/// `x` if it lies in `[lo, hi]`; else what is wrong, e.g. "the mass must be within
/// [1e-9, 1e9] kg, got 1e-320 kg" (`unit` may be empty).
#[doc(hidden)]
pub fn check(x: Real, (lo, hi): (Real, Real), what: &str, unit: &str) -> Result<Real, String> {
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    let range = format!("[{}, {}]{unit}", number(lo), number(hi));
    if x.is_finite() && (lo..=hi).contains(&x) {
        Ok(x)
    } else if x.is_finite() {
        Err(format!(
            "{what} must be within {range}, got {}{unit}",
            number(x)
        ))
    } else {
        Err(format!(
            "{what} must be a finite number within {range}, got {x}"
        ))
    }
}

/// Whether `x` lies in `[lo, hi]`.
pub(super) fn inside(x: Real, (lo, hi): (Real, Real)) -> bool {
    x.is_finite() && (lo..=hi).contains(&x)
}

/// `x` as a person reads it: plain, or in scientific notation when very large or small.
pub(super) fn number(x: Real) -> String {
    if x != 0.0 && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Why `name` cannot name a scene, a body, a shape or an obstacle, if it cannot: it must
/// be 1 to 64 printable characters (no control character: NUL, newline, tab …), without
/// `/` (pair names are `<a>/<b>`) or `\`, and not begin or end with a space.
#[doc(hidden)]
pub fn bad_name(name: &str) -> Option<String> {
    let count = name.chars().count();
    if count == 0 {
        Some("a name cannot be empty".into())
    } else if count > NAME_LENGTH {
        Some(format!(
            "a name has at most {NAME_LENGTH} characters, got {count}"
        ))
    } else if let Some(c) = name.chars().find(|c| c.is_control()) {
        Some(format!(
            "a name must be printable, got the control character {c:?}"
        ))
    } else if name.contains(['/', '\\']) {
        Some("a name cannot contain `/` or `\\` (pair names are `<a>/<b>`)".into())
    } else if name.trim() != name {
        Some("a name cannot begin or end with a space".into())
    } else {
        None
    }
}
