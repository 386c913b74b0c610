//! [`TreeMatrix`]: a symmetric matrix with the sparsity of a kinematic tree, and its
//! factorization `M = Lᵀ L` [F, §6.5].
//!
//! The mass matrix of a tree has `M_ij ≠ 0` only when speed `j` is an ancestor of speed
//! `i` (or `i` itself) in the *expanded parent array* `λ` of the speeds [F, §6.4]: a joint
//! with several speeds is a chain of one-speed joints, its first speed's parent the last
//! speed of the nearest ancestor joint that has speeds. The composite rigid body algorithm
//! writes only those entries [F, §6.2], and the `LᵀL` factorization keeps them: `L` has the
//! sparsity of `M`'s lower triangle, with no fill-in [F, §6.5]. Storage and the solve are
//! `O(Σ_i depth(i))`: `O(n)` for free bodies, `n(n+1)/2` for a chain of `n` links (all of
//! whose entries are non-zero).
//!
//! Row `i` is stored contiguously, its diagonal first, then the entries of `λ(i)`,
//! `λ(λ(i))`, … up to the root: the entry `(i, j)` of an ancestor `j` is at
//! `start[i] + depth(i) − depth(j)`.

use nalgebra::DMatrix;

use crate::math::Real;

/// No parent.
const ROOT: usize = usize::MAX;

/// The sparsity of a [`TreeMatrix`]: the parent array `λ` of `n` indices, `λ(i) < i`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TreePattern {
    /// `λ(i)`, or `ROOT`.
    parent: Vec<usize>,
    /// The number of ancestors of each index.
    depth: Vec<usize>,
    /// Where row `i` starts in the values `[n + 1]` (the last is the number of entries).
    start: Vec<usize>,
}

impl TreePattern {
    /// The pattern of the parent array `parent` (`None` for a root). Returns `None` unless
    /// every parent precedes its child (`λ(i) < i`).
    pub fn new(parent: &[Option<usize>]) -> Option<Self> {
        let n = parent.len();
        let mut p = Vec::with_capacity(n);
        let mut depth = Vec::with_capacity(n);
        let mut start = Vec::with_capacity(n + 1);
        start.push(0);
        for (i, &lambda) in parent.iter().enumerate() {
            let d = match lambda {
                None => 0,
                Some(l) if l < i => depth[l] + 1,
                Some(_) => return None,
            };
            p.push(lambda.unwrap_or(ROOT));
            depth.push(d);
            start.push(start[i] + d + 1);
        }
        Some(TreePattern {
            parent: p,
            depth,
            start,
        })
    }

    /// The dense pattern of `n` indices: each the parent of the next (`λ(i) = i − 1`).
    pub fn dense(n: usize) -> Self {
        let parent: Vec<Option<usize>> = (0..n).map(|i| i.checked_sub(1)).collect();
        // λ(i) = i − 1 < i always holds.
        Self::new(&parent).unwrap_or_else(|| unreachable!())
    }

    /// The dimension `n`.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// `true` for the pattern of no index.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// The number of stored entries (the lower triangle's non-zeros).
    pub fn entries(&self) -> usize {
        self.start.last().copied().unwrap_or(0)
    }

    /// `λ(i)`, `None` for a root.
    pub fn parent(&self, i: usize) -> Option<usize> {
        Some(self.parent[i]).filter(|&p| p != ROOT)
    }

    /// Where the entry `(i, j)` is stored, for `j = i` or an ancestor of `i`; `None`
    /// otherwise (or out of range).
    fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (i, j) = (i.max(j), i.min(j));
        if i >= self.len() {
            return None;
        }
        let mut a = i;
        while a != ROOT && a > j {
            a = self.parent[a];
        }
        (a == j).then(|| self.start[i] + self.depth[i] - self.depth[j])
    }
}

/// A symmetric matrix with the sparsity of a [`TreePattern`]: the entries `(i, j)` with
/// `j = i` or an ancestor of `i` (and their mirror images) are stored, all others are zero.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TreeMatrix {
    pattern: TreePattern,
    /// Row by row, diagonal first (see the module docs).
    values: Vec<Real>,
}

/// The zero of the entries outside the pattern, for [`std::ops::Index`].
static ZERO: Real = 0.0;

impl TreeMatrix {
    /// The zero matrix of `pattern`.
    pub fn zeros(pattern: TreePattern) -> Self {
        let values = vec![0.0; pattern.entries()];
        TreeMatrix { pattern, values }
    }

