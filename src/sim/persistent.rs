//! Persistent contact: closed contact points held by forces at the acceleration level,
//! with Coulomb friction, between impacts.
//!
//! A closed point `k` of a pair keeps its normal relative acceleration at zero, and if it
//! sticks its tangential one too:
//!
//! ```text
//! M u̇ = τ − h + Σ_k (J_n,kᵀ λ_n,k + J_t,kᵀ λ_t,k)
//! a_n,k = J_n,k u̇ + c_n,k = 0                       (closed)
//! a_t,k = J_t,k u̇ + c_t,k = 0, |λ_t,k| ≤ μ λ_n,k     (sticking)
//! λ_t,k = −μ s_k λ_n,k                               (sliding with slip s_k = ±1 along t)
//! ```
//!
//! with `J_n`, `J_t` the rows of the contact frame ([`crate::contact::frame_at`], tangent
//! `t = perp(n)`) and `c` the velocity-product parts of the contact accelerations. The
//! normal velocity of a point is `V_n(t, q, u) = n(q)·v^R(t, q, u)`, so
//! `a_n = dV_n/dt = J_n u̇ + c_n` with `c_n = ∂V_n/∂t + (∂V_n/∂q) u`, computed by a central
//! difference along the motion, `c_n ≈ [V_n(t+ε, q+εu, u) − V_n(t−ε, q−εu, u)] / (2ε)`
//! (the same for `c_t`): it holds the curvature of both surfaces and the turning of `n`
//! whatever the shapes. A vertex on a fixed half-space (a pendulum's tip, a block's corner
//! on the floor) has neither, and takes `c` exactly: `c_n = n·a_P`, `c_t = t·a_P`, with
//! `a_P` the acceleration of the material point at `u̇ = 0`. With `A = J M⁻¹ Jᵀ` and `b = J M⁻¹ (τ − h) + c`, the forces
//! solve the equations of the modes ([`crate::lcp::forces`]); the modes themselves come
//! from the complementarity problem `a = A λ + b` ([`crate::lcp::solutions`]: every
//! solution of a few points by enumeration, Lemke's one beyond), whose lack of solution or
//! multiple solutions is Painlevé's paradox.

use nalgebra::{DMatrix, DVector};
use parry2d_f64::shape::ShapeType;

use super::{AtTime, Scales, SimError};
use crate::contact::{
    ClosedVertex, ContactError, ContactFrame, FrameWorkspace, ManifoldWorkspace, PairContact,
    Tangent, contact_points_of, frame_of, relative_velocity_of,
};
use crate::dynamics::coordinate_rates;
use crate::kinematics::{
    point_acceleration, update_positions, update_velocities, velocity_product_accelerations,
};
use crate::lcp::{self, Allowed, Mode};
use crate::linalg::{copy_short, dot, fit_matrix, fit_vector};
use crate::math::{Pose, Real, Vec2, perp};
use crate::model::spatial::Twist;
use crate::model::{ContactPair, Model, PairId};
use crate::state::Data;

/// How a closed contact point holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hold {
    /// It does not slip.
    Stick,
    /// It slips in the direction `s = ±1` along its tangent `t = perp(n)`.
    Slide(Real),
}

impl Hold {
    /// The mode of the complementarity problem.
    pub fn mode(self) -> Mode {
        match self {
            Hold::Stick => Mode::Stick,
            Hold::Slide(s) => Mode::Slide(s),
        }
    }
}

/// A closed contact point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closed {
    /// The pair.
    pub pair: PairId,
    /// The point on the shape of the pair's collider `a`, in the frame of its body (m):
    /// which of the pair's (at most two) contact points this is.
    pub local: Vec2,
    /// How it holds.
    pub hold: Hold,
    /// A sliding point's slip stops when `s V_t ≤ −slip_margin` (m/s): zero for a point
    /// that was sliding when its mode was selected; for one that starts to slide from rest
    /// (`|V_t| ≤ v_slip`, the drift of a sticking point), its drift against `s` plus
    /// `0.1 v_slip`, so that neither that drift nor the rounding of a tangential
    /// acceleration that is zero at the start stops the slip at once (see `select_group`).
    pub slip_margin: Real,
    /// Its forces `(λ_n, λ_t)` in the selection that closed it (N): where the points are
    /// redundant (two capsule ends at one hinge on a floor) the forces of the modes are not
    /// unique, and the right-hand side takes those nearest the selection's, which met every
    /// condition; a split of least norm instead could pull at one point at once, whose
    /// lift-off event then came back at every selection (the 16-link chain stalled so at
    /// t = 1.9673 s).
    pub reference: (Real, Real),
}

/// One contact point at an instant: its frame and velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// The pair.
    pub pair: PairId,
    /// The point on `a` in the frame of `a`'s body (m).
    pub local: Vec2,
    /// Its frame, tangent `perp(n)`.
    pub frame: ContactFrame,
    /// Normal relative velocity `V_n = v^R·n` (m/s).
    pub v_n: Real,
    /// Tangential relative velocity `V_t = v^R·t` (m/s).
    pub v_t: Real,
}

/// The contact points of `pair` at the poses of `data`, with the point on `a` in its
/// body's frame, within `tolerance` (m).
pub fn pair_points(
    model: &Model,
    data: &Data,
    pair: PairId,
    tolerance: Real,
    ws: &mut ManifoldWorkspace,
) -> Result<arrayvec::ArrayVec<(PairContact, Vec2), 2>, SimError> {
    let p = resolve(model, data, pair)?;
    pair_points_of(model, data, (pair, &p), tolerance, ws)
}

/// The pair `pair` of the model (its colliders and material), or the error of an unknown
/// one at the time of `data`.
fn resolve(model: &Model, data: &Data, pair: PairId) -> Result<ContactPair, SimError> {
    (model.pair(pair))
        .ok_or(ContactError::UnknownPair { pair: pair.index() })
        .map_err(|e| e.at(data.time))
}

