//! The simulation loop: integrate between events, locate the first event on the dense
//! output, resolve what happens at its instant (impacts, contact modes), repeat until the
//! end time.
//!
//! ```text
//! start        y(t0) = [q0; u0; 0], E0, first sample, contacts already closed at t0
//! loop         stop?  (end time, Ctrl-C)
//!              step          one accepted integrator step              (integrate)
//!              locate        the earliest event in the step            (events)
//!              settle        re-take the step to the event time        (full order)
//!              samples       the output times passed, on dense output
//!              contacts      impacts (frame → W → law → Δu), accumulations,
//!                            persistent-contact modes, Painlevé         (contacts.rs)
//! finish       final sample, energy audit, counters
//! ```
//!
//! The events are the closing crossings of the functions of [`gaps`]: the gap of an open
//! contact (an impact), and, for closed contact points in persistent contact, the normal
//! force (lift-off), the friction margin (stick to slip), the slip velocity (slip to stop)
//! and the Painlevé coefficient.

mod accumulation;
mod broad;
mod contacts;
mod coupling;
mod error;
pub mod gaps;
mod impact_map;
mod moreau_jean;
mod observer;
#[doc(hidden)]
pub mod pair_map;
#[doc(hidden)]
pub mod persistent;
mod summary;
mod system;

use std::fmt::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};

pub use accumulation::Scales;
pub use error::{AtTime, Nested, SimError, StopReason, describe, describe_messages};
pub use gaps::GapFunctions;
pub use impact_map::{ImpactCause, ImpactEvent, ImpactMap, MaterialOverride, Support};
pub use moreau_jean::{MoreauJean, MoreauJeanSettings, SolverReport};
pub use observer::{
    Level, NullObserver, Observer, ObserverError, PairMode, Recorder, Sample, Transition,
};
pub use pair_map::PairMap;
pub use persistent::{Closed, Hold};
pub use summary::{EnergyAudit, RunCounters, RunSummary};
pub use system::MotionSystem;

use crate::dynamics::{Energy, energy};
use crate::events::{Event, EventLocator, LocatorSettings};
use crate::integrate::{AnyStepper, Stepper};
use crate::kinematics::{update_positions, update_velocities};
use crate::math::Real;
use crate::model::{Model, PairId};
use crate::settings::Settings;
use crate::state::{Data, State};
use accumulation::Guard;

/// The samples of a model with at most this many pairs list every pair; beyond, the pairs
/// near contact (see `Simulation::list_pairs`).
pub const LISTED_PAIRS: usize = 1000;

