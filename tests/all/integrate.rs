//! Integrators against exact solutions: observed orders of convergence (DOPRI5 5, RK4 4),
//! local orders of the continuous extensions (4 and 3), DOPRI5's global error tracking
//! the tolerance, exact work counters, re-step and reset semantics, typed errors, and no
//! allocation inside a step.

use crate::common::alloc::allocations_in;

use ricochet::integrate::{
    AnyStepper, Dopri5, Dopri5Settings, FnSystem, IntegrateError, Method, OdeSystem, Rk4,
    Rk4Settings, RungeKutta, StepOutcome, Stepper,
};
use ricochet::settings::IntegratorSettings;

// ---------------------------------------------------------------------------------------
// Problems with exact solutions. Their spans are multiples of powers of two, so that the
// fixed steps `span / 2^k` add up exactly.

/// A test problem: dimension, right-hand side, exact solution, time span.
#[derive(Clone, Copy)]
struct Problem {
    name: &'static str,
    n: usize,
    f: fn(f64, &[f64], &mut [f64]),
    exact: fn(f64, &mut [f64]),
    t0: f64,
    t1: f64,
}

/// ẏ = λ y, λ = −2: y = e^{λ t}.
const EXP: Problem = Problem {
    name: "exp",
    n: 1,
    f: |_t, y, dy| dy[0] = -2.0 * y[0],
    exact: |t, y| y[0] = (-2.0 * t).exp(),
    t0: 0.0,
    t1: 2.0,
};

/// Harmonic oscillator ẍ = −x, x(0) = 1, ẋ(0) = 0: x = cos t.
const OSC: Problem = Problem {
    name: "oscillator",
    n: 2,
    f: |_t, y, dy| {
        dy[0] = y[1];
        dy[1] = -y[0];
    },
    exact: |t, y| {
        y[0] = t.cos();
        y[1] = -t.sin();
    },
    t0: 0.0,
    t1: 10.0,
};

/// The nonlinear Riccati equation ẏ = 1 + y², y(0) = 0: y = tan t.
const TAN: Problem = Problem {
    name: "tan",
    n: 1,
    f: |_t, y, dy| dy[0] = 1.0 + y[0] * y[0],
    exact: |t, y| y[0] = t.tan(),
    t0: 0.0,
    t1: 1.0,
};

/// The logistic equation ẏ = y (1 − y), y(0) = 1/10: y = 1 / (1 + 9 e^{−t}).
const LOGISTIC: Problem = Problem {
    name: "logistic",
    n: 1,
    f: |_t, y, dy| dy[0] = y[0] * (1.0 - y[0]),
    exact: |t, y| y[0] = 1.0 / (1.0 + 9.0 * (-t).exp()),
    t0: 0.0,
    t1: 8.0,
};

/// A non-autonomous nonlinear one: ẏ = −2 t y², y(0) = 1: y = 1/(1 + t²).
const RATIONAL: Problem = Problem {
    name: "rational",
    n: 1,
    f: |t, y, dy| dy[0] = -2.0 * t * y[0] * y[0],
    exact: |t, y| y[0] = 1.0 / (1.0 + t * t),
    t0: 0.0,
    t1: 3.0,
};

fn system(p: &Problem) -> impl OdeSystem<Error = std::convert::Infallible> {
    let f = p.f;
    FnSystem::new(p.n, move |t, y: &[f64], dy: &mut [f64]| f(t, y, dy))
}

