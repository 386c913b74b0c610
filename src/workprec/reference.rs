//! The references of the work-precision errors: the closed form of the bouncing ball, the
//! analytic first impact of the falling rod, and a tight DOPRI5 run for the rest.

use super::sweep::{Method, trace_of};
use super::{ImpactRecord, Trace, WorkprecError};
use crate::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};
use crate::math::Real;
use crate::scene::Scene;

/// Relative tolerance of the tight reference runs (absolute: `1e-2` of it).
pub const TIGHT_RTOL: Real = 1e-13;

/// A ball dropped from rest on a floor, moving vertically: gravity `g` (m/s², > 0), the
/// height of its centre `y0` (m), its radius `r` (m), mass `m` (kg), restitution `e`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    /// Gravity (m/s², positive).
    pub g: Real,
    /// Initial height of the centre (m).
    pub y0: Real,
    /// Radius (m).
    pub r: Real,
    /// Mass (kg).
    pub m: Real,
    /// Coefficient of restitution.
    pub e: Real,
}

impl Ball {
    /// The closed-form trace up to `t_end` (before the accumulation point): the first
    /// impact at `t₁ = √(2 h₀/g)` with speed `v₁ = √(2 g h₀)`, `h₀ = y₀ − r`; impact k + 1
    /// leaves at `v_k = e^k v₁` and the flight after it lasts `2 v_k / g`; the energy after
    /// impact k is `½ m v_k² + m g r`; in flight `y = r + v_k τ − ½ g τ²`, `u = v_k − g τ`.
    /// The impacts follow Newton's hypothesis [P, Sect. 3] without friction and with one
    /// degree of freedom: `v_n^S = −e v_n^A`.
    pub fn closed_form(&self, t_end: Real) -> Trace {
        let Ball { g, y0, r, m, e } = *self;
        let h0 = y0 - r;
        let v1 = (2.0 * g * h0).sqrt();
        let mut trace = Trace {
            energy_initial: m * g * y0,
            t_end,
            ..Trace::default()
        };
        let t1 = (2.0 * h0 / g).sqrt();
        if t_end < t1 {
            trace.q = vec![y0 - 0.5 * g * t_end * t_end];
            trace.u = vec![-g * t_end];
            return trace;
        }
        let (mut t, mut v) = (t1, v1);
        loop {
            v *= e;
            trace.impacts.push(ImpactRecord {
                t,
                v_s: [v, 0.0],
                energy_after: 0.5 * m * v * v + m * g * r,
            });
            let flight = 2.0 * v / g;
            if t + flight > t_end || flight <= 0.0 {
                let tau = t_end - t;
                trace.q = vec![r + v * tau - 0.5 * g * tau * tau];
                trace.u = vec![v - g * tau];
                return trace;
            }
            t += flight;
        }
    }
}

/// The falling rod's first impact (`scenes/falling_rod.toml`) from its free flight and the
/// impact law on the hand-derived `W`: a uniform rod (mass `m`, length `l`, capsule radius
/// `r`) released from rest at height `y0`, tilted by `θ`, falls without turning and lands
/// at `t₁ = √(2 (y₀ − (l/2) sin θ − r)/g)` with `v^A = (−g t₁, 0)`; at the contact point
/// `ρ = (−(l/2) cos θ, −(l/2) sin θ − r)` from the centre, `W = I₂/m + perp(ρ) perp(ρ)ᵀ/I`
/// (Eq. 20 for a free body, `I = m l²/12`); the law gives `v^S` (Eqs. 22–23).
/// The normal is the floor's `+y`, the tangent `perp(n)` oriented by Eq. (10) (no slip:
/// `−x`, as the simulation chooses; only `v_t^S` of zero or either sign is compared).
#[allow(clippy::too_many_arguments)]
pub fn falling_rod_first_impact(
    m: Real,
    l: Real,
    r: Real,
    theta: Real,
    y0: Real,
    g: Real,
    e: Real,
    mu: Real,
) -> Result<ImpactRecord, impact::ImpactError> {
    let inertia = m * l * l / 12.0;
    let t1 = (2.0 * (y0 - 0.5 * l * theta.sin() - r) / g).sqrt();
    let rho = (-0.5 * l * theta.cos(), -0.5 * l * theta.sin() - r);
    let perp = (-rho.1, rho.0);
    // n = +y, t = −x.
    let (pn, pt) = (perp.1, -perp.0);
    let w = ImpactMatrix::new(
        1.0 / m + pn * pn / inertia,
        pn * pt / inertia,
        1.0 / m + pt * pt / inertia,
    );
    let v_a = ContactVelocity::new(-g * t1, 0.0);
    let out = impact::solve(Law::Newton, &ImpactProblem::new(w, v_a, e, mu))?;
    // Energy after: before it, m g y0 (potential at release); plus ΔE of Eq. (29).
    Ok(ImpactRecord {
        t: t1,
        v_s: [out.v_s.n, out.v_s.t],
        energy_after: m * g * y0 + out.delta_e,
    })
}

/// The tight reference of a scene: the event-driven loop with DOPRI5 at
/// [`TIGHT_RTOL`] (`atol = 1e-2 rtol`).
pub fn tight(scene: &Scene) -> Result<Trace, WorkprecError> {
    Ok(trace_of(scene, Method::Dopri5, TIGHT_RTOL)?.0)
}