/// A gap event disarmed after a crossing that closed nothing (see
/// `disarm_open_crossing`): armed again, normally, once the gap is clearly open.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Disarm {
    /// The step cap while disarmed (s): steps short enough to see a separating contact
    /// close again (infinite for a grazing one).
    cap: Real,
    /// The time (s) after which the cap no longer holds, though the pair may stay
    /// disarmed: ten caps after the crossing, a contact separating at the speed the cap
    /// was made for is 100 gap_tol clear; one still within the tolerance is not
    /// separating at that speed but held (the end of a link lying on the floor at a
    /// hinge), and its floor alone watches it.
    until: Real,
    /// The gap (m, `≤ −gap_tol`) below which the point counts as sinking: the event
    /// function is `gap − floor` meanwhile.
    floor: Real,
}

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
    /// Which contact points are coupled (solved together at an instant).
    coupling: coupling::Coupling,
    /// Scratch for samples.
    sampler: Data,
    /// Armed event functions of the candidate pairs (see [`gaps::slot`]).
    armed: Vec<bool>,
    /// Pairs whose gap event is disarmed after a spurious crossing (rounding noise just
    /// after an impact), until they are clearly open (see `disarm_open_crossing`).
    disarmed: PairMap<Option<Disarm>>,
    /// The mode of each pair, for the samples.
    modes: PairMap<PairMode>,
    /// The slip direction of each pair, for the samples (see [`Sample::slips`]).
    slips: PairMap<i8>,
    /// The last instant of impacts on each pair and the fastest separation of its points
    /// then `(t, v_n)`: the last hop, for the ratio and duration of an accumulation.
    last_separation: PairMap<Option<(Real, Real)>>,
    /// The pairs whose accumulation of impacts ended at the current instant, until the
    /// mode selection reports them.
    accumulating: PairMap<Option<contacts::Accumulation>>,
    /// An instant `t` and the approach speed (m/s, at most `v_drift`) that the impact laws
    /// left unresolved there (see `leave_unresolved`): at `t`, a touching point approaches
    /// only faster than that.
    unresolved: (Real, Real),
    /// The bounding boxes of the colliders for the broad phase (see [`broad`]).
    boxes: Vec<parry2d_f64::bounding_volume::Aabb>,
    /// The regions of the half-spaces among them (see [`broad::Plane`]).
    planes: Vec<broad::Plane>,
    /// Their hierarchy, kept between steps.
    finder: crate::contact::broad::PairFinder,
    /// Scratch pairs (see `rearm`).
    pair_scratch: Vec<PairId>,
    /// Every pair, when the model has at most [`LISTED_PAIRS`] (the samples list them all).
    all_pairs: Option<Vec<PairId>>,
    /// Without the broad phase, every pair of the model: each step samples them all (the
    /// oracle of the tests; see [`Self::set_broad_phase`]).
    every_pair: Option<Vec<PairId>>,
    /// The pairs the current sample lists, and their gaps, modes and slips.
    listed: Vec<PairId>,
    listed_modes: Vec<PairMode>,
    listed_slips: Vec<i8>,
    /// Changes of mode to report later: passages to persistent contact stamped at the
    /// extrapolated end `t∞` of an accumulation (the samples before it show the old mode).
    passages: Vec<contacts::Passage>,
    guard: Guard,
    /// Samples per step of the event location.
    locator_samples: usize,
    /// The last choice among several consistent contact modes: its time, and how many
    /// times in a row a choice was undone at once (see `select_modes`).
    indeterminate: (Real, usize),
    /// The points that started to slip at the instant of the last contact stage, and that
    /// instant (see `slip_starts_at`).
    slip_starts: (Real, Vec<(PairId, crate::math::Vec2, Real)>),
    /// The points that lifted off at the instant of the last contact stage, and that
    /// instant (see `lift_offs_at`).
    lift_offs: (Real, Vec<(PairId, crate::math::Vec2)>),
    /// Scratch state `y`.
    y: Vec<Real>,
    /// Scratch of the contact stage (see [`contacts::Scratch`]).
    scratch: contacts::Scratch,
    /// Scratch gaps.
    gap_values: Vec<Real>,
    /// Index of the next output time `k / rate`.
    next_output: u64,
    audit: EnergyAudit,
    counters: RunCounters,
    /// Runs of the contact stage in this run ([`Sample::contact_stages`]).
    contact_stages: u64,
    /// Time of the last sample reported (s).
    last_sample_t: Option<Real>,
    /// The stepper's largest step as built (s), for each run's start (`cap_for_spin`
    /// changes it at every step).
    h_max: Real,
    /// The stepper's counters at the start of the run (they count since it was built).
    stepper_counters: crate::integrate::Counters,
}

impl<'m> Simulation<'m> {
    /// A simulation of `model` with `settings` and the material overrides.
    pub fn new(
        model: &'m Model,
        settings: &Settings,
        overrides: MaterialOverride,
    ) -> Result<Self, SimError> {
        overrides.validate()?;
        let scales = Scales::of(model, &settings.integrator);
        let system = MotionSystem::new(model, scales);
        let n = crate::integrate::OdeSystem::dim(&system);
        let all_pairs = broad::all_pairs_if_few(model);
        let mut stepper = AnyStepper::new(n, &settings.integrator)?;
        let h_max = stepper.h_max();
        // A step below 10 ε t_end cannot bring the run to its end: it is lost in the
        // rounding of any time near t_end. (The floor 10 ε |t| alone is 0 at t = 0, where a
        // run whose steps kept shrinking never failed.)
        stepper.set_h_min(10.0 * Real::EPSILON * settings.t_end.abs());
        // Room for the event functions of every pair of a model with at most LISTED_PAIRS
        // of them: the candidate pairs grow and shrink with the motion, and the loop then
        // allocates nothing (beyond, the buffers grow to the largest candidate set).
        let pairs = all_pairs.as_ref().map_or(0, Vec::len);
        let mut gaps = GapFunctions::new(model, scales);
        gaps.reserve(pairs);
        let mut locator = EventLocator::new(n, 0, LocatorSettings::default());
        locator.reserve(gaps::SLOTS * pairs);
        Ok(Self {
            model,
            settings: settings.clone(),
            overrides,
            scales,
            stepper,
            locator,
            system,
            gaps,
            map: ImpactMap::new(model).with_still(scales.v_drift),
            coupling: coupling::Coupling::new(model),
            sampler: Data::new(model),
            armed: Vec::with_capacity(gaps::SLOTS * pairs),
            disarmed: PairMap::new(None),
            modes: PairMap::new(PairMode::Free),
            slips: PairMap::new(0),
            last_separation: PairMap::new(None),
            accumulating: PairMap::new(None),
            unresolved: (Real::NAN, 0.0),
            boxes: Vec::new(),
            planes: Vec::new(),
            finder: Default::default(),
            pair_scratch: Vec::new(),
            all_pairs,
            every_pair: None,
            listed: Vec::new(),
            listed_modes: Vec::new(),
            listed_slips: Vec::new(),
            passages: Vec::new(),
            guard: Guard::new(),
            locator_samples: LocatorSettings::default().samples,
            indeterminate: (Real::NEG_INFINITY, 0),
            slip_starts: (Real::NEG_INFINITY, Vec::new()),
            lift_offs: (Real::NEG_INFINITY, Vec::new()),
            y: vec![0.0; n],
            scratch: Default::default(),
            gap_values: Vec::new(),
            next_output: 0,
            audit: EnergyAudit::default(),
            counters: RunCounters::default(),
            contact_stages: 0,
            last_sample_t: None,
            h_max,
            stepper_counters: Default::default(),
        })
    }

