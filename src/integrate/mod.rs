//! Time integration of `ẏ = f(t, y)`: DOPRI5(4) and DOP853 with step-size control and
//! dense output, RK4 with a fixed step.
//! This module knows nothing about bodies or contacts. ([`Method`] also names the
//! Moreau–Jean time-stepping scheme, which is not an ODE stepper: it lives in `sim`.)
//!
//! - [`OdeSystem`]: the system, whose right-hand side may fail.
//! - [`Stepper`]: one accepted step at a time, the continuous extension (dense output) of
//!   the last step (DOP853's completed on demand by [`Stepper::complete_dense`], before it
//!   is read inside the step), a re-step to an event time at full order, a reset at an impact, a cap
//!   on the step, and work [`Counters`]. Implemented by [`RungeKutta`], one explicit
//!   Runge–Kutta stepper driven by its [`tableau::Tableau`]: DOPRI5 [HNW, II.4–6;
//!   Dormand & Prince 1980; Shampine 1986], DOP853 [HNW, II.10] and RK4 [HNW, II.1],
//!   chosen by the run's [`Method`] ([`AnyStepper`], [`Dopri5`] and [`Rk4`] are its
//!   former names).
//! - Event location on the dense output lives in [`crate::events`]; the reset (impact) map
//!   stays with the simulation loop.
//!
//! Every vector is allocated when a stepper is built (or when `start` meets a system of
//! another dimension); a step allocates nothing.
//!
//! Why our own Runge–Kutta rather than a crate: `notes/crates.md` §3d (event semantics for
//! impacts, a maximum step, re-stepping to the event).
//!
//! # Driving a stepper
//!
//! ```
//! use ricochet::integrate::{Dopri5, Dopri5Settings, FnSystem, StepOutcome, Stepper};
//! // Harmonic oscillator ẍ = −x, x(0) = 1, ẋ(0) = 0.
//! let mut sys = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
//!     dy[0] = y[1];
//!     dy[1] = -y[0];
//! });
//! let settings = Dopri5Settings { rtol: 1e-9, atol: 1e-12, h_max: 0.5, ..Default::default() };
//! let mut stepper = Dopri5::new(2, settings)?;
//! stepper.start(&mut sys, 0.0, &[1.0, 0.0])?;
//! let mut x = [0.0; 2];
//! loop {
//!     let outcome = stepper.step(&mut sys, 3.0)?;
//!     // The last step is [t_prev, t]; its continuous extension is available.
//!     let t_mid = 0.5 * (stepper.t_prev() + stepper.t());
//!     stepper.dense(t_mid, &mut x)?;
//!     assert!((x[0] - t_mid.cos()).abs() < 1e-8);
//!     if outcome == StepOutcome::ReachedStop {
//!         break;
//!     }
//! }
//! assert_eq!(stepper.t(), 3.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

#[doc(hidden)]
pub mod control;
mod dense;
mod error;
mod rk;
mod stepper;
mod system;
pub mod tableau;

pub use error::{DenseIncomplete, IntegrateError, SettingsError};
pub use rk::{
    AdaptiveSettings, AnyStepper, Dopri5, Dopri5Settings, Rk4, Rk4Settings, RungeKutta,
    StepperConfig,
};
pub use stepper::{Counters, StepOutcome, Stepper};
pub use system::{FnSystem, OdeSystem};

/// The time-integration method of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Dormand–Prince 5(4), adaptive step, dense output of order 4 [HNW, II.5–6].
    Dopri5,
    /// Dormand–Prince 8(5,3), adaptive step, dense output of order 7 [HNW, II.10]: for
    /// tight tolerances.
    Dop853,
    /// The classical Runge–Kutta method of order 4 with a fixed step.
    Rk4,
    /// The time-stepping scheme of Moreau and Jean with a fixed step `dt`: not an ODE
    /// stepper (there is no [`Stepper`] for it); the run is `sim::MoreauJean`'s, which
    /// solves the contacts at the velocity level in every step.
    MoreauJean,
}

impl Method {
    /// Every method, in the order shown to users.
    pub const ALL: [Method; 4] = [
        Method::Dopri5,
        Method::Dop853,
        Method::Rk4,
        Method::MoreauJean,
    ];

    /// The methods that are ODE steppers ([`RungeKutta`] runs them).
    pub const ODE: [Method; 3] = [Method::Dopri5, Method::Dop853, Method::Rk4];

    /// Whether the method is an ODE stepper run by the event-driven loop (not
    /// Moreau–Jean's time-stepping).
    pub fn is_ode(self) -> bool {
        !matches!(self, Method::MoreauJean)
    }

    /// Whether the method takes a fixed step `dt` (RK4, Moreau–Jean).
    pub fn is_fixed_step(self) -> bool {
        matches!(self, Method::Rk4 | Method::MoreauJean)
    }

    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::Dop853 => "dop853",
            Method::Rk4 => "rk4",
            Method::MoreauJean => "moreau-jean",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A method name that is not known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown method `{0}` (expected one of: dopri5, dop853, rk4, moreau-jean)")]
pub struct UnknownMethod(pub String);

impl FromStr for Method {
    type Err = UnknownMethod;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}
