//! The contact problem of the table in [`crate::lcp`] written as one standard LCP, solved by
//! Lemke's algorithm ([`super::lemke`]): one solution, in polynomial time in practice,
//! for many contacts.
//!
//! **Formulation** (Stewart and Trinkle's split of the planar friction cone into its two
//! edges [ST; AP]). A contact whose slip is not known has four LCP variables, its normal
//! force `x_n`, the two edge forces `f⁺, f⁻` with `x_t = f⁺ − f⁻`, and the slip magnitude
//! `σ`:
//!
//! ```text
//! 0 ≤ x_n ⊥ w_n              ≥ 0
//! 0 ≤ f⁺  ⊥ σ + w_t          ≥ 0
//! 0 ≤ f⁻  ⊥ σ − w_t          ≥ 0
//! 0 ≤ σ   ⊥ μ x_n − f⁺ − f⁻  ≥ 0          (w = A x + b, x_t = f⁺ − f⁻)
//! ```
//!
//! The signs against the table: if `w_t > 0` then `σ ≥ w_t > 0`, so `f⁺ + f⁻ = μ x_n` and
//! `f⁺ = 0` (its partner `σ + w_t > 0`): `x_t = −μ x_n`, slide `s = +1` with `s w_t ≥ 0`;
//! `w_t < 0` mirrors it (`s = −1`); `w_t = 0` with `σ = 0` leaves `f⁺ + f⁻ ≤ μ x_n`, stick;
//! `x_n = 0` forces `f⁺ = f⁻ = 0`, open. So the LCP's solutions are the table's.
//!
//! A contact with a known slip `s` has one variable `x_n`, with `x_t = −μ s x_n`
//! substituted into `A`'s columns: its column is `A_:n − μ s A_:t`, its row `w_n ⊥ x_n`
//! (the non-symmetric case where Painlevé's paradox lives: `A_nn − μ s A_nt < 0` with a
//! pressing `b_n`, and Lemke ends on a ray). A contact with `μ = 0` has one variable `x_n`
//! too (`x_t = 0`).
//!
//! **Scaling.** The rows of `w` are divided by `s_A = max|A|` and `σ` is measured in the
//! same unit (`σ = s_A σ̂`), so the LCP matrix has entries `A/s_A`, `±1` and `μ`, all of
//! order one, whatever the units of `A` (a positive row and column scaling does not change
//! the LCP's solutions).
//!
//! **Back to modes.** `x_n ≤ TOL (max|x| + max|b| / max|A|)` is open (its forces set to
//! exactly 0; the second term is the problem's unit of force, for solutions `x ≈ 0`); a known
//! slip slides; else `|w_t| > tol_w` slides along `w_t`, and the rest sticks, where
//! `tol_w = TOL (max|b| + max|A| max|x|)` is the enumeration's. `Solution::w = A x + b`
//! as the enumeration computes it. The modes' conditions are checked before the solution
//! is returned ([`LcpError::Inaccurate`] if rounding broke them).
//!
//! **When Lemke's path can end on a ray** (every slip unknown; a known slip makes `M`
//! non-copositive, Painlevé's case, and none of this holds). `M` is copositive when `A` is
//! positive semidefinite: for `z ≥ 0`, `zᵀMz = yᵀAy + Σ μ σ x_n ≥ 0`, `y = (x_n, x_t)`
//! (the `±σ f±` terms of the cone rows cancel). Anitescu and Potra's argument [AP; CPS,
//! §3.8 and §4.4], in exact arithmetic with the lexicographic rule: a ray is an unbounded
//! edge `(z + λ z*, z₀)` of the augmented problem with `z₀ > 0` and `z* ≥ 0, z* ≠ 0`,
//! `M z* ≥ 0`, complementary along the edge: `zᵀM z* = z*ᵀM z* = 0` and
//! `z*ᵀ(M z + q + d z₀) = 0`. Copositivity at `z* + ε z` gives `z*ᵀM z ≥ −zᵀM z* = 0`, so
//! `qᵀz* = −z*ᵀM z − z₀ dᵀz* < 0`. Here `z*ᵀM z* = 0` means `A y* = 0` and
//! `σ*_i x*_n,i = 0`, `M z* ≥ 0` means `f*⁺ + f*⁻ ≤ μ x*_n`, and `qᵀz* = bᵀy*` (`q_σ = 0`).
//! So **a ray needs contact forces `y*` in the friction cones with `A y* = 0` (`Jᵀy* = 0`:
//! points jammed, forces that balance each other) and `bᵀy* < 0`**, and there is none:
//!
//! - when a velocity `u` lifts every point off (`J_n u > μ |J_t u|` row by row): then
//!   `uᵀJᵀy* = Σ (J_n u) x*_n + (J_t u) x*_t > 0` for every nonzero `y*` in the cones;
//!   whatever `b` — bodies on a floor (the chain: `u` lifts everything), every point at
//!   rest or approaching, with any tangential `b`;
//! - when `b = J v` is in the range of `A` (`bᵀy* = vᵀJᵀy* = 0`): time stepping [AP], the
//!   Newton law with `e = 0`, the free accelerations of persistent contacts.
//!
//! They can still happen with restitution at jammed points: Newton's law gives
//! `b = J v⁻ + e (J_n v⁻ on the approaching rows)`, so `bᵀy* = e Σ (J_n v⁻)_i x*_n,i < 0`
//! when `y*` loads an approaching point (a wedge closing). Then the ray does not prove that
//! no solution exists either (`M` is not copositive-plus: a sliding solution may exist that
//! the path misses). In floating point the path must also see exactly-zero basic values as
//! zero; the rays the 32-link chain met (b_n = 0 at rest, two points at one hinge) were
//! rounding (`lcp::lemke`, "Numerics"): `tests/all/lcp_lemke.rs` counts rays on 600 such
//! problems of up to 32 points (zero) and the misses on random ones.
//!
//! References: **[ST]** D. E. Stewart, J. C. Trinkle, *An implicit time-stepping scheme for
//! rigid body dynamics with inelastic collisions and Coulomb friction*, IJNME 39 (1996).
//! **[AP]** M. Anitescu, F. A. Potra, *Formulating dynamic multi-rigid-body contact
//! problems with friction as solvable linear complementarity problems*, Nonlinear Dynamics
//! 14 (1997). **[CPS]** see [`super::lemke`].