    /// Turns the broad phase off (`false`: every step samples the event functions of every
    /// pair, `O(n²)`, as before it existed) or on again (the default). With it off the
    /// runs must be the same bit for bit: the oracle of `tests/all/broad_phase.rs`.
    pub fn set_broad_phase(&mut self, on: bool) {
        self.every_pair = (!on).then(|| self.model.pair_ids().collect());
    }

    /// Allows (the default) or forbids the stand-ins of the force functions at the
    /// interior samples of the event location (see `gaps::StandIns`) and the taking of the
    /// right-hand side's forces at a step's end (`GapFunctions::take_end_evaluation`).
    /// Forbidden, every sample solves the constrained dynamics: the runs must be the same
    /// bit for bit (the oracle of `tests/all/event_stand_ins.rs`).
    pub fn set_stand_ins(&mut self, on: bool) {
        self.gaps.set_stand_ins(on);
    }

    /// The integrator's work counters since the simulation was built (all its runs):
    /// with the re-steps, resets and completed dense outputs that the run's counters do
    /// not show.
    pub fn stepper_counters(&self) -> crate::integrate::Counters {
        self.stepper.counters()
    }

    /// What the stand-ins of the force functions did in the event location: the interior
    /// samples with closed points, those that used them, the steps located again.
    pub fn stand_in_counts(&self) -> gaps::StandInCounts {
        self.gaps.stand_in_counts()
    }

    /// The closed contact points in persistent contact now, with their modes.
    pub fn closed_points(&self) -> &[Closed] {
        self.gaps.persistent.closed()
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
        self.arm();
        if let Some(stop) = self.contacts(None, observer)? {
            return Ok(stop);
        }
        let t_end = self.settings.t_end;
        loop {
            let t = self.stepper.t();
            self.gaps.persistent.release_margins();
            self.rearm(t)?;
            if interrupt.is_some_and(|flag| flag.load(Ordering::Relaxed)) {
                return Ok(StopReason::Interrupted { t });
            }
            if t >= t_end {
                return Ok(StopReason::EndTime);
            }
            self.broad_before_step()?;
            self.cap_for_spin()?;
            self.system.persistent.clear_bounds();
            self.stepper.step(&mut self.system, t_end)?;
            self.broad_after_step()?;
            let Some(found) = self.locate()? else {
                // The closed contacts have no forces from some instant inside the step on
                // (a mode that stops being consistent): the run is now just before it;
                // the contact stage selects the modes there again.
                self.samples_until(self.stepper.t(), observer)?;
                if let Some(stop) = self.contacts(None, observer)? {
                    return Ok(stop);
                }
                if let Some(reason) = self.guard.after_event(self.stepper.t()) {
                    return Ok(self.stall(self.stepper.t(), PairId(0), reason));
                }
                continue;
            };
            match found {
                None => self.samples_until(self.stepper.t(), observer)?,
                Some(event) => {
                    self.counters.events += 1;
                    self.settle(&event)?;
                    // The event with its slot among every pair's (`SLOTS · pair + s`).
                    let event = Event {
                        index: self.gaps.global_slot(event.index),
                        ..event
                    };
                    if let Some(reason) = self.guard.after_event(self.stepper.t()) {
                        return Ok(self.stall(
                            self.stepper.t(),
                            PairId(event.index / gaps::SLOTS),
                            reason,
                        ));
                    }
                    self.samples_until(self.stepper.t(), observer)?;
                    if let Some(stop) = self.contacts(Some(&event), observer)? {
                        return Ok(stop);
                    }
                }
            }
        }
    }

    /// Stage `start`: the initial state, energy and sample.
    fn start(&mut self, initial: &State, observer: &mut dyn Observer) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        if initial.q.len() != n || initial.u.len() != nqu - n {
            return Err(SimError::InitialState {
                expected_q: n,
                expected_u: nqu - n,
                got_q: initial.q.len(),
                got_u: initial.u.len(),
            });
        }
        let t0 = initial.t;
        self.reset();
        self.y.fill(0.0);
        self.y[..n].copy_from_slice(initial.q.as_slice());
        self.y[n..nqu].copy_from_slice(initial.u.as_slice());
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

