//! The unit tests of `linalg` (`src/linalg.rs`).

// The source module's own imports.
use nalgebra::{DMatrix, DVector};
use ricochet::math::Real;

use ricochet::linalg::*;

/// [`copy_short`] copies as `copy_from_slice` does, every entry's bits (NaN, `−0`
/// among them), at every length from 0 to 6 (the short cases and the fallback).
#[test]
fn copy_short_is_copy_from_slice() {
    let mut rng = Lcg(5);
    for len in 0..=6 {
        for case in 0..50 {
            let src: Vec<Real> = (0..len)
                .map(|i| match (case + i) % 5 {
                    0 => -0.0,
                    1 => Real::NAN,
                    _ => rng.next() * 1e3,
                })
                .collect();
            let (mut fast, mut slow) = (vec![7.0; len], vec![7.0; len]);
            copy_short(&mut fast, &src);
            slow.copy_from_slice(&src);
            let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&slow), "length {len}");
            assert_eq!(bits(&fast), bits(&src), "length {len}");
        }
    }
}

/// `amax` of a slice is nalgebra's `amax` of the matrix with those entries, to the bit,
/// with NaN, infinities, signed zeros and subnormals among random entries (a NaN's
/// place decides nalgebra's result: first, it stays unless a later entry is not below
/// it; later, it is skipped), and empty.
#[test]
fn amax_is_nalgebra_s_to_the_bit() {
    let mut rng = Lcg(7);
    let special = [
        Real::NAN,
        -Real::NAN,
        Real::INFINITY,
        Real::NEG_INFINITY,
        0.0,
        -0.0,
        5e-324,
        -Real::MAX,
    ];
    assert_eq!(
        amax(&[]).to_bits(),
        DVector::<Real>::zeros(0).amax().to_bits()
    );
    for case in 0..20_000 {
        let n = 1 + case % 7;
        let v: Vec<Real> = (0..n)
            .map(|_| {
                let r = rng.next();
                if r > 0.6 {
                    special[((r - 0.6) * 20.0) as usize % special.len()]
                } else {
                    r * 10f64.powi((case % 9) as i32 - 4)
                }
            })
            .collect();
        let m = DMatrix::from_column_slice(1, n, &v);
        assert_eq!(amax(&v).to_bits(), m.amax().to_bits(), "{v:?}");
    }
}

/// A deterministic pseudo-random sequence in [−1, 1) (a 64-bit LCG); the unit tests of
/// other modules use it too.
pub(crate) struct Lcg(pub(crate) u64);
impl Lcg {
    /// Uniform in `[−1, 1)`.
    pub(crate) fn next(&mut self) -> Real {
        self.unit() * 2.0 - 1.0
    }
    /// Uniform in `[0, 1)`.
    pub(crate) fn unit(&mut self) -> Real {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as Real / (1u64 << 53) as Real
    }
    fn matrix(&mut self, m: usize, n: usize) -> DMatrix<Real> {
        DMatrix::from_fn(m, n, |_, _| self.next())
    }
}

/// An orthogonal matrix: the Q of a random matrix.
fn orthogonal(rng: &mut Lcg, n: usize) -> DMatrix<Real> {
    rng.matrix(n, n).qr().q()
}

/// The `2 × 2` path gives the general path's numbers to the bit: its solution, rank
/// and truncation, on random systems of spread scales, nearly dependent columns and
/// exactly dependent ones (which it hands to the general path), at both rank
/// thresholds.
#[test]
fn the_2x2_path_is_the_general_path_to_the_bit() {
    let mut rng = Lcg(11);
    let (mut fast, mut general) = (MinNorm::new(), MinNorm::new());
    let mut solved_fast = 0;
    for case in 0..20_000 {
        let mut a = rng.matrix(2, 2);
        let scale = 10f64.powi((case % 13) as i32 - 6);
        a *= scale;
        match case % 5 {
            // Nearly dependent columns, at relative distances 1e-4 .. 1e-14.
            1 => {
                let d = 10f64.powi(-4 - (case % 11) as i32);
                let (c0, c1) = (a[(0, 0)], a[(1, 0)]);
                a[(0, 1)] = 2.0 * c0 * (1.0 + d * rng.next());
                a[(1, 1)] = 2.0 * c1;
            }
            // Exactly dependent, or a zero column.
            2 => {
                a[(0, 1)] = -3.0 * a[(0, 0)];
                a[(1, 1)] = -3.0 * a[(1, 0)];
            }
            3 => {
                a[(0, case % 2)] = 0.0;
                a[(1, case % 2)] = 0.0;
            }
            _ => {}
        }
        let b = DVector::from_fn(2, |_, _| rng.next() * scale);
        let rel_tol = if case % 2 == 0 { 0.0 } else { 1e-10 };
        let (mut x1, mut x2) = (DVector::zeros(2), DVector::zeros(2));
        let fast_rank = fast.solve_to_2x2(&a, &b, &mut x1, rel_tol);
        let r1 = fast.solve_to(&a, &b, &mut x1, rel_tol);
        let r2 = general.solve_general(&a, &b, &mut x2, rel_tol);
        solved_fast += usize::from(fast_rank.is_some());
        assert_eq!(r1, r2, "{a} {b}");
        assert_eq!(fast.truncated(), general.truncated(), "{a} {b}");
        for (u, v) in x1.iter().zip(x2.iter()) {
            assert_eq!(u.to_bits(), v.to_bits(), "{a} {b}: {x1} vs {x2}");
        }
    }
    assert!(
        solved_fast > 10_000,
        "only {solved_fast} systems on the 2x2 path"
    );
}

