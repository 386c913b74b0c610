//! DOPRI5(4): the Dormand–Prince 5(4) pair with FSAL, PI step-size control, a maximum
//! step and Shampine's continuous extension of order 4 [HNW, II.4–6; Dormand & Prince
//! 1980; Shampine 1986]. The tableau is in [`tableau`](super::tableau).
//!
//! Per accepted or rejected step: 6 evaluations of `f` (stages 2–7; stage 1 is the
//! previous step's stage 7). At `start`: 1 evaluation, plus 1 for the initial step guess
//! when `h_init` is not given. A re-step to an event time costs 6.

use super::control::{
    PiController, after_failed_stage, clip_step, error_norm, scaled_sq, smallest_step,
};
use super::dense::Dense;
use super::error::{require_non_negative, require_positive};
use super::tableau::*;
use super::{Counters, IntegrateError, Method, OdeSystem, SettingsError, StepOutcome, Stepper};
use crate::math::Real;
use crate::settings::IntegratorSettings;

/// Settings of [`Dopri5`].
#[derive(Clone, Debug, PartialEq)]
pub struct Dopri5Settings {
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
    /// PI stabilization exponent β (dimensionless, HNW's DOPRI5: 0.04; 0 is the
    /// classical I controller).
    pub beta: Real,
    /// Smallest step ratio `h_new / h` (dimensionless, HNW: 0.2).
    pub fac_min: Real,
    /// Largest step ratio `h_new / h` (dimensionless, HNW: 10).
    pub fac_max: Real,
}

impl Default for Dopri5Settings {
    fn default() -> Self {
        Self::from(&IntegratorSettings::default())
    }
}

impl From<&IntegratorSettings> for Dopri5Settings {
    fn from(s: &IntegratorSettings) -> Self {
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
}

impl Dopri5Settings {
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
        if self.h_max.is_nan() || self.h_max <= 0.0 {
            return Err(SettingsError {
                field: "h_max",
                value: self.h_max,
                reason: "must be > 0 (INFINITY for no cap)",
            });
        }
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

/// Stage vectors of one DOPRI5 step, allocated once.
#[derive(Clone, Debug)]
struct Stages {
    k2: Vec<Real>,
    k3: Vec<Real>,
    k4: Vec<Real>,
    k5: Vec<Real>,
    k6: Vec<Real>,
    /// `k₇ = f(t₁, y₁)`, the FSAL derivative at the end of the step.
    k7: Vec<Real>,
    /// Argument of the current stage.
    y_stage: Vec<Real>,
    /// The 5th-order solution `y₁`.
    y_new: Vec<Real>,
    /// The local error estimate `h Σ eᵢ kᵢ`.
    err: Vec<Real>,
}

impl Stages {
    fn new(n: usize) -> Self {
        Self {
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            k5: vec![0.0; n],
            k6: vec![0.0; n],
            k7: vec![0.0; n],
            y_stage: vec![0.0; n],
            y_new: vec![0.0; n],
            err: vec![0.0; n],
        }
    }

