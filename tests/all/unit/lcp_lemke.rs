//! The unit tests of `lcp::lemke` (`src/lcp/lemke.rs`).

// The source module's own imports.
use ricochet::math::Real;

use nalgebra::{DMatrix, DVector};

use crate::unit::linalg::Lcg;
use ricochet::lcp::lemke::*;

/// The textbook loops of this module before `B⁻¹` went by columns (row-major `B⁻¹`,
/// row-by-row dot products, no term left out): the reference the workspace must match
/// to the bit.
struct Textbook {
    n: usize,
    binv: Vec<Real>,
    xb: Vec<Real>,
    basis: Vec<usize>,
    col: Vec<Real>,
    cover: Vec<Real>,
    ties: Vec<usize>,
    z: Vec<Real>,
    w: Vec<Real>,
}

impl Textbook {
    fn solve(
        m: &DMatrix<Real>,
        q: &DVector<Real>,
        d: Option<&[Real]>,
    ) -> (LemkeStatus, Vec<Real>, Vec<Real>) {
        let n = q.len();
        let mut t = Textbook {
            n,
            binv: vec![0.0; n * n],
            xb: vec![0.0; n],
            basis: (0..n).collect(),
            col: vec![0.0; n],
            cover: d.map_or(vec![1.0; n], <[Real]>::to_vec),
            ties: Vec::new(),
            z: vec![0.0; n],
            w: vec![0.0; n],
        };
        let sq = q.iter().fold(0.0 as Real, |acc, v| acc.max(v.abs()));
        if q.iter().all(|&v| v >= 0.0) {
            return (
                LemkeStatus::Solved { pivots: 0 },
                t.z,
                q.as_slice().to_vec(),
            );
        }
        let sm = m.iter().fold(0.0 as Real, |acc, v| acc.max(v.abs()));
        let sm = if sm > 0.0 { sm } else { 1.0 };
        for i in 0..n {
            t.binv[i * n + i] = 1.0;
            t.xb[i] = q[i] / sq;
        }
        let max_pivots = 1000.max(50 * n);
        let z0 = 2 * n;
        let mut entering = z0;
        t.column(m, sm, entering);
        let mut pivots = 0;
        let mut leave = t.ratio_test(true);
        let z0_row = leave.unwrap_or(0);
        let z0_start = leave.map_or(0.0, |r| t.xb[r] / t.col[r]);
        loop {
            let Some(r) = leave else {
                return (LemkeStatus::RayTermination { pivots }, t.z, t.w);
            };
            if pivots == max_pivots {
                return (LemkeStatus::PivotLimit { pivots }, t.z, t.w);
            }
            let left = t.pivot(r, entering);
            pivots += 1;
            if left == z0 {
                break;
            }
            t.refine(m, q, sm, sq);
            if t.xb[z0_row] <= Z0_TOL * z0_start {
                break;
            }
            entering = if left < n { left + n } else { left - n };
            t.column(m, sm, entering);
            leave = t.ratio_test(false);
        }
        t.refine(m, q, sm, sq);
        t.refine(m, q, sm, sq);
        for (b, &var) in t.basis.iter().enumerate() {
            if (n..2 * n).contains(&var) {
                // `.max(0.0)`, as main's build computes it (`maxsd v, +0`: `+0` for
                // either zero; `f64::max` leaves the sign of a zero open).
                let v = t.xb[b] * sq / sm;
                t.z[var - n] = if v > 0.0 { v } else { 0.0 };
            }
        }
        for i in 0..n {
            t.w[i] = q[i] + (0..n).map(|j| m[(i, j)] * t.z[j]).sum::<Real>();
        }
        (LemkeStatus::Solved { pivots }, t.z, t.w)
    }

    fn column(&mut self, m: &DMatrix<Real>, sm: Real, e: usize) {
        let n = self.n;
        for i in 0..n {
            let row = &self.binv[i * n..(i + 1) * n];
            self.col[i] = if e < n {
                row[e]
            } else if e < 2 * n {
                let j = e - n;
                let (sum, size) = (0..n).fold((0.0 as Real, 0.0 as Real), |(s, a), k| {
                    let t = row[k] * m[(k, j)];
                    (s + t, a + t.abs())
                });
                if sum.abs() <= CANCEL_TOL * size {
                    0.0
                } else {
                    -sum / sm
                }
            } else {
                -row.iter()
                    .zip(&self.cover)
                    .map(|(a, d)| a * d)
                    .sum::<Real>()
            };
        }
    }

    fn ratio_test(&mut self, initial: bool) -> Option<usize> {
        let n = self.n;
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
        let mut min = Real::INFINITY;
        for i in 0..n {
            let c = piv(self.col[i]);
            if c > 0.0 {
                min = min.min(self.xb[i] / c);
            }
        }
        if !min.is_finite() {
            return None;
        }
        let tie = |a: Real, b: Real| (a - b).abs() <= TIE_TOL * (1.0 + a.abs().max(b.abs()));
        self.ties.clear();
        for i in 0..n {
            let c = piv(self.col[i]);
            if c > 0.0 && tie(self.xb[i] / c, min) {
                self.ties.push(i);
            }
        }
        if let Some(&r) = self.ties.iter().find(|&&i| self.basis[i] == 2 * n) {
            return Some(r);
        }
        let mut j = 0;
        while self.ties.len() > 1 && j < n {
            let ratio = |i: usize| self.binv[i * n + j] / piv(self.col[i]);
            let min = (self.ties.iter().map(|&i| ratio(i))).fold(Real::INFINITY, Real::min);
            self.ties.retain(|&i| tie(ratio(i), min));
            j += 1;
        }
        self.ties.first().copied()
    }

