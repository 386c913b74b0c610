//! The complementarity problem of several contacts with Coulomb friction. Pure numerics on
//! `(A, b, μ)`: nothing here knows about bodies.
//!
//! For `n` contacts, with unknown forces (or impulses) `x = (x_n0, x_t0, x_n1, x_t1, …)` and
//! `w = A x + b` the resulting normal and tangential accelerations (or velocities), each
//! contact is in one of the modes
//!
//! | mode | equations | conditions |
//! |---|---|---|
//! | open | `x_n = 0`, `x_t = 0` | `w_n ≥ 0` |
//! | stick | `w_n = 0`, `w_t = 0` | `x_n ≥ 0`, `|x_t| ≤ μ x_n` |
//! | slide `s` | `w_n = 0`, `x_t = −μ s x_n` | `x_n ≥ 0`, and `s w_t ≥ 0` when the slip starts |
//!
//! This is Coulomb's law with unilateral contact at the acceleration level (persistent
//! contacts: `w` is the relative acceleration, the slip direction `s` of a sliding contact
//! is known from its velocity) or at the velocity level (Moreau's generalized Newton law
//! for simultaneous impacts: `w = v⁺ + e v⁻`, the slip is that of `v⁺`).
//!
//! Two solvers:
//!
//! - [`solve`] enumerates the `≤ 4ⁿ` mode combinations (`enumerate.rs`) and finds every
//!   solution: none or several reveal Painlevé's paradox (inconsistency or indeterminacy).
//!   Exact, for a few contacts ([`MAX_ENUMERATED`]). [`forces`] solves one known
//!   combination.
//! - [`Solver`] finds one solution by Lemke's complementary pivoting (`lemke.rs`) on the
//!   problem written as a standard LCP with the friction cone split into its two edges
//!   (`friction.rs`): polynomial in practice, for many contacts; its ray termination is
//!   [`LcpError::NoSolution`].

#[doc(hidden)]
pub mod enumerate;
#[doc(hidden)]
pub mod friction;
pub mod lemke;
#[doc(hidden)]
pub mod repair;

pub use enumerate::{Enumeration, ModeSystem, forces, forces_near, solve};
pub use friction::{CHECK_TOL, LcpError, Solver, conditions_violation};

use nalgebra::DVector;

use crate::math::Real;

/// The mode of one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// The contact opens: no force.
    Open,
    /// The contact is closed and does not slip.
    Stick,
    /// The contact is closed and slips in the direction `s = ±1` along its tangent; the
    /// friction is `x_t = −μ s x_n`.
    Slide(Real),
}

/// Which modes a contact may take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Allowed {
    /// Coulomb's coefficient `μ ≥ 0`.
    pub mu: Real,
    /// The contact may open.
    pub open: bool,
    /// The known slip direction (`Some(±1)`: the contact slides, it cannot stick); `None`:
    /// it may stick, or start to slip either way (then `s w_t ≥ 0` is required).
    pub slip: Option<Real>,
}

/// A solution: the mode, force and resulting `w` of every contact.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Mode of each contact.
    pub modes: Vec<Mode>,
    /// Forces `x` (2n): normal and tangential of each contact.
    pub x: DVector<Real>,
    /// `w = A x + b` (2n).
    pub w: DVector<Real>,
}

/// A solution of no contacts, with no buffers: storage to be written into.
impl Default for Solution {
    fn default() -> Self {
        Self {
            modes: Vec::new(),
            x: DVector::zeros(0),
            w: DVector::zeros(0),
        }
    }
}

impl Solution {
    /// Opens every closed contact whose normal force came out negative, `x_n < 0`: the
    /// solvers accept a solution whose conditions hold to their tolerance, and a contact
    /// whose force is zero in exact arithmetic can end at `x_n ≈ −1e-12 |x|` (the 32-link
    /// chain's simultaneous impacts, `tests/all/sim_persistent.rs`). Its forces become
    /// exactly zero (`x_n ≥ 0` holds exactly, as an impulse of Moreau's law must) and
    /// `w = A x + b` is recomputed; the other conditions move by `A` times that rounding.
    /// Returns the number of contacts opened.
    pub fn open_negative_normals(
        &mut self,
        a: &nalgebra::DMatrix<Real>,
        b: &DVector<Real>,
    ) -> usize {
        let mut opened = 0;
        for (i, mode) in self.modes.iter_mut().enumerate() {
            if *mode != Mode::Open && self.x[2 * i] < 0.0 {
                *mode = Mode::Open;
                self.x[2 * i] = 0.0;
                self.x[2 * i + 1] = 0.0;
                opened += 1;
            }
        }
        if opened > 0 {
            self.w.copy_from(b);
            self.w.gemv(1.0, a, &self.x, 1.0);
        }
        opened
    }
}

