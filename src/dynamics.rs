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

use crate::articulated::ArticulatedFactor;
use crate::kinematics::{
    KinematicsError, check_len, move_joint, place_joint, update_positions, update_velocities,
};
use crate::linalg::product_into;
use crate::math::{Pose, Real, Vec2};
use crate::model::spatial::{Inertia, Twist, Wrench};
use crate::model::{Body, Joint, JointId, JointKind, Model};
use crate::state::Data;
use crate::tree_matrix::{TreeMatrix, TreePattern};

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

/// The factorization of the mass matrix, `M = Lᵀ L` [F, §6.5] with `L` lower triangular
/// and the sparsity of the tree ([`TreeMatrix::factor_ltl_from`]): for free bodies it is
/// diagonal by blocks, for a branched tree it has no entry beyond the ancestors of each
/// speed. When the pattern is the full triangle (a single chain of speeds, a nonholonomic
/// model) nothing is saved by the tree, and nalgebra's dense Cholesky `M = L Lᵀ` is used
/// instead: the same cost, and the results of the scenes recorded before the sparse
/// factor bit for bit (the two factorizations round differently; a one-ulp change of
/// `kane_double_pendulum`'s state then takes another event sequence, beyond its golden
/// file's margin). Its storage is allocated once, so that refactoring allocates nothing.
/// A long chain (from 9 links, [`articulated_pays`]) takes the articulated-body
/// factorization instead, `O(n)` in work and storage, without forming `M`
/// ([`ArticulatedFactor`]). The impact map solves `M x = b` with it for several
/// right-hand sides (`W = J M⁻¹ Jᵀ`, [P, Eq. (20)]).
#[derive(Clone, Debug)]
pub struct MassFactor {
    storage: FactorStorage,
    /// `true` if the storage holds the factor of the last mass matrix.
    valid: bool,
}

/// The factor of a [`MassFactor`].
#[derive(Clone, Debug)]
enum FactorStorage {
    /// `M = Lᵀ L` with the tree's sparsity.
    Tree(TreeMatrix),
    /// `M⁻¹ = Gᵀ D⁻¹ G` by the articulated-body algorithm, `O(n)`, for deep trees of
    /// holonomic models ([`ArticulatedFactor`]); `M` itself is not formed.
    Articulated(Box<ArticulatedFactor>),
    /// `M = L Lᵀ` dense for two speeds (the full `2 × 2` pattern), `[L₀₀, L₁₀, L₁₁]`: the
    /// operations of nalgebra's [`Cholesky`] and of its solves in the same order, on the
    /// stack ([`cholesky_2x2`]), so the same bits without the dynamic-size bookkeeping.
    Dense2([Real; 3]),
    /// `M = L Lᵀ` dense (a full pattern): the factor, or the buffer before the first one.
    Dense {
        chol: Option<Cholesky<Real, Dyn>>,
        spare: Option<DMatrix<Real>>,
        n: usize,
    },
}

impl MassFactor {
    /// The factor that `model` uses, with the sparsity `pattern` of its mass matrix
    /// ([`mass_pattern`]): the articulated-body one where [`articulated_pays`] says so,
    /// else [`Self::new`].
    pub fn for_model(model: &Model, pattern: TreePattern, allocate: bool) -> Self {
        if model.is_holonomic() && articulated_pays(&pattern) {
            Self::articulated(model)
        } else {
            Self::new(pattern, allocate)
        }
    }

    /// The articulated-body factor of a holonomic `model` ([`ArticulatedFactor`]),
    /// whatever its size. A nonholonomic model's speeds are not its tree's: use
    /// [`Self::for_model`].
    pub fn articulated(model: &Model) -> Self {
        MassFactor {
            storage: FactorStorage::Articulated(Box::new(ArticulatedFactor::new(model))),
            valid: false,
        }
    }

    /// `true` for the articulated-body factor, which [`factor_mass`] computes from the
    /// kinematics without the mass matrix.
    pub fn is_articulated(&self) -> bool {
        matches!(self.storage, FactorStorage::Articulated(_))
    }

    /// A factor of the sparsity `pattern`, not yet valid; its storage is allocated at the
    /// first factorization when `allocate` is false.
    pub fn new(pattern: TreePattern, allocate: bool) -> Self {
        let n = pattern.len();
        let storage = if n == 2 && pattern.entries() == 3 {
            FactorStorage::Dense2([0.0; 3])
        } else if pattern.entries() == n * (n + 1) / 2 {
            FactorStorage::Dense {
                chol: None,
                spare: allocate.then(|| DMatrix::zeros(n, n)),
                n,
            }
        } else if allocate {
            FactorStorage::Tree(TreeMatrix::zeros(pattern))
        } else {
            FactorStorage::Tree(TreeMatrix::unallocated(pattern))
        };
        MassFactor {
            storage,
            valid: false,
        }
    }

    /// `true` if it holds the factor of the last mass matrix.
    pub fn is_valid(&self) -> bool {
        self.valid
    }

    /// `M` rebuilt from the factor (dense, for tests: `Lᵀ L` or `L Lᵀ`), if factored.
    pub fn product(&self) -> Option<DMatrix<Real>> {
        if !self.valid {
            return None;
        }
        match &self.storage {
            FactorStorage::Tree(l) => {
                let l = l.to_dense_lower();
                Some(l.transpose() * l)
            }
            FactorStorage::Dense { chol, .. } => chol.as_ref().map(|c| {
                let l = c.l();
                &l * l.transpose()
            }),
            FactorStorage::Dense2([l00, l10, l11]) => {
                let l = DMatrix::from_row_slice(2, 2, &[*l00, 0.0, *l10, *l11]);
                Some(&l * l.transpose())
            }
            FactorStorage::Articulated(_) => None,
        }
    }

