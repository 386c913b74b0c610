//! What a run reports when it ends: the energy audit and the work counters.

use crate::dynamics::Energy;
use crate::math::Real;
use crate::state::State;

use super::StopReason;

/// The energy audit of a run: `E_end − E_0` against what explains it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyAudit {
    /// Energies at the start (J).
    pub initial: Energy,
    /// Energies at the end (J).
    pub end: Energy,
    /// Σ ΔE of Eq. (29) over the impacts (J).
    pub impact_delta_e: Real,
    /// Σ of the Eq. (28) terms over the impacts: the work of the prescribed motions at the
    /// impacts (J).
    pub impact_prescribed_work: Real,
    /// Work of the joint dampers (J), never positive.
    pub damping_work: Real,
    /// Work of the constant joint efforts (J).
    pub applied_work: Real,
    /// Work of the prescribed drives between impacts (J).
    pub drive_work: Real,
    /// Work of the forces of the closed contacts in persistent contact (J): friction of
    /// sliding contacts, never positive without prescribed motion.
    pub contact_work: Real,
}

impl EnergyAudit {
    /// What the bookkeeping does not explain, the integration drift:
    /// `E_end − E_0 − (ΣΔE + Σ Eq. 28 + W_damping + W_applied + W_drives + W_contact)` (J).
    pub fn drift(&self) -> Real {
        self.end.total()
            - self.initial.total()
            - (self.impact_delta_e
                + self.impact_prescribed_work
                + self.damping_work
                + self.applied_work
                + self.drive_work
                + self.contact_work)
    }
}

/// Work counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunCounters {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Events located.
    pub events: u64,
    /// Impacts applied.
    pub impacts: u64,
    /// Samples reported.
    pub samples: u64,
}

/// The result of a run.
#[derive(Debug)]
pub struct RunSummary {
    /// Why it stopped.
    pub stop: StopReason,
    /// The state where it stopped.
    pub state: State,
    /// The energy audit.
    pub audit: EnergyAudit,
    /// Work counters.
    pub counters: RunCounters,
}
