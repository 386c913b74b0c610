//! Equations of motion: the mass matrix `M(q)`, the bias forces `h(t, q, u)`, forward and
//! inverse dynamics, energies and powers.
//!
//! The equations of motion are Kane's equations [P, Eq. (1)] with the usual sign,
//!
//! ```text
//! M(q) u̇ = τ − h(t, q, u)
//! ```
//!
//! with `M = −M_paper` symmetric positive definite ([P, Eq. (68)], `paper/ERRATA.md`),
//! `τ` the generalized forces supplied by the caller (e.g. contact forces) and `h`
//! everything the model itself knows: velocity products, gravity, joint springs, dampers
//! and efforts, and the coupling to prescribed accelerations.
//!
//! The kernels follow the Model/Data pattern: `algo(&Model, &mut Data, …)` writes its
//! result into `data` and says which earlier stage it needs.
//!
//! ## Prescribed motion
//!
//! Over all joint coordinates (free `f` and prescribed `p`) the equations read
//! `M_ff u̇_f + M_fp q̈_p + h_f = τ_f` and `M_pf u̇_f + M_pp q̈_p + h_p = Q_p`, where `Q_p` is
//! the effort of the drives. Only the free rows are integrated: the Newton–Euler pass that
//! computes `h` runs with the prescribed accelerations `q̈_p(t)` in place, so `h` contains
//! `M_fp q̈_p`. The drive efforts `Q_p` come from the same pass run with the solved `u̇`
//! ([`power`]).

use nalgebra::{Cholesky, DMatrix, DVectorViewMut, Dyn, SymmetricEigen};

use crate::kinematics::{KinematicsError, check_len, update_positions, update_velocities};
use crate::math::Real;
use crate::model::spatial::{Twist, Wrench};
use crate::model::{JointId, Model};
use crate::state::Data;

/// A failure to evaluate the equations of motion, with the evidence.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A kinematics query failed (wrong vector length, unknown id).
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// A number is NaN or infinite.
    #[error("at t = {t}: {what}[{index}] is not finite ({value})")]
    NonFinite {
        /// Time (s).
        t: Real,
        /// Which vector: `"q"`, `"u"`, `"tau"` or `"udot"`.
        what: &'static str,
        /// Index of the first bad entry.
        index: usize,
        /// Its value.
        value: Real,
    },
    /// The mass matrix is not positive definite (its Cholesky factorization failed).
    #[error(
        "at t = {t}: the mass matrix is not positive definite (smallest eigenvalue {min_eigenvalue})"
    )]
    NotPositiveDefinite {
        /// Time (s).
        t: Real,
        /// The smallest eigenvalue of `M` (kg, kg·m², …; NaN if `M` is not finite).
        min_eigenvalue: Real,
    },
    /// [`solve_mass`] was called before a successful factorization.
    #[error("the mass matrix has not been factored (call forward_dynamics first)")]
    NotFactored,
}

/// The Cholesky factorization `M = L Lᵀ` (`L` lower triangular) of the mass matrix,
/// nalgebra's [`Cholesky`], kept with its buffer so that refactoring allocates nothing: the
/// factor's matrix is taken back with `unpack_dirty`, overwritten with the new `M` and
/// factored in place. The impact map solves `M x = b` with it for several right-hand sides
/// (`W = J M⁻¹ Jᵀ`, [P, Eq. (20)]).
#[derive(Clone, Debug)]
pub struct MassFactor {
    /// The factor of the last mass matrix, if it was positive definite.
    chol: Option<Cholesky<Real, Dyn>>,
    /// The buffer when there is no factor (before the first factorization).
    spare: Option<DMatrix<Real>>,
    /// The dimension `nu`.
    n: usize,
}

impl MassFactor {
    /// A factor buffer for an `n × n` matrix, not yet valid.
    pub fn new(n: usize) -> Self {
        MassFactor {
            chol: None,
            spare: Some(DMatrix::zeros(n, n)),
            n,
        }
    }