/// The 2×2 path keeps the signs of zeros as the general path makes them (its sums
/// `0 + x` and an empty sum's `−0` reach the solution): every system with entries in
/// {±0, ±1, 2, −½, 3} that the 2×2 path solves, bit for bit against the general path.
#[test]
fn the_2x2_path_keeps_the_general_path_s_signed_zeros() {
    let values = [0.0, -0.0, 1.0, -1.0, 2.0, -0.5, 3.0];
    let (mut fast, mut general) = (MinNorm::new(), MinNorm::new());
    let mut taken = 0;
    for code in 0..7usize.pow(6) {
        let e: Vec<Real> = (0..6).map(|d| values[code / 7usize.pow(d) % 7]).collect();
        let a = DMatrix::from_row_slice(2, 2, &e[..4]);
        let b = DVector::from_column_slice(&e[4..]);
        let (mut x1, mut x2) = (DVector::zeros(2), DVector::zeros(2));
        if fast.solve_to_2x2(&a, &b, &mut x1, 0.0).is_none() {
            continue;
        }
        taken += 1;
        general.solve_general(&a, &b, &mut x2, 0.0);
        for (u, v) in x1.iter().zip(x2.iter()) {
            assert_eq!(u.to_bits(), v.to_bits(), "{a} {b}: {x1} vs {x2}");
        }
    }
    assert!(taken > 50_000, "only {taken} systems on the 2x2 path");
}

#[test]
fn a_rank_deficient_system_of_known_svd_gets_its_minimum_norm_solution() {
    // A = U Σ Vᵀ with chosen singular values (some zero): the minimum-norm least-squares
    // solution is V Σ⁺ Uᵀ b, whatever b (consistent or not).
    let mut rng = Lcg(7);
    for (m, n, sigma) in [
        (6, 6, vec![36.8, 21.9, 1.04, 1.04, 0.77, 0.0]),
        (8, 8, vec![5.0, 3.0, 2.0, 1.0, 0.5, 0.0, 0.0, 0.0]),
        (5, 7, vec![2.0, 1.0, 1.0, 0.0, 0.0]),
        (7, 4, vec![3.0, 2.0, 0.0, 0.0]),
        (4, 4, vec![1e3, 1.0, 1e-3, 1e-6]),
        (3, 3, vec![0.0, 0.0, 0.0]),
    ] {
        let (u, v) = (orthogonal(&mut rng, m), orthogonal(&mut rng, n));
        let mut s = DMatrix::zeros(m, n);
        for (i, x) in sigma.iter().enumerate() {
            s[(i, i)] = *x;
        }
        let a = &u * &s * v.transpose();
        let b = DVector::from_fn(m, |_, _| rng.next());
        let mut s_plus = DMatrix::zeros(n, m);
        for (i, x) in sigma.iter().enumerate() {
            if *x > 0.0 {
                s_plus[(i, i)] = 1.0 / x;
            }
        }
        let expected = &v * s_plus * u.transpose() * &b;
        let mut x = DVector::zeros(0);
        let rank = MinNorm::new().solve(&a, &b, &mut x);
        assert_eq!(rank, sigma.iter().filter(|x| **x > 0.0).count(), "{m}×{n}");
        let scale = expected.amax().max(1.0);
        assert!(
            (&x - &expected).amax() <= 1e-9 * scale,
            "{m}×{n}: {:e}",
            (&x - &expected).amax()
        );
    }
}

