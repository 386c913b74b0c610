//! The exact solver of the contact problem: enumeration of the `≤ 4ⁿ` mode combinations
//! ([`solve`]), and the forces of one known combination ([`forces`]). Each combination is a
//! linear system solved in least squares (minimum norm, [`MinNorm`]), so rank-deficient `A` (one degree of
//! freedom) is handled; a combination counts only if its residual vanishes.

use nalgebra::{DMatrix, DVector};

use super::{Allowed, CHECK_TOL, Mode, Solution, Solutions, TOL};
use crate::linalg::{MinNorm, amax, fit_matrix, fit_vector};
use crate::math::Real;

/// Solves the contact problem `w = A x + b` with the allowed modes, by enumeration.
/// `A` is `2n × 2n`, `b` has `2n` entries, `allowed` has `n`. Intended for a few contacts
/// (it tries up to `4ⁿ` linear systems); returns every consistent combination. (A fresh
/// workspace: [`Enumeration::solve_into`] keeps one.)
pub fn solve(a: &DMatrix<Real>, b: &DVector<Real>, allowed: &[Allowed]) -> Solutions {
    let mut all = Vec::new();
    Enumeration::default().solve_into(a, b, allowed, &mut all);
    Solutions { all }
}

/// The workspace of the enumeration ([`solve`]), kept between calls: after the calls of
/// the largest problem and the most solutions, [`Enumeration::solve_into`] allocates
/// nothing (the mode selections and the simultaneous impacts of a run call it at every
/// event).
#[derive(Clone, Debug, Default)]
pub struct Enumeration {
    /// The modes each contact may take, in the enumeration's order (open, stick, slide
    /// +1, slide −1), and how many.
    options: Vec<([Mode; 4], usize)>,
    /// The odometer of the combinations: the option of each contact taken.
    index: Vec<usize>,
    /// The combination tried.
    modes: Vec<Mode>,
    /// The linear system of the combination, its forces `x` and `w = A x + b`.
    system: ModeSystem,
    /// Scratch: the difference of two solutions' `w` (2n).
    diff: DVector<Real>,
    /// Solutions of earlier calls whose buffers the next solutions are written into.
    spare: Vec<Solution>,
}

impl Enumeration {
    /// [`solve`] into `out` (its solutions replaced; their buffers are reused): every
    /// consistent combination of modes, in the enumeration's order, the same numbers.
    pub fn solve_into(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        out: &mut Vec<Solution>,
    ) {
        self.recycle(out);
        let n = allowed.len();
        debug_assert_eq!(a.nrows(), 2 * n);
        self.options.clear();
        self.options.extend(allowed.iter().map(|c| {
            let mut m = [Mode::Open; 4];
            let mut len = 0;
            let mut push = |mode: Mode| {
                m[len] = mode;
                len += 1;
            };
            if c.open {
                push(Mode::Open);
            }
            match c.slip {
                Some(s) => push(Mode::Slide(s)),
                None => [Mode::Stick, Mode::Slide(1.0), Mode::Slide(-1.0)]
                    .into_iter()
                    .for_each(push),
            }
            (m, len)
        }));
        let scale_x = a.amax().max(Real::MIN_POSITIVE);
        let scale_w = b.amax();
        self.index.clear();
        self.index.resize(n, 0);
        loop {
            self.modes.clear();
            (self.modes).extend((0..n).map(|i| self.options[i].0[self.index[i]]));
            if self.solve_modes(a, b, allowed, scale_x, scale_w) {
                self.push_distinct(out, scale_w);
            }
            // Next combination (odometer).
            let mut i = 0;
            loop {
                if i == n {
                    return;
                }
                self.index[i] += 1;
                if self.index[i] < self.options[i].1 {
                    break;
                }
                self.index[i] = 0;
                i += 1;
            }
        }
    }

