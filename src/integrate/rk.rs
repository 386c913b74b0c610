//! [`RungeKutta`]: the one explicit Runge–Kutta stepper, driven by its
//! [`Tableau`](super::tableau::Tableau) — DOPRI5(4) and DOP853 with step-size control,
//! RK4 with a fixed step [HNW, II.1–6, II.10].
//!
//! A step evaluates the stages 2 … s of the tableau (stage 1 is the derivative at the
//! step's start, the previous step's last evaluation), the solution `y₁`, its derivative
//! `f(t₁, y₁)` (the next step's stage 1: FSAL), and the dense output's coefficients that
//! need no more evaluations. DOP853's three extra stages of its dense output (and its
//! `r₅ … r₈`) wait for [`Stepper::complete_dense`], called by whoever reads the step
//! inside: its stages `k₂ … k₁₂` stay in the work vectors until the next step or re-step
//! (`f(t₁, y₁)` is lent back from `f`), so the completion computes what the eager code
//! did, from the same bits. A step that is only read at its ends (the event location from
//! stand-ins, no output sample in it) does not pay for them. The adaptive methods weigh the
//! error estimate of their tableau with a PI controller [HNW, II.4]; RK4 takes `dt`. Event
//! location (`crate::events`), re-stepping to an event, resets and the counters work the
//! same for every method.
//!
//! Cost in evaluations of `f` per step (accepted or rejected) and per re-step: DOPRI5 6,
//! RK4 4, DOP853 12, plus 3 for DOP853's dense output where it is completed (at most once
//! per accepted step or re-step); at `start` 1, plus 1 for the initial step guess of an
//! adaptive method without `h_init`; 1 per reset. (Kane's pendulum, 5 s at rtol 1e-10 with
//! DOP853: 2 + 12 × (63 steps + 3 rejected + 27 re-steps) + 13 resets + 3 × 24 completed
//! dense outputs = 1203; completing all 90, as before, was 1401.)

use super::control::{
    PiController, after_failed_stage, clip_step, dop853_error_norm, error_norm, scaled_sq,
    smallest_step,
};
use super::dense::{Completion, Dense};
use super::error::{require_non_negative, require_positive};
use super::tableau::{DOP853, DOPRI5, DenseOutput, ErrorEstimate, RK4, Tableau};
use super::{
    Counters, DenseIncomplete, IntegrateError, Method, OdeSystem, SettingsError, StepOutcome,
    Stepper,
};
use crate::math::Real;
use crate::settings::IntegratorSettings;

/// Settings of an adaptive method (DOPRI5, DOP853).
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Relative tolerance (dimensionless).
    pub rtol: Real,
    /// Absolute tolerance (units of the state).
    pub atol: Real,
    /// Largest step (s); `Real::INFINITY` for none.
    pub h_max: Real,
    /// Smallest step the controller may reduce to before it gives up with
    /// [`IntegrateError::StepSizeTooSmall`] (s). The effective floor is
    /// `max(h_min, 10 ε |t|)`. Steps shortened to reach a stop time are exempt.
    pub h_min: Real,
    /// First step (s); `None` guesses it from `f(t₀, y₀)` [HNW, II.4, p. 169].
    pub h_init: Option<Real>,
    /// Safety factor of the controller (dimensionless, HNW: 0.9).
    pub safety: Real,
    /// PI stabilization exponent β (dimensionless; HNW's DOPRI5: 0.04, DOP853: 0; 0 is the
    /// classical I controller).
    pub beta: Real,
    /// Smallest step ratio `h_new / h` (dimensionless; HNW's DOPRI5: 0.2, DOP853: 0.333).
    pub fac_min: Real,
    /// Largest step ratio `h_new / h` (dimensionless; HNW's DOPRI5: 10, DOP853: 6).
    pub fac_max: Real,
}

/// The settings of DOPRI5 (the name they had before DOP853 shared them).
pub type Dopri5Settings = AdaptiveSettings;

impl Default for AdaptiveSettings {
    /// DOPRI5's, with the default run's tolerances.
    fn default() -> Self {
        Self::dopri5(&IntegratorSettings::default())
    }
}

impl From<&IntegratorSettings> for AdaptiveSettings {
    /// DOPRI5's controller constants with the run's tolerances and `h_max`.
    fn from(s: &IntegratorSettings) -> Self {
        Self::dopri5(s)
    }
}

impl AdaptiveSettings {
    /// The run's tolerances and `h_max` with the constants of Hairer's `DOPRI5`: safety
    /// 0.9, β = 0.04, step ratios in [0.2, 10].
    pub fn dopri5(s: &IntegratorSettings) -> Self {
        Self {
            rtol: s.rtol,
            atol: s.atol,
            h_max: s.h_max,
            h_min: 0.0,
            h_init: None,
            safety: 0.9,
            beta: 0.04,
            fac_min: 0.2,
            fac_max: 10.0,
        }
    }

    /// The run's tolerances and `h_max` with the constants of Hairer's `DOP853`: safety
    /// 0.9, β = 0, step ratios in [0.333, 6].
    pub fn dop853(s: &IntegratorSettings) -> Self {
        Self {
            beta: 0.0,
            fac_min: 0.333,
            fac_max: 6.0,
            ..Self::dopri5(s)
        }
    }

