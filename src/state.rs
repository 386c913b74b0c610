//! [`State`], what the integrator advances, and [`Data`], the scratch workspace of the
//! kinematics and dynamics kernels.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::dynamics::{MassFactor, mass_pattern};
use crate::math::{Pose, Real, Vec2};
use crate::model::Model;
use crate::model::spatial::{Inertia, Twist, Wrench};
use crate::tree_matrix::TreeMatrix;

/// The state of a run: all that is needed to restart it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Time `t` (s).
    pub t: Real,
    /// Generalized coordinates `q` `[nq]` (m, rad), in the order of
    /// [`Model::coordinates`].
    pub q: DVector<Real>,
    /// Generalized speeds `u` `[nu]` (m/s, rad/s), in the order of [`Model::speeds`]:
    /// `u = q̇` for a holonomic model, `q̇ = A(q, t) u + b(q, t)` with nonholonomic
    /// constraints.
    pub u: DVector<Real>,
}

impl State {
    /// The state at time `t` with coordinates `q` and speeds `u`.
    pub fn new(t: Real, q: DVector<Real>, u: DVector<Real>) -> Self {
        State { t, q, u }
    }

    /// The state of `model` at `t = 0` with every coordinate and speed zero.
    pub fn zeros(model: &Model) -> Self {
        State {
            t: 0.0,
            q: DVector::zeros(model.nq()),
            u: DVector::zeros(model.nu()),
        }
    }
}