    /// Empties `out`, its solutions kept as spares to be written into.
    pub fn recycle(&mut self, out: &mut Vec<Solution>) {
        self.spare.append(out);
    }

    /// The spare solution of the largest buffers, to be written into, or an empty one:
    /// Lemke's solution, of the most points (the enumeration's are of four at most, and
    /// solutions that the caller drops are replaced by empty ones).
    pub(super) fn spare(&mut self) -> Solution {
        let largest = (0..self.spare.len()).max_by_key(|&i| self.spare[i].modes.capacity());
        largest.map_or_else(Solution::default, |i| self.spare.swap_remove(i))
    }

    /// Keeps `sol` as a spare.
    pub(super) fn keep(&mut self, sol: Solution) {
        self.spare.push(sol);
    }

    /// Whether the combination `self.modes` is consistent: its system solved (into
    /// `self.system`) and its sign conditions met.
    fn solve_modes(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        scale_a: Real,
        scale_b: Real,
    ) -> bool {
        let (modes, sys) = (&self.modes, &mut self.system);
        if sys
            .solve(a, b, |i| allowed[i].mu, modes, (scale_a, scale_b), None)
            .is_none()
        {
            return false;
        }
        let (x, w) = (&sys.x, &sys.w);
        let tol_w = TOL * (scale_b + scale_a * x.amax()).max(Real::MIN_POSITIVE);
        let tol_x = TOL * x.amax().max(Real::MIN_POSITIVE);
        modes.iter().enumerate().all(|(i, mode)| {
            let (xn, xt, wn, wt) = (x[2 * i], x[2 * i + 1], w[2 * i], w[2 * i + 1]);
            let mu = allowed[i].mu;
            match *mode {
                Mode::Open => wn >= -tol_w,
                Mode::Stick => xn >= -tol_x && xt.abs() <= mu * xn + tol_x,
                // A slip that starts needs a tangential tendency in its direction: with
                // none, the point sticks (and both directions would pass a closed test).
                Mode::Slide(s) => xn >= -tol_x && (allowed[i].slip.is_some() || s * wt > tol_w),
            }
        })
    }

    /// Adds the solution of `self.modes` and `self.system` to `all` unless a solution
    /// with the same motion `w` is there already: two mode sets with the same `w` differ
    /// only in forces that do not move anything — points at a boundary (an open point
    /// with no force, a closed point with no force), or redundant points whose forces may
    /// be shared in many ways (a rod lying on two points of a floor; `Jᵀ Δx = 0` since
    /// `Δxᵀ A Δx = 0`). Of two such, the one with more open points is kept.
    fn push_distinct(&mut self, all: &mut Vec<Solution>, scale_w: Real) {
        let (modes, w) = (&self.modes, &self.system.w);
        let tol = TOL * scale_w.max(w.amax()).max(Real::MIN_POSITIVE);
        let open = |m: &[Mode]| m.iter().filter(|m| **m == Mode::Open).count();
        let diff = &mut self.diff;
        let same = all.iter_mut().find(|s| {
            // `(&s.w - w).amax()`, in place.
            fit_vector(diff, w.len());
            diff.copy_from(&s.w);
            *diff -= w;
            diff.amax() <= tol
        });
        let to = match same {
            Some(same) if open(modes) > open(&same.modes) => same,
            Some(_) => return,
            None => {
                all.push(self.spare.pop().unwrap_or_default());
                let last = all.len() - 1;
                &mut all[last]
            }
        };
        to.modes.clear();
        to.modes.extend_from_slice(modes);
        let (x, w) = (&self.system.x, &self.system.w);
        fit_vector(&mut to.x, x.len());
        to.x.copy_from(x);
        fit_vector(&mut to.w, w.len());
        to.w.copy_from(w);
    }
}

/// The forces for a given combination of modes, without checking its sign conditions:
/// the linear system of the modes' equations (the constrained dynamics of a contact set
/// whose modes are known). `mu` has one entry per contact; `None` if the system has no
/// solution.
pub fn forces(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    mu: &[Real],
    modes: &[Mode],
) -> Option<Solution> {
    forces_with(a, b, mu, modes, None)
}