    /// `true` if it holds the factor of the last mass matrix.
    pub fn is_valid(&self) -> bool {
        self.chol.is_some()
    }

    /// The lower triangular factor `L` of `M = L Lᵀ` (a copy), if factored.
    pub fn lower(&self) -> Option<DMatrix<Real>> {
        self.chol.as_ref().map(|c| c.l())
    }

    /// Factors the symmetric matrix `m` (its lower triangle is read) into `M = L Lᵀ`.
    ///
    /// Returns the smallest eigenvalue of `m` if it is not positive definite (computed on
    /// that cold path only; the buffer is then lost and reallocated at the next call).
    fn factor(&mut self, m: &DMatrix<Real>) -> Result<(), Real> {
        let mut buf = match (self.chol.take(), self.spare.take()) {
            (Some(chol), _) => chol.unpack_dirty(),
            (None, Some(buf)) => buf,
            (None, None) => DMatrix::zeros(self.n, self.n),
        };
        buf.copy_from(m);
        match Cholesky::new(buf) {
            Some(chol) => {
                self.chol = Some(chol);
                Ok(())
            }
            None => Err(smallest_eigenvalue(m)),
        }
    }

    /// Solves `M x = b` in place (`b` becomes `x`): `L y = b` forward, then `Lᵀ x = y`
    /// backward.
    pub fn solve_in_place(&self, b: &mut [Real]) -> Result<(), DynamicsError> {
        let chol = self.chol.as_ref().ok_or(DynamicsError::NotFactored)?;
        check_len("right-hand side", self.n, b.len())?;
        chol.solve_mut(&mut DVectorViewMut::from_slice(b, self.n));
        Ok(())
    }
}

/// The smallest eigenvalue of a symmetric matrix (the evidence of a failed factorization).
#[cold]
fn smallest_eigenvalue(m: &DMatrix<Real>) -> Real {
    if m.iter().any(|x| !x.is_finite()) {
        return Real::NAN;
    }
    SymmetricEigen::new(m.clone())
        .eigenvalues
        .iter()
        .copied()
        .fold(Real::INFINITY, Real::min)
}

/// Kinetic and potential energy.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Energy {
    /// Kinetic energy `T` (J), [P, Eq. (70)], including prescribed motions.
    pub kinetic: Real,
    /// Potential energy `V` (J): gravity and joint springs.
    pub potential: Real,
}

impl Energy {
    /// `T + V` (J).
    pub fn total(&self) -> Real {
        self.kinetic + self.potential
    }
}

/// The powers that change the mechanical energy `E = T + V` in free flight:
/// `dE/dt = damping + applied + drives + uᵀ τ`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Power {
    /// Power of the joint dampers `−Σ c q̇²` (W), never positive.
    pub damping: Real,
    /// Power of the constant joint efforts `Σ τ q̇` (W).
    pub applied: Real,
    /// Power delivered by the prescribed drives `Σ Q_p q̇_p` (W).
    pub drives: Real,
}

