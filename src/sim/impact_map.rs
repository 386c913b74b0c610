//! The impact map of one contact pair: the contact frame, `W = J M⁻¹ Jᵀ`, the impact law
//! and the jump of the generalized speeds.

use crate::contact::{ContactFrame, FrameWorkspace, contact_frame};
use crate::dynamics::{Energy, energy, factor_mass_matrix, mass_matrix, solve_mass};
use crate::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law, Outcome};
use crate::kinematics::{update_positions, update_velocities};
use crate::math::Real;
use crate::model::{Material, Model, PairId};
use crate::state::Data;

use super::SimError;

/// Overrides of the scene's contact materials, for every pair (the command line's
/// `--law`, `--e`, `--mu`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MaterialOverride {
    /// Impact law for every pair.
    pub law: Option<Law>,
    /// Coefficient of restitution for every pair.
    pub e: Option<Real>,
    /// Coefficient of friction for every pair.
    pub mu: Option<Real>,
}

impl MaterialOverride {
    /// Checks the overrides: `e ∈ [0, 1]`, `μ ≥ 0`, finite.
    pub fn validate(&self) -> Result<(), SimError> {
        if let Some(e) = self.e
            && !(0.0..=1.0).contains(&e)
        {
            return Err(SimError::Override {
                what: "e",
                value: e,
            });
        }
        if let Some(mu) = self.mu
            && !(mu >= 0.0 && mu.is_finite())
        {
            return Err(SimError::Override {
                what: "mu",
                value: mu,
            });
        }
        Ok(())
    }

    /// The material of a pair after the overrides.
    pub fn apply(&self, m: Material) -> Material {
        Material {
            law: self.law.unwrap_or(m.law),
            e: self.e.unwrap_or(m.e),
            mu: self.mu.unwrap_or(m.mu),
        }
    }
}

/// What one impact did: an entry of the impact ledger.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpactEvent {
    /// Index of the impact in the run, from 0.
    pub index: u64,
    /// Time of the impact (s).
    pub t: Real,
    /// The contact frame at the impact (before the jump).
    pub frame: ContactFrame,
    /// The material used (after overrides).
    pub material: Material,
    /// `W = J M⁻¹ Jᵀ` in the frame `(n, t)` [P, Eq. (20)].
    pub w: ImpactMatrix,
    /// Velocity of approach in the frame `(n, t)` (m/s).
    pub v_a: ContactVelocity,
    /// The impact law's solution.
    pub outcome: Outcome,
    /// The jump of the generalized speeds `Δu` [P, Eq. (16)] (nu entries).
    pub delta_u: Vec<Real>,
    /// Energies before the impact, from the model (J).
    pub energy_before: Energy,
    /// Energies after the impact, from the model (J).
    pub energy_after: Energy,
}

impl ImpactEvent {
    /// The change of mechanical energy computed from the model (J): Eq. (29) plus the
    /// work of the prescribed motions, Eq. (28).
    pub fn energy_change(&self) -> Real {
        self.energy_after.total() - self.energy_before.total()
    }

    /// The part of the energy change that is not Eq. (29): the work of the prescribed
    /// motions at the impact, the left-hand side of [P, Eq. (28)] (J). Zero to rounding
    /// without prescribed motion.
    pub fn prescribed_work(&self) -> Real {
        self.energy_change() - self.outcome.delta_e
    }
}

/// Scratch of the impact map, allocated once per run.
pub struct ImpactMap {
    data: Data,
    frame_ws: FrameWorkspace,
    /// `J_n` (nu).
    j_n: Vec<Real>,
    /// `J_t` (nu).
    j_t: Vec<Real>,
    /// `M⁻¹ J_nᵀ` (nu).
    x_n: Vec<Real>,
    /// `M⁻¹ J_tᵀ` (nu).
    x_t: Vec<Real>,
}

impl ImpactMap {
    /// Scratch for `model`.
    pub fn new(model: &Model) -> Self {
        let nu = model.nu();
        Self {
            data: Data::new(model),
            frame_ws: FrameWorkspace::new(model),
            j_n: vec![0.0; nu],
            j_t: vec![0.0; nu],
            x_n: vec![0.0; nu],
            x_t: vec![0.0; nu],
        }
    }