/// The relative rank threshold of the change from a reference in [`forces_near`]: the
/// directions of the modes' equations whose singular values are below `1e-10` of the
/// largest are left at the reference's split. The system `A = J M⁻¹ Jᵀ` is known only to
/// the rounding of `M⁻¹` (relative 1e-16 times its condition number); nearly dependent
/// rows of closed points (a chain folded on itself lying on the floor) leave a direction
/// whose singular value is rounding, and the least change along it amplified the
/// equations' rounding into forces of −201 N where the selection found 1.3e-3 N (the
/// 32-link chain with μ = 0.1, e = 0.6 at t = 2.0579 s: its lift-off event came back at
/// once, 1,000 times).
const REFERENCE_RANK_TOL: Real = 1e-10;

/// [`forces`], of the solutions nearest `reference` (`‖x − x_ref‖₂` least) where the
/// system is rank-deficient: the split of redundant points' forces that changes least
/// from a known one (the selection's, which met every condition). A regular system has
/// one solution, the same as [`forces`]' where both solve. The equations are held to the
/// selection's tolerance, `CHECK_TOL` (see `ModeSystem::solve`), where [`forces`] holds
/// them to `TOL`.
pub fn forces_near(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    mu: &[Real],
    modes: &[Mode],
    reference: &DVector<Real>,
) -> Option<Solution> {
    forces_with(a, b, mu, modes, Some(reference))
}

fn forces_with(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    mu: &[Real],
    modes: &[Mode],
    reference: Option<&DVector<Real>>,
) -> Option<Solution> {
    let allowed: Vec<Allowed> = mu
        .iter()
        .zip(modes)
        .map(|(&mu, m)| Allowed {
            mu,
            open: true,
            slip: match *m {
                Mode::Slide(s) => Some(s),
                _ => None,
            },
        })
        .collect();
    let (x, w) = linear(
        a,
        b,
        &allowed,
        modes,
        (a.amax().max(Real::MIN_POSITIVE), b.amax()),
        reference,
    )?;
    Some(Solution {
        modes: modes.to_vec(),
        x,
        w,
    })
}

/// The forces and `w` of the linear system of one combination of modes, if its equations
/// can hold; of several solutions, the nearest `reference` if one is given, else the
/// proportional split below. (A fresh workspace: the enumeration and the mode
/// selections; the right-hand side keeps a [`ModeSystem`].)
fn linear(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
    modes: &[Mode],
    scales: (Real, Real),
    reference: Option<&DVector<Real>>,
) -> Option<(DVector<Real>, DVector<Real>)> {
    let mut ws = ModeSystem::default();
    let mu = |i: usize| allowed[i].mu;
    ws.solve(a, b, mu, modes, scales, reference.map(|r| r.as_slice()))?;
    Some((ws.x, ws.w))
}

/// The linear system of one combination of modes and its solve, with every vector and
/// matrix kept between calls: after the first call of a size, [`ModeSystem::forces_near`]
/// allocates nothing (the right-hand side of the persistent contact calls it at every
/// evaluation).
///
/// One linear equation per unknown: the rows of `A` for the closed directions (`w = 0`),
/// and rows of the identity for the fixed forces (an open point's `x = 0`) or of the
/// friction law (a sliding point's `x_t + μ s x_n = 0`):
///
/// ```text
/// open:       x_n = 0,  x_t = 0
/// stick:      (A x + b)_n = 0,  (A x + b)_t = 0
/// slide (s):  (A x + b)_n = 0,  x_t + μ s x_n = 0
/// ```
#[derive(Clone, Debug, Default)]
pub struct ModeSystem {
    lhs: DMatrix<Real>,
    rhs: DVector<Real>,
    /// The solution `x`, and `w = A x + b`.
    #[doc(hidden)]
    pub x: DVector<Real>,
    #[doc(hidden)]
    pub w: DVector<Real>,
    /// Scratch: residuals, the right-hand side about the reference.
    tmp: DVector<Real>,
    /// The split's scaled system, its scales and solution.
    scaled: DMatrix<Real>,
    scale: DVector<Real>,
    y: DVector<Real>,
    /// With a reference: the solution nearest it at [`REFERENCE_RANK_TOL`], kept while the
    /// full rank is tried.
    nearest: DVector<Real>,
    ls: MinNorm,
}

