//! DOP853's dense output completed on demand (issue 16, `Stepper::complete_dense`): its
//! three extra stages are evaluated only when the step is read inside. The dense values
//! are those of a stepper that completes every step, bit for bit; a run that never reads
//! a step inside pays 12 evaluations per step; reading before completing is an error.

use std::path::Path;

use ricochet::events::{EventError, EventLocator, FnEvents, LocatorSettings};
use ricochet::integrate::tableau::DOP853;
use ricochet::integrate::{
    AdaptiveSettings, DenseIncomplete, FnSystem, IntegrateError, OdeSystem, RungeKutta,
    StepOutcome, Stepper,
};
use ricochet::settings::IntegratorSettings;
use ricochet::sim::{MaterialOverride, MotionSystem, Recorder, Scales, Simulation};

/// Evaluations of a DOP853 step (stages 2 … 12 and `f(t₁, y₁)`) and of its completion.
const STEP: u64 = 12;
const EXTRA: u64 = 3;

fn dop853(n: usize, rtol: f64, h_max: f64) -> RungeKutta {
    let run = IntegratorSettings {
        rtol,
        atol: rtol,
        h_max,
        ..Default::default()
    };
    RungeKutta::dop853(n, AdaptiveSettings::dop853(&run)).unwrap()
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Asserts the two steppers stand at the same step, to the bit.
fn same_state(a: &RungeKutta, b: &RungeKutta, at: &str) {
    assert_eq!(a.t().to_bits(), b.t().to_bits(), "{at}: t");
    assert_eq!(a.t_prev().to_bits(), b.t_prev().to_bits(), "{at}: t_prev");
    assert_eq!(bits(a.y()), bits(b.y()), "{at}: y");
    assert_eq!(bits(a.dy()), bits(b.dy()), "{at}: dy");
    assert_eq!(bits(a.y_prev()), bits(b.y_prev()), "{at}: y_prev");
}

/// Asserts the dense outputs of the two (complete) steppers are the same bits at 23
/// times of the step (and a little beyond its ends), and returns how many were compared.
fn same_dense(a: &RungeKutta, b: &RungeKutta, at: &str) -> usize {
    let (t0, t1) = (a.t_prev(), a.t());
    let n = a.dim();
    let (mut ya, mut yb) = (vec![0.0; n], vec![0.0; n]);
    let mut compared = 0;
    for j in -1..=21 {
        let t = t0 + (t1 - t0) * (j as f64 / 20.0 + 0.013);
        a.dense(t, &mut ya).unwrap();
        b.dense(t, &mut yb).unwrap();
        assert_eq!(bits(&ya), bits(&yb), "{at}: dense at {t}");
        a.dense_derivative(t, &mut ya).unwrap();
        b.dense_derivative(t, &mut yb).unwrap();
        assert_eq!(bits(&ya), bits(&yb), "{at}: dense derivative at {t}");
        compared += 1;
    }
    compared
}

/// Runs `eager` (completed inside every step and re-step from the stages where they
/// stand: the code before the completion on demand, `set_eager_dense`) and `lazy` in
/// lockstep on their own copies of the system from `y0` to `t_end`. Every third step
/// both re-take it to 60 % (as to an event). `lazy` completes only where `read(k)` for
/// the `k`-th step or re-step, and before that evaluates its system at another state
/// (its last evaluation, which a system may remember, is then elsewhere, as in the
/// simulation). Returns the dense values compared and the lazy stepper.
fn lockstep<S: OdeSystem>(
    system: impl Fn() -> S,
    n: usize,
    y0: &[f64],
    (rtol, h_max, t_end): (f64, f64, f64),
    read: impl Fn(usize) -> bool,
) -> (usize, RungeKutta) {
    let (mut sys_e, mut sys_l) = (system(), system());
    let (mut eager, mut lazy) = (dop853(n, rtol, h_max), dop853(n, rtol, h_max));
    eager.set_eager_dense(true);
    eager.start(&mut sys_e, 0.0, y0).unwrap();
    lazy.start(&mut sys_l, 0.0, y0).unwrap();
    let mut elsewhere = vec![0.0; n];
    let (mut k, mut compared) = (0, 0);
    loop {
        let outcome = eager.step(&mut sys_e, t_end).unwrap();
        assert_eq!(lazy.step(&mut sys_l, t_end).unwrap(), outcome);
        for restep in [false, true] {
            if restep {
                let t_e = eager.t_prev() + 0.6 * (eager.t() - eager.t_prev());
                eager.restep_to(&mut sys_e, t_e).unwrap();
                lazy.restep_to(&mut sys_l, t_e).unwrap();
            }
            let at = format!("step {k} (re-step {restep})");
            assert!(eager.dense_complete(), "{at}: the oracle is not complete");
            same_state(&eager, &lazy, &at);
            if read(k) {
                assert!(!lazy.dense_complete(), "{at}: complete before asked");
                sys_l.rhs(1e3, y0, &mut elsewhere).unwrap();
                lazy.complete_dense(&mut sys_l).unwrap();
                compared += same_dense(&eager, &lazy, &at);
            }
            k += 1;
            if !restep && k % 3 != 0 {
                break;
            }
        }
        if outcome == StepOutcome::ReachedStop || lazy.t() >= t_end {
            break;
        }
    }
    assert!(k > 10, "too few steps: {k}");
    // The oracle completed every step and re-step; the lazy stepper paid 3 for each it
    // completed, nothing for the others.
    let (e, l) = (eager.counters(), lazy.counters());
    assert_eq!(
        (e.steps, e.rejected, e.resteps),
        (l.steps, l.rejected, l.resteps)
    );
    assert_eq!(e.dense_completions, e.steps + e.resteps);
    assert_eq!(
        e.rhs_evals,
        l.rhs_evals + EXTRA * (e.dense_completions - l.dense_completions),
        "{e:?} vs {l:?}"
    );
    (compared, lazy)
}

/// The harmonic oscillator `x = cos t`: the dense output completed on demand, at any
/// later step or re-step, is the eager one bit for bit (and it is the solution).
#[test]
fn an_oscillator_s_dense_output_on_demand_is_the_eager_one() {
    let osc = || {
        FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
        })
    };
    for read in [
        |k: usize| k % 2 == 1,
        |k: usize| k.is_multiple_of(5),
        |_| true,
    ] {
        let (compared, lazy) = lockstep(osc, 2, &[1.0, 0.0], (1e-10, 0.7, 12.0), read);
        assert!(compared > 100, "{compared}");
        let mut y = [0.0; 2];
        let t = lazy.t_prev() + 0.3 * (lazy.t() - lazy.t_prev());
        let mut s = lazy.clone();
        s.complete_dense(&mut osc()).unwrap();
        s.dense(t, &mut y).unwrap();
        assert!((y[0] - t.cos()).abs() < 1e-8, "{} vs {}", y[0], t.cos());
    }
}