/// The outward normal `n` (world frame) of the half-space of pair `p` when its contact
/// points are vertices of a polygonal shape of a body (a segment, a box, a convex polygon
/// or a triangle: no rounded border) on a half-space of the world: parry's manifold of such
/// a pair holds vertices of `a` (material points of its body) and the fixed normal of `b`.
fn vertex_on_fixed_plane(model: &Model, p: &ContactPair) -> Option<Vec2> {
    let (ca, cb) = (
        &model.colliders()[p.a.index()],
        &model.colliders()[p.b.index()],
    );
    let polygonal = matches!(
        ca.shape.shape_type(),
        ShapeType::Segment | ShapeType::Cuboid | ShapeType::ConvexPolygon | ShapeType::Triangle
    );
    match (ca.body, cb.body, cb.shape.as_halfspace()) {
        (Some(_), None, Some(h)) if polygonal => Some(cb.pose.rotation * h.normal),
        _ => None,
    }
}

/// [`pair_points`] of a pair already resolved (`model.pair(pair)`).
fn pair_points_of(
    model: &Model,
    data: &Data,
    (pair, p): (PairId, &ContactPair),
    tolerance: Real,
    ws: &mut ManifoldWorkspace,
) -> Result<arrayvec::ArrayVec<(PairContact, Vec2), 2>, SimError> {
    let t = data.time;
    let points = contact_points_of(model, data, (pair, p), tolerance, ws).map_err(|e| e.at(t))?;
    let pose = body_pose_of_a(model, data, p);
    let mut out = arrayvec::ArrayVec::new();
    for c in points {
        out.push((c, pose.inverse_transform_point(c.point_a)));
    }
    Ok(out)
}

/// The pose of the body of the pair's collider `a` (the identity for an obstacle): the
/// frame of the closed points' `local`.
fn body_pose_of_a(model: &Model, data: &Data, p: &ContactPair) -> Pose {
    match model.colliders()[p.a.index()].body {
        Some(b) => data.body_pose[b.index()],
        None => Pose::IDENTITY,
    }
}

/// The results of the last evaluation of the closed points' constrained dynamics
/// ([`Persistent::accelerate`]), with the state it was at. It can be handed from one
/// [`Persistent`] to another of the same closed points
/// ([`Persistent::trade_evaluation`]): the event functions take the right-hand side's
/// evaluation at the end of a step (DOPRI5's last stage is the step's end state) instead
/// of solving the same forces again.
#[derive(Clone, Debug, Default)]
pub struct Evaluation {
    /// The time and `[q; u]` evaluated; `None` unless an evaluation completed.
    at: Option<Real>,
    qu: Vec<Real>,
    /// `A = J M⁻¹ Jᵀ = Yᵀ Y` (2k × 2k, symmetric).
    a: DMatrix<Real>,
    /// The forces `λ` (2k).
    lambda: DVector<Real>,
    /// The points.
    points: Vec<Point>,
    /// Whether it found every closed point.
    complete: bool,
}

impl Evaluation {
    /// Whether it is the evaluation of `(t, q, u)` for `k` closed points.
    fn is_at(&self, t: Real, q: &[Real], u: &[Real], k: usize) -> bool {
        self.at == Some(t)
            && self.lambda.len() == 2 * k
            && self.qu.len() == q.len() + u.len()
            && self.qu[..q.len()] == *q
            && self.qu[q.len()..] == *u
    }

    /// Forgets the state it was at.
    pub fn forget(&mut self) {
        self.at = None;
    }

    /// Gives it room for `k` closed points of a model with `n` coordinates and speeds, so
    /// that a [`Persistent`] that takes it in trade allocates nothing.
    pub fn fit(&mut self, k: usize, n: usize) {
        fit_matrix(&mut self.a, 2 * k, 2 * k);
        fit_vector(&mut self.lambda, 2 * k);
        self.points.reserve(k.saturating_sub(self.points.len()));
        self.qu.reserve(n.saturating_sub(self.qu.len()));
        self.at = None;
    }
}

/// Where [`Persistent::vertex_products`] takes the bodies' spatial accelerations at
/// `u̇ = 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[doc(hidden)]
pub enum Accel {
    /// From `data.body_accel`: `data` holds the forward dynamics of the state
    /// ([`crate::dynamics::forward_dynamics`], whose Newton–Euler pass at `u̇ = 0` wrote
    /// them), as [`Persistent::accelerate`] requires.
    InData,
    /// [`velocity_product_accelerations`] of the kinematics in `data`.
    Compute,
}

/// Scratch and results of the constrained dynamics of a set of closed points.
pub struct Persistent {
    /// The closed points.
    closed: Vec<Closed>,
    /// Coefficients of friction of the closed points.
    mu: Vec<Real>,
    scales: Scales,
    /// Kinematics at the perturbed states of the central differences.
    data_fd: Data,
    /// Scratch of the point evaluations.
    eval: PointScratch,
    /// The perturbed coordinates of the central differences.
    q_fd: Vec<Real>,
    /// The coordinate rates `q̇ = A u + b` the differences move along.
    qdot_fd: Vec<Real>,
    /// The velocities `(v_n, v_t)` of each closed point at the four shifts of the
    /// differences.
    v_fd: Vec<[(Real, Real); 4]>,
    /// The pair of each closed point, looked up once per set of closed points
    /// ([`Self::resolve_pairs`]).
    pairs: Vec<ContactPair>,
    /// The normals `n` (world frame) of the half-spaces of closed points that are vertices
    /// on them ([`vertex_on_fixed_plane`]), up to the first that is not.
    #[doc(hidden)]
    pub planes: Vec<Vec2>,
    /// The vertex (in its shape's frame) that each closed point is, where it is one of a
    /// polygonal shape on a half-space ([`ClosedVertex::of`]): its contact is computed
    /// alone ([`PointScratch::point`]); `None` for the others, which query the pair's
    /// points.
    closed_vertices: Vec<Option<ClosedVertex>>,
    /// Whether `pairs`, `planes`, `closed_vertices` and `vertices` are those of `closed`
    /// (`set` forgets them).
    resolved: bool,
    /// Whether every closed point is a vertex on a half-space of the world, in a holonomic
    /// model with no prescribed motion: its velocity products are exact
    /// ([`Self::vertex_products`]).
    vertices: bool,
    /// The spatial accelerations of the bodies at `u̇ = 0` `[nbody]` (rad/s², m/s²).
    accel: Vec<Twist>,
    /// Whether vertices on fixed half-spaces take their exact velocity products
    /// ([`Self::vertex_products`]; the default) or the differences like every point.
    exact_products: bool,
    /// One column of `Y`, or `Y λ` (nu).
    column: Vec<Real>,
    /// The velocity-product terms `c` (2k).
    #[doc(hidden)]
    pub c: DVector<Real>,
    /// `J` (2k × nu): rows n, t of each closed point.
    jac: DMatrix<Real>,
    /// `Y = F⁻¹ Jᵀ` (nu × 2k) for the factor `M = F Fᵀ` of the mass matrix
    /// ([`crate::dynamics::MassFactor::solve_factor_in_place`]).
    y: DMatrix<Real>,
    /// `b = J u̇_free + c` (2k).
    b: DVector<Real>,
    /// The last evaluation: `A`, the forces, the points.
    ev: Evaluation,
    /// The complementarity solver of the mode selection.
    lcp: lcp::Solver,
    /// The linear system of the closed points' modes, and its modes and reference forces.
    system: lcp::ModeSystem,
    modes: Vec<Mode>,
    reference: Vec<Real>,
    /// The buffers of the next mode selection ([`Self::select`], given back by
    /// [`Self::recycle_selection`]).
    selection: Selection,
    /// The least and largest values of each closed point's force functions over the
    /// evaluations since the last [`Self::clear_bounds`] (see [`Self::force_functions`];
    /// the slip velocity `s V_t + margin` in place of a sliding point's friction margin):
    /// over the stages of a step, what the event location needs to know that a function
    /// cannot reach zero in it.
    bounds: Vec<[(Real, Real); 3]>,
}