impl ModeSystem {
    /// A workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// [`forces_near`] without allocating: the forces `x` of the modes nearest
    /// `reference` and `w = A x + b`, if the modes' equations can hold (to `CHECK_TOL`,
    /// the tolerance a selection took them to: see [`Self::solve`]). `mu` has one entry
    /// per contact.
    pub fn forces_near(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        mu: &[Real],
        modes: &[Mode],
        reference: &[Real],
    ) -> Option<(&DVector<Real>, &DVector<Real>)> {
        if let [mode] = modes
            && self.solve_one(a, b, mu[0], *mode, reference)
        {
            return Some((&self.x, &self.w));
        }
        // nalgebra's `amax` to the bit (`linalg::amax`), on the storage.
        let scales = (
            amax(a.as_slice()).max(Real::MIN_POSITIVE),
            amax(b.as_slice()),
        );
        self.solve(a, b, |i| mu[i], modes, scales, Some(reference))?;
        Some((&self.x, &self.w))
    }

    /// [`Self::solve`] with a reference of one contact point (a `2 × 2` system, the
    /// equations of [`ModeSystem`]) on the stack, without the buffers of the general path:
    /// the change `δ` from the reference solved by Cramer's rule,
    ///
    /// ```text
    ///   δ = [l₁₁ c₀ − l₀₁ c₁,  l₀₀ c₁ − l₁₀ c₀] / det,   det = l₀₀ l₁₁ − l₀₁ l₁₀
    /// ```
    ///
    /// (`L` the mode's rows, `c = r − L x_ref`), where the general path takes the pivoted
    /// Householder QR: the same solution to the rounding the system's condition number
    /// amplifies (the test `one_point_agrees_with_the_general_path`), with one division
    /// where the QR chains four square roots and four divisions (issue 16: the one sliding
    /// point's right-hand side 416 → 337 ns). The rank test is the QR's, `|r₁₁| ≤ 10⁻¹⁰ |r₀₀|`
    /// with `|r₀₀|` the larger column norm and `|r₀₀ r₁₁| = |det|`, i.e.
    /// `|det| ≤ 10⁻¹⁰ max_j ‖L e_j‖²`. `true` with `self.x`, `self.w` written when the equations
    /// hold; `false`, with nothing written, when the system is rank-deficient or not finite,
    /// or when its solution does not meet the equations to `CHECK_TOL`: the general path
    /// then decides (at extreme scales the two paths' roundings can fall on either side of
    /// that tolerance, and a failure of the right-hand side must be the general path's,
    /// which the selections use).
    #[doc(hidden)]
    #[inline]
    pub fn solve_one(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        mu: Real,
        mode: Mode,
        reference: &[Real],
    ) -> bool {
        if a.shape() != (2, 2) || b.len() != 2 || reference.len() != 2 {
            return false;
        }
        // Column-major storage: `a[(i, j)]` is `s[i + 2 j]`.
        let (s, b, r) = (a.as_slice(), b.as_slice(), reference);
        let (a, b) = ([[s[0], s[2]], [s[1], s[3]]], [b[0], b[1]]);
        let finite = [s[0], s[1], s[2], s[3], b[0], b[1], r[0], r[1]];
        if !finite.iter().fold(true, |all, v| all & v.is_finite()) {
            return false;
        }
        // The scales of `forces_near` (nalgebra's `amax` of `A` and `b`, `linalg::amax`).
        let scale_a = amax(&[s[0], s[1], s[2], s[3]]).max(Real::MIN_POSITIVE);
        let scale_b = amax(&b);
        // The rows of the mode, `lhs[i][j]` (row i), and the right-hand side.
        let (lhs, rhs) = match mode {
            Mode::Open => ([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0]),
            Mode::Stick => (a, [-b[0], -b[1]]),
            Mode::Slide(s) => ([a[0], [mu * s, 1.0]], [-b[0], 0.0]),
        };
        let mul = |m: &[[Real; 2]; 2], x: [Real; 2]| {
            [
                m[0][0] * x[0] + m[0][1] * x[1],
                m[1][0] * x[0] + m[1][1] * x[1],
            ]
        };
        // x = x_ref + δ, δ the least change that meets the equations (a regular system:
        // its one solution).
        let x_ref = [reference[0], reference[1]];
        let at_ref = mul(&lhs, x_ref);
        let change = [rhs[0] - at_ref[0], rhs[1] - at_ref[1]];
        // Cramer's rule, with the QR's rank test: |det| = |r₀₀ r₁₁| against the larger
        // column norm |r₀₀|, squared.
        let [[l00, l01], [l10, l11]] = lhs;
        let det = l00 * l11 - l01 * l10;
        let norm2 = (l00 * l00 + l10 * l10).max(l01 * l01 + l11 * l11);
        // Written so that a NaN (an overflow of the products) fails it too.
        let full_rank = det.abs() > REFERENCE_RANK_TOL * norm2;
        if !full_rank {
            return false;
        }
        let delta = [
            (l11 * change[0] - l01 * change[1]) / det,
            (l00 * change[1] - l10 * change[0]) / det,
        ];
        let x = [delta[0] + x_ref[0], delta[1] + x_ref[1]];
        // `holds_to`: the residual within `CHECK_TOL` of the scales, the tolerance the
        // general path holds a reference's modes to (see `Self::solve`), the forces'
        // scale being the larger of `x`'s and the reference's (`x_ref + δ` carries the
        // rounding of `lhs x_ref`).
        let lx = mul(&lhs, x);
        let residual = (lx[0] - rhs[0]).abs().max((lx[1] - rhs[1]).abs());
        let x_max = (x[0].abs().max(x[1].abs())).max(x_ref[0].abs().max(x_ref[1].abs()));
        let tol = CHECK_TOL * (scale_b + scale_a * x_max).max(Real::MIN_POSITIVE);
        if !(x.iter().all(|v| v.is_finite()) && residual <= tol) {
            return false;
        }
        let ax = mul(&a, x);
        fit_vector(&mut self.x, 2);
        fit_vector(&mut self.w, 2);
        for i in 0..2 {
            self.x[i] = x[i];
            self.w[i] = ax[i] + b[i];
        }
        true
    }

