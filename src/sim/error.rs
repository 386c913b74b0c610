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
            // The whole chain, what failed and why, each said once.
            StopReason::Failed(e) => write!(f, "failed: {}", describe(e)),
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
        /// The contact pair (its [`PairId::index`](crate::model::PairId::index)).
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
    #[error(
        "the override of {what} = {value} is out of range (e ∈ [0, 1], μ ≥ 0)",
        value = crate::math::Shown(*.value)
    )]
    Override {
        /// `e` or `mu`.
        what: &'static str,
        /// The value given.
        value: Real,
    },
    /// The initial state does not fit the model.
    #[error(
        "the initial state has {got_q} coordinates and {got_u} speeds, the model {expected_q} and {expected_u}"
    )]
    InitialState {
        /// `nq` of the model.
        expected_q: usize,
        /// `nu` of the model.
        expected_u: usize,
        /// The length of the state's `q`.
        got_q: usize,
        /// The length of the state's `u`.
        got_u: usize,
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
            // With its causes: "MCAP error" alone does not say that the disk is full.
            message: describe(&*self),
        }
    }
}

impl SimError {
    /// `e` at time `t`.
    pub fn at(t: Real, e: impl AtTime) -> SimError {
        e.at(t)
    }

    /// The time of the failure (s), when the error has one.
    pub fn time(&self) -> Option<Real> {
        match self {
            SimError::Dynamics { t, .. }
            | SimError::Kinematics { t, .. }
            | SimError::ContactQuery { t, .. }
            | SimError::Contact { t, .. }
            | SimError::Impact { t, .. }
            | SimError::Simultaneous { t, .. }
            | SimError::Observer { t, .. } => Some(*t),
            SimError::Integrate(
                IntegrateError::Rhs { t, .. }
                | IntegrateError::StepSizeTooSmall { t, .. }
                | IntegrateError::NonFinite { t, .. },
            ) => Some(*t),
            SimError::Locate(EventError::Function { t, .. } | EventError::NonFinite { t, .. })
            | SimError::Settle(EventError::Function { t, .. } | EventError::NonFinite { t, .. }) => {
                Some(*t)
            }
            _ => None,
        }
    }

    /// What failed and why, without the time (for a line that says it already): the
    /// error and its causes, each said once.
    pub fn what(&self) -> String {
        let said = self.time().map(time_text).into_iter().collect();
        join_messages(chain_messages(self), said)
    }
}

/// An error and its causes ([`std::error::Error::source`]), joined by `: `, each said
/// once: a cause whose message the text already holds is left out, and so is a statement
/// `at t = X` of a time it already states. (The layers of a run's errors each say their
/// time, and many also print their cause's message, which the chain then gives again:
/// `at t = 0.5: at t = 0.5: q[0] is not finite (NaN): at t = 0.5: q[0] is not finite
/// (NaN)` becomes `at t = 0.5: q[0] is not finite (NaN)`.)
pub fn describe(error: &(dyn std::error::Error + 'static)) -> String {
    join_messages(chain_messages(error), Vec::new())
}

/// [`describe`] for the messages of a chain of errors, outermost first (e.g. from
/// `anyhow::Error::chain`).
pub fn describe_messages(messages: impl IntoIterator<Item = String>) -> String {
    join_messages(messages, Vec::new())
}

/// The messages of `error` and of its causes, outermost first.
fn chain_messages(error: &(dyn std::error::Error + 'static)) -> impl Iterator<Item = String> {
    std::iter::successors(Some(error), |e| e.source()).map(ToString::to_string)
}

/// The messages joined by `: `, without the times in `said` (`t = X`) nor those stated
/// before, nor a message the text already holds.
fn join_messages(messages: impl IntoIterator<Item = String>, mut said: Vec<String>) -> String {
    let mut text = String::new();
    for message in messages {
        let kept = without_said_times(&message, &mut said);
        let kept = kept.trim_matches(|c: char| c == ':' || c == ' ');
        if kept.is_empty() || text.contains(kept) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(kept);
    }
    text
}

/// `message` without its statements of the times in `said`; the times it states first
/// are added to `said`.
fn without_said_times(message: &str, said: &mut Vec<String>) -> String {
    let mut kept = String::new();
    let mut rest = message;
    while let Some(found) = next_time(rest) {
        kept.push_str(found.before);
        if !said.iter().any(|s| s == found.time) {
            said.push(found.time.to_owned());
            kept.push_str(found.statement);
        }
        rest = found.after;
    }
    kept.push_str(rest);
    kept
}

/// A statement of a time in a message.
struct TimeStatement<'a> {
    /// The text before it.
    before: &'a str,
    /// `t = X`.
    time: &'a str,
    /// The whole statement: `at t = X: ` (a prefix) or ` at t = X` (in a sentence).
    statement: &'a str,
    /// The text after it.
    after: &'a str,
}

/// The first statement `at t = X` in `text`.
fn next_time(text: &str) -> Option<TimeStatement<'_>> {
    let at = text.find("at t = ")?;
    let number = at + "at t = ".len();
    let number_end = number
        + text[number..]
            .find(|c: char| !(c.is_ascii_alphanumeric() || "+-.".contains(c)))
            .unwrap_or(text.len() - number);
    let start = if text[..at].ends_with(' ') {
        at - 1
    } else {
        at
    };
    let end = if text[number_end..].starts_with(": ") {
        number_end + 2
    } else {
        number_end
    };
    Some(TimeStatement {
        before: &text[..start],
        time: &text[at + "at ".len()..number_end],
        statement: &text[start..end],
        after: &text[end..],
    })
}

/// `t = X` as the errors print the time `t`.
fn time_text(t: Real) -> String {
    format!("t = {t}")
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