/// Computes the mass matrix by the composite rigid body algorithm [F, §6.2].
///
/// Implements [P, Eq. (68)] with the sign of `paper/ERRATA.md`: for rigid bodies with
/// partial twists `S_r(b)`, `M_rs = Σ_b S_r(b)ᵀ I_b S_s(b)` (`= Σ m v_r^C·v_s^C + I_c ω_r ω_s`).
/// In a tree, `S_r(b)` is `S_r` carried down to `b`, so with the composite inertias
///
/// ```text
/// I^c_b = I_b + Σ_{children c} P_cᵀ I^c_c P_c        (P_c = 1, or the projection of an absolute joint)
/// M_rs  = S_sᵀ (P…ᵀ I^c_b S_r)                        (s on the path from b to the root)
/// ```
///
/// `P_cᵀ I^c P_c` is the point mass `I^c.m` at the joint (see
/// [`crate::model::spatial::Inertia::projected_at`]). Cost: `O(n·depth)`.
///
/// Requires [`update_positions`]. Writes `data.composite` and `data.mass`.
pub fn mass_matrix(model: &Model, data: &mut Data) {
    if model.is_holonomic() {
        let mut mass = std::mem::take(&mut data.mass);
        tree_mass_matrix(model, data, &mut mass);
        data.mass = mass;
    } else {
        // M = Sᵀ M_v S  (Kane's generalized inertia forces in the speeds u).
        let mut mass_tree = std::mem::take(&mut data.mass_tree);
        tree_mass_matrix(model, data, &mut mass_tree);
        data.mass_map.gemm(1.0, &mass_tree, &data.speed_map, 0.0);
        data.mass.gemm_tr(1.0, &data.speed_map, &data.mass_map, 0.0);
        // Exactly symmetric: the upper triangle from the lower one.
        let nu = data.mass.nrows();
        for c in 1..nu {
            for r in 0..c {
                data.mass[(r, c)] = data.mass[(c, r)];
            }
        }
        data.mass_tree = mass_tree;
    }
}

/// The composite rigid body algorithm of [`mass_matrix`] over the tree speeds, into `out`
/// `[nv × nv]`.
fn tree_mass_matrix(model: &Model, data: &mut Data, out: &mut DMatrix<Real>) {
    let joints = model.joints();
    // Composite inertias, leaves first.
    data.composite.copy_from_slice(&data.body_inertia);
    for i in (0..joints.len()).rev() {
        if let Some(p) = joints[i].parent {
            let mut ic = data.composite[i];
            if joints[i].is_absolute() {
                ic = ic.projected_at(data.joint_frame[i].translation);
            }
            data.composite[p.index()] += ic;
        }
    }
    // Rows: for each free coordinate, the wrench I^c S walked up to the root. M is
    // symmetric; both triangles are written (column-major slice, M_rc at c·nu + r).
    let nu = model.nv();
    let (subspace, frames, composite) = (&data.subspace, &data.joint_frame, &data.composite);
    let mass = out.as_mut_slice();
    mass.fill(0.0);
    for (i, joint) in joints.iter().enumerate() {
        let Some(si) = model.q_index(JointId(i)) else {
            continue;
        };
        for k in 0..joint.kind.ndof() {
            let r = si + k;
            let mut f = composite[i].mul_twist(&subspace[i][k]);
            for k2 in 0..=k {
                let m = subspace[i][k2].dot(&f);
                mass[(si + k2) * nu + r] = m;
                mass[r * nu + si + k2] = m;
            }
            let mut b = i;
            while let Some(p) = joints[b].parent {
                if joints[b].is_absolute() {
                    f = f.projected_at(frames[b].translation);
                }
                b = p.index();
                if let Some(sp) = model.q_index(JointId(b)) {
                    for k2 in 0..joints[b].kind.ndof() {
                        let m = subspace[b][k2].dot(&f);
                        mass[(sp + k2) * nu + r] = m;
                        mass[r * nu + sp + k2] = m;
                    }
                }
            }
        }
    }
}

/// Which generalized accelerations the Newton–Euler pass uses for the free coordinates.
#[derive(Clone, Copy)]
enum FreeAccel<'a> {
    /// `u̇ = 0`: the pass yields the bias forces.
    Zero,
    /// `u̇` given by the caller.
    Given(&'a [Real]),
    /// `u̇ = data.udot`, the last forward dynamics.
    Solved,
}