/// Kane's double pendulum swinging free (the simulation's right-hand side, which keeps
/// the kinematics of its last evaluation): the same, bit for bit.
#[test]
fn kane_s_dense_output_on_demand_is_the_eager_one() {
    let scene = scene("scenes/kane_double_pendulum.toml");
    let scales = Scales::of(&scene.model, &scene.settings.integrator);
    let system = || MotionSystem::new(&scene.model, scales);
    let mut y0: Vec<f64> = scene
        .initial
        .q
        .iter()
        .chain(scene.initial.u.iter())
        .copied()
        .collect();
    let n = system().dim();
    y0.resize(n, 0.0);
    let (compared, _) = lockstep(system, n, &y0, (1e-10, 0.1, 2.0), |k| k % 3 != 1);
    assert!(compared > 100, "{compared}");
}

fn scene(path: &str) -> ricochet::scene::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    ricochet::scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The evaluations of `f`: 1 at the start and 1 for the first step's guess, 12 per step
/// (accepted, rejected or re-taken) and 3 per completed dense output, whichever steps are
/// read; a second completion of the same step costs nothing.
#[test]
fn a_step_read_only_at_its_ends_costs_twelve() {
    let calls = std::cell::Cell::new(0u64);
    let mut sys = FnSystem::new(1, |t, y: &[f64], dy: &mut [f64]| {
        calls.set(calls.get() + 1);
        dy[0] = -y[0] * (1.0 + t).cos() + (3.0 * t).sin();
    });
    let mut s = dop853(1, 1e-9, f64::INFINITY);
    s.start(&mut sys, 0.0, &[1.0]).unwrap();
    while s.step(&mut sys, 4.0).unwrap() != StepOutcome::ReachedStop {}
    let c = s.counters();
    assert!(c.steps > 10 && c.rejected > 0, "{c:?}");
    assert_eq!(c.rhs_evals, 2 + STEP * (c.steps + c.rejected), "{c:?}");
    assert_eq!((c.dense_completions, c.resteps), (0, 0));
    assert_eq!(calls.get(), c.rhs_evals);
    // Read every other step inside, re-take some: 3 more for each completion only.
    let mut read = 0;
    while s.step(&mut sys, 8.0).unwrap() != StepOutcome::ReachedStop {
        if s.counters().steps.is_multiple_of(2) {
            s.complete_dense(&mut sys).unwrap();
            s.complete_dense(&mut sys).unwrap();
            read += 1;
        }
        if s.counters().steps.is_multiple_of(3) {
            s.restep_to(&mut sys, s.t_prev() + 0.5 * (s.t() - s.t_prev()))
                .unwrap();
            s.complete_dense(&mut sys).unwrap();
            read += 1;
        }
    }
    let c = s.counters();
    assert_eq!(c.dense_completions, read);
    assert!(c.resteps > 0);
    assert_eq!(
        c.rhs_evals,
        2 + STEP * (c.steps + c.rejected + c.resteps) + EXTRA * c.dense_completions,
        "{c:?}"
    );
    assert_eq!(calls.get(), c.rhs_evals);
    assert_eq!(DOP853.evaluations_per_step(), STEP + EXTRA);
}