use nalgebra::{DMatrix, DMatrixView, DVector, DVectorView};

use super::lemke::{Lemke, LemkeError, LemkeStatus};
use super::repair;
use super::{Allowed, Mode, Solution, TOL};
use crate::linalg::fit_vector;
use crate::math::Real;

/// Why [`Solver::solve`] returned no solution.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum LcpError {
    /// Lemke's algorithm ended on a ray: the problem has no solution (Painlevé's
    /// inconsistency) when its LCP matrix is copositive-plus or `b` lies in the range of
    /// `A` (see the module's doc for when it only means that Lemke's path missed one).
    #[error("the contact problem has no solution (Lemke's ray termination after {pivots} pivots)")]
    NoSolution {
        /// Pivots of all the paths tried.
        pivots: usize,
        /// A contact had a known slip: the LCP matrix is not copositive, and Lemke's rays
        /// (along `1 + RETRIES` covering vectors) do not prove that no solution exists
        /// (measured: 17 solvable problems of 8,000 random ones reported so, all with a
        /// known slip; `tests/all/lcp_lemke.rs`).
        known_slip: bool,
    },
    /// Lemke's algorithm reached its pivot limit.
    #[error("the contact problem was not solved within {pivots} pivots of Lemke's algorithm")]
    PivotLimit {
        /// Pivots made.
        pivots: usize,
    },
    /// `A` or `b` has a NaN or an infinite entry.
    #[error("the contact problem is not finite (A or b has a NaN or an infinite entry)")]
    NotFinite,
    /// The sizes of `A`, `b` and `allowed` do not match.
    #[error(
        "the contact problem's sizes do not match: A is {rows}×{cols}, b has {b} entries, \
         {contacts} contacts (A must be 2n×2n and b 2n)"
    )]
    Shape {
        /// Rows of `A`.
        rows: usize,
        /// Columns of `A`.
        cols: usize,
        /// Entries of `b`.
        b: usize,
        /// Contacts (`allowed.len()`).
        contacts: usize,
    },
    /// A contact's `μ` is negative or not finite, or its slip is not finite.
    #[error("contact {contact}: μ = {mu} and slip {slip:?} (μ must be finite and ≥ 0)")]
    BadContact {
        /// The contact.
        contact: usize,
        /// Its `μ`.
        mu: Real,
        /// Its slip.
        slip: Option<Real>,
    },
    /// A contact may not open (`Allowed::open == false`): `w_n = 0` with `x_n ≥ 0` is not a
    /// complementarity condition; only the enumeration ([`super::solve`]) takes it.
    #[error(
        "contact {contact} may not open: the complementarity solver needs every contact free to open"
    )]
    MustStayClosed {
        /// The contact.
        contact: usize,
    },
    /// Lemke's solution misses the conditions of its modes by more than [`CHECK_TOL`]
    /// (relative): rounding on an ill-conditioned problem.
    #[error("Lemke's solution misses the conditions of its modes by {violation:.1e} (relative)")]
    Inaccurate {
        /// The largest relative violation.
        violation: Real,
    },
}