    /// Checks every field; at least one of `rtol`, `atol` must be positive.
    pub fn validate(&self) -> Result<(), SettingsError> {
        require_non_negative("rtol", self.rtol)?;
        require_non_negative("atol", self.atol)?;
        if self.rtol == 0.0 && self.atol == 0.0 {
            return Err(SettingsError {
                field: "atol",
                value: self.atol,
                reason: "rtol and atol cannot both be 0",
            });
        }
        require_h_max(self.h_max)?;
        require_non_negative("h_min", self.h_min)?;
        if let Some(h) = self.h_init {
            require_positive("h_init", h)?;
        }
        require_positive("safety", self.safety)?;
        require_non_negative("beta", self.beta)?;
        require_positive("fac_min", self.fac_min)?;
        if self.fac_min >= 1.0 {
            return Err(SettingsError {
                field: "fac_min",
                value: self.fac_min,
                reason: "must be < 1",
            });
        }
        if self.fac_max.is_nan() || self.fac_max <= 1.0 {
            return Err(SettingsError {
                field: "fac_max",
                value: self.fac_max,
                reason: "must be > 1",
            });
        }
        Ok(())
    }
}

/// Settings of the fixed-step method (RK4).
#[derive(Clone, Debug, PartialEq)]
pub struct Rk4Settings {
    /// The step (s). The last step before a stop time is shortened to land on it (or
    /// stretched by at most 1 % to avoid a sliver).
    pub dt: Real,
    /// Largest step (s), a cap on `dt`; `Real::INFINITY` for none.
    pub h_max: Real,
}

impl Default for Rk4Settings {
    fn default() -> Self {
        Self::from(&IntegratorSettings::default())
    }
}

impl From<&IntegratorSettings> for Rk4Settings {
    fn from(s: &IntegratorSettings) -> Self {
        Self {
            dt: s.dt,
            h_max: s.h_max,
        }
    }
}

impl Rk4Settings {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), SettingsError> {
        require_positive("dt", self.dt)?;
        require_h_max(self.h_max)
    }
}

fn require_h_max(h_max: Real) -> Result<(), SettingsError> {
    if h_max.is_nan() || h_max <= 0.0 {
        return Err(SettingsError {
            field: "h_max",
            value: h_max,
            reason: "must be > 0 (INFINITY for no cap)",
        });
    }
    Ok(())
}

/// What a stepper is built from: a method's settings (an [`AdaptiveSettings`] alone is
/// DOPRI5's, an [`Rk4Settings`] RK4's) or the run's [`IntegratorSettings`] (its method).
pub trait StepperConfig {
    /// The stepper for systems of dimension `n`.
    fn build(self, n: usize) -> Result<RungeKutta, SettingsError>;
}

impl StepperConfig for AdaptiveSettings {
    fn build(self, n: usize) -> Result<RungeKutta, SettingsError> {
        RungeKutta::dopri5(n, self)
    }
}

impl StepperConfig for Rk4Settings {
    fn build(self, n: usize) -> Result<RungeKutta, SettingsError> {
        RungeKutta::rk4(n, self)
    }
}

impl StepperConfig for &IntegratorSettings {
    /// The stepper of `settings.method` with the run's tolerances, `dt` and `h_max` (the
    /// other settings at the method's defaults). A [`SettingsError`] for
    /// [`Method::MoreauJean`], which is not an ODE stepper.
    fn build(self, n: usize) -> Result<RungeKutta, SettingsError> {
        match self.method {
            Method::Dopri5 => RungeKutta::dopri5(n, AdaptiveSettings::dopri5(self)),
            Method::Dop853 => RungeKutta::dop853(n, AdaptiveSettings::dop853(self)),
            Method::Rk4 => RungeKutta::rk4(n, Rk4Settings::from(self)),
            Method::MoreauJean => Err(SettingsError {
                field: "method",
                value: Real::NAN,
                reason: "moreau-jean is a time-stepping scheme with its own loop \
                         (sim::MoreauJean), not an ODE stepper: run it with MoreauJean, \
                         not Simulation",
            }),
        }
    }
}

/// How the step is chosen.
#[derive(Clone, Debug)]
enum Control {
    /// By the error estimate: the settings, the controller and the next step to try (s).
    Adaptive {
        settings: AdaptiveSettings,
        ctrl: PiController,
        h: Real,
    },
    /// `dt`.
    Fixed { settings: Rk4Settings },
}

/// A row of coefficients without its zeros: `(stage index from 0, coefficient)`.
type Row = Vec<(usize, Real)>;

fn sparse(row: &[Real]) -> Row {
    (row.iter().enumerate())
        .filter(|&(_, &a)| a != 0.0)
        .map(|(j, &a)| (j, a))
        .collect()
}

/// The tableau's rows without their zeros (built once with the stepper).
#[derive(Clone, Debug)]
struct Plan {
    /// Rows 2 … s, then the rows of the dense output's extra stages.
    a: Vec<Row>,
    b: Row,
    /// `e` (DOPRI5) or `ê₅` (DOP853).
    e: Row,
    /// `ê₃` (DOP853).
    e3: Row,
    /// The dense output's weights: Shampine's `d`, or DOP853's four rows.
    d: Vec<Row>,
}

impl Plan {
    fn of(tab: &Tableau) -> Self {
        let mut a: Vec<Row> = tab.a.iter().map(|r| sparse(r)).collect();
        let (e, e3) = match tab.error {
            ErrorEstimate::None => (Row::new(), Row::new()),
            ErrorEstimate::Embedded { e } => (sparse(e), Row::new()),
            ErrorEstimate::Dop853 { e5, e3 } => (sparse(e5), sparse(e3)),
        };
        let d = match tab.dense {
            DenseOutput::Hermite => Vec::new(),
            DenseOutput::Shampine { d } => vec![sparse(d)],
            DenseOutput::Extended { a: extra, d, .. } => {
                a.extend(extra.iter().map(|r| sparse(r)));
                d.iter().map(|r| sparse(r)).collect()
            }
        };
        Self {
            a,
            b: sparse(tab.b),
            e,
            e3,
            d,
        }
    }
}