    /// The contact frame of `pair` at `(t, q, u)`: where it is, how far, how fast.
    pub fn frame(
        &mut self,
        model: &Model,
        pair: PairId,
        t: Real,
        q: &[Real],
        u: &[Real],
    ) -> Result<ContactFrame, SimError> {
        update_positions(model, &mut self.data, t, q).map_err(|e| SimError::at(t, e))?;
        update_velocities(model, &mut self.data, u).map_err(|e| SimError::at(t, e))?;
        let frame = contact_frame(
            model,
            &self.data,
            pair,
            Real::INFINITY,
            &mut self.frame_ws,
            &mut self.j_n,
            &mut self.j_t,
        )
        .map_err(|e| SimError::at(t, e))?;
        frame.ok_or(SimError::Contact {
            t,
            message: format!("pair #{} has no closest points", pair.index()),
        })
    }

    /// Applies the impact of `pair` at `(t, q, u)`: `u` becomes `u⁺`. Returns `None` (and
    /// leaves `u`) if the points do not approach (`v_n^A ≥ 0`).
    ///
    /// The stages of [P, Sects. 2–4]:
    /// 1. the contact frame and `J_n`, `J_t` (the rows `v_r^R·n`, `v_r^R·t`);
    /// 2. `W = J M⁻¹ Jᵀ` through the Cholesky factor of `M` [P, Eq. (20)]:
    ///    `m_nn = J_n M⁻¹ J_nᵀ`, `m_nt = J_n M⁻¹ J_tᵀ`, `m_tt = J_t M⁻¹ J_tᵀ`;
    /// 3. the impact law on `(W, v^A, e, μ)`;
    /// 4. `Δu = M⁻¹ (J_nᵀ I_n + J_tᵀ I_t)` [P, Eq. (16)] (with the positive definite `M`).
    ///
    /// The energies before and after come from the model, so the ledger can check them
    /// against ΔE of Eq. (29).
    pub fn apply(
        &mut self,
        model: &Model,
        pair: PairId,
        material: Material,
        t: Real,
        q: &[Real],
        u: &mut [Real],
    ) -> Result<Option<ImpactEvent>, SimError> {
        // 1. Contact frame, velocity of approach.
        let frame = self.frame(model, pair, t, q, u)?;
        let v_a = ContactVelocity::new(frame.v_n(), frame.v_t());
        if v_a.n >= 0.0 {
            return Ok(None);
        }
        // 2. W = J M⁻¹ Jᵀ.
        mass_matrix(model, &mut self.data);
        factor_mass_matrix(&mut self.data, t).map_err(|e| SimError::at(t, e))?;
        self.x_n.copy_from_slice(&self.j_n);
        self.x_t.copy_from_slice(&self.j_t);
        solve_mass(&self.data, &mut self.x_n).map_err(|e| SimError::at(t, e))?;
        solve_mass(&self.data, &mut self.x_t).map_err(|e| SimError::at(t, e))?;
        let dot = |a: &[Real], b: &[Real]| a.iter().zip(b).map(|(x, y)| x * y).sum::<Real>();
        let w = ImpactMatrix::new(
            dot(&self.j_n, &self.x_n),
            0.5 * (dot(&self.j_n, &self.x_t) + dot(&self.j_t, &self.x_n)),
            dot(&self.j_t, &self.x_t),
        );
        // 3. The impact law.
        let problem = ImpactProblem::new(w, v_a, material.e, material.mu);
        let outcome = impact::solve(material.law, &problem).map_err(|source| SimError::Impact {
            t,
            pair: pair.index(),
            name: pair_name(model, pair),
            source,
        })?;
        // 4. Δu = M⁻¹ Jᵀ I.
        let energy_before =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        let (i_n, i_t) = (outcome.impulse.n, outcome.impulse.t);
        let delta_u: Vec<Real> = (self.x_n.iter().zip(&self.x_t))
            .map(|(xn, xt)| xn * i_n + xt * i_t)
            .collect();
        for (ur, du) in u.iter_mut().zip(&delta_u) {
            *ur += du;
        }
        let energy_after =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        Ok(Some(ImpactEvent {
            index: 0,
            t,
            frame,
            material,
            w,
            v_a,
            outcome,
            delta_u,
            energy_before,
            energy_after,
        }))
    }
}

/// The name of a contact pair, `<collider a>/<collider b>`.
pub fn pair_name(model: &Model, pair: PairId) -> String {
    let p = &model.pairs()[pair.index()];
    let name = |c: crate::model::ColliderId| &model.colliders()[c.index()].name;
    format!("{}/{}", name(p.a), name(p.b))
}
