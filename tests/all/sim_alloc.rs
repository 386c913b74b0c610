//! No allocation in the loop (issue 16): after the first steps, a stretch of the run with
//! no event in it — free flight, persistent contact with its closed points sticking or
//! sliding — allocates nothing: the integrator's stages, the right-hand side with the
//! constrained dynamics of the closed points, the event location (samples, stand-ins, root
//! searches of the gaps), the broad phase and the samples all work in kept buffers.
//!
//! An observer reads the thread's allocation counter (`common::alloc`, the test crate's
//! global allocator) at every sample of the output grid; between two of them with no
//! impact, message or mode change between them (the samples that bracket an impact are
//! the contact stage's), the count must not move.

use std::path::Path;

use ricochet::model::Model;
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, Sample, Simulation, StopReason,
    Transition,
};

use crate::common::alloc::allocations;

/// What happened at a callback: a sample, or anything else (an event of the contact
/// stage), with the allocations counted just before it.
#[derive(Clone, Copy, Debug)]
enum Call {
    Sample(f64, usize),
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
            Call::Sample(s.t, allocations())
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
        if let [Call::Sample(t0, a0), Call::Sample(t1, a1)] = *w
            && t0 >= warm
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