impl Persistent {
    /// Scratch for `model`, no closed point.
    pub fn new(model: &Model, scales: Scales) -> Self {
        let nu = model.nu();
        Self {
            closed: Vec::new(),
            mu: Vec::new(),
            scales,
            data_fd: Data::new(model),
            eval: PointScratch::new(model),
            q_fd: vec![0.0; model.nq()],
            qdot_fd: vec![0.0; model.nq()],
            v_fd: Vec::new(),
            pairs: Vec::new(),
            planes: Vec::new(),
            closed_vertices: Vec::new(),
            resolved: false,
            vertices: false,
            accel: vec![Twist::ZERO; model.bodies().len()],
            exact_products: true,
            column: vec![0.0; nu],
            c: DVector::zeros(0),
            jac: DMatrix::zeros(0, nu),
            y: DMatrix::zeros(nu, 0),
            b: DVector::zeros(0),
            ev: Evaluation {
                complete: true,
                ..Evaluation::default()
            },
            lcp: lcp::Solver::new(),
            system: lcp::ModeSystem::new(),
            modes: Vec::new(),
            reference: Vec::new(),
            selection: Selection::default(),
            bounds: Vec::new(),
        }
    }

    /// The closed points.
    pub fn closed(&self) -> &[Closed] {
        &self.closed
    }

    /// Replaces the closed points (`mu` from their pairs, after overrides): see
    /// [`Self::set_from`].
    pub fn set(&mut self, closed: Vec<Closed>, mu: Vec<Real>) {
        self.set_from(&closed, &mu);
    }

    /// Replaces the closed points, copied into the kept buffers (`mu` from their pairs,
    /// after overrides): no allocation once they have held the most closed points (a mode
    /// selection's candidates among them).
    pub fn set_from(&mut self, closed: &[Closed], mu: &[Real]) {
        self.closed.clear();
        self.closed.extend_from_slice(closed);
        self.mu.clear();
        self.mu.extend_from_slice(mu);
        self.fit_closed();
    }

    /// The coefficients of friction of the closed points, in order.
    pub fn mus(&self) -> &[Real] {
        &self.mu
    }

    /// The buffers of the closed points' rows, `A`, `b`, `c` and forces fitted to them and
    /// zeroed (their storage kept: [`fit_matrix`]), the last evaluation and the bounds
    /// forgotten.
    fn fit_closed(&mut self) {
        let (k, nu) = (self.closed.len(), self.column.len());
        fit_matrix(&mut self.jac, 2 * k, nu);
        self.jac.fill(0.0);
        fit_matrix(&mut self.y, nu, 2 * k);
        self.y.fill(0.0);
        fit_vector(&mut self.b, 2 * k);
        self.b.fill(0.0);
        fit_vector(&mut self.c, 2 * k);
        self.c.fill(0.0);
        fit_matrix(&mut self.ev.a, 2 * k, 2 * k);
        self.ev.a.fill(0.0);
        fit_vector(&mut self.ev.lambda, 2 * k);
        self.ev.lambda.fill(0.0);
        self.ev.points.clear();
        self.ev.at = None;
        self.resolved = false;
        self.clear_bounds();
    }

    /// Looks up the pair of each closed point, and whether they are all vertices on
    /// half-spaces of the world (see `vertices`): once per set of closed points, not at
    /// every right-hand side. `data` gives the time of an error.
    #[inline]
    fn resolve_pairs(&mut self, model: &Model, data: &Data) -> Result<(), SimError> {
        if self.resolved {
            return Ok(());
        }
        self.resolve_pairs_now(model, data)
    }

    /// [`Self::resolve_pairs`] when they are not resolved yet: out of line, so that the
    /// check at every right-hand side costs a comparison.
    #[inline(never)]
    fn resolve_pairs_now(&mut self, model: &Model, data: &Data) -> Result<(), SimError> {
        self.pairs.clear();
        for c in &self.closed {
            self.pairs.push(resolve(model, data, c.pair)?);
        }
        self.planes.clear();
        (self.planes).extend((self.pairs.iter()).map_while(|p| vertex_on_fixed_plane(model, p)));
        self.closed_vertices.clear();
        for (c, p) in self.closed.iter().zip(&self.pairs) {
            // The closed point in the frame of its shape: within 1e-9 L of a vertex that
            // stands 1e-6 L clear of the others (`local` came from that vertex, to rounding).
            let l = self.scales.length;
            let vertex = ClosedVertex::of(model, p, c.local, 1e-9 * l, 1e-6 * l);
            self.closed_vertices.push(vertex);
        }
        let prescribed = model.joints().iter().any(|j| j.drive.is_some());
        self.vertices =
            self.planes.len() == self.closed.len() && model.is_holonomic() && !prescribed;
        self.resolved = true;
        Ok(())
    }

