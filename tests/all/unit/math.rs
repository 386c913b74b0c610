//! The unit tests of `math` (`src/math.rs`).

// The source module's own imports.
use parry2d_f64::math::Vector as Vec2;

use ricochet::math::*;

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