/// The recursive Newton–Euler pass [F, §5.3] over all joints, free and prescribed:
///
/// ```text
/// A_b = P_b A_parent + c_b + Σ S_k q̈_k
/// F_b = I_b A_b + V_b ×* (I_b V_b) − (c_b × m_b g, m_b g) + Σ_{children} P_cᵀ F_c
/// effort_k = S_kᵀ F_b
/// ```
///
/// with `q̈` from `accel` for the free coordinates and `q̈_p(t)` for the prescribed ones.
/// Writes `data.body_accel`, `data.body_wrench`, `data.joint_effort`.
fn newton_euler(model: &Model, data: &mut Data, accel: FreeAccel<'_>) {
    let joints = model.joints();
    let g = model.gravity();
    // Forward: accelerations and the net wrench each body needs.
    for (i, joint) in joints.iter().enumerate() {
        let mut a = match joint.parent {
            Some(p) => data.body_accel[p.index()],
            None => Twist::ZERO,
        };
        if joint.is_absolute() {
            a = a.projected_at(data.joint_frame[i].translation);
        }
        a += data.body_accel_vp[i];
        let qdd = data.joint_qdd_prescribed[i];
        let free = model.q_index(JointId(i));
        for k in 0..joint.kind.ndof() {
            let acc = match (free, accel) {
                (None, _) | (_, FreeAccel::Zero) => qdd[k],
                (Some(s), FreeAccel::Given(udot)) => udot[s + k],
                (Some(s), FreeAccel::Solved) if model.is_holonomic() => data.udot[s + k],
                (Some(s), FreeAccel::Solved) => data.tree_accel[s + k],
            };
            a += data.subspace[i][k] * acc;
        }
        let inertia = &data.body_inertia[i];
        let v = &data.body_twist[i];
        let weight = Wrench::force_at(g * inertia.m, data.body_com[i]);
        data.body_accel[i] = a;
        data.body_wrench[i] = inertia.mul_twist(&a) + v.cross_force(&inertia.mul_twist(v)) - weight;
    }
    // Backward: joint efforts, and the wrench passed on to the parent.
    for i in (0..joints.len()).rev() {
        let f = data.body_wrench[i];
        for k in 0..joints[i].kind.ndof() {
            data.joint_effort[i][k] = data.subspace[i][k].dot(&f);
        }
        if let Some(p) = joints[i].parent {
            let f = if joints[i].is_absolute() {
                f.projected_at(data.joint_frame[i].translation)
            } else {
                f
            };
            data.body_wrench[p.index()] += f;
        }
    }
}

/// Writes the generalized forces of the free coordinates, `out = effort − Q_force` with
/// `Q_force = −k (q − q_rest) − c q̇ + τ` the joint force elements.
fn gather_free(model: &Model, data: &Data, out: &mut [Real]) {
    for (i, joint) in model.joints().iter().enumerate() {
        if let Some(s) = model.q_index(JointId(i)) {
            let nd = joint.kind.ndof();
            out[s..s + nd].copy_from_slice(&data.joint_effort[i][..nd]);
            if joint.kind.ndof() == 1 {
                out[s] -= joint
                    .force
                    .generalized_force(data.joint_q[i][0], data.joint_qd[i][0]);
            }
        }
    }
}

/// Computes the bias forces `h(t, q, u)`: the generalized forces that would be needed for
/// `u̇ = 0`, by the Newton–Euler pass with the free accelerations set to zero:
///
/// ```text
/// h = C(q, u) u + g(q) + M_fp q̈_p(t) − Q_force(q, u)
/// ```
///
/// (velocity products, gravity, coupling to the prescribed accelerations, and the joint
/// springs, dampers and efforts `Q_force = −k (q − q_rest) − c q̇ + τ`).
///
/// Requires [`update_velocities`]. Writes `data.bias` (and the Newton–Euler scratch).
///
/// With nonholonomic constraints, `h = Sᵀ (M_v v̇₀ + h_v)`: the tree's inverse dynamics at
/// the accelerations `v̇₀` the removed speeds have when `u̇ = 0` (see
/// [`crate::constraints`]), projected on the speeds (Kane's equations in `u`,
/// [P, Eq. (1)]); `data.tree_accel0` holds `v̇₀`.
pub fn bias_forces(model: &Model, data: &mut Data) {
    newton_euler(model, data, FreeAccel::Zero);
    if model.is_holonomic() {
        let mut bias = std::mem::take(&mut data.bias);
        gather_free(model, data, bias.as_mut_slice());
        data.bias = bias;
    } else {
        crate::constraints::removed_accelerations(model, data);
        let accel0 = std::mem::take(&mut data.tree_accel0);
        newton_euler(model, data, FreeAccel::Given(accel0.as_slice()));
        data.tree_accel0 = accel0;
        project_tree_forces(model, data, ProjectInto::Bias);
    }
}

