//! Dense least squares: the minimum-norm solution of a possibly rank-deficient system by a
//! complete orthogonal decomposition.
//!
//! The contact problems are often exactly rank-deficient: two capsule ends at one hinge
//! lying on a floor give identical rows of `W = J M⁻¹ Jᵀ`, a block on two corners has more
//! friction unknowns than its one rotation can tell apart. Their systems are otherwise well
//! conditioned, and a consistent right-hand side must give a residual at rounding level.
//!
//! Why not nalgebra's decompositions (0.35): its `SVD` reconstructs a well-conditioned
//! 6 × 6 matrix of rank 5 (three sliding points of the 8-link chain, singular values 36.8 …
//! 0.77 and 0) only to 8.6e-4, and `SVD::solve` left a residual of 2.9e-6 on its consistent
//! system (`tests/linalg.rs` keeps that matrix; dimforge/nalgebra#1117 reports other wrong
//! solutions); its `ColPivQR` pivots on the largest entry, not the largest column norm,
//! which does not reveal the rank, and its `solve` needs full rank. No other crate of our
//! stack has a rank-revealing least-squares solve (faer does, at two minutes of build on
//! our two cores). What follows is the textbook algorithm (Golub and Van Loan, *Matrix
//! Computations*, §5.4.1–5.5.2): Householder QR with column pivoting by norms (Businger
//! and Golub), then the QR of the leading rows' transpose for the minimum norm.

use nalgebra::{DMatrix, DVector};

use crate::math::Real;

/// Workspace of [`MinNorm::solve`]; it grows to the largest system solved and is then
/// reused without allocating.
#[derive(Clone, Debug, Default)]
pub struct MinNorm {
    /// The factor `R` (upper), with the Householder vectors (but their first entries) below
    /// its diagonal; `Qᵀ` is applied to `b` as it is made.
    r: DMatrix<Real>,
    /// The column permutation: column `j` of the factored matrix is column `perm[j]` of `A`.
    perm: Vec<usize>,
    /// `Qᵀ b`.
    c: Vec<Real>,
    /// `R₁ᵀ` (n × r) and its factor, with Householder vectors below the diagonal.
    t: DMatrix<Real>,
    head_t: Vec<Real>,
    beta_t: Vec<Real>,
    /// The solution in pivoted order.
    z: Vec<Real>,
    /// Whether the last solve left out a column that the rounding threshold
    /// `max(m, n) · ε` would have counted (see [`Self::solve_to`]).
    truncated: bool,
}

/// One Householder reflection `H = I − β v vᵀ` with `H x = α e₀`, for the entries `x` of
/// a column: returns `(α, v₀, β)`; `v` is `x` with `v₀` in place of `x₀`.
fn householder(x: impl Iterator<Item = Real> + Clone) -> (Real, Real, Real) {
    let mut it = x.clone();
    let x0 = it.next().unwrap_or(0.0);
    let tail: Real = it.map(|v| v * v).sum();
    let norm = (x0 * x0 + tail).sqrt();
    if norm == 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let alpha = if x0 >= 0.0 { -norm } else { norm };
    let v0 = x0 - alpha;
    let vv = v0 * v0 + tail;
    let beta = if vv > 0.0 { 2.0 / vv } else { 0.0 };
    (alpha, v0, beta)
}

