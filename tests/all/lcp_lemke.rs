//! Lemke's algorithm (`lcp::lemke`) and the complementarity solver of the contact problem
//! (`lcp::Solver`): against the exact enumeration (`lcp::solve`) on random small problems,
//! against the LCP's defining conditions on random P-matrix problems up to 256 variables,
//! and on known answers (a particle on a floor, Painlevé's rod, a block on a slope).

use nalgebra::{DMatrix, DVector};
use ricochet::lcp::lemke::{Lemke, LemkeStatus};
use ricochet::lcp::{self, Allowed, LcpError, Mode, Solver};

use crate::common::rng;
use rng::Rng;

/// A random contact problem of `n` contacts: `A = J M⁻¹ Jᵀ` with a random SPD `M`
/// (`d × d`, `R Rᵀ + 0.1 I`, `R` uniform in [−1, 1]) and a random `J` (2n × d), so that `A`
/// is singular when `d < 2n`; `μ` in [0, 1.5] (0 one time in ten), the slip unknown one
/// time in two, else ±1; `b` uniform in [−1, 1] (`in_range`: `b = J v`, `v` uniform).
fn problem(
    rng: &mut Rng,
    n: usize,
    d: usize,
    in_range: bool,
) -> (DMatrix<f64>, DVector<f64>, Vec<Allowed>) {
    let r = DMatrix::from_fn(d, d, |_, _| rng.range(-1.0, 1.0));
    let m = &r * r.transpose() + DMatrix::identity(d, d) * 0.1;
    let j = DMatrix::from_fn(2 * n, d, |_, _| rng.range(-1.0, 1.0));
    let m_inv = m.try_inverse().expect("SPD");
    let a = &j * m_inv * j.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let b = if in_range {
        let v = DVector::from_fn(d, |_, _| rng.range(-1.0, 1.0));
        &j * v
    } else {
        DVector::from_fn(2 * n, |_, _| rng.range(-1.0, 1.0))
    };
    let allowed = (0..n)
        .map(|_| {
            let mu = if rng.pick(10) == 0 {
                0.0
            } else {
                rng.range(0.0, 1.5)
            };
            let slip = match rng.pick(4) {
                0 => Some(1.0),
                1 => Some(-1.0),
                _ => None,
            };
            Allowed {
                mu,
                open: true,
                slip,
            }
        })
        .collect();
    (a, b, allowed)
}

/// What Lemke's solver and the enumeration said on a set of problems.
#[derive(Default, Debug)]
struct Tally {
    problems: usize,
    /// Both found a solution, Lemke's `w` is one of the enumeration's.
    both_solved: usize,
    /// Neither found one.
    both_none: usize,
    /// The enumeration found one, Lemke ended on a ray.
    missed: usize,
    /// … of which every contact's slip was unknown (a copositive LCP).
    missed_unknown_slip: usize,
    /// Lemke found a solution (that satisfies the table), the enumeration none.
    extra: usize,
    /// Both found one, Lemke's `w` is none of the enumeration's.
    w_differs: usize,
    /// Lemke returned another error.
    other_error: usize,
    /// Solutions of the enumeration that break the table's conditions (discarded).
    bogus: usize,
    worst_w: f64,
    worst_conditions: f64,
    max_pivots: usize,
}

