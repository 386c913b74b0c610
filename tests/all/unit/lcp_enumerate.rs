//! The unit tests of `lcp::enumerate` (`src/lcp/enumerate.rs`).

// The source module's own imports.
use nalgebra::{DMatrix, DVector};
use ricochet::lcp::{Allowed, Mode, Solutions};
use ricochet::linalg::{MinNorm, amax};
use ricochet::math::Real;

use crate::unit::linalg::Lcg;
use ricochet::lcp::enumerate::*;

/// The condition number `κ = σ₁/σ₂` of the `2 × 2` matrix `m` (rows), from
/// `σ₁σ₂ = |det|` and `σ₁² + σ₂² = ‖m‖²_F`; infinite when singular.
fn condition(m: [[Real; 2]; 2]) -> Real {
    let det = (m[0][0] * m[1][1] - m[0][1] * m[1][0]).abs();
    let f2: Real = m.iter().flatten().map(|v| v * v).sum();
    let s1 = ((f2 + (f2 * f2 - 4.0 * det * det).max(0.0).sqrt()) / 2.0).sqrt();
    s1 * s1 / det
}

/// The one-point path of [`ModeSystem::forces_near`] ([`ModeSystem::solve_one`], Cramer's
/// rule) against the general path (the pivoted Householder QR), a second determination,
/// on 40,000 random systems `A = Yᵀ Y` (of rank 2, and of rank 1: the general path's
/// fallback), with every mode, references at zero, at random and near the solution, over
/// 12 decades of scale: what it solves the general path solves too (it declines, to the
/// general path, the systems of rank 1 and those whose solution misses the equations'
/// tolerance: of the 38,572 the general path solves it takes 38,571), with the same forces to
/// the rounding the mode's system amplifies, `|Δx| ≤ 8 κ ε max(‖x‖∞, ‖x_ref‖∞)` (`κ` its condition number; the
/// reference's scale enters through `x = x_ref + δ`), and `w = A x + b` to that change
/// times `‖A‖` plus its own rounding; `forces_near` gives the one-point path's numbers. And a
/// sliding point's forces are the closed form of its equations,
/// `λ_n = −b_n / (A_nn − μ s A_nt)`, `λ_t = −μ s λ_n`, to the rounding `κ` amplifies and
/// the closed form's own pivot `h ≥ 10⁻³ max|A|` loses (`10³ κ ε`). (Until stop 39 the
/// one-point path was the QR on the stack, the general path's numbers to the bit.)
#[test]
fn one_point_agrees_with_the_general_path() {
    let mut rng = Lcg(16);
    let (mut fast, mut general) = (ModeSystem::new(), ModeSystem::new());
    let (mut taken, mut solved, mut worst_closed): (usize, usize, Real) = (0, 0, 0.0);
    let mut worst_general: Real = 0.0;
    for case in 0..40_000 {
        let scale = 10f64.powi(case % 13 - 6);
        let rows = if case % 7 == 3 { 1 } else { 2 };
        let y = DMatrix::from_fn(rows, 2, |_, _| rng.next() * scale.sqrt());
        let a = y.transpose() * &y;
        let b = DVector::from_fn(2, |_, _| 10.0 * rng.next());
        let mu = 0.5 * (rng.next() + 1.0);
        let mode = match case % 4 {
            0 => Mode::Open,
            1 => Mode::Stick,
            2 => Mode::Slide(1.0),
            _ => Mode::Slide(-1.0),
        };
        let reference = match case % 3 {
            0 => [0.0, 0.0],
            1 => [rng.next() / scale, rng.next() / scale],
            _ => match ricochet::lcp::forces(&a, &b, &[mu], &[mode]) {
                Some(s) => [s.x[0] * (1.0 + 1e-9 * rng.next()), s.x[1]],
                None => [0.0, 0.0],
            },
        };
        let scales = (a.amax().max(Real::MIN_POSITIVE), b.amax());
        let ok = fast.solve_one(&a, &b, mu, mode, &reference);
        let expected = general.solve(&a, &b, |_| mu, &[mode], scales, Some(&reference));
        if expected.is_some() {
            taken += 1;
        }
        if !ok {
            continue;
        }
        // What the one-point path solves, the general path solves.
        assert!(expected.is_some(), "case {case}: {a} {b} {mode:?}");
        solved += 1;
        let lhs = match mode {
            Mode::Open => [[1.0, 0.0], [0.0, 1.0]],
            Mode::Stick => [[a[(0, 0)], a[(0, 1)]], [a[(1, 0)], a[(1, 1)]]],
            Mode::Slide(s) => [[a[(0, 0)], a[(0, 1)]], [mu * s, 1.0]],
        };
        let kappa = condition(lhs);
        let x_scale = (fast.x.amax()).max(reference[0].abs().max(reference[1].abs()));
        let bound = 8.0 * kappa * Real::EPSILON * x_scale;
        for i in 0..2 {
            let dx = (fast.x[i] - general.x[i]).abs();
            worst_general = worst_general.max(dx / (kappa * Real::EPSILON * x_scale));
            assert!(
                dx <= bound,
                "case {case} {mode:?}: x[{i}] {} against {} (κ = {kappa:e})",
                fast.x[i],
                general.x[i]
            );
            // w = A x + b: the forces' difference through A, and w's own roundings.
            let dw = (fast.w[i] - general.w[i]).abs();
            let w_bound = 2.0 * scales.0 * bound
                + 4.0 * Real::EPSILON * (scales.1 + 2.0 * scales.0 * x_scale);
            assert!(
                dw <= w_bound,
                "case {case} {mode:?}: w[{i}] differs by {dw:e}"
            );
        }
        let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let x_fast = bits(&fast.x);
        let via = fast
            .forces_near(&a, &b, &[mu], &[mode], &reference)
            .unwrap();
        assert_eq!(bits(via.0), x_fast, "case {case}: forces_near");
        if let Mode::Slide(s) = mode {
            let h = a[(0, 0)] - mu * s * a[(0, 1)];
            // Well-posed: the pivot of the closed form is not itself rounding.
            if h.abs() > 1e-3 * a.amax() {
                let n = -b[0] / h;
                let err = (fast.x[0] - n).abs().max((fast.x[1] + mu * s * n).abs());
                // In units of the rounding the modes' system amplifies: κ ε.
                let rel = err / n.abs().max(Real::MIN_POSITIVE);
                worst_closed = worst_closed.max(rel / (kappa * Real::EPSILON));
            }
        }
    }
    println!("the general path solved {taken} systems, the one-point path {solved} of them");
    assert!(
        taken > 30_000 && solved > 20_000,
        "{taken} taken, {solved} solved"
    );
    println!(
        "against the general path: worst {worst_general:.2} κ ε; closed form: worst relative \
         difference {worst_closed:.2} κ ε"
    );
    assert!(worst_closed < 1e3, "closed form: {worst_closed} κ ε");
}