/// The vectors of one step, allocated once.
#[derive(Clone, Debug)]
struct Work {
    /// Stages 2 …: `k[j − 1]` is the stage of index `j` (0-based; index 0 is `k₁`, kept by
    /// the stepper), up to `f(t₁, y₁)` and the extra stages of the dense output.
    k: Vec<Vec<Real>>,
    /// Argument of the current stage.
    y_stage: Vec<Real>,
    /// The solution `y₁`.
    y_new: Vec<Real>,
    /// The error estimate (DOPRI5: `h Σ eⱼ kⱼ`; DOP853: `Σ ê₅ⱼ kⱼ`).
    err: Vec<Real>,
    /// DOP853's `Σ ê₃ⱼ kⱼ`.
    err3: Vec<Real>,
}

impl Work {
    fn new(tab: &Tableau, n: usize) -> Self {
        let extra = (tab.evaluations_per_step() as usize) - tab.stages();
        let dop853 = matches!(tab.error, ErrorEstimate::Dop853 { .. });
        Self {
            k: vec![vec![0.0; n]; tab.stages() + extra],
            y_stage: vec![0.0; n],
            y_new: vec![0.0; n],
            err: vec![0.0; n],
            err3: if dop853 { vec![0.0; n] } else { Vec::new() },
        }
    }

    fn resize(&mut self, n: usize) {
        for v in self
            .k
            .iter_mut()
            .chain([&mut self.y_stage, &mut self.y_new])
        {
            v.resize(n, 0.0);
        }
        self.err.resize(n, 0.0);
        if !self.err3.is_empty() {
            self.err3.resize(n, 0.0);
        }
    }

    /// `f(t₁, y₁)`, the stage after the last of a tableau with `s` stages.
    fn f_new(&self, s: usize) -> &[Real] {
        &self.k[s - 1]
    }
}

/// The stages `k₁ … k_m`: `k₁` and the computed ones, stage `j` (from 0) as a slice
/// ([`Self::get`]). Two references, not an array of the slices: that one (256 bytes) was
/// built and copied (`memcpy`) for every stage of every step.
#[derive(Clone, Copy)]
struct StageSlices<'a> {
    k1: &'a [Real],
    done: &'a [Vec<Real>],
}

impl<'a> StageSlices<'a> {
    /// Stage `j`: `k₁` for `j = 0`, else the computed stage `j − 1` (empty if not computed).
    #[inline(always)]
    fn get(&self, j: usize) -> &'a [Real] {
        match j.checked_sub(1) {
            None => self.k1,
            Some(i) => self.done.get(i).map_or(&[], |k| k.as_slice()),
        }
    }
}

/// The stages `k₁ … k_m` as slices: `k₁` and the computed ones.
fn stage_slices<'a>(k1: &'a [Real], done: &'a [Vec<Real>]) -> StageSlices<'a> {
    StageSlices { k1, done }
}

/// `out = base + h Σⱼ aⱼ kⱼ` for a row of `A`, summed from left to right; a row with a
/// single coefficient as `base + (h a) k` (see [`Tableau`]).
fn stage_argument(out: &mut [Real], base: &[Real], h: Real, row: &Row, k: StageSlices<'_>) {
    if let [(j, a)] = row[..] {
        let ha = h * a;
        for ((o, y0), k) in out.iter_mut().zip(base).zip(k.get(j)) {
            *o = y0 + ha * k;
        }
        return;
    }
    weighted_sum(out, row, k);
    for (o, y0) in out.iter_mut().zip(base) {
        *o = y0 + h * *o;
    }
}

/// `out = Σⱼ aⱼ kⱼ`, each element summed from left to right over the nonzero coefficients
/// (0 for none). The sum runs over `j` outside and the elements inside, so that each
/// `kⱼ` is read as one contiguous slice (no bounds check per term, vector instructions):
/// element by element the operations and their order are those of `Σⱼ` written per
/// element, so the result is the same to the bit.
#[inline]
fn weighted_sum(out: &mut [Real], row: &Row, k: StageSlices<'_>) {
    let Some(&(j0, a0)) = row.first() else {
        out.fill(0.0);
        return;
    };
    for (o, k) in out.iter_mut().zip(k.get(j0)) {
        *o = a0 * k;
    }
    for &(j, a) in &row[1..] {
        for (o, k) in out.iter_mut().zip(k.get(j)) {
            *o += a * k;
        }
    }
}

/// `out = factor · Σⱼ wⱼ kⱼ` (`out = base + factor · Σ` with a base).
fn combination(
    out: &mut [Real],
    base: Option<&[Real]>,
    factor: Real,
    row: &Row,
    k: StageSlices<'_>,
) {
    weighted_sum(out, row, k);
    match base {
        Some(base) => {
            for (o, b) in out.iter_mut().zip(base) {
                *o = b + factor * *o;
            }
        }
        None => {
            for o in out.iter_mut() {
                *o *= factor;
            }
        }
    }
}

/// Evaluates `f` and counts it; a failure carries its time.
#[inline]
fn eval<S: OdeSystem>(
    sys: &mut S,
    t: Real,
    y: &[Real],
    dy: &mut [Real],
    counters: &mut Counters,
) -> Result<(), IntegrateError<S::Error>> {
    counters.rhs_evals += 1;
    sys.rhs(t, y, dy)
        .map_err(|source| IntegrateError::Rhs { t, source })
}

