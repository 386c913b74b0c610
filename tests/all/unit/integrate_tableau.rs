//! The unit tests of `integrate::tableau` (`src/integrate/tableau.rs`).

// The source module's own imports.
use ricochet::math::Real;

use ricochet::integrate::tableau::*;
use std::collections::BTreeSet;

/// A rooted tree, its children in canonical (sorted) order [HNW, II.2].
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Tree(Vec<Tree>);

impl Tree {
    fn order(&self) -> usize {
        1 + self.0.iter().map(Tree::order).sum::<usize>()
    }

    /// `γ(t) = |t| Π γ(children)`.
    fn gamma(&self) -> Real {
        self.order() as Real * self.0.iter().map(Tree::gamma).product::<Real>()
    }

    /// Every tree made by attaching a leaf to one node of this one, canonical.
    fn grown(&self) -> Vec<Tree> {
        let mut out = vec![{
            let mut c = self.0.clone();
            c.push(Tree(Vec::new()));
            c.sort();
            Tree(c)
        }];
        for (k, child) in self.0.iter().enumerate() {
            for g in child.grown() {
                let mut c = self.0.clone();
                c[k] = g;
                c.sort();
                out.push(Tree(c));
            }
        }
        out
    }

    /// The stage vector `Φᵢ(t) = Πᵤ (Σⱼ aᵢⱼ Φⱼ(u))` over the children `u` [HNW, II.2,
    /// Def. 2.9]; `a[i]` is row `i` of the full matrix (row 0 empty).
    fn phi(&self, a: &[Vec<Real>]) -> Vec<Real> {
        let mut phi = vec![1.0; a.len()];
        for u in &self.0 {
            let pu = u.phi(a);
            for (i, row) in a.iter().enumerate() {
                phi[i] *= row.iter().zip(&pu).map(|(a, p)| a * p).sum::<Real>();
            }
        }
        phi
    }
}

/// All rooted trees of order 1 … `max`.
fn trees(max: usize) -> Vec<Tree> {
    let mut all = vec![Tree(Vec::new())];
    let mut last: BTreeSet<Tree> = all.iter().cloned().collect();
    for _ in 2..=max {
        let next: BTreeSet<Tree> = last.iter().flat_map(Tree::grown).collect();
        all.extend(next.iter().cloned());
        last = next;
    }
    all
}

/// The full `A` (row 0 empty) of stages 1 … s, and the extended one with the row of
/// `f(t₁, y₁)` (= b) and the dense output's extra rows.
fn full_a(tab: &Tableau, extended: bool) -> Vec<Vec<Real>> {
    let mut rows: Vec<&[Real]> = vec![&[]];
    rows.extend(tab.a.iter().copied());
    let b: Vec<Real> = tab.b.iter().map(|b| b / tab.b_den).collect();
    let mut a: Vec<Vec<Real>> = rows.iter().map(|r| r.to_vec()).collect();
    if extended {
        a.push(b);
        if let DenseOutput::Extended { a: extra, .. } = tab.dense {
            a.extend(extra.iter().map(|r| r.to_vec()));
        }
    }
    let m = a.len();
    a.iter_mut().for_each(|r| r.resize(m, 0.0));
    a
}

/// The largest residual `|Σ bᵢ Φᵢ(t) − 1/γ(t)|` over the trees of order `q`.
fn residual(a: &[Vec<Real>], b: &[Real], all: &[Tree], q: usize) -> Real {
    (all.iter().filter(|t| t.order() == q))
        .map(|t| {
            let w: Real = t.phi(a).iter().zip(b).map(|(p, b)| p * b).sum();
            (w - 1.0 / t.gamma()).abs()
        })
        .fold(0.0, Real::max)
}

/// Checks that `b` has exactly order `p` on `a`: every tree of order ≤ p within `tol`
/// (486 trees up to order 9), some tree of order p + 1 off by more than 1e-6.
fn assert_order(name: &str, a: &[Vec<Real>], b: &[Real], p: usize, tol: Real) {
    let all = trees(p + 1);
    for q in 1..=p {
        let r = residual(a, b, &all, q);
        assert!(r <= tol, "{name}: order {q} residual {r:e}");
    }
    let r = residual(a, b, &all, p + 1);
    assert!(r > 1e-6, "{name}: order {} holds too ({r:e})", p + 1);
}

/// The number of trees of each order: 1, 1, 2, 4, 9, 20, 48, 115, 286 [HNW, II.2,
/// Table 2.1].
#[test]
fn the_trees_are_counted_right() {
    let all = trees(9);
    let counts: Vec<usize> = (1..=9)
        .map(|q| all.iter().filter(|t| t.order() == q).count())
        .collect();
    assert_eq!(counts, [1, 1, 2, 4, 9, 20, 48, 115, 286]);
}