fn one(a: [[Real; 2]; 2], b: [Real; 2], allowed: Allowed) -> Solutions {
    solve(
        &DMatrix::from_row_slice(2, 2, &[a[0][0], a[0][1], a[1][0], a[1][1]]),
        &DVector::from_row_slice(&b),
        &[allowed],
    )
}

#[test]
fn a_pressed_contact_sticks_and_a_pulled_one_opens() {
    let free = Allowed {
        mu: 0.5,
        open: true,
        slip: None,
    };
    // A particle on a floor pressed by gravity (b_n = −g), no tangential push.
    let s = one([[1.0, 0.0], [0.0, 1.0]], [-9.81, 0.0], free);
    assert_eq!(s.all.len(), 1);
    assert_eq!(s.all[0].modes, vec![Mode::Stick]);
    assert!((s.all[0].x[0] - 9.81).abs() < 1e-12 && s.all[0].x[1].abs() < 1e-12);
    // Pulled away: it opens.
    let s = one([[1.0, 0.0], [0.0, 1.0]], [2.0, 1.0], free);
    assert_eq!(s.all.len(), 1);
    assert_eq!(s.all[0].modes, vec![Mode::Open]);
    // Pressed and pushed sideways beyond the cone: it starts to slip along the push.
    let s = one([[1.0, 0.0], [0.0, 1.0]], [-1.0, 3.0], free);
    assert_eq!(s.all.len(), 1);
    assert_eq!(s.all[0].modes, vec![Mode::Slide(1.0)]);
    assert!((s.all[0].x[1] + 0.5).abs() < 1e-12 && (s.all[0].w[1] - 2.5).abs() < 1e-12);
}