fn exact(p: &Problem, t: f64) -> Vec<f64> {
    let mut y = vec![0.0; p.n];
    (p.exact)(t, &mut y);
    y
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// DOPRI5 settings for exactly fixed steps `h`: huge tolerances (every step accepted),
/// the first step and the cap equal to `h`.
fn dopri_fixed(h: f64) -> Dopri5Settings {
    Dopri5Settings {
        rtol: 1e6,
        atol: 1e6,
        h_max: h,
        h_init: Some(h),
        ..Default::default()
    }
}

/// Integrates `p` over its span with `stepper` and returns the largest error at the
/// step ends (the error at one point may vanish by accident, its maximum does not).
fn run_to_end<S: Stepper>(p: &Problem, stepper: &mut S) -> f64 {
    let mut sys = system(p);
    stepper.start(&mut sys, p.t0, &exact(p, p.t0)).unwrap();
    let mut err: f64 = 0.0;
    loop {
        let outcome = stepper.step(&mut sys, p.t1).unwrap();
        err = err.max(max_abs_diff(stepper.y(), &exact(p, stepper.t())));
        if outcome == StepOutcome::ReachedStop {
            break;
        }
    }
    assert_eq!(stepper.t(), p.t1);
    err
}

fn sci(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.3e}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn fix(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:.3}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Observed orders `log2(e(h) / e(h/2))` along `steps`.
fn observed_orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

// ---------------------------------------------------------------------------------------
// Orders of convergence.

/// Fixed steps `span / N`, N = 8 … 512; the observed orders are asserted in the
/// asymptotic range N ≥ 64 (the last three ratios), where every error is still far above
/// the rounding floor.
const STEPS: [u64; 7] = [8, 16, 32, 64, 128, 256, 512];

#[test]
fn dopri5_converges_with_order_5_at_fixed_steps() {
    for p in [EXP, OSC, TAN, LOGISTIC, RATIONAL] {
        let mut errors = Vec::new();
        for n_steps in STEPS {
            let h = (p.t1 - p.t0) / n_steps as f64;
            let mut d = Dopri5::new(p.n, dopri_fixed(h)).unwrap();
            errors.push(run_to_end(&p, &mut d));
            let c = d.counters();
            assert_eq!(
                (c.steps, c.rejected),
                (n_steps, 0),
                "{}: not fixed steps {c:?}",
                p.name
            );
        }
        let orders = observed_orders(&errors);
        println!(
            "dopri5 {:>10}: errors {}, orders {}",
            p.name,
            sci(&errors),
            fix(&orders)
        );
        if p.name == "tan" {
            // On ẏ = 1 + y² DOPRI5's leading error term nearly vanishes: the observed
            // order is 5.0–6.8 until the rounding floor (3e-15) at N = 256. Assert order
            // ≥ 5 down to the floor.
            for (w, q) in errors.windows(2).zip(&orders) {
                assert!(*q > 4.7 || w[1] < 1e-14, "tan: observed order {q}");
            }
            continue;
        }
        for q in &orders[orders.len() - 3..] {
            assert!((q - 5.0).abs() < 0.3, "{}: observed order {q}", p.name);
        }
    }
}

#[test]
fn rk4_converges_with_order_4() {
    for p in [EXP, OSC, TAN, LOGISTIC, RATIONAL] {
        let mut errors = Vec::new();
        for n_steps in STEPS {
            let dt = (p.t1 - p.t0) / n_steps as f64;
            let settings = Rk4Settings {
                dt,
                h_max: f64::INFINITY,
            };
            let mut r = Rk4::new(p.n, settings).unwrap();
            errors.push(run_to_end(&p, &mut r));
            let c = r.counters();
            assert_eq!(c.steps, n_steps, "{}: not fixed steps", p.name);
            assert_eq!(
                c.rhs_evals,
                1 + 4 * n_steps,
                "{}: RK4 costs 4 per step + 1",
                p.name
            );
        }
        let orders = observed_orders(&errors);
        println!(
            "rk4    {:>10}: errors {}, orders {}",
            p.name,
            sci(&errors),
            fix(&orders)
        );
        for q in &orders[orders.len() - 3..] {
            assert!((q - 4.0).abs() < 0.2, "{}: observed order {q}", p.name);
        }
    }
}

/// DOP853 converges with order 8 [HNW, II.10]: fixed steps `span / N`, N = 4 … 128. The
/// errors reach the rounding floor within a few halvings, so the order is asserted on
/// the halvings from an error above 1e-13 (at least two per problem): above 7 on
/// each (the coarse ones are pre-asymptotic: 7.3 to 9.9), 8 ± 0.6 on the last two.
#[test]
fn dop853_converges_with_order_8_at_fixed_steps() {
    const STEPS8: [u64; 6] = [4, 8, 16, 32, 64, 128];
    for p in [EXP, OSC, TAN, LOGISTIC, RATIONAL] {
        let mut errors = Vec::new();
        for n_steps in STEPS8 {
            let h = (p.t1 - p.t0) / n_steps as f64;
            let mut d = RungeKutta::dop853(p.n, dopri_fixed(h)).unwrap();
            errors.push(run_to_end(&p, &mut d));
            let c = d.counters();
            // The dense output is never read: its 3 extra stages are not evaluated.
            assert_eq!(
                (c.steps, c.rejected, c.rhs_evals, c.dense_completions),
                (n_steps, 0, 1 + 12 * n_steps, 0),
                "{}: not fixed steps of 12 evaluations {c:?}",
                p.name
            );
        }
        let orders = observed_orders(&errors);
        println!(
            "dop853 {:>10}: errors {}, orders {}",
            p.name,
            sci(&errors),
            fix(&orders)
        );
        let above: Vec<f64> = (errors.windows(2).zip(&orders))
            .filter(|(w, _)| w[0] > 1e-13)
            .map(|(_, &q)| q)
            .collect();
        assert!(above.len() >= 2, "{}: {above:?} above the floor", p.name);
        for q in &above {
            assert!(*q > 7.0, "{}: observed order {q}", p.name);
        }
        for q in &above[above.len() - 2..] {
            assert!((q - 8.0).abs() < 0.6, "{}: observed order {q}", p.name);
        }
    }
}

/// Error of the continuous extension at `θ` after one step of length `h` from the exact
/// value at `t0`.
fn one_step_dense_error<S: Stepper>(
    p: &Problem,
    stepper: &mut S,
    t0: f64,
    h: f64,
    theta: f64,
) -> f64 {
    let mut sys = system(p);
    stepper.start(&mut sys, t0, &exact(p, t0)).unwrap();
    assert_eq!(
        stepper.step(&mut sys, t0 + h).unwrap(),
        StepOutcome::ReachedStop
    );
    let t = t0 + theta * h;
    let mut y = vec![0.0; p.n];
    stepper.complete_dense(&mut sys).unwrap();
    stepper.dense(t, &mut y).unwrap();
    max_abs_diff(&y, &exact(p, t))
}

/// Local error of the continuous extension `O(h^(p*+1))`: DOPRI5's is of order `p* = 4`
/// [HNW, II.6; Shampine 1986], RK4's cubic Hermite of order 3, DOP853's of order 7
/// [HNW, II.10]. One step from the exact
/// value at `t0 = 0.2`; the exponent is asserted on the two finest halvings (each
/// method's step sequence ends well above its rounding floor).
#[test]
fn dense_output_local_orders() {
    type Make = fn(usize, f64) -> AnyStepper;
    let cases: [(&str, f64, &[f64], Make); 3] = [
        ("dopri5", 5.0, &[0.2, 0.1, 0.05, 0.025], |n, h| {
            Dopri5::new(n, dopri_fixed(h)).unwrap()
        }),
        ("rk4", 4.0, &[0.1, 0.05, 0.025, 0.0125], |n, h| {
            Rk4::new(n, Rk4Settings { dt: h, h_max: h }).unwrap()
        }),
        // DOP853's continuous extension is of order 7: local exponent 8 [HNW, II.10].
        ("dop853", 8.0, &[0.8, 0.4, 0.2, 0.1, 0.05, 0.025], |n, h| {
            RungeKutta::dop853(n, dopri_fixed(h)).unwrap()
        }),
    ];
    for (name, expected_exponent, steps, make) in cases {
        // DOP853's errors reach the rounding floor within three halvings: its exponents
        // are asserted where the finer error is above 1e-13, on the linear problems (on
        // tan and rational its one-step errors wander between exponents 5 and 11 down to
        // the floor: the interpolation error and the step's own, of similar size, change
        // sign).
        let (problems, floor) = if name == "dop853" {
            (vec![OSC, EXP], 1e-13)
        } else {
            (vec![OSC, TAN, RATIONAL], 0.0)
        };
        for p in problems {
            for theta in [0.3, 0.5, 0.7] {
                let t0 = 0.2;
                let errors: Vec<f64> = steps
                    .iter()
                    .map(|&h| one_step_dense_error(&p, &mut make(p.n, h), t0, h, theta))
                    .collect();
                let orders = observed_orders(&errors);
                println!(
                    "{name} dense {:>10} θ = {theta}: errors {}, exponents {}",
                    p.name,
                    sci(&errors),
                    fix(&orders)
                );
                let finer = &errors[2..];
                for (q, _) in orders[1..].iter().zip(finer).filter(|(_, e)| **e > floor) {
                    assert!(
                        (q - expected_exponent).abs() < 0.25,
                        "{name} {} θ = {theta}: local exponent {q}",
                        p.name
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Tolerance proportionality.

/// DOPRI5's global error tracks the tolerance [HNW, II.4, "tolerance proportionality"]:
/// over rtol = atol = 1e-4 … 1e-12 the ratio (largest error at the step ends) / tol stays
/// inside a band of at most one decade, within [1e-3, 10].
#[test]
fn dopri5_error_tracks_the_tolerance() {
    for p in [EXP, OSC, LOGISTIC, RATIONAL] {
        let mut ratios = Vec::new();
        let mut work = Vec::new();
        for k in 4..=12 {
            let tol = 10f64.powi(-k);
            let settings = Dopri5Settings {
                rtol: tol,
                atol: tol,
                h_max: f64::INFINITY,
                ..Default::default()
            };
            let mut d = Dopri5::new(p.n, settings).unwrap();
            let err = run_to_end(&p, &mut d);
            ratios.push(err / tol);
            work.push(d.counters().rhs_evals);
        }
        let lo = ratios.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = ratios.iter().cloned().fold(0.0, f64::max);
        println!(
            "dopri5 {:>10}: err/tol {} (band {:.2e} .. {:.2e}, ×{:.1}); rhs evals {:?}",
            p.name,
            sci(&ratios),
            lo,
            hi,
            hi / lo,
            work
        );
        assert!(
            lo >= 1e-3 && hi <= 10.0,
            "{}: err/tol outside [1e-3, 10]",
            p.name
        );
        assert!(
            hi / lo <= 10.0,
            "{}: err/tol spreads over more than a decade",
            p.name
        );
    }
}

// ---------------------------------------------------------------------------------------
// Work counters.

/// A system that counts its own evaluations, independently of the stepper's counters.
struct Counted<F> {
    n: usize,
    f: F,
    calls: u64,
}

impl<F: FnMut(f64, &[f64], &mut [f64])> OdeSystem for Counted<F> {
    type Error = std::convert::Infallible;
    fn dim(&self) -> usize {
        self.n
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Self::Error> {
        self.calls += 1;
        (self.f)(t, y, dy);
        Ok(())
    }
}

/// ẏ = 1 has a zero error estimate: with `h_init = h_max = 0.1` DOPRI5 takes exactly 10
/// steps to t = 1, 6 evaluations each (FSAL) plus 1 at the start.
#[test]
fn dopri5_counters_are_exact_with_fsal() {
    let mut sys = Counted {
        n: 1,
        f: |_t: f64, _y: &[f64], dy: &mut [f64]| dy[0] = 1.0,
        calls: 0,
    };
    let settings = Dopri5Settings {
        h_init: Some(0.125),
        h_max: 0.125,
        ..Default::default()
    };
    let mut d = Dopri5::new(1, settings).unwrap();
    d.start(&mut sys, 0.0, &[0.0]).unwrap();
    while d.step(&mut sys, 1.0).unwrap() != StepOutcome::ReachedStop {}
    let c = d.counters();
    assert_eq!(
        (c.steps, c.rejected, c.rhs_evals, c.resteps),
        (8, 0, 1 + 6 * 8, 0)
    );
    assert_eq!(sys.calls, c.rhs_evals);
    assert!((d.y()[0] - 1.0).abs() <= 2.0 * f64::EPSILON);
}

/// With rejections (a stiff-ish decay started with a far too large step) and the
/// automatic first step: `rhs_evals = 1 + 1 (HINIT) + 6 (steps + rejected)`, matching the
/// system's own count; then a re-step (6) and a reset (1).
#[test]
fn dopri5_counters_with_rejections_restep_and_reset() {
    let mut sys = Counted {
        n: 2,
        f: |_t: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = -50.0 * (y[0] - y[1].cos());
            dy[1] = 1.0;
        },
        calls: 0,
    };
    for h_init in [None, Some(1.0)] {
        sys.calls = 0;
        let settings = Dopri5Settings {
            rtol: 1e-8,
            atol: 1e-8,
            h_max: f64::INFINITY,
            h_init,
            ..Default::default()
        };
        let mut d = Dopri5::new(2, settings).unwrap();
        d.start(&mut sys, 0.0, &[0.0, 0.0]).unwrap();
        while d.step(&mut sys, 2.0).unwrap() != StepOutcome::ReachedStop {}
        let c = d.counters();
        let start = if h_init.is_some() { 1 } else { 2 };
        println!("h_init {h_init:?}: {c:?}");
        assert!(c.rejected > 0, "the test wants rejected steps");
        assert_eq!(c.rhs_evals, start + 6 * (c.steps + c.rejected));
        assert_eq!(sys.calls, c.rhs_evals);
        d.restep_to(&mut sys, 0.5 * (d.t_prev() + d.t())).unwrap();
        d.reset(&mut sys, d.t(), &[0.0, 0.0]).unwrap();
        let c2 = d.counters();
        assert_eq!(c2.rhs_evals, c.rhs_evals + 6 + 1);
        assert_eq!(c2.resteps, 1);
        assert_eq!(sys.calls, c2.rhs_evals);
    }
}

// ---------------------------------------------------------------------------------------
// Stepping semantics.

/// Steps never exceed `h_max`, never pass the stop time, and land on it exactly; a new
/// cap applies from the next step.
#[test]
fn steps_respect_h_max_and_the_stop_time() {
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            rtol: 1e-3,
            atol: 1e-3,
            dt: 0.3,
            h_max: 0.25,
        };
        let mut s = AnyStepper::new(2, &settings).unwrap();
        let mut sys = system(&OSC);
        s.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
        for (k, t_stop) in [0.7, 1.0, 2.5, 2.6, 10.0].into_iter().enumerate() {
            if k == 3 {
                s.set_h_max(0.01);
            }
            loop {
                let outcome = s.step(&mut sys, t_stop).unwrap();
                let h = s.t() - s.t_prev();
                assert!(h <= s.h_max() * (1.0 + 1e-12), "{method}: h = {h} > h_max");
                assert!(s.t() <= t_stop);
                if outcome == StepOutcome::ReachedStop {
                    assert_eq!(s.t(), t_stop);
                    break;
                }
            }
        }
        let err = max_abs_diff(s.y(), &exact(&OSC, 10.0));
        assert!(err < 1e-2, "{method}: error {err}");
    }
}

/// `restep_to` re-takes the last step from `(t_prev, y_prev)`: bit for bit the state of
/// a fresh stepper that takes one step of that length; it is full order (its error is
/// far below the continuous extension's), and the stepper continues from there.
#[test]
fn restep_is_a_full_order_step_to_the_target() {
    let p = LOGISTIC;
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            rtol: 1e-6,
            atol: 1e-6,
            dt: 0.5,
            h_max: 0.5,
        };
        let mut sys = system(&p);
        let mut s = AnyStepper::new(1, &settings).unwrap();
        s.start(&mut sys, 0.0, &exact(&p, 0.0)).unwrap();
        for _ in 0..3 {
            s.step(&mut sys, 8.0).unwrap();
        }
        let (t_prev, y_prev, t_end) = (s.t_prev(), s.y_prev().to_vec(), s.t());
        let t_e = t_prev + 0.37 * (t_end - t_prev);
        let mut y_dense = [0.0];
        s.complete_dense(&mut sys).unwrap();
        s.dense(t_e, &mut y_dense).unwrap();
        s.restep_to(&mut sys, t_e).unwrap();
        assert_eq!((s.t(), s.t_prev()), (t_e, t_prev));

        // The same step by a fresh stepper.
        let one = IntegratorSettings {
            h_max: t_e - t_prev,
            dt: t_e - t_prev,
            rtol: 1e6,
            atol: 1e6,
            ..settings.clone()
        };
        let mut fresh = AnyStepper::new(1, &one).unwrap();
        if let Some(adaptive) = fresh.adaptive_settings() {
            let d = Dopri5Settings {
                h_init: Some(t_e - t_prev),
                ..adaptive.clone()
            };
            fresh = match method {
                Method::Dop853 => RungeKutta::dop853(1, d),
                _ => RungeKutta::dopri5(1, d),
            }
            .unwrap();
        }
        fresh.start(&mut sys, t_prev, &y_prev).unwrap();
        fresh.step(&mut sys, t_e).unwrap();
        assert_eq!(fresh.t(), t_e);
        assert_eq!(
            fresh.y(),
            s.y(),
            "{method}: restep differs from a fresh step"
        );
        assert_eq!(fresh.dy(), s.dy());

        // Local errors, against the logistic solution through (t_prev, y_prev):
        // y(t) = 1 / (1 + (1/y_prev − 1) e^{−(t − t_prev)}).
        let local = 1.0 / (1.0 + (1.0 / y_prev[0] - 1.0) * (-(t_e - t_prev)).exp());
        let err_restep = (s.y()[0] - local).abs();
        let err_dense = (y_dense[0] - local).abs();
        println!(
            "{method}: local error of the dense output {err_dense:.2e}, of the restep {err_restep:.2e}"
        );
        assert!(
            err_restep < 0.1 * err_dense,
            "{method}: restep not more accurate than the dense output"
        );

        // Re-stepping again (forward, up to the accepted end) and rewinding are allowed;
        // beyond the accepted end is an error.
        s.restep_to(&mut sys, t_end).unwrap();
        s.restep_to(&mut sys, t_prev).unwrap();
        assert_eq!((s.t(), s.y()), (t_prev, &y_prev[..]));
        assert!(matches!(
            s.restep_to(&mut sys, t_end + 1e-9),
            Err(IntegrateError::RestepOutOfRange { .. })
        ));
        // And the stepper continues.
        while s.step(&mut sys, 8.0).unwrap() != StepOutcome::ReachedStop {}
        let err = (s.y()[0] - exact(&p, 8.0)[0]).abs();
        assert!(err < 1e-4, "{method}: error {err} after continuing");
    }
}

/// `reset` replaces the state, recomputes the derivative (FSAL invalidated) and empties
/// the last step; integration continues correctly from the new state.
#[test]
fn reset_restarts_from_the_new_state() {
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            rtol: 1e-10,
            atol: 1e-12,
            dt: 1e-3,
            h_max: 0.1,
        };
        let mut sys = system(&OSC);
        let mut s = AnyStepper::new(2, &settings).unwrap();
        s.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
        while s.step(&mut sys, 1.0).unwrap() != StepOutcome::ReachedStop {}
        // Jump to the oscillator's state at phase π/2: x = cos(t + π/2 − 1).
        let y_new = [0.0, -1.0];
        s.reset(&mut sys, 1.0, &y_new).unwrap();
        assert_eq!((s.t(), s.t_prev()), (1.0, 1.0));
        assert_eq!(s.y(), &y_new);
        assert_eq!(s.dy(), &[-1.0, -0.0]);
        let mut y = [0.0; 2];
        s.dense(1.0, &mut y).unwrap();
        assert_eq!(y, y_new);
        while s.step(&mut sys, 3.0).unwrap() != StepOutcome::ReachedStop {}
        let x_exact = (3.0 + std::f64::consts::FRAC_PI_2 - 1.0).cos();
        assert!((s.y()[0] - x_exact).abs() < 1e-8, "{method}: {}", s.y()[0]);
    }
}

// ---------------------------------------------------------------------------------------
// Errors.

#[derive(Debug, thiserror::Error)]
#[error("singular at t = {0}")]
struct Singular(f64);

/// A failing right-hand side is returned as `Rhs` with the time of the evaluation.
#[test]
fn rhs_errors_propagate_with_their_time() {
    struct Failing;
    impl OdeSystem for Failing {
        type Error = Singular;
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, t: f64, _y: &[f64], dy: &mut [f64]) -> Result<(), Singular> {
            if t >= 0.5 {
                return Err(Singular(t));
            }
            dy[0] = 1.0;
            Ok(())
        }
    }
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            dt: 0.1,
            h_max: 0.1,
            ..Default::default()
        };
        let mut s = AnyStepper::new(1, &settings).unwrap();
        s.start(&mut Failing, 0.0, &[0.0]).unwrap();
        let err = loop {
            match s.step(&mut Failing, 1.0) {
                Ok(_) => continue,
                Err(e) => break e,
            }
        };
        match err {
            IntegrateError::Rhs { t, source } => {
                assert!((0.5..0.7).contains(&t), "{method}: t = {t}");
                assert_eq!(source.0, t);
            }
            other => panic!("{method}: unexpected {other:?}"),
        }
        assert!(
            s.t() < 0.5,
            "{method}: the state must stay at the last good step"
        );
    }
}