    /// The sparse factor `L` of `M = Lᵀ L`, if factored and the pattern is not full.
    pub fn tree_factor(&self) -> Option<&TreeMatrix> {
        match &self.storage {
            FactorStorage::Tree(l) if self.valid => Some(l),
            _ => None,
        }
    }

    /// Factors the symmetric matrix `m`.
    ///
    /// Returns the smallest eigenvalue of `m` if it is not positive definite (computed on
    /// that cold path only, for at most [`EIGENVALUE_EVIDENCE_MAX`] speeds; NaN beyond).
    #[inline]
    fn factor(&mut self, m: &TreeMatrix) -> Result<(), Real> {
        self.valid = false;
        let ok = match &mut self.storage {
            FactorStorage::Tree(l) => l.factor_ltl_from(m).is_ok(),
            FactorStorage::Dense2(l) => factor_2x2(m, l),
            FactorStorage::Dense { chol, spare, n } => {
                let mut buf = match (chol.take(), spare.take()) {
                    (Some(c), _) => c.unpack_dirty(),
                    (None, Some(buf)) => buf,
                    (None, None) => DMatrix::zeros(*n, *n),
                };
                // The lower triangle, which nalgebra's Cholesky reads.
                for i in 0..*n {
                    let mut j = i;
                    for &v in m.row(i) {
                        buf[(i, j)] = v;
                        j = j.wrapping_sub(1);
                    }
                }
                *chol = Cholesky::new(buf);
                chol.is_some()
            }
            // Factored from the kinematics (`factor_mass`), not from `m`.
            FactorStorage::Articulated(_) => false,
        };
        if ok {
            self.valid = true;
            Ok(())
        } else {
            Err(smallest_eigenvalue(m))
        }
    }

    /// `b ← F⁻¹ b` for the factor `F` of `M = F Fᵀ` (`F = Lᵀ` of the tree factor, `L` of
    /// the dense one): half of [`Self::solve_in_place`], which is
    /// [`Self::solve_factor_transpose_in_place`] after this. With `Y = F⁻¹ Jᵀ`,
    /// `J M⁻¹ Jᵀ = Yᵀ Y` (one triangular solve per column of `Jᵀ`, not two, and a symmetric
    /// product) and `M⁻¹ Jᵀ λ = F⁻ᵀ (Y λ)`.
    ///
    /// The factor of two speeds is solved inline ([`solve_lower_2x2`], the same operations
    /// as the general dispatch), the others out of line: a persistent contact's right-hand
    /// side makes two or three of these solves.
    #[inline]
    pub fn solve_factor_in_place(&mut self, b: &mut [Real]) -> Result<(), DynamicsError> {
        if let (true, FactorStorage::Dense2(l), [_, _]) = (self.valid, &self.storage, &*b) {
            solve_lower_2x2(l, b);
            return Ok(());
        }
        self.solve_factor_in_place_general(b)
    }

    /// [`Self::solve_factor_in_place`] of any factor.
    fn solve_factor_in_place_general(&mut self, b: &mut [Real]) -> Result<(), DynamicsError> {
        if !self.valid {
            return Err(DynamicsError::NotFactored);
        }
        match &mut self.storage {
            FactorStorage::Tree(l) => {
                check_len("right-hand side", l.nrows(), b.len())?;
                l.solve_lt(b);
            }
            FactorStorage::Articulated(a) => {
                check_len("right-hand side", a.nrows(), b.len())?;
                a.solve_factor_in_place(b);
            }
            FactorStorage::Dense2(l) => {
                check_len("right-hand side", 2, b.len())?;
                solve_lower_2x2(l, b);
            }
            FactorStorage::Dense { chol, n, .. } => {
                let chol = chol.as_ref().ok_or(DynamicsError::NotFactored)?;
                check_len("right-hand side", *n, b.len())?;
                (chol.l_dirty())
                    .solve_lower_triangular_unchecked_mut(&mut DVectorViewMut::from_slice(b, *n));
            }
        }
        Ok(())
    }

    /// `y ← F⁻ᵀ y`, the other half of [`Self::solve_in_place`] (see
    /// [`Self::solve_factor_in_place`]). The factor of two speeds inline, as there.
    #[inline]
    pub fn solve_factor_transpose_in_place(&mut self, y: &mut [Real]) -> Result<(), DynamicsError> {
        if let (true, FactorStorage::Dense2(l), [_, _]) = (self.valid, &self.storage, &*y) {
            solve_upper_2x2(l, y);
            return Ok(());
        }
        self.solve_factor_transpose_in_place_general(y)
    }

    /// [`Self::solve_factor_transpose_in_place`] of any factor.
    fn solve_factor_transpose_in_place_general(
        &mut self,
        y: &mut [Real],
    ) -> Result<(), DynamicsError> {
        if !self.valid {
            return Err(DynamicsError::NotFactored);
        }
        match &mut self.storage {
            FactorStorage::Tree(l) => {
                check_len("right-hand side", l.nrows(), y.len())?;
                l.solve_l(y);
            }
            FactorStorage::Articulated(a) => {
                check_len("right-hand side", a.nrows(), y.len())?;
                a.solve_factor_transpose_in_place(y);
            }
            FactorStorage::Dense2(l) => {
                check_len("right-hand side", 2, y.len())?;
                solve_upper_2x2(l, y);
            }
            FactorStorage::Dense { chol, n, .. } => {
                let chol = chol.as_ref().ok_or(DynamicsError::NotFactored)?;
                check_len("right-hand side", *n, y.len())?;
                (chol.l_dirty()).ad_solve_lower_triangular_unchecked_mut(
                    &mut DVectorViewMut::from_slice(y, *n),
                );
            }
        }
        Ok(())
    }

