//! The scaling of the event-driven loop with the number of links of a rope that falls
//! onto a floor (issue 15): what contact costs as the mechanism grows.
//!
//! **The rope.** `scenes/chain_floor.toml` cut into `N` links: a rope of
//! [`ROPE_LENGTH`] = 3.2 m and [`ROPE_MASS`] = 1.6 kg hanging from a pivot
//! [`PIVOT_HEIGHT`] = 1 m above a floor (`e = 0.2`, `μ = 0.4`), released straight and
//! horizontal at rest. Each link is `L = 3.2/N` m long, `1.6/N` kg, a capsule of radius
//! `r = L/10` ([`RADIUS_PER_LENGTH`]): links two apart are then `L − 2r = 0.8 L` apart at
//! the start (the scene loader rejects overlaps), and the rope's shape is the same at
//! every `N`. `N = 32` is the file exactly ([`scene_text`]; `tests/all/workprec.rs`
//! compares the two models).
//!
//! **The window.** The rope falls freely until it first strikes the floor, at `t₁` (0.45 s
//! at 32 links); from then on it whips against the floor and comes to lie on it: impacts
//! of many coupled points, then many closed points in stick and slip. Its cost is
//! measured over `[t₁, t₁ + W]`, the same stretch of the motion at every `N` (a window
//! fixed in absolute time would start in free fall for some `N` and in contact for
//! others). Two runs per `N`, both without an observer's samples:
//!
//! 1. release → first impact (stopped there): `t₁`, the free fall's wall time and its
//!    counters;
//! 2. release → `t₁ + W`, under a wall-time budget: the wall time at the first impact is
//!    read on the clock when the observer hears of it, and the window's counters are run
//!    2's minus run 1's (the runs are deterministic: the same steps to `t₁`).
//!
//! Runs shorter than [`SHORT_RUN`] (the small ropes) are repeated and their median kept.
//! The CPU time of the simulating thread is recorded beside the wall time (Linux only; to
//! a scheduler tick): on a shared machine the wall time grows with the load.
//!
//! A run that exhausts its budget is interrupted at its next step; the row then reports
//! how far the window got (`window_reached_s`) and its cost per simulated second as wall
//! over simulated time reached, marked `budget_limited`. The start of the window (the
//! whip) costs differently from its end (the rope lying), so such a cost is not the
//! window's: [`common_window`] also gives every row's cost over the shortest window any
//! row reached, from the clock readings at its impacts and mode changes, which compares
//! all `N` over the same stretch.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::WorkprecError;
use super::table::FloorRow;
use crate::contact::{ManifoldWorkspace, contact_points};
use crate::kinematics::update_positions;
use crate::math::Real;
use crate::model::{Model, PairId};
use crate::scene::Scene;
use crate::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, PairMode, RunSummary, Sample,
    Simulation, StopReason, Transition,
};
use crate::state::Data;

/// Length of the rope, all links together (m): `scenes/chain_floor.toml`'s 32 × 0.1 m.
pub const ROPE_LENGTH: Real = 3.2;
/// Mass of the rope (kg): 32 × 50 g.
pub const ROPE_MASS: Real = 1.6;
/// Capsule radius over link length: 1 cm on 0.1 m links.
pub const RADIUS_PER_LENGTH: Real = 0.1;
/// Height of the pivot above the floor (m).
pub const PIVOT_HEIGHT: Real = 1.0;

/// The scene of the rope cut into `links` links: `scenes/chain_floor.toml` with the
/// link length, mass and radius divided among them (see the module doc).
pub fn scene_text(links: usize) -> String {
    let n = links.max(1) as Real;
    // Divided as 3.2/N, not 0.1·32/N: at N = 32 (any power of two) the quotients are the
    // file's 0.1, 0.05 and 0.01 exactly. The radius is 0.32/N = RADIUS_PER_LENGTH · L
    // (the product 0.1 · 3.2 rounds to 0.32000000000000006).
    let length = ROPE_LENGTH / n;
    let mass = ROPE_MASS / n;
    let radius = 0.32 / n;
    format!(
        r#"# scenes/chain_floor.toml cut into {links} links (ricochet::workprec::chain_floor).
version = 1
name = "chain_floor_{links}"
description = "A {ROPE_LENGTH} m rope of {links} links released horizontally, falling to lie on the floor {PIVOT_HEIGHT} m below its pivot"
gravity = [0.0, -9.81]

[run]
t_end = 5.0
output_rate = 100.0

[contact]
law = "newton"
e = 0.2
mu = 0.4

[chain]
links = {links}
length = {length:?}
mass = {mass:?}
radius = {radius:?}
at = [0.0, 0.0]
angle = "90 deg"
rate = "0 rad/s"

[[obstacle]]
name = "floor"
type = "halfspace"
point = [0.0, {floor:?}]
normal = [0.0, 1.0]
"#,
        floor = -PIVOT_HEIGHT,
    )
}

