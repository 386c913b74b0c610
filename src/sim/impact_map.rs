//! The impact map of one contact pair: the contact frame, `W = J M⁻¹ Jᵀ`, the impact law
//! and the jump of the generalized speeds.

use nalgebra::{DMatrix, DVector};

use crate::contact::{
    ContactFrame, FrameWorkspace, PairContact, Tangent, contact_frame, frame_at, pair_contact,
};
use crate::dynamics::{Energy, energy, factor_mass, solve_mass};
use crate::impact::{
    self, Coefficients, CollisionType, ContactVelocity, ImpactMatrix, ImpactProblem, Impulse, Law,
    Outcome, Phases, energy_change,
};
use crate::kinematics::{update_positions, update_velocities};
use crate::lcp::{self, Allowed, Mode};
use crate::linalg::{MinNorm, fit_matrix, fit_vector, product_into};
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

/// Why an impulse was applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpactCause {
    /// One contact point approaching: the scene's one-point law \[P\].
    Collision,
    /// Several contact points at once, or an impact that made another touching point
    /// approach: Moreau's generalized Newton law ([`ImpactMap::apply_many`]).
    Simultaneous,
    /// Painlevé's inconsistency: the one-point law in its grazing limit, an impact without
    /// collision ([`ImpactMap::apply_at`] with a floor).
    WithoutCollision,
    /// The end of an accumulation of impacts: the impact after which the hop would be too
    /// small to resolve, made plastic — the scene's law (one point) or Moreau's law
    /// (several) with `e = 0` and the pair's friction; the contact stays closed.
    AccumulationEnd,
    /// The end of a rocking accumulation, when the plastic impact that ends an
    /// accumulation lifts another touching point too slowly to resolve: the contact
    /// impulse of the hops left, until `t∞` — the jump that brings the points to rest
    /// ([`ImpactMap::close`]) and the [`Support`] the closed contacts give until `t∞`.
    RockingEnd,
}

impl ImpactCause {
    /// The name used in logs: `collision`, `simultaneous`, `without_collision`,
    /// `accumulation_end`, `rocking_end`.
    pub fn name(self) -> &'static str {
        match self {
            ImpactCause::Collision => "collision",
            ImpactCause::Simultaneous => "simultaneous",
            ImpactCause::WithoutCollision => "without_collision",
            ImpactCause::AccumulationEnd => "accumulation_end",
            ImpactCause::RockingEnd => "rocking_end",
        }
    }
}

/// What one impact did: an entry of the impact ledger.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpactEvent {
    /// Index of the impact in the run, from 0.
    pub index: u64,
    /// Why the impulse was applied.
    pub cause: ImpactCause,
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
    /// For a [`ImpactCause::RockingEnd`]: the impulse of the persistent contact force at
    /// this point until the hops left would have ended. `None` for every other impact.
    pub support: Option<Support>,
}

/// The impulse a closed contact point delivers over the hops left of a rocking
/// accumulation (see [`ImpactCause::RockingEnd`]).
///
/// A rocking body (a block on its corners) cannot be brought to rest by impulses `≥ 0`
/// at one instant: the plastic impact on one corner lifts the other, and only gravity,
/// over the infinitely many ever smaller hops left, brings it down. Their contact impulse
/// over `[t, t∞]` is, by the momentum balance over that interval,
///
/// ```text
/// Jᵀ I = M (u(t∞) − u⁻) − ∫ (τ − h) dt
/// ```
///
/// and the run delivers the same: the jump `P` at `t` that brings the points to rest
/// (the kinetic-metric projection, [`ImpactMap::close`]), then the persistent contact
/// force `λ` of the closed points over `[t, t∞]`. The ledger entry reports
/// `I = P + S` with the support `S = λ (t∞ − t)` (λ constant over that short time), which
/// is `≥ 0` where `P` alone pulls the lifting corner down: the weight it carries over the
/// remaining hops is larger than the impulse that stops them (a block: `I_n = m g Δt/2 −
/// I_B ω/(2b)` on the lifting corner, and `Δt ≥` its hop `2 I_B ω/(m g b)`).
/// `Δu = M⁻¹ Jᵀ P` and Eq. (29) hold for the jump `P = I − S`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Support {
    /// `S = λ (t∞ − t)` in the entry's frame `(n, t)` (N·s).
    pub impulse: Impulse,
    /// `t∞ − t`, how long the hops left would have lasted (s).
    pub duration: Real,
}

