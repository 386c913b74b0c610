//! The classical Runge–Kutta method of order 4 with a fixed step [HNW, II.1, Table 1.2]
//! and the cubic Hermite interpolant of `(y₀, f₀, y₁, f₁)` as continuous extension
//! (order 3).
//!
//! ```text
//!   k₁ = f(t₀, y₀)            k₂ = f(t₀ + h/2, y₀ + h/2 k₁)
//!   k₃ = f(t₀ + h/2, y₀ + h/2 k₂)   k₄ = f(t₀ + h, y₀ + h k₃)
//!   y₁ = y₀ + h/6 (k₁ + 2 k₂ + 2 k₃ + k₄)
//! ```
//!
//! `f₁ = f(t₁, y₁)`, needed by the interpolant, is evaluated at the end of each step and
//! is the next step's `k₁`: 4 evaluations per step, plus 1 at `start` and after a reset.

use super::control::{after_failed_stage, clip_step, smallest_step};
use super::dense::Dense;
use super::dopri5::all_finite;
use super::error::require_positive;
use super::{Counters, IntegrateError, Method, OdeSystem, SettingsError, StepOutcome, Stepper};
use crate::math::Real;
use crate::settings::IntegratorSettings;

/// Settings of [`Rk4`].
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
        if self.h_max.is_nan() || self.h_max <= 0.0 {
            return Err(SettingsError {
                field: "h_max",
                value: self.h_max,
                reason: "must be > 0 (INFINITY for no cap)",
            });
        }
        Ok(())
    }
}

/// Stage vectors of one RK4 step, allocated once.
#[derive(Clone, Debug)]
struct Stages {
    k2: Vec<Real>,
    k3: Vec<Real>,
    k4: Vec<Real>,
    y_stage: Vec<Real>,
    y_new: Vec<Real>,
    /// `f(t₁, y₁)`, the next step's `k₁`.
    f_new: Vec<Real>,
}

impl Stages {
    fn new(n: usize) -> Self {
        Self {
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            y_stage: vec![0.0; n],
            y_new: vec![0.0; n],
            f_new: vec![0.0; n],
        }
    }

    fn resize(&mut self, n: usize) {
        for v in [
            &mut self.k2,
            &mut self.k3,
            &mut self.k4,
            &mut self.y_stage,
            &mut self.y_new,
            &mut self.f_new,
        ] {
            v.resize(n, 0.0);
        }
    }
}

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