/// The rope of `links` links, loaded (and checked) like a scene file.
pub fn scene(links: usize) -> Result<Scene, WorkprecError> {
    Ok(crate::scene::load_str(
        &scene_text(links),
        format!("chain_floor_{links}.toml"),
    )?)
}

/// What [`measure`] is asked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorSettings {
    /// The window after the first impact (s of simulated time).
    pub window: Real,
    /// The wall-time budget of the run through the window, free fall included (s).
    pub budget: Real,
}

/// CPU time of the calling thread (s), from Linux's `/proc/thread-self/schedstat` (its
/// first field, ns on the CPU); `None` elsewhere. On a machine shared with other jobs the
/// wall time of a run grows with the load, its CPU time much less.
pub fn thread_cpu_s() -> Option<Real> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns as Real * 1e-9)
}

/// The load average of the last minute (Linux's `/proc/loadavg`); `None` elsewhere.
pub fn load_average() -> Option<Real> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Hears the run: the clock at the first impact, and at every impact and mode change
/// after it; the mode of every pair that changed one. Takes no samples.
struct Clock<'a> {
    start: Instant,
    /// The thread's CPU time at the start (s).
    cpu_start: Option<Real>,
    /// The CPU time from the start to the first impact (s).
    cpu_first: Option<Real>,
    /// Set at the first impact (run 1 stops there).
    stop_at_first: Option<&'a AtomicBool>,
    /// `(t, wall)` of the first impact (s, s since the start).
    first: Option<(Real, Real)>,
    /// `(t, wall)` at every impact, transition and message from the first impact on.
    readings: Vec<(Real, Real)>,
    /// Impacts (points) and impact instants from the first impact on.
    impacts: u64,
    instants: u64,
    last_instant: Real,
    /// The last reported mode of each pair that changed one.
    modes: BTreeMap<PairId, PairMode>,
    /// The most pairs closed at once.
    max_closed: usize,
}

impl<'a> Clock<'a> {
    fn new(stop_at_first: Option<&'a AtomicBool>) -> Self {
        Self {
            start: Instant::now(),
            cpu_start: None,
            cpu_first: None,
            stop_at_first,
            first: None,
            readings: Vec::new(),
            impacts: 0,
            instants: 0,
            last_instant: Real::NEG_INFINITY,
            modes: BTreeMap::new(),
            max_closed: 0,
        }
    }

    /// CPU time since the start (s).
    fn cpu(&self) -> Option<Real> {
        Some(thread_cpu_s()? - self.cpu_start?)
    }

    fn read(&mut self, t: Real) {
        if self.first.is_some() {
            self.readings.push((t, self.start.elapsed().as_secs_f64()));
        }
    }

    fn closed_pairs(&self) -> impl Iterator<Item = PairId> + '_ {
        (self.modes.iter())
            .filter(|(_, m)| matches!(m, PairMode::Sticking | PairMode::Sliding))
            .map(|(p, _)| *p)
    }
}

impl Observer for Clock<'_> {
    fn wants_samples(&self) -> bool {
        false
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        Ok(())
    }
    fn impact(&mut self, _: &Model, impact: &ImpactEvent) -> Result<(), ObserverError> {
        if self.first.is_none() {
            self.first = Some((impact.t, self.start.elapsed().as_secs_f64()));
            self.cpu_first = self.cpu();
            if let Some(flag) = self.stop_at_first {
                flag.store(true, Ordering::Relaxed);
            }
        }
        self.impacts += 1;
        if impact.t != self.last_instant {
            self.instants += 1;
            self.last_instant = impact.t;
        }
        self.read(impact.t);
        Ok(())
    }
    fn message(&mut self, t: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        self.read(t);
        Ok(())
    }
    fn transition(&mut self, _: &Model, tr: &Transition) -> Result<(), ObserverError> {
        self.modes.insert(tr.pair, tr.to);
        self.max_closed = self.max_closed.max(self.closed_pairs().count());
        self.read(tr.t);
        Ok(())
    }
}

