//! No allocation in the loop (issue 16): after the first steps, a stretch of the run with
//! no event in it — free flight, persistent contact with its closed points sticking or
//! sliding — allocates nothing: the integrator's stages, the right-hand side with the
//! constrained dynamics of the closed points, the event location (samples, stand-ins, root
//! searches of the gaps), the broad phase and the samples all work in kept buffers.
//!
//! An observer reads the thread's allocation counter (`common::alloc`, the test crate's
//! global allocator) at every sample of the output grid; between two of them with no
//! impact, message or mode change between them (the samples that bracket an impact are
//! the contact stage's) and no run of the contact stage at all (`Sample::contact_stages`:
//! a located event that changes nothing, such as a gap crossing at rounding that disarms
//! its pair, reports nothing to the observer but is an event, whose buffers may grow the
//! first time), the count must not move.
//!
//! Events too, once their buffers have grown (`assert_events_allocate_nothing`): the same
//! `Simulation` run again from its initial state allocates nothing from its first callback
//! to its last, impacts, accumulations, mode changes and rocking ends included.

use std::path::Path;

use ricochet::model::Model;
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, Recorder, Sample, Simulation,
    StopReason, Transition,
};

use crate::common::alloc::allocations;

/// What happened at a callback: a sample, or anything else (an event of the contact
/// stage), with the allocations counted just before it.
#[derive(Clone, Copy, Debug)]
enum Call {
    /// Time, allocations, runs of the contact stage.
    Sample(f64, usize, u64),
    Event,
}

struct Counter {
    calls: Vec<Call>,
}

impl Counter {
    fn note(&mut self, call: Call) {
        // Capacity reserved up front: the counter itself does not allocate.
        assert!(self.calls.len() < self.calls.capacity(), "too many calls");
        self.calls.push(call);
    }
}

impl Observer for Counter {
    fn wants_samples(&self) -> bool {
        true
    }
    fn sample(&mut self, _: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        // The samples just before and after an impact belong to the contact stage.
        self.note(if s.at_impact {
            Call::Event
        } else {
            Call::Sample(s.t, allocations(), s.contact_stages)
        });
        Ok(())
    }
    fn impact(&mut self, _: &Model, _: &ImpactEvent) -> Result<(), ObserverError> {
        self.note(Call::Event);
        Ok(())
    }
    fn message(&mut self, _: f64, _: Level, _: &str) -> Result<(), ObserverError> {
        self.note(Call::Event);
        Ok(())
    }
    fn transition(&mut self, _: &Model, _: &Transition) -> Result<(), ObserverError> {
        self.note(Call::Event);
        Ok(())
    }
}

