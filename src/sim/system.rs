//! The equations of motion as an ODE for the integrator.

use crate::dynamics::{DynamicsError, forward_dynamics, power};
use crate::integrate::OdeSystem;
use crate::math::Real;
use crate::model::Model;
use crate::state::Data;

/// The first-order system the integrator advances between impacts:
///
/// ```text
/// y = [q; u; w],   ẏ = [u; M(q)⁻¹ (τ − h(t, q, u)); P]
/// ```
///
/// where `w = (w_damping, w_applied, w_drives)` (J) integrates the powers `P` of the
/// dampers, of the constant efforts and of the prescribed drives, for the energy audit.
/// `w` is present only when the model has such elements (then `dim = 2n + 3`, else `2n`).
pub struct MotionSystem<'m> {
    model: &'m Model,
    /// Scratch of the right-hand side.
    pub data: Data,
    works: bool,
}

/// Number of work quadratures when present: dampers, applied efforts, drives.
pub const WORKS: usize = 3;

impl<'m> MotionSystem<'m> {
    /// The system of `model`.
    pub fn new(model: &'m Model) -> Self {
        let works = model.has_prescribed_motion()
            || (model.joints().iter()).any(|j| j.force.damping != 0.0 || j.force.effort != 0.0);
        Self {
            model,
            data: Data::new(model),
            works,
        }
    }

    /// Whether `y` carries the work quadratures.
    pub fn has_works(&self) -> bool {
        self.works
    }
}

impl OdeSystem for MotionSystem<'_> {
    type Error = DynamicsError;

    fn dim(&self) -> usize {
        2 * self.model.nq() + if self.works { WORKS } else { 0 }
    }

    fn rhs(&mut self, t: Real, y: &[Real], dy: &mut [Real]) -> Result<(), DynamicsError> {
        let n = self.model.nq();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        forward_dynamics(self.model, &mut self.data, t, q, u)?;
        dy[..n].copy_from_slice(u);
        dy[n..2 * n].copy_from_slice(self.data.udot.as_slice());
        if self.works {
            let p = power(self.model, &mut self.data);
            dy[2 * n] = p.damping;
            dy[2 * n + 1] = p.applied;
            dy[2 * n + 2] = p.drives;
        }
        Ok(())
    }
}