impl ImpactEvent {
    /// The contact impulse of the entry in its frame `(n, t)` (N·s): the law's, plus the
    /// [`Support`] of a rocking end.
    pub fn impulse(&self) -> Impulse {
        let i = self.outcome.impulse;
        match self.support {
            Some(s) => Impulse::new(i.n + s.impulse.n, i.t + s.impulse.t),
            None => i,
        }
    }

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
    /// Below this normal speed (m/s) a point of a simultaneous impact does not approach
    /// (rounding noise of a touching or held contact): its ledger entry has no `α`.
    still: Real,
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
    /// The complementarity solver of simultaneous impacts.
    lcp: lcp::Solver,
    /// The scratch of the impacts of several points.
    many: Many,
    /// The `Δu` of ledger entries handed back ([`Self::recycle`]), refilled by the next
    /// entries: a run's impacts allocate nothing once it has had its largest impact.
    spare: Vec<Vec<Real>>,
}

impl ImpactMap {
    /// Scratch for `model`.
    pub fn new(model: &Model) -> Self {
        let nu = model.nu();
        Self {
            still: 0.0,
            data: Data::new(model),
            frame_ws: FrameWorkspace::new(model),
            j_n: vec![0.0; nu],
            j_t: vec![0.0; nu],
            x_n: vec![0.0; nu],
            x_t: vec![0.0; nu],
            lcp: lcp::Solver::new(),
            many: Many::default(),
            spare: Vec::new(),
        }
    }

    /// Empties `events`, keeping their `Δu` buffers for the next ledger entries.
    pub fn recycle(&mut self, events: &mut Vec<ImpactEvent>) {
        self.recycle_from(events, 0);
    }

    /// Drops the entries of `events` from `start` on, keeping their `Δu` buffers for the
    /// next ledger entries.
    pub fn recycle_from(&mut self, events: &mut Vec<ImpactEvent>, start: usize) {
        (self.spare).extend(events.drain(start..).map(|ev| ev.delta_u));
    }

    /// An empty `Δu` for a ledger entry: a recycled one if there is one.
    fn delta_u_buffer(&mut self) -> Vec<Real> {
        let mut buffer = self.spare.pop().unwrap_or_default();
        buffer.clear();
        buffer
    }

