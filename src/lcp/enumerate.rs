//! The exact solver of the contact problem: enumeration of the `≤ 4ⁿ` mode combinations
//! ([`solve`]), and the forces of one known combination ([`forces`]). Each combination is a
//! linear system solved in least squares (minimum norm, [`MinNorm`]), so rank-deficient `A` (one degree of
//! freedom) is handled; a combination counts only if its residual vanishes.

use nalgebra::{DMatrix, DVector};

use super::{Allowed, CHECK_TOL, Mode, Solution, Solutions, TOL};
use crate::linalg::{MinNorm, amax, fit_matrix, fit_vector, min_norm_2x2};
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
    x: DVector<Real>,
    w: DVector<Real>,
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
            && let Some(solved) = self.solve_one(a, b, mu[0], *mode, reference)
        {
            return solved.then_some((&self.x, &self.w));
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
    /// equations of [`ModeSystem`]) on the stack: the same operations in the same order,
    /// so the same numbers to the bit (the test
    /// `one_point_is_the_general_path_to_the_bit`), without the buffers of the general
    /// path. `Some(true)` with `self.x`, `self.w` written when the equations hold,
    /// `Some(false)` when they cannot (the general path would fail too), `None`, with
    /// nothing written, when the system is rank-deficient or not finite: the general path
    /// then solves.
    fn solve_one(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        mu: Real,
        mode: Mode,
        reference: &[Real],
    ) -> Option<bool> {
        if a.shape() != (2, 2) || b.len() != 2 || reference.len() != 2 {
            return None;
        }
        // Column-major storage: `a[(i, j)]` is `s[i + 2 j]`.
        let (s, b, r) = (a.as_slice(), b.as_slice(), reference);
        let (a, b) = ([[s[0], s[2]], [s[1], s[3]]], [b[0], b[1]]);
        let finite = [s[0], s[1], s[2], s[3], b[0], b[1], r[0], r[1]];
        if !finite.iter().fold(true, |all, v| all & v.is_finite()) {
            return None;
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
        let by_columns = [[lhs[0][0], lhs[1][0]], [lhs[0][1], lhs[1][1]]];
        let delta = min_norm_2x2(by_columns, change, REFERENCE_RANK_TOL)?;
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
            return Some(false);
        }
        let ax = mul(&a, x);
        fit_vector(&mut self.x, 2);
        fit_vector(&mut self.w, 2);
        for i in 0..2 {
            self.x[i] = x[i];
            self.w[i] = ax[i] + b[i];
        }
        Some(true)
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
    fn solve(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::tests::Lcg;

    /// The one-point path of [`ModeSystem::forces_near`] ([`ModeSystem::solve_one`]) gives
    /// the general path's numbers to the bit, or the same failure, on 40,000 random
    /// systems `A = Yᵀ Y` (of rank 2, and of rank 1: the general path's fallback), with
    /// every mode, references at zero, at random and near the solution, over 12 decades
    /// of scale; and a sliding point's forces are the closed form of its equations,
    /// `λ_n = −b_n / (A_nn − μ s A_nt)`, `λ_t = −μ s λ_n`, to the rounding the system's
    /// condition number `κ` amplifies and the closed form's own pivot `h ≥ 10⁻³ max|A|`
    /// loses (`10³ κ ε`).
    #[test]
    fn one_point_is_the_general_path_to_the_bit() {
        let mut rng = Lcg(16);
        let (mut fast, mut general) = (ModeSystem::new(), ModeSystem::new());
        let (mut taken, mut solved, mut worst_closed): (usize, usize, Real) = (0, 0, 0.0);
        for case in 0..40_000 {
            let scale = 10f64.powi(case % 13 - 6);
            let rows = if case % 7 == 3 { 1 } else { 2 };
            let y = DMatrix::from_fn(rows, 2, |_, _| rng.next() * scale.sqrt());
            let a = y.transpose() * &y;
            let b = DVector::from_fn(2, |_, _| 10.0 * rng.next());
            let mu = 0.5 * (rng.next() + 1.0);
            let mode = match case % 4 {
                0 => Mode::Open,
                1 => Mode::Stick,
                2 => Mode::Slide(1.0),
                _ => Mode::Slide(-1.0),
            };
            let reference = match case % 3 {
                0 => [0.0, 0.0],
                1 => [rng.next() / scale, rng.next() / scale],
                _ => match crate::lcp::forces(&a, &b, &[mu], &[mode]) {
                    Some(s) => [s.x[0] * (1.0 + 1e-9 * rng.next()), s.x[1]],
                    None => [0.0, 0.0],
                },
            };
            let scales = (a.amax().max(Real::MIN_POSITIVE), b.amax());
            let Some(ok) = fast.solve_one(&a, &b, mu, mode, &reference) else {
                continue;
            };
            taken += 1;
            let expected = general.solve(&a, &b, |_| mu, &[mode], scales, Some(&reference));
            assert_eq!(ok, expected.is_some(), "case {case}: {a} {b} {mode:?}");
            if !ok {
                continue;
            }
            solved += 1;
            let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast.x), bits(&general.x), "case {case}: x");
            assert_eq!(bits(&fast.w), bits(&general.w), "case {case}: w");
            let via = fast
                .forces_near(&a, &b, &[mu], &[mode], &reference)
                .unwrap();
            assert_eq!(bits(via.0), bits(&general.x), "case {case}: forces_near");
            if let Mode::Slide(s) = mode {
                let h = a[(0, 0)] - mu * s * a[(0, 1)];
                // Well-posed: the pivot of the closed form is not itself rounding.
                if h.abs() > 1e-3 * a.amax() {
                    let n = -b[0] / h;
                    let err = (fast.x[0] - n).abs().max((fast.x[1] + mu * s * n).abs());
                    // In units of the rounding the modes' system amplifies: its condition
                    // number κ = σ₁/σ₂ (σ₁σ₂ = |det|, σ₁² + σ₂² = ‖lhs‖²_F) times ε.
                    let lhs = [a[(0, 0)], a[(0, 1)], mu * s, 1.0];
                    let det = (lhs[0] * lhs[3] - lhs[1] * lhs[2]).abs();
                    let f2: Real = lhs.iter().map(|v| v * v).sum();
                    let s1 = ((f2 + (f2 * f2 - 4.0 * det * det).max(0.0).sqrt()) / 2.0).sqrt();
                    let kappa = s1 * s1 / det;
                    let rel = err / n.abs().max(Real::MIN_POSITIVE);
                    worst_closed = worst_closed.max(rel / (kappa * Real::EPSILON));
                }
            }
        }
        assert!(
            taken > 30_000 && solved > 20_000,
            "{taken} taken, {solved} solved"
        );
        println!("closed form: worst relative difference {worst_closed:.2} κ ε");
        assert!(worst_closed < 1e3, "closed form: {worst_closed} κ ε");
    }

    fn one(a: [[Real; 2]; 2], b: [Real; 2], allowed: Allowed) -> Solutions {
        solve(
            &DMatrix::from_row_slice(2, 2, &[a[0][0], a[0][1], a[1][0], a[1][1]]),
            &DVector::from_row_slice(&b),
            &[allowed],
        )
    }

    #[test]
    fn a_pressed_contact_sticks_and_a_pulled_one_opens() {
        let free = Allowed {
            mu: 0.5,
            open: true,
            slip: None,
        };
        // A particle on a floor pressed by gravity (b_n = −g), no tangential push.
        let s = one([[1.0, 0.0], [0.0, 1.0]], [-9.81, 0.0], free);
        assert_eq!(s.all.len(), 1);
        assert_eq!(s.all[0].modes, vec![Mode::Stick]);
        assert!((s.all[0].x[0] - 9.81).abs() < 1e-12 && s.all[0].x[1].abs() < 1e-12);
        // Pulled away: it opens.
        let s = one([[1.0, 0.0], [0.0, 1.0]], [2.0, 1.0], free);
        assert_eq!(s.all.len(), 1);
        assert_eq!(s.all[0].modes, vec![Mode::Open]);
        // Pressed and pushed sideways beyond the cone: it starts to slip along the push.
        let s = one([[1.0, 0.0], [0.0, 1.0]], [-1.0, 3.0], free);
        assert_eq!(s.all.len(), 1);
        assert_eq!(s.all[0].modes, vec![Mode::Slide(1.0)]);
        assert!((s.all[0].x[1] + 0.5).abs() < 1e-12 && (s.all[0].w[1] - 2.5).abs() < 1e-12);
    }

    #[test]
    fn painleve_sliding_contact_has_no_or_two_solutions() {
        // A sliding contact (s = +1) whose effective normal coefficient
        // h = m_nn − μ m_nt is negative: pressed (b_n < 0) there is no solution, pulled
        // (b_n > 0) there are two (open, or slide with x_n = −b_n/h).
        let (nn, nt, tt, mu) = (1.0, 1.5, 3.0, 1.0); // h = −0.5
        let sliding = Allowed {
            mu,
            open: true,
            slip: Some(1.0),
        };
        assert!(
            one([[nn, nt], [nt, tt]], [-1.0, 0.0], sliding)
                .all
                .is_empty()
        );
        let two = one([[nn, nt], [nt, tt]], [1.0, 0.0], sliding);
        assert_eq!(two.all.len(), 2);
        assert!((two.all[1].x[0] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn rank_deficient_a_is_handled() {
        // One degree of freedom: A = m [[1, k], [k, k²]]; the sticking system is singular
        // but consistent when the tangential row is a multiple of the normal one.
        let k = 0.1;
        let a = [[1.0, k], [k, k * k]];
        let s = one(
            a,
            [-2.0, -2.0 * k],
            Allowed {
                mu: 1.0,
                open: true,
                slip: None,
            },
        );
        assert!(s.all.iter().any(|sol| sol.modes == vec![Mode::Stick]));
        for sol in &s.all {
            assert!(sol.w[0].abs() < 1e-9 || sol.modes == vec![Mode::Open]);
        }
    }

    /// Three points sliding together (a 16-link chain lying on the floor, t = 0.82 s): a
    /// regular 6×6 system (singular values 23…0.94) whose SVD solution missed the
    /// equations by 9e-4 (nalgebra 0.35), so that the modes were reported to have no
    /// solution; LU solves it to rounding. The normal rows are the chain's; the tangential
    /// rows, which sliding modes do not use, are filled symmetrically.
    #[test]
    fn a_regular_system_the_svd_solves_badly_is_solved() {
        let a = DMatrix::from_row_slice(
            6,
            6,
            &[
                17.302117445679748,
                1.8165105226191547,
                -4.572156682577878,
                -0.36634463106233955,
                0.9849425829114355,
                0.16445165719519866,
                1.8165105226191547,
                1.0,
                -1.917698421818475,
                0.0,
                1.0701654368316207,
                0.0,
                -4.572156682577888,
                -1.917698421818475,
                17.05047970909367,
                1.4544438810525593,
                -3.6226685807213177,
                -0.5111557899640272,
                -0.36634463106233955,
                0.0,
                1.4544438810525593,
                1.0,
                -0.6640752695117632,
                0.0,
                0.9849425829114341,
                1.0701654368316207,
                -3.622668580721315,
                -0.6640752695117632,
                13.478413789294763,
                1.8276465193845035,
                0.16445165719519866,
                0.0,
                -0.5111557899640272,
                0.0,
                1.8276465193845035,
                1.0,
            ],
        );
        let b = DVector::from_row_slice(&[
            -9.660775322462747,
            0.0,
            -10.77653621543649,
            0.0,
            -6.045218443159906,
            0.0,
        ]);
        let modes = [Mode::Slide(1.0); 3];
        let sol = forces(&a, &b, &[0.3; 3], &modes).expect("a regular system has a solution");
        for (i, row) in [0usize, 2, 4].into_iter().enumerate() {
            // The normal equations w_n = 0, and Coulomb's sliding friction x_t = −μ x_n.
            assert!(sol.w[row].abs() <= 1e-12, "w_n{i} = {}", sol.w[row]);
            let slip = sol.x[row + 1] + 0.3 * sol.x[row];
            assert!(
                slip.abs() <= 1e-14 * sol.x[row].abs(),
                "x {:?}",
                sol.x.as_slice()
            );
        }
    }

    /// Two sticking points at one place (identical rows: two capsule ends at one hinge on a
    /// floor) and a third: the forces of the modes are not unique. `forces_near` keeps a
    /// valid split it is given, and otherwise changes it least (`x − x_ref` orthogonal to
    /// the null space: of the solutions, the nearest); on a regular system it is `forces`.
    #[test]
    fn forces_near_a_reference_keep_the_split_of_redundant_points() {
        // J: rows (n0, t0), (n1, t1) = (n0, t0), (n2, t2) of a body with 3 speeds.
        let j = DMatrix::from_row_slice(
            6,
            3,
            &[
                1.0, 0.0, 0.3, 0.0, 1.0, -0.2, 1.0, 0.0, 0.3, 0.0, 1.0, -0.2, 1.0, 0.0, -0.7, 0.0,
                1.0, -0.2,
            ],
        );
        let a = &j * j.transpose();
        let b = DVector::from_row_slice(&[-9.81, 1.0, -9.81, 1.0, -9.81, 1.0]);
        let modes = [Mode::Stick; 3];
        let mu = [0.5; 3];
        let plain = forces(&a, &b, &mu, &modes).unwrap();
        assert!(plain.w.amax() <= 1e-12);
        // The split with all of the hinge's force on its first point.
        let mut reference = plain.x.clone();
        reference[0] += plain.x[2];
        reference[1] += plain.x[3];
        reference[2] = 0.0;
        reference[3] = 0.0;
        let near = forces_near(&a, &b, &mu, &modes, &reference).unwrap();
        assert!((&near.x - &reference).amax() <= 1e-12, "{}", near.x);
        assert!(near.w.amax() <= 1e-12);
        // A reference off the solutions: the nearest solution. Its change is orthogonal
        // to the null direction (the hinge's force moved from one point to the other).
        let mut off = reference.clone();
        off[0] += 0.3;
        off[5] -= 0.2;
        let near = forces_near(&a, &b, &mu, &modes, &off).unwrap();
        assert!(near.w.amax() <= 1e-12);
        let null = DVector::from_row_slice(&[1.0, 0.0, -1.0, 0.0, 0.0, 0.0]);
        let tangential_null = DVector::from_row_slice(&[0.0, 1.0, 0.0, -1.0, 0.0, 0.0]);
        let change = &near.x - &off;
        assert!(change.dot(&null).abs() <= 1e-12 && change.dot(&tangential_null).abs() <= 1e-12);
        // A regular system: the one solution.
        let (a1, b1) = (
            a.view((4, 4), (2, 2)).into_owned(),
            b.rows(4, 2).into_owned(),
        );
        let one = forces(&a1, &b1, &mu[..1], &modes[..1]).unwrap();
        let near = forces_near(
            &a1,
            &b1,
            &mu[..1],
            &modes[..1],
            &DVector::from_element(2, 5.0),
        )
        .unwrap();
        assert!((&near.x - &one.x).amax() <= 1e-12 * one.x.amax());
    }

    /// Newton's cradle under RK4 at t = 0.9578 s: balls 1–4 at rest, touching, three
    /// frictionless points (sliding with μ = 0), forces of rounding. The selection after
    /// the impacts left a reference of 1.9e-17 N; `b` has fallen to 1.8e-32. The equations
    /// are regular; `x_ref + δ` carries the rounding of `lhs x_ref` (~1e-33), which the
    /// tolerance of the solution's own scale (1e-39) refused: "the forces of the closed
    /// contact points have no solution", the run failed. The tolerance takes the
    /// reference's scale too; the forces are the regular system's to that rounding. The
    /// same for one point (the stack path).
    #[test]
    fn forces_far_below_their_reference_hold_to_the_reference_s_rounding() {
        let (d, c, p, q) = (
            3.9937597503900153,
            -1.9968798751950076,
            0.12480499219968798,
            0.0078003120124804995,
        );
        // Rows (n1, t1, n2, t2, n3, t3); the columns of the three points' normal and
        // tangential forces.
        let rows = [
            [d, 0.0, c, -p, 0.0, 0.0],
            [0.0, 2.0 * q, p, q, 0.0, 0.0],
            [c, p, d, 0.0, c, -p],
            [-p, q, 0.0, 2.0 * q, p, q],
            [0.0, 0.0, c, p, d, 0.0],
            [0.0, 0.0, -p, q, 0.0, 2.0 * q],
        ];
        let a = DMatrix::from_fn(6, 6, |i, j| rows[i][j]);
        let b = DVector::from_row_slice(&[
            1.7860112240328213e-32,
            1.116775127450512e-33,
            -8.28979888901439e-36,
            0.0,
            -8.289798887961006e-36,
            0.0,
        ]);
        let reference = [
            1.9144841961749036e-17,
            -4.6222318665293654e-33,
            1.276322797449936e-17,
            -3.7982270983039195e-65,
            6.381613987249679e-18,
            -0.0,
        ];
        let (modes, mu) = ([Mode::Slide(-1.0); 3], [0.0; 3]);
        let mut ws = ModeSystem::new();
        let (x, w) = ws
            .forces_near(&a, &b, &mu, &modes, &reference)
            .expect("regular equations hold to the rounding of the reference");
        let (x, w) = (x.clone(), w.clone());
        let plain = forces(&a, &b, &mu, &modes).expect("the regular system's one solution");
        let rounding = 1e3 * Real::EPSILON * a.amax() * amax(&reference);
        assert!((&x - &plain.x).amax() <= rounding, "{x} vs {}", plain.x);
        for row in [0, 2, 4] {
            assert!(w[row].abs() <= rounding, "w_n = {}", w[row]);
        }
        // One point: the same equations on the stack.
        let (a1, b1) = (
            a.view((0, 0), (2, 2)).into_owned(),
            b.rows(0, 2).into_owned(),
        );
        let (x1, _) = ws
            .forces_near(&a1, &b1, &mu[..1], &modes[..1], &reference[..2])
            .expect("one point holds to the rounding of its reference");
        let one = forces(&a1, &b1, &mu[..1], &modes[..1]).unwrap();
        assert!((x1 - &one.x).amax() <= rounding, "{x1} vs {}", one.x);
    }

    /// Two sticking points at *nearly* one place (the second capsule end at a hinge 1e-6 m
    /// off the first) and a third: `A = J Jᵀ` has a singular value of 1.1e-12 of its
    /// largest, which the equations' rounding cannot determine. A right-hand side moved by
    /// rounding (5e-15 of `|b|`) along that direction: the least change at the rounding
    /// rank moves the forces by 5e-15 / 1.1e-12 of `|b|` — percents — while
    /// `forces_near` (rank at `REFERENCE_RANK_TOL`) keeps the reference's forces to
    /// rounding, and its equations hold. (The 32-link chain with μ = 0.1, e = 0.6: −201 N
    /// where the selection found 1.3e-3 N, and its lift-off event came back 1,000 times.)
    #[test]
    fn forces_near_a_reference_ignore_what_rounding_cannot_determine() {
        // A fourth speed that moves the second point's normal alone, by 1e-6.
        let j = DMatrix::from_row_slice(
            6,
            4,
            &[
                1.0, 0.0, 0.3, 0.0, 0.0, 1.0, -0.2, 0.0, 1.0, 0.0, 0.3, 1e-6, 0.0, 1.0, -0.2, 0.0,
                1.0, 0.0, -0.7, 0.0, 0.0, 1.0, -0.2, 0.0,
            ],
        );
        let a = &j * j.transpose();
        let b = DVector::from_row_slice(&[-9.81, 1.0, -9.81, 1.0, -9.81, 1.0]);
        let modes = [Mode::Stick; 3];
        let mu = [0.5; 3];
        let svd = a.clone().svd(true, true);
        let sigma = &svd.singular_values;
        let largest = sigma.max();
        // The near-null direction: below 1e-10 of the largest, above the rounding rank.
        let small = (0..6)
            .filter(|&i| sigma[i] > 6.0 * Real::EPSILON * largest && sigma[i] < 1e-10 * largest)
            .collect::<Vec<_>>();
        assert_eq!(small.len(), 1, "{sigma}");
        let u = svd.u.as_ref().unwrap().column(small[0]).into_owned();
        let reference = forces(&a, &b, &mu, &modes).unwrap();
        assert!(reference.w.amax() <= 1e-12);
        let moved = &b + &u * (5e-15 * b.amax());
        // The least change at the rounding rank, for comparison: percents.
        let mut change = DVector::zeros(0);
        let residual = -(&a * &reference.x + &moved);
        MinNorm::new().solve(&a, &residual, &mut change);
        assert!(change.amax() > 1e-3 * reference.x.amax(), "{change}");
        // forces_near keeps the reference.
        let near = forces_near(&a, &moved, &mu, &modes, &reference.x).unwrap();
        assert!(
            (&near.x - &reference.x).amax() <= 1e-12 * reference.x.amax(),
            "{} against {}",
            near.x,
            reference.x
        );
        assert!(near.w.amax() <= 1e-12 * b.amax());
    }
}