fn compare(
    tally: &mut Tally,
    solver: &mut Solver,
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    allowed: &[Allowed],
) {
    let enumerated = lcp::solve(a, b, allowed).all;
    let listed = enumerated.len();
    // Only the enumeration's solutions that satisfy the table's conditions with forces of
    // a sensible size: its LU fallback returns x ~ 1e16 for some singular systems (a
    // "stick" with w_n = −0.6 when b ~ 1), whose residual passes its test relative to
    // |A| |x| (reported; the enumeration is left as it is).
    let plausible = |s: &lcp::Solution| {
        lcp::conditions_violation(a, b, allowed, s) <= 1e-7
            && a.amax() * s.x.amax() <= 1e8 * b.amax()
    };
    let all: Vec<lcp::Solution> = enumerated.into_iter().filter(plausible).collect();
    tally.bogus += listed - all.len();
    let got = solver.solve(a, b, allowed);
    tally.problems += 1;
    tally.max_pivots = tally.max_pivots.max(solver.pivots());
    let show = |what: &str| {
        if std::env::var("LCP_SHOW").is_ok_and(|v| what.starts_with(&v)) {
            eprintln!("{what}: A = {a:?}\nb = {b:?}\nallowed = {allowed:?}\nenumeration {all:?}");
        }
    };
    match (all.is_empty(), got) {
        (true, Err(LcpError::NoSolution { .. })) => tally.both_none += 1,
        (false, Ok(sol)) => {
            let v = lcp::conditions_violation(a, b, allowed, &sol);
            tally.worst_conditions = tally.worst_conditions.max(v);
            let sx = all.iter().map(|s| s.x.amax()).fold(sol.x.amax(), f64::max);
            let scale = b.amax() + a.amax() * sx;
            let d = (all.iter())
                .map(|s| (&s.w - &sol.w).amax() / scale)
                .fold(f64::INFINITY, f64::min);
            tally.worst_w = tally.worst_w.max(d);
            if d <= W_TOL {
                tally.both_solved += 1;
            } else {
                tally.w_differs += 1;
                show(&format!("w differs by {d:e}, Lemke {sol:?}"));
            }
        }
        (false, Err(LcpError::NoSolution { .. })) => {
            tally.missed += 1;
            if allowed.iter().all(|c| c.slip.is_none()) {
                tally.missed_unknown_slip += 1;
            }
            show("missed");
        }
        (true, Ok(sol)) => {
            tally.extra += 1;
            tally.worst_conditions = tally
                .worst_conditions
                .max(lcp::conditions_violation(a, b, allowed, &sol));
            show(&format!("extra, Lemke {sol:?}"));
        }
        (_, Err(e)) => {
            tally.other_error += 1;
            show(&format!("error {e}"));
        }
    }
}

/// Lemke's `w` against the enumeration's, relative to `max|b| + max|A| max|x|`.
const W_TOL: f64 = 1e-7;

/// Lemke's solver against the enumeration on 8,000 random problems of 1 to 4 contacts
/// (`problem`: `A` singular when `d < 2n`, random `μ`, slips unknown or known), half with
/// `b = J v` (in the range of `A`, as the impact and the free accelerations make it), half
/// with `b` anywhere. Measured (seed below):
///
/// | b | agree | neither | Lemke misses | Lemke only | enumeration's bogus |
/// |---|---|---|---|---|---|
/// | J v | 3,635 | 154 | 13 | 198 | 0 |
/// | any | 3,514 | 482 | 4 | 0 | 313 |
///
/// Every miss has a contact with a known slip (a non-copositive LCP: Painlevé's case,
/// where Lemke's path from `d = 1` can end on a ray though a solution exists; the 8
/// retries along other covering vectors brought 44 misses down to 17). "Lemke only": a
/// solution that satisfies the table to 1e-14 and that the enumeration does not find — a
/// stick of redundant contacts whose least-squares split leaves the cone (the block on two
/// corners of issue 15). "Bogus": solutions of the enumeration with forces ~1e16 from its
/// LU fallback on a singular system, left out of the comparison.
#[test]
fn lemke_agrees_with_the_enumeration_on_random_problems() {
    let mut rng = Rng(0x1e3e_0015);
    let mut solver = Solver::new();
    let mut missed = 0;
    for in_range in [true, false] {
        let mut tally = Tally::default();
        for case in 0..4000 {
            let n = 1 + case % 4;
            let d = 1 + rng.pick(8);
            let (a, b, allowed) = problem(&mut rng, n, d, in_range);
            compare(&mut tally, &mut solver, &a, &b, &allowed);
        }
        println!("b = J v: {in_range}: {tally:?}");
        assert_eq!(tally.w_differs, 0, "{tally:?}");
        assert_eq!(tally.other_error, 0, "{tally:?}");
        assert_eq!(tally.missed_unknown_slip, 0, "{tally:?}");
        assert!(tally.worst_w <= 1e-12, "{tally:?}");
        assert!(tally.worst_conditions <= 1e-13, "{tally:?}");
        assert!(tally.both_solved + tally.both_none >= 3600, "{tally:?}");
        missed += tally.missed;
    }
    // The measured misses (all with a known slip); more would be a regression. (17 until
    // the enumeration took the proportional split of redundant sticking points: it now
    // solves 154 of the 198 problems only Lemke solved, and one more that Lemke misses.)
    assert!(missed <= 18, "Lemke missed {missed} solvable problems");
}

