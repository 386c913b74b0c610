//! The contact problem of one Moreau–Jean step: the index set, `W = J M⁻¹ Jᵀ` of all its
//! contacts together, and the velocity-level problem with Newton's restitution and
//! Coulomb friction, solved exactly by enumeration ([`crate::lcp`]) for a few contacts and
//! by nonsmooth Gauss–Seidel ([`crate::pgs`]) for more.

use nalgebra::{DMatrix, DVector};

use crate::contact::{
    ContactFrame, FrameWorkspace, MAX_CONTACT_POINTS, ManifoldWorkspace, Tangent, contact_points,
    frame_at,
};
use crate::dynamics::solve_mass;
use crate::impact::{ContactVelocity, ImpactMatrix, Impulse};
use crate::lcp::{self, Allowed};
use crate::math::Real;
use crate::model::{Material, Model, PairId};
use crate::pgs::{self, PgsSettings, PgsStatus};
use crate::state::Data;

use super::super::{MaterialOverride, PairMap, SimError};

/// One contact of the index set in a step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Active {
    /// The pair.
    pub pair: PairId,
    /// Which of the pair's contact points ([`contact_points`]: 0 the closest one).
    pub point: usize,
    /// Its frame at the θ-point `(t_θ, q_θ)`, velocities at `u_k`.
    pub frame: ContactFrame,
    /// Its material after the overrides.
    pub material: Material,
    /// `v^k = J(q_θ) u_k + v_rem`: the velocity before the step, in `(n, t)` (m/s);
    /// `v_t^k ≥ 0` by the frame's orientation [P, Eq. (10)].
    pub v_k: ContactVelocity,
    /// `v_free = J u_free + v_rem` (m/s).
    pub v_free: ContactVelocity,
    /// `v^{k+1} = J u_{k+1} + v_rem` (m/s), after [`ContactProblem::end_velocities`].
    pub v_next: ContactVelocity,
    /// The impulse of the step `(P_n, P_t)` (N·s).
    pub impulse: Impulse,
}

/// Which solver solved a step's problem, and how it went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Solved {
    /// No contact in the index set.
    Nothing,
    /// The exact enumeration (the first of its solutions).
    Exact {
        /// Whether two of its solutions differ in their velocities (beyond rounding).
        ambiguous: bool,
        /// Whether it ran because Gauss–Seidel stopped unconverged.
        rescue: bool,
    },
    /// Nonsmooth Gauss–Seidel.
    Pgs {
        /// Its status.
        status: PgsStatus,
        /// Whether it ran because the enumeration found no solution.
        no_exact: bool,
    },
}

/// Scratch of the contact problem, grown to the largest index set seen (a model lists no
/// pairs: the index set comes from the broad phase).
pub(super) struct ContactProblem {
    nu: usize,
    /// The index set, in pair order, then point order.
    pub active: Vec<Active>,
    /// Scratch of the contact points of a pair.
    manifold: ManifoldWorkspace,
    /// `J_n` of each active contact, row `i` at `i·nu` (active contacts × nu).
    j_n: Vec<Real>,
    /// `J_t` of each active contact (same size).
    j_t: Vec<Real>,
    /// `M⁻¹ J_nᵀ` of each active contact (same size).
    x_n: Vec<Real>,
    /// `M⁻¹ J_tᵀ` of each active contact (same size).
    x_t: Vec<Real>,
    /// `A = W`, `2m × 2m`, column-major.
    a: Vec<Real>,
    /// `b = v_free + (e v_n^k, 0)` per contact (2m).
    b: Vec<Real>,
    /// The impulses `x = (P_n0, P_t0, …)` (2m).
    x: Vec<Real>,
    /// `μ` per contact (m).
    mu: Vec<Real>,
    /// The last impulse at each contact point of each pair, for the warm start of
    /// Gauss–Seidel (zero when the point was not in the previous index set).
    warm: PairMap<[Impulse; MAX_CONTACT_POINTS]>,
    /// Whether each pair was in the index set of the previous step.
    was_active: PairMap<bool>,
    /// The colliders' boxes of the broad phase.
    boxes: Vec<parry2d_f64::bounding_volume::Aabb>,
    /// The margin of the boxes (m): `1e-9` of the largest shape, so that rounding in the
    /// boxes cannot leave out a pair at a gap `≤ 0`.
    margin: Real,
    frame_ws: FrameWorkspace,
    /// Contacts up to which the problem is solved by enumeration.
    exact_up_to: usize,
    /// Contacts up to which the enumeration solves a problem Gauss–Seidel did not.
    rescue_up_to: usize,
    pgs: PgsSettings,
}

