//! The simulation loop: integrate the free flight, locate the first impact on the dense
//! output, apply the impact map, repeat until the end time.
//!
//! ```text
//! start        y(t0) = [q0; u0; 0], E0, first sample, impacts already under way at t0
//! loop         stop?  (end time, Ctrl-C)
//!              step          one accepted integrator step            (integrate)
//!              locate        the earliest closing gap in the step    (events)
//!              settle        re-take the step to the event time      (full order)
//!              samples       the output times passed, on dense output
//!              impacts       frame → W → law → Δu for every closing contact (impact map)
//!              accumulation  stop when the contact no longer separates
//! finish       final sample, energy audit, counters
//! ```
//!
//! Persistent contact is not modelled yet: a contact that no longer separates after an
//! impact (an accumulation of impacts, `e = 0`, a resting contact) stops the run with
//! [`StopReason::Accumulation`] and a valid log.

mod accumulation;
mod gaps;
mod impact_map;
mod moreau_jean;
mod observer;
mod system;

use std::sync::atomic::{AtomicBool, Ordering};

pub use accumulation::Scales;
pub use gaps::GapFunctions;
pub use impact_map::{ImpactEvent, ImpactMap, MaterialOverride};
pub use moreau_jean::{MoreauJean, MoreauJeanSettings, SolverReport};
pub use observer::{Level, NullObserver, Observer, ObserverError, Recorder, Sample};
pub use system::MotionSystem;

use crate::contact::ContactError;
use crate::dynamics::{DynamicsError, Energy, energy};
use crate::events::{Event, EventError, EventLocator, LocatorSettings};
use crate::impact::ImpactError;
use crate::integrate::{AnyStepper, IntegrateError, SettingsError, Stepper};
use crate::kinematics::{KinematicsError, update_positions};
use crate::math::Real;
use crate::model::{Model, PairId};
use crate::settings::Settings;
use crate::state::{Data, State};
use accumulation::Guard;

/// Why a run stopped.
#[derive(Debug)]
pub enum StopReason {
    /// It reached its end time.
    EndTime,
    /// A contact no longer separates after its impacts (an accumulation of impacts, a
    /// plastic impact, a resting contact): persistent contact is not modelled yet.
    Accumulation {
        /// Time (s).
        t: Real,
        /// The contact pair.
        pair: usize,
        /// Its name, `<collider a>/<collider b>`.
        name: String,
        /// What was seen.
        reason: String,
    },
    /// The caller asked it to stop (Ctrl-C).
    Interrupted {
        /// Time reached (s).
        t: Real,
    },
    /// Something failed; the error says when and what.
    Failed(SimError),
}