/// One step of the tableau from `(t0, y0)` with `k1 = f(t0, y0)` to `t1`
/// [HNW, II.1, Eq. (1.8)]: the stages 2 … s, `y₁ = y₀ + (h / b_den) Σ bⱼ kⱼ` and
/// `k_{s+1} = f(t₁, y₁)`.
#[allow(clippy::too_many_arguments)]
fn stages<S: OdeSystem>(
    tab: &Tableau,
    plan: &Plan,
    sys: &mut S,
    t0: Real,
    y0: &[Real],
    k1: &[Real],
    t1: Real,
    w: &mut Work,
    counters: &mut Counters,
) -> Result<(), IntegrateError<S::Error>> {
    let h = t1 - t0;
    let s = tab.stages();
    for j in 1..s {
        let (done, rest) = w.k.split_at_mut(j - 1);
        let k = stage_slices(k1, done);
        stage_argument(&mut w.y_stage, y0, h, &plan.a[j - 1], k);
        let c = tab.c[j];
        let t = if c == 1.0 { t1 } else { t0 + c * h };
        eval(sys, t, &w.y_stage, &mut rest[0], counters)?;
    }
    let (done, rest) = w.k.split_at_mut(s - 1);
    let k = stage_slices(k1, done);
    combination(&mut w.y_new, Some(y0), h / tab.b_den, &plan.b, k);
    eval(sys, t1, &w.y_new, &mut rest[0], counters)
}

/// The continuous extension of the step `[t0, t0 + h]` just taken by [`stages`], as far
/// as it needs no more evaluations of `f`: the Hermite part, then Shampine's `r₅`; DOP853's
/// `r₅ … r₈` are left pending for [`extended_dense`] (its extra stages evaluated only if
/// the step is read inside).
#[allow(clippy::too_many_arguments)]
fn dense_output(
    tab: &Tableau,
    plan: &Plan,
    t0: Real,
    h: Real,
    y0: &[Real],
    k1: &[Real],
    w: &Work,
    dense: &mut Dense,
) {
    let s = tab.stages();
    dense.set_hermite(t0, h, y0, k1, &w.y_new, w.f_new(s));
    match tab.dense {
        DenseOutput::Hermite => {}
        DenseOutput::Shampine { .. } => {
            let k = stage_slices(k1, &w.k);
            combination(&mut dense.r5, None, h, &plan.d[0], k);
        }
        DenseOutput::Extended { .. } => dense.completion = Completion::Pending,
    }
}

/// DOP853's extra stages of the step `[t0, t0 + h]` from `(y0, k1)`, whose stages
/// `k₂ … k_{s+1}` are in `w.k` (as [`stages`] left them), and `r₅ … r₈`: the numbers
/// [`dense_output`] would have computed right after the step, from the same inputs;
/// counted in `counters.dense_completions`.
#[allow(clippy::too_many_arguments)]
fn extended_dense<S: OdeSystem>(
    tab: &Tableau,
    plan: &Plan,
    sys: &mut S,
    (t0, h): (Real, Real),
    y0: &[Real],
    k1: &[Real],
    w: &mut Work,
    dense: &mut Dense,
    counters: &mut Counters,
) -> Result<(), IntegrateError<S::Error>> {
    let DenseOutput::Extended { c, .. } = tab.dense else {
        return Ok(());
    };
    let s = tab.stages();
    for (m, &c) in c.iter().enumerate() {
        // Stage index j = s + 1 + m (after f(t₁, y₁), index s); its row follows rows
        // 2 … s in the plan.
        let j = s + 1 + m;
        let (done, rest) = w.k.split_at_mut(j - 1);
        let k = stage_slices(k1, done);
        stage_argument(&mut w.y_stage, y0, h, &plan.a[s - 1 + m], k);
        eval(sys, t0 + c * h, &w.y_stage, &mut rest[0], counters)?;
    }
    let k = stage_slices(k1, &w.k);
    let [r6, r7, r8] = &mut dense.r678;
    for (r, d) in [&mut dense.r5, r6, r7, r8].into_iter().zip(&plan.d) {
        combination(r, None, h, d, k);
    }
    dense.completion = Completion::Done;
    counters.dense_completions += 1;
    Ok(())
}

/// Whether every component is finite.
#[inline]
pub(crate) fn all_finite(v: &[Real]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The explicit Runge–Kutta stepper, driven by its [`Tableau`]: [DOPRI5](Self::dopri5)
/// and [DOP853](Self::dop853) with step-size control, [RK4](Self::rk4) with a fixed step.
///
/// ```
/// use ricochet::integrate::{AdaptiveSettings, FnSystem, RungeKutta, StepOutcome, Stepper};
/// use ricochet::settings::IntegratorSettings;
/// // ẏ = −y, y(0) = 1, to t = 1, with DOP853.
/// let mut sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| dy[0] = -y[0]);
/// let run = IntegratorSettings { rtol: 1e-12, atol: 1e-14, ..Default::default() };
/// let mut rk = RungeKutta::dop853(1, AdaptiveSettings::dop853(&run)).unwrap();
/// rk.start(&mut sys, 0.0, &[1.0]).unwrap();
/// while rk.step(&mut sys, 1.0).unwrap() != StepOutcome::ReachedStop {}
/// assert!((rk.y()[0] - (-1.0f64).exp()).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct RungeKutta {
    method: Method,
    tableau: &'static Tableau,
    plan: Plan,
    control: Control,
    n: usize,
    started: bool,
    /// Current time (s) and state, with `f = f(t, y)` (the FSAL stage).
    t: Real,
    y: Vec<Real>,
    f: Vec<Real>,
    /// Start of the last step, its state and derivative.
    t_prev: Real,
    y_prev: Vec<Real>,
    f_prev: Vec<Real>,
    /// End of the last accepted step (re-steps may not go beyond it) (s).
    t_end: Real,
    work: Work,
    dense: Dense,
    h_max: Real,
    counters: Counters,
    /// Complete the dense output inside every step and re-step, from the stages where
    /// they stand (the code before the extra stages were evaluated on demand): the oracle
    /// of the tests ([`Self::set_eager_dense`]).
    eager_dense: bool,
}

