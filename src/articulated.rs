//! [`ArticulatedFactor`]: the mass matrix of a holonomic tree inverted in `O(n)` by the
//! articulated-body algorithm [F, §7.3], without forming `M`.
//!
//! The articulated-body algorithm with zero velocities and no gravity solves `M x = b` for
//! any generalized force `b`. Its first sweep (leaves to root) depends on the positions
//! alone, so it is the *factorization*: for each joint `i` with the motion subspace
//! `Sᵢ` (`3 × nᵢ`, world coordinates referred to `O`, as in [`crate::model::spatial`]),
//!
//! ```text
//! Iᴬᵢ = Iᵢ + Σ_{children c} Pcᵀ Iᵃc Pc          (Pc = 1, or the projection P(a) of an absolute joint)
//! Uᵢ  = Iᴬᵢ Sᵢ,   Dᵢ = Sᵢᵀ Uᵢ = Cᵢ Cᵢᵀ,   Kᵢ = Uᵢ Dᵢ⁻¹
//! Iᵃᵢ = Iᴬᵢ − Kᵢ Uᵢᵀ
//! ```
//!
//! and each solve is two sweeps of `O(n)`:
//!
//! ```text
//! backward (G):   pᵢ = Σ_c Pcᵀ (pc + Kc uc),   uᵢ = bᵢ − Sᵢᵀ pᵢ
//! middle (D⁻¹):   vᵢ = Dᵢ⁻¹ uᵢ
//! forward (Gᵀ):   a′ᵢ = Pᵢ a_parent,   xᵢ = vᵢ − Kᵢᵀ a′ᵢ,   aᵢ = a′ᵢ + Sᵢ xᵢ
//! ```
//!
//! (`τᵢ = Sᵢᵀ (Iᴬᵢ aᵢ + pᵢ)` solved for the joint accelerations `xᵢ`, [F, Eq. (7.38)–(7.42)]
//! with `c = 0`, `pᴬ` the bias of the applied forces only). The forward sweep is the
//! transpose of the backward one (differentiate the backward recursion in reverse: its
//! adjoint is the forward recursion), so `M⁻¹ = Gᵀ D⁻¹ G`, the *innovations
//! factorization* of Rodriguez, Jain and Kreutz-Delgado. With `D = C Cᵀ` blockwise this
//! gives the factor `M = F Fᵀ`, `F⁻¹ = C⁻¹ G`, that the persistent-contact stage uses for
//! `J M⁻¹ Jᵀ = Yᵀ Y` with `Y = F⁻¹ Jᵀ` (one sweep per column instead of a full solve).
//!
//! Storage and work are `O(n)`, against `O(n²)` entries and `O(n³)` work for the factor of
//! a chain's dense mass matrix. The 3-vectors are twists `(ω, v_O)` and wrenches
//! `(n_O, f)` in the component order of [`crate::model::spatial`]; a joint's `nᵢ ≤ 3`
//! speeds fill the first `nᵢ` entries of a padded 3-vector, and `Dᵢ` is padded with the
//! identity so that one 3 × 3 Cholesky factorization (nalgebra's) serves every joint with
//! more than one speed (a hinge's `Dᵢ` is a number).

use nalgebra::{Matrix3, Vector3};

use crate::math::{Pose, Real, Vec2};
use crate::model::spatial::{Inertia, Twist};
use crate::model::{JointId, Model};

/// The spatial inertia `I` as a symmetric 3 × 3 matrix acting on `(ω, v_x, v_y)`:
/// `I V = (I_O ω + h × v, m v + ω perp(h))` ([`Inertia::mul_twist`]).
#[doc(hidden)]
pub fn inertia_matrix(i: &Inertia) -> Matrix3<Real> {
    let (hx, hy) = (i.h.x, i.h.y);
    Matrix3::new(
        i.i_o, -hy, hx, //
        -hy, i.m, 0.0, //
        hx, 0.0, i.m,
    )
}

/// The projection `P(a)` of an absolute revolute joint at `a` ([`Twist::projected_at`]):
/// `(ω, v) ↦ (0, v + ω perp(a))`.
#[doc(hidden)]
pub fn projection_matrix(a: Vec2) -> Matrix3<Real> {
    Matrix3::new(
        0.0, 0.0, 0.0, //
        -a.y, 1.0, 0.0, //
        a.x, 0.0, 1.0,
    )
}

#[doc(hidden)]
pub fn twist_vector(s: &Twist) -> Vector3<Real> {
    Vector3::new(s.w, s.v.x, s.v.y)
}

/// `P(a) x` for a twist `x`.
#[inline]
#[doc(hidden)]
pub fn project_twist(a: Vec2, x: &Vector3<Real>) -> Vector3<Real> {
    Vector3::new(0.0, x[1] - a.y * x[0], x[2] + a.x * x[0])
}

/// `P(a)ᵀ f` for a wrench `f`: `(a × f, f)`.
#[inline]
#[doc(hidden)]
pub fn project_wrench(a: Vec2, f: &Vector3<Real>) -> Vector3<Real> {
    Vector3::new(a.x * f[2] - a.y * f[1], f[1], f[2])
}

