//! Lemke's complementary pivoting algorithm for the standard linear complementarity
//! problem LCP(q, M) [CPS, §4.4]:
//!
//! ```text
//! find z ∈ ℝⁿ:   w = M z + q ≥ 0,   z ≥ 0,   wᵀ z = 0
//! ```
//!
//! **Scheme 1 of [CPS, §4.4]**: the augmented system `w = M z + d z₀ + q` with the
//! covering vector `d = 1` (every component positive, so the starting point `z = 0`,
//! `z₀ = −min q` is feasible; the problem is first scaled to `max|M| = max|q| = 1`, so that
//! `d = 1` weighs all rows alike). `z₀` enters, the row of the most negative `q` leaves;
//! then the complement of the variable that left enters, and the ratio test picks the
//! variable that leaves, until `z₀` leaves (a solution, `z₀ = 0`) or the entering column
//! has no positive entry (**ray termination**: an unbounded edge of the augmented
//! problem). For a copositive-plus `M` (positive semidefinite ones included) ray
//! termination proves that the LCP has no feasible point [CPS, §4.4]; for other
//! matrices it only says that Lemke's path did not find a solution.
//!
//! **Lexicographic minimum ratio test** [CPS, §4.9]: among the rows that tie in the ratio
//! `x_B,i / col_i`, the one whose row of `[x_B | B⁻¹] / col_i` is lexicographically
//! smallest leaves. Since `B⁻¹` is regular no two such rows are equal, so the choice is
//! unique and no basis repeats: Lemke's path cannot cycle, even on degenerate problems
//! (redundant contact rows, `q_i = 0`). When `z₀` is among the rows tied in the first
//! column it leaves at once (a solution, the usual practice of PATH and Drake).
//!
//! **Numerics.** The revised form: the workspace keeps `B⁻¹` (n × n, row-major) and the
//! basic values `x_B = B⁻¹ q`, updated by one Gauss–Jordan step per pivot (`2n²` flops),
//! and computes the entering column `B⁻¹ a_e` on demand (`n²`). Tolerances are relative:
//! the problem is scaled to `max|M| = max|q| = 1`, an entry of the entering column counts
//! as positive above [`PIVOT_TOL`] times the column's largest (and is zero when it is a
//! cancellation below [`CANCEL_TOL`] of its terms), ratios tie within
//! [`TIE_TOL`]. After every pivot one step of iterative refinement with the basis' own
//! columns (`x_B += B⁻¹ (q − B x_B)`, `2n²` flops more) removes the rounding of the update,
//! and the path ends as soon as `z₀` is within [`Z0_TOL`] of zero (a basic `z₀ = 0`: the
//! basis is a solution); at the end two more steps, and `w = M z + q` is computed from the
//! original data, `z₀` counted as 0.
//!
//! Why both (issue 15, the 32-link chain on the floor): on degenerate, ill-conditioned
//! problems (`q_i = 0` for points at rest, nearly equal columns for two points at one
//! hinge) the path takes pivots of `1.6e-7` and growths of `2.3e4`; the updated `x_B`
//! drifts by `~1e-9` from `B⁻¹ q` of its own basis. Where `z₀` and another row tie in
//! exact arithmetic (both reach zero on the same step) their computed ratios then differ by
//! more than [`TIE_TOL`], the other row leaves, `z₀` stays in the basis at `3.6e-10`
//! instead of 0, and the path goes on to a ray that exact arithmetic excludes (the same
//! data in rational arithmetic: solved in 17 and 27 pivots). With the refinement `z₀` is
//! `4e-20` after that pivot, and the `Z0_TOL` test ends the path there. Neither alone is
//! enough: without the refinement `z₀` is `3.6e-10` (a tolerance of `1e-9` would be
//! needed); without the test the refined path still ends on the ray (a replica of this
//! code in Python, run on both dumps).
//!
//! **Why not a crate.** Searched (2026): no maintained Rust crate implements Lemke's
//! algorithm. `lemke-rs` (GitHub megesdal/lemke-rs, a port of GameTheoryExplorer's
//! exact-rational Lemke for bimatrix games) has no release on crates.io; the LP crates
//! (`good_lp`, `minilp`/`microlp`, `rustplex`) solve linear programs, not LCPs; the
//! maintained implementations are C++ (Drake's `UnrevisedLemkeSolver`, DART, Siconos,
//! PATH). Lemke with a lexicographic rule is ~300 lines on nalgebra's types, so it is
//! written here, with the allocation-free workspace the simulation loop wants.
//!
//! Reference: **\[CPS\]** R. W. Cottle, J.-S. Pang, R. E. Stone, *The Linear Complementarity
//! Problem*, Academic Press (1992), §4.4 (Lemke's method), §4.9 (degeneracy, lexicographic
//! pivoting).

