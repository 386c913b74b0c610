//! The unit tests of `regress::drift` (`src/regress/drift.rs`).

// The source module's own imports.

use ricochet::regress::drift::DriftCheck;

#[test]
fn the_budget_holds_or_breaks_by_the_ratio() {
    let ok = DriftCheck::new(-2e-9, 10.0, Some(1e-9));
    assert_eq!(ok.relative, Some(2e-10));
    assert!(!ok.broken());
    assert!(ok.describe().contains("within the budget max_drift = 1e-9"));
    let bad = DriftCheck::new(3e-8, 10.0, Some(1e-9));
    assert!(bad.broken());
    assert!((bad.ratio().unwrap() - 3.0).abs() < 1e-12);
    let text = bad.describe();
    assert!(
        text.contains(
            "BEYOND the budget max_drift = 1e-9 (3.000 times the budget, 2.000e-8 J over it)"
        ),
        "{text}"
    );
    // No budget: never broken.
    assert!(!DriftCheck::new(1.0, 1.0, None).broken());
    // No energy at all: zero drift is within any budget, any other breaks it.
    assert_eq!(DriftCheck::new(0.0, 0.0, Some(1e-12)).relative, Some(0.0));
    assert!(!DriftCheck::new(0.0, 0.0, Some(1e-12)).broken());
    let none = DriftCheck::new(1e-20, 0.0, Some(1.0));
    assert_eq!(none.relative, None);
    assert!(none.broken());
    assert!(DriftCheck::new(f64::NAN, 1.0, Some(1.0)).broken());
}