/// [`MinNorm::solve_to`] of a `2 × 2` system of full rank, on the stack: `a` by columns
/// (`a[j][i]` is the entry of row `i`, column `j`). The same operations in the same order as
/// the general path (the pivoted Householder QR, then the back substitution `R₁₁ z = Qᵀ b`),
/// so the same numbers to the bit (the test `the_2x2_path_is_the_general_path_to_the_bit`).
/// `None` when the rank test leaves a column out (the general path then solves).
#[doc(hidden)]
pub fn min_norm_2x2(a: [[Real; 2]; 2], b: [Real; 2], rel_tol: Real) -> Option<[Real; 2]> {
    let mut col = a;
    let mut c = b;
    let mut perm = [0, 1];
    let first = (0..2)
        .map(|j| dot(&col[j], &col[j]).sqrt())
        .fold(0.0, Real::max);
    let rounding = 2.0 * Real::EPSILON * first;
    let tol = rounding.max(rel_tol * first);
    // k = 0: the pivot column, its reflection applied to the other column and to c.
    let mut best = (0, -1.0);
    for (j, cj) in col.iter().enumerate() {
        let s = dot(cj, cj);
        if s > best.1 {
            best = (j, s);
        }
    }
    if best.1.sqrt() <= tol {
        return None;
    }
    col.swap(0, best.0);
    perm.swap(0, best.0);
    let (alpha, v0, beta) = householder(col[0].iter().copied());
    let v = [col[0][1]];
    let f = beta * (v0 * col[1][0] + dot(&v, &col[1][1..]));
    col[1][0] -= f * v0;
    col[1][1] -= f * v[0];
    let f = beta * (v0 * c[0] + dot(&v, &c[1..]));
    c[0] -= f * v0;
    c[1] -= f * v[0];
    col[0][0] = alpha;
    // k = 1: the remaining entry.
    let mut best = (1, -1.0);
    let s = dot(&col[1][1..], &col[1][1..]);
    if s > best.1 {
        best = (1, s);
    }
    if best.1.sqrt() <= tol {
        return None;
    }
    let (alpha, v0, beta) = householder(col[1][1..].iter().copied());
    let f = beta * (v0 * c[1] + dot(&[], &[]));
    c[1] -= f * v0;
    col[1][1] = alpha;
    // R₁₁ z = c, R[(i, j)] = col[j][i].
    let mut z = [0.0; 2];
    for i in (0..2).rev() {
        let s: Real = (i + 1..2).map(|j| col[j][i] * z[j]).sum();
        z[i] = (c[i] - s) / col[i][i];
    }
    let mut x = [0.0; 2];
    for (j, &p) in perm.iter().enumerate() {
        x[p] = z[j];
    }
    Some(x)
}

/// The largest absolute value of `v` (zero if empty): nalgebra's `amax` of a matrix whose
/// entries are `v` in storage order, the same comparisons in the same order (the first
/// entry's `|·|`, then each next `|x|` taken unless the running value is `≥` it), so the
/// same number to the bit, without its generic iterator.
#[doc(hidden)]
pub fn amax(v: &[Real]) -> Real {
    let Some((first, rest)) = v.split_first() else {
        return 0.0;
    };
    let mut m = first.abs();
    for x in rest {
        let a = x.abs();
        m = if m >= a { m } else { a };
    }
    m
}

/// Gives `m` the shape `rows × cols`, keeping its buffer when the shape is already right
/// (nalgebra's `resize_mut` copies into a new buffer every time); the entries are left as
/// they are when it is, and zero otherwise. At another shape the buffer is kept too (it is
/// reallocated only to grow): a workspace that takes turns between a few shapes (the
/// closed points, then a mode selection's candidates) allocates nothing once it has held
/// the largest.
#[doc(hidden)]
pub fn fit_matrix(m: &mut DMatrix<Real>, rows: usize, cols: usize) {
    if m.shape() != (rows, cols) {
        let mut data: Vec<Real> = std::mem::replace(m, DMatrix::zeros(0, 0)).data.into();
        data.clear();
        data.resize(rows * cols, 0.0);
        *m = DMatrix::from_vec(rows, cols, data);
    }
}

/// Gives `v` the length `len`, keeping its buffer when it is already right, and its
/// capacity otherwise, with every entry zero (see [`fit_matrix`]).
#[doc(hidden)]
pub fn fit_vector(v: &mut DVector<Real>, len: usize) {
    if v.len() != len {
        let mut data: Vec<Real> = std::mem::replace(v, DVector::zeros(0)).data.into();
        data.clear();
        data.resize(len, 0.0);
        *v = DVector::from_vec(data);
    }
}

/// `dst.copy_from_slice(src)` (the same lengths, or it panics as that does), entry by entry
/// up to four entries: `copy_from_slice` of a length unknown at compile time calls
/// `memcpy`, dearer than the few moves of a small model's coordinates, speeds, forces or
/// per-body kinematics (several per right-hand side).
#[inline(always)]
#[doc(hidden)]
pub fn copy_short<T: Copy>(dst: &mut [T], src: &[T]) {
    match (dst, src) {
        ([d0], [s0]) => *d0 = *s0,
        ([d0, d1], [s0, s1]) => [*d0, *d1] = [*s0, *s1],
        ([d0, d1, d2], [s0, s1, s2]) => [*d0, *d1, *d2] = [*s0, *s1, *s2],
        ([d0, d1, d2, d3], [s0, s1, s2, s3]) => {
            [*d0, *d1, *d2, *d3] = [*s0, *s1, *s2, *s3];
        }
        (dst, src) => dst.copy_from_slice(src),
    }
}