/// Every tableau meets the order conditions of its order on all the Butcher trees
/// [HNW, II.2, Th. 2.13] and fails one of the next order; its embedded weights meet
/// theirs (DOPRI5's `b̂` order 4 with the FSAL stage, DOP853's `b − ê₅` order 5 and
/// `b − ê₃` order 3); the nodes are the row sums of `A`; DOP853's extra stages of the
/// dense output too.
#[test]
fn tableaux_meet_their_order_conditions() {
    for tab in [DOPRI5, RK4, DOP853] {
        let a = full_a(&tab, false);
        let b: Vec<Real> = tab.b.iter().map(|b| b / tab.b_den).collect();
        for (i, row) in a.iter().enumerate() {
            let sum: Real = row.iter().sum();
            assert!((sum - tab.c[i]).abs() < 1e-14, "{}: c{}", tab.name, i + 1);
        }
        assert_order(tab.name, &a, &b, tab.order as usize, 1e-13);
        let ext = full_a(&tab, true);
        for (i, row) in ext.iter().enumerate().skip(tab.stages()) {
            let sum: Real = row.iter().sum();
            let c = match (i - tab.stages(), tab.dense) {
                (0, _) => 1.0,
                (m, DenseOutput::Extended { c, .. }) => c[m - 1],
                _ => unreachable!(),
            };
            assert!((sum - c).abs() < 1e-14, "{}: extended c{}", tab.name, i + 1);
        }
    }
    // DOPRI5's b̂ = b − e over the 7 stages (the 7th is f(t₁, y₁)).
    let ext = full_a(&DOPRI5, true);
    let ErrorEstimate::Embedded { e } = DOPRI5.error else {
        unreachable!()
    };
    let b_hat: Vec<Real> = (0..7)
        .map(|j| DOPRI5.b.get(j).copied().unwrap_or(0.0) - e[j])
        .collect();
    assert_order("dopri5 b̂", &ext[..7], &b_hat, 4, 1e-14);
    // DOP853's b − ê₅ and b − ê₃ over its 12 stages.
    let a = full_a(&DOP853, false);
    let ErrorEstimate::Dop853 { e5, e3 } = DOP853.error else {
        unreachable!()
    };
    let minus = |e: &[Real]| -> Vec<Real> { DOP853.b.iter().zip(e).map(|(b, e)| b - e).collect() };
    assert_order("dop853 b − ê₅", &a, &minus(e5), 5, 1e-13);
    assert_order("dop853 b − ê₃", &a, &minus(e3), 3, 1e-13);
}

/// DOPRI5's error weights `e = b − b̂` and dense weights `d`, over `k₁ … k₇`.
fn dopri5_e_and_d() -> (&'static [Real], &'static [Real]) {
    let ErrorEstimate::Embedded { e } = DOPRI5.error else {
        unreachable!()
    };
    let DenseOutput::Shampine { d } = DOPRI5.dense else {
        unreachable!()
    };
    (e, d)
}

/// Row sums of `A` equal the nodes `c` (the stages are consistent), and the weights `b`
/// (row 7, FSAL) sum to 1.
#[test]
fn row_sums_are_the_nodes() {
    let eps = 4.0 * Real::EPSILON;
    for (i, row) in DOPRI5.a.iter().enumerate() {
        let tol = if i < 3 { eps } else { 16.0 * eps };
        let sum: Real = row.iter().sum();
        assert!((sum - DOPRI5.c[i + 1]).abs() <= tol, "row {}", i + 2);
    }
    assert_eq!(DOPRI5.b_den, 1.0);
    assert!((DOPRI5.b.iter().sum::<Real>() - 1.0).abs() <= eps);
}

/// The order conditions of the 5th-order weights up to order 5 along the "bushy"
/// trees `Σ bᵢ cᵢ^(q−1) = 1/q`, and `Σ eᵢ = 0` (both weights are consistent).
#[test]
fn quadrature_conditions() {
    // Over k₁ … k₇: k₇ = f(t₁, y₁) has weight 0 in b and node 1.
    let b: Vec<Real> = DOPRI5.b.iter().copied().chain([0.0]).collect();
    let c: Vec<Real> = DOPRI5.c.iter().copied().chain([1.0]).collect();
    assert_eq!((b.len(), c.len()), (7, 7));
    for q in 1..=5 {
        let s: Real = b.iter().zip(&c).map(|(b, c)| b * c.powi(q - 1)).sum();
        assert!((s - 1.0 / q as Real).abs() < 1e-15, "q = {q}: {s}");
    }
    let (e, _) = dopri5_e_and_d();
    assert!(e.iter().sum::<Real>().abs() < 1e-16);
    // b̂ = b − e integrates polynomials up to degree 3 exactly (order 4).
    for q in 1..=4 {
        let s: Real = b
            .iter()
            .zip(e)
            .zip(&c)
            .map(|((b, e), c)| (b - e) * c.powi(q - 1))
            .sum();
        assert!((s - 1.0 / q as Real).abs() < 1e-15, "q = {q}: {s}");
    }
}

/// `Σ dᵢ = 0`: `r₅` vanishes on a constant slope, so the dense output of `ẏ = c` is
/// exactly linear.
#[test]
fn dense_weights_sum_to_zero() {
    let (_, d) = dopri5_e_and_d();
    let s: Real = d.iter().sum();
    assert!(s.abs() < 1e-14, "{s}");
}