    /// [`forces`] without allocating once the workspace has met the size: the forces `x`
    /// of the modes (the proportional split of redundant sticking points) and
    /// `w = A x + b`, if the modes' equations can hold; the same numbers to the bit. `mu`
    /// has one entry per contact.
    pub(super) fn forces(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        mu: &[Real],
        modes: &[Mode],
    ) -> Option<(&DVector<Real>, &DVector<Real>)> {
        let scales = (a.amax().max(Real::MIN_POSITIVE), b.amax());
        self.solve(a, b, |i| mu[i], modes, scales, None)?;
        Some((&self.x, &self.w))
    }

    /// Whether `x` is finite and meets the equations, to `TOL` of the scales.
    fn holds(&mut self, x: &DVector<Real>, scales: (Real, Real)) -> bool {
        self.holds_to(x, scales, TOL, 0.0)
    }

    /// Whether `x` is finite and meets the equations, to `tol` of the scales: `A`'s and
    /// `b`'s, and of the forces the larger of `max|x|` and `x_floor` (the reference's,
    /// whose rounding `x = x_ref + δ` carries).
    fn holds_to(
        &mut self,
        x: &DVector<Real>,
        (scale_a, scale_b): (Real, Real),
        tol: Real,
        x_floor: Real,
    ) -> bool {
        if !x.iter().all(|v| v.is_finite()) {
            return false;
        }
        fit_vector(&mut self.tmp, x.len());
        self.lhs.mul_to(x, &mut self.tmp);
        self.tmp -= &self.rhs;
        let x_scale = x.amax().max(x_floor);
        self.tmp.amax() <= tol * (scale_b + scale_a * x_scale).max(Real::MIN_POSITIVE)
    }