/// ẏ = y², y(0) = 1 blows up at t = 1: DOPRI5 reports `StepSizeTooSmall` just before.
#[test]
fn blow_up_gives_step_size_too_small() {
    let mut sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| dy[0] = y[0] * y[0]);
    let settings = Dopri5Settings {
        rtol: 1e-8,
        atol: 1e-8,
        h_max: f64::INFINITY,
        ..Default::default()
    };
    let mut d = Dopri5::new(1, settings).unwrap();
    d.start(&mut sys, 0.0, &[1.0]).unwrap();
    let err = loop {
        if let Err(e) = d.step(&mut sys, 2.0) {
            break e;
        }
    };
    match err {
        IntegrateError::StepSizeTooSmall { t, h, h_min } => {
            println!("blow-up: t = {t}, h = {h:e}, h_min = {h_min:e}");
            assert!((t - 1.0).abs() < 1e-3 && h < h_min);
        }
        IntegrateError::NonFinite { t } => {
            println!("blow-up: non-finite at t = {t}");
            assert!((t - 1.0).abs() < 1e-3);
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn misuse_is_reported() {
    let mut sys = system(&OSC);
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            ..Default::default()
        };
        let mut s = AnyStepper::new(2, &settings).unwrap();
        assert!(matches!(
            s.step(&mut sys, 1.0),
            Err(IntegrateError::NotStarted)
        ));
        assert!(matches!(
            s.start(&mut sys, 0.0, &[1.0]),
            Err(IntegrateError::Dimension {
                expected: 2,
                got: 1
            })
        ));
        assert!(matches!(
            s.start(&mut sys, 0.0, &[f64::NAN, 0.0]),
            Err(IntegrateError::NonFinite { t: 0.0 })
        ));
        s.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
        assert!(matches!(
            s.step(&mut sys, 0.0),
            Err(IntegrateError::StopNotAhead { .. })
        ));
        assert!(matches!(
            s.step(&mut sys, f64::NAN),
            Err(IntegrateError::StopNotAhead { .. })
        ));
    }
    let bad = Dopri5Settings {
        rtol: -1.0,
        ..Default::default()
    };
    let e = Dopri5::new(2, bad).unwrap_err();
    assert_eq!(e.field, "rtol");
    let bad = Rk4Settings {
        dt: 0.0,
        h_max: 1.0,
    };
    assert_eq!(Rk4::new(2, bad).unwrap_err().field, "dt");
}