    /// A matrix of `pattern` with no storage until [`Self::allocate`]: for a workspace
    /// that may never hold one.
    pub fn unallocated(pattern: TreePattern) -> Self {
        TreeMatrix {
            pattern,
            values: Vec::new(),
        }
    }

    /// Gives the matrix its storage (zeros), if it has none.
    #[inline]
    pub fn allocate(&mut self) {
        if self.values.len() != self.pattern.entries() {
            self.values = vec![0.0; self.pattern.entries()];
        }
    }

    /// The pattern.
    pub fn pattern(&self) -> &TreePattern {
        &self.pattern
    }

    /// The dimension `n`.
    pub fn nrows(&self) -> usize {
        self.pattern.len()
    }

    /// The stored entries, row by row (see the module docs).
    pub fn values(&self) -> &[Real] {
        &self.values
    }

    /// Sets every entry to zero (allocating the storage if there is none).
    pub fn clear(&mut self) {
        self.allocate();
        self.values.fill(0.0);
    }

    /// The entry `(i, j)` (zero outside the pattern or out of range).
    pub fn get(&self, i: usize, j: usize) -> Real {
        self.pattern
            .position(i, j)
            .and_then(|k| self.values.get(k).copied())
            .unwrap_or(0.0)
    }

    /// Sets the entry `(i, j)` (and `(j, i)`). Returns `false`, changing nothing, if it is
    /// outside the pattern (or the storage is not allocated).
    pub fn set(&mut self, i: usize, j: usize, value: Real) -> bool {
        match self.pattern.position(i, j) {
            Some(k) if k < self.values.len() => {
                self.values[k] = value;
                true
            }
            _ => false,
        }
    }

    /// Sets the entry `(i, j)` for `j = i` or an ancestor of `i`, which the caller knows
    /// (in `O(1)`: no walk up the tree; checked in debug builds only).
    #[inline]
    pub fn set_ancestor(&mut self, i: usize, j: usize, value: Real) {
        debug_assert_eq!(self.pattern.position(i, j), {
            let p = &self.pattern;
            Some(p.start[i] + p.depth[i] - p.depth[j])
        });
        let p = &self.pattern;
        self.values[p.start[i] + p.depth[i] - p.depth[j]] = value;
    }

    /// Row `i`'s stored entries: `(i, i)`, `(i, λ(i))`, `(i, λ(λ(i)))`, … (empty if not
    /// allocated).
    #[inline]
    pub fn row(&self, i: usize) -> &[Real] {
        self.values
            .get(self.pattern.start[i]..self.pattern.start[i + 1])
            .unwrap_or(&[])
    }

    /// Row `i`'s stored entries, mutable (see [`Self::row`]).
    #[inline]
    pub fn row_mut(&mut self, i: usize) -> &mut [Real] {
        let range = self.pattern.start[i]..self.pattern.start[i + 1];
        self.values.get_mut(range).unwrap_or(&mut [])
    }

    /// The dense symmetric matrix (for reports and tests; it allocates `n²`).
    pub fn to_dense(&self) -> DMatrix<Real> {
        let n = self.nrows();
        let mut m = DMatrix::zeros(n, n);
        if self.values.len() != self.pattern.entries() {
            return m;
        }
        for i in 0..n {
            let mut j = i;
            for &v in self.row(i) {
                m[(i, j)] = v;
                m[(j, i)] = v;
                j = self.pattern.parent[j];
            }
        }
        m
    }

    /// The dense lower triangle `L` (for tests of a factor; it allocates `n²`).
    pub fn to_dense_lower(&self) -> DMatrix<Real> {
        let mut m = self.to_dense();
        m.fill_upper_triangle(0.0, 1);
        m
    }

    /// Copies the lower triangle of the dense `m` into the pattern's entries (the others
    /// are ignored).
    pub fn copy_lower_from(&mut self, m: &DMatrix<Real>) {
        self.allocate();
        for i in 0..self.nrows() {
            let mut j = i;
            let start = self.pattern.start[i];
            for d in 0..=self.pattern.depth[i] {
                self.values[start + d] = m[(i, j)];
                j = self.pattern.parent[j];
            }
        }
    }