/// Runs `scene` (from `scenes/` or `tests/data/`) to `t_end` with samples at `rate` and
/// returns, for every stretch between two consecutive samples after `warm` (s) with no
/// event between them, its end time and the allocations in it; and the stretches in all.
fn quiet_stretches(path: &str, t_end: f64, rate: f64, warm: f64) -> (Vec<(f64, usize)>, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let mut scene = ricochet::scene::load(&path).unwrap();
    scene.settings.t_end = t_end;
    scene.settings.output_rate = rate;
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut counter = Counter {
        calls: Vec::with_capacity(1_000_000),
    };
    let summary = sim.run(&scene.initial, &mut counter, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let mut stretches = 0;
    let mut allocating = Vec::new();
    for w in counter.calls.windows(2) {
        if let [Call::Sample(t0, a0, c0), Call::Sample(t1, a1, c1)] = *w
            && t0 >= warm
            && c0 == c1
        {
            stretches += 1;
            if a1 != a0 {
                allocating.push((t1, a1 - a0));
            }
        }
    }
    (allocating, stretches)
}

fn assert_quiet(path: &str, t_end: f64, rate: f64, warm: f64, at_least: usize) {
    let (allocating, stretches) = quiet_stretches(path, t_end, rate, warm);
    println!(
        "{path}: {stretches} quiet stretches, {} allocating",
        allocating.len()
    );
    assert!(
        stretches >= at_least,
        "{path}: only {stretches} quiet stretches"
    );
    assert!(
        allocating.is_empty(),
        "{path}: stretches that allocated (end time, allocations): {:?}",
        &allocating[..allocating.len().min(10)]
    );
}

/// Free flight: the ball between its bounces (the sample rate puts several samples in each
/// flight).
#[test]
fn free_flight_allocates_nothing() {
    assert_quiet("scenes/bouncing_ball.toml", 3.0, 100.0, 0.05, 200);
}

/// Persistent contact, one closed point: Kane's pendulum sliding on the floor after its
/// accumulation (0.19 s) to 5 s — the constrained dynamics at every stage, the stand-ins
/// and exact samples of the event location.
#[test]
fn one_sliding_point_allocates_nothing() {
    assert_quiet("scenes/kane_double_pendulum.toml", 5.0, 100.0, 0.25, 400);
}

/// Persistent contact, two closed points (the rod at rest flat on the floor), and many:
/// the 8-link chain lying partly on its floor, whose stretches between mode changes hold
/// several sticking and sliding points.
#[test]
fn several_closed_points_allocate_nothing() {
    assert_quiet("scenes/falling_rod.toml", 3.0, 100.0, 1.0, 100);
    assert_quiet("scenes/chain.toml", 3.0, 200.0, 0.5, 100);
    assert_quiet("scenes/chain_floor.toml", 1.0, 200.0, 0.5, 20);
}

/// Every callback of a run: how many, of each kind, and the allocations counted at the
/// first and at the last (the observer itself allocates nothing).
#[derive(Debug, Default)]
struct Callbacks {
    samples: usize,
    impacts: usize,
    messages: usize,
    transitions: usize,
    first: Option<usize>,
    last: usize,
}

impl Callbacks {
    fn note(&mut self) {
        let now = allocations();
        self.first.get_or_insert(now);
        self.last = now;
    }
}

impl Observer for Callbacks {
    fn wants_samples(&self) -> bool {
        true
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        self.samples += 1;
        self.note();
        Ok(())
    }
    fn impact(&mut self, _: &Model, _: &ImpactEvent) -> Result<(), ObserverError> {
        self.impacts += 1;
        self.note();
        Ok(())
    }
    fn message(&mut self, _: f64, _: Level, _: &str) -> Result<(), ObserverError> {
        self.messages += 1;
        self.note();
        Ok(())
    }
    fn transition(&mut self, _: &Model, _: &Transition) -> Result<(), ObserverError> {
        self.transitions += 1;
        self.note();
        Ok(())
    }
}

/// What a run reported, for comparing two runs.
fn record(sim: &mut Simulation<'_>, initial: &ricochet::state::State) -> (Recorder, String) {
    let mut rec = Recorder {
        keep_samples: true,
        ..Recorder::default()
    };
    let summary = sim.run(initial, &mut rec, None);
    (rec, format!("{summary:?}"))
}

/// Events allocate nothing once their buffers have grown: a third run of the same
/// [`Simulation`] (which starts afresh: it reports the same as the first, bit for bit)
/// allocates nothing from its first callback (the initial sample) to its last (the final
/// message) — the steps, the samples, and every event's contact stage: impacts (one point,
/// several at once), the end of an accumulation (its plastic impact, the mode selection,
/// the passage reported at t∞), the stop and reversal of a slip, a stick, rocking ends;
/// the ledger entries, messages and transitions given to the observer. (The third, not the
/// second: buffers kept for reuse in a pool — the spare solutions of the mode enumeration,
/// the two rounds of a rocking end — are handed out in an order that need not be the
/// first run's, so one may still grow in the second run; by the third each has.)
fn assert_events_allocate_nothing(path: &str, t_end: f64, at_least: Callbacks) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let mut scene = ricochet::scene::load(&path).unwrap();
    scene.settings.t_end = t_end;
    scene.settings.output_rate = 100.0;
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let first = record(&mut sim, &scene.initial);
    let summary = sim.run(&scene.initial, &mut Callbacks::default(), None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let mut calls = Callbacks::default();
    let summary = sim.run(&scene.initial, &mut calls, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let fourth = record(&mut sim, &scene.initial);
    let same = |a: &Recorder, b: &Recorder| {
        format!(
            "{:?}",
            (&a.impacts, &a.messages, &a.transitions, &a.samples)
        ) == format!(
            "{:?}",
            (&b.impacts, &b.messages, &b.transitions, &b.samples)
        )
    };
    assert!(
        same(&first.0, &fourth.0) && first.1 == fourth.1,
        "{}: a run again differs from the first",
        path.display()
    );
    let allocated = calls.last - calls.first.unwrap();
    println!("{}: {calls:?}, {allocated} allocations", path.display());
    assert!(
        calls.impacts >= at_least.impacts
            && calls.transitions >= at_least.transitions
            && calls.messages >= at_least.messages,
        "{}: fewer events than expected: {calls:?}",
        path.display()
    );
    assert_eq!(allocated, 0, "{}: {calls:?}", path.display());
}

/// Kane's double pendulum to 5 s: 11 impacts, the end of their accumulation (0.19 s), the
/// tip sliding, its slip stopping and reversing, and sticking.
#[test]
fn events_allocate_nothing_kane() {
    let at_least = Callbacks {
        impacts: 11,
        transitions: 3,
        ..Callbacks::default()
    };
    assert_events_allocate_nothing("scenes/kane_double_pendulum.toml", 5.0, at_least);
}

/// The bouncing ball: its bounces, the end of their accumulation, the ball at rest.
#[test]
fn events_allocate_nothing_bouncing_ball() {
    let at_least = Callbacks {
        impacts: 20,
        transitions: 1,
        ..Callbacks::default()
    };
    assert_events_allocate_nothing("scenes/bouncing_ball.toml", 5.0, at_least);
}

/// Several points: the rod landing on one end and striking with the other (impacts in
/// cascade, Moreau's law over two points), coming to rest flat.
#[test]
fn events_of_two_points_allocate_nothing() {
    let at_least = Callbacks {
        impacts: 30,
        transitions: 5,
        ..Callbacks::default()
    };
    assert_events_allocate_nothing("scenes/falling_rod.toml", 3.0, at_least);
}

/// The block rocking on its corners to rest: rocking ends.
#[test]
fn rocking_ends_allocate_nothing() {
    let at_least = Callbacks {
        impacts: 10,
        transitions: 1,
        ..Callbacks::default()
    };
    assert_events_allocate_nothing("scenes/rocking_block.toml", 3.0, at_least);
}

/// Lemke's path (`lcp::Solver`, beyond the enumeration's four points: the LCP, Lemke's
/// pivots, its solution's modes, their polish and repair): the 32-link chain on the floor
/// to 0.5 s, its first whip against the floor — simultaneous impacts of 6 and 8 points and
/// mode selections of 5 to 8 (23 calls of Lemke's solver per run), among impacts and mode
/// selections of fewer points. On stop 34's code the third run allocated 150 times; 28
/// once Lemke's path was done: the packing buffers of `matrixmultiply`, to which
/// nalgebra's product handed `W = J M⁻¹ Jᵀ` of three points or more, now
/// `linalg::product_into` (the same bits) in kept storage.
#[test]
fn lemke_s_path_allocates_nothing() {
    let at_least = Callbacks {
        impacts: 80,
        transitions: 10,
        ..Callbacks::default()
    };
    assert_events_allocate_nothing("scenes/chain_floor.toml", 0.5, at_least);
}
