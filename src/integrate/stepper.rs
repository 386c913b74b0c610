//! The stepping interface shared by the integrators: the simulation loop drives a
//! [`Stepper`] one accepted step at a time, reads the dense output of the last step to
//! locate events, re-takes the step to an event time, and resets the state after an
//! impact. The reset map itself (the impact law) stays outside the integrator.

use serde::{Deserialize, Serialize};

use super::{DenseIncomplete, IntegrateError, Method, OdeSystem};
use crate::math::Real;

/// What one call of [`Stepper::step`] did. Neither outcome is a failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepOutcome {
    /// One step was accepted and it ended before the stop time.
    Advanced,
    /// One step was accepted and it ended exactly at the stop time (`t() == t_stop`).
    ReachedStop,
}

/// Work counters of a stepper since it was built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Counters {
    /// Accepted steps (re-taken steps not included).
    pub steps: u64,
    /// Rejected steps (the adaptive methods; RK4 only after a failing stage).
    pub rejected: u64,
    /// Evaluations of the right-hand side, all included: start, stages, steps re-taken
    /// to an event and resets.
    pub rhs_evals: u64,
    /// Steps re-taken to an event time by [`Stepper::restep_to`] (a rewind to the
    /// step's start costs nothing and is not counted).
    pub resteps: u64,
    /// Resets of the state by [`Stepper::reset`] (one evaluation of `f` each).
    pub resets: u64,
    /// Dense outputs completed by [`Stepper::complete_dense`] with evaluations of `f`
    /// (DOP853: three each; a step or re-step whose interior is never read costs none).
    pub dense_completions: u64,
}

/// One-step integration driven from outside, with a continuous extension of the last
/// step.
///
/// The life cycle is `start` → (`step` → `complete_dense` if the step is read inside →
/// read `dense` / locate events → possibly `restep_to` → possibly `reset`)*. After
/// [`step`](Stepper::step) (or [`restep_to`](Stepper::restep_to)), `[t_prev(), t()]` is
/// the last step: its end points are `y_prev()` and `y()`, with derivatives `dy_prev()`
/// and `dy()`, and [`dense`](Stepper::dense) evaluates the continuous extension inside
/// it once [`complete_dense`](Stepper::complete_dense) has made the evaluations of `f` it
/// needs beyond the step's own (DOP853's three extra stages; none for DOPRI5 and RK4): a
/// step whose interior is never read does not pay for them.
///
/// Integration runs forward in time only. The methods are generic over the system, so
/// the trait is not object safe; [`RungeKutta`](super::RungeKutta) runs the method chosen
/// at run time.
pub trait Stepper {
    /// The method.
    fn method(&self) -> Method;

    /// Sets the initial value `y(t0) = y0`, evaluates `f(t0, y0)`, and (the adaptive
    /// methods) guesses the first step. The last step is empty (`t_prev() == t() == t0`).
    fn start<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: Real,
        y0: &[Real],
    ) -> Result<(), IntegrateError<S::Error>>;

    /// Takes one accepted step that does not go past `t_stop` (it ends exactly at
    /// `t_stop` when it reaches it). An adaptive method may reject and retry steps inside
    /// this call.
    fn step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_stop: Real,
    ) -> Result<StepOutcome, IntegrateError<S::Error>>;

    /// Re-takes the last step from `(t_prev(), y_prev())` with `h = t_target − t_prev()`,
    /// so that the state at `t_target` is the method's full-order solution rather than
    /// its continuous extension. `t_target` must lie in `[t_prev(), t_end]`, where `t_end`
    /// is the end of the last *accepted* step (several re-steps in a row are allowed).
    /// Afterwards the last step is `[t_prev(), t_target]` and the stepper continues from
    /// `t_target`; the step-size suggestion is kept. `t_target == t_prev()` rewinds to the
    /// step's start without evaluating `f`.
    fn restep_to<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_target: Real,
    ) -> Result<(), IntegrateError<S::Error>>;

    /// Replaces the state at a discontinuity (an impact): `y(t) = y`. The derivative is
    /// re-evaluated (the FSAL derivative of the old state is invalid), the last step
    /// becomes empty at `t`, and the step-size suggestion is kept (limited by `h_max`).
    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        y: &[Real],
    ) -> Result<(), IntegrateError<S::Error>>;

    /// Current time `t` (s).
    fn t(&self) -> Real;
    /// Current state `y(t)`.
    fn y(&self) -> &[Real];
    /// Derivative `f(t, y)` at the current state.
    fn dy(&self) -> &[Real];
    /// Start of the last step (s).
    fn t_prev(&self) -> Real;
    /// State at the start of the last step.
    fn y_prev(&self) -> &[Real];
    /// Derivative at the start of the last step.
    fn dy_prev(&self) -> &[Real];

    /// Makes the continuous extension of the last step readable: the evaluations of `f`
    /// it needs beyond the step's own, the first time it is called after a step or a
    /// re-step (DOP853: its three extra stages, the same numbers as if they had been
    /// evaluated right after the step); afterwards, and for DOPRI5, RK4 and an empty step,
    /// it does nothing. A failing `f` is returned as [`IntegrateError::Rhs`] with the time
    /// of that evaluation, and the dense output stays incomplete.
    fn complete_dense<S: OdeSystem>(&mut self, sys: &mut S)
    -> Result<(), IntegrateError<S::Error>>;

    /// Whether the continuous extension of the last step can be read
    /// ([`complete_dense`](Stepper::complete_dense) has nothing left to do).
    fn dense_complete(&self) -> bool;

    /// Evaluates the continuous extension of the last step at `t ∈ [t_prev(), t()]` into
    /// `out` (length `n`). Outside the step the polynomial is extrapolated, which is
    /// inaccurate. On an empty step it returns `y()`. [`DenseIncomplete`] (and `out`
    /// untouched) before [`complete_dense`](Stepper::complete_dense) on a step that needs
    /// it.
    fn dense(&self, t: Real, out: &mut [Real]) -> Result<(), DenseIncomplete>;

    /// Evaluates the time derivative of the continuous extension at `t` into `out`. It
    /// interpolates `dy_prev()` and `dy()` at the ends and is one order lower than
    /// [`dense`](Stepper::dense) inside. [`DenseIncomplete`] as for `dense`.
    fn dense_derivative(&self, t: Real, out: &mut [Real]) -> Result<(), DenseIncomplete>;

    /// [`dense`](Stepper::dense) at `t` inside the last step, its continuous extension
    /// completed first with `sys` ([`complete_dense`](Stepper::complete_dense)): what a
    /// reader with the system at hand calls.
    fn dense_completing<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        out: &mut [Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        self.complete_dense(sys)?;
        Ok(self.dense(t, out)?)
    }

    /// [`dense_derivative`](Stepper::dense_derivative) at `t`, completed first as in
    /// [`dense_completing`](Stepper::dense_completing).
    fn dense_derivative_completing<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        out: &mut [Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        self.complete_dense(sys)?;
        Ok(self.dense_derivative(t, out)?)
    }

    /// Largest step (s); the loop lowers it, e.g. from a bound on the closing speed of the
    /// contacts. `Real::INFINITY` removes the cap. Non-positive or NaN values are
    /// ignored.
    fn set_h_max(&mut self, h_max: Real);

    /// The current largest step (s).
    fn h_max(&self) -> Real;

    /// Work counters since the stepper was built.
    fn counters(&self) -> Counters;

    /// The dimension `n` of the state.
    fn dim(&self) -> usize;
}
