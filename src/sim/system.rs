//! The equations of motion as an ODE for the integrator.

use super::persistent::Persistent;
use super::{AtTime, Nested, Scales};
use crate::dynamics::{Power, coordinate_rates, forward_dynamics, has_power, power};
use crate::integrate::OdeSystem;
use crate::linalg::copy_short;
use crate::math::Real;
use crate::model::Model;
use crate::state::Data;

/// The first-order system the integrator advances between impacts:
///
/// ```text
/// y = [q; u; w],   ẏ = [A u + b; M(q)⁻¹ (τ − h(t, q, u) + Fᵀ λ); P]
/// ```
///
/// where `Fᵀ λ` are the forces of the closed contact points in persistent contact
/// (`Persistent`) and `w = (w_damping, w_applied, w_drives, w_contact)` (J) integrates
/// the powers `P` of the dampers, of the constant efforts, of the prescribed drives and of
/// the contact forces, for the energy audit.
pub struct MotionSystem<'m> {
    model: &'m Model,
    /// Scratch of the right-hand side (written by it alone: see [`Self::kinematics_at`]).
    data: Data,
    /// The closed contact points and their forces.
    pub persistent: Persistent,
    /// The state `(t, [q; u])` whose kinematics `data` holds (see [`Self::kinematics_at`]).
    kinematics: KinematicsAt,
    /// Whether the dampers, efforts and drives can have power ([`has_power`]); if not, the
    /// right-hand side takes their zero powers without calling [`power`].
    has_power: bool,
}

/// The state of the last right-hand side whose kinematics completed.
struct KinematicsAt {
    /// Whether `t` and `qu` describe `data`.
    valid: bool,
    t: Real,
    qu: Vec<Real>,
}

/// Number of work quadratures: dampers, applied efforts, drives, contact forces.
pub const WORKS: usize = 4;

impl<'m> MotionSystem<'m> {
    /// The system of `model`, with no closed contact point.
    pub fn new(model: &'m Model, scales: Scales) -> Self {
        Self {
            model,
            data: Data::new(model),
            persistent: Persistent::new(model, scales),
            kinematics: KinematicsAt {
                valid: false,
                t: Real::NAN,
                qu: vec![0.0; model.nq() + model.nu()],
            },
            has_power: has_power(model),
        }
    }

    /// The scratch of the right-hand side if it holds the kinematics of `(t, q, u)` (the
    /// positions and velocities of its last evaluation, there): e.g. the end state of a
    /// DOPRI5 step, whose last stage (FSAL) is evaluated there. A consumer of the
    /// kinematics of that state copies them ([`Data::copy_kinematics_from`]): the same
    /// numbers as `update_positions` and `update_velocities` there.
    pub fn kinematics_at(&self, t: Real, q: &[Real], u: &[Real]) -> Option<&Data> {
        let k = &self.kinematics;
        let n = q.len();
        (k.valid && k.t == t && k.qu.len() == n + u.len() && k.qu[..n] == *q && k.qu[n..] == *u)
            .then_some(&self.data)
    }
}

impl OdeSystem for MotionSystem<'_> {
    type Error = Nested;

    fn dim(&self) -> usize {
        self.model.nq() + self.model.nu() + WORKS
    }

    /// `q` and `u`: the works are quadratures of them, outside the step-size control.
    fn controlled(&self) -> usize {
        self.model.nq() + self.model.nu()
    }

    fn rhs(&mut self, t: Real, y: &[Real], dy: &mut [Real]) -> Result<(), Nested> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        self.kinematics.valid = false;
        forward_dynamics(self.model, &mut self.data, t, q, u).map_err(|e| Nested::from(e.at(t)))?;
        // `accelerate` and `power` leave the kinematics as they are.
        self.kinematics.t = t;
        copy_short(&mut self.kinematics.qu, &y[..nqu]);
        self.kinematics.valid = true;
        self.persistent
            .accelerate(self.model, &mut self.data, (t, q, u))?;
        coordinate_rates(self.model, &self.data, u, &mut dy[..n]);
        copy_short(&mut dy[n..nqu], self.data.udot.as_slice());
        let p = if self.has_power {
            power(self.model, &mut self.data)
        } else {
            Power::default()
        };
        dy[nqu] = p.damping;
        dy[nqu + 1] = p.applied;
        dy[nqu + 2] = p.drives;
        dy[nqu + 3] = if self.persistent.closed().is_empty() {
            0.0
        } else {
            self.persistent.power()
        };
        Ok(())
    }
}