/// A random P-matrix of size `k`: `S + K` with `S = R Rᵀ / k + 0.1 I` symmetric positive
/// definite and `K` skew (`xᵀ(S + K)x = xᵀSx > 0`: positive definite, hence P).
fn p_matrix(rng: &mut Rng, k: usize) -> DMatrix<f64> {
    let r = DMatrix::from_fn(k, k, |_, _| rng.range(-1.0, 1.0));
    let g = DMatrix::from_fn(k, k, |_, _| rng.range(-1.0, 1.0));
    &r * r.transpose() / k as f64 + DMatrix::identity(k, k) * 0.1 + (&g - g.transpose()) * 0.5
}

/// The LCP's defining conditions on random P-matrix problems of 4 to 256 variables: a
/// P-matrix LCP has exactly one solution and Lemke's algorithm finds it [CPS, §3.3, §4.4],
/// so every run must end `Solved` with `z ≥ 0` (exactly: the solver clips rounding),
/// `w = M z + q ≥ 0` and `z_i w_i = 0`, to `1e-11` of the scale `max|q| + max|M| max|z|`:
/// the backward error of a pivoting solve is a few ulps times the growth of `B⁻¹` (here
/// measured ≤ 8.8e-16 up to 256 variables, at most 270 pivots), so 1e-11 leaves room for ill-conditioned bases
/// without hiding a wrong basis (which violates a sign by O(1)).
#[test]
fn lemke_solves_random_p_matrix_problems() {
    let mut rng = Rng(0x9a77_0015);
    let mut lemke = Lemke::new();
    for (k, cases) in [(4, 200), (16, 100), (64, 20), (256, 3)] {
        let (mut worst, mut most) = (0.0f64, 0);
        for _ in 0..cases {
            let m = p_matrix(&mut rng, k);
            let q = DVector::from_fn(k, |_, _| rng.range(-1.0, 1.0));
            let status = lemke.solve(&m, &q).expect("finite");
            let LemkeStatus::Solved { pivots } = status else {
                panic!("k = {k}: {status:?}");
            };
            most = most.max(pivots);
            let z = DVector::from_column_slice(lemke.z());
            let w = &m * &z + &q;
            let scale = q.amax() + m.amax() * z.amax();
            assert!(z.iter().all(|&v| v >= 0.0));
            for i in 0..k {
                let v = (-w[i]).max((z[i] * w[i]).abs() / z.amax().max(1e-300)) / scale;
                worst = worst.max(v);
            }
            assert!((&w - DVector::from_column_slice(lemke.w())).amax() <= 1e-12 * scale);
        }
        println!("P-matrix k = {k}: worst violation {worst:.1e}, most pivots {most}");
        assert!(worst <= 1e-11, "k = {k}: {worst:e}");
    }
}

