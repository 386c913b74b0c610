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

/// Numbers uniform in `[0, 1)` (53 bits each) from the xorshift64 generator started at
/// `state` (not 0): the random inputs of the library's tests.
#[cfg(test)]
pub(crate) fn uniform_numbers(mut state: u64) -> impl FnMut() -> Real {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as Real / (1u64 << 53) as Real
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shown_number_is_short_and_reads_back_exactly() {
        // The everyday numbers as `{}` prints them.
        for x in [0.5, -2.0, 0.0, 1e-3, 123456.75, 1e-5, 9.999e15] {
            assert_eq!(Shown(x).to_string(), x.to_string());
        }
        assert_eq!(Shown(-0.0).to_string(), "-0");
        assert_eq!(Shown(f64::NAN).to_string(), "NaN");
        assert_eq!(Shown(f64::NEG_INFINITY).to_string(), "-inf");
        // The extremes with an exponent.
        assert_eq!(Shown(1e-300).to_string(), "1e-300");
        assert_eq!(Shown(-1e308).to_string(), "-1e308");
        assert_eq!(Shown(f64::from_bits(1)).to_string(), "5e-324");
        assert_eq!(Shown(1e16).to_string(), "1e16");
        // Every finite double (random bit patterns): short, and the same double read back.
        let mut bits = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..100_000 {
            bits ^= bits << 13;
            bits ^= bits >> 7;
            bits ^= bits << 17;
            let x = f64::from_bits(bits);
            if !x.is_finite() {
                continue;
            }
            let text = Shown(x).to_string();
            assert!(text.len() <= 24, "{x:e}: {text}");
            assert_eq!(
                text.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{text}"
            );
        }
    }

    #[test]
    fn perp_is_cross_with_unit_z() {
        let r = Vec2::new(0.3, -1.7);
        // ω ẑ × r = ω (−r_y, r_x)
        assert_eq!(perp(r), Vec2::new(1.7, 0.3));
        assert_eq!(cross(r, perp(r)), r.length_squared());
    }
}
