//! Running the methods over their settings: a run for the errors (with a
//! [`TraceObserver`]) and repeated runs without any observer for the wall time.

use std::hint::black_box;
use std::time::Instant;

use super::{Trace, TraceObserver, WorkprecError};
use crate::integrate::Method as Integrator;
use crate::math::Real;
use crate::scene::Scene;
use crate::sim::{
    MaterialOverride, MoreauJean, NullObserver, Observer, RunCounters, RunSummary, Simulation,
    StopReason,
};

/// A way to run a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// The event-driven loop with DOPRI5(4); the setting is `rtol` (`atol = 1e-2 rtol`).
    Dopri5,
    /// The event-driven loop with DOP853; the setting is `rtol` (`atol = 1e-2 rtol`).
    Dop853,
    /// The event-driven loop with RK4 at a fixed step; the setting is the step (s).
    Rk4,
    /// The Moreau–Jean time-stepping (θ = ½); the setting is the step (s).
    MoreauJean,
    /// rapier2d-f64 (feature `rapier`); the setting is the time step (s).
    Rapier,
}

impl Method {
    /// Every method, in chart order.
    pub const ALL: [Method; 5] = [
        Method::Dopri5,
        Method::Dop853,
        Method::Rk4,
        Method::MoreauJean,
        Method::Rapier,
    ];

    /// `dopri5`, `rk4`, `moreau-jean`, `rapier`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Rk4 => "rk4",
            Method::MoreauJean => "moreau-jean",
            Method::Rapier => "rapier",
        }
    }

    /// The name of the swept setting: `rtol` or `dt`.
    pub fn parameter(self) -> &'static str {
        match self {
            Method::Dopri5 | Method::Dop853 => "rtol",
            _ => "dt",
        }
    }

    /// The method named `name` (see [`Method::name`]).
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The default sweep of the setting: tolerances from 1e-3 to 1e-12 for DOPRI5 and
    /// DOP853, steps from 1e-2 s down for the fixed-step methods (each divides the end
    /// times used).
    pub fn default_sweep(self) -> Vec<Real> {
        match self {
            Method::Dopri5 | Method::Dop853 => (3..=12).map(|k| 10f64.powi(-k)).collect(),
            Method::Rk4 => vec![1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4],
            Method::MoreauJean | Method::Rapier => {
                vec![1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5]
            }
        }
    }
}

/// The scene's settings with `method` at `setting`.
fn configured(scene: &Scene, method: Method, setting: Real) -> crate::settings::Settings {
    let mut s = scene.settings.clone();
    s.output_rate = 0.0;
    match method {
        Method::Dopri5 | Method::Dop853 => {
            s.integrator.method = if method == Method::Dop853 {
                Integrator::Dop853
            } else {
                Integrator::Dopri5
            };
            s.integrator.rtol = setting;
            s.integrator.atol = 1e-2 * setting;
        }
        Method::Rk4 => {
            s.integrator.method = Integrator::Rk4;
            s.integrator.dt = setting;
        }
        Method::MoreauJean | Method::Rapier => {
            s.integrator.method = Integrator::MoreauJean;
            s.integrator.dt = setting;
        }
    }
    s
}

/// One run of a ricochet method (not rapier) with `observer`.
pub fn run_ricochet(
    scene: &Scene,
    method: Method,
    setting: Real,
    observer: &mut dyn Observer,
) -> Result<RunSummary, WorkprecError> {
    let settings = configured(scene, method, setting);
    let setup = |error| WorkprecError::Setup {
        method: method.name(),
        error: Box::new(error),
    };
    let overrides = MaterialOverride::default();
    Ok(match method {
        Method::Dopri5 | Method::Dop853 | Method::Rk4 => {
            Simulation::new(&scene.model, &settings, overrides)
                .map_err(setup)?
                .run(&scene.initial, observer, None)
        }
        Method::MoreauJean => MoreauJean::new(&scene.model, &settings, overrides)
            .map_err(setup)?
            .run(&scene.initial, observer, None),
        Method::Rapier => {
            return Err(WorkprecError::Unsupported {
                method: "rapier",
                scene: scene.name.clone(),
                reason: "rapier runs through workprec::rapier".into(),
            });
        }
    })
}

/// The trace and the counters of one run of a ricochet method. A run that failed still
/// gives its trace up to the failure (its end state then counts as not reached).
pub fn trace_of(
    scene: &Scene,
    method: Method,
    setting: Real,
) -> Result<(Trace, RunCounters, StopReason), WorkprecError> {
    let mut obs = TraceObserver::default();
    let summary = run_ricochet(scene, method, setting, &mut obs)?;
    let mut trace = obs.trace;
    trace.energy_initial = summary.audit.initial.total();
    trace.t_end = summary.state.t;
    trace.q = summary.state.q.as_slice().to_vec();
    trace.u = summary.state.u.as_slice().to_vec();
    Ok((trace, summary.counters, summary.stop))
}

/// Wall times of `repeats` calls of `run` (s): the median, the fastest, the slowest.
pub fn wall_times(repeats: usize, mut run: impl FnMut()) -> (Real, Real, Real) {
    let mut walls: Vec<Real> = (0..repeats.max(1))
        .map(|_| {
            let start = Instant::now();
            run();
            start.elapsed().as_secs_f64()
        })
        .collect();
    walls.sort_by(Real::total_cmp);
    let k = walls.len();
    let median = if k % 2 == 1 {
        walls[k / 2]
    } else {
        0.5 * (walls[k / 2 - 1] + walls[k / 2])
    };
    (median, walls[0], walls[k - 1])
}

/// Wall times of a ricochet method without any observer (the simulation alone).
pub fn time_ricochet(
    scene: &Scene,
    method: Method,
    setting: Real,
    repeats: usize,
) -> Result<(Real, Real, Real), WorkprecError> {
    // Set up once to report bad settings as an error; the timed runs repeat the set-up
    // (it is part of running a scene).
    run_ricochet(scene, method, setting, &mut NullObserver)?;
    Ok(wall_times(repeats, || {
        let _ = black_box(run_ricochet(scene, method, setting, &mut NullObserver));
    }))
}