    /// The pair of closed point `i`, looked up once per set of closed points. `data` gives
    /// the time of an error.
    pub fn closed_pair(
        &mut self,
        model: &Model,
        data: &Data,
        i: usize,
    ) -> Result<ContactPair, SimError> {
        self.resolve_pairs(model, data)?;
        Ok(self.pairs[i])
    }

    /// Gives vertices on fixed half-spaces their exact velocity products (the default) or,
    /// with `false`, the central differences of every other point (the oracle of the
    /// tests).
    pub fn set_exact_products(&mut self, on: bool) {
        self.exact_products = on;
    }

    /// Forgets the bounds of the force functions (before a step).
    pub fn clear_bounds(&mut self) {
        self.bounds.clear();
        (self.bounds).resize(self.closed.len(), [(Real::INFINITY, Real::NEG_INFINITY); 3]);
    }

    /// The least and largest values `(lo, hi)` of each closed point's
    /// [`Self::force_functions`] over the evaluations since the last
    /// [`Self::clear_bounds`] (`lo > hi` where there was none).
    pub fn bounds(&self) -> &[[(Real, Real); 3]] {
        &self.bounds
    }

    /// The event functions of closed point `i` that its forces give, at the last
    /// evaluation ([`crate::sim::gaps::slot`] `1 + 3j`, `2 + 3j`, `3 + 3j`): `λ_n` (N), the
    /// friction margin `μ λ_n − |λ_t|` of a sticking point (N; NaN for a sliding one, whose
    /// function there is its slip velocity), and the Painlevé coefficient capped at the
    /// scene's length (1/kg).
    #[inline]
    pub fn force_functions(&self, i: usize) -> [Real; 3] {
        let (lambda_n, lambda_t) = self.force(i);
        let margin = match self.closed[i].hold {
            Hold::Stick => self.mu[i] * lambda_n - lambda_t.abs(),
            Hold::Slide(_) => Real::NAN,
        };
        [lambda_n, margin, self.painleve(i).min(self.scales.length)]
    }

    /// The velocity-product parts `c = (c_n, c_t)` of the accelerations of every closed
    /// point, into `self.c`: the derivative of each point's velocities along the motion
    /// `(q + s u, t + s)` at fixed `u`, by Richardson's extrapolation of central
    /// differences,
    ///
    /// ```text
    /// D(ε) = (v(+ε) − v(−ε)) / 2ε,   c = (4 D(ε) − D(2ε)) / 3   (error O(ε⁴))
    /// ```
    ///
    /// with `ε = 10⁻³ L / v_ref` (the scene's length and speed scales). The step is large
    /// on purpose: the velocities carry the rounding of the positions (`≈ 1e-16 |x|`), which
    /// a difference divides by `ε`; with `ε = 10⁻⁶ L / v_ref` and a plain central
    /// difference, that noise grew with the distance from the origin until it dominated the
    /// integrator's error estimate (the rimless wheel, 740 m down its slope after 1000 s,
    /// took 7 times the steps per second of its first 100 s).
    ///
    /// Four kinematics passes in all, each shared by every point (one per point and shift
    /// before: 44 % of the 32-link chain lying on the floor, with ~35 closed points; the
    /// same numbers). When every closed point is a vertex on a half-space of the world and
    /// the model is holonomic with no prescribed motion, none: [`Self::vertex_products`]
    /// gives `c` exactly.
    #[doc(hidden)]
    #[inline]
    pub fn velocity_products(
        &mut self,
        model: &Model,
        data: &Data,
        (t, q, u): (Real, &[Real], &[Real]),
        accel: Accel,
    ) -> Result<(), SimError> {
        let eps = 1e-3 * self.scales.length / self.scales.speed;
        let k = self.closed.len();
        // Each closed point's pair looked up once.
        self.resolve_pairs(model, data)?;
        if self.exact_products && self.vertices {
            self.vertex_products(model, data, accel);
            return Ok(());
        }
        // v at s = +ε, −ε, +2ε, −2ε, of each point.
        self.v_fd.clear();
        self.v_fd.resize(k, [(0.0, 0.0); 4]);
        if model.is_holonomic() {
            self.qdot_fd.copy_from_slice(u);
        } else {
            update_positions(model, &mut self.data_fd, t, q).map_err(|e| e.at(t))?;
            update_velocities(model, &mut self.data_fd, u).map_err(|e| e.at(t))?;
            coordinate_rates(model, &self.data_fd, u, &mut self.qdot_fd);
        }
        for (shift, s) in [eps, -eps, 2.0 * eps, -2.0 * eps].into_iter().enumerate() {
            for ((qf, qi), qd) in self.q_fd.iter_mut().zip(q).zip(&self.qdot_fd) {
                *qf = qi + s * qd;
            }
            let ts = t + s;
            update_positions(model, &mut self.data_fd, ts, &self.q_fd).map_err(|e| e.at(t))?;
            update_velocities(model, &mut self.data_fd, u).map_err(|e| e.at(t))?;
            for i in 0..k {
                let Closed { pair, local, .. } = self.closed[i];
                self.v_fd[i][shift] = self
                    .eval
                    .velocities_of(
                        model,
                        &self.data_fd,
                        (pair, &self.pairs[i]),
                        local,
                        self.scales.length,
                    )?
                    .ok_or_else(|| SimError::Contact {
                        t,
                        message: format!("closed contact point of pair #{} lost", pair.index()),
                    })?;
            }
        }
        let richardson = |d1: Real, d2: Real| (4.0 * d1 - d2) / 3.0;
        for (i, v) in self.v_fd.iter().enumerate() {
            self.c[2 * i] = richardson(
                (v[0].0 - v[1].0) / (2.0 * eps),
                (v[2].0 - v[3].0) / (4.0 * eps),
            );
            self.c[2 * i + 1] = richardson(
                (v[0].1 - v[1].1) / (2.0 * eps),
                (v[2].1 - v[3].1) / (4.0 * eps),
            );
        }
        Ok(())
    }