/// 64 frictional contacts (256 LCP variables) with a regular `A` (`d = 160 > 128`) and
/// random `b`: the table's conditions hold on every solution.
#[test]
fn sixty_four_contacts_satisfy_the_table() {
    let mut rng = Rng(0x64c0_0015);
    let mut solver = Solver::new();
    for _ in 0..3 {
        let n = 64;
        let (a, b, mut allowed) = problem(&mut rng, n, 160, false);
        for c in &mut allowed {
            c.slip = None;
        }
        let sol = solver
            .solve(&a, &b, &allowed)
            .expect("a regular A: solvable");
        let v = lcp::conditions_violation(&a, &b, &allowed, &sol);
        let modes = |m: fn(&Mode) -> bool| sol.modes.iter().filter(|x| m(x)).count();
        println!(
            "64 contacts: {} pivots, violation {v:.1e}, open {} stick {} slide {}",
            solver.pivots(),
            modes(|m| *m == Mode::Open),
            modes(|m| *m == Mode::Stick),
            modes(|m| matches!(m, Mode::Slide(_)))
        );
        assert!(v <= 1e-11, "{v:e}");
    }
}

fn single(b: [f64; 2], a: [[f64; 2]; 2], allowed: Allowed) -> Result<lcp::Solution, LcpError> {
    Solver::new().solve(
        &DMatrix::from_row_slice(2, 2, &[a[0][0], a[0][1], a[1][0], a[1][1]]),
        &DVector::from_row_slice(&b),
        &[allowed],
    )
}

#[test]
fn a_particle_on_a_floor_sticks_when_pressed_and_slides_when_pushed_beyond_the_cone() {
    // Unit mass: A = I; gravity presses, b_n = −g.
    let (g, mu) = (9.81, 0.5);
    let free = Allowed {
        mu,
        open: true,
        slip: None,
    };
    let eye = [[1.0, 0.0], [0.0, 1.0]];
    let s = single([-g, 0.0], eye, free).unwrap();
    assert_eq!(s.modes, vec![Mode::Stick]);
    assert!((s.x[0] - g).abs() <= 1e-14 * g && s.x[1].abs() <= 1e-14 * g);
    // A push F = 2 μ g along +t: it slides along the push, friction −μ g, w_t = F − μ g.
    let f = 2.0 * mu * g;
    let s = single([-g, f], eye, free).unwrap();
    assert_eq!(s.modes, vec![Mode::Slide(1.0)]);
    assert!((s.x[0] - g).abs() <= 1e-14 * g);
    assert!((s.x[1] + mu * g).abs() <= 1e-14 * g);
    assert!((s.w[1] - (f - mu * g)).abs() <= 1e-14 * g);
    // Just inside the cone (F = 0.99 μ g): it sticks, x_t = −F.
    let s = single([-g, 0.99 * mu * g], eye, free).unwrap();
    assert_eq!(s.modes, vec![Mode::Stick]);
    assert!((s.x[1] + 0.99 * mu * g).abs() <= 1e-14 * g);
    // Pulled away: it opens.
    let s = single([1.0, 3.0], eye, free).unwrap();
    assert_eq!(s.modes, vec![Mode::Open]);
    assert_eq!(s.x, DVector::zeros(2));
}

/// Painlevé's rod: a rod (mass m, half-length l, at φ = 30° to the floor, at rest) whose
/// lower end slides with `s = −1` and `μ = 3`. Its end's `A = J M⁻¹ Jᵀ` with
/// `M = diag(m, m, m l²/3)`, `J_n = [0, 1, −l cos φ]`, `J_t = [1, 0, l sin φ]`:
/// `A_nn = (1 + 3 cos²φ)/m`, `A_nt = −3 sin φ cos φ / m`, and `h = A_nn − μ s A_nt
/// = (3.25 − 1.299 μ)/m < 0`. Pressed by gravity (`b_n = −g`) there is no solution; pulled
/// (`b_n > 0`) there are two (open, or slide with `x_n = −b_n/h`) and Lemke gives one.
#[test]
fn painleve_rod_has_no_solution_pressed_and_one_pulled() {
    let (m, phi, mu, g) = (1.0, 30f64.to_radians(), 3.0, 9.81);
    let (c, s) = (phi.cos(), phi.sin());
    let a = [
        [(1.0 + 3.0 * c * c) / m, -3.0 * s * c / m],
        [-3.0 * s * c / m, (1.0 + 3.0 * s * s) / m],
    ];
    let h = a[0][0] + mu * a[0][1];
    assert!(h < 0.0, "h = {h}");
    let sliding = Allowed {
        mu,
        open: true,
        slip: Some(-1.0),
    };
    let pressed = single([-g, 0.0], a, sliding);
    assert!(
        matches!(
            pressed,
            Err(LcpError::NoSolution {
                known_slip: true,
                ..
            })
        ),
        "{pressed:?}"
    );
    let am = DMatrix::from_row_slice(2, 2, &[a[0][0], a[0][1], a[1][0], a[1][1]]);
    assert!(
        lcp::solve(&am, &DVector::from_row_slice(&[-g, 0.0]), &[sliding])
            .all
            .is_empty()
    );
    let pulled = single([g, 0.0], a, sliding).unwrap();
    let all = lcp::solve(&am, &DVector::from_row_slice(&[g, 0.0]), &[sliding]).all;
    assert_eq!(all.len(), 2);
    assert!(all.iter().any(|e| (&e.w - &pulled.w).amax() <= 1e-12 * g));
}