use nalgebra::{Dim, Matrix, RawStorage, U1};

use crate::math::Real;

/// An entry of the entering column counts as positive (a pivot candidate) above this
/// fraction of the column's largest magnitude (scaled problem). Below it the entry is
/// rounding of a zero: pivoting on it would blow up `B⁻¹`.
pub const PIVOT_TOL: Real = 1e-11;

/// An entry `Σ_k B⁻¹_ik a_k` of a `z_j`'s entering column below this fraction of
/// `Σ_k |B⁻¹_ik a_k|` is the rounding of a zero and is set to 0: pivoting on it makes `B`
/// singular. The 16-link chain (an 11-point impact, `tests/all/lcp_lemke.rs`) pivoted on such
/// an entry, `1.1e-11` of its terms (`1.3e-11` of the column's largest, past
/// [`PIVOT_TOL`]); `B⁻¹` grew to `3e10` and the "solution" had `w_n = −0.03`. Measured on
/// that path: the rounding zeros reach `1.1e-11` of their terms, the smallest other entries
/// `7.9e-10`; the tolerance sits between.
pub const CANCEL_TOL: Real = 1e-10;

/// Two ratios of the ratio test tie within this relative difference (scaled problem).
pub const TIE_TOL: Real = 1e-11;

/// A basic `z₀` at most this fraction of its starting value counts as zero: the basis is
/// then a solution (`z₀` reached zero together with the row that the ratio test chose, a
/// tie that the rounding of the ratios hid).
pub const Z0_TOL: Real = 1e-11;

/// How a run of Lemke's algorithm ended (outcomes, not failures: see [`LemkeError`] for
/// bad input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LemkeStatus {
    /// `z₀` left the basis: [`Lemke::z`] and [`Lemke::w`] solve the LCP.
    Solved {
        /// Pivots made (0 when `q ≥ 0`: `z = 0`).
        pivots: usize,
    },
    /// The entering column had no positive entry: an unbounded ray of the augmented
    /// problem. For copositive-plus `M`, the LCP has no solution.
    RayTermination {
        /// Pivots made before the ray.
        pivots: usize,
    },
    /// The pivot limit ([`Lemke::max_pivots`]) was reached first.
    PivotLimit {
        /// Pivots made.
        pivots: usize,
    },
}

/// Input Lemke's algorithm cannot take.
#[derive(thiserror::Error, Clone, Debug, PartialEq)]
pub enum LemkeError {
    /// `M` is not square, or `q` does not match it.
    #[error("Lemke: M is {rows}×{cols} and q has {q} entries (M must be n×n, q n)")]
    Shape {
        /// Rows of `M`.
        rows: usize,
        /// Columns of `M`.
        cols: usize,
        /// Entries of `q`.
        q: usize,
    },
    /// `M` or `q` has a NaN or an infinite entry.
    #[error("Lemke: M or q is not finite")]
    NotFinite,
    /// The covering vector does not have `n` positive finite entries.
    #[error("Lemke: the covering vector must have n positive finite entries")]
    Cover,
}