/// The per-joint part of the factor.
#[derive(Clone, Debug, Default)]
struct Link {
    /// The parent joint, `usize::MAX` for a root.
    parent: usize,
    /// The point of an absolute revolute joint, whose projection carries the parent's
    /// motion to this body.
    projection: Option<Vec2>,
    /// The first speed of the joint, and the number `nᵢ` of its free speeds (0 for a
    /// weld or a prescribed joint).
    speed: usize,
    n: usize,
    /// The columns of `Sᵢ` (twists); those beyond `nᵢ` unused.
    s: [Vector3<Real>; 3],
    /// The columns of `Kᵢ = Uᵢ Dᵢ⁻¹` (wrenches per unit speed); those beyond `nᵢ` unused.
    k: [Vector3<Real>; 3],
    /// The lower Cholesky factor `Cᵢ` of `Dᵢ`, in its top-left `nᵢ × nᵢ` block.
    c: Matrix3<Real>,
}

/// No parent.
const ROOT: usize = usize::MAX;

/// The articulated-body factorization of the mass matrix of a holonomic model (see the
/// module docs). Allocated once for the model; factoring and solving allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct ArticulatedFactor {
    links: Vec<Link>,
    /// The number of speeds `n`.
    nu: usize,
    /// Scratch: the articulated inertias during the factorization.
    inertia: Vec<Matrix3<Real>>,
    /// Scratch: the bias wrenches `pᵢ` of the backward sweep, the accelerations `aᵢ` of
    /// the forward one.
    sweep: Vec<Vector3<Real>>,
}

/// A joint whose articulated inertia along its own subspace `Dᵢ` is not positive
/// definite: `M` is not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotPositiveDefinite {
    /// The joint.
    pub joint: usize,
}

impl ArticulatedFactor {
    /// The factor's storage for `model` (holonomic: its speeds are the tree's).
    pub fn new(model: &Model) -> Self {
        let nb = model.nbody();
        let links = model
            .joints()
            .iter()
            .enumerate()
            .map(|(i, joint)| {
                let speed = model.q_index(JointId(i));
                Link {
                    parent: joint.parent.map_or(ROOT, |p| p.index()),
                    projection: None,
                    speed: speed.unwrap_or(0),
                    n: if speed.is_some() {
                        joint.kind.ndof()
                    } else {
                        0
                    },
                    ..Link::default()
                }
            })
            .collect();
        ArticulatedFactor {
            links,
            nu: model.nu(),
            inertia: vec![Matrix3::zeros(); nb],
            sweep: vec![Vector3::zeros(); nb],
        }
    }

    /// The number of speeds.
    pub fn nrows(&self) -> usize {
        self.nu
    }

    /// Factors the mass matrix at the positions of the last
    /// [`crate::kinematics::update_positions`], from its joint frames, motion subspaces and
    /// body inertias (the first sweep of the articulated-body algorithm, [F, §7.3]):
    ///
    /// ```text
    /// Iᴬᵢ = Iᵢ + Σ_c Pcᵀ (Iᴬc − Kc Ucᵀ) Pc,   Uᵢ = Iᴬᵢ Sᵢ,   Dᵢ = Sᵢᵀ Uᵢ = Cᵢ Cᵢᵀ,   Kᵢ = Uᵢ Dᵢ⁻¹
    /// ```
    pub fn factor(
        &mut self,
        model: &Model,
        joint_frame: &[Pose],
        subspace: &[[Twist; 3]],
        body_inertia: &[Inertia],
    ) -> Result<(), NotPositiveDefinite> {
        for (ia, body) in self.inertia.iter_mut().zip(body_inertia) {
            *ia = inertia_matrix(body);
        }
        let joints = model.joints();
        for i in (0..self.links.len()).rev() {
            let link = &mut self.links[i];
            link.projection = joints[i]
                .is_absolute()
                .then_some(joint_frame[i].translation);
            let mut ia = self.inertia[i];
            match link.n {
                0 => {}
                // A hinge or a slider: D is a number, Iᵃ = Iᴬ − U Uᵀ / D.
                1 => {
                    let s = twist_vector(&subspace[i][0]);
                    let u = ia * s;
                    let d = s.dot(&u);
                    if !(d.is_finite() && d > 0.0) {
                        return Err(NotPositiveDefinite { joint: i });
                    }
                    let k = u / d;
                    ia -= k * u.transpose();
                    link.s[0] = s;
                    link.k[0] = k;
                    link.c[(0, 0)] = d.sqrt();
                }
                // Padded with the identity to one 3 × 3 Cholesky factorization.
                n => {
                    let mut s = Matrix3::zeros();
                    for (k, column) in subspace[i][..n].iter().enumerate() {
                        s.set_column(k, &twist_vector(column));
                    }
                    let u = ia * s;
                    let mut d = s.transpose() * u;
                    for k in n..3 {
                        d[(k, k)] = 1.0;
                    }
                    let chol = d.cholesky().ok_or(NotPositiveDefinite { joint: i })?;
                    let c = chol.l();
                    if !(0..n).all(|k| c[(k, k)].is_finite() && c[(k, k)] > 0.0) {
                        return Err(NotPositiveDefinite { joint: i });
                    }
                    // K = U D⁻¹, i.e. Kᵀ = D⁻¹ Uᵀ (D symmetric); U's padding columns are 0.
                    let k = chol.solve(&u.transpose()).transpose();
                    ia -= k * u.transpose();
                    for j in 0..n {
                        link.s[j] = s.column(j).into_owned();
                        link.k[j] = k.column(j).into_owned();
                    }
                    link.c = c;
                }
            }
            if link.parent != ROOT {
                let p = link.parent;
                self.inertia[p] += match link.projection {
                    Some(a) => {
                        let pm = projection_matrix(a);
                        pm.transpose() * ia * pm
                    }
                    None => ia,
                };
            }
        }
        Ok(())
    }