/// Every solution of the problem (none, one, or several).
#[derive(Clone, Debug, PartialEq)]
pub struct Solutions {
    /// The solutions, in the order the modes were enumerated (for each contact: open,
    /// stick, slide +1, slide −1).
    pub all: Vec<Solution>,
}

/// Relative tolerance of the residuals and sign conditions.
#[doc(hidden)]
pub const TOL: Real = 1e-9;

/// The most contacts of one problem that [`solutions`] enumerates: `4⁴ = 256` linear
/// systems of size 8, about 3 ms (benches/lcp.rs: 2.9 ms for 4 contacts, 14.5 ms for 5,
/// 73 ms for 6; Lemke 11 µs for 4). Beyond it only Lemke's algorithm runs.
pub const ENUMERATED_UP_TO: usize = 4;

/// The most contacts the enumeration [`solve`] is meant for: `4⁶ = 4096` linear systems of
/// size 12, some tens of milliseconds (its `4ⁿ` cost would stall a run beyond: four
/// million systems at 11 points). The simulation enumerates up to [`ENUMERATED_UP_TO`]
/// only; Moreau–Jean's exact check up to this.
pub const MAX_ENUMERATED: usize = 6;

/// The solutions of the contact problem as the simulation takes them: several where it
/// can see them, one otherwise.
///
/// - Up to [`ENUMERATED_UP_TO`] contacts, the enumeration ([`solve`]): every solution,
///   exactly, so that several (Painlevé's indeterminacy, redundant points) are seen and the
///   documented rule chooses among them.
/// - Where the enumeration finds none, or beyond that size: Lemke's algorithm
///   ([`Solver::solve`]), one solution. It also finds what the enumeration misses: the
///   statically indeterminate split of redundant sticking points (a block on two corners
///   on a slope sticks for every μ ≥ tan θ; the enumeration's least-squares split needs an
///   equal share of the friction, μ ≥ 0.812 at 30°).
///
/// `Err(LcpError::NoSolution)` is Lemke's ray termination (Painlevé's inconsistency; see
/// its `known_slip`); the other errors are failures of the solver.
pub fn solutions(
    solver: &mut Solver,
    a: &nalgebra::DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
) -> Result<Vec<Solution>, LcpError> {
    let mut all = Vec::new();
    solutions_into(solver, a, b, allowed, &mut all)?;
    Ok(all)
}

/// [`solutions`] into `out`, whose solutions are replaced (their buffers kept in
/// `solver` and written into by this call or a later one): the same solutions, to the
/// bit, without allocating once the workspace has met the largest problem and the most
/// solutions (the enumeration's and Lemke's: its solution is written into a spare one,
/// its polish and repair work in the solver's buffers). On an error `out` is empty.
pub fn solutions_into(
    solver: &mut Solver,
    a: &nalgebra::DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
    out: &mut Vec<Solution>,
) -> Result<(), LcpError> {
    if allowed.len() <= ENUMERATED_UP_TO {
        solver.enumeration.solve_into(a, b, allowed, out);
        if !out.is_empty() {
            return Ok(());
        }
    } else {
        solver.enumeration.recycle(out);
    }
    let mut sol = solver.enumeration.spare();
    match solver.solve_into(a, b, allowed, &mut sol) {
        Ok(()) => {
            out.push(sol);
            Ok(())
        }
        Err(e) => {
            solver.enumeration.keep(sol);
            // Lemke's path can end on a ray where a solution exists (a known slip), or its
            // solution miss the conditions by rounding (ill-conditioned bases of redundant
            // points): a few points more are checked by the enumeration before giving up.
            let missed = matches!(e, LcpError::NoSolution { .. } | LcpError::Inaccurate { .. });
            if missed && (ENUMERATED_UP_TO + 1..=MAX_ENUMERATED).contains(&allowed.len()) {
                solver.enumeration.solve_into(a, b, allowed, out);
                if !out.is_empty() {
                    return Ok(());
                }
            }
            Err(e)
        }
    }
}
