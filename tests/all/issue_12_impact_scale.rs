//! Issue 12, item 5: the impact laws were not scale-invariant. Stronge's law gained energy
//! at W ≈ 1e-299 (`Δ = m_nn m_tt − m_nt²` underflowed to 0, so W was taken for singular,
//! and `V²` underflowed in the works), Poisson's failed beyond a scale of about 1e±200
//! (`Δ` overflowed), and Stronge called a singular W "incoherent", so that
//! `ricochet regions --w 1,1,1` failed.
//!
//! The laws are homogeneous. If `(I, v^S)` solves `(W, v^A, e, μ)`, then for `s, c > 0`,
//! `((c/s) I, c v^S)` solves `(s W, c v^A, e, μ)`:
//! - Eqs. (22)–(23), `v^S − v^A = W I`: `c v^S − c v^A = (s W)((c/s) I)`;
//! - Coulomb's cone and the directions of the phases (`dI_t = ∓μ dI_n`,
//!   `dI_t = −(m_nt/m_tt) dI_n`) are linear in `I` and invariant under `W → s W`;
//! - Newton's end condition `v_n^S = −e v_n^A` is linear in the velocities; Poisson's
//!   `I_n = (1 + e) I_c` linear in the impulses; Stronge's works `∫ v_n dI_n` scale by
//!   `c · c/s` on both sides of `W_r = −e² W_c`.
//!
//! So the works and `ΔE` scale by `c²/s`, g, h, p, q by `s`, and α, the type and the sign
//! case do not change. With `s = 2^a`, `c = 2^b` every product by them is exact in binary
//! floating point, so the relation holds bit for bit wherever the answer is a normal
//! double, and the answer must be an error exactly where it overflows (or where `I_n > 0`
//! rounds to 0). Checked here for
//! `a, b ∈ [−1000, 1000]` on random problems of every law, with the reproducers.

use proptest::prelude::*;
use ricochet::impact::{
    self, ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem, Law, Outcome,
};
use ricochet::regions::{Axis, Cell, MapSpec, RegionMap};

/// `x · 2^k` for `|k| ≤ 2046`, in two exact steps (so that no intermediate overflows
/// while the result does not).
fn times_pow2(x: f64, k: i32) -> f64 {
    let half = k / 2;
    x * 2f64.powi(half) * 2f64.powi(k - half)
}

/// A positive semidefinite W: `R diag(λ1, λ2) Rᵀ` with `λ1 ∈ [1e-3, 1e3]` and
/// `λ2 = 0` (singular) or up to 1e6 times `λ1`; or diagonal.
fn psd() -> impl Strategy<Value = ImpactMatrix> {
    let rotated = (
        -3.0..3.0f64,
        prop_oneof![1 => Just(None), 6 => (0.0..6.0f64).prop_map(Some)],
        0.0..std::f64::consts::PI,
    )
        .prop_map(|(l1, k, th)| {
            let l1 = 10f64.powf(l1);
            let l2 = k.map_or(0.0, |k| l1 * 10f64.powf(k));
            let (c, s) = (th.cos(), th.sin());
            ImpactMatrix::new(
                c * c * l1 + s * s * l2,
                c * s * (l1 - l2),
                s * s * l1 + c * c * l2,
            )
        });
    let diagonal = (-3.0..3.0f64, -3.0..3.0f64)
        .prop_map(|(a, b)| ImpactMatrix::new(10f64.powf(a), 0.0, 10f64.powf(b)));
    prop_oneof![4 => rotated, 1 => diagonal]
}

fn problem() -> impl Strategy<Value = ImpactProblem> {
    let vn = (-3.0..2.0f64).prop_map(|x| -(10f64.powf(x)));
    let vt = prop_oneof![1 => Just(0.0), 8 => -100.0..100.0f64];
    let e = prop_oneof![1 => Just(0.0), 1 => Just(1.0), 6 => 0.0..=1.0f64];
    let mu = prop_oneof![1 => Just(0.0), 6 => 0.0..3.0f64];
    (psd(), vn, vt, e, mu)
        .prop_map(|(w, vn, vt, e, mu)| ImpactProblem::new(w, ContactVelocity::new(vn, vt), e, mu))
}

fn law() -> impl Strategy<Value = Law> {
    prop_oneof![
        Just(Law::Newton),
        Just(Law::KaneLevinson),
        Just(Law::Poisson),
        Just(Law::Stronge)
    ]
}

/// `pb` with `W → 2^a W`, `v^A → 2^b v^A`.
fn scaled(pb: &ImpactProblem, a: i32, b: i32) -> ImpactProblem {
    let w = &pb.w;
    ImpactProblem::new(
        ImpactMatrix::new(
            times_pow2(w.nn, a),
            times_pow2(w.nt, a),
            times_pow2(w.tt, a),
        ),
        ContactVelocity::new(times_pow2(pb.v_a.n, b), times_pow2(pb.v_a.t, b)),
        pb.e,
        pb.mu,
    )
}