/// One RK4 step from `(t0, y0)`, `k1 = f(t0, y0)`, to `t1`, then `f(t1, y1)`.
fn rk4_step<S: OdeSystem>(
    sys: &mut S,
    t0: Real,
    y0: &[Real],
    k1: &[Real],
    t1: Real,
    st: &mut Stages,
    counters: &mut Counters,
) -> Result<(), IntegrateError<S::Error>> {
    let h = t1 - t0;
    let half = 0.5 * h;
    let t_mid = t0 + half;
    for ((ys, y0), k1) in st.y_stage.iter_mut().zip(y0).zip(k1) {
        *ys = y0 + half * k1;
    }
    eval(sys, t_mid, &st.y_stage, &mut st.k2, counters)?;
    for ((ys, y0), k2) in st.y_stage.iter_mut().zip(y0).zip(&st.k2) {
        *ys = y0 + half * k2;
    }
    eval(sys, t_mid, &st.y_stage, &mut st.k3, counters)?;
    for ((ys, y0), k3) in st.y_stage.iter_mut().zip(y0).zip(&st.k3) {
        *ys = y0 + h * k3;
    }
    eval(sys, t1, &st.y_stage, &mut st.k4, counters)?;
    let ks = k1.iter().zip(&st.k2).zip(st.k3.iter().zip(&st.k4));
    for ((yn, y0), ((k1, k2), (k3, k4))) in st.y_new.iter_mut().zip(y0).zip(ks) {
        *yn = y0 + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    eval(sys, t1, &st.y_new, &mut st.f_new, counters)
}

/// The classical Runge–Kutta method of order 4 with a fixed step [HNW, II.1, Table 1.2],
/// with the cubic Hermite interpolant of `(y₀, f₀, y₁, f₁)` as continuous extension
/// (order 3). `f₁` is evaluated at the end of each step and is the next step's `k₁`: 4
/// evaluations per step (and per re-step), 1 at `start` and per reset.
#[derive(Clone, Debug)]
pub struct Rk4 {
    settings: Rk4Settings,
    n: usize,
    started: bool,
    t: Real,
    y: Vec<Real>,
    f: Vec<Real>,
    t_prev: Real,
    y_prev: Vec<Real>,
    f_prev: Vec<Real>,
    t_end: Real,
    st: Stages,
    dense: Dense,
    h_max: Real,
    counters: Counters,
}

impl Rk4 {
    /// A stepper for systems of dimension `n` (all vectors are allocated here).
    pub fn new(n: usize, settings: Rk4Settings) -> Result<Self, SettingsError> {
        settings.validate()?;
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
            h_max: settings.h_max,
            counters: Counters::default(),
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &Rk4Settings {
        &self.settings
    }

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
        if n != self.n {
            self.n = n;
            for v in [&mut self.y, &mut self.f, &mut self.y_prev, &mut self.f_prev] {
                v.resize(n, 0.0);
            }
            self.st.resize(n);
            self.dense.resize(n);
        }
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
        Ok(())
    }
}

impl Stepper for Rk4 {
    fn method(&self) -> Method {
        Method::Rk4
    }

    fn start<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: Real,
        y0: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        self.started = false;
        self.set_state(sys, t0, y0)?;
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
        let (mut h, mut reaches) = clip_step(self.settings.dt, self.h_max, t_stop - self.t);
        let mut t1 = if reaches { t_stop } else { self.t + h };
        // A right-hand side that fails at a trial stage (a state the solution never
        // reaches) shortens this step by 4 and tries again, at most 30 times (a factor
        // 1e18) and down to `10 ε |t|`, where the failure is returned; the next step is
        // `dt` again. Stage 1 is the accepted state, already evaluated: a failure there is
        // never retried.
        let mut failures = 0u32;
        loop {
            match rk4_step(
                sys,
                self.t,
                &self.y,
                &self.f,
                t1,
                &mut self.st,
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
        if !all_finite(&self.st.y_new) || !all_finite(&self.st.f_new) {
            return Err(IntegrateError::NonFinite { t: t1 });
        }
        self.dense
            .set_hermite(self.t, h, &self.y, &self.f, &self.st.y_new, &self.st.f_new);
        std::mem::swap(&mut self.y_prev, &mut self.y);
        std::mem::swap(&mut self.y, &mut self.st.y_new);
        std::mem::swap(&mut self.f_prev, &mut self.f);
        std::mem::swap(&mut self.f, &mut self.st.f_new);
        self.t_prev = self.t;
        self.t = t1;
        self.t_end = t1;
        self.counters.steps += 1;
        Ok(if reaches {
            StepOutcome::ReachedStop
        } else {
            StepOutcome::Advanced
        })
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
        rk4_step(
            sys,
            t0,
            &self.y_prev,
            &self.f_prev,
            t_target,
            &mut self.st,
            &mut self.counters,
        )?;
        self.counters.resteps += 1;
        if !all_finite(&self.st.y_new) || !all_finite(&self.st.f_new) {
            return Err(IntegrateError::NonFinite { t: t_target });
        }
        let h = t_target - t0;
        self.dense.set_hermite(
            t0,
            h,
            &self.y_prev,
            &self.f_prev,
            &self.st.y_new,
            &self.st.f_new,
        );
        std::mem::swap(&mut self.y, &mut self.st.y_new);
        std::mem::swap(&mut self.f, &mut self.st.f_new);
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
        self.set_state(sys, t, y)
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