    /// The same, with `still` (m/s): in a simultaneous impact, a point whose normal speed
    /// is above `−still` does not approach (rounding noise), and its ledger entry has no
    /// `α = v_t / |v_n|`.
    pub fn with_still(mut self, still: Real) -> Self {
        self.still = still;
        self
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

    /// The frame (tangent along the slip) of `pair` at its contact point `contact`, at
    /// `(t, q, u)`; its rows are left in `j_n`, `j_t`.
    fn frame_at_point(
        &mut self,
        model: &Model,
        point: (PairId, PairContact),
        t: Real,
        q: &[Real],
        u: &[Real],
    ) -> Result<ContactFrame, SimError> {
        self.place(model, t, q, u)?;
        self.placed_frame(model, point, Tangent::AlongSlip, t)
    }

    /// The frame (tangent `perp(n)`) of `pair` at its contact point `contact`, at the
    /// instant `t` whose positions and velocities `data` holds (the caller's, already
    /// placed there: the touching points of an instant read the kinematics the contact
    /// query used, computed once). Its rows are left in `j_n`, `j_t`.
    pub fn frame_perp_in(
        &mut self,
        model: &Model,
        data: &Data,
        (pair, contact): (PairId, PairContact),
        t: Real,
    ) -> Result<ContactFrame, SimError> {
        frame_at(
            model,
            data,
            pair,
            contact,
            Tangent::Perp,
            &mut self.frame_ws,
            &mut self.j_n,
            &mut self.j_t,
        )
        .map_err(|e| SimError::at(t, e))
    }

    /// Places the bodies of `data` at `(t, q, u)`: the positions and velocities that
    /// [`Self::placed_frame`] reads (once for the frames of several points at one instant).
    fn place(&mut self, model: &Model, t: Real, q: &[Real], u: &[Real]) -> Result<(), SimError> {
        update_positions(model, &mut self.data, t, q).map_err(|e| SimError::at(t, e))?;
        update_velocities(model, &mut self.data, u).map_err(|e| SimError::at(t, e))
    }

    /// The frame of `point` at the positions and velocities of the last [`Self::place`]
    /// (the instant `t`); its rows are left in `j_n`, `j_t`.
    fn placed_frame(
        &mut self,
        model: &Model,
        (pair, contact): (PairId, PairContact),
        tangent: Tangent,
        t: Real,
    ) -> Result<ContactFrame, SimError> {
        frame_at(
            model,
            &self.data,
            pair,
            contact,
            tangent,
            &mut self.frame_ws,
            &mut self.j_n,
            &mut self.j_t,
        )
        .map_err(|e| SimError::at(t, e))
    }

    /// The frame (tangent along the slip) and `W = J M⁻¹ Jᵀ` of `pair` at its contact point
    /// `contact`, at `(t, q, u)`, without applying any impulse: what the impact law would
    /// be given there (`ricochet regions` maps it).
    ///
    /// Implements [P, Eq. (20)]: `m_nn = J_n M⁻¹ J_nᵀ`, `m_nt = J_n M⁻¹ J_tᵀ`,
    /// `m_tt = J_t M⁻¹ J_tᵀ`, with the rows of [`crate::contact::frame_at`].
    pub fn impact_matrix(
        &mut self,
        model: &Model,
        point: (PairId, PairContact),
        t: Real,
        q: &[Real],
        u: &[Real],
    ) -> Result<(ContactFrame, ImpactMatrix), SimError> {
        let frame = self.frame_at_point(model, point, t, q, u)?;
        let w = self.impact_matrix_of_rows(model, t)?;
        Ok((frame, w))
    }

    /// `W = J M⁻¹ Jᵀ` [P, Eq. (20)] from the rows left in `j_n`, `j_t` by the last frame,
    /// at the positions in `data`; `M⁻¹ J_nᵀ`, `M⁻¹ J_tᵀ` are left in `x_n`, `x_t`.
    fn impact_matrix_of_rows(&mut self, model: &Model, t: Real) -> Result<ImpactMatrix, SimError> {
        factor_mass(model, &mut self.data, t).map_err(|e| SimError::at(t, e))?;
        self.x_n.copy_from_slice(&self.j_n);
        self.x_t.copy_from_slice(&self.j_t);
        solve_mass(&mut self.data, &mut self.x_n).map_err(|e| SimError::at(t, e))?;
        solve_mass(&mut self.data, &mut self.x_t).map_err(|e| SimError::at(t, e))?;
        let dot = |a: &[Real], b: &[Real]| a.iter().zip(b).map(|(x, y)| x * y).sum::<Real>();
        Ok(ImpactMatrix::new(
            dot(&self.j_n, &self.x_n),
            0.5 * (dot(&self.j_n, &self.x_t) + dot(&self.j_t, &self.x_n)),
            dot(&self.j_t, &self.x_t),
        ))
    }

    /// Applies the impact of `pair` at its closest points at `(t, q, u)`: see
    /// [`ImpactMap::apply_at`].
    pub fn apply(
        &mut self,
        model: &Model,
        pair: PairId,
        material: Material,
        t: Real,
        q: &[Real],
        u: &mut [Real],
    ) -> Result<Option<ImpactEvent>, SimError> {
        update_positions(model, &mut self.data, t, q).map_err(|e| SimError::at(t, e))?;
        let contact = pair_contact(model, &self.data, pair, Real::INFINITY)
            .map_err(|e| SimError::at(t, e))?
            .ok_or(SimError::Contact {
                t,
                message: format!("pair #{} has no closest points", pair.index()),
            })?;
        self.apply_at(model, (pair, contact), material, None, t, q, u)
    }

    /// Applies the one-point impact of `pair` at its contact point `contact` at
    /// `(t, q, u)`: `u` becomes `u⁺`. Returns `None` (and leaves `u`) if the points do
    /// not approach (`v_n^A ≥ 0`), unless `approach_floor = Some(δ)`: then a normal
    /// velocity above `−δ` is taken as `−δ` (the grazing limit, an impact without
    /// collision: the law's impulses stay finite as `v_n^A → 0⁻`).
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
    #[allow(clippy::too_many_arguments)]
    pub fn apply_at(
        &mut self,
        model: &Model,
        (pair, contact): (PairId, PairContact),
        material: Material,
        approach_floor: Option<Real>,
        t: Real,
        q: &[Real],
        u: &mut [Real],
    ) -> Result<Option<ImpactEvent>, SimError> {
        // 1. Contact frame, velocity of approach.
        let frame = self.frame_at_point(model, (pair, contact), t, q, u)?;
        let actual = ContactVelocity::new(frame.v_n(), frame.v_t());
        let mut v_a = actual;
        match approach_floor {
            Some(delta) if v_a.n > -delta => v_a.n = -delta,
            None if v_a.n >= 0.0 => return Ok(None),
            _ => {}
        }
        // 2. W = J M⁻¹ Jᵀ.
        let w = self.impact_matrix_of_rows(model, t)?;
        // 3. The impact law.
        let problem = ImpactProblem::new(w, v_a, material.e, material.mu);
        let mut outcome =
            impact::solve(material.law, &problem).map_err(|source| SimError::Impact {
                t,
                pair: pair.index(),
                name: pair_name(model, pair),
                source,
            })?;
        if v_a != actual {
            // Floored: the law ran on v^A = (−δ, v_t); the jump W I applies to the actual
            // velocity, and Eq. (29) is that of the actual velocities (the model's energy
            // change), ΔE = ½ [I_n (v_n^A + v_n^S) + I_t (v_t^A + v_t^S)].
            outcome.v_s = ContactVelocity::new(outcome.v_s.n + actual.n - v_a.n, outcome.v_s.t);
            outcome.delta_e = energy_change(outcome.impulse, actual, outcome.v_s);
            v_a = actual;
        }
        // 4. Δu = M⁻¹ Jᵀ I.
        let energy_before =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        let (i_n, i_t) = (outcome.impulse.n, outcome.impulse.t);
        let mut delta_u = self.delta_u_buffer();
        delta_u.extend((self.x_n.iter().zip(&self.x_t)).map(|(xn, xt)| xn * i_n + xt * i_t));
        for (ur, du) in u.iter_mut().zip(&delta_u) {
            *ur += du;
        }
        let energy_after =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        Ok(Some(ImpactEvent {
            index: 0,
            cause: if approach_floor.is_some() {
                ImpactCause::WithoutCollision
            } else {
                ImpactCause::Collision
            },
            t,
            frame,
            material,
            w,
            v_a,
            outcome,
            delta_u,
            energy_before,
            energy_after,
            support: None,
        }))
    }

    /// Applies the impacts of several contact points at once at `(t, q, u)`: `u` becomes
    /// `u⁺`; one ledger entry per point that receives an impulse.
    ///
    /// The one-point laws of \[P\] do not apply to several contacts. DEVIATION (a law beyond
    /// the paper): Moreau's generalized Newton law with Coulomb friction, the velocity-level
    /// complementarity problem over all the points (closed ones included, with `v_n⁻ ≈ 0`),
    ///
    /// ```text
    /// v⁺ = v⁻ + W P,   v_n⁺ + e v_n⁻ ≥ 0 ⊥ P_n ≥ 0,   |P_t| ≤ μ P_n (stick or slip by v_t⁺)
    /// ```
    ///
    /// with `W = J M⁻¹ Jᵀ` over all the points (2k × 2k), solved by [`crate::lcp::solutions`]
    /// (the enumeration for a few points, its first solution; Lemke's algorithm beyond); then `Δu = M⁻¹ Jᵀ P`. Each entry reports the point's own
    /// 2×2 block of `W`, its velocities and impulses, the type of its final slip, Eq. (29)
    /// and the works along the straight path (`Phases::straight`); the law is reported as
    /// Newton's. The energies before and after each entry add up the points' Eq. (29) in
    /// order; the last entry closes on the model's energy after the impact.
    pub fn apply_many(
        &mut self,
        model: &Model,
        points: &[(PairId, PairContact, Material)],
        t: Real,
        q: &[Real],
        u: &mut [Real],
        out: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        let mut many = std::mem::take(&mut self.many);
        let result = self.apply_many_with(&mut many, model, points, t, q, u, out);
        self.many = many;
        result
    }

    /// [`Self::apply_many`] with the scratch `s` (taken out of `self`).
    #[allow(clippy::too_many_arguments)]
    fn apply_many_with(
        &mut self,
        s: &mut Many,
        model: &Model,
        points: &[(PairId, PairContact, Material)],
        t: Real,
        q: &[Real],
        u: &mut [Real],
        out: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        let k = points.len();
        let at = points.iter().map(|p| (p.0, p.1));
        self.assemble(&mut s.set, &mut s.column, model, at, t, q, u)?;
        let set = &s.set;
        // The complementarity problem: w = W P + b with b_n = (1 + e) v_n⁻, b_t = v_t⁻.
        fit_vector(&mut s.b, 2 * k);
        s.allowed.clear();
        for (i, &(_, _, m)) in points.iter().enumerate() {
            s.b[2 * i] = (1.0 + m.e) * set.v[2 * i];
            s.b[2 * i + 1] = set.v[2 * i + 1];
            s.allowed.push(Allowed {
                mu: m.mu,
                open: true,
                slip: None,
            });
        }
        lcp::solutions_into(&mut self.lcp, &set.w, &s.b, &s.allowed, &mut s.solutions).map_err(
            |e| SimError::Contact {
                t,
                message: format!(
                    "the simultaneous impact of {k} contact points under the generalized \
                     Newton law: {e}"
                ),
            },
        )?;
        // P_n ≥ 0 exactly: a force the solver left at −rounding is none.
        let sol = s.solutions.first_mut().ok_or_else(|| SimError::Contact {
            t,
            message: format!("the simultaneous impact of {k} contact points has no solution"),
        })?;
        sol.open_negative_normals(&set.w, &s.b);
        let sol = &*sol;
        s.materials.clear();
        s.materials.extend(points.iter().map(|p| p.2));
        self.jump(
            model,
            ImpactCause::Simultaneous,
            (set, &mut s.jump),
            &s.materials,
            &sol.x,
            &sol.modes,
            (t, q, u),
            out,
        )
    }

    /// Ends a *rocking* accumulation of impacts: brings every point of `points` to rest in
    /// the normal direction, `v_n⁺ = 0`, and in the tangential one too where it barely slips
    /// (`|v_t⁻| ≤ v_stop`) and has friction, at `(t, q, u)`; `u` becomes `u⁺`. One ledger
    /// entry per point with an impulse (reported with `e = 0`). Used only when the plastic
    /// impact that ends an accumulation leaves another touching point lifting off slower
    /// than its resting speed (a rocking body: the impact on one corner lifts the other),
    /// which no impulse `≥ 0` at that instant can hold down.
    ///
    /// DEVIATION (a truncation beyond the paper): when the hops of a rocking accumulation
    /// fall below what the event location resolves, the infinitely many impacts left are
    /// replaced by the kinetic-metric projection of the velocity onto the closed contacts,
    /// the least-squares solution of
    ///
    /// ```text
    /// W_rr P_r = −v_r⁻   (r: the normal rows, and the tangential rows of the points that
    ///                     stop; W = J M⁻¹ Jᵀ; the other impulses are zero)
    /// ```
    ///
    /// — with one addition: a point that keeps slipping (friction, `|v_t⁻| > v_stop`)
    /// takes Coulomb's sliding friction with its normal impulse, `P_t = −μ s P_n`,
    /// `s = sign v_t⁻`, so that `W_rr`'s column of its normal row is `W_{r,n} − μ s W_{r,t}`
    /// (no longer symmetric: a least-squares solve). `slides[i] = Some(s)` makes point `i`
    /// slip with `s` even where it barely slips (the caller's choice when stopping it
    /// would take an impulse outside the cone). Each hop the jump replaces slides with
    /// `I_t = −μ s I_n`, and so does the support of a sliding point: the entry's sum
    /// `I = P + S` is on the edge of the cone, as the hops' sum would be (a projection
    /// without it left `|I_t| > μ I_n` by `μ |P_n|` where `P_n < 0`).
    ///
    /// The impulses may be of either sign: the jump pulls a rocking body's lifting corner
    /// down (`P_n < 0`). It is only the first part of the contact impulse of the hops it
    /// replaces; the contacts stage adds the second, the [`Support`] of the closed points
    /// until `t∞`, and the ledger entry reports their sum, which is `≥ 0`. What the jump
    /// removes is the energy of the hops left, of the order of `m v_rest²`, and it is in
    /// the ledger (Eq. (29) of the jump).
    #[allow(clippy::too_many_arguments)]
    pub fn close(
        &mut self,
        model: &Model,
        points: &[(PairId, PairContact, Material)],
        slides: &[Option<Real>],
        v_stop: Real,
        t: Real,
        q: &[Real],
        u: &mut [Real],
        out: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        let mut many = std::mem::take(&mut self.many);
        let result = self.close_with(&mut many, model, points, slides, v_stop, (t, q, u), out);
        self.many = many;
        result
    }

    /// [`Self::close`] with the scratch `s` (taken out of `self`).
    #[allow(clippy::too_many_arguments)]
    fn close_with(
        &mut self,
        s: &mut Many,
        model: &Model,
        points: &[(PairId, PairContact, Material)],
        slides: &[Option<Real>],
        v_stop: Real,
        (t, q, u): (Real, &[Real], &mut [Real]),
        out: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        let k = points.len();
        let at = points.iter().map(|p| (p.0, p.1));
        self.assemble(&mut s.set, &mut s.column, model, at, t, q, u)?;
        let set = &s.set;
        let forced = |i: usize| slides.get(i).copied().flatten();
        s.rows.clear();
        s.rows.extend((0..2 * k).filter(|&r| {
            let i = r / 2;
            r.is_multiple_of(2)
                || (points[i].2.mu > 0.0 && set.v[r].abs() <= v_stop && forced(i).is_none())
        }));
        let (rows, m) = (&s.rows, s.rows.len());
        // Whether each point stops (its tangential row is an unknown).
        s.stops.clear();
        s.stops.resize(k, false);
        for &r in rows.iter().filter(|r| !r.is_multiple_of(2)) {
            s.stops[r / 2] = true;
        }
        let stops = &s.stops;
        // The tangential impulse of a point that keeps slipping, per unit of its normal
        // impulse: −μ s, s = sign v_t or the slip `slides` gives (Coulomb's sliding
        // friction); 0 for the rows that are themselves unknowns (a tangential row, or a
        // normal row whose point stops). Once per point, not per entry of `W_rr`.
        s.friction.clear();
        s.friction.extend((0..k).map(|i| {
            if points[i].2.mu > 0.0 && !stops[i] {
                -points[i].2.mu * forced(i).unwrap_or(set.v[2 * i + 1].signum())
            } else {
                0.0
            }
        }));
        let friction = &s.friction;
        let slide = |r: usize| -> Real {
            if r.is_multiple_of(2) {
                friction[r / 2]
            } else {
                0.0
            }
        };
        fit_matrix(&mut s.w_rr, m, m);
        for j in 0..m {
            for i in 0..m {
                let w = set.w[(rows[i], rows[j])];
                s.w_rr[(i, j)] = match slide(rows[j]) {
                    0.0 => w,
                    f => w + f * set.w[(rows[i], rows[j] + 1)],
                };
            }
        }
        fit_vector(&mut s.rhs, m);
        for (i, r) in s.rhs.iter_mut().enumerate() {
            *r = -set.v[rows[i]];
        }
        // The minimum-norm solution: W_rr is singular where closing points are redundant.
        fit_vector(&mut s.p_r, m);
        s.ls.solve(&s.w_rr, &s.rhs, &mut s.p_r);
        if !s.p_r.iter().all(|p| p.is_finite()) {
            return Err(SimError::Contact {
                t,
                message: "the end of an accumulation of impacts: no finite impulse".to_owned(),
            });
        }
        fit_vector(&mut s.x, 2 * k);
        s.x.fill(0.0);
        for (i, &r) in rows.iter().enumerate() {
            s.x[r] = s.p_r[i];
            match slide(r) {
                0.0 => {}
                f => s.x[r + 1] = f * s.p_r[i],
            }
        }
        s.materials.clear();
        (s.materials).extend(points.iter().map(|p| Material { e: 0.0, ..p.2 }));
        s.modes.clear();
        s.modes.extend((0..k).map(|i| {
            if stops[i] {
                Mode::Stick
            } else {
                Mode::Slide(forced(i).unwrap_or(set.v[2 * i + 1].signum()))
            }
        }));
        self.jump(
            model,
            ImpactCause::RockingEnd,
            (set, &mut s.jump),
            &s.materials,
            &s.x,
            &s.modes,
            (t, q, u),
            out,
        )
    }

    /// The frames, rows, `W = J M⁻¹ Jᵀ` and velocities of several contact points at
    /// `(t, q, u)`, into `set` (`column`: scratch of `nu`).
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &mut self,
        set: &mut PointSet,
        column: &mut Vec<Real>,
        model: &Model,
        points: impl ExactSizeIterator<Item = (PairId, PairContact)>,
        t: Real,
        q: &[Real],
        u: &[Real],
    ) -> Result<(), SimError> {
        let (k, nu) = (points.len(), model.nu());
        fit_matrix(&mut set.jac, 2 * k, nu);
        set.frames.clear();
        fit_vector(&mut set.v, 2 * k);
        self.place(model, t, q, u)?;
        for (i, point) in points.enumerate() {
            let frame = self.placed_frame(model, point, Tangent::AlongSlip, t)?;
            for r in 0..nu {
                set.jac[(2 * i, r)] = self.j_n[r];
                set.jac[(2 * i + 1, r)] = self.j_t[r];
            }
            set.v[2 * i] = frame.v_n();
            set.v[2 * i + 1] = frame.v_t();
            set.frames.push(frame);
        }
        factor_mass(model, &mut self.data, t).map_err(|e| SimError::at(t, e))?;
        fit_matrix(&mut set.minv_jt, nu, 2 * k);
        column.clear();
        column.resize(nu, 0.0);
        for col in 0..2 * k {
            column
                .iter_mut()
                .zip(set.jac.row(col).iter())
                .for_each(|(x, j)| *x = *j);
            solve_mass(&mut self.data, column).map_err(|e| SimError::at(t, e))?;
            set.minv_jt.column_mut(col).copy_from_slice(column);
        }
        // W = J M⁻¹ Jᵀ: nalgebra's product to the bit (fused multiply–adds from 6 × 6 on),
        // without `matrixmultiply`'s packing buffer and its choice of kernel at run time.
        product_into(&set.jac, &set.minv_jt, &mut set.w);
        Ok(())
    }