/// The numbers of an outcome with the power of two each scales by (`a` for W, `b` for
/// the velocities): impulses `b − a`, velocities `b`, works `2b − a`, g, h, p, q `a`.
fn scaled_numbers(out: &Outcome, a: i32, b: i32) -> Vec<(&'static str, f64, i32)> {
    let (i, v, w) = (b - a, b, 2 * b - a);
    let c = &out.coefficients;
    let mut numbers = vec![
        ("I_n", out.impulse.n, i),
        ("I_t", out.impulse.t, i),
        ("v_n^S", out.v_s.n, v),
        ("v_t^S", out.v_s.t, v),
        ("ΔE", out.delta_e, w),
        ("work_n", out.work_n, w),
        ("work_t", out.work_t, w),
        ("g", c.g, a),
        ("h", c.h, a),
        ("p", c.p, a),
        ("q", c.q, a),
        ("α", c.alpha(), 0),
    ];
    for phase in out.phases.iter() {
        let end = phase.end;
        numbers.extend([
            ("phase I_n", end.i.n, i),
            ("phase I_t", end.i.t, i),
            ("phase v_n", end.v.n, v),
            ("phase v_t", end.v.t, v),
            ("phase work_n", end.work_n, w),
            ("phase work_t", end.work_t, w),
        ]);
    }
    numbers
}