/// Where [`project_tree_forces`] writes.
enum ProjectInto {
    Bias,
    Tau,
}

/// Gathers the tree's joint forces of the last Newton–Euler pass into
/// `data.force_tree` and projects them on the speeds, `Sᵀ f`.
fn project_tree_forces(model: &Model, data: &mut Data, into: ProjectInto) {
    let mut f = std::mem::take(&mut data.force_tree);
    gather_free(model, data, f.as_mut_slice());
    let out = match into {
        ProjectInto::Bias => &mut data.bias,
        ProjectInto::Tau => &mut data.tau,
    };
    out.gemv_tr(1.0, &data.speed_map, &f, 0.0);
    data.force_tree = f;
}

/// Computes the generalized forces that produce the accelerations `udot`:
/// `τ = M u̇ + h` (inverse dynamics, by the Newton–Euler pass).
///
/// Requires [`update_velocities`]. Writes `data.tau` (and the Newton–Euler scratch,
/// including the prescribed joints' efforts in `data.joint_effort`).
pub fn inverse_dynamics(
    model: &Model,
    data: &mut Data,
    udot: &[Real],
) -> Result<(), DynamicsError> {
    check_len("udot", model.nu(), udot.len())?;
    if model.is_holonomic() {
        newton_euler(model, data, FreeAccel::Given(udot));
        let mut tau = std::mem::take(&mut data.tau);
        gather_free(model, data, tau.as_mut_slice());
        data.tau = tau;
    } else {
        // v̇ = S u̇ + v̇₀, τ = Sᵀ (M_v v̇ + h_v).
        newton_euler(model, data, FreeAccel::Zero);
        crate::constraints::removed_accelerations(model, data);
        let mut accel = std::mem::take(&mut data.tree_accel);
        accel.copy_from(&data.tree_accel0);
        accel.gemv(
            1.0,
            &data.speed_map,
            &nalgebra::DVectorView::from_slice(udot, udot.len()),
            1.0,
        );
        newton_euler(model, data, FreeAccel::Given(accel.as_slice()));
        data.tree_accel = accel;
        project_tree_forces(model, data, ProjectInto::Tau);
    }
    Ok(())
}

/// Solves the equations of motion `M u̇ = −h` (no external generalized force): see
/// [`forward_dynamics_with`].
pub fn forward_dynamics(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
    u: &[Real],
) -> Result<(), DynamicsError> {
    forward_dynamics_with(model, data, t, q, u, None)
}

/// Solves the equations of motion for the generalized accelerations,
///
/// ```text
/// u̇ = M(q)⁻¹ (τ − h(t, q, u))
/// ```
///
/// through the Cholesky factorization `M = L Lᵀ` ([P, Eq. (1)] with `M = −M_paper`).
/// Stages: check the input, kinematics, [`mass_matrix`], [`bias_forces`], factor, solve.
/// `tau` is an optional generalized force `[nu]` (N, N·m), zero if `None`. Allocates nothing.
///
/// Writes every kinematics field, `data.mass`, `data.mass_factor`, `data.bias` and
/// `data.udot`. The factor stays valid for [`solve_mass`] until the next call.
pub fn forward_dynamics_with(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
    u: &[Real],
    tau: Option<&[Real]>,
) -> Result<(), DynamicsError> {
    // Input: sizes and finite numbers.
    check_len("q", model.nq(), q.len())?;
    check_len("u", model.nu(), u.len())?;
    check_finite(t, "q", q)?;
    check_finite(t, "u", u)?;
    if let Some(tau) = tau {
        check_len("tau", model.nu(), tau.len())?;
        check_finite(t, "tau", tau)?;
    }
    // Kinematics, M(q), h(t, q, u).
    update_positions(model, data, t, q)?;
    update_velocities(model, data, u)?;
    mass_matrix(model, data);
    bias_forces(model, data);
    // M = L Lᵀ.
    data.mass_factor
        .factor(&data.mass)
        .map_err(|min_eigenvalue| DynamicsError::NotPositiveDefinite { t, min_eigenvalue })?;
    // u̇ = M⁻¹ (τ − h).
    for r in 0..model.nu() {
        data.udot[r] = tau.map_or(0.0, |tau| tau[r]) - data.bias[r];
    }
    data.mass_factor.solve_in_place(data.udot.as_mut_slice())?;
    check_finite(t, "udot", data.udot.as_slice())?;
    if !model.is_holonomic() {
        // v̇ = S u̇ + v̇₀, for the drives' power.
        let mut accel = std::mem::take(&mut data.tree_accel);
        accel.copy_from(&data.tree_accel0);
        accel.gemv(1.0, &data.speed_map, &data.udot, 1.0);
        data.tree_accel = accel;
    }
    Ok(())
}