    /// Solves `M x = b` in place (`b` becomes `x`): `Lᵀ y = b` backward, then `L x = y`
    /// forward (`L y = b`, `Lᵀ x = y` for the dense factor).
    #[inline]
    pub fn solve_in_place(&mut self, b: &mut [Real]) -> Result<(), DynamicsError> {
        if !self.valid {
            return Err(DynamicsError::NotFactored);
        }
        match &mut self.storage {
            FactorStorage::Tree(l) => {
                check_len("right-hand side", l.nrows(), b.len())?;
                l.solve_ltl(b);
            }
            FactorStorage::Articulated(a) => {
                check_len("right-hand side", a.nrows(), b.len())?;
                a.solve_in_place(b);
            }
            FactorStorage::Dense2(l) => {
                check_len("right-hand side", 2, b.len())?;
                solve_lower_2x2(l, b);
                solve_upper_2x2(l, b);
            }
            FactorStorage::Dense { chol, n, .. } => {
                let chol = chol.as_ref().ok_or(DynamicsError::NotFactored)?;
                check_len("right-hand side", *n, b.len())?;
                chol.solve_mut(&mut DVectorViewMut::from_slice(b, *n));
            }
        }
        Ok(())
    }
}

/// The Cholesky factor `[L₀₀, L₁₀, L₁₁]` of the symmetric `2 × 2` matrix `[[m00, m10],
/// [m10, m11]]`, `M = L Lᵀ`, or `None` where nalgebra's [`Cholesky::new`] fails (a pivot
/// zero, negative or NaN):
///
/// ```text
/// L₀₀ = √m00,   L₁₀ = m10 / L₀₀,   L₁₁ = √(m11 − L₁₀ L₁₀)
/// ```
///
/// nalgebra's column algorithm for `n = 2` in its order of operations (its `axpy` adds
/// `(−L₁₀) L₁₀` to `m11`, the same number as the subtraction), so its bits: the recorded
/// runs of `kane_double_pendulum` depend on them (test
/// `the_2x2_cholesky_is_nalgebras_to_the_bit`).
#[doc(hidden)]
pub fn cholesky_2x2(m00: Real, m10: Real, m11: Real) -> Option<[Real; 3]> {
    // nalgebra's test: the pivot is not zero and `try_sqrt` takes it (`≥ 0`, not NaN),
    // that is `> 0`.
    let pivot_ok = |v: Real| v > 0.0;
    if !pivot_ok(m00) {
        return None;
    }
    let l00 = m00.sqrt();
    let l10 = m10 / l00;
    let d = m11 - l10 * l10;
    if !pivot_ok(d) {
        return None;
    }
    Some([l00, l10, d.sqrt()])
}

/// [`cholesky_2x2`] of the `2 × 2` matrix `m` (the full pattern of two speeds, stored as
/// `[M₀₀ | M₁₁, M₁₀]`, [`TreeMatrix::row`]) into `l`; `false` (and `l` unchanged) where it
/// fails or `m` has no storage.
#[inline(always)]
fn factor_2x2(m: &TreeMatrix, l: &mut [Real; 3]) -> bool {
    let &[m00, m11, m10] = m.values() else {
        return false;
    };
    match cholesky_2x2(m00, m10, m11) {
        Some(f) => {
            *l = f;
            true
        }
        None => false,
    }
}

/// The end of [`forward_dynamics_with`] for a factor of two speeds
/// ([`FactorStorage::Dense2`]), with the mass matrix and the bias forces in `data`: the
/// factorization ([`factor_mass_matrix`]), `u̇ = M⁻¹ (τ − h)` ([`MassFactor::solve_in_place`])
/// and its check, the same operations in the same order on the stack. Returns `None` if the
/// factor is not the `2 × 2` one.
#[inline(always)]
fn solve_2x2(data: &mut Data, t: Real, tau: Option<&[Real]>) -> Option<Result<(), DynamicsError>> {
    let Data {
        mass,
        mass_factor,
        bias,
        udot,
        ..
    } = data;
    let FactorStorage::Dense2(l) = &mut mass_factor.storage else {
        return None;
    };
    mass_factor.valid = false;
    if !factor_2x2(mass, l) {
        return Some(Err(DynamicsError::NotPositiveDefinite {
            t,
            min_eigenvalue: smallest_eigenvalue(mass),
        }));
    }
    mass_factor.valid = true;
    let h = &bias.as_slice()[..2];
    let mut x = match tau {
        Some(tau) => [tau[0] - h[0], tau[1] - h[1]],
        None => [0.0 - h[0], 0.0 - h[1]],
    };
    solve_lower_2x2(l, &mut x);
    solve_upper_2x2(l, &mut x);
    let udot = &mut udot.as_mut_slice()[..2];
    udot.copy_from_slice(&x);
    Some(check_finite(t, "udot", udot))
}

/// `b ← L⁻¹ b` for the `2 × 2` factor `l = [L₀₀, L₁₀, L₁₁]`, forward, as nalgebra's
/// `solve_lower_triangular_unchecked_mut`: `y₀ = b₀ / L₀₀`, `y₁ = (b₁ − y₀ L₁₀) / L₁₁`.
#[doc(hidden)]
pub fn solve_lower_2x2(l: &[Real; 3], b: &mut [Real]) {
    let y0 = b[0] / l[0];
    b[0] = y0;
    b[1] = (b[1] - y0 * l[1]) / l[2];
}

/// `y ← L⁻ᵀ y` for the `2 × 2` factor `l = [L₀₀, L₁₀, L₁₁]`, backward, as nalgebra's
/// `ad_solve_lower_triangular_unchecked_mut`: `x₁ = y₁ / L₁₁`, `x₀ = (y₀ − (0 + L₁₀ x₁)) /
/// L₀₀` (its dot product starts from `+0`, which turns a `−0` product into `+0`).
#[doc(hidden)]
pub fn solve_upper_2x2(l: &[Real; 3], y: &mut [Real]) {
    let x1 = y[1] / l[2];
    y[1] = x1;
    let dot = 0.0 + l[1] * x1;
    y[0] = (y[0] - dot) / l[0];
}