/// The relative tolerance of the final check of the modes' conditions (see
/// [`conditions_violation`]).
pub const CHECK_TOL: Real = 1e-7;

/// Lemke's solutions that miss their modes' conditions by more than this (relative, see
/// [`conditions_violation`]) are polished: their modes' forces solved again from the
/// modes' own linear system.
pub const POLISH_TOL: Real = 1e-12;

/// The other covering vectors tried when Lemke's path with `d = 1` fails
/// ([`Solver::solve`]): a ray on a problem with a known slip (not copositive: the ray
/// proves nothing) or without (where a ray is rounding's, the module doc: the 32-link
/// chain's 28-point impact ended on a ray after 67 pivots along `d = 1` and was solved
/// along the first other vector, to 1.4e-16), the pivot limit (a cycle by rounding), or
/// a solution whose modes miss their conditions after the polish and the repair (the
/// 45-point impact at t = 2.33 s, 1.2e-3); `tests/all/lcp_lemke.rs`.
pub const RETRIES: usize = 8;

/// How a contact enters the LCP.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Slip not known, `μ > 0`: `(x_n, f⁺, f⁻, σ̂)`.
    Cone,
    /// One variable `x_n`, with `x_t = tau x_n` (`tau = −μ s` for a known slip `s`, 0 for
    /// `μ = 0`).
    Normal {
        /// `x_t / x_n`.
        tau: Real,
    },
}

/// The complementarity solver of the contact problem: Lemke's algorithm on the LCP of the
/// module's doc, with its workspace (buffers grown to the largest problem seen and reused).
#[derive(Clone, Debug, Default)]
pub struct Solver {
    /// Lemke's workspace.
    lemke: Lemke,
    /// The LCP matrix `M` (k × k, column-major).
    m: Vec<Real>,
    /// The LCP vector `q` (k).
    q: Vec<Real>,
    /// How each contact enters, and its first LCP variable.
    kinds: Vec<(Kind, usize)>,
    /// The LCP rows as combinations of `A`'s rows: (LCP row, row of `A`, sign).
    rows: Vec<(usize, usize, Real)>,
    /// The LCP columns as combinations of `A`'s columns: (LCP column, column of `A`, coefficient).
    cols: Vec<(usize, usize, Real)>,
    /// Lemke's pivots in the last call.
    pivots: usize,
    /// A covering vector of a retry (k).
    cover: Vec<Real>,
    /// The polish's solution (the forces of Lemke's modes solved again), against Lemke's
    /// own.
    polish: Solution,
    /// The buffers of the polish and the repair.
    fix: repair::Workspace,
    /// The enumeration's workspace, for [`super::solutions_into`].
    pub(super) enumeration: super::Enumeration,
}