#[test]
fn painleve_sliding_contact_has_no_or_two_solutions() {
    // A sliding contact (s = +1) whose effective normal coefficient
    // h = m_nn − μ m_nt is negative: pressed (b_n < 0) there is no solution, pulled
    // (b_n > 0) there are two (open, or slide with x_n = −b_n/h).
    let (nn, nt, tt, mu) = (1.0, 1.5, 3.0, 1.0); // h = −0.5
    let sliding = Allowed {
        mu,
        open: true,
        slip: Some(1.0),
    };
    assert!(
        one([[nn, nt], [nt, tt]], [-1.0, 0.0], sliding)
            .all
            .is_empty()
    );
    let two = one([[nn, nt], [nt, tt]], [1.0, 0.0], sliding);
    assert_eq!(two.all.len(), 2);
    assert!((two.all[1].x[0] - 2.0).abs() < 1e-12);
}

#[test]
fn rank_deficient_a_is_handled() {
    // One degree of freedom: A = m [[1, k], [k, k²]]; the sticking system is singular
    // but consistent when the tangential row is a multiple of the normal one.
    let k = 0.1;
    let a = [[1.0, k], [k, k * k]];
    let s = one(
        a,
        [-2.0, -2.0 * k],
        Allowed {
            mu: 1.0,
            open: true,
            slip: None,
        },
    );
    assert!(s.all.iter().any(|sol| sol.modes == vec![Mode::Stick]));
    for sol in &s.all {
        assert!(sol.w[0].abs() < 1e-9 || sol.modes == vec![Mode::Open]);
    }
}

/// Three points sliding together (a 16-link chain lying on the floor, t = 0.82 s): a
/// regular 6×6 system (singular values 23…0.94) whose SVD solution missed the
/// equations by 9e-4 (nalgebra 0.35), so that the modes were reported to have no
/// solution; LU solves it to rounding. The normal rows are the chain's; the tangential
/// rows, which sliding modes do not use, are filled symmetrically.
#[test]
fn a_regular_system_the_svd_solves_badly_is_solved() {
    let a = DMatrix::from_row_slice(
        6,
        6,
        &[
            17.302117445679748,
            1.8165105226191547,
            -4.572156682577878,
            -0.36634463106233955,
            0.9849425829114355,
            0.16445165719519866,
            1.8165105226191547,
            1.0,
            -1.917698421818475,
            0.0,
            1.0701654368316207,
            0.0,
            -4.572156682577888,
            -1.917698421818475,
            17.05047970909367,
            1.4544438810525593,
            -3.6226685807213177,
            -0.5111557899640272,
            -0.36634463106233955,
            0.0,
            1.4544438810525593,
            1.0,
            -0.6640752695117632,
            0.0,
            0.9849425829114341,
            1.0701654368316207,
            -3.622668580721315,
            -0.6640752695117632,
            13.478413789294763,
            1.8276465193845035,
            0.16445165719519866,
            0.0,
            -0.5111557899640272,
            0.0,
            1.8276465193845035,
            1.0,
        ],
    );
    let b = DVector::from_row_slice(&[
        -9.660775322462747,
        0.0,
        -10.77653621543649,
        0.0,
        -6.045218443159906,
        0.0,
    ]);
    let modes = [Mode::Slide(1.0); 3];
    let sol = forces(&a, &b, &[0.3; 3], &modes).expect("a regular system has a solution");
    for (i, row) in [0usize, 2, 4].into_iter().enumerate() {
        // The normal equations w_n = 0, and Coulomb's sliding friction x_t = −μ x_n.
        assert!(sol.w[row].abs() <= 1e-12, "w_n{i} = {}", sol.w[row]);
        let slip = sol.x[row + 1] + 0.3 * sol.x[row];
        assert!(
            slip.abs() <= 1e-14 * sol.x[row].abs(),
            "x {:?}",
            sol.x.as_slice()
        );
    }
}

