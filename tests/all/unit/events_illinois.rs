//! The unit tests of `events::illinois` (`src/events/illinois.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::events::illinois::*;

fn solve(f: impl Fn(Real) -> Real, lo: Real, hi: Real) -> Solved {
    illinois::<()>(
        |x| Ok(Probe::Value(f(x))),
        (lo, f(lo)),
        (hi, f(hi)),
        |a, b| 4.0 * Real::EPSILON * a.abs().max(b.abs()),
        200,
    )
    .unwrap()
}

#[test]
fn brackets_a_simple_root_to_a_few_ulp() {
    // f(x) = 2 − x² falls through zero at √2.
    let Solved::Bracket { lo, hi, iters } = solve(|x| 2.0 - x * x, 0.0, 3.0) else {
        panic!("not converged");
    };
    let r = 2f64.sqrt();
    assert!(
        lo <= r && r <= hi && hi - lo <= 8.0 * Real::EPSILON * r,
        "{lo} {hi}"
    );
    assert!(2.0 - lo * lo > 0.0 && 2.0 - hi * hi <= 0.0);
    assert!(iters < 20, "{iters} iterations");
}

#[test]
fn flat_and_steep_functions_converge() {
    // A root of multiplicity 3 (regula falsi alone stalls here) and a steep step.
    for (f, r) in [
        (
            Box::new(|x: Real| -(x - 0.3).powi(3)) as Box<dyn Fn(Real) -> Real>,
            0.3,
        ),
        (Box::new(|x: Real| (-1e3 * (x - 0.7)).tanh()), 0.7),
    ] {
        match solve(&f, 0.0, 1.0) {
            Solved::Bracket { lo, hi, .. } => {
                assert!(f(lo) > 0.0 && f(hi) <= 0.0);
                assert!((lo - r).abs() < 1e-5, "{lo} {hi}");
                assert!(hi - lo <= 1e-15, "{lo} {hi}");
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn stop_is_reported() {
    let s = illinois::<()>(
        |x| {
            Ok(if x > 0.5 {
                Probe::Stop
            } else {
                Probe::Value(1.0 - x)
            })
        },
        (0.0, 1.0),
        (2.0, -1.0),
        |_, _| 1e-12,
        100,
    )
    .unwrap();
    assert!(matches!(s, Solved::Stopped { t, .. } if t > 0.5));
}