/// A block (mass m, 2a × 2h) resting on its two lower corners on a slope of angle θ,
/// in the slope's frame (x downhill, y normal): corner i at `(∓a, −h)` from the centre,
/// `J_ni = [0, 1, ∓a]`, `J_ti = [1, 0, h]`, `M = diag(m, m, m (a² + h²)/3)`, gravity
/// `(m g sin θ, −m g cos θ, 0)`, so `b_n = −g cos θ`, `b_t = g sin θ` at both corners.
/// `A` (4 × 4) has rank 3: the split of the forces between the corners is statically
/// indeterminate when both stick.
fn block_on_slope(theta: f64) -> (DMatrix<f64>, DVector<f64>, f64) {
    let (m, a, h, g) = (2.0, 0.3, 0.2, 9.81);
    let inertia = m * (a * a + h * h) / 3.0;
    let j = DMatrix::from_row_slice(4, 3, &[0.0, 1.0, -a, 1.0, 0.0, h, 0.0, 1.0, a, 1.0, 0.0, h]);
    let m_inv =
        DMatrix::from_diagonal(&DVector::from_row_slice(&[1.0 / m, 1.0 / m, 1.0 / inertia]));
    let force = DVector::from_row_slice(&[m * g * theta.sin(), -m * g * theta.cos(), 0.0]);
    let a_mat = &j * &m_inv * j.transpose();
    let b = &j * (&m_inv * force);
    (a_mat, b, m * g)
}

#[test]
fn a_block_on_two_corners_sticks_on_a_slope_when_mu_reaches_tan_theta_and_slides_below() {
    let theta = 30f64.to_radians();
    let g = 9.81;
    for mu in [0.58, 0.6, 0.7, 0.81, 1.5] {
        // μ ≥ tan 30° = 0.577 holds the block, whatever the split (issue 15: ricochet found
        // no consistent mode for 0.58 ≤ μ ≤ 0.81).
        let (a, b, weight) = block_on_slope(theta);
        let allowed = [Allowed {
            mu,
            open: true,
            slip: None,
        }; 2];
        let s = Solver::new().solve(&a, &b, &allowed).unwrap();
        let enumerated = lcp::solve(&a, &b, &allowed).all.len();
        println!(
            "μ = {mu}: Lemke {:?} x = {:?}; the enumeration: {enumerated} solutions",
            s.modes,
            s.x.as_slice()
        );
        assert_eq!(s.modes, vec![Mode::Stick, Mode::Stick], "μ = {mu}");
        for i in 0..2 {
            assert!(s.x[2 * i] >= 0.0 && s.x[2 * i + 1].abs() <= mu * s.x[2 * i] * (1.0 + 1e-12));
        }
        assert!(s.w.amax() <= 1e-12 * g, "{:?}", s.w);
        // The forces balance the weight's components.
        let (n, t) = (s.x[0] + s.x[2], s.x[1] + s.x[3]);
        assert!(
            (n - weight * theta.cos()).abs() <= 1e-12 * weight,
            "Σ x_n = {n}"
        );
        assert!(
            (t + weight * theta.sin()).abs() <= 1e-12 * weight,
            "Σ x_t = {t}"
        );
    }
    for mu in [0.0, 0.3, 0.5, 0.57] {
        let (a, b, weight) = block_on_slope(theta);
        let allowed = [Allowed {
            mu,
            open: true,
            slip: None,
        }; 2];
        let s = Solver::new().solve(&a, &b, &allowed).unwrap();
        // Slides downhill without turning: both corners accelerate at g (sin θ − μ cos θ).
        let acc = g * (theta.sin() - mu * theta.cos());
        assert_eq!(s.modes, vec![Mode::Slide(1.0); 2], "μ = {mu}");
        for i in 0..2 {
            assert!(s.w[2 * i].abs() <= 1e-12 * g);
            assert!(
                (s.w[2 * i + 1] - acc).abs() <= 1e-12 * g,
                "w_t = {}",
                s.w[2 * i + 1]
            );
        }
        let n = s.x[0] + s.x[2];
        assert!(
            (n - weight * theta.cos()).abs() <= 1e-12 * weight,
            "Σ x_n = {n}"
        );
    }
}