/// One run of `scene` to `t_end` (s), interrupted when `flag` is set (by the observer or
/// by the budget's watchdog, after `budget` s of wall time); the summary, its wall time
/// and its CPU time (s).
fn run(
    scene: &Scene,
    t_end: Real,
    clock: &mut Clock<'_>,
    flag: &AtomicBool,
    budget: Real,
) -> Result<(RunSummary, Real, Option<Real>), WorkprecError> {
    let mut settings = scene.settings.clone();
    settings.t_end = t_end;
    settings.output_rate = 0.0;
    let mut sim =
        Simulation::new(&scene.model, &settings, MaterialOverride::default()).map_err(|e| {
            WorkprecError::Setup {
                method: "dopri5",
                error: Box::new(e),
            }
        })?;
    let (done, wait) = mpsc::channel::<()>();
    let summary = std::thread::scope(|s| {
        // The watchdog: sets the flag unless the run ends first (the sender dropped).
        s.spawn(move || {
            let budget = Duration::try_from_secs_f64(budget).unwrap_or(Duration::MAX);
            if let Err(mpsc::RecvTimeoutError::Timeout) = wait.recv_timeout(budget) {
                flag.store(true, Ordering::Relaxed);
            }
        });
        clock.start = Instant::now();
        clock.cpu_start = thread_cpu_s();
        let summary = sim.run(&scene.initial, clock, Some(flag));
        drop(done);
        summary
    });
    Ok((summary, clock.start.elapsed().as_secs_f64(), clock.cpu()))
}

/// The closed points at the end of a run: the points within the closed-contact tolerance
/// of the pairs whose last reported mode is closed.
fn closed_points(scene: &Scene, clock: &Clock<'_>, summary: &RunSummary, gap_tol: Real) -> usize {
    let model = &scene.model;
    let mut data = Data::for_kinematics(model);
    let t = summary.state.t;
    if update_positions(model, &mut data, t, summary.state.q.as_slice()).is_err() {
        return 0;
    }
    let mut ws = ManifoldWorkspace::default();
    (clock.closed_pairs())
        .map(|pair| contact_points(model, &data, pair, gap_tol, &mut ws).map_or(0, |p| p.len()))
        .sum()
}

/// A run shorter than this (s of wall time) is repeated, up to [`REPEATS`] runs in all,
/// and the median kept: the small ropes take milliseconds.
pub const SHORT_RUN: Real = 1.0;
/// The most runs of one kind per size.
pub const REPEATS: usize = 5;