/// The stepper of the run's method (the name of the enum it replaces).
pub type AnyStepper = RungeKutta;
/// DOPRI5 is a [`RungeKutta`] built from [`Dopri5Settings`].
pub type Dopri5 = RungeKutta;
/// RK4 is a [`RungeKutta`] built from [`Rk4Settings`].
pub type Rk4 = RungeKutta;

impl RungeKutta {
    /// The stepper `config` describes (an [`AdaptiveSettings`] alone: DOPRI5; an
    /// [`Rk4Settings`]: RK4; the run's [`IntegratorSettings`]: its method) for systems of
    /// dimension `n`. Every vector is allocated here; `start` resizes them if the system's
    /// dimension differs.
    pub fn new(n: usize, config: impl StepperConfig) -> Result<Self, SettingsError> {
        config.build(n)
    }

    /// DOPRI5(4) [Dormand & Prince 1980; HNW, II.5] with Shampine's dense output.
    pub fn dopri5(n: usize, settings: AdaptiveSettings) -> Result<Self, SettingsError> {
        Self::adaptive(Method::Dopri5, &DOPRI5, n, settings)
    }

    /// DOP853 [HNW, II.10] with its dense output of order 7.
    pub fn dop853(n: usize, settings: AdaptiveSettings) -> Result<Self, SettingsError> {
        Self::adaptive(Method::Dop853, &DOP853, n, settings)
    }

    /// RK4 with a fixed step and the cubic Hermite dense output.
    pub fn rk4(n: usize, settings: Rk4Settings) -> Result<Self, SettingsError> {
        settings.validate()?;
        let h_max = settings.h_max;
        Ok(Self::with(
            Method::Rk4,
            &RK4,
            n,
            Control::Fixed { settings },
            h_max,
        ))
    }

    fn adaptive(
        method: Method,
        tableau: &'static Tableau,
        n: usize,
        settings: AdaptiveSettings,
    ) -> Result<Self, SettingsError> {
        settings.validate()?;
        let ctrl = PiController::new(
            tableau.controller,
            settings.safety,
            settings.beta,
            settings.fac_min,
            settings.fac_max,
        );
        let h_max = settings.h_max;
        let control = Control::Adaptive {
            settings,
            ctrl,
            h: 0.0,
        };
        Ok(Self::with(method, tableau, n, control, h_max))
    }

    fn with(
        method: Method,
        tableau: &'static Tableau,
        n: usize,
        control: Control,
        h_max: Real,
    ) -> Self {
        let dense = match tableau.dense {
            DenseOutput::Extended { .. } => Dense::septic(n),
            _ => Dense::new(n),
        };
        Self {
            method,
            tableau,
            plan: Plan::of(tableau),
            control,
            n,
            started: false,
            t: 0.0,
            y: vec![0.0; n],
            f: vec![0.0; n],
            t_prev: 0.0,
            y_prev: vec![0.0; n],
            f_prev: vec![0.0; n],
            t_end: 0.0,
            work: Work::new(tableau, n),
            dense,
            h_max,
            counters: Counters::default(),
            eager_dense: false,
        }
    }

