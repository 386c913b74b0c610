//! [`AnyStepper`]: the method chosen at run time (from a scene file or the command line).

use super::{
    Counters, Dopri5, Dopri5Settings, IntegrateError, Method, OdeSystem, Rk4, Rk4Settings,
    SettingsError, StepOutcome, Stepper,
};
use crate::math::Real;
use crate::settings::IntegratorSettings;

/// One of the steppers, chosen by [`Method`] at run time. It forwards every call.
#[derive(Clone, Debug)]
pub enum AnyStepper {
    /// DOPRI5(4), adaptive.
    Dopri5(Dopri5),
    /// RK4, fixed step.
    Rk4(Rk4),
}

impl AnyStepper {
    /// The stepper of `settings.method` for systems of dimension `n`, with the run's
    /// tolerances, `dt` and `h_max` (the other DOPRI5 settings at their defaults). A
    /// [`SettingsError`] for [`Method::MoreauJean`], which is not an ODE stepper.
    pub fn new(n: usize, settings: &IntegratorSettings) -> Result<Self, SettingsError> {
        Ok(match settings.method {
            Method::Dopri5 => AnyStepper::Dopri5(Dopri5::new(n, Dopri5Settings::from(settings))?),
            Method::Rk4 => AnyStepper::Rk4(Rk4::new(n, Rk4Settings::from(settings))?),
            Method::MoreauJean => {
                return Err(SettingsError {
                    field: "method",
                    value: Real::NAN,
                    reason: "moreau-jean is a time-stepping scheme with its own loop \
                             (sim::MoreauJean), not an ODE stepper: run it with MoreauJean, \
                             not Simulation",
                });
            }
        })
    }

    /// Sets the smallest step of the adaptive method (s): below `max(h_min, 10 ε |t|)` it
    /// gives up with [`super::IntegrateError::StepSizeTooSmall`]. No effect on RK4.
    pub fn set_h_min(&mut self, h_min: Real) {
        if let AnyStepper::Dopri5(s) = self {
            s.set_h_min(h_min);
        }
    }
}

macro_rules! forward {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnyStepper::Dopri5($s) => $e,
            AnyStepper::Rk4($s) => $e,
        }
    };
}

impl Stepper for AnyStepper {
    fn method(&self) -> Method {
        forward!(self, s => s.method())
    }
    fn start<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: Real,
        y0: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        forward!(self, s => s.start(sys, t0, y0))
    }
    fn step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_stop: Real,
    ) -> Result<StepOutcome, IntegrateError<S::Error>> {
        forward!(self, s => s.step(sys, t_stop))
    }
    fn restep_to<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t_target: Real,
    ) -> Result<(), IntegrateError<S::Error>> {
        forward!(self, s => s.restep_to(sys, t_target))
    }
    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: Real,
        y: &[Real],
    ) -> Result<(), IntegrateError<S::Error>> {
        forward!(self, s => s.reset(sys, t, y))
    }
    fn t(&self) -> Real {
        forward!(self, s => s.t())
    }
    fn y(&self) -> &[Real] {
        forward!(self, s => s.y())
    }
    fn dy(&self) -> &[Real] {
        forward!(self, s => s.dy())
    }
    fn t_prev(&self) -> Real {
        forward!(self, s => s.t_prev())
    }
    fn y_prev(&self) -> &[Real] {
        forward!(self, s => s.y_prev())
    }
    fn dy_prev(&self) -> &[Real] {
        forward!(self, s => s.dy_prev())
    }
    fn dense(&self, t: Real, out: &mut [Real]) {
        forward!(self, s => s.dense(t, out))
    }
    fn dense_derivative(&self, t: Real, out: &mut [Real]) {
        forward!(self, s => s.dense_derivative(t, out))
    }
    fn set_h_max(&mut self, h_max: Real) {
        forward!(self, s => s.set_h_max(h_max))
    }
    fn h_max(&self) -> Real {
        forward!(self, s => s.h_max())
    }
    fn counters(&self) -> Counters {
        forward!(self, s => s.counters())
    }
    fn dim(&self) -> usize {
        forward!(self, s => s.dim())
    }
}