#[test]
fn bad_input_gets_typed_errors() {
    let a = DMatrix::identity(2, 2);
    let free = Allowed {
        mu: 0.5,
        open: true,
        slip: None,
    };
    let mut s = Solver::new();
    assert!(matches!(
        s.solve(&a, &DVector::zeros(3), &[free]),
        Err(LcpError::Shape { .. })
    ));
    assert_eq!(
        s.solve(&a, &DVector::from_row_slice(&[f64::NAN, 0.0]), &[free]),
        Err(LcpError::NotFinite)
    );
    let neg = Allowed { mu: -1.0, ..free };
    assert!(matches!(
        s.solve(&a, &DVector::zeros(2), &[neg]),
        Err(LcpError::BadContact { contact: 0, .. })
    ));
    let closed = Allowed {
        open: false,
        ..free
    };
    assert_eq!(
        s.solve(&a, &DVector::zeros(2), &[closed]),
        Err(LcpError::MustStayClosed { contact: 0 })
    );
    // No contact at all: an empty solution.
    let s0 = s
        .solve(&DMatrix::zeros(0, 0), &DVector::zeros(0), &[])
        .unwrap();
    assert!(s0.modes.is_empty());
}

/// A problem dumped by the simulation (`DUMP A=[…]` column-major, `DUMP b=[…]`,
/// `DUMP mu=[…]`), every slip unknown, as the simultaneous impact poses it.
pub(crate) fn dumped(text: &str) -> (DMatrix<f64>, DVector<f64>, Vec<Allowed>) {
    let list = |key: &str| -> Vec<f64> {
        let line = text
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .unwrap_or_else(|| panic!("no {key}"));
        let inner = line.trim().trim_start_matches('[').trim_end_matches(']');
        inner
            .split(',')
            .map(|v| v.trim().parse().expect("a number"))
            .collect()
    };
    let (a, b, mu) = (list("DUMP A="), list("DUMP b="), list("DUMP mu="));
    let n = mu.len();
    assert_eq!((a.len(), b.len()), (4 * n * n, 2 * n));
    let allowed = mu
        .iter()
        .map(|&mu| Allowed {
            mu,
            open: true,
            slip: None,
        })
        .collect();
    (
        DMatrix::from_column_slice(2 * n, 2 * n, &a),
        DVector::from_vec(b),
        allowed,
    )
}