    /// `b ← G b`: the backward sweep, `uᵢ = bᵢ − Sᵢᵀ pᵢ` (see the module docs).
    ///
    /// The joints after the last one with a non-zero entry of `b` pass nothing up (a
    /// joint's subtree comes after it, so theirs hold no force either): the sweep starts
    /// at that joint. A contact point's Jacobian row has entries on its body's ancestors
    /// alone, so on a chain the sweep of a row covers the links above the point.
    fn backward(&mut self, b: &mut [Real]) {
        let end = (self.links.iter())
            .rposition(|l| b[l.speed..l.speed + l.n].iter().any(|&x| x != 0.0))
            .map_or(0, |i| i + 1);
        self.sweep[..end].fill(Vector3::zeros());
        for i in (0..end).rev() {
            let link = &self.links[i];
            if link.n == 0 && link.parent == ROOT {
                continue;
            }
            let p = self.sweep[i];
            let mut w = p;
            for (j, bj) in b[link.speed..link.speed + link.n].iter_mut().enumerate() {
                *bj -= link.s[j].dot(&p);
                w += link.k[j] * *bj;
            }
            if link.parent != ROOT {
                let up = match link.projection {
                    Some(a) => project_wrench(a, &w),
                    None => w,
                };
                self.sweep[link.parent] += up;
            }
        }
    }

    /// `x ← Gᵀ x`: the forward sweep, `xᵢ = vᵢ − Kᵢᵀ a′ᵢ` (see the module docs).
    fn forward(&mut self, x: &mut [Real]) {
        for i in 0..self.links.len() {
            let link = &self.links[i];
            let mut a = if link.parent == ROOT {
                Vector3::zeros()
            } else {
                let ap = self.sweep[link.parent];
                match link.projection {
                    Some(pa) => project_twist(pa, &ap),
                    None => ap,
                }
            };
            let a_parent = a;
            for (j, xj) in x[link.speed..link.speed + link.n].iter_mut().enumerate() {
                *xj -= link.k[j].dot(&a_parent);
                a += link.s[j] * *xj;
            }
            self.sweep[i] = a;
        }
    }

    /// `uᵢ ← Cᵢ⁻¹ uᵢ` for every joint (forward substitution).
    fn scale_c_inverse(&self, u: &mut [Real]) {
        for link in &self.links {
            let (c, u) = (&link.c, &mut u[link.speed..link.speed + link.n]);
            for i in 0..u.len() {
                let mut x = u[i];
                for j in 0..i {
                    x -= c[(i, j)] * u[j];
                }
                u[i] = x / c[(i, i)];
            }
        }
    }

    /// `uᵢ ← Cᵢ⁻ᵀ uᵢ` for every joint (backward substitution).
    fn scale_c_inverse_transpose(&self, u: &mut [Real]) {
        for link in &self.links {
            let (c, u) = (&link.c, &mut u[link.speed..link.speed + link.n]);
            for i in (0..u.len()).rev() {
                let mut x = u[i];
                for j in i + 1..u.len() {
                    x -= c[(j, i)] * u[j];
                }
                u[i] = x / c[(i, i)];
            }
        }
    }

    /// `b ← M⁻¹ b = Gᵀ D⁻¹ G b`. `b` has [`Self::nrows`] entries.
    pub fn solve_in_place(&mut self, b: &mut [Real]) {
        self.backward(b);
        self.scale_c_inverse(b);
        self.scale_c_inverse_transpose(b);
        self.forward(b);
    }

    /// `b ← F⁻¹ b = C⁻¹ G b`, for the factor `M = F Fᵀ`.
    pub fn solve_factor_in_place(&mut self, b: &mut [Real]) {
        self.backward(b);
        self.scale_c_inverse(b);
    }

    /// `y ← F⁻ᵀ y = Gᵀ C⁻ᵀ y`.
    pub fn solve_factor_transpose_in_place(&mut self, y: &mut [Real]) {
        self.scale_c_inverse_transpose(y);
        self.forward(y);
    }
}