/// The workspace of Lemke's algorithm: its buffers grow to the largest problem solved and
/// are reused, so that a warmed-up workspace solves without allocating.
///
/// `B⁻¹` is kept column by column: the entering column `B⁻¹ a_e`, the refinement's
/// `B⁻¹ r` and the pivot's row operations are sweeps down contiguous columns, every entry
/// of a result accumulated in the same order (over `k`) as a row-by-row dot product.
/// Column `k` of `B⁻¹` stays the unit vector of its row while `w_k` is basic (`B⁻¹ =
/// [[I, −X Y⁻¹], [0, Y⁻¹]]` up to a permutation, `Y` the rows of the basic `z`'s columns
/// that left): such a column is one term of a sum and no work in a pivot. Only terms that
/// are products with an exact zero are left out; see [`Lemke::pivot`] for why that
/// changes no bit of the path or of the solution.
#[derive(Clone, Debug, Default)]
pub struct Lemke {
    /// Problem size `n`.
    n: usize,
    /// The most pivots of one run; `None`: `max(1000, 50 n)`.
    pub max_pivots: Option<usize>,
    /// `B⁻¹` (n × n, column-major: `B⁻¹_ik` at `k n + i`).
    binv: Vec<Real>,
    /// Basic values `x_B = B⁻¹ q̂` (n).
    xb: Vec<Real>,
    /// The variable of each basis row: `0..n` is `w_i`, `n..2n` is `z_j`, `2n` is `z₀`.
    basis: Vec<usize>,
    /// The entering column `B⁻¹ a_e` (n).
    col: Vec<Real>,
    /// The covering vector `d` (n).
    cover: Vec<Real>,
    /// Scratch: the residual of the refinement (n).
    scratch: Vec<Real>,
    /// Scratch: running sums of the column sweeps (n).
    acc: Vec<Real>,
    /// Scratch: running sums of magnitudes of the entering column's terms, then the
    /// ratios of the ratio test (n).
    size: Vec<Real>,
    /// The scaled `q̂ = q / s_q` (n).
    qhat: Vec<Real>,
    /// The row of column `k` of `B⁻¹` if that column is a unit vector (the `1` there,
    /// exact zeros elsewhere), else [`DENSE`] (n).
    unit: Vec<usize>,
    /// `M`, unscaled, contiguous (n × n, column-major).
    mc: Vec<Real>,
    /// The rows of `M`'s nonzero entries, column after column.
    nz: Vec<usize>,
    /// Where each column's rows start in `nz` (n + 1).
    nz_start: Vec<usize>,
    /// Tied rows of the ratio test.
    ties: Vec<usize>,
    /// `z₀`'s value when it entered (the scale of [`Z0_TOL`]).
    z0_start: Real,
    /// The solution `z` (n).
    z: Vec<Real>,
    /// `w = M z + q` (n).
    w: Vec<Real>,
}

impl Lemke {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// The solution `z` of the last run that ended in [`LemkeStatus::Solved`] (n).
    pub fn z(&self) -> &[Real] {
        &self.z[..self.n]
    }

    /// `w = M z + q` of the last solved run, computed from `M` and `q` (n).
    pub fn w(&self) -> &[Real] {
        &self.w[..self.n]
    }

    /// Solves LCP(q, M) by Lemke's algorithm (scheme 1 of [CPS, §4.4], covering vector
    /// `d = 1`, lexicographic ratio test). On [`LemkeStatus::Solved`] the solution is in
    /// [`Lemke::z`] and [`Lemke::w`]: `z ≥ 0` exactly (entries that rounding left at
    /// `−1e-16` are set to 0) and `w = M z + q`, `w ≥ 0` and `wᵀz = 0` to rounding.
    pub fn solve<R, C, S, QS>(
        &mut self,
        m: &Matrix<Real, R, C, S>,
        q: &Matrix<Real, R, U1, QS>,
    ) -> Result<LemkeStatus, LemkeError>
    where
        R: Dim,
        C: Dim,
        S: RawStorage<Real, R, C>,
        QS: RawStorage<Real, R, U1>,
    {
        self.solve_covered(m, q, None)
    }