    /// The method's tableau.
    pub fn tableau(&self) -> &'static Tableau {
        self.tableau
    }

    /// The settings of an adaptive method (`None` for RK4).
    pub fn adaptive_settings(&self) -> Option<&AdaptiveSettings> {
        match &self.control {
            Control::Adaptive { settings, .. } => Some(settings),
            Control::Fixed { .. } => None,
        }
    }

    /// Sets the smallest step of an adaptive method (s; ignored unless finite and ≥ 0, and
    /// by RK4): below `max(h_min, 10 ε |t|)` it gives up with
    /// [`IntegrateError::StepSizeTooSmall`].
    pub fn set_h_min(&mut self, h_min: Real) {
        if let Control::Adaptive { settings, .. } = &mut self.control
            && h_min.is_finite()
            && h_min >= 0.0
        {
            settings.h_min = h_min;
        }
    }

    /// With `true`, DOP853 completes its dense output inside every accepted step and
    /// re-step, from the stages where they stand, as before it was completed on demand
    /// (then [`Stepper::complete_dense`] has nothing to do): the oracle of the tests, whose
    /// dense values the completion on demand must give bit for bit. A failing extra stage
    /// then fails the step or re-step. Default `false`.
    pub fn set_eager_dense(&mut self, eager: bool) {
        self.eager_dense = eager;
    }

    /// The step the next call of [`step`](Stepper::step) will try first, before capping
    /// by `h_max` and the stop time (s): the controller's suggestion, or `dt`.
    pub fn h_next(&self) -> Real {
        match &self.control {
            Control::Adaptive { h, .. } => *h,
            Control::Fixed { settings } => settings.dt,
        }
    }

    fn resize(&mut self, n: usize) {
        if n != self.n {
            self.n = n;
            for v in [&mut self.y, &mut self.f, &mut self.y_prev, &mut self.f_prev] {
                v.resize(n, 0.0);
            }
            self.work.resize(n);
            self.dense.resize(n);
        }
    }

    /// Sets `(t, y)`, evaluates `f(t, y)` and makes the last step empty at `t`.
    fn set_state<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        y: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        let n = sys.dim();
        if y.len() != n {
            return Err(IntegrateError::Dimension {
                expected: n,
                got: y.len(),
            });
        }
        self.resize(n);
        if !t.is_finite() || !all_finite(y) {
            return Err(IntegrateError::NonFinite { t });
        }
        self.y.copy_from_slice(y);
        eval(sys, t, &self.y, &mut self.f, &mut self.counters)?;
        if !all_finite(&self.f) {
            return Err(IntegrateError::NonFinite { t });
        }
        self.t = t;
        self.t_prev = t;
        self.t_end = t;
        self.y_prev.copy_from_slice(&self.y);
        self.f_prev.copy_from_slice(&self.f);
        self.dense.set_empty(t);
        if let Control::Adaptive { ctrl, .. } = &mut self.control {
            ctrl.restart();
        }
        Ok(())
    }

    /// The initial step guess of [HNW, II.4, p. 169] (Hairer's `HINIT`, of the method's
    /// order `p`): from `d₀ = ‖y₀‖`, `d₁ = ‖f₀‖` take `h₀ = 0.01 d₀/d₁`, an explicit Euler
    /// step gives `d₂ ≈ ‖ÿ‖`, and `h = min(100 h₀, (0.01 / max(d₁, d₂))^(1/p), h_max)`.
    /// One evaluation of `f`.
    fn initial_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        rtol: Real,
        atol: Real,
    ) -> Result<Real, IntegrateError<S::Error>> {
        let m = sys.controlled().min(self.n);
        let dnf = scaled_sq(&self.f[..m], &self.y[..m], rtol, atol);
        let dny = scaled_sq(&self.y[..m], &self.y[..m], rtol, atol);
        let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
            1e-6
        } else {
            (dny / dnf).sqrt() * 0.01
        };
        h = h.min(self.h_max);
        // Explicit Euler step to estimate the second derivative.
        let w = &mut self.work;
        for i in 0..self.n {
            w.y_stage[i] = self.y[i] + h * self.f[i];
        }
        eval(sys, self.t + h, &w.y_stage, &mut w.k[0], &mut self.counters)?;
        for i in 0..self.n {
            w.err[i] = w.k[0][i] - self.f[i];
        }
        let der2 = scaled_sq(&w.err[..m], &self.y[..m], rtol, atol).sqrt() / h;
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 || !der12.is_finite() {
            (h * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(1.0 / Real::from(self.tableau.order))
        };
        Ok((100.0 * h).min(h1).min(self.h_max))
    }

    /// The error norm of the step just taken by [`stages`] from `(t, y)`, or NaN when
    /// `y₁` is not finite.
    fn error_of_step(&mut self, m: usize, h: Real, rtol: Real, atol: Real) -> Real {
        let w = &mut self.work;
        if !all_finite(&w.y_new) {
            return Real::NAN;
        }
        let k = stage_slices(&self.f, &w.k);
        match self.tableau.error {
            ErrorEstimate::None => 0.0,
            ErrorEstimate::Embedded { .. } => {
                combination(&mut w.err, None, h, &self.plan.e, k);
                error_norm(&w.err[..m], &self.y[..m], &w.y_new[..m], rtol, atol)
            }
            ErrorEstimate::Dop853 { .. } => {
                combination(&mut w.err, None, 1.0, &self.plan.e, k);
                combination(&mut w.err3, None, 1.0, &self.plan.e3, k);
                dop853_error_norm(
                    &w.err[..m],
                    &w.err3[..m],
                    &self.y[..m],
                    &w.y_new[..m],
                    rtol,
                    atol,
                    h,
                )
            }
        }
    }

    /// Makes the step `[t, t1]` of length `h` just taken the last step (`t1` is `t + h`
    /// or the stop time: the dense output takes `h`, not `t1 − t`): its dense output
    /// (DOP853's pending, or completed with `eager_dense`), then
    /// `(y_prev, f_prev) ← (y, f) ← (y₁, f(t₁, y₁))`.
    fn accept<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t1: Real,
        h: Real,
    ) -> Result<(), IntegrateError<S::Error>> {
        let s = self.tableau.stages();
        dense_output(
            self.tableau,
            &self.plan,
            self.t,
            h,
            &self.y,
            &self.f,
            &self.work,
            &mut self.dense,
        );
        self.complete_eagerly(sys, (self.t, h), false)?;
        std::mem::swap(&mut self.y_prev, &mut self.y);
        std::mem::swap(&mut self.y, &mut self.work.y_new);
        std::mem::swap(&mut self.f_prev, &mut self.f);
        std::mem::swap(&mut self.f, &mut self.work.k[s - 1]);
        self.t_prev = self.t;
        self.t = t1;
        self.t_end = t1;
        self.counters.steps += 1;
        Ok(())
    }

    /// With `eager_dense`, completes the dense output of the step `(t0, h)` just taken,
    /// before its stages move: from `(y_prev, f_prev)` for a re-step, else `(y, f)`.
    fn complete_eagerly<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        step: (Real, Real),
        restep: bool,
    ) -> Result<(), IntegrateError<S::Error>> {
        if !self.eager_dense || self.dense.completion != Completion::Pending {
            return Ok(());
        }
        let (y0, k1) = if restep {
            (&self.y_prev, &self.f_prev)
        } else {
            (&self.y, &self.f)
        };
        extended_dense(
            self.tableau,
            &self.plan,
            sys,
            step,
            y0,
            k1,
            &mut self.work,
            &mut self.dense,
            &mut self.counters,
        )
    }

    /// Before [`stages`] overwrites the work vectors: pending extra stages of the last
    /// step can no longer be evaluated (the call fails, or makes a new last step).
    fn overwrite_stages(&mut self) {
        if self.dense.completion == Completion::Pending {
            self.dense.completion = Completion::Lost;
        }
    }

    /// One accepted adaptive step (rejected ones retried inside).
    fn step_adaptive<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_stop: Real,
    ) -> Result<StepOutcome, IntegrateError<S::Error>> {
        let Control::Adaptive { settings, .. } = &self.control else {
            unreachable!("step_adaptive on a fixed-step method");
        };
        let (rtol, atol, h_min_setting) = (settings.rtol, settings.atol, settings.h_min);
        let mut non_finite_rejections = 0u32;
        let mut rhs_failures = 0u32;
        loop {
            let h_try = self.h_next();
            let (h, reaches) = clip_step(h_try, self.h_max, t_stop - self.t);
            // The controller's own step below the floor (not one capped by h_max or
            // shortened to the stop): accepted steps that small cannot bring the run
            // anywhere, however long it runs (a first step of 1e-126 s at t = 0).
            let h_min = smallest_step(h_min_setting, self.t);
            if !reaches && h_try < h_min && h_try < self.h_max {
                return Err(IntegrateError::StepSizeTooSmall {
                    t: self.t,
                    h: h_try,
                    h_min,
                });
            }
            let t1 = if reaches { t_stop } else { self.t + h };
            // A right-hand side that fails at a trial stage (a state the accepted solution
            // never reaches, such as a contact problem without solution far from it)
            // rejects the step: it shrinks by 4 and is tried again, down to the smallest
            // step (or 30 failures in a row, a factor 1e18), where the failure is returned.
            // Stage 1 is the accepted state, already evaluated: a failure there is never
            // retried. (The extra stages of the dense output come after acceptance, in
            // `complete_dense`; a failure there is returned by it.)
            match stages(
                self.tableau,
                &self.plan,
                sys,
                self.t,
                &self.y,
                &self.f,
                t1,
                &mut self.work,
                &mut self.counters,
            ) {
                Ok(()) => {}
                Err(e @ IntegrateError::Rhs { .. }) => {
                    self.counters.rejected += 1;
                    let h_min = smallest_step(h_min_setting, self.t);
                    let Some(h_new) = after_failed_stage(h, &mut rhs_failures, h_min) else {
                        return Err(e);
                    };
                    self.set_h_next(h_new);
                    continue;
                }
                Err(e) => return Err(e),
            }
            let m = sys.controlled().min(self.n);
            // The estimate of the step as taken, `t1 − t` (`h` may differ from it in its
            // last bits; the controller and the dense output take `h`, as before).
            let err = self.error_of_step(m, t1 - self.t, rtol, atol);
            let Control::Adaptive { ctrl, .. } = &mut self.control else {
                unreachable!();
            };
            let verdict = ctrl.judge(h, err);
            if verdict.accept {
                self.accept(sys, t1, h)?;
                // A step shortened to land on t_stop says little about the step the
                // solution allows (its growth is clamped at fac_max): keep the larger of
                // the two suggestions. A step capped by h_max informs the controller as
                // usual.
                let shortened_for_stop = reaches && h < h_try.min(self.h_max);
                self.set_h_next(if shortened_for_stop {
                    verdict.h_new.max(h_try)
                } else {
                    verdict.h_new
                });
                return Ok(if reaches {
                    StepOutcome::ReachedStop
                } else {
                    StepOutcome::Advanced
                });
            }
            self.counters.rejected += 1;
            let h_min = smallest_step(h_min_setting, self.t);
            if err.is_finite() {
                non_finite_rejections = 0;
            } else {
                non_finite_rejections += 1;
                if non_finite_rejections >= 40 {
                    return Err(IntegrateError::NonFinite { t: self.t });
                }
            }
            if verdict.h_new < h_min {
                if err.is_finite() {
                    return Err(IntegrateError::StepSizeTooSmall {
                        t: self.t,
                        h: verdict.h_new,
                        h_min,
                    });
                }
                return Err(IntegrateError::NonFinite { t: self.t });
            }
            self.set_h_next(verdict.h_new);
        }
    }

    /// The error of reading the last step's dense output before it is complete.
    fn incomplete(&self) -> DenseIncomplete {
        DenseIncomplete {
            t_prev: self.t_prev,
            t: self.t,
        }
    }

    fn set_h_next(&mut self, h_new: Real) {
        if let Control::Adaptive { h, .. } = &mut self.control {
            *h = h_new;
        }
    }

    /// One fixed step (shortened after failing stages).
    fn step_fixed<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_stop: Real,
    ) -> Result<StepOutcome, IntegrateError<S::Error>> {
        let (mut h, mut reaches) = clip_step(self.h_next(), self.h_max, t_stop - self.t);
        let mut t1 = if reaches { t_stop } else { self.t + h };
        // A right-hand side that fails at a trial stage (a state the solution never
        // reaches) shortens this step by 4 and tries again, at most 30 times (a factor
        // 1e18) and down to `10 ε |t|`, where the failure is returned; the next step is
        // `dt` again. Stage 1 is the accepted state, already evaluated: a failure there is
        // never retried.
        let mut failures = 0u32;
        loop {
            match stages(
                self.tableau,
                &self.plan,
                sys,
                self.t,
                &self.y,
                &self.f,
                t1,
                &mut self.work,
                &mut self.counters,
            ) {
                Ok(()) => break,
                Err(e @ IntegrateError::Rhs { .. }) => {
                    self.counters.rejected += 1;
                    let h_min = smallest_step(0.0, self.t);
                    let Some(h_new) = after_failed_stage(h, &mut failures, h_min) else {
                        return Err(e);
                    };
                    h = h_new;
                    reaches = false;
                    t1 = self.t + h;
                }
                Err(e) => return Err(e),
            }
        }
        let s = self.tableau.stages();
        if !all_finite(&self.work.y_new) || !all_finite(self.work.f_new(s)) {
            return Err(IntegrateError::NonFinite { t: t1 });
        }
        self.accept(sys, t1, h)?;
        Ok(if reaches {
            StepOutcome::ReachedStop
        } else {
            StepOutcome::Advanced
        })
    }
}