/// The 32-link chain falling on the floor (issue 15) stopped at t = 0.734 s on these
/// simultaneous impacts: 6 and 8 contact points, `A = W` positive semidefinite and rank
/// deficient (two capsule ends at one hinge: equal normal rows), `b_n ~ 1e-14` for the
/// points at rest, every slip unknown. Lemke's path ended on a ray after 25 pivots, which
/// Anitescu and Potra's theorem excludes (module `lcp::friction`): now solved, and the
/// solution satisfies the table's conditions to rounding. The 16-link chain's 11-point
/// impact at t = 0.9196 s (`tests/all/sim_persistent.rs`'s run) ended `Inaccurate` (1.4e-2:
/// a pivot on a rounding zero, `lcp::lemke::CANCEL_TOL`). Two impacts of the 32-link chain
/// that stopped it later (t = 0.5644 s and 1.1228 s, 28 and 29 points): a ray along the
/// covering vector d = 1 after 67 pivots, and the pivot limit along it; both solved along
/// the next covering vector (`lcp::RETRIES`).
#[test]
fn the_chain_of_32_links_on_the_floor_is_solved() {
    for (name, text, tol) in [
        (
            "6 contacts",
            include_str!("../data/lcp/chain32_6_contacts.txt"),
            1e-12,
        ),
        (
            "8 contacts",
            include_str!("../data/lcp/chain32_8_contacts.txt"),
            1e-12,
        ),
        (
            "16 links, 11 contacts",
            include_str!("../data/lcp/chain16_11_contacts.txt"),
            1e-12,
        ),
        (
            "28 contacts",
            include_str!("../data/lcp/chain32_28_contacts.txt"),
            1e-12,
        ),
        // Lemke's path along d = 1 reaches its pivot limit (5,800) on this one; the path
        // along the first other covering vector ends in 103 pivots, with four points
        // approaching at b_n ≈ −7e-12 m/s (relative 2.8e-10) left open: met to the
        // solver's check, lcp::CHECK_TOL, not to 1e-12.
        (
            "29 contacts",
            include_str!("../data/lcp/chain32_29_contacts_pivots.txt"),
            lcp::CHECK_TOL,
        ),
    ] {
        let (a, b, allowed) = dumped(text);
        let mut solver = Solver::new();
        let sol = solver
            .solve(&a, &b, &allowed)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let v = lcp::conditions_violation(&a, &b, &allowed, &sol);
        println!(
            "chain of 32 links, {name}: {} pivots, violation {v:.1e}, modes {:?}",
            solver.pivots(),
            sol.modes
        );
        assert!(v <= tol, "{name}: {v:e}");
        // A second method: Lemke's w is one of the enumeration's (9 solutions on the
        // 6 contacts; 4⁸ systems are too many for the 8).
        if allowed.len() <= lcp::MAX_ENUMERATED {
            let all = lcp::solve(&a, &b, &allowed).all;
            let scale = b.amax() + a.amax() * sol.x.amax();
            let d = (all.iter())
                .map(|s| (&s.w - &sol.w).amax() / scale)
                .fold(f64::INFINITY, f64::min);
            println!(
                "{name}: {} solutions enumerated, Lemke's w within {d:.1e}",
                all.len()
            );
            assert!(d <= W_TOL, "{name}: {d:e} from the enumeration's {all:?}");
        }
    }
}