    /// [`Lemke::solve`] with the covering vector `d` (n entries, positive and finite; `None`:
    /// `d = 1`), for the scaled problem (`max|M| = max|q| = 1`). Another `d` follows another
    /// path: on a matrix that is not copositive, one may reach a solution where `d = 1`
    /// ended on a ray.
    pub fn solve_covered<R, C, S, QS>(
        &mut self,
        m: &Matrix<Real, R, C, S>,
        q: &Matrix<Real, R, U1, QS>,
        d: Option<&[Real]>,
    ) -> Result<LemkeStatus, LemkeError>
    where
        R: Dim,
        C: Dim,
        S: RawStorage<Real, R, C>,
        QS: RawStorage<Real, R, U1>,
    {
        let n = q.nrows();
        if m.nrows() != n || m.ncols() != n {
            return Err(LemkeError::Shape {
                rows: m.nrows(),
                cols: m.ncols(),
                q: n,
            });
        }
        if !m.iter().chain(q.iter()).all(|v| v.is_finite()) {
            return Err(LemkeError::NotFinite);
        }
        if let Some(d) = d
            && (d.len() != n || !d.iter().all(|&v| v.is_finite() && v > 0.0))
        {
            return Err(LemkeError::Cover);
        }
        self.reserve(n);
        match d {
            Some(d) => self.cover[..n].copy_from_slice(d),
            None => self.cover[..n].fill(1.0),
        }
        // q ≥ 0: z = 0 solves it.
        let sq = q.iter().fold(0.0 as Real, |acc, v| acc.max(v.abs()));
        if q.iter().all(|&v| v >= 0.0) {
            self.z[..n].fill(0.0);
            for (w, &v) in self.w.iter_mut().zip(q.iter()) {
                *w = v;
            }
            return Ok(LemkeStatus::Solved { pivots: 0 });
        }
        // Scale to max|M̂| = max|q̂| = 1: M̂ = M / sm, q̂ = q / sq; then z = ẑ sq / sm.
        let sm = m.iter().fold(0.0 as Real, |acc, v| acc.max(v.abs()));
        let sm = if sm > 0.0 { sm } else { 1.0 };
        self.start(m, q, sq);
        let max_pivots = self.max_pivots.unwrap_or(1000.max(50 * n));
        let z0 = 2 * n;
        // z₀ enters; the row of the most negative q̂ leaves (the lexicographic minimum of
        // [q̂_i, e_i] / d_i: col = −d = −1, all entries negative, so the test takes |col|).
        let mut entering = z0;
        self.column(sm, entering);
        let mut pivots = 0;
        let mut leave = self.ratio_test(true);
        // z₀'s start −q̂_r / d_r (x_B,r = q̂_r < 0 over col_r = −d_r), and its row.
        let z0_row = leave.unwrap_or(0);
        self.z0_start = leave.map_or(0.0, |r| self.xb[r] / self.col[r]);
        loop {
            let Some(r) = leave else {
                return Ok(LemkeStatus::RayTermination { pivots });
            };
            if pivots == max_pivots {
                return Ok(LemkeStatus::PivotLimit { pivots });
            }
            let left = self.pivot(r, entering);
            pivots += 1;
            if left == z0 {
                break;
            }
            // x_B = B⁻¹ q̂ for the new basis, to rounding: the ratio tests that follow
            // compare basic values that must be exactly zero on degenerate problems.
            self.refine(sm);
            // z₀ (still in the row it entered) at zero: the basis is complementary but for
            // the pair of the next entering variable, both nonbasic; a solution.
            if self.xb[z0_row] <= Z0_TOL * self.z0_start {
                break;
            }
            // The complement of the variable that left enters.
            entering = if left < n { left + n } else { left - n };
            self.column(sm, entering);
            leave = self.ratio_test(false);
        }
        self.refine(sm);
        self.refine(sm);
        self.extract(q, sm, sq);
        Ok(LemkeStatus::Solved { pivots })
    }