impl Stepper for RungeKutta {
    fn method(&self) -> Method {
        self.method
    }

    fn start<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: Real,
        y0: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        self.started = false;
        self.set_state(sys, t0, y0)?;
        if let Control::Adaptive { settings, .. } = &self.control {
            let h = match settings.h_init {
                Some(h) => h,
                None => {
                    let (rtol, atol) = (settings.rtol, settings.atol);
                    self.initial_step(sys, rtol, atol)?
                }
            };
            self.set_h_next(h);
        }
        self.started = true;
        Ok(())
    }

    fn step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_stop: Real,
    ) -> Result<StepOutcome, IntegrateError<S::Error>> {
        if !self.started {
            return Err(IntegrateError::NotStarted);
        }
        if t_stop.is_nan() || t_stop <= self.t {
            return Err(IntegrateError::StopNotAhead { t: self.t, t_stop });
        }
        self.overwrite_stages();
        match self.control {
            Control::Adaptive { .. } => self.step_adaptive(sys, t_stop),
            Control::Fixed { .. } => self.step_fixed(sys, t_stop),
        }
    }

    fn restep_to<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_target: Real,
    ) -> Result<(), IntegrateError<S::Error>> {
        if !self.started {
            return Err(IntegrateError::NotStarted);
        }
        if t_target == self.t_prev {
            self.y.copy_from_slice(&self.y_prev);
            self.f.copy_from_slice(&self.f_prev);
            self.t = self.t_prev;
            self.dense.set_empty(self.t_prev);
            return Ok(());
        }
        if t_target.is_nan() || t_target < self.t_prev || t_target > self.t_end {
            return Err(IntegrateError::RestepOutOfRange {
                t_target,
                t_prev: self.t_prev,
                t_end: self.t_end,
            });
        }
        let t0 = self.t_prev;
        self.overwrite_stages();
        stages(
            self.tableau,
            &self.plan,
            sys,
            t0,
            &self.y_prev,
            &self.f_prev,
            t_target,
            &mut self.work,
            &mut self.counters,
        )?;
        self.counters.resteps += 1;
        let s = self.tableau.stages();
        if !all_finite(&self.work.y_new) || !all_finite(self.work.f_new(s)) {
            return Err(IntegrateError::NonFinite { t: t_target });
        }
        dense_output(
            self.tableau,
            &self.plan,
            t0,
            t_target - t0,
            &self.y_prev,
            &self.f_prev,
            &self.work,
            &mut self.dense,
        );
        self.complete_eagerly(sys, (t0, t_target - t0), true)?;
        std::mem::swap(&mut self.y, &mut self.work.y_new);
        std::mem::swap(&mut self.f, &mut self.work.k[s - 1]);
        self.t = t_target;
        Ok(())
    }

    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        y: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        if !self.started {
            return Err(IntegrateError::NotStarted);
        }
        self.counters.resets += 1;
        self.set_state(sys, t, y)?;
        let h_max = self.h_max;
        if let Control::Adaptive { h, .. } = &mut self.control {
            *h = h.min(h_max);
        }
        Ok(())
    }

    fn t(&self) -> Real {
        self.t
    }
    fn y(&self) -> &[Real] {
        &self.y
    }
    fn dy(&self) -> &[Real] {
        &self.f
    }
    fn t_prev(&self) -> Real {
        self.t_prev
    }
    fn y_prev(&self) -> &[Real] {
        &self.y_prev
    }
    fn dy_prev(&self) -> &[Real] {
        &self.f_prev
    }

    fn complete_dense<S: OdeSystem>(
        &mut self,
        sys: &mut S,
    ) -> Result<(), IntegrateError<S::Error>> {
        match self.dense.completion {
            Completion::Done => return Ok(()),
            Completion::Lost => return Err(self.incomplete().into()),
            Completion::Pending => {}
        }
        // f(t₁, y₁), the stage after the last, went to `self.f` when the step was
        // accepted: lent back to the work vectors for the extra stages' rows.
        let s = self.tableau.stages();
        std::mem::swap(&mut self.f, &mut self.work.k[s - 1]);
        let done = extended_dense(
            self.tableau,
            &self.plan,
            sys,
            (self.dense.t0, self.dense.h),
            &self.y_prev,
            &self.f_prev,
            &mut self.work,
            &mut self.dense,
            &mut self.counters,
        );
        std::mem::swap(&mut self.f, &mut self.work.k[s - 1]);
        done
    }

    fn dense_complete(&self) -> bool {
        self.dense.completion == Completion::Done
    }

    fn dense(&self, t: Real, out: &mut [Real]) -> Result<(), DenseIncomplete> {
        if !self.dense_complete() {
            return Err(self.incomplete());
        }
        self.dense.eval(&self.y_prev, t, out);
        Ok(())
    }

    fn dense_derivative(&self, t: Real, out: &mut [Real]) -> Result<(), DenseIncomplete> {
        if !self.dense_complete() {
            return Err(self.incomplete());
        }
        self.dense.eval_derivative(&self.f_prev, t, out);
        Ok(())
    }

    fn set_h_max(&mut self, h_max: Real) {
        if h_max > 0.0 {
            self.h_max = h_max;
        }
    }

    fn h_max(&self) -> Real {
        self.h_max
    }

    fn counters(&self) -> Counters {
        self.counters
    }

    fn dim(&self) -> usize {
        self.n
    }
}