/// The right-hand side of the first-order system `ẏ = f(t, y)` with `y = [q; u]`:
/// `dy = [A u + b; M⁻¹(−h)]` (`A u + b = u` for a holonomic model). Allocates nothing;
/// see [`forward_dynamics`].
pub fn ode_rhs(
    model: &Model,
    data: &mut Data,
    t: Real,
    y: &[Real],
    dy: &mut [Real],
) -> Result<(), DynamicsError> {
    let (n, nu) = (model.nq(), model.nu());
    check_len("y", n + nu, y.len())?;
    check_len("dy", n + nu, dy.len())?;
    let (q, u) = y.split_at(n);
    forward_dynamics(model, data, t, q, u)?;
    coordinate_rates(model, data, u, &mut dy[..n]);
    dy[n..].copy_from_slice(data.udot.as_slice());
    Ok(())
}

/// The coordinate rates `q̇ = A(q, t) u + b(q, t)` [P, Eq. (1)] at the state of the last
/// [`update_velocities`] (at the speeds `u`): `u` itself for a holonomic model.
pub fn coordinate_rates(model: &Model, data: &Data, u: &[Real], qdot: &mut [Real]) {
    if model.is_holonomic() {
        qdot.copy_from_slice(u);
    } else {
        crate::constraints::coordinate_rates(model, data, qdot);
    }
}

/// The kinematic equations `q̇ = A(q, t) u + b(q, t)` [P, Eq. (1)] at `(t, q)`: `A`
/// `[nq × nu]` column by column (`A e_i = q̇(e_i) − b`), and `b = q̇(u = 0)`, the rates due
/// to the prescribed motions alone. For reports (`ricochet check`); it allocates.
pub fn kinematic_equations(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
) -> Result<(DMatrix<Real>, nalgebra::DVector<Real>), KinematicsError> {
    let (nq, nu) = (model.nq(), model.nu());
    update_positions(model, data, t, q)?;
    let mut u = vec![0.0; nu];
    let mut b = nalgebra::DVector::zeros(nq);
    update_velocities(model, data, &u)?;
    coordinate_rates(model, data, &u, b.as_mut_slice());
    let mut a = DMatrix::zeros(nq, nu);
    let mut col = vec![0.0; nq];
    for i in 0..nu {
        u.fill(0.0);
        u[i] = 1.0;
        update_velocities(model, data, &u)?;
        coordinate_rates(model, data, &u, &mut col);
        for r in 0..nq {
            a[(r, i)] = col[r] - b[r];
        }
    }
    Ok((a, b))
}

/// Solves `M x = b` in place with the factor of the last [`forward_dynamics`] (`b`
/// becomes `x`). For the impact map: `Δu = M⁻¹ Jᵀ I` [P, Eq. (16)], `W = J M⁻¹ Jᵀ`
/// [P, Eq. (20)].
pub fn solve_mass(data: &Data, b: &mut [Real]) -> Result<(), DynamicsError> {
    data.mass_factor.solve_in_place(b)
}

