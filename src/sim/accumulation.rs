//! The scales of a scene for its tolerances, and the guard that stops a run whose impacts
//! stall.

use crate::math::Real;
use crate::model::Model;
use crate::settings::IntegratorSettings;

/// Scales of a model, for the tolerances of the loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scales {
    /// Length scale `L` (m): the largest bounding radius of the shapes carried by bodies
    /// (1 m if there is none).
    pub length: Real,
    /// Speed scale `v_ref = √(|g| L)` (m/s), the speed of a fall through `L` (1 m/s
    /// without gravity).
    pub speed: Real,
    /// A contact is closed when its gap is at most `gap_tol = 1e-9 L` (m).
    pub gap_tol: Real,
    /// A touching contact approaches when `v_n < −v_tiny`, `v_tiny = 1e-10 v_ref` (m/s).
    pub v_tiny: Real,
    /// A point held closed in persistent contact approaches (or separates) only when
    /// `|v_n| > v_drift = 1e-7 v_ref` (m/s): its normal speed is held at zero through its
    /// acceleration, and drifts with the integration error.
    pub v_drift: Real,
    /// The height of the smallest hop the loop resolves, `h_rest = 100 δ` (m): 100 times
    /// the position tolerance of the integrator, `δ = atol + rtol L`, below which the event
    /// location cannot tell a hop from rounding. See [`Scales::v_rest_at`].
    pub h_rest: Real,
    /// The resting speed of a contact whose normal acceleration is `−|g|`,
    /// [`Scales::v_rest_at`]`(−|g|)` (m/s; with `a = v_ref²/L` without gravity): the
    /// reference value for messages and tests.
    pub v_rest: Real,
}

impl Scales {
    /// The scales of `model` integrated with `settings`.
    pub fn of(model: &Model, settings: &IntegratorSettings) -> Self {
        let length = model
            .colliders()
            .iter()
            .filter(|c| c.body.is_some())
            .map(|c| c.shape.compute_local_bounding_sphere().radius())
            .filter(|r| r.is_finite() && *r > 0.0)
            .fold(0.0, Real::max);
        let length = if length > 0.0 { length } else { 1.0 };
        let g = model.gravity().length();
        let speed = if g > 0.0 { (g * length).sqrt() } else { 1.0 };
        let accel = if g > 0.0 { g } else { speed * speed / length };
        let delta = settings.atol + settings.rtol * length;
        Self {
            length,
            speed,
            gap_tol: 1e-9 * length,
            v_tiny: 1e-10 * speed,
            v_drift: 1e-7 * speed,
            h_rest: 100.0 * delta,
            v_rest: (2.0 * accel * 100.0 * delta).sqrt(),
        }
    }

    /// The resting speed of a contact point whose normal acceleration in flight is `a_n`
    /// (m/s², negative when it falls back): an impact that leaves it separating at most
    /// this fast starts a hop lower than `h_rest` (`v²/(2|a_n|) ≤ h_rest`), too small to
    /// resolve, and ends an accumulation of impacts. `√(2 |a_n| h_rest)` when `a_n < 0`;
    /// `0` when the point accelerates away (`a_n ≥ 0`): it leaves for good, however
    /// slowly it starts.
    pub fn v_rest_at(&self, a_n: Real) -> Real {
        if a_n < 0.0 {
            (2.0 * -a_n * self.h_rest).sqrt()
        } else {
            0.0
        }
    }
}

/// Impacts in a row that may leave the time where it is before the run is stopped.
const MAX_STALLED_IMPACTS: u32 = 1000;

/// Watches the impacts for a contact that no longer separates.
#[derive(Clone, Debug)]
pub(super) struct Guard {
    last_t: Real,
    stalled: u32,
    last_event_t: Real,
    stalled_events: u32,
}

impl Guard {
    pub(super) fn new() -> Self {
        Self {
            last_t: Real::NEG_INFINITY,
            stalled: 0,
            last_event_t: Real::NEG_INFINITY,
            stalled_events: 0,
        }
    }

    /// Starts watching at `t0`.
    pub(super) fn reset(&mut self, t0: Real) {
        self.last_t = t0;
        self.stalled = 0;
        self.last_event_t = t0;
        self.stalled_events = 0;
    }

    /// After an event at `t`: why the run must stop, if events keep coming without the time
    /// advancing (contact modes that chatter).
    pub(super) fn after_event(&mut self, t: Real) -> Option<String> {
        if t - self.last_event_t <= 1e-12 * (1.0 + t.abs()) {
            self.stalled_events += 1;
        } else {
            self.stalled_events = 0;
        }
        self.last_event_t = t;
        (self.stalled_events >= MAX_STALLED_IMPACTS)
            .then(|| format!("{MAX_STALLED_IMPACTS} events without the time advancing"))
    }

    /// After an impact at `t`: why the run must stop, if it must — impacts keep coming
    /// without the time advancing (accumulations themselves pass to persistent contact in
    /// the contact stage).
    pub(super) fn after_impact(&mut self, t: Real) -> Option<String> {
        if t - self.last_t <= 1e-12 * (1.0 + t.abs()) {
            self.stalled += 1;
        } else {
            self.stalled = 0;
        }
        self.last_t = t;
        (self.stalled >= MAX_STALLED_IMPACTS)
            .then(|| format!("{MAX_STALLED_IMPACTS} impacts without the time advancing"))
    }
}