    /// Grows the buffers to size `n` (no allocation once they have been that large).
    fn reserve(&mut self, n: usize) {
        self.n = n;
        self.binv.resize(n * n, 0.0);
        self.mc.resize(n * n, 0.0);
        for v in [
            &mut self.xb,
            &mut self.col,
            &mut self.cover,
            &mut self.scratch,
            &mut self.acc,
            &mut self.size,
            &mut self.qhat,
            &mut self.z,
            &mut self.w,
        ] {
            v.resize(n, 0.0);
        }
        self.basis.resize(n, 0);
        self.unit.resize(n, 0);
        self.nz_start.resize(n + 1, 0);
        self.nz.clear();
        self.nz.reserve(n * n);
        self.ties.clear();
        self.ties.reserve(n);
    }

    /// The starting basis: every `w_i` basic, `B = I`, `x_B = q̂`; and `M` copied into the
    /// contiguous [`Lemke::mc`] with the rows of each column's nonzero entries.
    fn start<R: Dim, C: Dim, S: RawStorage<Real, R, C>, QS: RawStorage<Real, R, U1>>(
        &mut self,
        m: &Matrix<Real, R, C, S>,
        q: &Matrix<Real, R, U1, QS>,
        sq: Real,
    ) {
        let n = self.n;
        self.binv[..n * n].fill(0.0);
        for i in 0..n {
            self.binv[i * n + i] = 1.0;
            self.unit[i] = i;
            self.qhat[i] = q[i] / sq;
            self.xb[i] = self.qhat[i];
            self.basis[i] = i;
        }
        self.nz.clear();
        for j in 0..n {
            self.nz_start[j] = self.nz.len();
            let mj = &mut self.mc[j * n..(j + 1) * n];
            for (k, v) in mj.iter_mut().enumerate() {
                *v = m[(k, j)];
                if *v != 0.0 {
                    self.nz.push(k);
                }
            }
        }
        self.nz_start[n] = self.nz.len();
    }

    /// The entering column `col = B⁻¹ a_e` of variable `e`, where the augmented system is
    /// `I w − M̂ z − d z₀ = q̂`: `a_e = e_j` for `w_j`, `−M̂_:j` for `z_j`, `−d` for `z₀`.
    ///
    /// Each entry is the sum `Σ_k B⁻¹_ik a_k` in the order of `k`, swept column by column
    /// of `B⁻¹`. For `z_j` the terms of `M`'s zero entries and of a unit column's zeros are
    /// left out: they add nothing to the sum of magnitudes, and change the sum at most in
    /// the sign of a zero, which the cancellation test maps to 0.
    fn column(&mut self, sm: Real, e: usize) {
        let n = self.n;
        let col = &mut self.col[..n];
        if e < n {
            col.copy_from_slice(&self.binv[e * n..(e + 1) * n]);
        } else if e < 2 * n {
            let j = e - n;
            let (sum, size) = (&mut self.acc[..n], &mut self.size[..n]);
            sum.fill(0.0);
            size.fill(0.0);
            for &k in &self.nz[self.nz_start[j]..self.nz_start[j + 1]] {
                let mk = self.mc[j * n + k];
                let u = self.unit[k];
                if u != DENSE {
                    // The term 1 · m_kj.
                    sum[u] += mk;
                    size[u] += mk.abs();
                    continue;
                }
                let bk = &self.binv[k * n..(k + 1) * n];
                for ((s, a), &b) in sum.iter_mut().zip(size.iter_mut()).zip(bk) {
                    let t = b * mk;
                    *s += t;
                    *a += t.abs();
                }
            }
            for ((c, &s), &a) in col.iter_mut().zip(sum.iter()).zip(size.iter()) {
                // Cancellation down to the rounding of B⁻¹: a zero (CANCEL_TOL).
                *c = if s.abs() <= CANCEL_TOL * a {
                    0.0
                } else {
                    -s / sm
                };
            }
        } else {
            // −Σ_k B⁻¹_ik d_k.
            let sum = &mut self.acc[..n];
            binv_mul(&self.binv[..n * n], &self.unit[..n], &self.cover[..n], sum);
            for (c, &s) in col.iter_mut().zip(sum.iter()) {
                *c = -s;
            }
        }
    }