/// Two sticking points at one place (identical rows: two capsule ends at one hinge on a
/// floor) and a third: the forces of the modes are not unique. `forces_near` keeps a
/// valid split it is given, and otherwise changes it least (`x − x_ref` orthogonal to
/// the null space: of the solutions, the nearest); on a regular system it is `forces`.
#[test]
fn forces_near_a_reference_keep_the_split_of_redundant_points() {
    // J: rows (n0, t0), (n1, t1) = (n0, t0), (n2, t2) of a body with 3 speeds.
    let j = DMatrix::from_row_slice(
        6,
        3,
        &[
            1.0, 0.0, 0.3, 0.0, 1.0, -0.2, 1.0, 0.0, 0.3, 0.0, 1.0, -0.2, 1.0, 0.0, -0.7, 0.0, 1.0,
            -0.2,
        ],
    );
    let a = &j * j.transpose();
    let b = DVector::from_row_slice(&[-9.81, 1.0, -9.81, 1.0, -9.81, 1.0]);
    let modes = [Mode::Stick; 3];
    let mu = [0.5; 3];
    let plain = forces(&a, &b, &mu, &modes).unwrap();
    assert!(plain.w.amax() <= 1e-12);
    // The split with all of the hinge's force on its first point.
    let mut reference = plain.x.clone();
    reference[0] += plain.x[2];
    reference[1] += plain.x[3];
    reference[2] = 0.0;
    reference[3] = 0.0;
    let near = forces_near(&a, &b, &mu, &modes, &reference).unwrap();
    assert!((&near.x - &reference).amax() <= 1e-12, "{}", near.x);
    assert!(near.w.amax() <= 1e-12);
    // A reference off the solutions: the nearest solution. Its change is orthogonal
    // to the null direction (the hinge's force moved from one point to the other).
    let mut off = reference.clone();
    off[0] += 0.3;
    off[5] -= 0.2;
    let near = forces_near(&a, &b, &mu, &modes, &off).unwrap();
    assert!(near.w.amax() <= 1e-12);
    let null = DVector::from_row_slice(&[1.0, 0.0, -1.0, 0.0, 0.0, 0.0]);
    let tangential_null = DVector::from_row_slice(&[0.0, 1.0, 0.0, -1.0, 0.0, 0.0]);
    let change = &near.x - &off;
    assert!(change.dot(&null).abs() <= 1e-12 && change.dot(&tangential_null).abs() <= 1e-12);
    // A regular system: the one solution.
    let (a1, b1) = (
        a.view((4, 4), (2, 2)).into_owned(),
        b.rows(4, 2).into_owned(),
    );
    let one = forces(&a1, &b1, &mu[..1], &modes[..1]).unwrap();
    let near = forces_near(
        &a1,
        &b1,
        &mu[..1],
        &modes[..1],
        &DVector::from_element(2, 5.0),
    )
    .unwrap();
    assert!((&near.x - &one.x).amax() <= 1e-12 * one.x.amax());
}

/// Newton's cradle under RK4 at t = 0.9578 s: balls 1–4 at rest, touching, three
/// frictionless points (sliding with μ = 0), forces of rounding. The selection after
/// the impacts left a reference of 1.9e-17 N; `b` has fallen to 1.8e-32. The equations
/// are regular; `x_ref + δ` carries the rounding of `lhs x_ref` (~1e-33), which the
/// tolerance of the solution's own scale (1e-39) refused: "the forces of the closed
/// contact points have no solution", the run failed. The tolerance takes the
/// reference's scale too; the forces are the regular system's to that rounding. The
/// same for one point (the stack path).
#[test]
fn forces_far_below_their_reference_hold_to_the_reference_s_rounding() {
    let (d, c, p, q) = (
        3.9937597503900153,
        -1.9968798751950076,
        0.12480499219968798,
        0.0078003120124804995,
    );
    // Rows (n1, t1, n2, t2, n3, t3); the columns of the three points' normal and
    // tangential forces.
    let rows = [
        [d, 0.0, c, -p, 0.0, 0.0],
        [0.0, 2.0 * q, p, q, 0.0, 0.0],
        [c, p, d, 0.0, c, -p],
        [-p, q, 0.0, 2.0 * q, p, q],
        [0.0, 0.0, c, p, d, 0.0],
        [0.0, 0.0, -p, q, 0.0, 2.0 * q],
    ];
    let a = DMatrix::from_fn(6, 6, |i, j| rows[i][j]);
    let b = DVector::from_row_slice(&[
        1.7860112240328213e-32,
        1.116775127450512e-33,
        -8.28979888901439e-36,
        0.0,
        -8.289798887961006e-36,
        0.0,
    ]);
    let reference = [
        1.9144841961749036e-17,
        -4.6222318665293654e-33,
        1.276322797449936e-17,
        -3.7982270983039195e-65,
        6.381613987249679e-18,
        -0.0,
    ];
    let (modes, mu) = ([Mode::Slide(-1.0); 3], [0.0; 3]);
    let mut ws = ModeSystem::new();
    let (x, w) = ws
        .forces_near(&a, &b, &mu, &modes, &reference)
        .expect("regular equations hold to the rounding of the reference");
    let (x, w) = (x.clone(), w.clone());
    let plain = forces(&a, &b, &mu, &modes).expect("the regular system's one solution");
    let rounding = 1e3 * Real::EPSILON * a.amax() * amax(&reference);
    assert!((&x - &plain.x).amax() <= rounding, "{x} vs {}", plain.x);
    for row in [0, 2, 4] {
        assert!(w[row].abs() <= rounding, "w_n = {}", w[row]);
    }
    // One point: the same equations on the stack.
    let (a1, b1) = (
        a.view((0, 0), (2, 2)).into_owned(),
        b.rows(0, 2).into_owned(),
    );
    let (x1, _) = ws
        .forces_near(&a1, &b1, &mu[..1], &modes[..1], &reference[..2])
        .expect("one point holds to the rounding of its reference");
    let one = forces(&a1, &b1, &mu[..1], &modes[..1]).unwrap();
    assert!((x1 - &one.x).amax() <= rounding, "{x1} vs {}", one.x);
}