impl ContactProblem {
    /// Scratch for every pair of `model` (`A` grows to the largest index set seen, once).
    pub(super) fn new(
        model: &Model,
        (exact_up_to, rescue_up_to): (usize, usize),
        pgs: PgsSettings,
    ) -> Self {
        let nu = model.nu();
        let size = (model.colliders().iter())
            .map(|c| c.shape.compute_local_bounding_sphere().radius())
            .fold(0.0, Real::max);
        Self {
            nu,
            active: Vec::new(),
            manifold: ManifoldWorkspace::default(),
            j_n: Vec::new(),
            j_t: Vec::new(),
            x_n: Vec::new(),
            x_t: Vec::new(),
            a: Vec::new(),
            b: Vec::new(),
            x: Vec::new(),
            mu: Vec::new(),
            warm: PairMap::new([Impulse::default(); MAX_CONTACT_POINTS]),
            was_active: PairMap::new(false),
            boxes: Vec::new(),
            margin: (1e-9 * size).max(1e-300),
            frame_ws: FrameWorkspace::new(model),
            exact_up_to,
            rescue_up_to,
            pgs,
        }
    }

    /// Forgets the previous steps (a new run).
    pub(super) fn reset(&mut self) {
        self.active.clear();
        self.warm.fill([Impulse::default(); MAX_CONTACT_POINTS]);
        self.was_active.fill(false);
        self.boxes.clear();
    }

    /// Stage *index set*: the contact points ([`contact_points`]: the closest one, and the
    /// ends of flat features lying on the other shape) whose gap at the θ-point is closed,
    /// `g_i(q_θ) ≤ 0`, with their frames, `J_n`, `J_t` and velocities `vᵏ` (Moreau's
    /// midpoint rule for θ = ½). Requires the kinematics of `(t_θ, q_θ, u_k)` in `data`.
    /// Returns the number of pairs that entered the index set (had no point in the
    /// previous one).
    pub(super) fn index_set(
        &mut self,
        model: &Model,
        data: &Data,
        overrides: &MaterialOverride,
        t: Real,
    ) -> Result<u64, SimError> {
        let nu = self.nu;
        self.active.clear();
        let mut entered = 0;
        // The pairs at a gap ≤ 0 are among those whose boxes overlap (the broad phase); the
        // others leave the index set (no warm start, not active).
        let margin = self.margin;
        let boxes = &mut self.boxes;
        boxes.clear();
        for c in model.collider_ids() {
            let pose =
                crate::kinematics::collider_pose(model, data, c).map_err(|e| SimError::at(t, e))?;
            let aabb = model.colliders()[c.index()].shape.compute_aabb(&pose);
            boxes.push(parry2d_f64::bounding_volume::BoundingVolume::loosened(
                &aabb, margin,
            ));
        }
        let near = crate::contact::broad::overlapping_pairs(model, boxes);
        let (mut warm, mut was_active) = (
            PairMap::new([Impulse::default(); MAX_CONTACT_POINTS]),
            PairMap::new(false),
        );
        for pair in near {
            let k = pair.index();
            let points = contact_points(model, data, pair, 0.0, &mut self.manifold)
                .map_err(|e| SimError::at(t, e))?;
            let mut closed = [false; MAX_CONTACT_POINTS];
            for (point, contact) in points.iter().enumerate() {
                if contact.gap > 0.0 {
                    continue;
                }
                closed[point] = true;
                let slot = self.active.len();
                let rows = slot * nu..(slot + 1) * nu;
                for v in [&mut self.j_n, &mut self.j_t, &mut self.x_n, &mut self.x_t] {
                    if v.len() < rows.end {
                        v.resize(rows.end, 0.0);
                    }
                }
                let frame = frame_at(
                    model,
                    data,
                    pair,
                    *contact,
                    Tangent::AlongSlip,
                    &mut self.frame_ws,
                    &mut self.j_n[rows.clone()],
                    &mut self.j_t[rows],
                )
                .map_err(|e| SimError::at(t, e))?;
                self.active.push(Active {
                    pair,
                    point,
                    frame,
                    material: overrides.apply(model.pair_of(pair).material),
                    v_k: ContactVelocity::new(frame.v_n(), frame.v_t()),
                    v_free: ContactVelocity::default(),
                    v_next: ContactVelocity::default(),
                    impulse: Impulse::default(),
                });
            }
            let any = closed.iter().any(|&c| c);
            if any && !self.was_active[k] {
                entered += 1;
            }
            if any {
                was_active[k] = true;
                let mut kept = self.warm[k];
                for (warm, closed) in kept.iter_mut().zip(closed) {
                    if !closed {
                        *warm = Impulse::default();
                    }
                }
                warm[k] = kept;
            }
        }
        (self.warm, self.was_active) = (warm, was_active);
        Ok(entered)
    }

