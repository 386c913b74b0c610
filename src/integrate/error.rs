//! Errors of the integrators: a failing right-hand side, a step size that collapsed, a
//! state that stopped being finite, and misuse of the stepping API. Every variant carries
//! the time at which it happened.

use crate::math::Real;

/// An integration failure. `E` is the error type of the system's right-hand side
/// ([`OdeSystem::Error`](super::OdeSystem::Error)).
#[derive(Debug, thiserror::Error)]
pub enum IntegrateError<E>
where
    E: std::error::Error + 'static,
{
    /// The right-hand side `f(t, y)` failed (e.g. a singular mass matrix).
    #[error("right-hand side failed at t = {t}")]
    Rhs {
        /// Time of the failing evaluation (s).
        t: Real,
        /// The system's error.
        #[source]
        source: E,
    },
    /// The step-size controller reduced the step below the smallest admissible step
    /// `max(h_min, 10 ε |t|)` after rejected steps.
    #[error("step size {h:e} below the minimum {h_min:e} at t = {t}")]
    StepSizeTooSmall {
        /// Time at the start of the failing step (s).
        t: Real,
        /// The step that would have been tried next (s).
        h: Real,
        /// The smallest admissible step at `t` (s).
        h_min: Real,
    },
    /// The state or its derivative is not finite (NaN or infinite) and reducing the step
    /// did not help.
    #[error("non-finite state or derivative at t = {t}")]
    NonFinite {
        /// Time of the state that is not finite (s).
        t: Real,
    },
    /// A vector's length does not match the system's dimension.
    #[error(
        "dimension mismatch: the system has dimension {expected}, got a vector of length {got}"
    )]
    Dimension {
        /// The system's dimension `n`.
        expected: usize,
        /// The length that was passed.
        got: usize,
    },
    /// [`Stepper::step`](super::Stepper::step) was asked to stop at a time that is not
    /// after the current time (integration runs forward only).
    #[error("stop time {t_stop} is not after the current time {t}")]
    StopNotAhead {
        /// The current time (s).
        t: Real,
        /// The requested stop time (s).
        t_stop: Real,
    },
    /// [`Stepper::restep_to`](super::Stepper::restep_to) was asked for a time outside the
    /// last accepted step.
    #[error("restep target {t_target} is outside the last accepted step [{t_prev}, {t_end}]")]
    RestepOutOfRange {
        /// The requested time (s).
        t_target: Real,
        /// Start of the last accepted step (s).
        t_prev: Real,
        /// End of the last accepted step, before any restep (s).
        t_end: Real,
    },
    /// A stepping call came before [`Stepper::start`](super::Stepper::start).
    #[error("the stepper was not started")]
    NotStarted,
    /// The dense output was read inside a step before it was completed.
    #[error(transparent)]
    DenseIncomplete(#[from] DenseIncomplete),
}

/// [`Stepper::dense`](super::Stepper::dense) or
/// [`dense_derivative`](super::Stepper::dense_derivative) was asked for inside a step
/// whose dense output needs evaluations of `f` that were not made yet (DOP853's three
/// extra stages): call [`Stepper::complete_dense`](super::Stepper::complete_dense) with
/// the system first. Nothing was written.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "the dense output of the step [{t_prev}, {t}] is not complete: call complete_dense \
     before reading it inside the step"
)]
pub struct DenseIncomplete {
    /// Start of the step (s).
    pub t_prev: Real,
    /// End of the step (s).
    pub t: Real,
}

/// Invalid integrator settings, found when a stepper is built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid integrator setting `{field}`{}: {reason}", value_text(.field, *.value))]
pub struct SettingsError {
    /// The name of the setting.
    pub field: &'static str,
    /// Its value (not shown for `method`, which is not a number: NaN there).
    pub value: Real,
    /// What is required of it.
    pub reason: &'static str,
}

/// ` = value` for a numeric setting, nothing for the method.
fn value_text(field: &str, value: Real) -> String {
    if field == "method" {
        String::new()
    } else {
        format!(" = {value}")
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn require_positive(field: &'static str, value: Real) -> Result<(), SettingsError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SettingsError {
            field,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Checks that `value` is finite and not negative.
pub(crate) fn require_non_negative(field: &'static str, value: Real) -> Result<(), SettingsError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SettingsError {
            field,
            value,
            reason: "must be finite and ≥ 0",
        })
    }
}

impl IntegrateError<std::convert::Infallible> {
    /// The same error with another right-hand-side error type (a system that cannot fail
    /// produces none).
    pub fn widen<E: std::error::Error + 'static>(self) -> IntegrateError<E> {
        match self {
            IntegrateError::Rhs { source, .. } => match source {},
            IntegrateError::StepSizeTooSmall { t, h, h_min } => {
                IntegrateError::StepSizeTooSmall { t, h, h_min }
            }
            IntegrateError::NonFinite { t } => IntegrateError::NonFinite { t },
            IntegrateError::Dimension { expected, got } => {
                IntegrateError::Dimension { expected, got }
            }
            IntegrateError::StopNotAhead { t, t_stop } => {
                IntegrateError::StopNotAhead { t, t_stop }
            }
            IntegrateError::RestepOutOfRange {
                t_target,
                t_prev,
                t_end,
            } => IntegrateError::RestepOutOfRange {
                t_target,
                t_prev,
                t_end,
            },
            IntegrateError::NotStarted => IntegrateError::NotStarted,
            IntegrateError::DenseIncomplete(e) => IntegrateError::DenseIncomplete(e),
        }
    }
}