    /// Applies the impulses `x` (normal and tangential of each point of `set`) to `u`:
    /// `Δu = M⁻¹ Jᵀ x`; one ledger entry per point with a nonzero normal impulse.
    #[allow(clippy::too_many_arguments)]
    fn jump(
        &mut self,
        model: &Model,
        cause: ImpactCause,
        (set, scratch): (&PointSet, &mut JumpScratch),
        materials: &[Material],
        x: &DVector<Real>,
        modes: &[Mode],
        (t, q, u): (Real, &[Real], &mut [Real]),
        out: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        let energy_before =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        // Δu = M⁻¹ Jᵀ x and v⁺ = v⁻ + W x (`mul_to`: the products' own `gemm`).
        let delta_u = &mut scratch.delta_u;
        fit_vector(delta_u, set.minv_jt.nrows());
        set.minv_jt.mul_to(x, delta_u);
        for (ur, du) in u.iter_mut().zip(delta_u.iter()) {
            *ur += du;
        }
        let energy_after =
            energy(model, &mut self.data, t, q, u).map_err(|e| SimError::at(t, e))?;
        let v_plus = &mut scratch.v_plus;
        fit_vector(v_plus, set.v.len());
        set.w.mul_to(x, v_plus);
        for (vp, v) in v_plus.iter_mut().zip(set.v.iter()) {
            *vp += v; // `v + W x`: addition commutes
        }
        let (delta_u, v_plus) = (&scratch.delta_u, &scratch.v_plus);
        // An impulse below rounding of the largest one is no impact.
        let negligible = 1e-12 * x.amax();
        let start = out.len();
        let mut running = energy_before;
        for (i, &material) in materials.iter().enumerate() {
            let impulse = Impulse::new(x[2 * i], x[2 * i + 1]);
            if impulse.n.abs() <= negligible {
                continue;
            }
            let v_a = ContactVelocity::new(set.v[2 * i], set.v[2 * i + 1]);
            let v_s = ContactVelocity::new(v_plus[2 * i], v_plus[2 * i + 1]);
            let kind = match modes[i] {
                Mode::Slide(s) if s > 0.0 => CollisionType::ForwardSliding,
                Mode::Slide(_) => CollisionType::ReverseSliding,
                _ => CollisionType::Sticking,
            };
            let w = &set.w;
            let block = ImpactMatrix::new(
                w[(2 * i, 2 * i)],
                w[(2 * i, 2 * i + 1)],
                w[(2 * i + 1, 2 * i + 1)],
            );
            // A point that does not approach (|v_n| within rounding of 0) has no α: its
            // coefficients get v_n = 0, and α = v_t / 0 is left out of the ledger.
            let v_n = if v_a.n < -self.still { v_a.n } else { 0.0 };
            let coefficients =
                Coefficients::new(&block, material.mu, ContactVelocity::new(v_n, v_a.t));
            let phases = Phases::straight(v_a, kind, impulse, v_s);
            let end = *phases.end();
            let delta_e = energy_change(impulse, v_a, v_s);
            let before = running;
            running.kinetic += delta_e;
            let mut entry_delta_u = self.delta_u_buffer();
            entry_delta_u.extend_from_slice(delta_u.as_slice());
            out.push(ImpactEvent {
                index: 0,
                cause,
                t,
                frame: set.frames[i],
                material,
                w: block,
                v_a,
                outcome: Outcome {
                    law: Law::Newton,
                    kind,
                    case: coefficients.sign_case(),
                    coefficients,
                    impulse,
                    v_s,
                    phases,
                    delta_e,
                    work_n: end.work_n,
                    work_t: end.work_t,
                    mirrored: false,
                },
                delta_u: entry_delta_u,
                energy_before: before,
                energy_after: running,
                support: None,
            });
        }
        if let Some(last) = out[start..].last_mut() {
            last.energy_after = energy_after;
        }
        Ok(())
    }
}