// ---------------------------------------------------------------------------------------
// No allocation in the step.

#[test]
fn stepping_does_not_allocate() {
    for method in Method::ODE {
        let settings = IntegratorSettings {
            method,
            rtol: 1e-8,
            atol: 1e-8,
            dt: 0.01,
            h_max: 0.1,
        };
        let mut sys = system(&OSC);
        let mut s = AnyStepper::new(2, &settings).unwrap();
        s.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
        let mut y = [0.0; 2];
        let allocs = allocations_in(|| {
            for k in 1..=50 {
                let t_stop = 0.1 * k as f64;
                while s.step(&mut sys, t_stop).unwrap() != StepOutcome::ReachedStop {
                    s.complete_dense(&mut sys).unwrap();
                    s.dense(0.5 * (s.t_prev() + s.t()), &mut y).unwrap();
                    s.dense_derivative(s.t(), &mut y).unwrap();
                }
                s.restep_to(&mut sys, 0.5 * (s.t_prev() + s.t())).unwrap();
                s.reset(&mut sys, s.t(), &[1.0, 0.0]).unwrap();
            }
        });
        assert_eq!(allocs, 0, "{method}: {allocs} allocations while stepping");
        assert!(s.counters().steps > 50);
    }
}

/// Stopping at output times costs at most about one extra step per stop: a step
/// shortened to land on a stop time does not shrink the step-size suggestion.
#[test]
fn output_stops_do_not_degrade_the_step_size() {
    let p = OSC;
    let settings = Dopri5Settings {
        rtol: 1e-10,
        atol: 1e-10,
        h_max: f64::INFINITY,
        ..Default::default()
    };
    let mut plain = Dopri5::new(2, settings.clone()).unwrap();
    run_to_end(&p, &mut plain);
    let mut sys = system(&p);
    let mut stopped = Dopri5::new(2, settings).unwrap();
    stopped.start(&mut sys, p.t0, &exact(&p, p.t0)).unwrap();
    let n_stops = 40;
    for k in 1..=n_stops {
        let t_stop = p.t1 * k as f64 / n_stops as f64;
        while stopped.step(&mut sys, t_stop).unwrap() != StepOutcome::ReachedStop {}
    }
    let (a, b) = (plain.counters(), stopped.counters());
    println!("no stops: {a:?}\n{n_stops} stops: {b:?}");
    assert!(
        b.steps <= a.steps + n_stops + 2,
        "{} vs {}",
        b.steps,
        a.steps
    );
    assert!(b.rejected <= a.rejected + 2);
    let err = max_abs_diff(stopped.y(), &exact(&p, p.t1));
    assert!(err < 1e-8, "{err}");
}