    /// Stage *Delassus*: `x_i = M⁻¹ J_iᵀ` through the Cholesky factor in `data`, the matrix
    /// `A = W = J M⁻¹ Jᵀ` of all the active contacts together (`2m × 2m`, [P, Eq. (20)]
    /// for each 2×2 block), the free contact velocities `v_free = J u_free + v_rem` and
    /// `b = v_free + (e v_n^k, 0)`, so that the problem reads `w = A P + b` with
    /// `w = v^{k+1} + (e v_n^k, 0)`.
    pub(super) fn assemble(
        &mut self,
        data: &mut Data,
        u_free: &[Real],
        t: Real,
    ) -> Result<(), SimError> {
        let (nu, m) = (self.nu, self.active.len());
        for i in 0..m {
            let rows = i * nu..(i + 1) * nu;
            self.x_n[rows.clone()].copy_from_slice(&self.j_n[rows.clone()]);
            self.x_t[rows.clone()].copy_from_slice(&self.j_t[rows.clone()]);
            solve_mass(data, &mut self.x_n[rows.clone()]).map_err(|e| SimError::at(t, e))?;
            solve_mass(data, &mut self.x_t[rows]).map_err(|e| SimError::at(t, e))?;
        }
        let dim = 2 * m;
        self.a.clear();
        self.a.resize(dim * dim, 0.0);
        let (j_n, j_t, x_n, x_t) = (&self.j_n, &self.j_t, &self.x_n, &self.x_t);
        // Row r of J (J_n of contact r/2 for even r, J_t for odd), or of (M⁻¹ Jᵀ)ᵀ.
        let row = |r: usize, inverse: bool| {
            let rows = (r / 2) * nu..(r / 2 + 1) * nu;
            match (r.is_multiple_of(2), inverse) {
                (true, false) => &j_n[rows],
                (false, false) => &j_t[rows],
                (true, true) => &x_n[rows],
                (false, true) => &x_t[rows],
            }
        };
        for c in 0..dim {
            for r in 0..dim {
                self.a[c * dim + r] = dot(row(r, false), row(c, true));
            }
        }
        self.b.clear();
        self.mu.clear();
        for (i, c) in self.active.iter_mut().enumerate() {
            let rem = c.frame.v_rem;
            let rows = i * nu..(i + 1) * nu;
            c.v_free = ContactVelocity::new(
                dot(&self.j_n[rows.clone()], u_free) + rem.dot(c.frame.n),
                dot(&self.j_t[rows], u_free) + rem.dot(c.frame.t),
            );
            self.b.push(c.v_free.n + c.material.e * c.v_k.n);
            self.b.push(c.v_free.t);
            self.mu.push(c.material.mu);
        }
        Ok(())
    }

    /// The 2×2 block of `W` of active contact `i` [P, Eq. (20)].
    pub(super) fn block(&self, i: usize) -> ImpactMatrix {
        let dim = 2 * self.active.len();
        let at = |r: usize, c: usize| self.a[c * dim + r];
        let (n, t) = (2 * i, 2 * i + 1);
        ImpactMatrix::new(at(n, n), 0.5 * (at(n, t) + at(t, n)), at(t, t))
    }