/// Kane's pendulum for 5 s at rtol 1e-10 through the simulation: every evaluation is
/// accounted for (1 + 1 + 12 per step, rejected step and re-step, 3 per completed dense
/// output, 1 per reset), and the steps whose interior the loop never reads (stand-ins
/// inside, no sample in them) are not completed: fewer evaluations than the 15 per step
/// and re-step of an eager dense output. The same run with a sample every millisecond
/// (which reads every step) is the same run to the bit, completing more.
#[test]
fn kane_s_run_completes_only_the_steps_it_reads() {
    let mut scene = scene("scenes/kane_double_pendulum.toml");
    scene.settings.t_end = 5.0;
    scene.settings.integrator.method = ricochet::integrate::Method::Dop853;
    scene.settings.integrator.rtol = 1e-10;
    scene.settings.integrator.atol = 1e-12;
    let mut runs = Vec::new();
    for rate in [0.0, 1000.0] {
        scene.settings.output_rate = rate;
        let mut sim =
            Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
        let mut rec = Recorder {
            keep_samples: rate > 0.0,
            ..Recorder::default()
        };
        let summary = sim.run(&scene.initial, &mut rec, None);
        assert_eq!(summary.stop.name(), "t_end");
        let c = sim.stepper_counters();
        assert_eq!(c.rhs_evals, summary.counters.rhs_evals);
        assert_eq!(
            c.rhs_evals,
            2 + STEP * (c.steps + c.rejected + c.resteps) + EXTRA * c.dense_completions + c.resets,
            "rate {rate}: {c:?}"
        );
        let eager = c.rhs_evals + EXTRA * (c.steps + c.resteps - c.dense_completions);
        println!(
            "output rate {rate}: {c:?}; eager dense output: {eager} evaluations, on demand {}",
            c.rhs_evals
        );
        runs.push((summary, rec, c));
    }
    let ((quiet, quiet_rec, cq), (sampled, sampled_rec, cs)) = (&runs[0], &runs[1]);
    assert!(cq.dense_completions < cq.steps + cq.resteps, "{cq:?}");
    assert!(
        cq.dense_completions < cs.dense_completions,
        "{cq:?} vs {cs:?}"
    );
    assert!(cs.dense_completions <= cs.steps + cs.resteps, "{cs:?}");
    assert_eq!(
        (cq.steps, cq.rejected, cq.resteps, cq.resets),
        (cs.steps, cs.rejected, cs.resteps, cs.resets)
    );
    assert_eq!(format!("{:?}", quiet.state), format!("{:?}", sampled.state));
    assert_eq!(format!("{:?}", quiet.audit), format!("{:?}", sampled.audit));
    assert_eq!(
        format!("{:?}", quiet_rec.impacts),
        format!("{:?}", sampled_rec.impacts)
    );
    assert_eq!(
        format!("{:?}", quiet_rec.transitions),
        format!("{:?}", sampled_rec.transitions)
    );
    assert!(sampled.counters.samples > 4000);
}