/// Two sticking points at *nearly* one place (the second capsule end at a hinge 1e-6 m
/// off the first) and a third: `A = J Jᵀ` has a singular value of 1.1e-12 of its
/// largest, which the equations' rounding cannot determine. A right-hand side moved by
/// rounding (5e-15 of `|b|`) along that direction: the least change at the rounding
/// rank moves the forces by 5e-15 / 1.1e-12 of `|b|` — percents — while
/// `forces_near` (rank at `REFERENCE_RANK_TOL`) keeps the reference's forces to
/// rounding, and its equations hold. (The 32-link chain with μ = 0.1, e = 0.6: −201 N
/// where the selection found 1.3e-3 N, and its lift-off event came back 1,000 times.)
#[test]
fn forces_near_a_reference_ignore_what_rounding_cannot_determine() {
    // A fourth speed that moves the second point's normal alone, by 1e-6.
    let j = DMatrix::from_row_slice(
        6,
        4,
        &[
            1.0, 0.0, 0.3, 0.0, 0.0, 1.0, -0.2, 0.0, 1.0, 0.0, 0.3, 1e-6, 0.0, 1.0, -0.2, 0.0, 1.0,
            0.0, -0.7, 0.0, 0.0, 1.0, -0.2, 0.0,
        ],
    );
    let a = &j * j.transpose();
    let b = DVector::from_row_slice(&[-9.81, 1.0, -9.81, 1.0, -9.81, 1.0]);
    let modes = [Mode::Stick; 3];
    let mu = [0.5; 3];
    let svd = a.clone().svd(true, true);
    let sigma = &svd.singular_values;
    let largest = sigma.max();
    // The near-null direction: below 1e-10 of the largest, above the rounding rank.
    let small = (0..6)
        .filter(|&i| sigma[i] > 6.0 * Real::EPSILON * largest && sigma[i] < 1e-10 * largest)
        .collect::<Vec<_>>();
    assert_eq!(small.len(), 1, "{sigma}");
    let u = svd.u.as_ref().unwrap().column(small[0]).into_owned();
    let reference = forces(&a, &b, &mu, &modes).unwrap();
    assert!(reference.w.amax() <= 1e-12);
    let moved = &b + &u * (5e-15 * b.amax());
    // The least change at the rounding rank, for comparison: percents.
    let mut change = DVector::zeros(0);
    let residual = -(&a * &reference.x + &moved);
    MinNorm::new().solve(&a, &residual, &mut change);
    assert!(change.amax() > 1e-3 * reference.x.amax(), "{change}");
    // forces_near keeps the reference.
    let near = forces_near(&a, &moved, &mu, &modes, &reference.x).unwrap();
    assert!(
        (&near.x - &reference.x).amax() <= 1e-12 * reference.x.amax(),
        "{} against {}",
        near.x,
        reference.x
    );
    assert!(near.w.amax() <= 1e-12 * b.amax());
}