    /// Stage *solve*: the velocity-level problem `w = A P + b`,
    /// `0 ≤ w_n ⊥ P_n ≥ 0` (`w_n = v_n^{k+1} + e v_nᵏ`, Newton's restitution), Coulomb's
    /// `|P_t| ≤ μ P_n` with `P_t = −μ P_n sign(v_t^{k+1})` when the contact slips.
    ///
    /// Up to `exact_up_to` contacts: the exact enumeration (its first solution when there
    /// are several), Gauss–Seidel if it finds none. Beyond: Gauss–Seidel, warm-started
    /// from the points' last impulses; if it stops unconverged on at most `rescue_up_to`
    /// contacts, the enumeration, when it finds a solution. Writes each contact's
    /// `impulse`.
    pub(super) fn solve(&mut self) -> Solved {
        let m = self.active.len();
        if m == 0 {
            return Solved::Nothing;
        }
        self.x.clear();
        self.x.resize(2 * m, 0.0);
        let solved = if m <= self.exact_up_to {
            match self.solve_exact() {
                Some(ambiguous) => Solved::Exact {
                    ambiguous,
                    rescue: false,
                },
                None => Solved::Pgs {
                    status: self.solve_pgs(),
                    no_exact: true,
                },
            }
        } else {
            let status = self.solve_pgs();
            let rescued = (!status.converged() && m <= self.rescue_up_to)
                .then(|| self.solve_exact())
                .flatten();
            match rescued {
                Some(ambiguous) => Solved::Exact {
                    ambiguous,
                    rescue: true,
                },
                None => Solved::Pgs {
                    status,
                    no_exact: false,
                },
            }
        };
        for (i, c) in self.active.iter_mut().enumerate() {
            c.impulse = Impulse::new(self.x[2 * i], self.x[2 * i + 1]);
            self.warm[c.pair.index()][c.point] = c.impulse;
        }
        solved
    }

    /// Gauss–Seidel from the points' impulses of the previous step (zero where open).
    fn solve_pgs(&mut self) -> PgsStatus {
        for (i, c) in self.active.iter().enumerate() {
            let warm = self.warm[c.pair.index()][c.point];
            self.x[2 * i] = warm.n;
            self.x[2 * i + 1] = warm.t;
        }
        pgs::solve(&self.a, &self.b, &self.mu, &mut self.x, &self.pgs)
    }

    /// The exact enumeration: whether its solutions are ambiguous (differ in velocity),
    /// `None` if it finds none (then `x` is left as it was).
    fn solve_exact(&mut self) -> Option<bool> {
        let dim = 2 * self.active.len();
        let a = DMatrix::from_column_slice(dim, dim, &self.a);
        let b = DVector::from_column_slice(&self.b);
        let allowed: Vec<Allowed> = (self.mu.iter())
            .map(|&mu| Allowed {
                mu,
                open: true,
                slip: None,
            })
            .collect();
        let solutions = lcp::solve(&a, &b, &allowed).all;
        let first = solutions.first()?;
        let scale = b.amax().max(Real::MIN_POSITIVE);
        let ambiguous = (solutions.iter().skip(1)).any(|s| (&s.w - &first.w).amax() > 1e-8 * scale);
        self.x.copy_from_slice(first.x.as_slice());
        Some(ambiguous)
    }

    /// Stage *impulses*: `u += M⁻¹ Jᵀ P` [P, Eq. (16)] for every active contact.
    pub(super) fn apply(&self, u: &mut [Real]) {
        let nu = self.nu;
        for (i, c) in self.active.iter().enumerate() {
            let (p_n, p_t) = (c.impulse.n, c.impulse.t);
            let (x_n, x_t) = (
                &self.x_n[i * nu..(i + 1) * nu],
                &self.x_t[i * nu..(i + 1) * nu],
            );
            for ((u, a), b) in u.iter_mut().zip(x_n).zip(x_t) {
                *u += a * p_n + b * p_t;
            }
        }
    }

    /// `M⁻¹ J_iᵀ P_i`: the share of active contact `i` in the jump of `u` (nu).
    pub(super) fn delta_u(&self, i: usize) -> Vec<Real> {
        let nu = self.nu;
        let p = self.active[i].impulse;
        (self.x_n[i * nu..(i + 1) * nu].iter())
            .zip(&self.x_t[i * nu..(i + 1) * nu])
            .map(|(a, b)| a * p.n + b * p.t)
            .collect()
    }

    /// The contact velocities at the end of the step, `v^{k+1} = J u_{k+1} + v_rem`.
    pub(super) fn end_velocities(&mut self, u_next: &[Real]) {
        let nu = self.nu;
        for (i, c) in self.active.iter_mut().enumerate() {
            let rem = c.frame.v_rem;
            c.v_next = ContactVelocity::new(
                dot(&self.j_n[i * nu..(i + 1) * nu], u_next) + rem.dot(c.frame.n),
                dot(&self.j_t[i * nu..(i + 1) * nu], u_next) + rem.dot(c.frame.t),
            );
        }
    }

    /// The velocity scale of the step's problem, `max |b|` (m/s).
    pub(super) fn velocity_scale(&self) -> Real {
        self.b.iter().fold(0.0, |s: Real, v| s.max(v.abs()))
    }
}

fn dot(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