/// A right-hand side that fails at a state the solution never reaches, but that a large
/// trial step probes (issue 11: contact forces without solution at a trial stage): the
/// step is rejected and shrinks, and the solution is still the closed form. ẏ = −10 y,
/// y(0) = 1, whose stages at h = 0.5 go negative; the system refuses y < 0.
#[test]
fn a_failing_trial_stage_shrinks_the_step() {
    struct Decay;
    impl OdeSystem for Decay {
        type Error = Singular;
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), Singular> {
            if y[0] < 0.0 {
                return Err(Singular(t));
            }
            dy[0] = -10.0 * y[0];
            Ok(())
        }
    }
    // DOPRI5 starting at h = 0.5: its first trial fails and shrinks; then the controller.
    let settings = Dopri5Settings {
        rtol: 1e-10,
        atol: 1e-20,
        h_max: 0.5,
        h_init: Some(0.5),
        ..Default::default()
    };
    let mut d = Dopri5::new(1, settings).unwrap();
    d.start(&mut Decay, 0.0, &[1.0]).unwrap();
    while d.t() < 2.0 {
        d.step(&mut Decay, 2.0).unwrap();
    }
    let (y, exact) = (d.y()[0], (-20.0f64).exp());
    println!(
        "dopri5: y(2) = {y:.9e} (exact {exact:.9e}, {:.1e}); {} rejected",
        (y - exact).abs() / exact,
        d.counters().rejected
    );
    assert!(d.counters().rejected > 0);
    assert!((y - exact).abs() <= 1e-7 * exact);
    // RK4 with dt = 0.5: every step's second stage is negative (1 − 2.5 y); each step is
    // taken at dt/4 = 0.125 instead, so y(2) is the method's own amplification at
    // z = −1.25, R(z) = 1 + z + z²/2 + z³/6 + z⁴/24, to the 16th power.
    let settings = IntegratorSettings {
        method: Method::Rk4,
        dt: 0.5,
        h_max: 0.5,
        ..Default::default()
    };
    let mut s = AnyStepper::new(1, &settings).unwrap();
    s.start(&mut Decay, 0.0, &[1.0]).unwrap();
    // A far stop, so that no step is clipped to it: 16 steps of 0.125 s reach 2 s.
    while s.t() < 2.0 {
        s.step(&mut Decay, 100.0).unwrap();
    }
    assert_eq!(s.t(), 2.0);
    let z: f64 = -1.25;
    let r = 1.0 + z + z * z / 2.0 + z.powi(3) / 6.0 + z.powi(4) / 24.0;
    let y = s.y()[0];
    println!(
        "rk4: y(2) = {y:.9e} (R(−1.25)¹⁶ = {:.9e}); {:?}",
        r.powi(16),
        s.counters()
    );
    assert!((y - r.powi(16)).abs() <= 1e-12 * r.powi(16));
    assert_eq!((s.counters().steps, s.counters().rejected), (16, 16));
}
