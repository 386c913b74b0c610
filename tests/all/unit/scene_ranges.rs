//! The unit tests of `scene::ranges` (`src/scene/ranges.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::scene::ranges::*;

#[test]
fn ranges_and_names() {
    assert_eq!(check(1.0, MASS, "the mass", "kg"), Ok(1.0));
    assert_eq!(
        check(1e-320, MASS, "the mass", "kg"),
        Err("the mass must be within [1e-9, 1e9] kg, got 1e-320 kg".into())
    );
    assert!(
        check(Real::NAN, MASS, "m", "")
            .unwrap_err()
            .contains("finite")
    );
    assert_eq!(bad_name("rod B.1"), None);
    for bad in ["", "a/b", "a\0b", "a\nb", " a", &"x".repeat(65)] {
        assert!(bad_name(bad).is_some(), "{bad:?}");
    }
}