    fn resize(&mut self, n: usize) {
        for v in [
            &mut self.k2,
            &mut self.k3,
            &mut self.k4,
            &mut self.k5,
            &mut self.k6,
            &mut self.k7,
            &mut self.y_stage,
            &mut self.y_new,
            &mut self.err,
        ] {
            v.resize(n, 0.0);
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

/// One DOPRI5 step from `(t0, y0)` with `k1 = f(t0, y0)` to `t1`: stages 2–7, the
/// 5th-order solution `y_new` and the error estimate `err` [HNW, II.5, Eq. (5.1)]:
///
/// ```text
///   kᵢ = f(t₀ + cᵢ h, y₀ + h Σⱼ<ᵢ aᵢⱼ kⱼ),   i = 2 … 7
///   y₁ = y₀ + h Σ bᵢ kᵢ  (= the argument of stage 7),   err = h Σ eᵢ kᵢ
/// ```
// Indexed loops mirror the rows of the tableau; a seven-way `zip` would hide them.
#[allow(clippy::needless_range_loop)]
fn stages<S: OdeSystem>(
    sys: &mut S,
    t0: Real,
    y0: &[Real],
    k1: &[Real],
    t1: Real,
    st: &mut Stages,
    counters: &mut Counters,
) -> Result<(), IntegrateError<S::Error>> {
    let h = t1 - t0;
    for i in 0..y0.len() {
        st.y_stage[i] = y0[i] + h * A21 * k1[i];
    }
    eval(sys, t0 + C2 * h, &st.y_stage, &mut st.k2, counters)?;
    for i in 0..y0.len() {
        st.y_stage[i] = y0[i] + h * (A31 * k1[i] + A32 * st.k2[i]);
    }
    eval(sys, t0 + C3 * h, &st.y_stage, &mut st.k3, counters)?;
    for i in 0..y0.len() {
        st.y_stage[i] = y0[i] + h * (A41 * k1[i] + A42 * st.k2[i] + A43 * st.k3[i]);
    }
    eval(sys, t0 + C4 * h, &st.y_stage, &mut st.k4, counters)?;
    for i in 0..y0.len() {
        st.y_stage[i] =
            y0[i] + h * (A51 * k1[i] + A52 * st.k2[i] + A53 * st.k3[i] + A54 * st.k4[i]);
    }
    eval(sys, t0 + C5 * h, &st.y_stage, &mut st.k5, counters)?;
    for i in 0..y0.len() {
        st.y_stage[i] = y0[i]
            + h * (A61 * k1[i] + A62 * st.k2[i] + A63 * st.k3[i] + A64 * st.k4[i] + A65 * st.k5[i]);
    }
    eval(sys, t1, &st.y_stage, &mut st.k6, counters)?;
    for i in 0..y0.len() {
        st.y_new[i] = y0[i]
            + h * (A71 * k1[i] + A73 * st.k3[i] + A74 * st.k4[i] + A75 * st.k5[i] + A76 * st.k6[i]);
    }
    eval(sys, t1, &st.y_new, &mut st.k7, counters)?;
    for i in 0..y0.len() {
        st.err[i] = h
            * (E1 * k1[i]
                + E3 * st.k3[i]
                + E4 * st.k4[i]
                + E5 * st.k5[i]
                + E6 * st.k6[i]
                + E7 * st.k7[i]);
    }
    Ok(())
}

/// Shampine's quartic term `r₅ = h Σ dᵢ kᵢ` of the continuous extension.
#[allow(clippy::needless_range_loop)]
fn shampine_r5(r5: &mut [Real], h: Real, k1: &[Real], st: &Stages) {
    for i in 0..r5.len() {
        r5[i] = h
            * (D1 * k1[i]
                + D3 * st.k3[i]
                + D4 * st.k4[i]
                + D5 * st.k5[i]
                + D6 * st.k6[i]
                + D7 * st.k7[i]);
    }
}

/// Whether every component is finite.
#[inline]
pub(crate) fn all_finite(v: &[Real]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// DOPRI5(4): the Dormand–Prince 5(4) pair with FSAL, PI step-size control, a maximum
/// step and Shampine's continuous extension of order 4 [HNW, II.4–6; J. R. Dormand,
/// P. J. Prince, J. Comput. Appl. Math. 6, 19–26 (1980); L. F. Shampine, Math. Comp. 46,
/// 135–150 (1986)]; the tableau is in [`tableau`](crate::integrate::tableau).
///
/// Cost: 6 evaluations of `f` per accepted or rejected step (stage 1 is the previous
/// step's stage 7); at `start` 1, plus 1 for the initial step guess when `h_init` is not
/// given; 6 per re-step; 1 per reset.
///
/// ```
/// use ricochet::integrate::{Dopri5, Dopri5Settings, FnSystem, StepOutcome, Stepper};
/// // ẏ = −y, y(0) = 1, to t = 1.
/// let mut sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| dy[0] = -y[0]);
/// let settings = Dopri5Settings { rtol: 1e-10, atol: 1e-12, ..Default::default() };
/// let mut dopri = Dopri5::new(1, settings).unwrap();
/// dopri.start(&mut sys, 0.0, &[1.0]).unwrap();
/// while dopri.step(&mut sys, 1.0).unwrap() != StepOutcome::ReachedStop {}
/// assert!((dopri.y()[0] - (-1.0f64).exp()).abs() < 1e-10);
/// ```
#[derive(Clone, Debug)]
pub struct Dopri5 {
    settings: Dopri5Settings,
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
    st: Stages,
    dense: Dense,
    /// Next step to try (s).
    h: Real,
    h_max: Real,
    ctrl: PiController,
    counters: Counters,
}

impl Dopri5 {
    /// A stepper for systems of dimension `n` (all vectors are allocated here; `start`
    /// resizes them if the system's dimension differs).
    pub fn new(n: usize, settings: Dopri5Settings) -> Result<Self, SettingsError> {
        settings.validate()?;
        let ctrl = PiController::new(
            settings.safety,
            settings.beta,
            settings.fac_min,
            settings.fac_max,
        );
        Ok(Self {
            n,
            started: false,
            t: 0.0,
            y: vec![0.0; n],
            f: vec![0.0; n],
            t_prev: 0.0,
            y_prev: vec![0.0; n],
            f_prev: vec![0.0; n],
            t_end: 0.0,
            st: Stages::new(n),
            dense: Dense::new(n),
            h: 0.0,
            h_max: settings.h_max,
            ctrl,
            counters: Counters::default(),
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &Dopri5Settings {
        &self.settings
    }

    /// Sets the smallest step `h_min` (s; ignored unless finite and ≥ 0): see
    /// [`Dopri5Settings::h_min`].
    pub fn set_h_min(&mut self, h_min: Real) {
        if h_min.is_finite() && h_min >= 0.0 {
            self.settings.h_min = h_min;
        }
    }

    /// The step the next call of [`step`](Stepper::step) will try first, before capping
    /// by `h_max` and the stop time (s).
    pub fn h_next(&self) -> Real {
        self.h
    }

    fn resize(&mut self, n: usize) {
        if n != self.n {
            self.n = n;
            for v in [&mut self.y, &mut self.f, &mut self.y_prev, &mut self.f_prev] {
                v.resize(n, 0.0);
            }
            self.st.resize(n);
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
        self.ctrl.restart();
        Ok(())
    }

    /// The initial step guess of [HNW, II.4, p. 169] (Hairer's `HINIT`, order 5): from
    /// `d₀ = ‖y₀‖`, `d₁ = ‖f₀‖` take `h₀ = 0.01 d₀/d₁`, an explicit Euler step gives
    /// `d₂ ≈ ‖ÿ‖`, and `h = min(100 h₀, (0.01 / max(d₁, d₂))^(1/5), h_max)`.
    /// One evaluation of `f`.
    fn initial_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
    ) -> Result<Real, IntegrateError<S::Error>> {
        let (rtol, atol) = (self.settings.rtol, self.settings.atol);
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
        for i in 0..self.n {
            self.st.y_stage[i] = self.y[i] + h * self.f[i];
        }
        eval(
            sys,
            self.t + h,
            &self.st.y_stage,
            &mut self.st.k2,
            &mut self.counters,
        )?;
        for i in 0..self.n {
            self.st.err[i] = self.st.k2[i] - self.f[i];
        }
        let der2 = scaled_sq(&self.st.err[..m], &self.y[..m], rtol, atol).sqrt() / h;
        let der12 = der2.abs().max(dnf.sqrt());
        let h1 = if der12 <= 1e-15 || !der12.is_finite() {
            (h * 1e-3).max(1e-6)
        } else {
            (0.01 / der12).powf(0.2)
        };
        Ok((100.0 * h).min(h1).min(self.h_max))
    }
}

impl Stepper for Dopri5 {
    fn method(&self) -> Method {
        Method::Dopri5
    }

    fn start<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: Real,
        y0: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        self.started = false;
        self.set_state(sys, t0, y0)?;
        self.h = match self.settings.h_init {
            Some(h) => h,
            None => self.initial_step(sys)?,
        };
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
        let mut non_finite_rejections = 0u32;
        let mut rhs_failures = 0u32;
        loop {
            let (h, reaches) = clip_step(self.h, self.h_max, t_stop - self.t);
            // The controller's own step below the floor (not one capped by h_max or
            // shortened to the stop): accepted steps that small cannot bring the run
            // anywhere, however long it runs (a first step of 1e-126 s at t = 0).
            let h_min = smallest_step(self.settings.h_min, self.t);
            if !reaches && self.h < h_min && self.h < self.h_max {
                return Err(IntegrateError::StepSizeTooSmall {
                    t: self.t,
                    h: self.h,
                    h_min,
                });
            }
            let t1 = if reaches { t_stop } else { self.t + h };
            // A right-hand side that fails at a trial stage (a state the accepted solution
            // never reaches, such as a contact problem without solution far from it)
            // rejects the step: it shrinks by 4 and is tried again, down to the smallest
            // step (or 30 failures in a row, a factor 1e18), where the failure is returned.
            // Stage 1 is the accepted state, already evaluated: a failure there is never
            // retried.
            match stages(
                sys,
                self.t,
                &self.y,
                &self.f,
                t1,
                &mut self.st,
                &mut self.counters,
            ) {
                Ok(()) => {}
                Err(e @ IntegrateError::Rhs { .. }) => {
                    self.counters.rejected += 1;
                    let h_min = smallest_step(self.settings.h_min, self.t);
                    let Some(h_new) = after_failed_stage(h, &mut rhs_failures, h_min) else {
                        return Err(e);
                    };
                    self.h = h_new;
                    continue;
                }
                Err(e) => return Err(e),
            }
            let err = if all_finite(&self.st.y_new) {
                let m = sys.controlled().min(self.n);
                error_norm(
                    &self.st.err[..m],
                    &self.y[..m],
                    &self.st.y_new[..m],
                    self.settings.rtol,
                    self.settings.atol,
                )
            } else {
                Real::NAN
            };
            let verdict = self.ctrl.judge(h, err);
            if verdict.accept {
                // The continuous extension of this step, then rotate the buffers:
                // (y_prev, f_prev) ← (y, f) ← (y₁, k₇).
                self.dense
                    .set_hermite(self.t, h, &self.y, &self.f, &self.st.y_new, &self.st.k7);
                shampine_r5(&mut self.dense.r5, h, &self.f, &self.st);
                std::mem::swap(&mut self.y_prev, &mut self.y);
                std::mem::swap(&mut self.y, &mut self.st.y_new);
                std::mem::swap(&mut self.f_prev, &mut self.f);
                std::mem::swap(&mut self.f, &mut self.st.k7);
                self.t_prev = self.t;
                self.t = t1;
                self.t_end = t1;
                self.counters.steps += 1;
                // A step shortened to land on t_stop says little about the step the
                // solution allows (its growth is clamped at fac_max): keep the larger of
                // the two suggestions. A step capped by h_max informs the controller as
                // usual.
                let shortened_for_stop = reaches && h < self.h.min(self.h_max);
                self.h = if shortened_for_stop {
                    verdict.h_new.max(self.h)
                } else {
                    verdict.h_new
                };
                return Ok(if reaches {
                    StepOutcome::ReachedStop
                } else {
                    StepOutcome::Advanced
                });
            }
            self.counters.rejected += 1;
            let h_min = smallest_step(self.settings.h_min, self.t);
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
            self.h = verdict.h_new;
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
        stages(
            sys,
            t0,
            &self.y_prev,
            &self.f_prev,
            t_target,
            &mut self.st,
            &mut self.counters,
        )?;
        self.counters.resteps += 1;
        if !all_finite(&self.st.y_new) || !all_finite(&self.st.k7) {
            return Err(IntegrateError::NonFinite { t: t_target });
        }
        let h = t_target - t0;
        self.dense.set_hermite(
            t0,
            h,
            &self.y_prev,
            &self.f_prev,
            &self.st.y_new,
            &self.st.k7,
        );
        shampine_r5(&mut self.dense.r5, h, &self.f_prev, &self.st);
        std::mem::swap(&mut self.y, &mut self.st.y_new);
        std::mem::swap(&mut self.f, &mut self.st.k7);
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
        self.set_state(sys, t, y)?;
        self.h = self.h.min(self.h_max);
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

    fn dense(&self, t: Real, out: &mut [Real]) {
        self.dense.eval(&self.y_prev, t, out);
    }

    fn dense_derivative(&self, t: Real, out: &mut [Real]) {
        self.dense.eval_derivative(&self.f_prev, t, out);
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