impl StopReason {
    /// A short name for logs: `t_end`, `accumulation`, `interrupted`, `error`.
    pub fn name(&self) -> &'static str {
        match self {
            StopReason::EndTime => "t_end",
            StopReason::Accumulation { .. } => "accumulation",
            StopReason::Interrupted { .. } => "interrupted",
            StopReason::Failed(_) => "error",
        }
    }
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::EndTime => f.write_str("reached the end time"),
            StopReason::Accumulation { name, reason, .. } => {
                write!(f, "accumulation of impacts on {name}: {reason}")
            }
            StopReason::Interrupted { .. } => f.write_str("interrupted"),
            StopReason::Failed(e) => write!(f, "failed: {e}"),
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
    Integrate(#[from] IntegrateError<DynamicsError>),
    /// Locating an event failed.
    #[error(transparent)]
    Locate(#[from] EventError<ContactError>),
    /// Settling on an event failed.
    #[error(transparent)]
    Settle(#[from] EventError<ContactError, DynamicsError>),
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
}

impl EnergyAudit {
    /// What the bookkeeping does not explain, the integration drift:
    /// `E_end − E_0 − (ΣΔE + Σ Eq. 28 + W_damping + W_applied + W_drives)` (J).
    pub fn drift(&self) -> Real {
        self.end.total()
            - self.initial.total()
            - (self.impact_delta_e
                + self.impact_prescribed_work
                + self.damping_work
                + self.applied_work
                + self.drive_work)
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

/// The most impacts applied at one instant before giving up (simultaneous contacts that
/// keep re-closing each other).
const MAX_IMPACTS_AT_ONE_INSTANT: usize = 100;

/// A simulation of one model with its settings; [`Simulation::run`] runs it.
pub struct Simulation<'m> {
    model: &'m Model,
    settings: Settings,
    overrides: MaterialOverride,
    scales: Scales,
    system: MotionSystem<'m>,
    gaps: GapFunctions<'m>,
    stepper: AnyStepper,
    locator: EventLocator,
    map: ImpactMap,
    /// Scratch for samples.
    sampler: Data,
    armed: Vec<bool>,
    guard: Guard,
    /// Scratch state `y`.
    y: Vec<Real>,
    /// Scratch gaps.
    gap_values: Vec<Real>,
    /// Index of the next output time `k / rate`.
    next_output: u64,
    audit: EnergyAudit,
    counters: RunCounters,
    /// Time of the last sample reported (s).
    last_sample_t: Option<Real>,
}

impl<'m> Simulation<'m> {
    /// A simulation of `model` with `settings` and the material overrides.
    pub fn new(
        model: &'m Model,
        settings: &Settings,
        overrides: MaterialOverride,
    ) -> Result<Self, SimError> {
        overrides.validate()?;
        let system = MotionSystem::new(model);
        let n = crate::integrate::OdeSystem::dim(&system);
        let npairs = model.pairs().len();
        let scales = Scales::of(model, &settings.integrator);
        Ok(Self {
            model,
            settings: settings.clone(),
            overrides,
            scales,
            stepper: AnyStepper::new(n, &settings.integrator)?,
            locator: EventLocator::new(n, npairs, LocatorSettings::default()),
            system,
            gaps: GapFunctions::new(model),
            map: ImpactMap::new(model),
            sampler: Data::new(model),
            armed: vec![true; npairs],
            guard: Guard::new(scales),
            y: vec![0.0; n],
            gap_values: vec![0.0; npairs],
            next_output: 0,
            audit: EnergyAudit::default(),
            counters: RunCounters::default(),
            last_sample_t: None,
        })
    }

    /// The scales used for tolerances (length, resting speed).
    pub fn scales(&self) -> Scales {
        self.scales
    }

    /// Runs from `initial` to the end time, reporting to `observer`; stops early when
    /// `interrupt` becomes true. Always returns a summary: a failure is a stop reason.
    pub fn run(
        &mut self,
        initial: &State,
        observer: &mut dyn Observer,
        interrupt: Option<&AtomicBool>,
    ) -> RunSummary {
        let stop = match self.run_stages(initial, observer, interrupt) {
            Ok(stop) => stop,
            Err(e) => StopReason::Failed(e),
        };
        self.finish(stop, observer)
    }

    /// The loop, as named stages.
    fn run_stages(
        &mut self,
        initial: &State,
        observer: &mut dyn Observer,
        interrupt: Option<&AtomicBool>,
    ) -> Result<StopReason, SimError> {
        self.start(initial, observer)?;
        if let Some(stop) = self.impacts(None, observer)? {
            return Ok(stop);
        }
        let t_end = self.settings.t_end;
        loop {
            let t = self.stepper.t();
            self.rearm(t)?;
            if interrupt.is_some_and(|flag| flag.load(Ordering::Relaxed)) {
                return Ok(StopReason::Interrupted { t });
            }
            if t >= t_end {
                return Ok(StopReason::EndTime);
            }
            self.stepper.step(&mut self.system, t_end)?;
            match self
                .locator
                .locate(&self.stepper, &mut self.gaps, &self.armed)?
            {
                None => self.samples_until(self.stepper.t(), observer)?,
                Some(event) => {
                    self.counters.events += 1;
                    self.settle(&event)?;
                    self.samples_until(self.stepper.t(), observer)?;
                    if let Some(stop) = self.impacts(Some(&event), observer)? {
                        return Ok(stop);
                    }
                }
            }
        }
    }

    /// Stage `start`: the initial state, energy and sample.
    fn start(&mut self, initial: &State, observer: &mut dyn Observer) -> Result<(), SimError> {
        let n = self.model.nq();
        if initial.q.len() != n || initial.u.len() != n {
            return Err(SimError::InitialState {
                expected: n,
                got: initial.q.len().min(initial.u.len()),
            });
        }
        let t0 = initial.t;
        self.y.fill(0.0);
        self.y[..n].copy_from_slice(initial.q.as_slice());
        self.y[n..2 * n].copy_from_slice(initial.u.as_slice());
        self.stepper.start(&mut self.system, t0, &self.y)?;
        self.audit.initial = energy(
            self.model,
            &mut self.sampler,
            t0,
            initial.q.as_slice(),
            initial.u.as_slice(),
        )
        .map_err(|e| e.at(t0))?;
        self.guard.reset(t0);
        let rate = self.settings.output_rate;
        self.next_output = if rate > 0.0 {
            (t0 * rate).ceil() as u64
        } else {
            u64::MAX
        };
        let y = std::mem::take(&mut self.y);
        let result = self.sample(t0, &y, false, observer);
        self.y = y;
        result?;
        if self.next_output as Real / rate <= t0 {
            self.next_output += 1;
        }
        Ok(())
    }

    /// Stage `rearm`: a pair disarmed after a spurious event is armed again once its gap
    /// exceeds the closed-contact tolerance; then the step cap is lifted.
    fn rearm(&mut self, t: Real) -> Result<(), SimError> {
        if self.armed.iter().all(|&a| a) {
            return Ok(());
        }
        let n = self.model.nq();
        update_positions(self.model, &mut self.sampler, t, &self.stepper.y()[..n])
            .map_err(|e| e.at(t))?;
        for (k, armed) in self.armed.iter_mut().enumerate() {
            if !*armed {
                let gap = crate::contact::signed_gap(
                    self.model,
                    &self.sampler,
                    PairId(k),
                    Real::INFINITY,
                )
                .map_err(|e| e.at(t))?
                .unwrap_or(Real::INFINITY);
                *armed = gap > self.scales.gap_tol;
            }
        }
        if self.armed.iter().all(|&a| a) {
            self.stepper.set_h_max(self.settings.integrator.h_max);
        }
        Ok(())
    }

    /// Stage `settle`: the state at the event time at the method's full order.
    fn settle(&mut self, event: &Event) -> Result<(), SimError> {
        self.locator
            .settle(&mut self.stepper, &mut self.system, &mut self.gaps, event)?;
        Ok(())
    }

    /// Stage `samples`: every output time up to `t_until` on the last step's dense output.
    fn samples_until(
        &mut self,
        t_until: Real,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let rate = self.settings.output_rate;
        if rate.is_nan() || rate <= 0.0 {
            return Ok(());
        }
        let mut y = std::mem::take(&mut self.y);
        let mut result = Ok(());
        loop {
            let t = self.next_output as Real / rate;
            if t > t_until || t > self.settings.t_end {
                break;
            }
            if observer.wants_samples() {
                if t == self.stepper.t() {
                    y.copy_from_slice(self.stepper.y());
                } else {
                    self.stepper.dense(t, &mut y);
                }
                result = self.sample(t, &y, false, observer);
                if result.is_err() {
                    break;
                }
            }
            self.next_output += 1;
        }
        self.y = y;
        result
    }

    /// One sample of the state `y` at `t`.
    fn sample(
        &mut self,
        t: Real,
        y: &[Real],
        at_impact: bool,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        if !observer.wants_samples() {
            return Ok(());
        }
        let n = self.model.nq();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        let e = energy(self.model, &mut self.sampler, t, q, u).map_err(|e| e.at(t))?;
        for (k, g) in self.gap_values.iter_mut().enumerate() {
            *g = crate::contact::signed_gap(self.model, &self.sampler, PairId(k), Real::INFINITY)
                .map_err(|e| e.at(t))?
                .unwrap_or(Real::INFINITY);
        }
        let sample = Sample {
            t,
            q,
            u,
            energy: e,
            gaps: &self.gap_values,
            poses: &self.sampler.body_pose,
            at_impact,
        };
        observer.sample(self.model, &sample).map_err(|e| e.at(t))?;
        self.counters.samples += 1;
        self.last_sample_t = Some(t);
        Ok(())
    }

    /// Stage `impacts`: applies the impact map to every contact that is closed and
    /// approaching at the current time, the most violent first, until none approaches;
    /// then restarts the integrator from the new state. Returns a stop reason if a contact
    /// no longer separates (`accumulation`).
    fn impacts(
        &mut self,
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<Option<StopReason>, SimError> {
        let t = self.stepper.t();
        let mut y = std::mem::take(&mut self.y);
        y.copy_from_slice(self.stepper.y());
        let result = self.impacts_at(t, &mut y, event, observer);
        let outcome = match result {
            Ok((applied, stop)) => {
                if applied > 0 {
                    let reset = self.stepper.reset(&mut self.system, t, &y);
                    let sample = self.sample(t, &y, true, observer);
                    reset.map_err(SimError::from).and(sample).map(|()| stop)
                } else {
                    Ok(stop)
                }
            }
            Err(e) => Err(e),
        };
        self.y = y;
        outcome
    }

    /// The impacts at `t` on the state `y` (updated in place); the number applied and a
    /// stop reason, if any.
    fn impacts_at(
        &mut self,
        t: Real,
        y: &mut [Real],
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<(usize, Option<StopReason>), SimError> {
        let n = self.model.nq();
        let mut applied = 0usize;
        // The closed contact that approaches fastest, until none approaches.
        while let Some((pair, v_n)) = self.most_approaching(t, y)? {
            if applied == 0 {
                self.sample(t, y, true, observer)?;
            }
            if applied == MAX_IMPACTS_AT_ONE_INSTANT {
                return Err(SimError::Simultaneous { t, rounds: applied });
            }
            let material = self
                .overrides
                .apply(self.model.pairs()[pair.index()].material);
            let (q, u) = y[..2 * n].split_at_mut(n);
            let Some(mut impact) = self.map.apply(self.model, pair, material, t, q, u)? else {
                return Err(SimError::Contact {
                    t,
                    message: format!(
                        "pair #{} approaches at {v_n} m/s but its impact map found no approach",
                        pair.index()
                    ),
                });
            };
            impact.index = self.counters.impacts;
            self.counters.impacts += 1;
            applied += 1;
            self.audit.impact_delta_e += impact.outcome.delta_e;
            self.audit.impact_prescribed_work += impact.prescribed_work();
            observer.impact(self.model, &impact).map_err(|e| e.at(t))?;
            if applied == 2 {
                observer
                    .message(
                        t,
                        Level::Warning,
                        "simultaneous impacts: applied one contact at a time, the fastest approach first",
                    )
                    .map_err(|e| e.at(t))?;
            }
            if let Some(reason) = self.guard.after_impact(t, impact.outcome.v_s.n) {
                return Ok((applied, Some(self.accumulation(t, pair, reason))));
            }
        }
        if applied == 0
            && let Some(event) = event
        {
            let pair = PairId(event.index);
            let frame = self.map.frame(self.model, pair, t, &y[..n], &y[n..2 * n])?;
            if frame.v_n() > self.scales.v_tiny {
                // The contact separates: the "crossing" was the gap's rounding noise just
                // after an impact (the separation is still below it). Disarm the pair
                // until it is clearly open, with steps short enough to see it close again.
                self.armed[pair.index()] = false;
                let h = 10.0 * self.scales.gap_tol / frame.v_n();
                self.stepper
                    .set_h_max(h.min(self.settings.integrator.h_max));
                return Ok((0, None));
            }
            // The event closed a contact that does not approach: a resting or rolling
            // contact, which needs persistent-contact modes.
            let reason = format!(
                "the contact closed ({:?}) without approaching: gap {:.3e} m, normal velocity \
                 {:.3e} m/s",
                event.kind,
                frame.gap,
                frame.v_n()
            );
            return Ok((0, Some(self.accumulation(t, pair, reason))));
        }
        Ok((applied, None))
    }

    /// The closed contact (gap within the tolerance) that approaches fastest, if any
    /// approaches faster than the resting speed's tiny fraction.
    fn most_approaching(
        &mut self,
        t: Real,
        y: &[Real],
    ) -> Result<Option<(PairId, Real)>, SimError> {
        let n = self.model.nq();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        update_positions(self.model, &mut self.sampler, t, q).map_err(|e| e.at(t))?;
        let mut best: Option<(PairId, Real)> = None;
        for k in 0..self.model.pairs().len() {
            let pair = PairId(k);
            let gap = crate::contact::signed_gap(self.model, &self.sampler, pair, Real::INFINITY)
                .map_err(|e| e.at(t))?
                .unwrap_or(Real::INFINITY);
            if gap > self.scales.gap_tol {
                continue;
            }
            let v_n = self.map.frame(self.model, pair, t, q, u)?.v_n();
            if v_n < -self.scales.v_tiny && best.is_none_or(|(_, b)| v_n < b) {
                best = Some((pair, v_n));
            }
        }
        Ok(best)
    }

    /// A stop for an accumulation (the final message goes to the log in [`Self::finish`]).
    fn accumulation(&mut self, t: Real, pair: PairId, reason: String) -> StopReason {
        StopReason::Accumulation {
            t,
            pair: pair.index(),
            name: impact_map::pair_name(self.model, pair),
            reason,
        }
    }

    /// Stage `finish`: the final sample, the energy audit and the counters.
    fn finish(&mut self, stop: StopReason, observer: &mut dyn Observer) -> RunSummary {
        let n = self.model.nq();
        let t = self.stepper.t();
        let y = self.stepper.y().to_vec();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        self.audit.end = energy(self.model, &mut self.sampler, t, q, u).unwrap_or(Energy {
            kinetic: Real::NAN,
            potential: Real::NAN,
        });
        if self.system.has_works() {
            self.audit.damping_work = y[2 * n];
            self.audit.applied_work = y[2 * n + 1];
            self.audit.drive_work = y[2 * n + 2];
        }
        let level = match stop {
            StopReason::Failed(_) => Level::Error,
            StopReason::Accumulation { .. } | StopReason::Interrupted { .. } => Level::Warning,
            StopReason::EndTime => Level::Info,
        };
        // The last sample and message are best effort: the run is over either way. No
        // sample twice at the same instant (the output grid may have just taken it).
        if self.last_sample_t != Some(t) {
            let _ = self.sample(t, &y, false, observer);
        }
        let _ = observer.message(t, level, &format!("run stopped at t = {t} s: {stop}"));
        let c = self.stepper.counters();
        self.counters.steps = c.steps;
        self.counters.rejected = c.rejected;
        self.counters.rhs_evals = c.rhs_evals;
        RunSummary {
            stop,
            state: State::new(
                t,
                nalgebra::DVector::from_column_slice(q),
                nalgebra::DVector::from_column_slice(u),
            ),
            audit: self.audit,
            counters: self.counters,
        }
    }
}
