//! The scales of a scene for its tolerances, and the guard that stops a run when a
//! contact no longer separates (until persistent contact is modelled).

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
    /// A closed contact approaches when `v_n < −v_tiny`, `v_tiny = 1e-10 v_ref` (m/s).
    pub v_tiny: Real,
    /// An impact that leaves the contact separating slower than `v_rest` (m/s) ends the
    /// bouncing: the contact has come to rest (an accumulation of impacts). The next hop
    /// would rise `v²/(2a)` with `a = |g|`: `v_rest` makes that 100 times the position
    /// tolerance of the integrator, `δ = atol + rtol L`, below which the event location
    /// cannot tell a hop from rounding: `v_rest = √(2 a · 100 δ)`.
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
            v_rest: (2.0 * accel * 100.0 * delta).sqrt(),
        }
    }
}

/// Impacts in a row that may leave the time where it is before the run is stopped.
const MAX_STALLED_IMPACTS: u32 = 1000;

/// Watches the impacts for a contact that no longer separates.
#[derive(Clone, Debug)]
pub(super) struct Guard {
    scales: Scales,
    last_t: Real,
    stalled: u32,
}

impl Guard {
    pub(super) fn new(scales: Scales) -> Self {
        Self {
            scales,
            last_t: Real::NEG_INFINITY,
            stalled: 0,
        }
    }

    /// Starts watching at `t0`.
    pub(super) fn reset(&mut self, t0: Real) {
        self.last_t = t0;
        self.stalled = 0;
    }

    /// After an impact at `t` leaving the normal separation speed `v_s_n`: why
    /// the run must stop, if it must.
    ///
    /// Two signs of an accumulation: the separation speed is below the resting speed
    /// `v_rest` (the flights that follow would be shorter than the integrator can resolve,
    /// and infinitely many), or impacts keep coming without the time advancing.
    pub(super) fn after_impact(&mut self, t: Real, v_s_n: Real) -> Option<String> {
        if v_s_n <= self.scales.v_rest {
            return Some(format!(
                "the contact separates at {v_s_n:.3e} m/s after the impact, below the resting \
                 speed {:.1e} m/s: it comes to rest",
                self.scales.v_rest
            ));
        }
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
