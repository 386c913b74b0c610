//! The unit tests of `sim::gaps` (`src/sim/gaps.rs`).

// The source module's own imports.

use ricochet::sim::gaps::{gap_stays_positive, stays_positive};

/// A segment of half-length `r` spinning at `ω` about its centre, which falls from
/// height `d` at speed `v` (down) under gravity, above a floor: its gap is
/// `d − v t − ½ g t² − r |sin(θ₀ + ω t)|` exactly, and its rotation bound at the start is
/// `V₀ = |v| + |ω| r`. Over random steps `h`: wherever [`gap_stays_positive`] gives a
/// stand-in, the gap stays above half its start's value through the step (the a
/// posteriori check holds), so it never reaches zero; and a gap that does reach zero
/// in the step — a fast approach, a fast spin, a long step — is always refused, as is
/// one whose speed is unknown.
#[test]
fn a_gap_that_can_close_in_the_step_gets_no_stand_in() {
    let grav = 9.81;
    let mut uniform = crate::unit::uniform_numbers(0x9e37_79b9_7f4a_7c15);
    let (mut allowed, mut crossing) = (0, 0);
    for _ in 0..100_000 {
        let r = 0.01 + uniform();
        let d = r * (1.0 + 3.0 * uniform()) + 0.5 * uniform();
        let v = 20.0 * (uniform() - 0.3);
        let w = 200.0 * (uniform() - 0.5);
        let theta0 = 6.3 * uniform();
        let h = 10f64.powf(-4.0 + 3.0 * uniform());
        let gap = |t: f64| d - v * t - 0.5 * grav * t * t - r * (theta0 + w * t).sin().abs();
        let g0 = gap(0.0);
        let least = (0..=2_000)
            .map(|k| gap(h * k as f64 / 2_000.0))
            .fold(f64::INFINITY, f64::min);
        let bound = gap_stays_positive(g0, v.abs() + w.abs() * r, grav, h);
        if least <= 0.0 {
            crossing += 1;
            assert!(
                bound.is_none(),
                "d {d}, r {r}, v {v}, ω {w}, h {h}: a closing gap passed"
            );
        }
        if bound.is_some() {
            allowed += 1;
            assert!(
                least >= 0.5 * g0,
                "d {d}, r {r}, v {v}, ω {w}, h {h}: below g₀/2"
            );
        }
    }
    assert!(
        allowed > 10_000 && crossing > 1_000,
        "{allowed} allowed, {crossing} crossing"
    );
    assert_eq!(gap_stays_positive(1.0, f64::NAN, grav, 1e-3), None);
    assert_eq!(gap_stays_positive(-1.0, 0.0, grav, 1e-3), None);
    // Kane's pendulum: its hinge 1.7 m above the floor, 1 m/s, a 25 ms step.
    assert!(gap_stays_positive(1.7, 1.0, grav, 0.025).is_some());
}

/// Random polynomials of degree ≤ 5 on a step `[0, 1]`, set by their values at
/// DOPRI5's nodes (the step's start and its stages): wherever [`stays_positive`]
/// passes them, their least value over the whole step (on a grid of 10⁴ points),
/// computed here by Lagrange interpolation, is above 0.42 `lo` — the bound of its
/// doc, from the nodes' Lebesgue constant 5.64 — and so never reaches zero. Values at
/// the nodes drawn both uniformly and at the ends of `[lo, hi]` (the worst case of the
/// bound is an alternation of the extremes).
#[test]
fn a_polynomial_through_the_stages_that_passes_stays_positive() {
    let nodes = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0];
    let lagrange = |values: &[f64; 6], t: f64| -> f64 {
        let mut sum = 0.0;
        for (j, (&xj, &vj)) in nodes.iter().zip(values).enumerate() {
            let mut l = 1.0;
            for (k, &xk) in nodes.iter().enumerate() {
                if k != j {
                    l *= (t - xk) / (xj - xk);
                }
            }
            sum += vj * l;
        }
        sum
    };
    let mut uniform = crate::unit::uniform_numbers(0x2545_f491_4f6c_dd1d);
    let (mut passed, mut worst) = (0, f64::INFINITY);
    for case in 0..20_000 {
        let lo = 1.0;
        let spread = lo * 0.3 * uniform();
        let mut values = [0.0; 6];
        for v in &mut values {
            *v = if case % 2 == 0 {
                lo + spread * uniform()
            } else {
                lo + spread * (uniform() < 0.5) as u8 as f64
            };
        }
        let l = values.iter().copied().fold(f64::INFINITY, f64::min);
        let h = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !stays_positive(l, h) {
            continue;
        }
        passed += 1;
        let least = (0..=10_000)
            .map(|k| lagrange(&values, k as f64 / 10_000.0))
            .fold(f64::INFINITY, f64::min);
        worst = worst.min(least / l);
        assert!(
            least > 0.42 * l,
            "values {values:?}: least {least} below 0.42 lo"
        );
    }
    assert!(passed > 5_000, "only {passed} cases passed the rule");
    assert!(worst < 0.9, "no case came near the bound (worst {worst})");
}

/// The rule refuses what is not positive and what varies too much.
#[test]
fn the_rule_refuses_nonpositive_and_varying_functions() {
    assert!(!stays_positive(0.0, 0.0));
    assert!(!stays_positive(-1.0, -0.5));
    assert!(!stays_positive(1.0, 1.26));
    assert!(stays_positive(1.0, 1.24));
    assert!(!stays_positive(f64::NAN, 1.0));
}