impl Solver {
    /// A solver with an empty workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// The pivots Lemke's algorithm made in the last call of [`Solver::solve`].
    pub fn pivots(&self) -> usize {
        self.pivots
    }

    /// Sets the most pivots of one call (`None`: Lemke's default, `max(1000, 50 k)` for `k`
    /// LCP variables).
    pub fn set_max_pivots(&mut self, max: Option<usize>) {
        self.lemke.max_pivots = max;
    }

    /// One solution of `w = A x + b` with the allowed modes (the conventions and
    /// [`Solution`] of [`super::solve`]: modes, `x` (2n), `w = A x + b` (2n)), by Lemke's
    /// algorithm on the LCP of the module's doc (Stewart–Trinkle's friction cone edges).
    /// `A` is `2n × 2n`, `b` has `2n` entries, `allowed` has `n`. Where the problem has
    /// several solutions (Painlevé's indeterminacy, redundant contacts sharing a force),
    /// the one at the end of Lemke's path.
    pub fn solve(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
    ) -> Result<Solution, LcpError> {
        let mut sol = Solution::default();
        self.solve_into(a, b, allowed, &mut sol)?;
        Ok(sol)
    }

    /// [`Solver::solve`] written into `out` (its buffers reused): the same solution, to
    /// the bit, without allocating once the solver and `out` have met a problem of this
    /// size (Lemke's path, the polish and the repair work in the solver's buffers). On an
    /// error `out`'s numbers mean nothing.
    pub fn solve_into(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        out: &mut Solution,
    ) -> Result<(), LcpError> {
        self.validate(a, b, allowed)?;
        let k = self.layout(allowed);
        let sa = a.amax();
        let sa = if sa > 0.0 { sa } else { 1.0 };
        self.assemble(a, b, allowed, k, sa);
        let known_slip = allowed.iter().any(|c| c.slip.is_some());
        let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
        self.pivots = 0;
        // How the paths failed: the least violation of a solved path that missed its
        // conditions, and whether the last other one hit the pivot limit.
        let mut inaccurate: Option<Real> = None;
        let mut limit = false;
        for attempt in 0..=RETRIES {
            match self.lemke_path(allowed, k, attempt, &mut seed)? {
                LemkeStatus::Solved { .. } => {
                    let violation = self.polished(a, b, allowed, out);
                    if violation <= CHECK_TOL {
                        return Ok(());
                    }
                    // Lemke's modes wrong at a few points: single mode changes from them.
                    self.fix.start_from(&out.modes);
                    if self.fix.repair(a, b, allowed, out) {
                        return Ok(());
                    }
                    inaccurate = Some(inaccurate.map_or(violation, |v| v.min(violation)));
                }
                LemkeStatus::RayTermination { .. } => limit = false,
                LemkeStatus::PivotLimit { .. } => limit = true,
            }
        }
        // Every path failed. With every slip unknown a ray is rounding's (the module doc),
        // and so is a cycle: the repair from the pressed points may still find the
        // solution.
        if inaccurate.is_some() || limit || !known_slip {
            self.fix.start_pressed(b, allowed);
            if self.fix.repair(a, b, allowed, out) {
                return Ok(());
            }
        }
        Err(match inaccurate {
            Some(violation) => LcpError::Inaccurate { violation },
            None if limit => LcpError::PivotLimit {
                pivots: self.pivots,
            },
            None => LcpError::NoSolution {
                pivots: self.pivots,
                known_slip,
            },
        })
    }