    /// Forgets what an earlier run left: every run starts as on a new simulation (the
    /// same results bit for bit, `tests/all/sim_alloc.rs`), with the buffers it kept.
    fn reset(&mut self) {
        if self.stepper.counters() == Default::default() {
            // A new simulation: nothing to forget.
            return;
        }
        self.system.persistent.set_from(&[], &[]);
        self.gaps.set_closed(&[], &[]);
        self.gaps.candidates.clear();
        self.gaps.disarmed.clear();
        self.stepper.set_h_max(self.h_max);
        self.disarmed.reset_stored(&None);
        self.modes.reset_stored(&PairMode::Free);
        self.slips.reset_stored(&0);
        self.last_separation.reset_stored(&None);
        self.accumulating.reset_stored(&None);
        self.unresolved = (Real::NAN, 0.0);
        self.passages.clear();
        self.indeterminate = (Real::NEG_INFINITY, 0);
        self.slip_starts = (Real::NEG_INFINITY, std::mem::take(&mut self.slip_starts.1));
        self.slip_starts.1.clear();
        self.lift_offs = (Real::NEG_INFINITY, std::mem::take(&mut self.lift_offs.1));
        self.lift_offs.1.clear();
        self.audit = EnergyAudit::default();
        self.counters = RunCounters::default();
        self.contact_stages = 0;
        self.last_sample_t = None;
        self.stepper_counters = self.stepper.counters();
    }

    /// Stage `rearm`: a pair whose gap event is disarmed (a spurious or grazing crossing)
    /// is armed again once that gap exceeds the closed-contact tolerance; then the step cap
    /// is lifted.
    fn rearm(&mut self, t: Real) -> Result<(), SimError> {
        let mut disarmed = std::mem::take(&mut self.pair_scratch);
        disarmed.clear();
        disarmed.extend(self.disarmed.changed());
        let mut result: Result<(), SimError> = Ok(());
        for &pair in &disarmed {
            match self.gaps.open_gap(pair, t, self.stepper.y()) {
                Ok(gap) if gap > self.scales.gap_tol => self.disarmed[pair.index()] = None,
                Ok(_) => {}
                Err(e) => {
                    result = Err(e.into());
                    break;
                }
            }
        }
        let any = !disarmed.is_empty();
        self.pair_scratch = disarmed;
        result?;
        if any {
            self.disarmed.prune();
            self.arm();
        }
        Ok(())
    }

    /// Arms the event functions of the current contact modes (see [`gaps::slot`]).
    /// The pairs with a closed point and those whose gap event is disarmed join the
    /// candidates first (see [`broad`]).
    fn arm(&mut self) {
        let closed = self.system.persistent.closed();
        let always = (closed.iter().map(|c| c.pair)).chain(self.disarmed.changed());
        self.gaps.add_candidates(always);
        let candidates = &self.gaps.candidates;
        self.armed.clear();
        self.armed.resize(gaps::SLOTS * candidates.len(), false);
        self.locator.set_len(self.armed.len());
        // A disarmed pair's gap stays armed below its floor: its function is
        // `gap − floor`. The gap of an end of a link lying at a hinge whose other end is
        // closed is held at zero, and stays disarmed for good; when that hold goes (its
        // neighbour slides off, the link turns) the point sank through the floor unseen
        // (the 32-link chain: hinges 2.8 cm deep at 5 s).
        for (r, &pair) in candidates.iter().enumerate() {
            let on_pair = closed.iter().filter(|c| c.pair == pair).count();
            self.armed[gaps::SLOTS * r] = on_pair < 2;
        }
        self.gaps.disarmed.clear();
        self.gaps.disarmed.extend(
            (self.disarmed.changed())
                .filter_map(|pair| Some((pair, self.disarmed[pair.index()]?.floor))),
        );
        for (i, c) in closed.iter().enumerate() {
            let j = gaps::rank(&self.system.persistent, i);
            let Some(slot) = self.gaps.slot_of(c.pair, 0) else {
                continue;
            };
            self.armed[slot + 1 + 3 * j] = true;
            self.armed[slot + 2 + 3 * j] = true;
            self.armed[slot + 3 + 3 * j] = matches!(c.hold, Hold::Slide(_));
        }
    }