/// The fewest speeds for which a holonomic model whose speeds are on average at depth
/// 4 or more (a chain of 9 links or more, a tree with long branches) is factored by the
/// articulated-body algorithm, `O(n)`, rather than by the Cholesky factorization of `M`,
/// `O(n³)` for a chain. Measured with
/// `cargo bench -p ricochet-benches --bench rhs -- rhs_factor`
/// (`forward_dynamics` of an `n`-link chain with each factor, median ns): 4 links 289
/// dense / 321 articulated, 8 links 701 / 634, 16 links 1,884 / 1,289, 32 links
/// 5,913 / 2,557, 256 links 818,688 / 21,384.
pub const ARTICULATED_MIN_SPEEDS: usize = 8;

/// `true` if the articulated-body factor is the cheaper one for the mass-matrix sparsity
/// `pattern`: at least [`ARTICULATED_MIN_SPEEDS`] speeds and a factor of `M` that would
/// hold five entries per speed or more (`Σ (depth + 1) ≥ 5 n`). Free bodies and shallow
/// trees keep the sparse `LᵀL` factor, chains of up to 8 links the dense one (and the
/// bit-for-bit results recorded with it: `kane_double_pendulum`, `chain` at 8 links).
pub fn articulated_pays(pattern: &TreePattern) -> bool {
    let n = pattern.len();
    n >= ARTICULATED_MIN_SPEEDS && pattern.entries() >= 5 * n
}

/// The largest mass matrix whose smallest eigenvalue a failed factorization reports (a
/// dense eigen-decomposition, `O(n³)`).
pub const EIGENVALUE_EVIDENCE_MAX: usize = 1000;

/// The smallest eigenvalue of a symmetric matrix (the evidence of a failed factorization).
#[cold]
fn smallest_eigenvalue(m: &TreeMatrix) -> Real {
    if m.nrows() > EIGENVALUE_EVIDENCE_MAX || m.values().iter().any(|x| !x.is_finite()) {
        return Real::NAN;
    }
    SymmetricEigen::new(m.to_dense())
        .eigenvalues
        .iter()
        .copied()
        .fold(Real::INFINITY, Real::min)
}

