//! Repair of an almost right set of modes: single mode changes, each solving the linear
//! system of the modes ([`super::forces`]), until every condition of the table in
//! [`super`] holds.
//!
//! Lemke's pivots on the problems of a chain lying on the floor (rank-deficient `A`:
//! duplicated normal rows of two capsule ends at one hinge, `b_n = 0` at rest) run through
//! ill-conditioned bases; the modes they end with can be wrong at a few points (the
//! 32-link chain's impact of 10 points at t = 0.510 s missed its conditions by 1.2e-3 after
//! the polish). A wrong point shows as a violated condition of its mode, and the change
//! that condition asks for is the one an active-set method makes (Júdice and Pires' block
//! principal pivoting, one point at a time, the most violated first): an open point that
//! is pressed (`w_n < 0`) closes and sticks, a closed one that pulls (`x_n < 0`) opens, a
//! sticking one outside its cone slides against its friction, a sliding one whose slip
//! would start against its direction (`s w_t < 0`) sticks. Not a solver with a
//! guarantee: a start from Lemke's near-solution that settles in a few changes, or gives up.

use nalgebra::{DMatrix, DVector};

use super::friction::{CHECK_TOL, violation_in};
use super::{Allowed, Mode, ModeSystem, Solution};
use crate::linalg::fit_vector;
use crate::math::Real;

/// The most mode changes tried: a few per point.
fn max_changes(n: usize) -> usize {
    4 * n + 8
}

/// The buffers of the repair and of the polish of Lemke's solutions
/// ([`super::Solver`]), kept between calls: once they have met the largest problem,
/// [`Workspace::repair`], [`Workspace::forces_into`] and [`Workspace::violation`]
/// allocate nothing (the mode selections and the simultaneous impacts of many points call
/// them at events).
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    /// The contacts' `μ` (n).
    mu: Vec<Real>,
    /// The modes being repaired: the start, then changed one point at a time (n).
    modes: Vec<Mode>,
    /// The linear system of the modes, its solve, forces `x` and `w`.
    system: ModeSystem,
    /// [`super::conditions_violation`]'s `w = A x + b`, recomputed (2n).
    w: DVector<Real>,
    /// Its difference from the solution's `w` (2n).
    diff: DVector<Real>,
}

impl Workspace {
    /// Starts the repair from `modes` (Lemke's).
    pub fn start_from(&mut self, modes: &[Mode]) {
        self.modes.clear();
        self.modes.extend_from_slice(modes);
    }

    /// Starts the repair where Lemke's path gave no modes: each point closed if it is
    /// pressed with no force (`b_n < 0`), open otherwise.
    pub fn start_pressed(&mut self, b: &DVector<Real>, allowed: &[Allowed]) {
        self.modes.clear();
        self.modes.extend(allowed.iter().enumerate().map(|(i, c)| {
            if b[2 * i] < 0.0 || !c.open {
                c.slip.map_or(Mode::Stick, Mode::Slide)
            } else {
                Mode::Open
            }
        }));
    }

    /// The modes of the start repaired until they meet their conditions to
    /// [`CHECK_TOL`], written into `out`, if that happens within a few changes per point:
    /// `true`; else `false` (`out`'s numbers then mean nothing).
    pub fn repair(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        out: &mut Solution,
    ) -> bool {
        set_mu(&mut self.mu, allowed);
        for _ in 0..max_changes(allowed.len()) {
            if !forces_of(&mut self.system, a, b, &self.mu, &self.modes, out) {
                return false;
            }
            if violation_in(a, b, allowed, out, &mut self.w, &mut self.diff) <= CHECK_TOL {
                return true;
            }
            let Some((i, mode)) = worst_point(a, b, allowed, out) else {
                return false;
            };
            self.modes[i] = mode;
        }
        false
    }

    /// [`super::forces`] of `modes` written into `out` (the same numbers, to the bit):
    /// `false` if their system has no solution (`out`'s numbers then mean nothing).
    pub fn forces_into(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        modes: &[Mode],
        out: &mut Solution,
    ) -> bool {
        set_mu(&mut self.mu, allowed);
        forces_of(&mut self.system, a, b, &self.mu, modes, out)
    }

    /// [`super::conditions_violation`] of `sol`, in the kept buffers (the same number).
    pub fn violation(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        sol: &Solution,
    ) -> Real {
        violation_in(a, b, allowed, sol, &mut self.w, &mut self.diff)
    }
}

/// `mu` the contacts' `μ`.
fn set_mu(mu: &mut Vec<Real>, allowed: &[Allowed]) {
    mu.clear();
    mu.extend(allowed.iter().map(|c| c.mu));
}

/// [`super::forces`] by `system`, copied into `out`; `false` if the modes' system has no
/// solution.
fn forces_of(
    system: &mut ModeSystem,
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    mu: &[Real],
    modes: &[Mode],
    out: &mut Solution,
) -> bool {
    let Some((x, w)) = system.forces(a, b, mu, modes) else {
        return false;
    };
    out.modes.clear();
    out.modes.extend_from_slice(modes);
    fit_vector(&mut out.x, x.len());
    out.x.copy_from(x);
    fit_vector(&mut out.w, w.len());
    out.w.copy_from(w);
    true
}

/// The point whose condition is most violated, and the mode that condition asks for.
fn worst_point(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
    sol: &Solution,
) -> Option<(usize, Mode)> {
    let x = &sol.x;
    let sx = x.amax().max(Real::MIN_POSITIVE);
    let sw = (b.amax() + a.amax() * x.amax()).max(Real::MIN_POSITIVE);
    let w = &sol.w;
    let closed = |c: &Allowed| c.slip.map_or(Mode::Stick, Mode::Slide);
    let mut worst: Option<(Real, usize, Mode)> = None;
    for (i, (c, mode)) in allowed.iter().zip(&sol.modes).enumerate() {
        let (xn, xt, wn, wt) = (x[2 * i], x[2 * i + 1], w[2 * i], w[2 * i + 1]);
        let mut candidates: [(Real, Option<Mode>); 2] = [(0.0, None); 2];
        match *mode {
            Mode::Open => candidates[0] = (-wn / sw, Some(closed(c))),
            Mode::Stick => {
                candidates[0] = (-xn / sx, c.open.then_some(Mode::Open));
                let s = if xt > 0.0 { -1.0 } else { 1.0 };
                candidates[1] = ((xt.abs() - c.mu * xn) / sx, Some(Mode::Slide(s)));
            }
            Mode::Slide(s) => {
                candidates[0] = (-xn / sx, c.open.then_some(Mode::Open));
                if c.slip.is_none() {
                    candidates[1] = (-s * wt / sw, Some(Mode::Stick));
                }
            }
        }
        for (v, to) in candidates {
            if let Some(to) = to
                && v > CHECK_TOL
                && worst.is_none_or(|w| v > w.0)
            {
                worst = Some((v, i, to));
            }
        }
    }
    worst.map(|w| (w.1, w.2))
}