/// `Σ aᵢ bᵢ` over the shorter of `a` and `b`, in four lanes (which the compiler
/// vectorizes; a plain `zip().sum()` is one serial chain of additions).
#[doc(hidden)]
pub fn dot(a: &[Real], b: &[Real]) -> Real {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: Real = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// nalgebra's `gemm` hands a product of dynamic matrices to `matrixmultiply` when its sizes
/// all pass this (nalgebra 0.35, `blas_uninit::gemm_uninit`).
const GEMM_SMALL_DIM: usize = 5;

/// `matrixmultiply`'s depth of a block of `f64` (`D_KC`, 0.3): the sums over `r` are made
/// in blocks of this many terms.
#[doc(hidden)]
pub const GEMM_DEPTH: usize = 256;

/// `out = a b` (`a` n × m, `b` m × p) in `out`'s kept storage (given the shape n × p by
/// [`fit_matrix`]): nalgebra's `a.mul_to(b, out)` to the bit as it computes it on a
/// processor with fused multiply–adds, on every machine and without allocating.
///
/// nalgebra's product of such sizes that one of n, m, p is at most 5 sums each entry over
/// `r` in increasing order, `s = a_i0 b_0j`, then `s = a_ir b_rj + s` (a rounded product,
/// then a rounded sum: Rust never fuses them); so does this. Beyond, nalgebra hands it to
/// `matrixmultiply`, which allocates a packing buffer at every call and picks its kernel
/// from the processor at run time: with fused multiply–adds (x86-64 with FMA, as this
/// machine, whose product the test checks to the bit; its AVX-512 and aarch64 kernels
/// fuse too) each entry is `fma(a_ir, b_rj, s)` over `r` from `s = +0` in blocks of
/// [`GEMM_DEPTH`], the blocks' sums added in turn (the first to `+0`); without them
/// (older x86-64) a rounded product and sum, and the bits of the product — and of what
/// follows it — depended on the machine. Here they are the fused ones everywhere:
/// `mul_add` is the exactly rounded `a b + s` on every target (a call to the runtime's
/// `fma`, which uses the instruction where the processor has it).
#[doc(hidden)]
pub fn product_into(a: &DMatrix<Real>, b: &DMatrix<Real>, out: &mut DMatrix<Real>) {
    let ((n, m), p) = (a.shape(), b.ncols());
    debug_assert_eq!(b.nrows(), m, "product_into: shapes");
    fit_matrix(out, n, p);
    let (a, b, c) = (a.as_slice(), b.as_slice(), out.as_mut_slice());
    if m == 0 || n == 0 {
        c.fill(0.0);
        return;
    }
    let fused = n > GEMM_SMALL_DIM && p > GEMM_SMALL_DIM && m > GEMM_SMALL_DIM;
    for (b_j, c_j) in b.chunks_exact(m).zip(c.chunks_exact_mut(n)) {
        if !fused {
            // Column j: a's columns (contiguous) times b_rj, r increasing.
            for (s, &a_i0) in c_j.iter_mut().zip(&a[..n]) {
                *s = a_i0 * b_j[0];
            }
            for (a_r, &b_rj) in a.chunks_exact(n).zip(b_j).skip(1) {
                for (s, &a_ir) in c_j.iter_mut().zip(a_r) {
                    *s += a_ir * b_rj; // `a_ir b_rj + s`: addition commutes
                }
            }
        } else {
            // The first block summed in place from +0, then added to +0 (−0 becomes +0).
            c_j.fill(0.0);
            for (a_r, &b_rj) in a.chunks_exact(n).zip(&b_j[..m.min(GEMM_DEPTH)]) {
                for (s, &a_ir) in c_j.iter_mut().zip(a_r) {
                    *s = a_ir.mul_add(b_rj, *s);
                }
            }
            for s in c_j.iter_mut() {
                *s += 0.0;
            }
            // Each further block (a depth past GEMM_DEPTH) summed from +0, then added.
            for (block, b_block) in b_j.chunks(GEMM_DEPTH).enumerate().skip(1) {
                let a_block = &a[block * GEMM_DEPTH * n..];
                for (i, s) in c_j.iter_mut().enumerate() {
                    let terms = a_block.chunks_exact(n).zip(b_block);
                    let acc = terms.fold(0.0, |acc: Real, (a_r, &b_rj)| a_r[i].mul_add(b_rj, acc));
                    *s += acc;
                }
            }
        }
    }
}

/// Applies the reflection `H = I − β v vᵀ` of column `k` of `m` (`v = (v₀, m[k+1.., k])`)
/// to rows `k..` of column `j > k` of `m`.
fn reflect_column(m: &mut DMatrix<Real>, k: usize, (v0, beta): (Real, Real), j: usize) {
    debug_assert!(j > k);
    let rows = m.nrows();
    let (left, right) = m.as_mut_slice().split_at_mut(j * rows);
    let v = &left[k * rows + k + 1..(k + 1) * rows];
    let cj = &mut right[k..rows];
    let f = beta * (v0 * cj[0] + dot(v, &cj[1..]));
    cj[0] -= f * v0;
    for (c, vi) in cj[1..].iter_mut().zip(v) {
        *c -= f * vi;
    }
}

/// Applies the reflection of column `k` of `m` (as in [`reflect_column`]) to rows `k..`
/// of `y`.
fn reflect_vector(m: &DMatrix<Real>, k: usize, (v0, beta): (Real, Real), y: &mut [Real]) {
    let rows = m.nrows();
    let v = &m.as_slice()[k * rows + k + 1..(k + 1) * rows];
    let y = &mut y[k..rows];
    let f = beta * (v0 * y[0] + dot(v, &y[1..]));
    y[0] -= f * v0;
    for (c, vi) in y[1..].iter_mut().zip(v) {
        *c -= f * vi;
    }
}

impl MinNorm {
    /// A workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// The minimum-norm least-squares solution of `A x = b`: of the `x` that minimise
    /// `‖A x − b‖₂`, the one of least `‖x‖₂`. `A` is `m × n`; `x` is resized to `n`. The
    /// rank is decided by the pivoted `R`: column `k` counts if its remaining norm exceeds
    /// `max(m, n) · ε · ‖the first pivot column‖`. Returns the rank.
    ///
    /// ```text
    /// A P = Q [R₁₁ R₁₂; 0 0],  R₁ = [R₁₁ R₁₂] (r × n),   R₁ᵀ = Q₂ [T; 0],
    /// x = P Q₂ [T⁻ᵀ (Qᵀ b)₁..r ; 0]
    /// ```
    pub fn solve(&mut self, a: &DMatrix<Real>, b: &DVector<Real>, x: &mut DVector<Real>) -> usize {
        self.solve_to(a, b, x, 0.0)
    }

    /// Whether the last solve left out a column that [`Self::solve`]'s rounding
    /// threshold would have counted.
    pub fn truncated(&self) -> bool {
        self.truncated
    }

    /// [`Self::solve`] with the rank decided at `max(rel_tol, max(m, n) · ε)` times the
    /// first pivot column's norm: the columns the data determine only to `rel_tol` count
    /// as dependent.
    pub fn solve_to(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        x: &mut DVector<Real>,
        rel_tol: Real,
    ) -> usize {
        if a.shape() == (2, 2)
            && let Some(rank) = self.solve_to_2x2(a, b, x, rel_tol)
        {
            return rank;
        }
        self.solve_general(a, b, x, rel_tol)
    }

    /// [`Self::solve_to`] of a `2 × 2` system of full rank (one closed contact point's
    /// modes): [`min_norm_2x2`]. `None`, with nothing written, when the rank test leaves a
    /// column out: the general path then solves.
    #[doc(hidden)]
    #[inline]
    pub fn solve_to_2x2(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        x: &mut DVector<Real>,
        rel_tol: Real,
    ) -> Option<usize> {
        let col = [[a[(0, 0)], a[(1, 0)]], [a[(0, 1)], a[(1, 1)]]];
        let z = min_norm_2x2(col, [b[0], b[1]], rel_tol)?;
        if x.len() != 2 {
            *x = DVector::zeros(2);
        }
        x[0] = z[0];
        x[1] = z[1];
        self.truncated = false;
        Some(2)
    }

    /// [`Self::solve_to`] of any shape.
    #[doc(hidden)]
    #[inline]
    pub fn solve_general(
        &mut self,
        a: &DMatrix<Real>,
        b: &DVector<Real>,
        x: &mut DVector<Real>,
        rel_tol: Real,
    ) -> usize {
        let (m, n) = a.shape();
        debug_assert_eq!(b.len(), m);
        fit_matrix(&mut self.r, m, n);
        self.r.copy_from(a);
        self.c.clear();
        self.c.extend(b.iter());
        self.perm.clear();
        self.perm.extend(0..n);
        let first = (0..n)
            .map(|j| {
                let col = &self.r.as_slice()[j * m..(j + 1) * m];
                dot(col, col).sqrt()
            })
            .fold(0.0, Real::max);
        let rounding = m.max(n) as Real * Real::EPSILON * first;
        let tol = rounding.max(rel_tol * first);
        let mut rank = 0;
        self.truncated = false;
        for k in 0..m.min(n) {
            // The column of largest remaining norm, recomputed: not downdated (LAPACK's
            // xLAQP2), whose other choices among near ties of redundant contact points'
            // columns sent the 32-link chain on the floor into a stall of modes at 4.92 s
            // that the recomputed norms do not meet.
            let mut best = (k, -1.0);
            for j in k..n {
                let col = &self.r.as_slice()[j * m + k..(j + 1) * m];
                let s = dot(col, col);
                if s > best.1 {
                    best = (j, s);
                }
            }
            if best.1.sqrt() <= tol {
                self.truncated = best.1.sqrt() > rounding;
                break;
            }
            self.r.swap_columns(k, best.0);
            self.perm.swap(k, best.0);
            let (alpha, v0, beta) =
                householder(self.r.as_slice()[k * m + k..(k + 1) * m].iter().copied());
            // Apply H to the columns right of k and to c.
            for j in k + 1..n {
                reflect_column(&mut self.r, k, (v0, beta), j);
            }
            reflect_vector(&self.r, k, (v0, beta), &mut self.c);
            self.r[(k, k)] = alpha;
            rank = k + 1;
        }
        let r = rank;
        self.z.clear();
        self.z.resize(n, 0.0);
        if r == n {
            // Full column rank: back substitution R₁₁ z = c.
            for i in (0..n).rev() {
                let s: Real = (i + 1..n).map(|j| self.r[(i, j)] * self.z[j]).sum();
                self.z[i] = (self.c[i] - s) / self.r[(i, i)];
            }
        } else if r > 0 {
            // R₁ᵀ = Q₂ [T; 0]: Householder QR of the n × r transpose of the first r rows.
            fit_matrix(&mut self.t, n, r);
            for i in 0..n {
                for j in 0..r {
                    self.t[(i, j)] = if i >= j { self.r[(j, i)] } else { 0.0 };
                }
            }
            self.head_t.clear();
            self.beta_t.clear();
            for k in 0..r {
                let (alpha, v0, beta) =
                    householder(self.t.as_slice()[k * n + k..(k + 1) * n].iter().copied());
                for j in k + 1..r {
                    reflect_column(&mut self.t, k, (v0, beta), j);
                }
                self.t[(k, k)] = alpha;
                self.head_t.push(v0);
                self.beta_t.push(beta);
            }
            // Tᵀ y = c₁ (forward substitution), z = Q₂ [y; 0].
            for i in 0..r {
                let s: Real = (0..i).map(|j| self.t[(j, i)] * self.z[j]).sum();
                self.z[i] = (self.c[i] - s) / self.t[(i, i)];
            }
            for k in (0..r).rev() {
                let hk = (self.head_t[k], self.beta_t[k]);
                reflect_vector(&self.t, k, hk, &mut self.z);
            }
        }
        if x.len() != n {
            *x = DVector::zeros(n);
        }
        for (j, &p) in self.perm.iter().enumerate() {
            x[p] = self.z[j];
        }
        rank
    }
}
