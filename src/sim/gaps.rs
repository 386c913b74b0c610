//! The signed gaps of the contact pairs as the event functions of the integrator.

use crate::contact::{ContactError, pair_contact, signed_gap};
use crate::events::EventFunctions;
use crate::kinematics::{point_velocity, update_positions, update_velocities};
use crate::math::{Real, Vec2};
use crate::model::{Model, PairId};
use crate::state::Data;

/// `gᵢ(t, y)`: the signed gap of contact pair `i` at `q = y[..n]` (m), and its rate
/// `ġᵢ = v^R·n` (m/s), the normal relative velocity of the closest points.
pub struct GapFunctions<'m> {
    model: &'m Model,
    data: Data,
}

impl<'m> GapFunctions<'m> {
    /// The gaps of every contact pair of `model`, in pair order.
    pub fn new(model: &'m Model) -> Self {
        Self {
            model,
            data: Data::new(model),
        }
    }
}

impl EventFunctions for GapFunctions<'_> {
    type Error = ContactError;

    fn values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), ContactError> {
        let n = self.model.nq();
        update_positions(self.model, &mut self.data, t, &y[..n])?;
        for (k, gk) in g.iter_mut().enumerate() {
            *gk = signed_gap(self.model, &self.data, PairId(k), Real::INFINITY)?
                .unwrap_or(Real::INFINITY);
        }
        Ok(())
    }

    fn rates(
        &mut self,
        t: Real,
        y: &[Real],
        _dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, ContactError> {
        let n = self.model.nq();
        update_positions(self.model, &mut self.data, t, &y[..n])?;
        update_velocities(self.model, &mut self.data, &y[n..2 * n])?;
        for (k, gd) in g_dot.iter_mut().enumerate() {
            let pair = PairId(k);
            *gd = match pair_contact(self.model, &self.data, pair, Real::INFINITY)? {
                Some(c) => {
                    let p = &self.model.pairs()[k];
                    let v = |collider: crate::model::ColliderId, at: Vec2| match self
                        .model
                        .colliders()[collider.index()]
                    .body
                    {
                        Some(body) => {
                            point_velocity(self.model, &self.data, body, at).map(|v| v.total)
                        }
                        None => Ok(Vec2::ZERO),
                    };
                    (v(p.b, c.point_b)? - v(p.a, c.point_a)?).dot(c.normal)
                }
                None => 0.0,
            };
        }
        Ok(true)
    }
}