/// `solve_to` leaves out a column whose remaining norm is below its threshold and
/// above the rounding one, and says so: `A = U diag(1, 0.5, 1e-13, 0) Vᵀ` has rank 3
/// at rounding, 2 at 1e-10, and the solution at 1e-10 is `V Σ₂⁺ Uᵀ b` with the first
/// two singular values alone.
#[test]
fn a_threshold_above_rounding_leaves_out_what_it_says() {
    let mut rng = Lcg(5);
    let (u, v) = (orthogonal(&mut rng, 4), orthogonal(&mut rng, 4));
    let sigma = [1.0, 0.5, 1e-13, 0.0];
    let s = DMatrix::from_diagonal(&DVector::from_row_slice(&sigma));
    let a = &u * s * v.transpose();
    let b = DVector::from_fn(4, |_, _| rng.next());
    let mut ws = MinNorm::new();
    let mut x = DVector::zeros(0);
    assert_eq!(ws.solve(&a, &b, &mut x), 3);
    assert!(!ws.truncated());
    assert_eq!(ws.solve_to(&a, &b, &mut x, 1e-10), 2);
    assert!(ws.truncated());
    let mut s_plus = DMatrix::zeros(4, 4);
    s_plus[(0, 0)] = 1.0;
    s_plus[(1, 1)] = 2.0;
    let expected = &v * s_plus * u.transpose() * &b;
    assert!((&x - &expected).amax() <= 1e-9, "{x} against {expected}");
    // Nothing between the thresholds: not truncated.
    let s = DMatrix::from_diagonal(&DVector::from_row_slice(&[1.0, 0.5, 0.0, 0.0]));
    let a = &u * s * v.transpose();
    assert_eq!(ws.solve_to(&a, &b, &mut x, 1e-10), 2);
    assert!(!ws.truncated());
}

#[test]
fn a_regular_system_gets_the_solution_of_lu() {
    let mut rng = Lcg(11);
    let mut ws = MinNorm::new();
    let mut x = DVector::zeros(0);
    for n in [1, 2, 5, 12, 40] {
        let a = rng.matrix(n, n) + DMatrix::identity(n, n) * 3.0;
        let b = DVector::from_fn(n, |_, _| rng.next());
        assert_eq!(ws.solve(&a, &b, &mut x), n);
        let lu = a.clone().lu().solve(&b).unwrap();
        assert!((&x - &lu).amax() <= 1e-13 * lu.amax(), "{n}");
    }
}

#[test]
// The dumped values as printed (17 decimals): they parse to the run's doubles.
#[allow(clippy::excessive_precision)]
fn three_sliding_points_of_the_chain_with_two_at_one_hinge_are_solved_to_rounding() {
    // The mode system of three sliding points (μ = 0.3, slip +1) of the 8-link chain
    // at t = 9.774 s (scenes/chain.toml): points 0 and 2, two capsule ends at one
    // hinge, have identical normal rows (rank 5 of 6, the other singular values
    // 31.4 … 0.56) and b_n equal to 3e-15 relative. nalgebra's SVD::solve left a
    // residual of 2.9e-6 on it, and the run stopped: "the forces of the closed contact
    // points have no solution".
    let a = DMatrix::from_row_slice(
        6,
        6,
        &[
            1.22118106648984384e1,
            6.65926996340335031e-1,
            -4.35600534008838691e-1,
            -9.42822737794350374e0,
            1.22118106648984384e1,
            3.45934486334052382e-1,
            6.65926996340334698e-1,
            5.00742551153329618e0,
            -3.49724136347787251e0,
            1.23626105242017070e0,
            6.65926996340334698e-1,
            4.45363738162639855e0,
            -4.35600534008838802e-1,
            -3.49724136347787207e0,
            2.12325547523530069e1,
            1.55236876320411366e1,
            -4.35600534008838802e-1,
            -1.22187821842321243e0,
            -9.42822737794350374e0,
            1.23626105242017115e0,
            1.55236876320411348e1,
            2.22423064633132732e1,
            -9.42822737794350374e0,
            2.95898813866214372e0,
            1.22118106648984384e1,
            6.65926996340335031e-1,
            -4.35600534008838691e-1,
            -9.42822737794350374e0,
            1.22118106648984384e1,
            3.45934486334052382e-1,
            3.45934486334052438e-1,
            4.45363738162639944e0,
            -1.22187821842321176e0,
            2.95898813866214505e0,
            3.45934486334052438e-1,
            4.17062385668894997e0,
        ],
    );
    let b = DVector::from_row_slice(&[
        -2.34799095179703272e1,
        -7.50291608884479899e0,
        -1.82955588057435392e0,
        6.77809946144794395e0,
        -2.34799095179700146e1,
        -9.95370893338296803e0,
    ]);
    let mu = 0.3;
    let mut lhs = DMatrix::zeros(6, 6);
    let mut rhs = DVector::zeros(6);
    for i in 0..3 {
        lhs.row_mut(2 * i).copy_from(&a.row(2 * i));
        rhs[2 * i] = -b[2 * i];
        lhs[(2 * i + 1, 2 * i + 1)] = 1.0;
        lhs[(2 * i + 1, 2 * i)] = mu;
    }
    let mut x = DVector::zeros(0);
    assert_eq!(MinNorm::new().solve(&lhs, &rhs, &mut x), 5);
    let residual = (&lhs * &x - &rhs).amax();
    assert!(residual <= 1e-13 * rhs.amax(), "{residual:e}");
}

