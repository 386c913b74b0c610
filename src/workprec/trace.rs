//! [`Trace`]: what the work-precision metrics read from a run.

use crate::math::Real;
use crate::model::Model;
use crate::sim::{ImpactCause, ImpactEvent, Level, Observer, ObserverError, Sample};

/// One impact as the metrics see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactRecord {
    /// Time of the impact (s).
    pub t: Real,
    /// Post-impact velocity of the contact point relative to the other shape,
    /// `v^S = (v_n^S, v_t^S)` in the impact frame `(n, t)` (m/s).
    pub v_s: [Real; 2],
    /// Total mechanical energy after the impact (J).
    pub energy_after: Real,
}

/// The impacts and the end state of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    /// The impacts in time order; impulses at one instant count once (see
    /// [`Trace::push`]).
    pub impacts: Vec<ImpactRecord>,
    /// Total mechanical energy at the start (J).
    pub energy_initial: Real,
    /// Time the run ended (s).
    pub t_end: Real,
    /// Generalized coordinates at the end (m, rad).
    pub q: Vec<Real>,
    /// Generalized speeds at the end (m/s, rad/s).
    pub u: Vec<Real>,
}

impl Trace {
    /// Appends an impact. Impulses at the same instant (several contact points of one
    /// impact, as the event-driven loop's simultaneous impacts or Moreau–Jean's points of a
    /// step give) are one impact: the record of the fastest normal separation `v_n^S`
    /// is kept (with Newton's law `v_n^S = e |v_n^A|`: the point that struck hardest).
    pub fn push(&mut self, record: ImpactRecord) {
        match self.impacts.last_mut() {
            Some(last) if last.t == record.t => {
                if record.v_s[0] > last.v_s[0] {
                    *last = record;
                }
            }
            _ => self.impacts.push(record),
        }
    }
}

/// An observer that builds a [`Trace`] from a ricochet run (event-driven or Moreau–Jean):
/// the collisions and simultaneous impacts, not the closing impulse at the end of an
/// accumulation nor an impact without collision (they are not impacts of the rigid
/// dynamics that another method would reproduce one by one).
#[derive(Clone, Debug, Default)]
pub struct TraceObserver {
    /// The trace so far (the end state is filled in by the caller from the summary).
    pub trace: Trace,
}

impl Observer for TraceObserver {
    fn wants_samples(&self) -> bool {
        false
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        Ok(())
    }
    fn impact(&mut self, _: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        if matches!(ev.cause, ImpactCause::Collision | ImpactCause::Simultaneous) {
            let record = ImpactRecord {
                t: ev.t,
                v_s: [ev.outcome.v_s.n, ev.outcome.v_s.t],
                energy_after: ev.energy_after.total(),
            };
            self.trace.push(record);
        }
        Ok(())
    }
    fn message(&mut self, _: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        Ok(())
    }
}