/// Scratch space of the kernels of [`crate::kinematics`] and [`crate::dynamics`], sized
/// once from a [`Model`] so that evaluating the equations of motion allocates nothing.
/// Never serialized; rebuild it with [`Data::new`].
///
/// Per-joint arrays are indexed by joint (= body) index and hold up to three joint
/// coordinates (only the first `ndof` are meaningful). Spatial quantities are in world
/// coordinates referred to the world origin (see [`crate::model::spatial`]). Each field
/// says which kernel writes it.
#[derive(Clone, Debug)]
pub struct Data {
    /// Time of the last [`crate::kinematics::update_positions`] (s).
    pub time: Real,
    /// Joint coordinates, free and prescribed `[nbody][3]` (m, rad).
    /// Written by `update_positions`.
    pub joint_q: Vec<[Real; 3]>,
    /// Joint coordinate rates `[nbody][3]` (m/s, rad/s). Written by `update_velocities`.
    pub joint_qd: Vec<[Real; 3]>,
    /// Prescribed joint accelerations, zero for free joints `[nbody][3]` (m/s², rad/s²).
    /// Written by `update_positions`.
    pub joint_qdd_prescribed: Vec<[Real; 3]>,
    /// World pose of each joint frame `[nbody]`; its translation is the joint's position
    /// `a` (m). Written by `update_positions`.
    pub joint_frame: Vec<Pose>,
    /// Motion subspace columns `S` of each joint `[nbody][3]`: the twist the body gains per
    /// unit rate of each joint coordinate (world, referred to `O`). Written by
    /// `update_positions`.
    pub subspace: Vec<[Twist; 3]>,
    /// World pose of each body frame `[nbody]`. Written by `update_positions`.
    pub body_pose: Vec<Pose>,
    /// World position of each body's centre of mass `[nbody]` (m). Written by
    /// `update_positions`.
    pub body_com: Vec<Vec2>,
    /// Spatial inertia of each body `[nbody]` (world, referred to `O`). Written by
    /// `update_positions`.
    pub body_inertia: Vec<Inertia>,
    /// Twist of each body `[nbody]` (rad/s, m/s; world, referred to `O`), including the
    /// prescribed motions. Written by `update_velocities`.
    pub body_twist: Vec<Twist>,
    /// Remainder twist of each body `[nbody]`: its twist when `u = 0`, due to the prescribed
    /// motions alone (rad/s, m/s) — the `v_t` of [P, Eq. (2)]. Written by
    /// `update_velocities`.
    pub body_twist_remainder: Vec<Twist>,
    /// Velocity-product part of each body's spatial acceleration `[nbody]` (rad/s², m/s²):
    /// `A_b = P_b A_parent + c_b + Σ S q̈` holds `c_b = Ṗ_b V_parent + Σ Ṡ q̇`. Written by
    /// `update_velocities`.
    pub body_accel_vp: Vec<Twist>,
    /// Spatial acceleration of each body `[nbody]` (rad/s², m/s²) in the last
    /// Newton–Euler pass. Written by `dynamics`.
    pub body_accel: Vec<Twist>,
    /// Net wrench transmitted by each body's joint in the last Newton–Euler pass `[nbody]`
    /// (N·m, N; referred to `O`). Written by `dynamics`.
    pub body_wrench: Vec<Wrench>,
    /// Composite inertia of each body's subtree as seen through its joint `[nbody]`
    /// (referred to `O`). Written by `dynamics::mass_matrix`.
    pub composite: Vec<Inertia>,
    /// Joint efforts of the last Newton–Euler pass `[nbody][3]` (N·m, N): the generalized
    /// inertia and gravity forces `S_kᵀ F`; for prescribed joints after
    /// `dynamics::power`, the effort the drive exerts. Written by `dynamics`.
    pub joint_effort: Vec<[Real; 3]>,
    /// Mass matrix `M(q)` `[nu × nu]` (kg, kg·m, kg·m²), symmetric positive definite
    /// (`M = −M_paper`, [P, Eq. (68)]), stored with the tree's sparsity (the entries of a
    /// speed and its ancestors, [`crate::dynamics::mass_pattern`]). Written by
    /// `dynamics::mass_matrix`.
    pub mass: TreeMatrix,
    /// The factor of `M = Lᵀ L` [F, §6.5], with the same sparsity. Written by
    /// `dynamics::forward_dynamics`; use it with [`crate::dynamics::solve_mass`].
    pub mass_factor: MassFactor,
    /// Bias forces `h(t, q, u)` `[nu]` (N, N·m): velocity products, gravity, force elements
    /// and the coupling to the prescribed accelerations, so that `M u̇ = τ − h`. Written by
    /// `dynamics::bias_forces`.
    pub bias: DVector<Real>,
    /// Generalized accelerations `u̇` `[nu]` (m/s², rad/s²). Written by
    /// `dynamics::forward_dynamics`.
    pub udot: DVector<Real>,
    /// Generalized forces of the last inverse dynamics `M u̇ + h` `[nu]` (N, N·m). Written
    /// by `dynamics::inverse_dynamics`.
    pub tau: DVector<Real>,
    /// The world point `P` and blade normal `n` of each nonholonomic constraint `[m]`.
    /// Written by `update_positions`.
    pub constraint_frame: Vec<(Vec2, Vec2)>,
    /// The constraint rows `C` `[m × nv]`: `n · v^P = C v + c`. Written by
    /// `update_positions`.
    pub constraint_rows: DMatrix<Real>,
    /// The LU factors of `C_d` (the columns of the removed speeds) `[m × m]`, with partial
    /// pivoting: `P C_d = L U` packed, `constraint_pivots` the row swapped in at each
    /// column (applied in order, as LAPACK's `ipiv`). Written by
    /// `update_positions`.
    pub constraint_lu: DMatrix<Real>,
    /// The row swaps of `constraint_lu`.
    pub constraint_pivots: Vec<usize>,
    /// `S` `[nv × nu]`: `v = S u + s` (the rows of the removed speeds `−C_d⁻¹ C_i`, the
    /// others unit rows). Written by `update_positions`.
    pub speed_map: DMatrix<Real>,
    /// The tree speeds `v` `[nv]` of the last `update_velocities` (m/s, rad/s); this and
    /// the fields below are empty for a holonomic model, whose tree speeds are `u`.
    pub tree_speed: DVector<Real>,
    /// The tree accelerations when `u̇ = 0`, `v̇₀` `[nv]`: zero but for the removed speeds,
    /// `−C_d⁻¹ γ`. Written by `dynamics::bias_forces`.
    pub tree_accel0: DVector<Real>,
    /// The tree accelerations `v̇ = S u̇ + v̇₀` `[nv]` of the last forward dynamics.
    pub tree_accel: DVector<Real>,
    /// The tree's mass matrix `M_v` `[nv × nv]` (nonholonomic models; `M = Sᵀ M_v S`).
    pub mass_tree: DMatrix<Real>,
    /// `M_v S` `[nv × nu]`, scratch of `mass_matrix`.
    pub mass_map: DMatrix<Real>,
    /// `M = Sᵀ M_v S` `[nu × nu]` dense, scratch of `mass_matrix` (nonholonomic models).
    pub mass_dense: DMatrix<Real>,
    /// The tree's bias or inverse-dynamics forces `[nv]`, scratch.
    pub force_tree: DVector<Real>,
    /// Scratch `[m]`.
    pub constraint_scratch: DVector<Real>,
}

impl Data {
    /// Scratch space for `model`, every entry zero: the kinematics and the dynamics
    /// allocate nothing afterwards.
    pub fn new(model: &Model) -> Self {
        Self::with_mass(model, true)
    }

    /// Scratch space for `model` without the storage of the mass matrix and its factor
    /// (`O(n²)` for a chain of `n` links), for the kinematics and the energies alone; the
    /// first [`crate::dynamics::mass_matrix`] or factorization allocates it.
    pub fn for_kinematics(model: &Model) -> Self {
        Self::with_mass(model, false)
    }

