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

mod enumerate;
mod friction;
pub mod lemke;
mod repair;

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
const TOL: Real = 1e-9;

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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// [`solutions_into`] on storage reused from earlier calls — of other sizes, with
    /// more or fewer solutions, `out` still holding them — gives the solutions of a fresh
    /// [`solutions`] (a new solver), bit for bit (modes, `x`, `w`), or the same error, on
    /// 4,000 random problems of 1 to 5 contacts (`A = Yᵀ Y` of full or deficient rank,
    /// slips known or not, points that may not open): the enumeration, and Lemke's
    /// algorithm beyond four contacts or where the enumeration finds none. Solved again,
    /// a problem is written into the same buffers (their addresses unchanged).
    #[test]
    fn solutions_into_reused_storage_is_a_fresh_call_to_the_bit() {
        use crate::linalg::tests::Lcg;
        let mut rng = Lcg(23);
        let (mut solver, mut out) = (Solver::new(), Vec::new());
        let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let same = |a: &[Solution], b: &[Solution]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(a, b)| {
                    a.modes == b.modes && bits(&a.x) == bits(&b.x) && bits(&a.w) == bits(&b.w)
                })
        };
        // How many problems had no solution (or an error), one, several.
        let mut counts = [0usize; 3];
        let mut rewritten = 0;
        for case in 0..4000 {
            let n = 1 + case % 5;
            let rank = 1 + (rng.unit() * (2 * n) as Real) as usize;
            let scale = 10f64.powi((case % 7) as i32 - 3);
            let y = DMatrix::from_fn(rank, 2 * n, |_, _| rng.next() * scale);
            let a = y.transpose() * &y;
            let b = DVector::from_fn(2 * n, |_, _| 5.0 * rng.next());
            let allowed: Vec<Allowed> = (0..n)
                .map(|_| Allowed {
                    mu: 1.5 * rng.unit(),
                    open: rng.unit() < 0.9,
                    slip: match (rng.unit() * 4.0) as usize {
                        0 => Some(1.0),
                        1 => Some(-1.0),
                        _ => None,
                    },
                })
                .collect();
            let fresh = solutions(&mut Solver::new(), &a, &b, &allowed);
            let reused = solutions_into(&mut solver, &a, &b, &allowed, &mut out);
            match (&fresh, &reused) {
                (Ok(all), Ok(())) => {
                    assert!(same(all, &out), "case {case}: {all:?} against {out:?}");
                    counts[all.len().min(2)] += 1;
                }
                (Err(e), Err(f)) => {
                    assert_eq!(format!("{e:?}"), format!("{f:?}"), "case {case}");
                    assert!(out.is_empty(), "case {case}: {out:?}");
                    counts[0] += 1;
                }
                _ => panic!("case {case}: {fresh:?} against {reused:?}"),
            }
            // The same problem again: the same solutions, in the same buffers.
            if case % 10 == 0 && !out.is_empty() && out.len() == fresh.as_ref().unwrap().len() {
                let at = |out: &[Solution]| {
                    (out.iter())
                        .map(|s| (s.modes.as_ptr(), s.x.as_ptr(), s.w.as_ptr()))
                        .collect::<Vec<_>>()
                };
                let before = at(&out);
                solutions_into(&mut solver, &a, &b, &allowed, &mut out).unwrap();
                assert!(same(fresh.as_ref().unwrap(), &out), "case {case}, again");
                // Lemke's one solution is a new one; the enumeration's are rewritten.
                if allowed.len() <= ENUMERATED_UP_TO && out.len() > 1 {
                    let mut after = at(&out);
                    let mut before = before;
                    after.sort();
                    before.sort();
                    assert_eq!(before, after, "case {case}: other buffers");
                    rewritten += 1;
                }
            }
        }
        println!(
            "none {}, one {}, several {}; {rewritten} rewritten in place",
            counts[0], counts[1], counts[2]
        );
        assert!(counts.iter().all(|&c| c > 100), "{counts:?}");
        assert!(rewritten >= 5, "{rewritten} rewritten in place");
    }

    #[test]
    fn a_negative_normal_force_opens_its_contact_and_w_follows() {
        // Two coupled contacts, the first sliding with x_n = −1e-13 (rounding), the
        // second sticking.
        let a = DMatrix::from_row_slice(
            4,
            4,
            &[
                2.0, 0.3, 0.5, 0.1, //
                0.3, 1.0, 0.2, 0.4, //
                0.5, 0.2, 3.0, 0.6, //
                0.1, 0.4, 0.6, 1.5,
            ],
        );
        let b = DVector::from_column_slice(&[1e-13, 0.2, -1.2, 0.05]);
        let x = DVector::from_column_slice(&[-1e-13, 5e-14, 0.4, -0.03]);
        let mut sol = Solution {
            modes: vec![Mode::Slide(-1.0), Mode::Stick],
            w: &a * &x + &b,
            x,
        };
        assert_eq!(sol.open_negative_normals(&a, &b), 1);
        assert_eq!(sol.modes, vec![Mode::Open, Mode::Stick]);
        assert_eq!((sol.x[0], sol.x[1]), (0.0, 0.0));
        assert_eq!((sol.x[2], sol.x[3]), (0.4, -0.03));
        // w = A x + b of the new forces.
        let w = &a * &sol.x + &b;
        assert!((&sol.w - &w).amax() < 1e-15);
        // Nothing left to open.
        assert_eq!(sol.open_negative_normals(&a, &b), 0);
    }
}