    /// The velocity-product parts `c` of closed points that are vertices of bodies on
    /// half-spaces of the world (`self.planes`, their normals `n`), exactly, into `self.c`:
    /// the vertex `P` is a material point of its body and `n` is fixed, so that
    /// `V_n = n·v_P`, `V_t = perp(n)·v_P` and, along the motion at fixed `u` (a holonomic
    /// model; with no prescribed motion, whose `q̈_p(t)` the test below does not cover),
    ///
    /// ```text
    /// c_n = n·a_P,   c_t = perp(n)·a_P,   a_P = A.v + A.ω perp(P) + ω perp(v_P)
    /// ```
    ///
    /// with `A` the body's spatial acceleration at `u̇ = 0`
    /// ([`crate::kinematics::velocity_product_accelerations`], [`point_acceleration`]).
    /// The same numbers as the differences of [`Self::velocity_products`] to their error
    /// (the test `vertex_products_agree_with_the_differences`), without their four
    /// kinematics passes and contact queries. `data` holds the kinematics of the state;
    /// with [`Accel::InData`], the forward dynamics of the state too, whose Newton–Euler
    /// pass at `u̇ = 0` left those very accelerations in `data.body_accel` (the same
    /// operations: the test `forward_dynamics_leaves_the_velocity_product_accelerations`).
    #[inline]
    fn vertex_products(&mut self, model: &Model, data: &Data, accel: Accel) {
        let accel = match accel {
            Accel::InData => &data.body_accel[..],
            Accel::Compute => {
                velocity_product_accelerations(model, data, &mut self.accel);
                &self.accel[..]
            }
        };
        for (i, (c, n)) in self.closed.iter().zip(&self.planes).enumerate() {
            let Some(body) = model.colliders()[self.pairs[i].a.index()].body else {
                continue; // not eligible (`vertex_on_fixed_plane`)
            };
            let p = data.body_pose[body.index()].transform_point(c.local);
            let a = point_acceleration(data, body, p, accel[body.index()]);
            self.c[2 * i] = n.dot(a);
            self.c[2 * i + 1] = perp(*n).dot(a);
        }
    }

    /// The rows, `A`, `b` of the closed points at `(t, q, u)`. `data` holds the forward
    /// dynamics of that state (`M` factored, `u̇_free` in `data.udot`).
    fn assemble(
        &mut self,
        model: &Model,
        data: &mut Data,
        (t, q, u): (Real, &[Real], &[Real]),
        accel: Accel,
    ) -> Result<(), SimError> {
        let k = self.closed.len();
        let ev = &mut self.ev;
        ev.at = None;
        fit_matrix(&mut ev.a, 2 * k, 2 * k);
        fit_vector(&mut ev.lambda, 2 * k);
        ev.points.clear();
        ev.complete = true;
        self.resolve_pairs(model, data)?;
        for i in 0..k {
            let Closed { pair, local, .. } = self.closed[i];
            let at = (pair, &self.pairs[i]);
            let vertex = self.closed_vertices[i];
            match (self.eval).point(model, data, at, (local, vertex), self.scales.length)? {
                Some(p) if k == 1 => {
                    // One point: `Jᵀ` is `[J_n J_t]`, the two columns of `Y` before their
                    // solve; `J` itself is not stored (see below).
                    let nu = self.column.len();
                    let ys = self.y.as_mut_slice();
                    copy_short(&mut ys[..nu], &self.eval.j_n);
                    copy_short(&mut ys[nu..2 * nu], &self.eval.j_t);
                    self.ev.points.push(p);
                }
                Some(p) => {
                    // Rows 2i, 2i + 1 of the column-major `J` (2k × nu).
                    let jac = self.jac.as_mut_slice();
                    let rows = self.eval.j_n.iter().zip(&self.eval.j_t);
                    for (r, (&jn, &jt)) in rows.enumerate() {
                        jac[2 * i + 2 * k * r] = jn;
                        jac[2 * i + 1 + 2 * k * r] = jt;
                    }
                    self.ev.points.push(p);
                }
                None => {
                    self.ev.complete = false;
                    return Ok(());
                }
            }
        }
        self.velocity_products(model, data, (t, q, u), accel)?;
        if k == 1 {
            return self.assemble_one(data, t);
        }
        // Y = F⁻¹ Jᵀ column by column, with the factor M = F Fᵀ; A = J M⁻¹ Jᵀ = Yᵀ Y, one
        // triangle of dot products mirrored; b = J u̇_free + c.
        // On the column-major storages: `J[(i, r)]` is `jac[i + 2k r]`, column `i` of `Y`
        // is `y[nu i..nu (i + 1)]`.
        let (n2, nu) = (2 * k, self.column.len());
        let jac = self.jac.as_slice();
        let ys = self.y.as_mut_slice();
        for col in 0..n2 {
            let y = &mut ys[nu * col..nu * (col + 1)];
            for (r, x) in y.iter_mut().enumerate() {
                *x = jac[col + n2 * r];
            }
            (data.mass_factor)
                .solve_factor_in_place(y)
                .map_err(|e| e.at(t))?;
        }
        let (ys, a) = (self.y.as_slice(), self.ev.a.as_mut_slice());
        for i in 0..n2 {
            let yi = &ys[nu * i..nu * (i + 1)];
            for j in 0..=i {
                let v = dot(yi, &ys[nu * j..nu * (j + 1)]);
                a[i + n2 * j] = v;
                a[j + n2 * i] = v;
            }
        }
        // b = c + J u̇_free in the order of nalgebra's `gemv` with `α = β = 1` (the same
        // numbers): `b ← J[:, 0] u̇₀ + b`, then each next column likewise.
        let (b, c, udot) = (
            self.b.as_mut_slice(),
            self.c.as_slice(),
            data.udot.as_slice(),
        );
        b.copy_from_slice(c);
        let b = &mut b[..n2];
        for (r, &ud) in udot.iter().enumerate() {
            let col = &jac[n2 * r..n2 * (r + 1)];
            for i in 0..n2 {
                b[i] += col[i] * ud; // `J[(i, r)] u̇_r + b_i`: addition commutes
            }
        }
        Ok(())
    }