    /// Solves the modes' system into `self.x`, `self.w`; `None` if it cannot hold.
    #[doc(hidden)]
    pub fn solve(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        mu: impl Fn(usize) -> Real,
        modes: &[Mode],
        scales: (Real, Real),
        reference: Option<&[Real]>,
    ) -> Option<()> {
        let m = 2 * modes.len();
        fit_matrix(&mut self.lhs, m, m);
        self.lhs.fill(0.0);
        fit_vector(&mut self.rhs, m);
        self.rhs.fill(0.0);
        for (i, mode) in modes.iter().enumerate() {
            let (rn, rt) = (2 * i, 2 * i + 1);
            match *mode {
                Mode::Open => {
                    self.lhs[(rn, rn)] = 1.0;
                    self.lhs[(rt, rt)] = 1.0;
                }
                Mode::Stick => {
                    self.lhs.row_mut(rn).copy_from(&a.row(rn));
                    self.lhs.row_mut(rt).copy_from(&a.row(rt));
                    self.rhs[rn] = -b[rn];
                    self.rhs[rt] = -b[rt];
                }
                Mode::Slide(s) => {
                    self.lhs.row_mut(rn).copy_from(&a.row(rn));
                    self.rhs[rn] = -b[rn];
                    self.lhs[(rt, rt)] = 1.0;
                    self.lhs[(rt, rn)] = mu(i) * s;
                }
            }
        }
        // The minimum-norm least-squares solution (a rank-deficient system: redundant
        // contact points, e.g. both ends of a link lying flat, or two capsule ends at one
        // hinge). Not nalgebra's SVD: it left a residual of 2.9e-6 on a well-conditioned
        // system of rank 5 of three sliding points of the 8-link chain (and 9e-4 on a
        // regular one of the 16-link chain), so that consistent systems were taken for
        // inconsistent ones (src/linalg.rs).
        let mut x = std::mem::take(&mut self.x);
        fit_vector(&mut x, m);
        // With a reference: x = x_ref + δ, δ the least change that meets the equations
        // (the split is then the reference's, not the proportional one below).
        let rank = match reference {
            Some(x_ref) => {
                let x_ref = nalgebra::DVectorView::from_slice(x_ref, m);
                fit_vector(&mut self.tmp, m);
                self.lhs.mul_to(&x_ref, &mut self.tmp);
                for (t, r) in self.tmp.iter_mut().zip(self.rhs.iter()) {
                    *t = r - *t;
                }
                // First without the directions the data do not determine; if the
                // reference then misses the equations (it came from another state), the
                // least change at the full rank, as before.
                self.ls
                    .solve_to(&self.lhs, &self.tmp, &mut x, REFERENCE_RANK_TOL);
                x += x_ref;
                if self.ls.truncated() && !self.holds(&x, scales) {
                    let mut nearest = std::mem::take(&mut self.nearest);
                    fit_vector(&mut nearest, m);
                    nearest.copy_from(&x);
                    self.ls.solve(&self.lhs, &self.tmp, &mut x);
                    x += x_ref;
                    if !self.holds(&x, scales) {
                        // Neither holds to `TOL`: the nearest is the one the selection's
                        // tolerance may still take (below).
                        std::mem::swap(&mut x, &mut nearest);
                    }
                    self.nearest = nearest;
                }
                None
            }
            None => Some(self.ls.solve(&self.lhs, &self.rhs, &mut x)),
        };
        let mut ok = self.holds(&x, scales);
        // The modes of a reference come from a selection, which took them where their
        // equations hold to `CHECK_TOL` (Lemke's check): the right-hand side holds them to
        // the same. Redundant equations of closed points are consistent only as far as
        // the closed points' velocities vanish, which they do to their drift: two points
        // of one pair that lock the pair's relative motion (links 25 and 27 of the 32-link
        // chain folded in a Z, both sticking) have identical tangential rows, and their
        // velocity products differ by `ω (v_n1 − v_n2)` — the pair turning at ω = 2.45
        // rad/s, its points closing and opening at 5e-8 m/s: 2.5e-7 m/s², constant, where
        // `TOL` of the scales fell to 1.3e-7 as the forces decreased (μ = 0.1,
        // e = 0.6 − 1 ulp at t = 1.3909 s: "no solution", every step refused). The least
        // squares leave that inconsistency in the redundant directions, at the drift.
        // The forces' scale is the larger of the solution's and the reference's:
        // `x = x_ref + δ` carries the rounding of `lhs x_ref`, `ε max|A| max|x_ref|`, and a
        // solution far below its reference is known only to that. Newton's cradle under
        // RK4: balls 1–4 at rest, touching, with forces of rounding; the reference of
        // 1.9e-17 N came from the selection after the impacts, `b` fell to 1.8e-32 at
        // t = 0.9578 s and with it the tolerance of the solution's own scale (1e-39),
        // below the 1e-33 that subtracting `lhs x_ref` leaves: "no solution", the run
        // failed (regular equations, nothing drifting).
        if !ok && let Some(x_ref) = reference {
            ok = self.holds_to(&x, scales, CHECK_TOL, amax(x_ref));
        }
        self.x = x;
        if !ok {
            return None;
        }
        // Redundant sticking points (a block on two corners, a rod lying flat): the split of
        // their forces is statically indeterminate, and the minimum-norm one shares the
        // friction equally, which leaves the cone of the less loaded point (a block on a 30°
        // slope needed μ ≥ 0.812, what an equal split needs, instead of tan 30° = 0.577).
        // The split of least Σ x_t,k² / (μ_k x_n,k) is taken instead — each point's
        // friction in proportion to what its cone allows, within every cone whenever the
        // total fits: the minimum-norm solution in y_t,k = x_t,k / √(μ_k x_n,k), with the
        // normal forces of the first solution. Regular systems are left as they were.
        if rank.is_some_and(|rank| rank < m) && modes.contains(&Mode::Stick) {
            fit_vector(&mut self.scale, m);
            self.scale.fill(1.0);
            for (i, mode) in modes.iter().enumerate() {
                if *mode == Mode::Stick {
                    self.scale[2 * i + 1] = (mu(i) * self.x[2 * i]).max(0.0).sqrt();
                }
            }
            fit_matrix(&mut self.scaled, m, m);
            self.scaled.copy_from(&self.lhs);
            for (j, s) in self.scale.iter().enumerate() {
                self.scaled.column_mut(j).scale_mut(*s);
            }
            let mut y = std::mem::take(&mut self.y);
            // Its length first (every entry is then written): the solve would otherwise
            // replace a vector of another length by a new one.
            fit_vector(&mut y, m);
            self.ls.solve(&self.scaled, &self.rhs, &mut y);
            y.component_mul_assign(&self.scale);
            if self.holds(&y, scales) {
                std::mem::swap(&mut self.x, &mut y);
            }
            self.y = y;
        }
        fit_vector(&mut self.w, m);
        a.mul_to(&self.x, &mut self.w);
        self.w += b;
        Some(())
    }
}
