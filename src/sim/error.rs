//! Why a run stops, and what can fail.

use crate::contact::ContactError;
use crate::dynamics::DynamicsError;
use crate::events::EventError;
use crate::impact::ImpactError;
use crate::integrate::{IntegrateError, SettingsError};
use crate::kinematics::KinematicsError;
use crate::math::Real;

use super::ObserverError;

/// Why a run stopped.
#[derive(Debug)]
pub enum StopReason {
    /// It reached its end time.
    EndTime,
    /// The caller asked it to stop (Ctrl-C).
    Interrupted {
        /// Time reached (s).
        t: Real,
    },
    /// Something failed; the error says when and what.
    Failed(SimError),
}

impl StopReason {
    /// A short name for logs: `t_end`, `interrupted`, `error`.
    pub fn name(&self) -> &'static str {
        match self {
            StopReason::EndTime => "t_end",
            StopReason::Interrupted { .. } => "interrupted",
            StopReason::Failed(_) => "error",
        }
    }
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::EndTime => f.write_str("reached the end time"),
            StopReason::Interrupted { .. } => f.write_str("interrupted"),
            StopReason::Failed(e) => {
                // The whole chain: what failed, and why.
                write!(f, "failed: {e}")?;
                let mut cause = std::error::Error::source(e);
                while let Some(c) = cause {
                    write!(f, ": {c}")?;
                    cause = c.source();
                }
                Ok(())
            }
        }
    }
}

/// A failure of a run, with the time and what failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The dynamics failed (a singular mass matrix, a non-finite state).
    #[error("at t = {t}: {source}")]
    Dynamics {
        /// Time (s).
        t: Real,
        /// What failed.
        #[source]
        source: DynamicsError,
    },
    /// A kinematics query failed.
    #[error("at t = {t}: {source}")]
    Kinematics {
        /// Time (s).
        t: Real,
        /// What failed.
        #[source]
        source: KinematicsError,
    },
    /// A contact query failed (an unsupported shape pair).
    #[error("at t = {t}: {source}")]
    ContactQuery {
        /// Time (s).
        t: Real,
        /// What failed.
        #[source]
        source: ContactError,
    },
    /// A contact could not be resolved.
    #[error("at t = {t}: {message}")]
    Contact {
        /// Time (s).
        t: Real,
        /// What happened.
        message: String,
    },
    /// The impact law could not solve an impact.
    #[error("at t = {t}: the impact on {name} failed: {source}")]
    Impact {
        /// Time (s).
        t: Real,
        /// The contact pair.
        pair: usize,
        /// Its name, `<collider a>/<collider b>`.
        name: String,
        /// The law's error.
        #[source]
        source: ImpactError,
    },
    /// The integrator failed.
    #[error(transparent)]
    Integrate(#[from] IntegrateError<Nested>),
    /// Locating an event failed.
    #[error(transparent)]
    Locate(#[from] EventError<Nested>),
    /// Settling on an event failed.
    #[error(transparent)]
    Settle(#[from] EventError<Nested, Nested>),
    /// Simultaneous impacts kept re-closing.
    #[error("at t = {t}: simultaneous impacts did not settle after {rounds} sequential impacts")]
    Simultaneous {
        /// Time (s).
        t: Real,
        /// Impacts applied at that instant.
        rounds: usize,
    },
    /// The settings cannot be used.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// A material override is out of range.
    #[error("the override of {what} = {value} is out of range (e ∈ [0, 1], μ ≥ 0)")]
    Override {
        /// `e` or `mu`.
        what: &'static str,
        /// The value given.
        value: Real,
    },
    /// The initial state does not fit the model.
    #[error("the initial state has {got} coordinates or speeds, the model {expected}")]
    InitialState {
        /// `nq` of the model.
        expected: usize,
        /// What the state has.
        got: usize,
    },
    /// The observer (the log) failed.
    #[error("at t = {t}: the log failed: {message}")]
    Observer {
        /// Time (s).
        t: Real,
        /// Its error.
        message: String,
    },
}

/// An error that happened at a known time.
pub trait AtTime {
    /// The error as a [`SimError`] at time `t`.
    fn at(self, t: Real) -> SimError;
}

impl AtTime for DynamicsError {
    fn at(self, t: Real) -> SimError {
        SimError::Dynamics { t, source: self }
    }
}

impl AtTime for KinematicsError {
    fn at(self, t: Real) -> SimError {
        SimError::Kinematics { t, source: self }
    }
}

impl AtTime for ContactError {
    fn at(self, t: Real) -> SimError {
        SimError::ContactQuery { t, source: self }
    }
}

impl AtTime for ObserverError {
    fn at(self, t: Real) -> SimError {
        SimError::Observer {
            t,
            message: self.to_string(),
        }
    }
}

impl SimError {
    /// `e` at time `t`.
    pub fn at(t: Real, e: impl AtTime) -> SimError {
        e.at(t)
    }
}

/// A [`SimError`] raised inside the integrator or the event location (by the right-hand
/// side or an event function), boxed so that the error types do not contain themselves.
#[derive(Debug)]
pub struct Nested(pub Box<SimError>);

impl std::fmt::Display for Nested {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for Nested {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

impl From<SimError> for Nested {
    fn from(e: SimError) -> Self {
        Nested(Box::new(e))
    }
}

impl From<Nested> for SimError {
    fn from(e: Nested) -> Self {
        *e.0
    }
}