/// Factors the mass matrix already in `data.mass` (after [`mass_matrix`]) without solving
/// the dynamics, e.g. to compute an impact at a state. `t` is reported in errors.
pub fn factor_mass_matrix(data: &mut Data, t: Real) -> Result<(), DynamicsError> {
    data.mass_factor
        .factor(&data.mass)
        .map_err(|min_eigenvalue| DynamicsError::NotPositiveDefinite { t, min_eigenvalue })
}

/// The kinetic energy, [P, Eq. (70)], with the full velocities (prescribed motions
/// included):
///
/// ```text
/// T = Σ_b ½ V_bᵀ I_b V_b = Σ_b ½ m_b |v_c|² + ½ I_c ω_b²
/// ```
///
/// Without prescribed motion `T = ½ uᵀ M u`. Requires [`update_velocities`].
pub fn kinetic_energy(model: &Model, data: &Data) -> Real {
    (0..model.nbody())
        .map(|i| data.body_inertia[i].kinetic_energy(&data.body_twist[i]))
        .sum()
}

/// The potential energy of gravity and of the joint springs:
///
/// ```text
/// V = −Σ_b m_b g·c_b + Σ_joints ½ k (q − q_rest)²
/// ```
///
/// Requires [`update_positions`].
pub fn potential_energy(model: &Model, data: &Data) -> Real {
    let g = model.gravity();
    let gravity: Real = (0..model.nbody())
        .map(|i| -data.body_inertia[i].m * g.dot(data.body_com[i]))
        .sum();
    let springs: Real = model
        .joints()
        .iter()
        .enumerate()
        .filter(|(_, j)| j.drive.is_none() && j.kind.ndof() == 1)
        .map(|(i, j)| j.force.potential_energy(data.joint_q[i][0]))
        .sum();
    gravity + springs
}

/// Kinetic and potential energy at the state `(t, q, u)` (runs the kinematics).
pub fn energy(
    model: &Model,
    data: &mut Data,
    t: Real,
    q: &[Real],
    u: &[Real],
) -> Result<Energy, KinematicsError> {
    update_positions(model, data, t, q)?;
    update_velocities(model, data, u)?;
    Ok(Energy {
        kinetic: kinetic_energy(model, data),
        potential: potential_energy(model, data),
    })
}

/// The powers of the dampers, of the constant efforts and of the prescribed drives, for the
/// energy audit: in free flight `dE/dt = damping + applied + drives (+ uᵀ τ)`.
///
/// The drive efforts are `Q_p = S_pᵀ F` of the Newton–Euler pass with the solved `u̇`
/// (the prescribed rows of `M q̈ + h = Q`), and their power is `Σ Q_p q̇_p`.
///
/// Requires [`forward_dynamics`] at the same state (it uses `data.udot`). Writes the
/// Newton–Euler scratch, leaving the drive efforts in `data.joint_effort`.
pub fn power(model: &Model, data: &mut Data) -> Power {
    let mut p = Power::default();
    for (i, joint) in model.joints().iter().enumerate() {
        if joint.drive.is_none() && joint.kind.ndof() == 1 {
            let qd = data.joint_qd[i][0];
            p.damping -= joint.force.damping * qd * qd;
            p.applied += joint.force.effort * qd;
        }
    }
    if model.has_prescribed_motion() {
        newton_euler(model, data, FreeAccel::Solved);
        for (i, joint) in model.joints().iter().enumerate() {
            if joint.drive.is_some() {
                p.drives += data.joint_effort[i][0] * data.joint_qd[i][0];
            }
        }
    }
    p
}

fn check_finite(t: Real, what: &'static str, v: &[Real]) -> Result<(), DynamicsError> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(index) => Err(DynamicsError::NonFinite {
            t,
            what,
            index,
            value: v[index],
        }),
    }
}