    /// The end of [`Self::assemble`] for one closed point, whose rows `J_n`, `J_t` are the
    /// columns of `self.y`: `Y = F⁻¹ Jᵀ`, `A = Yᵀ Y` and `b = J u̇_free + c` (the point's
    /// accelerations `J u̇ + c = A λ + b`), the same operations in the same order as the
    /// general case (the same numbers) on fixed indices: the common case of a body sliding
    /// or sticking at one point.
    fn assemble_one(&mut self, data: &mut Data, t: Real) -> Result<(), SimError> {
        let nu = self.column.len();
        let (y_n, y_t) = self.y.as_mut_slice().split_at_mut(nu);
        let factor = &mut data.mass_factor;
        factor.solve_factor_in_place(y_n).map_err(|e| e.at(t))?;
        factor.solve_factor_in_place(y_t).map_err(|e| e.at(t))?;
        let (y_n, y_t) = (&*y_n, &y_t[..nu]);
        let (a_nn, a_tn, a_tt) = (dot(y_n, y_n), dot(y_t, y_n), dot(y_t, y_t));
        let a = self.ev.a.as_mut_slice();
        a[..4].copy_from_slice(&[a_nn, a_tn, a_tn, a_tt]);
        // b = c + J u̇_free, each row summed over the speeds in order, as the general case.
        let (b, c) = (self.b.as_mut_slice(), self.c.as_slice());
        let (mut b_n, mut b_t) = (c[0], c[1]);
        let udot = data.udot.as_slice();
        for ((&ud, &jn), &jt) in udot.iter().zip(&self.eval.j_n).zip(&self.eval.j_t) {
            b_n += jn * ud;
            b_t += jt * ud;
        }
        b[..2].copy_from_slice(&[b_n, b_t]);
        Ok(())
    }

    /// The constrained accelerations at `(t, q, u)`: solves for the forces of the closed
    /// points in their modes and adds `M⁻¹ Fᵀ λ` to `data.udot`, which holds the free
    /// accelerations (after `forward_dynamics` of the same state; its bodies' accelerations
    /// at `u̇ = 0` in `data.body_accel` give the velocity products of closed vertices).
    pub fn accelerate(
        &mut self,
        model: &Model,
        data: &mut Data,
        state: (Real, &[Real], &[Real]),
    ) -> Result<(), SimError> {
        if self.closed.is_empty() {
            return Ok(());
        }
        let t = state.0;
        // `data` holds the forward dynamics of `state` (the precondition).
        self.assemble(model, data, state, Accel::InData)?;
        if !self.ev.complete {
            return Err(SimError::Contact {
                t,
                message: "a closed contact point has no contact any more".to_owned(),
            });
        }
        // One point (the common case): its mode and reference on the stack.
        let (one_mode, one_reference);
        let (modes, reference) = match self.closed.as_slice() {
            [c] => {
                one_mode = [c.hold.mode()];
                one_reference = [c.reference.0, c.reference.1];
                (&one_mode[..], &one_reference[..])
            }
            _ => {
                self.modes.clear();
                self.modes.extend(self.closed.iter().map(|c| c.hold.mode()));
                self.reference.clear();
                (self.reference).extend(
                    self.closed
                        .iter()
                        .flat_map(|c| [c.reference.0, c.reference.1]),
                );
                (&self.modes[..], &self.reference[..])
            }
        };
        let (x, _) = (self.system)
            .forces_near(&self.ev.a, &self.b, &self.mu, modes, reference)
            .ok_or_else(|| SimError::Contact {
                t,
                message: "the forces of the closed contact points have no solution".to_owned(),
            })?;
        copy_short(self.ev.lambda.as_mut_slice(), x.as_slice());
        // u̇ += M⁻¹ Jᵀ λ = F⁻ᵀ (Y λ); Y λ summed column by column in the order of
        // nalgebra's `gemv` (the same numbers), without its generic machinery.
        let (nu, lambda) = (self.column.len(), self.ev.lambda.as_slice());
        let ys = self.y.as_slice();
        if let &[l_n, l_t] = lambda {
            // One point: the two columns `Y_n`, `Y_t`, in the same order.
            let (y_n, y_t) = ys[..2 * nu].split_at(nu);
            for ((out, &yn), &yt) in self.column.iter_mut().zip(y_n).zip(y_t) {
                *out = yn * l_n + yt * l_t;
            }
        } else {
            for (r, out) in self.column.iter_mut().enumerate() {
                let mut v = ys[r] * lambda[0];
                for (j, l) in lambda.iter().enumerate().skip(1) {
                    v += ys[j * nu + r] * l;
                }
                *out = v;
            }
        }
        (data.mass_factor)
            .solve_factor_transpose_in_place(&mut self.column)
            .map_err(|e| e.at(t))?;
        for (a, d) in data.udot.as_mut_slice().iter_mut().zip(&self.column) {
            *a += d;
        }
        for i in 0..self.closed.len() {
            let mut f = self.force_functions(i);
            if let Hold::Slide(s) = self.closed[i].hold {
                // A sliding point's second function is its slip velocity (see `gaps::slot`).
                f[1] = (self.ev.points.get(i))
                    .map_or(Real::NAN, |p| s * p.v_t + self.closed[i].slip_margin);
            }
            for (b, v) in self.bounds[i].iter_mut().zip(f) {
                *b = (b.0.min(v), b.1.max(v));
            }
        }
        let (_, q, u) = state;
        let qu = &mut self.ev.qu;
        if qu.len() == q.len() + u.len() {
            let (to_q, to_u) = qu.split_at_mut(q.len());
            copy_short(to_q, q);
            copy_short(to_u, u);
        } else {
            qu.clear();
            qu.extend_from_slice(q);
            qu.extend_from_slice(u);
        }
        self.ev.at = Some(t);
        Ok(())
    }