    fn pivot(&mut self, r: usize, e: usize) -> usize {
        let n = self.n;
        let p = self.col[r];
        for v in &mut self.binv[r * n..(r + 1) * n] {
            *v /= p;
        }
        self.xb[r] /= p;
        let prow: Vec<Real> = self.binv[r * n..(r + 1) * n].to_vec();
        for i in (0..n).filter(|&i| i != r) {
            let f = self.col[i];
            if f != 0.0 {
                for (v, pv) in self.binv[i * n..(i + 1) * n].iter_mut().zip(&prow) {
                    *v -= f * pv;
                }
                self.xb[i] -= f * self.xb[r];
            }
        }
        std::mem::replace(&mut self.basis[r], e)
    }

    fn refine(&mut self, m: &DMatrix<Real>, q: &DVector<Real>, sm: Real, sq: Real) {
        let n = self.n;
        let mut r: Vec<Real> = q.iter().map(|v| v / sq).collect();
        for (b, &var) in self.basis.iter().enumerate() {
            let x = self.xb[b];
            if var < n {
                r[var] -= x;
            } else if var < 2 * n {
                let (j, xs) = (var - n, x / sm);
                for (k, rk) in r.iter_mut().enumerate() {
                    *rk += m[(k, j)] * xs;
                }
            } else {
                for (rk, d) in r.iter_mut().zip(&self.cover) {
                    *rk += d * x;
                }
            }
        }
        for i in 0..n {
            let row = &self.binv[i * n..(i + 1) * n];
            self.xb[i] += row.iter().zip(&r).map(|(a, b)| a * b).sum::<Real>();
        }
    }
}

/// Stewart–Trinkle's LCP of `c` contacts (`lcp::friction`'s layout: `x_n, f⁺, f⁻, σ`)
/// with `A = J Jᵀ` of rank `dof < 2c` (redundant points, nearly equal columns) and
/// some points at rest (`b_n = 0`): the degenerate, ill-conditioned problems of a chain
/// lying on the floor.
fn contact_lcp(rng: &mut Lcg, c: usize, dof: usize) -> (DMatrix<Real>, DVector<Real>) {
    let mut j = DMatrix::from_fn(2 * c, dof, |_, _| rng.next());
    // A pair of nearly coincident points.
    if c >= 2 {
        for k in 0..dof {
            j[(2, k)] = j[(0, k)] * (1.0 + 1e-9 * rng.next());
        }
    }
    let a = &j * j.transpose();
    let b = DVector::from_fn(2 * c, |i, _| match (i % 2, rng.unit()) {
        (0, u) if u < 0.3 => 0.0,
        (_, u) => 2.0 * u - 1.2,
    });
    let mu = 0.1 + rng.unit();
    let k = 4 * c;
    let mut m = DMatrix::zeros(k, k);
    let mut q = DVector::zeros(k);
    let map = |i: usize| {
        [
            (4 * i, 2 * i, 1.0),
            (4 * i + 1, 2 * i + 1, 1.0),
            (4 * i + 2, 2 * i + 1, -1.0),
        ]
    };
    for r in 0..c {
        for (lr, ar, sr) in map(r) {
            q[lr] = sr * b[ar];
            for s in 0..c {
                for (lc, ac, sc) in map(s) {
                    m[(lr, lc)] = sr * sc * a[(ar, ac)];
                }
            }
        }
        let (xn, fp, fm, sigma) = (4 * r, 4 * r + 1, 4 * r + 2, 4 * r + 3);
        m[(fp, sigma)] = 1.0;
        m[(fm, sigma)] = 1.0;
        m[(sigma, xn)] = mu;
        m[(sigma, fp)] = -1.0;
        m[(sigma, fm)] = -1.0;
    }
    (m, q)
}

/// The workspace's path and solution are the textbook loops' to the bit (status,
/// pivots, every bit of `z` and `w`, signs of zeros included), on 400 degenerate contact
/// LCPs of 1 to 12 points, along `d = 1` and along random covering vectors, and on dense
/// random matrices; one workspace for all, so a larger problem's leftovers are reused.
#[test]
fn the_column_sweeps_are_the_textbook_loops_to_the_bit() {
    let mut rng = Lcg(16);
    let mut lemke = Lemke::new();
    let mut solved = 0;
    for case in 0..400 {
        let (m, q) = if case % 4 == 3 {
            let n = 1 + (rng.unit() * 30.0) as usize;
            let m = DMatrix::from_fn(n, n, |_, _| rng.next());
            (m, DVector::from_fn(n, |_, _| rng.next()))
        } else {
            let c = 1 + (rng.unit() * 12.0) as usize;
            let dof = 1 + (rng.unit() * (2 * c) as Real) as usize;
            contact_lcp(&mut rng, c, dof)
        };
        let cover: Vec<Real> = (0..q.len()).map(|_| 0.01 + 10.0 * rng.unit()).collect();
        for d in [None, Some(&cover[..])] {
            let (status, z, w) = Textbook::solve(&m, &q, d);
            assert_eq!(lemke.solve_covered(&m, &q, d), Ok(status), "case {case}");
            if let LemkeStatus::Solved { pivots } = status {
                solved += usize::from(pivots > 0);
                let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(lemke.z()), bits(&z), "case {case}: z");
                assert_eq!(bits(lemke.w()), bits(&w), "case {case}: w");
            }
        }
    }
    // The comparison is not vacuous: most paths pivot and solve.
    assert!(solved > 400, "{solved} solved paths with pivots");
}