    /// Factors the symmetric positive definite matrix `m` (of the same pattern) into
    /// `m = Lᵀ L`, `L` lower triangular with the pattern's sparsity, stored in `self`
    /// [F, §6.5, Table 6.3, the `LTL` factorization]:
    ///
    /// ```text
    /// for k = n−1 … 0:
    ///     L_kk = √H_kk
    ///     L_ki = H_ki / L_kk                          (i an ancestor of k)
    ///     H_ij −= L_ki L_kj                           (i an ancestor of k, j = i or an ancestor of i)
    /// ```
    ///
    /// Eliminating the leaves first, the updates touch only ancestors of `k`, so the
    /// factor has no entry outside the pattern. Returns the index of the first pivot that
    /// is not positive (or not finite) if `m` is not positive definite; `self` is then
    /// not a factor.
    pub fn factor_ltl_from(&mut self, m: &TreeMatrix) -> Result<(), usize> {
        debug_assert_eq!(self.pattern, m.pattern);
        self.allocate();
        self.values.copy_from_slice(&m.values);
        let p = &self.pattern;
        for k in (0..p.len()).rev() {
            let (sk, dk) = (p.start[k], p.depth[k]);
            let pivot = self.values[sk];
            if !(pivot > 0.0 && pivot.is_finite()) {
                return Err(k);
            }
            let a = pivot.sqrt();
            self.values[sk] = a;
            for v in &mut self.values[sk + 1..=sk + dk] {
                *v /= a;
            }
            // Row k's ancestors i = λ^m(k), m = 1 … dk: row i holds (i, λ^p(i)) at
            // start[i] + p, which is (k, λ^(m+p)(k)) of row k.
            let mut i = p.parent[k];
            for m_ in 1..=dk {
                let lki = self.values[sk + m_];
                let si = p.start[i];
                // Row i (later in memory than nothing of row k: i < k, so row i is
                // before row k and the two slices do not overlap).
                let (head, tail) = self.values.split_at_mut(sk);
                let row_k = &tail[m_..=dk];
                for (h, &lkj) in head[si..si + row_k.len()].iter_mut().zip(row_k) {
                    *h -= lki * lkj;
                }
                i = p.parent[i];
            }
        }
        Ok(())
    }

    /// Solves `Lᵀ L x = b` in place (`b` becomes `x`), `self` the factor `L` of
    /// [`Self::factor_ltl_from`] [F, §6.5, Table 6.4]:
    ///
    /// ```text
    /// Lᵀ y = b:   for i = n−1 … 0:  y_i = b_i / L_ii,   b_j −= L_ij y_i  (j an ancestor of i)
    /// L x = y:    for i = 0 … n−1:  x_i = (y_i − Σ_j L_ij x_j) / L_ii   (j an ancestor of i)
    /// ```
    ///
    /// Cost: twice the number of entries. `b` must have length `n`.
    pub fn solve_ltl(&self, b: &mut [Real]) {
        self.solve_lt(b);
        self.solve_l(b);
    }

    /// Solves `Lᵀ y = b` in place (`b` becomes `y`), backward along the tree: the first
    /// half of [`Self::solve_ltl`].
    pub fn solve_lt(&self, b: &mut [Real]) {
        let p = &self.pattern;
        debug_assert_eq!(b.len(), p.len());
        for i in (0..p.len()).rev() {
            let row = self.row(i);
            let y = b[i] / row[0];
            b[i] = y;
            let mut j = p.parent[i];
            for &l in &row[1..] {
                b[j] -= l * y;
                j = p.parent[j];
            }
        }
    }

    /// Solves `L x = y` in place (`y` becomes `x`), forward along the tree: the second
    /// half of [`Self::solve_ltl`].
    pub fn solve_l(&self, b: &mut [Real]) {
        let p = &self.pattern;
        debug_assert_eq!(b.len(), p.len());
        for i in 0..p.len() {
            let row = self.row(i);
            let mut s = b[i];
            let mut j = p.parent[i];
            for &l in &row[1..] {
                s -= l * b[j];
                j = p.parent[j];
            }
            b[i] = s / row[0];
        }
    }

    /// `y = M x` for the symmetric matrix (both triangles), allocation free.
    pub fn mul_vec(&self, x: &[Real], y: &mut [Real]) {
        let p = &self.pattern;
        y.fill(0.0);
        for i in 0..p.len() {
            let row = self.row(i);
            y[i] += row[0] * x[i];
            let mut j = p.parent[i];
            for &m in &row[1..] {
                y[i] += m * x[j];
                y[j] += m * x[i];
                j = p.parent[j];
            }
        }
    }
}

impl std::ops::Index<(usize, usize)> for TreeMatrix {
    type Output = Real;

    /// The entry `(i, j)`: a stored entry, or zero outside the pattern.
    fn index(&self, (i, j): (usize, usize)) -> &Real {
        match self.pattern.position(i, j) {
            Some(k) => self.values.get(k).unwrap_or(&ZERO),
            None => &ZERO,
        }
    }
}
