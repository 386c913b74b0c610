//! The unit tests of `scene::units` (`src/scene/units.rs`).

// The source module's own imports.

use ricochet::scene::units::*;

#[test]
fn units_convert_to_si() {
    let q = |s: &str| parse(s).unwrap();
    assert_eq!(q("20 deg").si(Kind::Angle).unwrap(), 20f64.to_radians());
    assert_eq!(q("-0.1 rad/s").si(Kind::AngularRate).unwrap(), -0.1);
    assert!(
        (q("60 rpm").si(Kind::AngularRate).unwrap() - 2.0 * std::f64::consts::PI).abs() < 1e-15
    );
    assert!(q("20 deg").si(Kind::AngularRate).is_err());
    assert!(Quantity::Number(1.0).si(Kind::Angle).is_err());
    assert!(q("1 rad").si(Kind::Plain).is_err());
    assert!(parse("20 degs").is_err());
    assert!(parse("twenty deg").is_err());
    assert!(parse("20").is_err());
}