    /// Exchanges the last evaluation with `other` (of the same closed points, or to be
    /// forgotten): see [`Evaluation`].
    pub fn trade_evaluation(&mut self, other: &mut Evaluation) {
        std::mem::swap(&mut self.ev, other);
    }

    /// Forgets the state of the last evaluation (its numbers are no longer to be taken).
    pub fn forget_evaluation(&mut self) {
        self.ev.forget();
    }

    /// Whether `ev` is an evaluation of these closed points at `(t, q, u)` (it must come
    /// from a [`Persistent`] with the same closed points).
    pub fn can_take(&self, ev: &Evaluation, (t, q, u): (Real, &[Real], &[Real])) -> bool {
        ev.is_at(t, q, u, self.closed.len())
    }

    /// Drops the slip margin of each point that started to slide from rest and has got
    /// going (`s V_t > 2 · margin` at the last evaluation): from then on its slip stops at
    /// `V_t = 0`, on time. The function drops from `s V_t + margin` to `s V_t`, both
    /// positive: no crossing is made. Call between steps.
    pub fn release_margins(&mut self) {
        if self.ev.points.len() != self.closed.len() {
            return;
        }
        for (c, p) in self.closed.iter_mut().zip(&self.ev.points) {
            if let Hold::Slide(s) = c.hold
                && c.slip_margin > 0.0
                && s * p.v_t > 2.0 * c.slip_margin
            {
                c.slip_margin = 0.0;
            }
        }
    }

    /// The coefficient of friction of closed point `i`.
    pub fn mu(&self, i: usize) -> Real {
        self.mu[i]
    }

    /// The forces `(λ_n, λ_t)` of closed point `i` at the last evaluation (N).
    #[inline]
    pub fn force(&self, i: usize) -> (Real, Real) {
        let lambda = self.ev.lambda.as_slice();
        (lambda[2 * i], lambda[2 * i + 1])
    }

    /// The points of the last evaluation.
    pub fn points(&self) -> &[Point] {
        &self.ev.points
    }

    /// The Painlevé coefficient of closed point `i` when it slides: its own normal
    /// acceleration per unit normal force with the friction of its slip,
    /// `A_nn − μ s A_nt` (`h` of [P, Eq. (35)] for `s = +1`, `q` for `s = −1`, in the frame
    /// of its slip). Non-positive: sliding cannot be held by a pushing force.
    #[inline]
    pub fn painleve(&self, i: usize) -> Real {
        match self.closed[i].hold {
            Hold::Slide(s) => {
                // `A[(2i, 2i)]`, `A[(2i, 2i + 1)]` of the column-major storage.
                let (a, n2) = (self.ev.a.as_slice(), self.ev.a.nrows());
                a[2 * i + n2 * 2 * i] - self.mu[i] * s * a[2 * i + n2 * (2 * i + 1)]
            }
            Hold::Stick => Real::INFINITY,
        }
    }

    /// The power of the contact forces on the system, `Σ λ_n V_n + λ_t V_t` (W).
    pub fn power(&self) -> Real {
        (self.ev.points.iter().enumerate())
            .map(|(i, p)| self.ev.lambda[2 * i] * p.v_n + self.ev.lambda[2 * i + 1] * p.v_t)
            .sum()
    }

    /// Selects the modes of the candidate points at `(t, q, u)` (`data` holds the forward
    /// dynamics of that state), by the complementarity problem at the acceleration level. A
    /// point slipping faster than `v_slip` keeps its slip direction; a candidate with a
    /// given slip takes it.
    ///
    /// The selection is written into the buffers of the one handed back by
    /// [`Self::recycle_selection`] (none allocated once they have held the largest).
    pub fn select(
        &mut self,
        model: &Model,
        data: &mut Data,
        state: (Real, &[Real], &[Real]),
        candidates: &[Candidate],
        v_slip: Real,
    ) -> Result<Selection, SimError> {
        // Assemble with provisional modes (the rows do not depend on them).
        self.closed.clear();
        self.closed.extend(candidates.iter().map(|c| Closed {
            pair: c.pair,
            local: c.local,
            hold: Hold::Stick,
            slip_margin: 0.0,
            reference: (0.0, 0.0),
        }));
        self.mu.clear();
        self.mu.extend(candidates.iter().map(|c| c.mu));
        self.fit_closed();
        self.assemble(model, data, state, Accel::Compute)?;
        let mut sel = std::mem::take(&mut self.selection);
        sel.allowed.clear();
        (sel.allowed).extend((self.ev.points.iter().zip(candidates)).map(|(p, c)| {
            Allowed {
                mu: c.mu,
                open: true,
                slip: c
                    .slip
                    .or_else(|| (p.v_t.abs() > v_slip).then(|| p.v_t.signum())),
            }
        }));
        // No solution (Lemke's ray) is Painlevé's inconsistency for the caller to resolve.
        let (a, b) = (&self.ev.a, &self.b);
        match lcp::solutions_into(&mut self.lcp, a, b, &sel.allowed, &mut sel.solutions) {
            Ok(()) | Err(lcp::LcpError::NoSolution { .. }) => {}
            Err(e) => {
                return Err(SimError::Contact {
                    t: state.0,
                    message: format!("the contact modes of {} points: {e}", candidates.len()),
                });
            }
        }
        sel.painleve.clear();
        (sel.painleve).extend((0..candidates.len()).map(|i| match sel.allowed[i].slip {
            Some(s) => a[(2 * i, 2 * i)] - sel.allowed[i].mu * s * a[(2 * i, 2 * i + 1)],
            None => Real::INFINITY,
        }));
        fit_matrix(&mut sel.a, a.nrows(), a.ncols());
        sel.a.copy_from(a);
        fit_vector(&mut sel.b, b.len());
        sel.b.copy_from(b);
        sel.points.clear();
        sel.points.extend_from_slice(&self.ev.points);
        sel.free.clear();
        sel.free.extend((0..candidates.len()).map(|i| b[2 * i]));
        Ok(sel)
    }

    /// Takes back a selection of [`Self::select`] whose numbers are no longer needed: the
    /// next selection is written into its buffers.
    pub fn recycle_selection(&mut self, sel: Selection) {
        self.selection = sel;
    }
}