    /// The lexicographic minimum ratio test [CPS, §4.9]: the row `r` that leaves when the
    /// entering variable's column is `col`. Rows with `col_i > PIVOT_TOL · max|col|` are
    /// candidates (`initial`: every row, by `|col_i|`, the first pivot of `z₀`); among those
    /// tied in `x_B,i / col_i`, `z₀`'s row if it is one, else the lexicographic minimum of
    /// the rows of `B⁻¹ / col_i`, column by column. `None`: no candidate, ray termination.
    fn ratio_test(&mut self, initial: bool) -> Option<usize> {
        let n = self.n;
        let z0 = 2 * n;
        let cmax = self.col.iter().fold(0.0 as Real, |a, v| a.max(v.abs()));
        let piv = |c: Real| {
            if initial {
                c.abs()
            } else if c > PIVOT_TOL * cmax {
                c
            } else {
                0.0
            }
        };
        // The minimum ratio, and the rows that tie with it.
        let ratios = &mut self.size[..n];
        let mut min = Real::INFINITY;
        for ((ratio, &c), &x) in ratios.iter_mut().zip(&self.col[..n]).zip(&self.xb[..n]) {
            let c = piv(c);
            if c > 0.0 {
                *ratio = x / c;
                min = min.min(*ratio);
            }
        }
        if !min.is_finite() {
            return None;
        }
        let tie = |a: Real, b: Real| (a - b).abs() <= TIE_TOL * (1.0 + a.abs().max(b.abs()));
        self.ties.clear();
        for (i, (&c, &ratio)) in self.col[..n].iter().zip(ratios.iter()).enumerate() {
            if piv(c) > 0.0 && tie(ratio, min) {
                self.ties.push(i);
            }
        }
        if let Some(&r) = self.ties.iter().find(|&&i| self.basis[i] == z0) {
            return Some(r);
        }
        // Lexicographic: the smallest B⁻¹_ij / col_i for j = 0, 1, … among the tied rows.
        let mut j = 0;
        while self.ties.len() > 1 && j < n {
            let ratio = |i: usize| self.binv[j * n + i] / piv(self.col[i]);
            let min = self
                .ties
                .iter()
                .map(|&i| ratio(i))
                .fold(Real::INFINITY, Real::min);
            self.ties.retain(|&i| tie(ratio(i), min));
            j += 1;
        }
        self.ties.first().copied()
    }

    /// One pivot: variable `e` (whose column is `col`) enters at row `r`; returns the
    /// variable that left. Gauss–Jordan on `[x_B | B⁻¹]`: row `r` divided by `col_r`, then
    /// `col_i` times it subtracted from every other row, column by column of `B⁻¹`.
    ///
    /// **What is left out, and why no bit changes.** A column whose entry `pv` in row `r`
    /// is zero is left as it is (every unit column but the one of row `r`, which becomes a
    /// full column): `v − col_i · (±0)` differs from `v` at most in the sign of a zero, and
    /// so does `v − 0 · pv`, which the loop computes for the rows whose `col_i` is zero.
    /// The same holds for the zero terms left out of [`Lemke::column`] and
    /// [`Lemke::refine`]. Signs of zeros in `B⁻¹`, `x_B` and the entering column reach
    /// nothing that decides: a candidate row needs `col_i > 0`, the multipliers are tested
    /// against 0, ratios tie by `|a − b|`, `z₀`'s test is `x_B ≤ ε`, and [`Lemke::extract`]
    /// maps `x_B ≤ 0` to `+0`. Every other value is computed as in the textbook loops (for
    /// finite `B⁻¹`).
    fn pivot(&mut self, r: usize, e: usize) -> usize {
        let n = self.n;
        let p = self.col[r];
        // The multipliers, row r's zero (it is divided instead).
        let f = &mut self.acc[..n];
        f.copy_from_slice(&self.col[..n]);
        f[r] = 0.0;
        for (bk, u) in self.binv[..n * n]
            .chunks_exact_mut(n)
            .zip(self.unit[..n].iter_mut())
        {
            if *u != DENSE {
                if *u != r {
                    continue;
                }
                *u = DENSE;
            }
            let pv = bk[r] / p;
            if pv == 0.0 {
                continue;
            }
            for (v, &fi) in bk.iter_mut().zip(f.iter()) {
                *v -= fi * pv;
            }
            bk[r] = pv;
        }
        self.xb[r] /= p;
        let xr = self.xb[r];
        for (x, &fi) in self.xb[..n].iter_mut().zip(f.iter()) {
            if fi != 0.0 {
                *x -= fi * xr;
            }
        }
        std::mem::replace(&mut self.basis[r], e)
    }