/// The sparsity of the mass matrix of `model`: the expanded parent array of its speeds
/// [F, §6.4] for a holonomic model (a joint's speeds in a row, the first one's parent the
/// last speed of the nearest ancestor joint that has speeds), dense for a nonholonomic one
/// (`M = Sᵀ M_v S` couples the speeds the constraints mix).
pub fn mass_pattern(model: &Model) -> TreePattern {
    if !model.is_holonomic() {
        return TreePattern::dense(model.nu());
    }
    let joints = model.joints();
    let mut parent = vec![None; model.nu()];
    // The last speed of each joint, or of its nearest ancestor that has speeds.
    let mut last: Vec<Option<usize>> = Vec::with_capacity(joints.len());
    for (i, joint) in joints.iter().enumerate() {
        let up = joint
            .parent
            .and_then(|p| last.get(p.index()).copied().flatten());
        match model.q_index(JointId(i)) {
            Some(s) => {
                let nd = joint.kind.ndof();
                for k in 0..nd {
                    parent[s + k] = if k == 0 { up } else { Some(s + k - 1) };
                }
                last.push(Some(s + nd - 1));
            }
            None => last.push(up),
        }
    }
    // The builder puts parents before children and numbers the speeds in joint order.
    TreePattern::new(&parent).unwrap_or_else(|| TreePattern::dense(model.nu()))
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
/// [`crate::model::spatial::Inertia::projected_at`]). Cost: `O(n·depth)`. Only the
/// entries of a speed and its ancestors are non-zero; `data.mass` stores those alone
/// ([`TreeMatrix`], [`mass_pattern`]).
///
/// Requires [`update_positions`]. Writes `data.composite` and `data.mass` (allocating its
/// storage if the workspace was built without it, [`Data::for_kinematics`]).
pub fn mass_matrix(model: &Model, data: &mut Data) {
    if model.is_holonomic() {
        let Data {
            mass,
            composite,
            body_inertia,
            joint_frame,
            subspace,
            ..
        } = data;
        // Every stored entry is set below (a speed's row holds exactly the speeds on its
        // path to the root), so the matrix needs its storage, not zeros.
        mass.allocate();
        let kin = (&joint_frame[..], &subspace[..], &body_inertia[..]);
        tree_mass_matrix(model, kin, composite, |r, c, m| mass.set_ancestor(r, c, m));
    } else {
        // M = Sᵀ M_v S  (Kane's generalized inertia forces in the speeds u).
        let mut mass_tree = std::mem::take(&mut data.mass_tree);
        mass_tree.fill(0.0);
        let kin = (
            &data.joint_frame[..],
            &data.subspace[..],
            &data.body_inertia[..],
        );
        tree_mass_matrix(model, kin, &mut data.composite, |r, c, m| {
            mass_tree[(r, c)] = m;
            mass_tree[(c, r)] = m;
        });
        // M_v S in kept storage, with the same bits on every machine (nalgebra's `gemm`
        // hands a product of more than 5 speeds to `matrixmultiply`, which allocates and
        // picks its kernel from the processor: `linalg::product_into`).
        product_into(&mass_tree, &data.speed_map, &mut data.mass_map);
        data.mass_dense
            .gemm_tr(1.0, &data.speed_map, &data.mass_map, 0.0);
        // Exactly symmetric: the lower triangle is stored.
        data.mass.copy_lower_from(&data.mass_dense);
        data.mass_tree = mass_tree;
    }
}

/// The composite rigid body algorithm of [`mass_matrix`] over the tree speeds: `set(r, c,
/// M_rc)` for every speed `r` and `c = r` or an ancestor of `r` in the expanded parent
/// array ([`mass_pattern`]); the other entries are zero.
fn tree_mass_matrix(
    model: &Model,
    (frames, subspace, body_inertia): (&[Pose], &[[Twist; 3]], &[Inertia]),
    composite: &mut [Inertia],
    set: impl FnMut(usize, usize, Real),
) {
    let joints = model.joints();
    let n = joints.len();
    // Sliced to the number of joints once: no bounds checks in the loops.
    let (frames, composite) = (&frames[..n], &mut composite[..n]);
    // Composite inertias, leaves first.
    composite.copy_from_slice(&body_inertia[..n]);
    for (i, joint) in joints.iter().enumerate().rev() {
        if let Some(p) = joint.parent {
            composite[p.index()] += presented_inertia(joint.kind, &composite[i], &frames[i]);
        }
    }
    mass_rows(model, (frames, subspace), composite, set);
}

/// The composite inertia `I^c` of the subtree of a joint's body (of kind `kind`) as its
/// parent sees it:
/// `P_cᵀ I^c P_c`, the point mass at the joint for an absolute joint (whose frame is
/// `frame`), `I^c` itself otherwise ([`mass_matrix`]).
#[inline(always)]
fn presented_inertia(kind: JointKind, composite: &Inertia, frame: &Pose) -> Inertia {
    if kind.is_absolute() {
        composite.projected_at(frame.translation)
    } else {
        *composite
    }
}

/// The rows of the composite rigid body algorithm of [`mass_matrix`] from the composite
/// inertias `composite`: `set(r, c, M_rc)` for every speed `r` and `c = r` or an ancestor
/// of `r` ([`mass_row`]).
#[inline(always)]
fn mass_rows(
    model: &Model,
    kin: (&[Pose], &[[Twist; 3]]),
    composite: &[Inertia],
    mut set: impl FnMut(usize, usize, Real),
) {
    let joints = model.joints();
    let composite = &composite[..joints.len()];
    for (i, joint) in joints.iter().enumerate() {
        let Some(si) = model.q_index(JointId(i)) else {
            continue;
        };
        for k in 0..joint.kind.ndof() {
            let at = (i, joint.kind, si);
            mass_row(model, kin, at, k, &composite[i], |c, _, m| {
                set(si + k, c, m)
            });
        }
    }
}

/// Row `r = s + k` of the mass matrix, the speed `k` of joint `i` (of kind `kind`, its
/// first speed `s`) whose subtree has the composite inertia `composite` [F, §6.2]: the
/// wrench `f = I^c S_k` walked up to the root (through `P_cᵀ` at each absolute joint),
///
/// ```text
/// M_rc = S_cᵀ f        (c = r and each ancestor of r in the expanded parent array)
/// ```
///
/// `set(c, d, M_rc)` for each, with `d = depth(r) − depth(c)` the entry's place in the row
/// of a [`TreeMatrix`] (the diagonal first).
#[inline(always)]
fn mass_row(
    model: &Model,
    (frames, subspace): (&[Pose], &[[Twist; 3]]),
    (i, kind, first): (usize, JointKind, usize),
    k: usize,
    composite: &Inertia,
    mut set: impl FnMut(usize, usize, Real),
) {
    let joints = model.joints();
    let s_i = &subspace[i];
    // This joint's speeds up to r: depth(r) − depth(s + k2) = k − k2.
    let mut f = composite.mul_twist(&s_i[k]);
    for (k2, s) in s_i[..=k].iter().enumerate() {
        set(first + k2, k - k2, s.dot(&f));
    }
    // The ancestors' speeds, each joint's last speed first in the row.
    let mut depth = k + 1;
    let (mut b, mut absolute) = (i, kind.is_absolute());
    while let Some(p) = joints[b].parent {
        if absolute {
            f = f.projected_at(frames[b].translation);
        }
        b = p.index();
        absolute = joints[b].is_absolute();
        if let Some(sp) = model.q_index(JointId(b)) {
            let nd = joints[b].kind.ndof();
            for (k2, s) in subspace[b][..nd].iter().enumerate() {
                set(sp + k2, depth + (nd - 1 - k2), s.dot(&f));
            }
            depth += nd;
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
    let n = joints.len();
    let g = model.gravity();
    let Data {
        joint_frame,
        subspace,
        joint_qdd_prescribed,
        body_inertia,
        body_twist,
        body_com,
        body_accel_vp,
        body_accel,
        body_wrench,
        joint_effort,
        udot,
        tree_accel,
        ..
    } = data;
    // The free coordinates' accelerations, or none (`u̇ = 0`: the prescribed `q̈_p`, zero
    // for a free joint, stand in).
    let free_accel: Option<&[Real]> = match accel {
        FreeAccel::Zero => None,
        FreeAccel::Given(udot) => Some(udot),
        FreeAccel::Solved if model.is_holonomic() => Some(udot.as_slice()),
        FreeAccel::Solved => Some(tree_accel.as_slice()),
    };
    // Sliced to the number of joints once: no bounds checks in the loops.
    let (joint_frame, subspace) = (&joint_frame[..n], &subspace[..n]);
    let joint_qdd_prescribed = &joint_qdd_prescribed[..n];
    let (body_inertia, body_twist, body_com) =
        (&body_inertia[..n], &body_twist[..n], &body_com[..n]);
    let body_accel_vp = &body_accel_vp[..n];
    let (body_accel, body_wrench) = (&mut body_accel[..n], &mut body_wrench[..n]);
    let joint_effort = &mut joint_effort[..n];
    // Forward: accelerations and the net wrench each body needs.
    for (i, joint) in joints.iter().enumerate() {
        let parent = match joint.parent {
            Some(p) => body_accel[p.index()],
            None => Twist::ZERO,
        };
        let nd = joint.kind.ndof();
        let qdd = match (model.q_index(JointId(i)), free_accel) {
            (Some(first), Some(acc)) => &acc[first..first + nd],
            _ => &joint_qdd_prescribed[i][..],
        };
        let (a, f) = accelerate_body(
            joint.kind,
            parent,
            (&joint_frame[i], &subspace[i]),
            body_accel_vp[i],
            qdd,
            (&body_inertia[i], &body_twist[i], body_com[i]),
            g,
        );
        body_accel[i] = a;
        body_wrench[i] = f;
    }
    // Backward: joint efforts, and the wrench passed on to the parent.
    for (i, joint) in joints.iter().enumerate().rev() {
        let f = effort_and_reaction(
            joint.kind,
            &body_wrench[i],
            (&joint_frame[i], &subspace[i]),
            &mut joint_effort[i],
        );
        if let Some(p) = joint.parent {
            body_wrench[p.index()] += f;
        }
    }
}

/// One body of the forward pass of [`newton_euler`] (its joint of kind `kind`): its spatial
/// acceleration from its
/// parent's `parent` (zero for a root), the joint frame and motion subspace, the
/// velocity-product acceleration `c` and the joint accelerations `qdd` (the first `ndof`
/// are used), and the net wrench its inertia, twist `v` and centre of mass `com` need,
///
/// ```text
/// A_b = P_b A_parent + c_b + Σ S_k q̈_k
/// F_b = I_b A_b + V_b ×* (I_b V_b) − (c_b × m_b g, m_b g)
/// ```
#[inline(always)]
fn accelerate_body(
    kind: JointKind,
    parent: Twist,
    (frame, s): (&Pose, &[Twist; 3]),
    c: Twist,
    qdd: &[Real],
    (inertia, v, com): (&Inertia, &Twist, Vec2),
    g: Vec2,
) -> (Twist, Wrench) {
    let mut a = parent;
    if kind.is_absolute() {
        a = a.projected_at(frame.translation);
    }
    a += c;
    for (s_k, qdd_k) in s.iter().take(kind.ndof()).zip(qdd) {
        a += *s_k * *qdd_k;
    }
    let weight = Wrench::force_at(g * inertia.m, com);
    let f = inertia.mul_twist(&a) + v.cross_force(&inertia.mul_twist(v)) - weight;
    (a, f)
}

/// One joint of the backward pass of [`newton_euler`] (of kind `kind`): the efforts `effort_k = S_kᵀ F_b`
/// of the body's net wrench `f` into the first `ndof` entries of `effort` (the others are
/// left as they are), and the wrench `P_bᵀ F_b` passed on to the parent.
#[inline(always)]
fn effort_and_reaction(
    kind: JointKind,
    f: &Wrench,
    (frame, s): (&Pose, &[Twist; 3]),
    effort: &mut [Real; 3],
) -> Wrench {
    for (e_k, s_k) in effort.iter_mut().zip(s).take(kind.ndof()) {
        *e_k = s_k.dot(f);
    }
    if kind.is_absolute() {
        f.projected_at(frame.translation)
    } else {
        *f
    }
}

/// Writes the generalized forces of the free coordinates, `out = effort − Q_force` with
/// `Q_force = −k (q − q_rest) − c q̇ + τ` the joint force elements.
fn gather_free(model: &Model, data: &Data, out: &mut [Real]) {
    let joints = model.joints();
    let n = joints.len();
    let (joint_effort, joint_q, joint_qd) = (
        &data.joint_effort[..n],
        &data.joint_q[..n],
        &data.joint_qd[..n],
    );
    for (i, joint) in joints.iter().enumerate() {
        if let Some(s) = model.q_index(JointId(i)) {
            let e = &joint_effort[i];
            free_forces((joint, joint.kind), e, (&joint_q[i], &joint_qd[i]), s, out);
        }
    }
}

/// One joint of [`gather_free`] (`joint`, of kind `kind` = `joint.kind`): `out[s..s +
/// ndof] = effort − Q_force` for the joint coordinates and rates `(q, qd)`.
#[inline(always)]
fn free_forces(
    (joint, kind): (&Joint, JointKind),
    e: &[Real; 3],
    (q, qd): (&[Real; 3], &[Real; 3]),
    s: usize,
    out: &mut [Real],
) {
    // Entry by entry: `copy_from_slice` of an unknown length calls `memcpy`.
    match &mut out[s..s + kind.ndof()] {
        [o0] => *o0 = e[0] - joint.force.generalized_force(q[0], qd[0]),
        [o0, o1] => [*o0, *o1] = [e[0], e[1]],
        [o0, o1, o2] => [*o0, *o1, *o2] = [e[0], e[1], e[2]],
        _ => {}
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
    // Kinematics, h(t, q, u), the factor of M(q).
    if model.is_holonomic() && !data.mass_factor.is_articulated() {
        tree_pass(model, data, t, q, u);
        if let Some(done) = solve_2x2(data, t, tau) {
            return done;
        }
        factor_mass_matrix(data, t)?;
    } else {
        update_positions(model, data, t, q)?;
        update_velocities(model, data, u)?;
        bias_forces(model, data);
        factor_mass(model, data, t)?;
    }
    // u̇ = M⁻¹ (τ − h).
    let (udot, bias) = (data.udot.as_mut_slice(), data.bias.as_slice());
    match tau {
        Some(tau) => {
            for ((x, t), h) in udot.iter_mut().zip(tau).zip(bias) {
                *x = t - h;
            }
        }
        None => {
            for (x, h) in udot.iter_mut().zip(bias) {
                *x = 0.0 - h;
            }
        }
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

/// [`update_positions`], [`update_velocities`], [`bias_forces`] and [`mass_matrix`] of a
/// holonomic model in one walk down the tree and one walk up, the stages of
/// [`forward_dynamics_with`] before the factorization: down, each joint's positions, its
/// velocities and the forward pass of the Newton–Euler algorithm [F, §5.3] (with `u̇ = 0`);
/// up, the backward pass (the joint efforts and the bias forces `h`) and the composite
/// inertias [F, §6.2]; then the rows of `M`.
///
/// Each joint goes through the same kernels as in the separate stages ([`place_joint`],
/// [`move_joint`], [`accelerate_body`], [`effort_and_reaction`], [`presented_inertia`],
/// [`free_forces`], [`mass_rows`]), in the same order, so every number is the one the
/// stages give, bit for bit; what is saved is walking the tree four times and reloading
/// every joint's kinematics from the workspace between the stages.
///
/// Writes what the four stages write: `data.time`, every kinematics field, the Newton–Euler
/// scratch, `data.bias`, `data.composite` and `data.mass`.
fn tree_pass(model: &Model, data: &mut Data, t: Real, q: &[Real], u: &[Real]) {
    data.time = t;
    let n = model.joints().len();
    let Data {
        joint_q,
        joint_qd,
        joint_qdd_prescribed,
        joint_frame,
        subspace,
        body_pose,
        body_com,
        body_inertia,
        body_twist,
        body_twist_remainder,
        body_accel_vp,
        body_accel,
        body_wrench,
        composite,
        joint_effort,
        mass,
        bias,
        ..
    } = data;
    // Every per-joint array sliced to the number of joints once: no bounds checks in the
    // loops.
    let mut tree = TreePass {
        model,
        t,
        q,
        u,
        joint_q: &mut joint_q[..n],
        joint_qd: &mut joint_qd[..n],
        joint_qdd_prescribed: &mut joint_qdd_prescribed[..n],
        joint_frame: &mut joint_frame[..n],
        subspace: &mut subspace[..n],
        body_pose: &mut body_pose[..n],
        body_com: &mut body_com[..n],
        body_inertia: &mut body_inertia[..n],
        body_twist: &mut body_twist[..n],
        body_twist_remainder: &mut body_twist_remainder[..n],
        body_accel_vp: &mut body_accel_vp[..n],
        body_accel: &mut body_accel[..n],
        body_wrench: &mut body_wrench[..n],
        composite: &mut composite[..n],
        joint_effort: &mut joint_effort[..n],
        bias: bias.as_mut_slice(),
        mass,
    };
    // Down: positions, velocities, accelerations at u̇ = 0 and the net wrenches. Each
    // joint's code is that of its kind alone for the revolute joints (the kind a literal).
    let bodies = &model.bodies()[..n];
    for (i, (joint, body)) in model.joints().iter().zip(bodies).enumerate() {
        match joint.kind {
            JointKind::Revolute { absolute: false } => {
                tree.down((i, joint, JointKind::Revolute { absolute: false }), body);
            }
            JointKind::Revolute { absolute: true } => {
                tree.down((i, joint, JointKind::Revolute { absolute: true }), body);
            }
            kind => tree.down((i, joint, kind), body),
        }
    }
    // Up: the joint efforts and h, the rows of M, the wrenches and composite inertias passed
    // on. Every stored entry of M is set: the matrix needs its storage, not zeros.
    tree.mass.allocate();
    for (i, joint) in model.joints().iter().enumerate().rev() {
        match joint.kind {
            JointKind::Revolute { absolute: false } => {
                tree.up((i, joint, JointKind::Revolute { absolute: false }));
            }
            JointKind::Revolute { absolute: true } => {
                tree.up((i, joint, JointKind::Revolute { absolute: true }));
            }
            kind => tree.up((i, joint, kind)),
        }
    }
}

/// The state of [`tree_pass`]: the model, the state and the workspace's per-joint arrays.
struct TreePass<'a> {
    model: &'a Model,
    t: Real,
    q: &'a [Real],
    u: &'a [Real],
    joint_q: &'a mut [[Real; 3]],
    joint_qd: &'a mut [[Real; 3]],
    joint_qdd_prescribed: &'a mut [[Real; 3]],
    joint_frame: &'a mut [Pose],
    subspace: &'a mut [[Twist; 3]],
    body_pose: &'a mut [Pose],
    body_com: &'a mut [Vec2],
    body_inertia: &'a mut [Inertia],
    body_twist: &'a mut [Twist],
    body_twist_remainder: &'a mut [Twist],
    body_accel_vp: &'a mut [Twist],
    body_accel: &'a mut [Twist],
    body_wrench: &'a mut [Wrench],
    composite: &'a mut [Inertia],
    joint_effort: &'a mut [[Real; 3]],
    bias: &'a mut [Real],
    mass: &'a mut TreeMatrix,
}

impl TreePass<'_> {
    /// Joint `i` (`joint`, of kind `kind`, carrying `body`) on the way down: its positions,
    /// velocities, acceleration at `u̇ = 0` and net wrench, after its parent's.
    #[inline(always)]
    fn down(&mut self, (i, joint, kind): (usize, &Joint, JointKind), body: &Body) {
        let (pose, vp, vp_rem, ap) = match joint.parent {
            Some(p) => {
                let p = p.index();
                (
                    self.body_pose[p],
                    self.body_twist[p],
                    self.body_twist_remainder[p],
                    self.body_accel[p],
                )
            }
            None => (Pose::IDENTITY, Twist::ZERO, Twist::ZERO, Twist::ZERO),
        };
        let (model, t) = (self.model, self.t);
        // Each stage's results stored as soon as they are known, so that fewer of them are
        // held (spilled) across the next stage.
        let place = place_joint(model, (i, joint, kind), body, t, self.q, &pose);
        self.joint_q[i] = place.q;
        self.joint_qdd_prescribed[i] = place.qdd;
        self.joint_frame[i] = place.frame;
        self.subspace[i] = place.subspace;
        self.body_pose[i] = place.pose;
        self.body_com[i] = place.com;
        self.body_inertia[i] = place.inertia;
        self.composite[i] = place.inertia;
        let at = (
            place.frame.translation,
            &place.subspace,
            place.pose.translation,
        );
        let motion = move_joint(model, (i, joint, kind), t, self.u, (vp, vp_rem), at);
        self.joint_qd[i] = motion.qd;
        self.body_twist[i] = motion.twist;
        self.body_twist_remainder[i] = motion.remainder;
        self.body_accel_vp[i] = motion.accel_vp;
        let at = (&place.frame, &place.subspace);
        let body = (&place.inertia, &motion.twist, place.com);
        let g = model.gravity();
        let (a, f) = accelerate_body(kind, ap, at, motion.accel_vp, &place.qdd, body, g);
        self.body_accel[i] = a;
        self.body_wrench[i] = f;
    }

    /// Joint `i` (`joint`, of kind `kind`) on the way up, after its children: its efforts,
    /// its speeds' bias forces and rows of `M` (its composite inertia is complete), and the
    /// wrench and composite inertia its parent gets.
    #[inline(always)]
    fn up(&mut self, (i, joint, kind): (usize, &Joint, JointKind)) {
        let at = (&self.joint_frame[i], &self.subspace[i]);
        let f = effort_and_reaction(kind, &self.body_wrench[i], at, &mut self.joint_effort[i]);
        if let Some(s) = self.model.q_index(JointId(i)) {
            let e = &self.joint_effort[i];
            let rates = (&self.joint_q[i], &self.joint_qd[i]);
            free_forces((joint, kind), e, rates, s, self.bias);
            let kin = (&self.joint_frame[..], &self.subspace[..]);
            for k in 0..kind.ndof() {
                // The row's entries in the order of its storage (`TreeMatrix::row`).
                let row = self.mass.row_mut(s + k);
                let at = (i, kind, s);
                mass_row(self.model, kin, at, k, &self.composite[i], |_, d, m| {
                    row[d] = m
                });
            }
        }
        if let Some(p) = joint.parent {
            let p = p.index();
            self.body_wrench[p] += f;
            let ic = presented_inertia(kind, &self.composite[i], &self.joint_frame[i]);
            self.composite[p] += ic;
        }
    }
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
#[inline]
pub fn coordinate_rates(model: &Model, data: &Data, u: &[Real], qdot: &mut [Real]) {
    if model.is_holonomic() {
        crate::linalg::copy_short(qdot, u);
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

/// Solves `M x = b` in place with the factor of the last [`forward_dynamics`] or
/// [`factor_mass`] (`b` becomes `x`). For the impact map: `Δu = M⁻¹ Jᵀ I` [P, Eq. (16)],
/// `W = J M⁻¹ Jᵀ` [P, Eq. (20)].
pub fn solve_mass(data: &mut Data, b: &mut [Real]) -> Result<(), DynamicsError> {
    data.mass_factor.solve_in_place(b)
}

/// Factors the mass matrix at the positions of the last [`update_positions`]: the
/// articulated-body factor straight from the kinematics, or [`mass_matrix`] then its
/// Cholesky factorization. `t` is reported in errors. Allocates nothing (but the evidence
/// of a failure).
///
/// Writes `data.mass_factor`, and `data.mass` and `data.composite` unless the factor is
/// the articulated-body one.
pub fn factor_mass(model: &Model, data: &mut Data, t: Real) -> Result<(), DynamicsError> {
    let Data {
        mass_factor,
        joint_frame,
        subspace,
        body_inertia,
        ..
    } = data;
    if let FactorStorage::Articulated(a) = &mut mass_factor.storage {
        mass_factor.valid = false;
        if a.factor(model, joint_frame, subspace, body_inertia).is_ok() {
            mass_factor.valid = true;
            return Ok(());
        }
        // The evidence: the mass matrix's smallest eigenvalue (cold, allocating).
        mass_matrix(model, data);
        return Err(DynamicsError::NotPositiveDefinite {
            t,
            min_eigenvalue: smallest_eigenvalue(&data.mass),
        });
    }
    mass_matrix(model, data);
    factor_mass_matrix(data, t)
}

/// Factors the mass matrix already in `data.mass` (after [`mass_matrix`]) without solving
/// the dynamics. `t` is reported in errors. A workspace that held the articulated-body
/// factor gets a factor of `M` instead (allocating once); [`factor_mass`] needs no `M`.
#[inline]
pub fn factor_mass_matrix(data: &mut Data, t: Real) -> Result<(), DynamicsError> {
    if data.mass_factor.is_articulated() {
        data.mass_factor = MassFactor::new(data.mass.pattern().clone(), true);
    }
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

/// `false` if [`power`] is zero whatever the state: no free joint of one coordinate has a
/// damper or a constant effort, and no joint is prescribed. Each term of such a joint is
/// then `0 · q̇ (· q̇)`, a zero (of either sign: `q̇` is finite, [`forward_dynamics`] checked
/// it) that leaves the sums at `+0` bit for bit, so a caller may take [`Power::default`]
/// instead (the right-hand side of the run, `sim::system::MotionSystem`).
pub fn has_power(model: &Model) -> bool {
    model.joints().iter().any(|joint| {
        joint.drive.is_some()
            || (joint.kind.ndof() == 1 && (joint.force.damping != 0.0 || joint.force.effort != 0.0))
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
    let joints = model.joints();
    let joint_qd = &data.joint_qd[..joints.len()];
    let mut driven = false;
    for (joint, qd) in joints.iter().zip(joint_qd) {
        if joint.drive.is_none() && joint.kind.ndof() == 1 {
            let qd = qd[0];
            p.damping -= joint.force.damping * qd * qd;
            p.applied += joint.force.effort * qd;
        }
        driven |= joint.drive.is_some();
    }
    if driven {
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