    /// The solution at the end of a solved Lemke path, polished where it misses its
    /// modes' conditions by more than [`POLISH_TOL`]: Lemke's modes (the active set) are
    /// right where its pivots' rounding is not (ill-conditioned bases of redundant points:
    /// 9e-7 on the 32-link chain lying on the floor); the forces of those modes from their
    /// own linear system ([`super::forces`]) meet the conditions to rounding. Written into
    /// `out`; returns its violation.
    fn polished(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        out: &mut Solution,
    ) -> Real {
        self.modes(a, b, allowed, out);
        let mut violation = self.fix.violation(a, b, allowed, out);
        if violation > POLISH_TOL
            && (self.fix).forces_into(a, b, allowed, &out.modes, &mut self.polish)
        {
            let v = self.fix.violation(a, b, allowed, &self.polish);
            if v < violation {
                std::mem::swap(out, &mut self.polish);
                violation = v;
            }
        }
        violation
    }

    /// Runs Lemke's algorithm on the assembled LCP of size `k` along the covering vector of
    /// `attempt`: `d = 1` first, then (after a ray, the pivot limit, or a solution that
    /// misses its conditions) [`RETRIES`] others, a fixed pseudo-random sequence with
    /// entries in [0.01, 100] drawn from `seed`. Adds its pivots to `self.pivots`.
    fn lemke_path(
        &mut self,
        allowed: &[Allowed],
        k: usize,
        attempt: usize,
        seed: &mut u64,
    ) -> Result<LemkeStatus, LcpError> {
        let m = DMatrixView::from_slice(&self.m[..k * k], k, k);
        let q = DVectorView::from_slice(&self.q[..k], k);
        let d = if attempt == 0 {
            None
        } else {
            self.cover.clear();
            for _ in 0..k {
                // xorshift64*: uniform u in [0, 1), d = 10^(4u − 2).
                *seed ^= *seed >> 12;
                *seed ^= *seed << 25;
                *seed ^= *seed >> 27;
                let u =
                    (seed.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as Real / (1u64 << 53) as Real;
                self.cover.push((10.0 as Real).powf(4.0 * u - 2.0));
            }
            Some(&self.cover[..])
        };
        let status = self.lemke.solve_covered(&m, &q, d).map_err(|e| match e {
            LemkeError::Shape { rows, cols, q } => LcpError::Shape {
                rows,
                cols,
                b: q,
                contacts: allowed.len(),
            },
            LemkeError::NotFinite | LemkeError::Cover => LcpError::NotFinite,
        })?;
        let (LemkeStatus::Solved { pivots }
        | LemkeStatus::RayTermination { pivots }
        | LemkeStatus::PivotLimit { pivots }) = status;
        self.pivots += pivots;
        Ok(status)
    }

    /// Checks the sizes and the contacts' data.
    fn validate(
        &self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
    ) -> Result<(), LcpError> {
        let n = allowed.len();
        if a.nrows() != 2 * n || a.ncols() != 2 * n || b.len() != 2 * n {
            return Err(LcpError::Shape {
                rows: a.nrows(),
                cols: a.ncols(),
                b: b.len(),
                contacts: n,
            });
        }
        if !a.iter().chain(b.iter()).all(|v| v.is_finite()) {
            return Err(LcpError::NotFinite);
        }
        for (i, c) in allowed.iter().enumerate() {
            if !(c.mu.is_finite() && c.mu >= 0.0) || c.slip.is_some_and(|s| !s.is_finite()) {
                return Err(LcpError::BadContact {
                    contact: i,
                    mu: c.mu,
                    slip: c.slip,
                });
            }
            if !c.open {
                return Err(LcpError::MustStayClosed { contact: i });
            }
        }
        Ok(())
    }

    /// How each contact enters the LCP and where its variables start; returns the LCP's
    /// size `k`. Fills the row and column maps from `A` to `M`.
    fn layout(&mut self, allowed: &[Allowed]) -> usize {
        self.kinds.clear();
        self.rows.clear();
        self.cols.clear();
        let mut k = 0;
        for (i, c) in allowed.iter().enumerate() {
            let (rn, rt) = (2 * i, 2 * i + 1);
            let kind = match c.slip {
                None if c.mu > 0.0 => Kind::Cone,
                Some(s) => Kind::Normal { tau: -c.mu * s },
                None => Kind::Normal { tau: 0.0 },
            };
            self.kinds.push((kind, k));
            // x_n: its row is w_n; its column A_:n + τ A_:t.
            self.rows.push((k, rn, 1.0));
            self.cols.push((k, rn, 1.0));
            match kind {
                Kind::Normal { tau } => {
                    if tau != 0.0 {
                        self.cols.push((k, rt, tau));
                    }
                    k += 1;
                }
                Kind::Cone => {
                    // f⁺: row σ + w_t, column A_:t; f⁻: row σ − w_t, column −A_:t.
                    self.rows.push((k + 1, rt, 1.0));
                    self.rows.push((k + 2, rt, -1.0));
                    self.cols.push((k + 1, rt, 1.0));
                    self.cols.push((k + 2, rt, -1.0));
                    k += 4;
                }
            }
        }
        k
    }

    /// The LCP `(M, q)` of size `k`, `A` and `b` scaled by `1/s_A`:
    ///
    /// ```text
    /// M[r, c] = Σ sign · coef · A[ra, ca] / s_A   over the row and column maps,
    ///           + the cone's entries: M[f±, σ] = 1, M[σ, x_n] = μ, M[σ, f±] = −1
    /// q[r]    = Σ sign · b[ra] / s_A              (0 for σ's row)
    /// ```
    fn assemble(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        allowed: &[Allowed],
        k: usize,
        sa: Real,
    ) {
        self.m.clear();
        self.m.resize(k * k, 0.0);
        self.q.clear();
        self.q.resize(k, 0.0);
        for &(r, ra, sign) in &self.rows {
            self.q[r] += sign * b[ra] / sa;
            for &(c, ca, coef) in &self.cols {
                self.m[r + c * k] += sign * coef * a[(ra, ca)] / sa;
            }
        }
        for (&(kind, o), c) in self.kinds.iter().zip(allowed) {
            if kind == Kind::Cone {
                let (xn, fp, fm, sigma) = (o, o + 1, o + 2, o + 3);
                self.m[fp + sigma * k] = 1.0;
                self.m[fm + sigma * k] = 1.0;
                self.m[sigma + xn * k] = c.mu;
                self.m[sigma + fp * k] = -1.0;
                self.m[sigma + fm * k] = -1.0;
            }
        }
    }

    /// The forces, modes and `w = A x + b` of Lemke's solution (module doc, "Back to
    /// modes"), written into `out`.
    fn modes(&self, a: &DMatrix<Real>, b: &DVector<Real>, allowed: &[Allowed], out: &mut Solution) {
        let n = allowed.len();
        let z = self.lemke.z();
        let x = &mut out.x;
        fit_vector(x, 2 * n);
        x.fill(0.0);
        for (i, &(kind, o)) in self.kinds.iter().enumerate() {
            x[2 * i] = z[o];
            x[2 * i + 1] = match kind {
                Kind::Cone => z[o + 1] - z[o + 2],
                Kind::Normal { tau } => tau * z[o],
            };
        }
        // Forces in the problem's own unit max|b| / max|A| too: where the solution is x = 0
        // (every point open) Lemke's degenerate basis leaves x ~ 1e-17, and max|x| alone
        // would call that noise a contact force.
        let sa = a.amax();
        let unit = if sa > 0.0 { b.amax() / sa } else { 0.0 };
        let tol_x = TOL * (x.amax() + unit);
        let modes = &mut out.modes;
        modes.clear();
        for i in 0..n {
            if x[2 * i] <= tol_x {
                x[2 * i] = 0.0;
                x[2 * i + 1] = 0.0;
                modes.push(Mode::Open);
            } else {
                // Placeholder until w is known.
                modes.push(Mode::Stick);
            }
        }
        // w = A x + b (`a * x + b`, in place).
        let w = &mut out.w;
        fit_vector(w, 2 * n);
        a.mul_to(x, w);
        *w += b;
        let tol_w = TOL * (b.amax() + a.amax() * x.amax());
        for (i, c) in allowed.iter().enumerate() {
            if modes[i] == Mode::Open {
                continue;
            }
            let wt = w[2 * i + 1];
            modes[i] = match c.slip {
                Some(s) => Mode::Slide(s),
                None if wt.abs() > tol_w => Mode::Slide(wt.signum()),
                None => Mode::Stick,
            };
        }
    }
}

/// The largest violation of the table's conditions (module [`crate::lcp`]) by `sol`,
/// relative to the scales of the problem, `max|x|` for forces and
/// `max|b| + max|A| max|x|` for `w`; 0 for an exact solution:
///
/// ```text
/// every contact:  w = A x + b (recomputed)
/// open:           x_n = x_t = 0,  w_n ≥ 0
/// stick:          w_n = w_t = 0,  x_n ≥ 0,  |x_t| ≤ μ x_n          (slip not known)
/// slide s:        w_n = 0,  x_n ≥ 0,  x_t = −μ s x_n,  s w_t ≥ 0 if the slip starts
/// ```
pub fn conditions_violation(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
    sol: &Solution,
) -> Real {
    let (mut w, mut diff) = (DVector::zeros(0), DVector::zeros(0));
    violation_in(a, b, allowed, sol, &mut w, &mut diff)
}

/// [`conditions_violation`] with its `w = A x + b` recomputed into `w` and its difference
/// from `sol.w` into `diff` (kept buffers, resized to 2n): the same number, to the bit.
#[doc(hidden)]
pub fn violation_in(
    a: &DMatrix<Real>,
    b: &DVector<Real>,
    allowed: &[Allowed],
    sol: &Solution,
    w: &mut DVector<Real>,
    diff: &mut DVector<Real>,
) -> Real {
    let x = &sol.x;
    let sx = x.amax().max(Real::MIN_POSITIVE);
    let sw = (b.amax() + a.amax() * x.amax()).max(Real::MIN_POSITIVE);
    // `a * x + b` and `(&w - &sol.w).amax()`, in place.
    fit_vector(w, a.nrows());
    a.mul_to(x, w);
    *w += b;
    fit_vector(diff, w.len());
    diff.copy_from(w);
    *diff -= &sol.w;
    let mut worst = diff.amax() / sw;
    for (i, (c, mode)) in allowed.iter().zip(&sol.modes).enumerate() {
        let (xn, xt, wn, wt) = (x[2 * i], x[2 * i + 1], w[2 * i], w[2 * i + 1]);
        let v = match *mode {
            Mode::Open => (xn.abs().max(xt.abs()) / sx).max(-wn / sw),
            Mode::Stick => {
                let forces = (-xn).max(xt.abs() - c.mu * xn) / sx;
                let slip = if c.slip.is_some() {
                    Real::INFINITY
                } else {
                    wt.abs() / sw
                };
                forces.max(wn.abs() / sw).max(slip)
            }
            Mode::Slide(s) => {
                let start = if c.slip.is_none() { -s * wt / sw } else { 0.0 };
                let wrong_way = match c.slip {
                    Some(known) if known != s => Real::INFINITY,
                    _ => 0.0,
                };
                (wn.abs() / sw)
                    .max(-xn / sx)
                    .max((xt + c.mu * s * xn).abs() / sx)
                    .max(start)
                    .max(wrong_way)
            }
        };
        worst = worst.max(v);
    }
    worst
}