/// Measures the rope of `links` links: free fall to its first impact, then the window
/// after it (see the module doc); runs shorter than [`SHORT_RUN`] are repeated and the
/// median kept. Keeps the clock readings of the window in `readings` (`(t − t₁, wall −
/// wall₁)`) for [`common_window`].
pub fn measure(
    links: usize,
    settings: FloorSettings,
    readings: &mut Vec<(Real, Real)>,
) -> Result<FloorRow, WorkprecError> {
    let scene = scene(links)?;
    let load = load_average();
    // Run 1: to the first impact (a rope that never lands stops at the scene's end time).
    let mut falls = Vec::new();
    while falls.len() < REPEATS {
        let flag = AtomicBool::new(false);
        let mut clock = Clock::new(Some(&flag));
        let (summary, wall, cpu) = run(
            &scene,
            scene.settings.t_end,
            &mut clock,
            &flag,
            settings.budget,
        )?;
        falls.push((summary, wall, cpu, clock.first));
        if wall >= SHORT_RUN || falls[0].3.is_none() {
            break;
        }
    }
    let fall_wall = median(falls.iter().map(|f| f.1));
    let fall_cpu = median_of_some(falls.iter().map(|f| f.2));
    let (fall, _, _, first) = falls.swap_remove(0);
    let Some((t1, _)) = first else {
        return Ok(FloorRow::without_impact(
            links,
            &scene,
            settings,
            &fall,
            (fall_wall, fall_cpu),
            load,
        ));
    };
    // Run 2: through the window, under the budget.
    let mut windows: Vec<Window> = Vec::new();
    while windows.len() < REPEATS {
        let w = window(&scene, t1, settings)?;
        let done = w.wall >= SHORT_RUN || w.budget_limited();
        windows.push(w);
        if done {
            break;
        }
    }
    let window_cpu = median_of_some(windows.iter().map(|w| w.cpu));
    windows.sort_by(|a, b| a.window_wall().total_cmp(&b.window_wall()));
    let w = windows.swap_remove(windows.len() / 2);
    readings.clear();
    readings.extend(w.readings());
    let t_reached = w.summary.state.t;
    let (c, c1) = (w.summary.counters, fall.counters);
    let window_reached = (t_reached - t1).max(0.0);
    let window_wall = w.window_wall();
    Ok(FloorRow {
        links: links as u32,
        pairs: scene.model.pair_count() as u32,
        window_s: settings.window,
        budget_s: settings.budget,
        t_first_impact: Some(t1),
        free_fall_wall_s: fall_wall,
        free_fall_wall_per_sim_s: fall_wall / t1,
        free_fall_cpu_s: fall_cpu,
        free_fall_steps: c1.steps,
        t_reached,
        window_reached_s: window_reached,
        wall_s: w.wall,
        window_wall_s: window_wall,
        wall_per_sim_s: window_wall / window_reached,
        window_cpu_s: window_cpu,
        cpu_per_sim_s: window_cpu.map(|c| c / window_reached),
        common_window_s: None,
        common_wall_per_sim_s: None,
        steps: c.steps.saturating_sub(c1.steps),
        rejected: c.rejected.saturating_sub(c1.rejected),
        rhs_evals: c.rhs_evals.saturating_sub(c1.rhs_evals),
        events: c.events.saturating_sub(c1.events),
        impacts: w.impacts,
        impact_instants: w.instants,
        closed_pairs_end: w.closed_pairs as u32,
        closed_points_end: w.closed_points as u32,
        max_closed_pairs: w.max_closed as u32,
        budget_limited: w.budget_limited(),
        stop: stop_text(&w.summary.stop),
        load_before: load,
    })
}

/// One run through the window: what [`measure`] keeps of it.
struct Window {
    summary: RunSummary,
    /// Wall time of the run, and at the first impact (s).
    wall: Real,
    wall1: Real,
    /// CPU time spent in the window (s).
    cpu: Option<Real>,
    t1: Real,
    /// The clock's readings `(t, wall)` from the first impact on.
    readings: Vec<(Real, Real)>,
    impacts: u64,
    instants: u64,
    closed_pairs: usize,
    closed_points: usize,
    max_closed: usize,
}

impl Window {
    fn window_wall(&self) -> Real {
        self.wall - self.wall1
    }

    fn budget_limited(&self) -> bool {
        matches!(self.summary.stop, StopReason::Interrupted { .. })
    }

    /// The readings from the first impact, `(t − t₁, wall − wall₁)`, and the end.
    fn readings(&self) -> impl Iterator<Item = (Real, Real)> + '_ {
        let end = (self.summary.state.t, self.wall);
        (self.readings.iter().copied().chain([end])).map(|(t, w)| (t - self.t1, w - self.wall1))
    }
}

/// Runs the rope from its release to `t1 + window` under the budget.
fn window(scene: &Scene, t1: Real, settings: FloorSettings) -> Result<Window, WorkprecError> {
    let flag = AtomicBool::new(false);
    let mut clock = Clock::new(None);
    let (summary, wall, cpu) = run(
        scene,
        t1 + settings.window,
        &mut clock,
        &flag,
        settings.budget,
    )?;
    let (t1, wall1) = clock.first.unwrap_or((t1, wall));
    let gap_tol = crate::sim::Scales::of(&scene.model, &scene.settings.integrator).gap_tol;
    Ok(Window {
        wall,
        wall1,
        cpu: cpu.zip(clock.cpu_first).map(|(c, c1)| c - c1),
        t1,
        impacts: clock.impacts,
        instants: clock.instants,
        closed_pairs: clock.closed_pairs().count(),
        closed_points: closed_points(scene, &clock, &summary, gap_tol),
        max_closed: clock.max_closed,
        readings: std::mem::take(&mut clock.readings),
        summary,
    })
}