/// A velocity-level problem of `n` contacts shaped like the chain on the floor: `A = J M⁻¹
/// Jᵀ` (`d` degrees of freedom, `n ≤ d < 2n`: rank deficient), where one contact in three
/// duplicates its neighbour's normal row (two points at one place; its tangent row the
/// neighbour's plus `1e-3` of noise: the capsule ends' offsets), most points at rest
/// (`b_n = 0` exactly), one in five approaching (`b_n ∈ [−1, −0.1]`, the same for a
/// duplicate), `b_t` uniform in [−1, 1], `μ` uniform in [0, 1], every slip unknown.
///
/// There is a velocity `u` that lifts every point off (`J_n u = 1`, `J_t u = 0`: the rows
/// are projected so): then `Jᵀ y = 0` with `y` in the friction cones forces
/// `uᵀJᵀy = Σ x_n = 0`, so `y = 0`, and by Anitescu–Potra's argument (module
/// `lcp::friction`) Lemke's path cannot end on a ray, whatever `b`.
fn resting_problem(rng: &mut Rng, n: usize) -> (DMatrix<f64>, DVector<f64>, Vec<Allowed>) {
    let d = n + rng.pick(n);
    let mut u = DVector::from_fn(d, |_, _| rng.range(-1.0, 1.0));
    u.normalize_mut();
    let r = DMatrix::from_fn(d, d, |_, _| rng.range(-1.0, 1.0));
    let m = &r * r.transpose() + DMatrix::identity(d, d) * 0.1;
    let mut j = DMatrix::from_fn(2 * n, d, |_, _| rng.range(-1.0, 1.0));
    let mut b = DVector::zeros(2 * n);
    let mut duplicate = false;
    for i in 0..n {
        // The previous contact's normal row (and b_n), one time in three.
        if i > 0 && !duplicate && rng.pick(3) == 0 {
            duplicate = true;
            let (normal, tangent) = (j.row(2 * i - 2).into_owned(), j.row(2 * i - 1).into_owned());
            j.row_mut(2 * i).copy_from(&normal);
            j.row_mut(2 * i + 1).copy_from(&tangent);
            for k in 0..d {
                j[(2 * i + 1, k)] += 1e-3 * rng.range(-1.0, 1.0);
            }
            b[2 * i] = b[2 * i - 2];
        } else {
            duplicate = false;
            let s = 1.0 - j.row(2 * i).dot(&u.transpose());
            for k in 0..d {
                j[(2 * i, k)] += s * u[k];
            }
            if rng.pick(5) == 0 {
                b[2 * i] = rng.range(-1.0, -0.1);
            }
        }
        let s = -j.row(2 * i + 1).dot(&u.transpose());
        for k in 0..d {
            j[(2 * i + 1, k)] += s * u[k];
        }
        b[2 * i + 1] = rng.range(-1.0, 1.0);
    }
    let a = &j * m.try_inverse().expect("SPD") * j.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let allowed = (0..n)
        .map(|_| Allowed {
            mu: rng.range(0.0, 1.0),
            open: true,
            slip: None,
        })
        .collect();
    (a, b, allowed)
}

/// Lemke's solver on 600 problems of `resting_problem` (2 to 32 contacts, up to 128 LCP
/// variables): no ray (the theorem excludes them: every slip unknown and a lifting
/// velocity), no other error, and every solution satisfies the table to rounding.
/// Before (ff31938): 1 ray (the refinement at every pivot and the `z₀ ≈ 0` test of
/// `lcp::lemke` removed it) and 9 `Inaccurate` errors with violations 0.02–0.55 (every
/// point open, `x = 0` exactly, but the degenerate basis left `x ~ 1e-17`, which the open
/// test relative to `max|x|` alone took for forces; fixed in `lcp::friction`'s modes).
#[test]
fn no_ray_on_resting_chains_with_unknown_slips() {
    let mut rng = Rng(0x1e3e_c4a1);
    let mut solver = Solver::new();
    let (mut rays, mut errors, mut worst, mut most) = (0, 0, 0.0f64, 0);
    for case in 0..600 {
        let n = 2 + case % 31;
        let (a, b, allowed) = resting_problem(&mut rng, n);
        match solver.solve(&a, &b, &allowed) {
            Ok(sol) => {
                worst = worst.max(lcp::conditions_violation(&a, &b, &allowed, &sol));
                most = most.max(solver.pivots());
            }
            Err(LcpError::NoSolution { .. }) => rays += 1,
            Err(e) => {
                errors += 1;
                println!("case {case}, {n} contacts: {e}");
            }
        }
    }
    println!(
        "resting chains: {rays} rays, {errors} other errors, worst violation {worst:.1e}, \
         most pivots {most}"
    );
    assert_eq!(rays, 0, "rays");
    assert_eq!(errors, 0, "other errors");
    assert!(worst <= 1e-12, "{worst:e}");
}