    /// Stage `broad` before the step: the candidates of the coming step for its cap,
    /// from the boxes grown by what the colliders travel within the horizon
    /// `H = min(h_max, 1.01 · 10 h_next)` from their speeds and gravity (see [`broad`]).
    /// The kinematics of the step's start: the right-hand side's, or computed into
    /// `self.sampler` (see [`Self::start_kinematics`]); `cap_for_spin` reads them too.
    fn broad_before_step(&mut self) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let t = self.stepper.t();
        if Self::start_kinematics(self.model, &self.system, &self.stepper, &self.gaps).is_none() {
            let y = self.stepper.y();
            update_positions(self.model, &mut self.sampler, t, &y[..n]).map_err(|e| e.at(t))?;
            update_velocities(self.model, &mut self.sampler, &y[n..nqu]).map_err(|e| e.at(t))?;
        }
        if self.every_pair_forced() {
            self.arm();
            return Ok(());
        }
        let h = self
            .h_max_base()
            .min(1.01 * broad::GROWTH * self.stepper.h_next());
        let (g, slack) = (self.model.gravity().length(), 10.0 * self.scales.gap_tol);
        let start = Self::start_kinematics(self.model, &self.system, &self.stepper, &self.gaps)
            .unwrap_or(&self.sampler);
        let regions = (&mut self.boxes, &mut self.planes);
        broad::grown_boxes(self.model, start, regions, |v| {
            v * h + 0.5 * g * h * h + slack
        })
        .map_err(|e| e.at(t))?;
        self.find_candidates();
        self.arm();
        Ok(())
    }

    /// The right-hand side's kinematics of the step's start, if its last evaluation was
    /// that state (the last stage of the step that ended there; the same numbers as
    /// computed, see `GapFunctions::take_end_kinematics`), read where they are instead of
    /// copied; `None`: `broad_before_step` computes them into `self.sampler`.
    fn start_kinematics<'a>(
        model: &Model,
        system: &'a MotionSystem<'_>,
        stepper: &AnyStepper,
        gaps: &GapFunctions<'_>,
    ) -> Option<&'a Data> {
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        let y = stepper.y();
        (system.kinematics_at(stepper.t(), &y[..n], &y[n..nqu]))
            .filter(|_| gaps.shares_kinematics())
    }

    /// Stage `broad` after the step: the boxes before the step grown to hold the
    /// colliders' boxes at the locator's sample times, each grown by what it travels in a
    /// sample interval at its speed bound there; their overlapping pairs are the
    /// candidates of the event location (see [`broad`]).
    fn broad_after_step(&mut self) -> Result<(), SimError> {
        if self.every_pair_forced() {
            // `broad_before_step` armed the same candidates for this step: the closed
            // points (only the contact stage sets them) and the disarmed pairs are those it
            // saw (every pair forced then too), and nothing since changed the candidates.
            return Ok(());
        }
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (t0, t1) = (self.stepper.t_prev(), self.stepper.t());
        let parts = self.locator_samples + 1;
        let dt = (t1 - t0) / parts as Real;
        let mut y = std::mem::take(&mut self.y);
        let mut result = Ok(());
        for j in 0..=parts {
            let t = if j == parts {
                t1
            } else {
                t0 + (t1 - t0) * (j as Real / parts as Real)
            };
            if j == parts {
                y.copy_from_slice(self.stepper.y());
            } else if j == 0 {
                y.copy_from_slice(self.stepper.y_prev());
            } else {
                result = (self.stepper.dense_completing(&mut self.system, t, &mut y))
                    .map_err(SimError::from);
                if result.is_err() {
                    break;
                }
            }
            let shared = (self.system.kinematics_at(t, &y[..n], &y[n..nqu]))
                .filter(|_| self.gaps.shares_kinematics());
            result = match shared {
                // The step's end: the right-hand side's last stage evaluated it.
                Some(data) => {
                    self.sampler.copy_kinematics_from(data);
                    Ok(())
                }
                None => update_positions(self.model, &mut self.sampler, t, &y[..n])
                    .and_then(|()| update_velocities(self.model, &mut self.sampler, &y[n..nqu])),
            }
            .and_then(|()| {
                let regions = (&mut self.boxes[..], &mut self.planes[..]);
                broad::sweep_boxes(self.model, &self.sampler, regions, |v| v * dt)
            })
            .map_err(|e| e.at(t));
            if result.is_err() {
                break;
            }
        }
        self.y = y;
        result?;
        self.find_candidates();
        self.arm();
        Ok(())
    }

    /// Whether every pair of the model is a candidate whatever the boxes: each has a
    /// closed point or a disarmed gap event, and `arm` adds those pairs to the candidates
    /// (a pendulum's tip sliding on the floor, its only pair). The broad phase can then
    /// add nothing and is skipped: the same candidates, the same steps and events.
    fn every_pair_forced(&self) -> bool {
        let Some(all) = &self.all_pairs else {
            return false;
        };
        let closed = self.system.persistent.closed();
        all.iter().all(|&pair| {
            closed.iter().any(|c| c.pair == pair) || self.disarmed[pair.index()].is_some()
        })
    }

    /// The candidates of the event location: the pairs whose boxes `self.boxes` overlap,
    /// or every pair without the broad phase.
    fn find_candidates(&mut self) {
        match &self.every_pair {
            Some(all) => {
                self.gaps.candidates.clear();
                self.gaps.candidates.extend_from_slice(all);
            }
            None => {
                let regions = (&self.boxes[..], &self.planes[..]);
                (self.finder).overlapping_pairs(self.model, regions, &mut self.gaps.candidates)
            }
        }
    }

    /// The pairs whose boxes, grown by `margin` (m), overlap at the positions of
    /// `self.sampler`, in pair order, into `near`: every pair within `margin` of contact.
    /// Without the broad phase, every pair.
    fn near_pairs(
        &mut self,
        t: Real,
        margin: Real,
        near: &mut Vec<PairId>,
    ) -> Result<(), SimError> {
        if let Some(all) = &self.every_pair {
            near.clear();
            near.extend_from_slice(all);
            return Ok(());
        }
        let regions = (&mut self.boxes, &mut self.planes);
        broad::grown_boxes(self.model, &self.sampler, regions, |_| margin).map_err(|e| e.at(t))?;
        let regions = (&self.boxes[..], &self.planes[..]);
        (self.finder).overlapping_pairs(self.model, regions, near);
        Ok(())
    }

    /// The step cap before [`Self::cap_for_spin`]: the integrator's, or the shortest cap
    /// of the pairs disarmed now (see `disarm_open_crossing`). Each cap lasts while its
    /// own pair stays disarmed, and no longer than `CAP_LIFETIME` caps: a pair held at a
    /// zero gap for good (the end of a link lying on the floor at a hinge whose other
    /// link's end is closed) must not keep the cap of a separation long over.
    fn h_max_base(&self) -> Real {
        let t = self.stepper.t();
        (self.disarmed.changed())
            .filter_map(|pair| self.disarmed[pair.index()])
            .filter(|d| t < d.until)
            .map(|d| d.cap)
            .fold(self.settings.integrator.h_max, Real::min)
    }

    /// Caps the next step so that the event location cannot miss a contact of a fast or
    /// fast-turning body. The location samples each gap `samples + 1` times a step and
    /// assumes at most one extremum between samples; a turning shape's gap oscillates with
    /// its rotation, and a fast one crosses a thin obstacle in less than a sample (a
    /// spinning corner that dips into the floor, a sliver or a segment that tunnels through
    /// a segment). For each pair whose gap event is armed, with `V` a bound of the
    /// relative speed of any two points of its shapes (`|v_G| + |ω| (|c − G| + r)` of
    /// each, `G` its body's centre of mass, `c` and `r` the centre and radius of the
    /// shape's bounding circle: a bound that holds as the body turns), `d` its gap, `R` the
    /// smaller of the two radii and `g` the gravity:
    ///
    /// ```text
    /// h ≤ max( 2d / (V + √(V² + 2|g|d)),  (samples + 1) · min(R/8 / V,  (π/8) / |ω|max) )
    /// ```
    ///
    /// — no cap while the shapes cannot reach each other within the step (the time to
    /// cover `d` from the speed `V` under gravity), and
    /// near them samples no farther apart than an eighth of the smaller shape's radius of
    /// relative motion, and an eighth of a half-turn of rotation. The speeds are those of
    /// the kinematics of the step's start that `broad_before_step` found or computed.
    fn cap_for_spin(&mut self) -> Result<(), SimError> {
        let t = self.stepper.t();
        let mut cap = self.h_max_base();
        let samples = (self.locator_samples + 1) as Real;
        // Gravity speeds the bodies up within the step: the time to cover d from speed V
        // at |g| is 2d / (V + √(V² + 2|g|d)).
        let g = self.model.gravity().length();
        // One kinematics pass for the gaps of every pair below, at the first that needs it.
        let mut positions = false;
        let start = Self::start_kinematics(self.model, &self.system, &self.stepper, &self.gaps)
            .unwrap_or(&self.sampler);
        for r in 0..self.gaps.candidates.len() {
            if !self.armed[gaps::SLOTS * r] {
                continue;
            }
            let id = self.gaps.candidates[r];
            // `model.pair_of`, through the event functions' last lookup (the same pair).
            let pair = self.gaps.pair_of(id);
            let reach = |c| broad::reach(self.model, start, c);
            let ((va, ra, wa), (vb, rb, wb)) = (reach(pair.a), reach(pair.b));
            let v = va + vb;
            if v.is_nan() || v <= 0.0 {
                continue;
            }
            let fine =
                samples * (ra.min(rb) / 8.0 / v).min(std::f64::consts::FRAC_PI_8 / wa.max(wb));
            if fine >= cap {
                continue;
            }
            if !positions {
                (self.gaps)
                    .set_positions(t, self.stepper.y())
                    .map_err(|e| SimError::Contact {
                        t,
                        message: format!("the positions for the gaps: {e}"),
                    })?;
                positions = true;
            }
            let d = self
                .gaps
                .open_gap_at_positions(id, t)
                .map_err(|e| SimError::Contact {
                    t,
                    message: format!("the gap of {}: {e}", impact_map::pair_name(self.model, id)),
                })?;
            let reach_time = 2.0 * d / (v + (v * v + 2.0 * g * d.max(0.0)).sqrt());
            cap = cap.min(reach_time.max(fine));
        }
        self.stepper.set_h_max(cap);
        Ok(())
    }

    /// Stage `locate`: the first event in the last step, `Some(None)` if there is none.
    /// When the event functions cannot be evaluated inside the step (the forces of the
    /// closed contacts have no solution from some instant `t_f` on: a mode that stops
    /// being consistent), the step is taken again up to halfway to `t_f`, until `t_f` is
    /// within `1e-12 (1 + |t|)` of its end; then `None`: the contact stage must select
    /// the modes again there.
    fn locate(&mut self) -> Result<Option<Option<Event>>, SimError> {
        self.gaps.take_end_evaluation(&mut self.system.persistent);
        (self.gaps).take_end_kinematics(&self.system, self.stepper.t(), self.stepper.y());
        let located = self.locate_events();
        self.gaps.drop_end_evaluation();
        located
    }

    /// [`Self::locate`] itself.
    fn locate_events(&mut self) -> Result<Option<Option<Event>>, SimError> {
        loop {
            let step = (self.stepper.t_prev(), self.stepper.t());
            self.gaps
                .begin_step(self.system.persistent.bounds(), step, true);
            // The dense output of the step is completed (DOP853's extra stages) only if
            // the location reads it inside the step; a failure of the right-hand side
            // there fails the run as that of the step.
            let mut located = self.locator.locate_completing_dense(
                &mut self.stepper,
                &mut self.system,
                &mut self.gaps,
                &self.armed,
            );
            if self.gaps.stand_ins_failed() {
                // A function left unsampled inside the step broke its bound: sample
                // it (see `gaps::StandIns`).
                self.gaps.begin_step(&[], step, false);
                located = self.locator.locate_completing_dense(
                    &mut self.stepper,
                    &mut self.system,
                    &mut self.gaps,
                    &self.armed,
                );
            }
            let located = located.map_err(|e| match e.or_integration() {
                Ok(e) => SimError::from(e),
                Err(e) => SimError::from(e),
            });
            match located {
                Ok(found) => return Ok(Some(found)),
                Err(SimError::Locate(crate::events::EventError::Function { t: t_f, source })) => {
                    let (t0, t1) = (self.stepper.t_prev(), self.stepper.t());
                    if !(t_f > t0 && t_f <= t1) {
                        let e: crate::events::EventError<Nested> =
                            crate::events::EventError::Function { t: t_f, source };
                        return Err(e.into());
                    }
                    self.system.persistent.clear_bounds();
                    if t_f - t0 <= 1e-12 * (1.0 + t0.abs()) {
                        self.stepper.restep_to(&mut self.system, t0)?;
                        return Ok(None);
                    }
                    self.stepper
                        .restep_to(&mut self.system, t0 + 0.5 * (t_f - t0))?;
                }
                Err(e) => return Err(e),
            }
        }
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
        let t_end = self.settings.t_end;
        let due = |k: u64| {
            let t = k as Real / rate;
            !(t > t_until || t > t_end)
        };
        if !observer.wants_samples() {
            // No samples: only the passages are due, up to the last output time, and one
            // flush there reports them in the order of the flushes one output time at a
            // time (each reports its own in time order, after the earlier times'). The
            // last due index `k`, from its estimate, by the loop's own test.
            let first = self.next_output;
            if !due(first) {
                return Ok(());
            }
            let mut k = ((t_until.min(t_end) * rate).floor() as u64).max(first);
            while k < u64::MAX && due(k + 1) {
                k += 1;
            }
            while !due(k) {
                k -= 1;
            }
            self.flush_passages(k as Real / rate, observer)?;
            self.next_output = k + 1;
            return Ok(());
        }
        let mut y = std::mem::take(&mut self.y);
        let mut result = Ok(());
        loop {
            let t = self.next_output as Real / rate;
            if !due(self.next_output) {
                break;
            }
            result = self.flush_passages(t, observer);
            if result.is_err() {
                break;
            }
            if t == self.stepper.t() {
                y.copy_from_slice(self.stepper.y());
            } else {
                result = (self.stepper.dense_completing(&mut self.system, t, &mut y))
                    .map_err(SimError::from);
                if result.is_err() {
                    break;
                }
            }
            result = self.sample(t, &y, false, observer);
            if result.is_err() {
                break;
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
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        let e = energy(self.model, &mut self.sampler, t, q, u).map_err(|e| e.at(t))?;
        self.list_pairs(t)?;
        self.gap_values.clear();
        for &pair in &self.listed {
            let g = crate::contact::signed_gap(self.model, &self.sampler, pair, Real::INFINITY)
                .map_err(|e| e.at(t))?
                .unwrap_or(Real::INFINITY);
            self.gap_values.push(g);
        }
        self.listed_modes.clear();
        self.listed_slips.clear();
        for pair in &self.listed {
            self.listed_modes.push(self.modes[pair.index()]);
            self.listed_slips.push(self.slips[pair.index()]);
        }
        let sample = Sample {
            t,
            q,
            u,
            energy: e,
            pairs: &self.listed,
            gaps: &self.gap_values,
            poses: &self.sampler.body_pose,
            at_impact,
            modes: &self.listed_modes,
            slips: &self.listed_slips,
            contact_stages: self.contact_stages,
        };
        observer.sample(self.model, &sample).map_err(|e| e.at(t))?;
        self.counters.samples += 1;
        self.last_sample_t = Some(t);
        Ok(())
    }

    /// The pairs a sample lists, into `self.listed` (positions in `self.sampler`): every
    /// pair when the model has at most [`LISTED_PAIRS`]; beyond, the pairs whose bounding
    /// boxes overlap at the sample and every pair in contact (a mode other than free).
    fn list_pairs(&mut self, t: Real) -> Result<(), SimError> {
        broad::listed_pairs(
            self.model,
            &self.sampler,
            self.all_pairs.as_deref(),
            self.modes.changed(),
            (&mut self.boxes, &mut self.planes, &mut self.finder),
            &mut self.listed,
        )
        .map_err(|e| e.at(t))
    }

    /// A stop for a stall: impacts or events that keep coming without the time advancing
    /// on `pair`. A failure, not an accumulation of impacts — those end in the contact
    /// stage, with the passage to persistent contact (the final message goes to the log
    /// in [`Self::finish`]).
    fn stall(&mut self, t: Real, pair: PairId, reason: String) -> StopReason {
        StopReason::Failed(SimError::Contact {
            t,
            message: format!(
                "the run stalls on {}: {reason} (impacts or contact-mode changes that repeat \
                 at one instant and that the contact stage does not resolve)",
                impact_map::pair_name(self.model, pair)
            ),
        })
    }

    /// Stage `finish`: the final sample, the energy audit and the counters.
    fn finish(&mut self, stop: StopReason, observer: &mut dyn Observer) -> RunSummary {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let t = self.stepper.t();
        let mut y = std::mem::take(&mut self.y);
        y.copy_from_slice(self.stepper.y());
        let (q, u) = (&y[..n], &y[n..nqu]);
        self.audit.end = energy(self.model, &mut self.sampler, t, q, u).unwrap_or(Energy {
            kinetic: Real::NAN,
            potential: Real::NAN,
        });
        self.audit.damping_work = y[nqu];
        self.audit.applied_work = y[nqu + 1];
        self.audit.drive_work = y[nqu + 2];
        self.audit.contact_work = y[nqu + 3];
        let level = match stop {
            StopReason::Failed(_) => Level::Error,
            StopReason::Interrupted { .. } => Level::Warning,
            StopReason::EndTime => Level::Info,
        };
        // The last sample and message are best effort: the run is over either way. No
        // sample twice at the same instant (the output grid may have just taken it).
        let _ = self.flush_passages(Real::INFINITY, observer);
        if self.last_sample_t != Some(t) {
            let _ = self.sample(t, &y, false, observer);
        }
        let mut text = std::mem::take(&mut self.scratch.text);
        text.clear();
        let _ = write!(text, "run stopped at t = {t} s: {stop}");
        let _ = observer.message(t, level, &text);
        self.scratch.text = text;
        let (c, c0) = (self.stepper.counters(), self.stepper_counters);
        self.counters.steps = c.steps - c0.steps;
        self.counters.rejected = c.rejected - c0.rejected;
        self.counters.rhs_evals = c.rhs_evals - c0.rhs_evals;
        let summary = RunSummary {
            stop,
            state: State::new(
                t,
                nalgebra::DVector::from_column_slice(q),
                nalgebra::DVector::from_column_slice(u),
            ),
            audit: self.audit,
            counters: self.counters,
        };
        self.y = y;
        summary
    }
}