/// The scale relation of the module doc between the outcome of `pb` and that of `pb`
/// scaled by `2^a`, `2^b`.
fn check_scaling(law: Law, pb: &ImpactProblem, a: i32, b: i32) -> Result<(), TestCaseError> {
    let big_pb = scaled(pb, a, b);
    // The scaled data must be the data times 2^a, 2^b exactly: normal doubles (or 0).
    let exact = |x: f64| x == 0.0 || x.is_normal();
    let (w, v) = (&big_pb.w, big_pb.v_a);
    prop_assume!([w.nn, w.nt, w.tt, v.n, v.t].into_iter().all(exact));
    let base = impact::solve(law, pb);
    let big = impact::solve(law, &big_pb);
    let out = match (&base, &big) {
        (Err(e0), Err(e1)) => {
            prop_assert_eq!(
                std::mem::discriminant(e0),
                std::mem::discriminant(e1),
                "{} then {}",
                e0,
                e1
            );
            return Ok(());
        }
        (Err(e0), Ok(_)) => {
            return Err(TestCaseError::fail(format!(
                "{law}: {pb:?} fails ({e0}) but not scaled by 2^{a}, 2^{b}"
            )));
        }
        (Ok(out), _) => out,
    };
    let expected: Vec<_> = (scaled_numbers(out, a, b).into_iter())
        .map(|(what, x, k)| (what, times_pow2(x, k)))
        .collect();
    // Beyond the range: a number overflows, or the impulse I_n > 0 rounds to 0.
    let i_n_lost = out.impulse.n > 0.0 && expected[0].1 == 0.0;
    let overflows = (expected.iter())
        .find(|(_, x)| !x.is_finite())
        .or(i_n_lost.then_some(&expected[0]));
    match (&big, overflows) {
        (Err(ImpactError::OutOfRange { .. }), Some(_)) => Ok(()),
        (Err(e), _) => Err(TestCaseError::fail(format!(
            "{law}: {pb:?} scaled by 2^{a}, 2^{b}: {e} (expected {expected:?})"
        ))),
        (Ok(_), Some((what, x))) => Err(TestCaseError::fail(format!(
            "{law}: {pb:?} scaled by 2^{a}, 2^{b}: {what} = {x} is not an error"
        ))),
        (Ok(got), None) => {
            prop_assert_eq!((got.kind, got.case), (out.kind, out.case));
            prop_assert_eq!(got.phases.len(), out.phases.len());
            let got = scaled_numbers(got, 0, 0);
            for ((what, x), (_, y, _)) in expected.iter().zip(&got) {
                if x.abs() >= f64::MIN_POSITIVE {
                    prop_assert!(
                        x.to_bits() == y.to_bits(),
                        "{} {:?} scaled by 2^{}, 2^{}: {} = {:e}, expected {:e}",
                        law,
                        pb,
                        a,
                        b,
                        what,
                        y,
                        x
                    );
                } else {
                    // Subnormal: each side rounded once or twice.
                    prop_assert!(
                        (x - y).abs() <= 2.0 * 2f64.powi(-1074) * 2f64.powi(0),
                        "{} {:?}: {} = {:e}, expected {:e}",
                        law,
                        pb,
                        what,
                        y,
                        x
                    );
                }
            }
            Ok(())
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The scale relation over the whole exponent range.
    #[test]
    fn the_laws_are_scale_invariant(
        law in law(),
        pb in problem(),
        a in -1000..=1000i32,
        b in -1000..=1000i32,
    ) {
        check_scaling(law, &pb, a, b)?;
    }

    /// The same near the ends of the range, where Δ = m_nn m_tt − m_nt² and V² overflow or
    /// underflow.
    #[test]
    fn the_laws_are_scale_invariant_at_the_ends_of_the_range(
        law in law(),
        pb in problem(),
        a in prop_oneof![-1000..=-900i32, 900..=1000i32],
        b in prop_oneof![-1000..=-900i32, 900..=1000i32],
    ) {
        check_scaling(law, &pb, a, b)?;
    }
}

/// The reproducer of `impact_stronge_tiny_w.jsonl`: Stronge's law gained energy
/// (ΔE = +3.2e-72 J with I_n = 5.6e113). It is the problem at W ≈ 1, v ≈ 1 scaled down
/// by powers of two.
#[test]
fn stronge_at_a_tiny_w_does_not_gain_energy() {
    let pb = ImpactProblem::new(
        ImpactMatrix::new(1.9983262030429345e-299, 0.0, 1.150198828981508e-301),
        ContactVelocity::new(-6.479938767407679e-201, 2.6483847459816043e-200),
        0.44092176413714235,
        0.0,
    );
    let out = impact::solve(Law::Stronge, &pb).unwrap();
    assert!(out.delta_e <= 0.0, "ΔE = {}", out.delta_e);
    // μ = 0, m_nt = 0: a frictionless direct impact, I_n = (1 + e) V / m_nn (Stronge's
    // restitution work e² times the compression work gives v_n^S = e V).
    let (v, m) = (-pb.v_a.n, pb.w.nn);
    let i_n = (1.0 + pb.e) * v / m;
    assert!(
        (out.impulse.n - i_n).abs() <= 1e-14 * i_n,
        "{} vs {i_n}",
        out.impulse.n
    );
    let de = 0.5 * out.impulse.n * (out.v_s.n + pb.v_a.n);
    assert!((out.delta_e - de).abs() <= 1e-14 * de.abs());
    check_scaling(Law::Stronge, &pb, 1000, 1000).unwrap();
}

/// The second line of `impact_incoherent.jsonl`: Poisson's law at W = 1e200 was
/// "incoherent" (Δ overflowed). Its answer is 1e-200 times that at W = 1.
#[test]
fn poisson_at_a_huge_w() {
    let v = ContactVelocity::new(-1.0, -0.04);
    let at = |s: f64| {
        impact::solve(
            Law::Poisson,
            &ImpactProblem::new(ImpactMatrix::new(s, 0.0, s), v, 0.5, 0.03),
        )
        .unwrap()
    };
    let (big, one) = (at(1e200), at(1.0));
    for (x, y) in [
        (big.impulse.n, one.impulse.n),
        (big.impulse.t, one.impulse.t),
        (big.delta_e, one.delta_e),
    ] {
        assert!((x * 1e200 - y).abs() <= 1e-14 * y.abs(), "{x} vs {y}");
    }
    for (x, y) in [(big.v_s.n, one.v_s.n), (big.v_s.t, one.v_s.t)] {
        assert!((x - y).abs() <= 1e-14, "{x} vs {y}");
    }
}

/// The first line of `impact_incoherent.jsonl`: a singular W (rank 1) where friction
/// holds the contact once its normal velocity is 0 (`p = 0`): Stronge's restitution can do
/// no work, no finite impulse ends the collision, a jam (as for Newton), not an
/// "incoherent" solution.
#[test]
fn stronge_jams_on_a_singular_w() {
    let pb = ImpactProblem::new(
        ImpactMatrix::new(1.0, 1.0, 1.0),
        ContactVelocity::new(-1.0, -1.0),
        0.5,
        1.0,
    );
    for law in [Law::Stronge, Law::Newton] {
        let err = impact::solve(law, &pb).unwrap_err();
        assert!(matches!(err, ImpactError::Jam { .. }), "{law}: {err}");
    }
}

/// `ricochet regions --w 1,1,1`: every law maps the singular W, the jams as their own
/// cells (drawn grey).
#[test]
fn regions_map_a_singular_w() {
    for law in Law::ALL {
        let spec = MapSpec {
            w: ImpactMatrix::new(1.0, 1.0, 1.0),
            e: 0.5,
            law,
            alpha: Axis::new(-4.0, 4.0, 41),
            mu: Axis::new(0.0, 1.0, 41),
        };
        let map = RegionMap::compute(&spec).unwrap_or_else(|e| panic!("{law}: {e}"));
        let jams = (0..41)
            .flat_map(|j| (0..41).map(move |i| (i, j)))
            .filter(|&(i, j)| map.cell(i, j) == Cell::Jam)
            .count();
        println!("{law}: {jams} jammed cells of 1681");
    }
}