/// The median of `values` (the mean of the middle two of an even count; NaN if none).
fn median(values: impl Iterator<Item = Real>) -> Real {
    let mut v: Vec<Real> = values.collect();
    v.sort_by(Real::total_cmp);
    match v.len() {
        0 => Real::NAN,
        k if k % 2 == 1 => v[k / 2],
        k => 0.5 * (v[k / 2 - 1] + v[k / 2]),
    }
}

/// The median of the values that are known, if all are.
fn median_of_some(values: impl Iterator<Item = Option<Real>>) -> Option<Real> {
    let v: Option<Vec<Real>> = values.collect();
    v.map(|v| median(v.into_iter()))
}

fn stop_text(stop: &StopReason) -> String {
    match stop {
        StopReason::Interrupted { .. } => "budget".into(),
        other => other.name().into(),
    }
}

impl FloorRow {
    /// The row of a rope whose first run found no impact (it never landed, or its budget
    /// ran out first): no window.
    fn without_impact(
        links: usize,
        scene: &Scene,
        settings: FloorSettings,
        fall: &RunSummary,
        (fall_wall, fall_cpu): (Real, Option<Real>),
        load: Option<Real>,
    ) -> FloorRow {
        let t = fall.state.t;
        FloorRow {
            links: links as u32,
            pairs: scene.model.pair_count() as u32,
            window_s: settings.window,
            budget_s: settings.budget,
            t_first_impact: None,
            free_fall_wall_s: fall_wall,
            free_fall_wall_per_sim_s: fall_wall / t,
            free_fall_cpu_s: fall_cpu,
            free_fall_steps: fall.counters.steps,
            t_reached: t,
            window_reached_s: 0.0,
            wall_s: fall_wall,
            window_wall_s: 0.0,
            wall_per_sim_s: Real::NAN,
            window_cpu_s: None,
            cpu_per_sim_s: None,
            common_window_s: None,
            common_wall_per_sim_s: None,
            steps: 0,
            rejected: 0,
            rhs_evals: 0,
            events: 0,
            impacts: 0,
            impact_instants: 0,
            closed_pairs_end: 0,
            closed_points_end: 0,
            max_closed_pairs: 0,
            budget_limited: matches!(fall.stop, StopReason::Interrupted { .. }),
            stop: stop_text(&fall.stop),
            load_before: load,
        }
    }
}

/// The wall time (s) at simulated time `tau` into the window, from the clock readings
/// `(t − t₁, wall − wall₁)` of a run (sorted by time): linear between the readings that
/// bracket `tau`. `None` beyond the last reading.
pub fn wall_at(readings: &[(Real, Real)], tau: Real) -> Option<Real> {
    let k = readings.iter().position(|r| r.0 >= tau)?;
    if k == 0 {
        // Before the first reading: linear from the start of the window.
        let (t, w) = readings[0];
        return Some(if t > 0.0 { w * (tau / t).max(0.0) } else { w });
    }
    let (a, b) = (readings[k - 1], readings[k]);
    let s = if b.0 > a.0 {
        (tau - a.0) / (b.0 - a.0)
    } else {
        1.0
    };
    Some(a.1 + s * (b.1 - a.1))
}

/// Sets every row's cost over the shortest window reached by any row with an impact
/// (`common_window_s`, `common_wall_per_sim_s`): the wall time at that point of its
/// window from its clock readings ([`wall_at`]) over that window.
pub fn common_window(rows: &mut [FloorRow], readings: &[Vec<(Real, Real)>]) {
    let tau = (rows.iter())
        .filter(|r| r.t_first_impact.is_some())
        .map(|r| r.window_reached_s)
        .fold(Real::INFINITY, Real::min);
    if !(tau.is_finite() && tau > 0.0) {
        return;
    }
    for (row, readings) in rows.iter_mut().zip(readings) {
        if row.t_first_impact.is_none() {
            continue;
        }
        let mut sorted = readings.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(w) = wall_at(&sorted, tau) {
            row.common_window_s = Some(tau);
            row.common_wall_per_sim_s = Some(w / tau);
        }
    }
}