/// Several contact points at one instant: their frames, `J` (2k × nu), `M⁻¹ Jᵀ` (nu × 2k),
/// `W = J M⁻¹ Jᵀ` (2k × 2k) and velocities `(v_n, v_t)` (2k).
#[derive(Clone, Debug, Default)]
struct PointSet {
    frames: Vec<ContactFrame>,
    jac: DMatrix<Real>,
    minv_jt: DMatrix<Real>,
    w: DMatrix<Real>,
    v: DVector<Real>,
}

/// The scratch of the impacts of several points ([`ImpactMap::apply_many`],
/// [`ImpactMap::close`]), kept between calls: sized to the most points met, then nothing
/// allocated but the ledger entries.
#[derive(Clone, Debug, Default)]
struct Many {
    /// The points: frames, rows, `W`, velocities.
    set: PointSet,
    /// One column of `M⁻¹ Jᵀ` being solved (nu).
    column: Vec<Real>,
    /// The generalized Newton law's complementarity problem: `b` (2k), the allowed modes
    /// (k) and its solutions.
    b: DVector<Real>,
    allowed: Vec<Allowed>,
    solutions: Vec<lcp::Solution>,
    /// The end of a rocking accumulation: the unknown rows of `W`, whether each point
    /// stops, the sliding friction per unit normal impulse of each point (k), `W_rr`, its
    /// right-hand side `−v_r⁻`, the solution `P_r` and its workspace, the impulses `x` (2k).
    rows: Vec<usize>,
    stops: Vec<bool>,
    friction: Vec<Real>,
    w_rr: DMatrix<Real>,
    rhs: DVector<Real>,
    p_r: DVector<Real>,
    ls: MinNorm,
    x: DVector<Real>,
    /// The modes and materials reported (k).
    modes: Vec<Mode>,
    materials: Vec<Material>,
    jump: JumpScratch,
}

/// The scratch of [`ImpactMap::jump`]: `Δu` (nu) and `v⁺` (2k).
#[derive(Clone, Debug, Default)]
struct JumpScratch {
    delta_u: DVector<Real>,
    v_plus: DVector<Real>,
}

/// The name of a contact pair, `<collider a>/<collider b>`.
pub fn pair_name(model: &Model, pair: PairId) -> String {
    let p = &model.pair_of(pair);
    let name = |c: crate::model::ColliderId| &model.colliders()[c.index()].name;
    format!("{}/{}", name(p.a), name(p.b))
}
