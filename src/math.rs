//! Planar math: the scalar type, 2-D vectors and poses (parry2d's glam types), and small
//! helpers.

pub use parry2d_f64::math::{Pose, Vector as Vec2};

/// The scalar type of the whole crate.
pub type Real = f64;

/// The scalar cross product of two planar vectors, `a × b = a_x b_y − a_y b_x`.
#[inline]
pub fn cross(a: Vec2, b: Vec2) -> Real {
    a.x * b.y - a.y * b.x
}

/// The vector rotated by +90°, `(−v_y, v_x)`: `ω × r` for a planar angular velocity `ω`
/// is `ω · perp(r)`.
#[inline]
pub fn perp(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

/// A number as an error message shows it: the shortest decimal that reads back as the same
/// double, without an exponent for `1e-5 ≤ |x| < 1e16` (and 0, ±∞, NaN) as `{}` prints
/// it, with one beyond (`{:e}`): `{}` alone writes `1e-300` with 300 zeros and `1e308`
/// with 309 digits. Either way the value reads back exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shown(pub Real);

impl std::fmt::Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if !a.is_finite() || a == 0.0 || (1e-5..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}
