//! What a run reports while it goes: samples of the state at the output rate, the impact
//! ledger, and messages. The MCAP log implements [`Observer`]; so can a test.

use crate::dynamics::Energy;
use crate::math::{Pose, Real};
use crate::model::{Model, PairId};

use super::ImpactEvent;

/// A sample of the run.
#[derive(Clone, Copy, Debug)]
pub struct Sample<'a> {
    /// Time (s).
    pub t: Real,
    /// Generalized coordinates `q` (m, rad).
    pub q: &'a [Real],
    /// Generalized speeds `u` (m/s, rad/s).
    pub u: &'a [Real],
    /// Energies (J).
    pub energy: Energy,
    /// The pairs this sample lists, in pair order: every pair of a model with at most
    /// [`LISTED_PAIRS`](super::LISTED_PAIRS) pairs; beyond, the pairs whose bounding boxes
    /// overlap and those in contact. `gaps`, `modes` and `slips` follow it.
    pub pairs: &'a [PairId],
    /// Signed gap of each listed pair (m).
    pub gaps: &'a [Real],
    /// World pose of every body, in body order.
    pub poses: &'a [Pose],
    /// `true` for the two samples taken at an impact instant (before and after the jump).
    pub at_impact: bool,
    /// The mode of each listed pair.
    pub modes: &'a [PairMode],
    /// The direction of the slip of each listed pair along its tangent `t = perp(n)`
    /// (`n` from `b` to `a`): `+1` or `−1` when it slides, `0` otherwise.
    pub slips: &'a [i8],
    /// How many times the contact stage has run since the run began: at the start, at every
    /// located event (those that change nothing too: a gap crossing at rounding after an
    /// impact, a touching point that stays open) and wherever the closed points' modes stop
    /// being consistent. Two samples with the same count have nothing but integration
    /// between them. Always 0 under Moreau–Jean (time-stepping: no contact stage).
    pub contact_stages: u64,
}

/// The mode of a contact pair: open, or closed and sticking or sliding (a pair with two
/// closed points slides if either slides).
///
/// Ordered from the least to the most constrained.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PairMode {
    /// Open (or touching without force).
    #[default]
    Free,
    /// Closed, slipping.
    Sliding,
    /// Closed, not slipping.
    Sticking,
    /// An impulse in this time step (time-stepping only: the event-driven loop marks its
    /// impact instants with [`Sample::at_impact`]).
    Impact,
}

impl PairMode {
    /// `free`, `sticking`, `sliding` or `impact`.
    pub fn name(self) -> &'static str {
        match self {
            PairMode::Free => "free",
            PairMode::Sticking => "sticking",
            PairMode::Sliding => "sliding",
            PairMode::Impact => "impact",
        }
    }
}

/// A change of the mode of a contact pair in persistent contact.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// Time (s).
    pub t: Real,
    /// The pair.
    pub pair: PairId,
    /// Its name, `<collider a>/<collider b>`.
    pub name: String,
    /// The mode before.
    pub from: PairMode,
    /// The mode after.
    pub to: PairMode,
    /// What happened, in words.
    pub note: String,
    /// For an accumulation of impacts: the time at which the extrapolated hops end (s).
    pub t_accumulation: Option<Real>,
}

/// The severity of a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// Information (a mode change, a stop).
    Info,
    /// Something the user should know (a simultaneous impact resolved sequentially).
    Warning,
    /// A failure that stops the run.
    Error,
}

/// An error of an observer (an I/O error of the log, typically).
pub type ObserverError = Box<dyn std::error::Error + Send + Sync>;

/// Receives what a run reports. All methods run on the simulation's thread.
pub trait Observer {
    /// Whether to compute samples at the output rate (energies, gaps and poses cost a
    /// kinematics pass each); `false` runs the simulation alone.
    fn wants_samples(&self) -> bool {
        true
    }

    /// A sample of the state.
    fn sample(&mut self, model: &Model, sample: &Sample<'_>) -> Result<(), ObserverError>;

    /// An impact (an entry of the ledger).
    fn impact(&mut self, model: &Model, impact: &ImpactEvent) -> Result<(), ObserverError>;

    /// A message at time `t` (s).
    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError>;

    /// A change of contact mode (also reported as a message).
    fn transition(&mut self, model: &Model, transition: &Transition) -> Result<(), ObserverError> {
        let _ = (model, transition);
        Ok(())
    }
}

/// An observer that keeps nothing: the simulation alone.
#[derive(Clone, Copy, Debug, Default)]
pub struct NullObserver;

impl Observer for NullObserver {
    fn wants_samples(&self) -> bool {
        false
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        Ok(())
    }
    fn impact(&mut self, _: &Model, _: &ImpactEvent) -> Result<(), ObserverError> {
        Ok(())
    }
    fn message(&mut self, _: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// An observer that keeps the impacts and messages in memory (for tests and scripts).
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    /// Every impact, in order.
    pub impacts: Vec<ImpactEvent>,
    /// Every message, with its time and level.
    pub messages: Vec<(Real, Level, String)>,
    /// Every change of contact mode.
    pub transitions: Vec<Transition>,
    /// Every sample's time, coordinates, speeds and total energy, if `samples` is set.
    pub samples: Vec<(Real, Vec<Real>, Vec<Real>, Real)>,
    /// Every sample's time and the modes of the pairs, if `samples` is set.
    pub sample_modes: Vec<(Real, Vec<PairMode>)>,
    /// Whether to keep samples.
    pub keep_samples: bool,
}

impl Observer for Recorder {
    fn wants_samples(&self) -> bool {
        self.keep_samples
    }
    fn sample(&mut self, _: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        self.samples
            .push((s.t, s.q.to_vec(), s.u.to_vec(), s.energy.total()));
        self.sample_modes.push((s.t, s.modes.to_vec()));
        Ok(())
    }
    fn impact(&mut self, _: &Model, impact: &ImpactEvent) -> Result<(), ObserverError> {
        self.impacts.push(impact.clone());
        Ok(())
    }
    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        self.messages.push((t, level, text.to_owned()));
        Ok(())
    }
    fn transition(&mut self, _: &Model, transition: &Transition) -> Result<(), ObserverError> {
        self.transitions.push(transition.clone());
        Ok(())
    }
}
