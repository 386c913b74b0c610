//! Run settings: end time, output rate and integrator settings. A scene file supplies
//! them; the command line may override them.

use serde::{Deserialize, Serialize};

use crate::integrate::Method;
use crate::math::Real;

/// Settings of one simulation run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// End time of the run (s).
    pub t_end: Real,
    /// Rate of `/state` samples in the log (Hz).
    pub output_rate: Real,
    /// How the equations of motion are integrated.
    pub integrator: IntegratorSettings,
    /// The energy-drift budget: the largest integration drift of the energy audit that a
    /// run may show, relative to the run's energy scale (dimensionless; see
    /// `regress::DriftCheck`). `None`: no budget. A run that breaks it still runs to its
    /// end and writes its log, and `ricochet run` exits with 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_drift: Option<Real>,
}

/// Integrator settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IntegratorSettings {
    /// The method.
    pub method: Method,
    /// Relative tolerance of the adaptive methods (dimensionless).
    pub rtol: Real,
    /// Absolute tolerance of the adaptive methods (units of the state).
    pub atol: Real,
    /// Step of the fixed-step methods (s).
    pub dt: Real,
    /// Largest step of the adaptive methods (s).
    pub h_max: Real,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            method: Method::Dopri5,
            rtol: 1e-10,
            atol: 1e-12,
            dt: 1e-3,
            h_max: 0.1,
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            t_end: 1.0,
            output_rate: 100.0,
            integrator: IntegratorSettings::default(),
            max_drift: None,
        }
    }
}