    /// One step of iterative refinement of the basis: `x_B += B⁻¹ (q̂ − Σ_b a_b x_b)`, with
    /// the basis' columns `a_b` taken from `M` (`e_j` for `w_j`, `−M̂_:j` for `z_j`, `−d` for
    /// `z₀`). `B⁻¹ r` is summed over `k` in order from −0, as `Iterator::sum` would.
    fn refine(&mut self, sm: Real) {
        let n = self.n;
        let r = &mut self.scratch[..n];
        r.copy_from_slice(&self.qhat[..n]);
        for (b, &var) in self.basis[..n].iter().enumerate() {
            let x = self.xb[b];
            if var < n {
                r[var] -= x;
            } else if var < 2 * n {
                let (j, xs) = (var - n, x / sm);
                for (v, &mk) in r.iter_mut().zip(&self.mc[j * n..(j + 1) * n]) {
                    *v += mk * xs;
                }
            } else {
                for (v, &d) in r.iter_mut().zip(&self.cover[..n]) {
                    *v += d * x;
                }
            }
        }
        let sum = &mut self.acc[..n];
        binv_mul(&self.binv[..n * n], &self.unit[..n], r, sum);
        for (x, &s) in self.xb[..n].iter_mut().zip(sum.iter()) {
            *x += s;
        }
    }

    /// `z` from the basis (unscaled, negatives of rounding and zeros set to `+0`, as
    /// `maxsd(v, +0)`), and `w = M z + q`
    /// (each row's `Σ_j M_ij z_j` in the order of `j` from −0, as `Iterator::sum`'s).
    fn extract<R: Dim, QS: RawStorage<Real, R, U1>>(
        &mut self,
        q: &Matrix<Real, R, U1, QS>,
        sm: Real,
        sq: Real,
    ) {
        let n = self.n;
        self.z[..n].fill(0.0);
        for (b, &var) in self.basis[..n].iter().enumerate() {
            if (n..2 * n).contains(&var) {
                let v = self.xb[b] * sq / sm;
                self.z[var - n] = if v > 0.0 { v } else { 0.0 };
            }
        }
        let sum = &mut self.acc[..n];
        sum.fill(-0.0);
        for (mj, &zj) in self.mc[..n * n].chunks_exact(n).zip(&self.z[..n]) {
            for (s, &v) in sum.iter_mut().zip(mj) {
                *s += v * zj;
            }
        }
        for (i, w) in self.w[..n].iter_mut().enumerate() {
            *w = q[i] + sum[i];
        }
    }
}

/// A column of `B⁻¹` that is not a unit vector ([`Lemke::unit`]).
const DENSE: usize = usize::MAX;

/// `sum = B⁻¹ v` (`B⁻¹` column-major, n × n, its unit columns marked in `unit`), each entry
/// summed over `k` in order from `−0`, as `Iterator::sum` of the row's products. Terms
/// with a zero factor (a unit column's zeros, `v_k = 0`) are left out: they change a sum
/// at most in the sign of a zero ([`Lemke::pivot`]).
fn binv_mul(binv: &[Real], unit: &[usize], v: &[Real], sum: &mut [Real]) {
    let n = v.len();
    sum.fill(-0.0);
    for ((bk, &u), &vk) in binv.chunks_exact(n).zip(unit).zip(v) {
        if u != DENSE {
            // The term 1 · v_k.
            sum[u] += vk;
        } else if vk != 0.0 {
            for (s, &b) in sum.iter_mut().zip(bk) {
                *s += b * vk;
            }
        }
    }
}