/// A candidate point of a mode selection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The pair.
    pub pair: PairId,
    /// The point on `a` in its body's frame (m).
    pub local: Vec2,
    /// Coulomb's coefficient.
    pub mu: Real,
    /// A slip direction it must take if it stays closed (it may not stick), if any.
    pub slip: Option<Real>,
}

/// The outcome of a mode selection.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    /// The problem `w = A x + b` of the candidates (2k × 2k, 2k), and their allowed modes.
    pub a: DMatrix<Real>,
    /// See `a`.
    pub b: DVector<Real>,
    /// See `a`.
    pub allowed: Vec<Allowed>,
    /// The candidate points, in order.
    pub points: Vec<Point>,
    /// The normal acceleration of each candidate with no contact force, `b_n` (m/s²).
    pub free: Vec<Real>,
    /// Every consistent combination of modes.
    pub solutions: Vec<lcp::Solution>,
    /// The Painlevé coefficient of each candidate that slides (infinite otherwise).
    pub painleve: Vec<Real>,
}

/// The velocities `(v_n, v_t)` of [`PointScratch::velocities`] from the pair's contact
/// points `candidates` (of [`PointScratch::candidates`] at the state of `data`): those of
/// the one nearest `local`, `None` if there is none.
#[doc(hidden)]
pub fn nearest_velocities(
    model: &Model,
    data: &Data,
    p: &ContactPair,
    candidates: &[(PairContact, Vec2)],
    local: Vec2,
) -> Result<Option<(Real, Real)>, SimError> {
    let Some((c, _)) = candidates
        .iter()
        .min_by(|x, y| (x.1 - local).length().total_cmp(&(y.1 - local).length()))
    else {
        return Ok(None);
    };
    let v_r = relative_velocity_of(model, data, p, c).map_err(|e| e.at(data.time))?;
    let n = -c.normal;
    Ok(Some((v_r.dot(n), v_r.dot(perp(n)))))
}

/// Scratch to evaluate one contact point: the manifold, the frame and its rows.
pub struct PointScratch {
    manifold: ManifoldWorkspace,
    frame: FrameWorkspace,
    /// `J_n` of the last point (nu).
    pub j_n: Vec<Real>,
    /// `J_t` of the last point (nu).
    pub j_t: Vec<Real>,
}

impl PointScratch {
    /// Scratch for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            manifold: ManifoldWorkspace::default(),
            frame: FrameWorkspace::new(model),
            j_n: vec![0.0; model.nu()],
            j_t: vec![0.0; model.nu()],
        }
    }

    /// The contact points of the pair `(pair, p)` (`p = model.pair(pair)`, looked up by the
    /// caller) within `prediction` (m), with their points on `a` in the frame of `a`'s body.
    pub fn candidates_of(
        &mut self,
        model: &Model,
        data: &Data,
        (pair, p): (PairId, &ContactPair),
        prediction: Real,
    ) -> Result<arrayvec::ArrayVec<(PairContact, Vec2), 2>, SimError> {
        pair_points_of(model, data, (pair, p), prediction, &mut self.manifold)
    }

    /// The velocities `(v_n, v_t)` of [`Self::point`] (the same numbers), without its
    /// Jacobian rows.
    pub fn velocities(
        &mut self,
        model: &Model,
        data: &Data,
        pair: PairId,
        local: Vec2,
        prediction: Real,
    ) -> Result<Option<(Real, Real)>, SimError> {
        let p = resolve(model, data, pair)?;
        self.velocities_of(model, data, (pair, &p), local, prediction)
    }

    /// [`Self::velocities`] of a pair already resolved (`model.pair(pair)`).
    fn velocities_of(
        &mut self,
        model: &Model,
        data: &Data,
        (pair, p): (PairId, &ContactPair),
        local: Vec2,
        prediction: Real,
    ) -> Result<Option<(Real, Real)>, SimError> {
        let candidates = pair_points_of(model, data, (pair, p), prediction, &mut self.manifold)?;
        nearest_velocities(model, data, p, &candidates, local)
    }

    /// The point of the pair `(pair, p)` (`p = model.pair(pair)`, looked up by the caller)
    /// nearest `local` (a point on `a` in its body's frame) at the state of `data`
    /// (positions and velocities updated), with its frame (`t = perp(n)`) and velocities;
    /// its rows in `j_n`, `j_t`. `None` if the pair has no point within `prediction` (m).
    ///
    /// With `vertex` ([`ClosedVertex::of`]: `local` is that vertex of a polygonal shape on
    /// a half-space, found once per set of closed points), the vertex's contact alone
    /// ([`ClosedVertex::contact`], the same numbers as the query's nearest point), unless
    /// the support feature no longer holds it or it is beyond `prediction`: then the
    /// query, as for every other point.
    #[inline]
    pub fn point(
        &mut self,
        model: &Model,
        data: &Data,
        (pair, p): (PairId, &ContactPair),
        (local, vertex): (Vec2, Option<ClosedVertex>),
        prediction: Real,
    ) -> Result<Option<Point>, SimError> {
        let t = data.time;
        let cached = match vertex {
            Some(v) => (v.contact(model, data, p, prediction)).map_err(|e| e.at(t))?,
            None => None,
        };
        let nearest = match cached {
            Some(c) => {
                let pose = body_pose_of_a(model, data, p);
                Some((c, pose.inverse_transform_point(c.point_a)))
            }
            None => {
                let candidates =
                    pair_points_of(model, data, (pair, p), prediction, &mut self.manifold)?;
                (candidates.into_iter())
                    .min_by(|x, y| (x.1 - local).length().total_cmp(&(y.1 - local).length()))
            }
        };
        let Some((c, l)) = nearest else {
            return Ok(None);
        };
        let rows = (&mut self.j_n[..], &mut self.j_t[..]);
        let frame = frame_of(
            model,
            data,
            (pair, p),
            c,
            Tangent::Perp,
            &mut self.frame,
            rows,
        )
        .map_err(|e| e.at(t))?;
        Ok(Some(Point {
            pair,
            local: l,
            v_n: frame.v_n(),
            v_t: frame.v_t(),
            frame,
        }))
    }
}