/// Reading a DOP853 step inside before completing it: a typed error and nothing written;
/// the locator that only reads the stepper says so too, the one given the system completes
/// it and finds the same event as on the completed step. A step or re-step that fails
/// after a step left pending loses its stages: completing is then an error, never a
/// polynomial of other stages.
#[test]
fn reading_before_completing_is_an_error() {
    let mut sys = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -9.81;
    });
    let mut s = dop853(2, 1e-10, 0.2);
    s.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
    s.step(&mut sys, 10.0).unwrap();
    assert!(!s.dense_complete());
    let (t0, t1) = (s.t_prev(), s.t());
    let mut y = [7.0; 2];
    let expected = DenseIncomplete { t_prev: t0, t: t1 };
    assert_eq!(s.dense(0.5 * (t0 + t1), &mut y), Err(expected));
    assert_eq!(s.dense_derivative(0.5 * (t0 + t1), &mut y), Err(expected));
    assert_eq!(y, [7.0; 2], "written");
    // A height crossed in the middle of the step (the fall is a parabola, which DOP853
    // integrates exactly): the locator samples inside the step.
    let tm = 0.5 * (t0 + t1);
    let mid = 1.0 - 0.5 * 9.81 * tm * tm;
    let mut gap = FnEvents::new(move |_t, y: &[f64], g: &mut [f64]| g[0] = y[0] - mid);
    let mut locator = EventLocator::new(2, 1, LocatorSettings::default());
    match locator.locate(&s, &mut gap, &[true]) {
        Err(EventError::Integrate(IntegrateError::DenseIncomplete(e))) => assert_eq!(e, expected),
        other => panic!("{other:?}"),
    }
    let before = s.counters().rhs_evals;
    let on_demand = locator
        .locate_completing_dense(&mut s, &mut sys, &mut gap, &[true])
        .unwrap();
    assert!(s.dense_complete());
    assert_eq!(s.counters().rhs_evals, before + EXTRA);
    let completed = locator.locate(&s, &mut gap, &[true]).unwrap();
    assert_eq!(on_demand, completed);
    assert!(on_demand.is_some());
    s.dense(0.5 * (t0 + t1), &mut y).unwrap();
    // A re-step that fails (here: a target outside the step is refused before any stage:
    // the step stays readable) …
    s.step(&mut sys, 10.0).unwrap();
    assert!(s.restep_to(&mut sys, s.t() + 1.0).is_err());
    s.complete_dense(&mut sys).unwrap();
    // … and one whose stages fail, through a system that fails after a number of calls.
    let mut calls = 0;
    let mut failing = Failing {
        left: &mut calls,
        after: 1000,
    };
    let mut f = dop853(1, 1e-8, 0.5);
    f.start(&mut failing, 0.0, &[1.0]).unwrap();
    f.step(&mut failing, 10.0).unwrap();
    assert!(!f.dense_complete());
    *failing.left = failing.after - 2;
    assert!(matches!(
        f.restep_to(&mut failing, 0.5 * (f.t_prev() + f.t())),
        Err(IntegrateError::Rhs { .. })
    ));
    *failing.left = 0;
    assert!(matches!(
        f.complete_dense(&mut failing),
        Err(IntegrateError::DenseIncomplete(_))
    ));
    assert!(f.dense(f.t(), &mut [0.0]).is_err());
}

/// A failing extra stage fails `complete_dense` with the time of that evaluation, leaves
/// the dense output incomplete, and a later completion (the system recovered) gives the
/// same numbers as a stepper that never failed.
#[test]
fn a_failing_extra_stage_is_returned_by_the_completion() {
    let mut calls = 0;
    let mut sys = Failing {
        left: &mut calls,
        after: 1000,
    };
    let mut s = dop853(1, 1e-8, 0.5);
    s.start(&mut sys, 0.0, &[1.0]).unwrap();
    s.step(&mut sys, 10.0).unwrap();
    let mut twin = s.clone();
    // The second extra stage fails: at t₀ + c₁₅ h.
    *sys.left = sys.after - 2;
    let (t0, h) = (s.t_prev(), s.t() - s.t_prev());
    let before = s.counters().rhs_evals;
    match s.complete_dense(&mut sys) {
        Err(IntegrateError::Rhs { t, .. }) => assert_eq!(t, t0 + extra_nodes()[1] * h),
        other => panic!("{other:?}"),
    }
    assert_eq!(s.counters().rhs_evals, before + 2);
    assert_eq!(s.counters().dense_completions, 0);
    assert!(!s.dense_complete());
    *sys.left = 0;
    s.complete_dense(&mut sys).unwrap();
    twin.complete_dense(&mut sys).unwrap();
    same_dense(&s, &twin, "after a failure");
}

/// The nodes `c₁₄, c₁₅, c₁₆` of DOP853's extra stages.
fn extra_nodes() -> &'static [f64] {
    match DOP853.dense {
        ricochet::integrate::tableau::DenseOutput::Extended { c, .. } => c,
        _ => unreachable!("DOP853's dense output has extra stages"),
    }
}

/// `ẏ = −y` that fails once `*left` reaches `after` evaluations.
struct Failing<'a> {
    left: &'a mut u64,
    after: u64,
}

#[derive(Debug, thiserror::Error)]
#[error("no value here")]
struct NoValue;

impl OdeSystem for Failing<'_> {
    type Error = NoValue;
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), NoValue> {
        *self.left += 1;
        if *self.left >= self.after {
            return Err(NoValue);
        }
        dy[0] = -y[0];
        Ok(())
    }
}