    fn with_mass(model: &Model, allocate: bool) -> Self {
        let nb = model.nbody();
        let nu = model.nu();
        let nv = model.nv();
        let m = model.constraints().len();
        // The tree-level matrices only where the speeds differ from the tree's.
        let (nh, nh_u) = if model.is_holonomic() {
            (0, 0)
        } else {
            (nv, nu)
        };
        let pattern = mass_pattern(model);
        // The articulated-body factor needs no mass matrix: its storage waits for a
        // `mass_matrix` call.
        let mass_factor = MassFactor::for_model(model, pattern.clone(), allocate);
        Data {
            time: 0.0,
            joint_q: vec![[0.0; 3]; nb],
            joint_qd: vec![[0.0; 3]; nb],
            joint_qdd_prescribed: vec![[0.0; 3]; nb],
            joint_frame: vec![Pose::IDENTITY; nb],
            subspace: vec![[Twist::ZERO; 3]; nb],
            body_pose: vec![Pose::IDENTITY; nb],
            body_com: vec![Vec2::ZERO; nb],
            body_inertia: vec![Inertia::ZERO; nb],
            body_twist: vec![Twist::ZERO; nb],
            body_twist_remainder: vec![Twist::ZERO; nb],
            body_accel_vp: vec![Twist::ZERO; nb],
            body_accel: vec![Twist::ZERO; nb],
            body_wrench: vec![Wrench::ZERO; nb],
            composite: vec![Inertia::ZERO; nb],
            joint_effort: vec![[0.0; 3]; nb],
            mass: if allocate && !mass_factor.is_articulated() {
                TreeMatrix::zeros(pattern.clone())
            } else {
                TreeMatrix::unallocated(pattern.clone())
            },
            mass_factor,
            bias: DVector::zeros(nu),
            udot: DVector::zeros(nu),
            tau: DVector::zeros(nu),
            constraint_frame: vec![(Vec2::ZERO, Vec2::ZERO); m],
            constraint_rows: DMatrix::zeros(m, nv),
            constraint_lu: DMatrix::zeros(m, m),
            constraint_pivots: (0..m).collect(),
            speed_map: DMatrix::zeros(nh, nh_u),
            tree_speed: DVector::zeros(nh),
            tree_accel0: DVector::zeros(nh),
            tree_accel: DVector::zeros(nh),
            mass_tree: DMatrix::zeros(nh, nh),
            mass_map: DMatrix::zeros(nh, nh_u),
            mass_dense: DMatrix::zeros(nh_u, nh_u),
            force_tree: DVector::zeros(nh),
            constraint_scratch: DVector::zeros(m),
        }
    }

    /// Copies the kinematics of `other`, scratch of the same model: every field that
    /// [`crate::kinematics::update_positions`] and [`crate::kinematics::update_velocities`]
    /// write (the time, the joint coordinates and rates, the joint frames, motion subspaces,
    /// body poses, centres of mass, inertias, twists and velocity-product accelerations,
    /// and for a nonholonomic model the constraint rows, their factors, the speed map and
    /// the tree speeds). Afterwards `self` holds, bit for bit, what those two calls at
    /// `other`'s state would have written: a consumer of the kinematics of a state that
    /// another scratch evaluated (the right-hand side's last stage is the step's end) copies
    /// them instead of computing them again — the tree pass and one `sincos` per revolute
    /// joint. Allocates nothing when both come from the same model.
    pub fn copy_kinematics_from(&mut self, other: &Data) {
        fn vec<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
            if dst.len() == src.len() {
                crate::linalg::copy_short(dst, src);
            } else {
                dst.clear();
                dst.extend_from_slice(src);
            }
        }
        fn mat(dst: &mut DMatrix<Real>, src: &DMatrix<Real>) {
            if dst.shape() == src.shape() {
                dst.copy_from(src);
            } else {
                *dst = src.clone();
            }
        }
        fn col(dst: &mut DVector<Real>, src: &DVector<Real>) {
            if dst.len() == src.len() {
                dst.copy_from(src);
            } else {
                *dst = src.clone();
            }
        }
        self.time = other.time;
        vec(&mut self.joint_q, &other.joint_q);
        vec(&mut self.joint_qd, &other.joint_qd);
        vec(&mut self.joint_qdd_prescribed, &other.joint_qdd_prescribed);
        vec(&mut self.joint_frame, &other.joint_frame);
        vec(&mut self.subspace, &other.subspace);
        vec(&mut self.body_pose, &other.body_pose);
        vec(&mut self.body_com, &other.body_com);
        vec(&mut self.body_inertia, &other.body_inertia);
        vec(&mut self.body_twist, &other.body_twist);
        vec(&mut self.body_twist_remainder, &other.body_twist_remainder);
        vec(&mut self.body_accel_vp, &other.body_accel_vp);
        if other.constraint_pivots.is_empty() && self.constraint_pivots.is_empty() {
            // Holonomic: no constraint fields (all empty).
            return;
        }
        vec(&mut self.constraint_frame, &other.constraint_frame);
        mat(&mut self.constraint_rows, &other.constraint_rows);
        mat(&mut self.constraint_lu, &other.constraint_lu);
        vec(&mut self.constraint_pivots, &other.constraint_pivots);
        mat(&mut self.speed_map, &other.speed_map);
        col(&mut self.tree_speed, &other.tree_speed);
        col(&mut self.constraint_scratch, &other.constraint_scratch);
    }
}