#[test]
fn the_workspace_serves_systems_of_any_size_in_turn() {
    let mut rng = Lcg(3);
    let mut ws = MinNorm::new();
    let mut x = DVector::zeros(0);
    for (m, n) in [(10, 10), (2, 2), (6, 3), (3, 6), (10, 10)] {
        let a = rng.matrix(m, n);
        let b = &a * DVector::from_fn(n, |_, _| rng.next());
        ws.solve(&a, &b, &mut x);
        assert_eq!(x.len(), n);
        assert!((&a * &x - &b).amax() <= 1e-12, "{m}×{n}");
    }
}

/// [`product_into`] on random `a` (n × m) and `b` (m × p) of every size up to 9 and a
/// few of the 32-link chain's (W of up to 45 points: 90 × 32 times 32 × 90; and depths
/// past a block of [`GEMM_DEPTH`]), signed zeros among the entries, one `out` for all in
/// turn: each entry is the triple loop's sum to the bit — a rounded product and sum
/// when a size is at most 5, fused multiply–adds in blocks beyond — and where the
/// processor has fused multiply–adds (as this machine, whose logs are the reference)
/// nalgebra's own product to the bit.
#[test]
fn product_into_is_the_triple_loop_and_nalgebra_s_product_to_the_bit() {
    #[cfg(target_arch = "x86_64")]
    let fused_here = std::arch::is_x86_feature_detected!("fma");
    #[cfg(target_arch = "aarch64")]
    let fused_here = true;
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    let fused_here = false;
    let mut rng = Lcg(21);
    let mut out = DMatrix::zeros(0, 0);
    let sizes = (0..=9)
        .flat_map(|n| (0..=9).flat_map(move |m| [(n, m, n), (n, m, 9 - n)]))
        .chain([
            (90, 32, 90),
            (12, 32, 12),
            (6, 6, 6),
            (6, 300, 7),
            (8, 520, 6),
        ])
        .chain([(4, 32, 90), (90, 32, 4), (1, 1, 1)]);
    let mut cases = 0;
    for (n, m, p) in sizes {
        let scale = 10f64.powi(cases % 5 - 2);
        let mut entry = || match rng.unit() {
            x if x < 0.05 => -0.0,
            _ => rng.next() * scale,
        };
        let a = DMatrix::from_fn(n, m, |_, _| entry());
        let b = DMatrix::from_fn(m, p, |_, _| entry());
        product_into(&a, &b, &mut out);
        assert_eq!(out.shape(), (n, p));
        let fused = n > 5 && m > 5 && p > 5;
        for j in 0..p {
            for i in 0..n {
                let sum = match m {
                    0 => 0.0,
                    _ if fused => (0..m).step_by(GEMM_DEPTH).fold(0.0, |total, r0| {
                        let r1 = (r0 + GEMM_DEPTH).min(m);
                        let block =
                            (r0..r1).fold(0.0, |s: Real, r| a[(i, r)].mul_add(b[(r, j)], s));
                        block + total
                    }),
                    _ => (1..m).fold(a[(i, 0)] * b[(0, j)], |s, r| a[(i, r)] * b[(r, j)] + s),
                };
                let at = format!("{n}×{m} × {m}×{p} ({i}, {j})");
                assert_eq!(out[(i, j)].to_bits(), sum.to_bits(), "{at}");
            }
        }
        if fused_here || !fused {
            let nalgebra = &a * &b;
            let bits = |m: &DMatrix<Real>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out), bits(&nalgebra), "{n}×{m} × {m}×{p}");
        }
        cases += 1;
    }
    assert_eq!(cases, 200 + 8);
}
