//! The impact laws against their defining equations: property tests over random
//! positive definite W (condition numbers up to 1e6), approach velocities, e and μ, and
//! the edge cases (direct impact, grazing, μ = 0, e = 0, e = 1, m_nt = 0, α on a type
//! boundary, bad input).
//!
//! Every expected value here is derived in this file from Eqs. (22)–(23), Coulomb's law
//! and the end condition of each law, by small linear solves: never from the closed
//! forms of `src/impact/`.

use nalgebra::{Matrix2, Vector2};
use proptest::prelude::*;
use ricochet::impact::{
    self, CollisionType, ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem, Law, Outcome,
};

// ---------------------------------------------------------------------------------------
// Generators

/// A random symmetric positive definite W = R diag(λ1, λ2) Rᵀ with λ1 ∈ [1e-3, 1e3] and
/// condition number up to 1e6.
fn spd() -> impl Strategy<Value = ImpactMatrix> {
    (-3.0..3.0f64, 0.0..6.0f64, 0.0..std::f64::consts::PI).prop_map(|(l1, k, th)| {
        let (l1, l2) = (10f64.powf(l1), 10f64.powf(l1 + k));
        let (c, s) = (th.cos(), th.sin());
        ImpactMatrix::new(
            c * c * l1 + s * s * l2,
            c * s * (l1 - l2),
            s * s * l1 + c * c * l2,
        )
    })
}

fn approach() -> impl Strategy<Value = ContactVelocity> {
    let vn = (-3.0..2.0f64).prop_map(|x| -(10f64.powf(x)));
    let vt = prop_oneof![
        1 => Just(0.0),
        8 => (-3.0..2.0f64, any::<bool>()).prop_map(|(x, neg)| if neg { -(10f64.powf(x)) } else { 10f64.powf(x) }),
    ];
    (vn, vt).prop_map(|(n, t)| ContactVelocity::new(n, t))
}

fn restitution() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 1 => Just(1.0), 6 => 0.0..=1.0f64]
}

fn friction() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 6 => 0.0..3.0f64]
}

fn problem() -> impl Strategy<Value = ImpactProblem> {
    (spd(), approach(), restitution(), friction())
        .prop_map(|(w, v, e, mu)| ImpactProblem::new(w, v, e, mu))
}

fn law() -> impl Strategy<Value = Law> {
    prop_oneof![
        Just(Law::Newton),
        Just(Law::KaneLevinson),
        Just(Law::Poisson),
        Just(Law::Stronge)
    ]
}

// ---------------------------------------------------------------------------------------
// Independent helpers

fn wmat(w: &ImpactMatrix) -> Matrix2<f64> {
    Matrix2::new(w.nn, w.nt, w.nt, w.tt)
}

/// Scale of velocities in a solution, for relative tolerances (m/s).
fn vscale(pb: &ImpactProblem, out: &Outcome) -> f64 {
    let w = &pb.w;
    let i = out.impulse;
    pb.v_a.n.abs()
        + pb.v_a.t.abs()
        + (w.nn * i.n).abs()
        + (w.nt * i.t).abs()
        + (w.nt * i.n).abs()
        + (w.tt * i.t).abs()
}

/// Residuals of Eqs. (22)–(23) at a point: v − v^A − W I.
fn momentum_residual(pb: &ImpactProblem, i: Vector2<f64>, v: Vector2<f64>) -> Vector2<f64> {
    v - Vector2::new(pb.v_a.n, pb.v_a.t) - wmat(&pb.w) * i
}

/// The problem in the paper's frame (v_t^A ≥ 0), as the test sees it: m_nt and v_t mirrored.
fn paper_frame(pb: &ImpactProblem) -> (Matrix2<f64>, f64, f64, bool) {
    let flip = pb.v_a.t < 0.0;
    let s = if flip { -1.0 } else { 1.0 };
    let w = Matrix2::new(pb.w.nn, s * pb.w.nt, s * pb.w.nt, pb.w.tt);
    (w, -pb.v_a.n, s * pb.v_a.t, flip)
}

/// A candidate solution derived here: type, impulses (paper's frame), and its coherence.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    kind: CollisionType,
    i: Vector2<f64>,
    coherent: bool,
    /// Distance of the coherence conditions from their boundaries, relative.
    margin: f64,
}

/// Newton's three types with the bisection of the collision time, each derived from the
/// type's definition [P, Eqs. (46), (48), (51)] by linear solves of Eqs. (22)–(23).
fn newton_candidates(pb: &ImpactProblem) -> [Candidate; 3] {
    let (w, big_v, vt, _) = paper_frame(pb);
    let (e, mu) = (pb.e, pb.mu);
    let target = Vector2::new((1.0 + e) * big_v, -vt); // W I = v^S − v^A with v^S = (eV, 0)
    let scale = big_v + vt;
    // Forward sliding throughout: I_t = −μ I_n, v_n^S = eV.
    let d_fwd = w[(0, 0)] - mu * w[(0, 1)];
    let i_n = (1.0 + e) * big_v / d_fwd;
    let i = Vector2::new(i_n, -mu * i_n);
    let v_ts = vt + (w * i)[1];
    let forward = Candidate {
        kind: CollisionType::ForwardSliding,
        i,
        coherent: d_fwd > 0.0 && v_ts >= 0.0,
        margin: (v_ts / scale).abs().min((d_fwd / w[(0, 0)]).abs()),
    };
    // Phase 1 up to G: I' = s (1, −μ) with v_t^A + (W I')_t = 0.
    let slip_rate = mu * w[(1, 1)] - w[(0, 1)]; // −dv_t/dI_n while sliding forward
    let s = if vt == 0.0 { 0.0 } else { vt / slip_rate };
    let i1 = Vector2::new(s, -mu * s);
    let g_reached = vt == 0.0 || slip_rate > 0.0;
    // Sticking after G: the total impulse solves W I = ((1+e)V, −v_t^A).
    let i = w.lu().solve(&target).unwrap();
    let i2 = i - i1;
    let cone = mu * i2[0] - i2[1].abs();
    let sticking = Candidate {
        kind: CollisionType::Sticking,
        i,
        coherent: g_reached && i2[0] > 0.0 && cone >= 0.0,
        margin: (cone / (i2[0].abs() + i2[1].abs() + 1e-300))
            .abs()
            .min(i2[0].abs() / (i.norm() + 1e-300)),
    };
    // Reverse sliding after G: I'' = r (1, μ), v_n^S = eV.
    let d_rev = w[(0, 0)] + mu * w[(0, 1)];
    let r = ((1.0 + e) * big_v - (w * i1)[0]) / d_rev;
    let i = i1 + Vector2::new(r, mu * r);
    let v_ts = vt + (w * i)[1];
    let reverse = Candidate {
        kind: CollisionType::ReverseSliding,
        i,
        coherent: g_reached && r > 0.0 && v_ts < 0.0,
        margin: (v_ts / scale).abs().min((r / (i.norm() + 1e-300)).abs()),
    };
    [sticking, reverse, forward]
}

/// Kane and Levinson's three single-phase candidates [P, Appendix C], derived here.
fn kane_levinson_candidates(pb: &ImpactProblem) -> [Candidate; 3] {
    let (w, big_v, vt, _) = paper_frame(pb);
    let (e, mu) = (pb.e, pb.mu);
    let scale = big_v + vt;
    let i = w.lu().solve(&Vector2::new((1.0 + e) * big_v, -vt)).unwrap();
    let cone = mu * i[0] - i[1].abs();
    let sticking = Candidate {
        kind: CollisionType::Sticking,
        i,
        coherent: i[0] > 0.0 && cone >= 0.0,
        margin: (cone / (i.norm() + 1e-300)).abs(),
    };
    let mk = |kind, sign: f64| {
        let d = w[(0, 0)] + sign * mu * w[(0, 1)];
        let i_n = (1.0 + e) * big_v / d;
        let i = Vector2::new(i_n, sign * mu * i_n);
        let v_ts = vt + (w * i)[1];
        let ok_sign = if sign > 0.0 { v_ts < 0.0 } else { v_ts >= 0.0 };
        Candidate {
            kind,
            i,
            coherent: d > 0.0 && ok_sign,
            margin: (v_ts / scale).abs().min((d / w[(0, 0)]).abs()),
        }
    };
    [
        sticking,
        mk(CollisionType::ReverseSliding, 1.0),
        mk(CollisionType::ForwardSliding, -1.0),
    ]
}

/// The normal velocity along the reported phases as a function of I_n, and the works of
/// the normal impulse during compression (v_n < 0) and restitution, by exact quadrature
/// of the piecewise-linear v_n(I_n).
fn compression_split(out: &Outcome) -> (f64, f64, f64) {
    let (mut i_c, mut w_c, mut w_r) = (f64::NAN, 0.0, 0.0);
    for ph in out.phases.iter() {
        let (a, b) = (ph.start, ph.end);
        let dx = b.i.n - a.i.n;
        if a.v.n < 0.0 && b.v.n > 0.0 {
            let f = -a.v.n / (b.v.n - a.v.n);
            i_c = a.i.n + f * dx;
            w_c += 0.5 * a.v.n * f * dx;
            w_r += 0.5 * b.v.n * (1.0 - f) * dx;
        } else if b.v.n <= 0.0 {
            // Still compressing at the end of this phase (e = 0 ends here, v_n ≈ 0).
            w_c += 0.5 * (a.v.n + b.v.n) * dx;
            i_c = b.i.n;
        } else {
            w_r += 0.5 * (a.v.n + b.v.n) * dx;
        }
    }
    (i_c, w_c, w_r)
}

// ---------------------------------------------------------------------------------------
// Properties

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// Eqs. (22)–(23) hold for the returned impulses, at the end and at every phase end
    /// point; the phases obey Coulomb's law; |I_t| ≤ μ I_n.
    #[test]
    fn momentum_relations_and_coulomb_hold(pb in problem(), law in law()) {
        let out = impact::solve(law, &pb).unwrap();
        let tol = 1e-9 * vscale(&pb, &out);
        let res = momentum_residual(&pb, Vector2::new(out.impulse.n, out.impulse.t), Vector2::new(out.v_s.n, out.v_s.t));
        prop_assert!(res.norm() <= tol, "residual {res:?} > {tol}");
        prop_assert!(out.impulse.n > 0.0);
        prop_assert!(out.impulse.t.abs() <= pb.mu * out.impulse.n * (1.0 + 1e-12), "{:?}", out.impulse);
        let sgn = if out.mirrored { -1.0 } else { 1.0 };
        for ph in out.phases.iter() {
            for p in [ph.start, ph.end] {
                let r = momentum_residual(&pb, Vector2::new(p.i.n, p.i.t), Vector2::new(p.v.n, p.v.t));
                prop_assert!(r.norm() <= tol, "phase point residual {r:?}");
            }
            let (di_n, di_t) = (ph.end.i.n - ph.start.i.n, sgn * (ph.end.i.t - ph.start.i.t));
            prop_assert!(di_n >= 0.0);
            let slip = |v: f64| sgn * v;
            match (law, ph.kind) {
                (Law::KaneLevinson, _) => {}
                (_, CollisionType::ForwardSliding) => {
                    prop_assert!((di_t + pb.mu * di_n).abs() <= 1e-12 * (di_n + di_t.abs()) + 1e-300);
                    prop_assert!(slip(ph.start.v.t) >= -tol && slip(ph.end.v.t) >= -tol);
                }
                (_, CollisionType::Sticking) => {
                    prop_assert!(di_t.abs() <= pb.mu * di_n * (1.0 + 1e-9) + 1e-12 * tol);
                    prop_assert!(ph.start.v.t.abs() <= tol && ph.end.v.t.abs() <= tol);
                }
                (_, CollisionType::ReverseSliding) => {
                    prop_assert!((di_t - pb.mu * di_n).abs() <= 1e-12 * (di_n + di_t.abs()) + 1e-300);
                    prop_assert!(slip(ph.start.v.t) <= tol && slip(ph.end.v.t) <= tol);
                }
            }
        }
        // The type names the slip at the end.
        let vts = sgn * out.v_s.t;
        match out.kind {
            CollisionType::Sticking => prop_assert!(vts.abs() <= tol),
            CollisionType::ForwardSliding => prop_assert!(vts >= -tol),
            CollisionType::ReverseSliding => prop_assert!(vts <= tol),
        }
    }

    /// Each law's normal end condition: Newton and Kane–Levinson `v_n^S = −e v_n^A` [P,
    /// Eq. (30)]; Poisson `I_n = (1+e) I_c`; Stronge `W_restitution = −e² W_compression`.
    #[test]
    fn normal_end_condition_holds(pb in problem(), law in law()) {
        let out = impact::solve(law, &pb).unwrap();
        let tol = 1e-9 * vscale(&pb, &out);
        let big_v = -pb.v_a.n;
        match law {
            Law::Newton | Law::KaneLevinson => prop_assert!((out.v_s.n - pb.e * big_v).abs() <= tol),
            Law::Poisson => {
                let (i_c, _, _) = compression_split(&out);
                prop_assert!((out.impulse.n - (1.0 + pb.e) * i_c).abs() <= 1e-9 * out.impulse.n, "I_n {} I_c {i_c}", out.impulse.n);
            }
            Law::Stronge => {
                let (_, w_c, w_r) = compression_split(&out);
                prop_assert!(w_c < 0.0);
                prop_assert!((w_r + pb.e * pb.e * w_c).abs() <= 1e-8 * w_c.abs(), "W_c {w_c} W_r {w_r}");
            }
        }
    }

    /// Exactly one type is coherent (away from the boundaries), and it is the one
    /// returned, with the same impulses: Newton with bisection [P, Table 1] and
    /// Kane–Levinson [P, Appendix C, Comment h], both derived here from their definitions.
    #[test]
    fn exactly_one_coherent_type(pb in problem()) {
        for (law, cands) in [(Law::Newton, newton_candidates(&pb)), (Law::KaneLevinson, kane_levinson_candidates(&pb))] {
            if cands.iter().any(|c| c.margin < 1e-7) {
                continue; // too close to a boundary for the counting to be meaningful
            }
            let coherent: Vec<_> = cands.iter().filter(|c| c.coherent).collect();
            prop_assert_eq!(coherent.len(), 1, "{:?}: {:?}", law, cands);
            let out = impact::solve(law, &pb).unwrap();
            prop_assert_eq!(out.kind, coherent[0].kind);
            let s = if out.mirrored { -1.0 } else { 1.0 };
            let got = Vector2::new(out.impulse.n, s * out.impulse.t);
            prop_assert!((got - coherent[0].i).norm() <= 1e-7 * coherent[0].i.norm(), "{got:?} vs {:?}", coherent[0].i);
        }
    }

    /// ΔE is Eq. (29), the works sum to it, Poisson and Stronge never create energy, and
    /// forward sliding never creates energy under any law [P, Eq. (67)].
    #[test]
    fn energy_bookkeeping(pb in problem(), law in law()) {
        let out = impact::solve(law, &pb).unwrap();
        let (i, va, vs) = (out.impulse, pb.v_a, out.v_s);
        let eq29 = 0.5 * i.n * (vs.n + va.n) + 0.5 * i.t * (vs.t + va.t);
        let escale = (i.n.abs() + i.t.abs()) * vscale(&pb, &out);
        prop_assert!((out.delta_e - eq29).abs() <= 1e-12 * escale);
        prop_assert!((out.work_n + out.work_t - out.delta_e).abs() <= 1e-9 * escale,
            "W_n + W_t = {} vs ΔE = {}", out.work_n + out.work_t, out.delta_e);
        // The kinetic energy change from W: ΔE = v^A·I + ½ Iᵀ W I (path independent).
        let iv = Vector2::new(i.n, i.t);
        let de = Vector2::new(va.n, va.t).dot(&iv) + 0.5 * iv.dot(&(wmat(&pb.w) * iv));
        prop_assert!((de - out.delta_e).abs() <= 1e-9 * escale);
        prop_assert!(out.work_t <= 1e-12 * escale || law == Law::KaneLevinson, "friction does work {}", out.work_t);
        if matches!(law, Law::Poisson | Law::Stronge) || out.kind == CollisionType::ForwardSliding {
            prop_assert!(out.delta_e <= 1e-9 * escale, "{law:?} {:?} ΔE = {}", out.kind, out.delta_e);
        }
    }

    /// The impulses are continuous in α across every type boundary [P, Comment a]: along
    /// a sweep of v_t^A the type changes are bisected and both sides compared.
    #[test]
    fn impulses_continuous_across_type_boundaries(w in spd(), e in restitution(), mu in 0.01..3.0f64, law in law()) {
        let solve = |vt: f64| impact::solve(law, &ImpactProblem::new(w, ContactVelocity::new(-1.0, vt), e, mu)).unwrap();
        let mut prev = (0.0, solve(0.0));
        for k in 0..=60 {
            let vt = 10f64.powf(-4.0 + 0.15 * k as f64) * (w.nn / w.tt).sqrt();
            let cur = solve(vt);
            if cur.kind != prev.1.kind {
                let (mut a, mut b) = (prev.0, vt);
                for _ in 0..200 {
                    let m = 0.5 * (a + b);
                    if m <= a || m >= b { break; }
                    if solve(m).kind == prev.1.kind { a = m } else { b = m }
                }
                let (ia, ib) = (solve(a).impulse, solve(b).impulse);
                let size = ia.n.abs() + ia.t.abs();
                prop_assert!((ia.n - ib.n).abs() + (ia.t - ib.t).abs() <= 1e-6 * size,
                    "{law:?} jump at v_t = {a}: {ia:?} vs {ib:?}");
            }
            prev = (vt, cur);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Edge cases

fn solve(law: Law, w: (f64, f64, f64), v: (f64, f64), e: f64, mu: f64) -> Outcome {
    let pb = ImpactProblem::new(
        ImpactMatrix::new(w.0, w.1, w.2),
        ContactVelocity::new(v.0, v.1),
        e,
        mu,
    );
    impact::solve(law, &pb).unwrap()
}

#[test]
fn newton_energy_gain_exists_and_only_when_sticking_or_reversing() {
    // Table 2, lower row 5 is one; a denser witness: scan α in Case 1 with e = 1, where
    // [P, Sect. 4.3] gives ΔE_max = ½ V² m_nt² / (m_nn Δ) at α = −m_nt/m_nn.
    let w = (1.0, -0.5, 1.0);
    let (nn, nt, tt) = w;
    let det = nn * tt - nt * nt;
    let out = solve(Law::Newton, w, (-1.0, -nt / nn), 1.0, 2.0);
    assert_eq!(out.kind, CollisionType::Sticking);
    assert!(
        (out.delta_e - 0.5 * nt * nt / (nn * det)).abs() < 1e-14,
        "ΔE = {}",
        out.delta_e
    );
    assert!(out.delta_e > 0.0);
    // Over a grid of inputs, gains occur, and never for forward sliding.
    let (mut gains, mut by_kind) = (0, std::collections::HashSet::new());
    for k in 0..40 {
        for m in 0..40 {
            for law in [Law::Newton, Law::KaneLevinson] {
                let vt = 0.05 * k as f64;
                let mu = 0.05 * m as f64;
                let out = solve(law, (0.3365, -0.5071, 0.8134), (-0.2684, vt), 0.9, mu);
                if out.delta_e > 0.0 {
                    gains += 1;
                    by_kind.insert(out.kind);
                    assert_ne!(out.kind, CollisionType::ForwardSliding);
                }
            }
        }
    }
    assert!(gains > 0);
    assert!(
        by_kind.contains(&CollisionType::Sticking)
            && by_kind.contains(&CollisionType::ReverseSliding)
    );
}

#[test]
fn direct_impact_is_continuous_from_both_sides() {
    // v_t^A = 0: the tangent is arbitrary; both orientations must give the same impulse,
    // and the limits v_t^A → 0± must agree with it. Cases 1 (stick) and 3/5 (slide).
    for w in [(1.0, 0.2, 2.0), (0.3365, -0.5071, 0.8134), (1.0, 0.9, 1.0)] {
        for law in Law::ALL {
            for mu in [0.0, 0.2, 0.5, 2.0] {
                let at0 = solve(law, w, (-1.0, 0.0), 0.6, mu);
                for vt in [1e-10, -1e-10] {
                    let near = solve(law, w, (-1.0, vt), 0.6, mu);
                    let d = (near.impulse.n - at0.impulse.n).abs()
                        + (near.impulse.t - at0.impulse.t).abs();
                    assert!(
                        d < 1e-8,
                        "{law:?} w {w:?} μ {mu} v_t {vt}: {:?} vs {:?}",
                        near.impulse,
                        at0.impulse
                    );
                }
            }
        }
    }
    // Sticking direct impact in closed form (derived from W I = ((1+e)V, 0)):
    // I_n = (1+e) m_tt V / Δ, I_t = −(1+e) m_nt V / Δ.
    let (nn, nt, tt) = (1.0, 0.2, 2.0);
    let det = nn * tt - nt * nt;
    let out = solve(Law::Newton, (nn, nt, tt), (-1.0, 0.0), 0.6, 0.5);
    assert_eq!(out.kind, CollisionType::Sticking);
    assert!(
        (out.impulse.n - 1.6 * tt / det).abs() < 1e-15
            && (out.impulse.t + 1.6 * nt / det).abs() < 1e-15
    );
}

#[test]
fn grazing_limits() {
    // v_n^A → 0⁻ with v_t^A fixed. Where the slip goes on to the end (Cases 1–3, 5), the
    // impulses vanish like V; in Case 4 (h < 0) Newton sticks with the finite limit
    // I_n → m_nt v_t^A / Δ, I_t → −m_nn v_t^A / Δ (from W I = (0, −v_t^A)).
    let vt = 1.0;
    for law in Law::ALL {
        let mut prev = f64::INFINITY;
        for k in 3..=12 {
            let out = solve(law, (1.0, 0.2, 2.0), (-(10f64.powi(-k)), vt), 0.7, 0.3);
            assert_eq!(out.kind, CollisionType::ForwardSliding);
            assert!(out.impulse.n < prev && out.impulse.n < 10.0 * 10f64.powi(-k));
            prev = out.impulse.n;
        }
    }
    let (nn, nt, tt, mu) = (1.0, 1.5, 3.0, 1.0); // h = nn − μ nt = −0.5 < 0
    let det = nn * tt - nt * nt;
    for law in [Law::Newton, Law::KaneLevinson] {
        let out = solve(law, (nn, nt, tt), (-1e-12, vt), 0.7, mu);
        assert_eq!(out.case.number(), 4);
        assert_eq!(out.kind, CollisionType::Sticking);
        assert!(
            (out.impulse.n - nt * vt / det).abs() < 1e-9,
            "{:?}",
            out.impulse
        );
        assert!((out.impulse.t + nn * vt / det).abs() < 1e-9);
    }
}

#[test]
fn frictionless_laws_reduce_to_the_normal_impulse() {
    // μ = 0 [P, Comment b]: I_t = 0 and I_n = (1+e) V / m_nn for every law (with μ = 0,
    // v_n is linear in I_n, so Poisson and Stronge coincide with Newton), and
    // ΔE = −½ (1 − e²) V² / m_nn.
    for law in Law::ALL {
        for &(w, vt) in &[
            ((1.0, 0.3, 2.0), 0.7),
            ((1.0, -0.3, 2.0), 0.7),
            ((2.0, 0.0, 1.0), -1.0),
        ] {
            let (e, v) = (0.4, 1.3);
            let out = solve(law, w, (-v, vt), e, 0.0);
            assert_eq!(out.impulse.t, 0.0);
            assert!((out.impulse.n - (1.0 + e) * v / w.0).abs() < 1e-14);
            assert!((out.delta_e + 0.5 * (1.0 - e * e) * v * v / w.0).abs() < 1e-14);
        }
    }
}

#[test]
fn perfectly_plastic_and_elastic_ends() {
    let w = (0.3365, -0.5071, 0.8134);
    // e = 0: v_n^S = 0; Newton, Poisson and Stronge all end where compression ends.
    let outs: Vec<_> = [Law::Newton, Law::Poisson, Law::Stronge]
        .iter()
        .map(|&l| solve(l, w, (-0.2684, 0.5343), 0.0, 0.5))
        .collect();
    for o in &outs {
        assert!(o.v_s.n.abs() < 1e-15);
        assert!(
            (o.impulse.n - outs[0].impulse.n).abs() < 1e-14
                && (o.impulse.t - outs[0].impulse.t).abs() < 1e-14
        );
    }
    // e = 1: Newton restores the normal speed; Stronge's normal impulse does no work.
    let n = solve(Law::Newton, w, (-0.2684, 0.5343), 1.0, 0.5);
    assert!((n.v_s.n - 0.2684).abs() < 1e-15);
    let s = solve(Law::Stronge, w, (-0.2684, 0.5343), 1.0, 0.5);
    assert!(s.work_n.abs() < 1e-15, "W_n = {}", s.work_n);
}

#[test]
fn balanced_collision_makes_all_laws_agree() {
    // m_nt = 0 [P, Comment e]: only Case 1; v_n grows at the same rate m_nn in every
    // phase, so the four laws coincide, and ΔE < 0 (ΔE = 0 only for an elastic direct
    // impact, e = 1 and v_t^A = 0, where nothing slips).
    for vt in [0.0, 0.1, 0.5, 2.0, 10.0] {
        for e in [0.0, 0.5, 1.0] {
            let outs: Vec<_> = Law::ALL
                .iter()
                .map(|&l| solve(l, (2.0, 0.0, 3.0), (-1.0, vt), e, 0.4))
                .collect();
            for o in &outs {
                assert_eq!(o.case.number(), 1);
                assert!(
                    (o.impulse.n - outs[0].impulse.n).abs() < 1e-14
                        && (o.impulse.t - outs[0].impulse.t).abs() < 1e-14
                );
                if e == 1.0 && vt == 0.0 {
                    assert!(o.delta_e.abs() < 1e-15);
                } else {
                    assert!(o.delta_e < 0.0, "e {e} v_t {vt}: ΔE = {}", o.delta_e);
                }
            }
        }
    }
}

#[test]
fn alpha_exactly_on_the_boundary() {
    // Case 1: W = (2, −1, 2), μ = 1 → g = h = 3, r_m = 1; e = 0.5 → α = 1.5 is the boundary,
    // exactly representable: h v_t^A = (1+e) g V = 4.5. Newton gives forward sliding with
    // v_t^S = 0, equal to the sticking solution I_n = 0.5, I_t = −0.5.
    let at = solve(Law::Newton, (2.0, -1.0, 2.0), (-1.0, 1.5), 0.5, 1.0);
    assert_eq!(at.kind, CollisionType::ForwardSliding);
    assert_eq!((at.impulse.n, at.impulse.t, at.v_s.t), (0.5, -0.5, 0.0));
    let below = solve(Law::Newton, (2.0, -1.0, 2.0), (-1.0, 1.5 - 1e-12), 0.5, 1.0);
    assert_eq!(below.kind, CollisionType::Sticking);
    assert!((below.impulse.n - 0.5).abs() < 1e-11);
    // Kane–Levinson's other boundary, α = −(1+e) r_p, Case 3: W = (2, −1, 1), μ = 0.5 →
    // p = −0.5, q = 1.5; e = 0.5 → α = 0.5: sticking on it and above, reverse below.
    let at = solve(Law::KaneLevinson, (2.0, -1.0, 1.0), (-1.0, 0.5), 0.5, 0.5);
    assert_eq!(at.kind, CollisionType::Sticking);
    let below = solve(
        Law::KaneLevinson,
        (2.0, -1.0, 1.0),
        (-1.0, 0.5 - 1e-12),
        0.5,
        0.5,
    );
    assert_eq!(below.kind, CollisionType::ReverseSliding);
    assert!(
        (at.impulse.n - below.impulse.n).abs() < 1e-11
            && (at.impulse.t - below.impulse.t).abs() < 1e-11
    );
}

#[test]
fn caller_frame_is_kept_when_vt_is_negative() {
    // Mirroring t is a change of frame: the physical result must be the mirror image.
    for law in Law::ALL {
        let a = solve(law, (0.3365, -0.5071, 0.8134), (-0.2684, 0.5343), 0.5, 0.2);
        let b = solve(law, (0.3365, 0.5071, 0.8134), (-0.2684, -0.5343), 0.5, 0.2);
        assert!(b.mirrored && !a.mirrored);
        assert_eq!(
            (a.impulse.n, a.impulse.t, a.v_s.n, a.v_s.t),
            (b.impulse.n, -b.impulse.t, b.v_s.n, -b.v_s.t)
        );
        assert_eq!((a.kind, a.case, a.delta_e), (b.kind, b.case, b.delta_e));
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let ok = ImpactProblem::new(
        ImpactMatrix::new(1.0, 0.1, 1.0),
        ContactVelocity::new(-1.0, 0.5),
        0.5,
        0.3,
    );
    assert!(impact::solve(Law::Newton, &ok).is_ok());
    type IsError = fn(&ImpactError) -> bool;
    let cases: Vec<(ImpactProblem, IsError)> = vec![
        (
            ImpactProblem {
                w: ImpactMatrix::new(1.0, 1.0, 0.99),
                ..ok
            },
            |e| matches!(e, ImpactError::NotPositiveDefinite { .. }),
        ),
        (
            ImpactProblem {
                w: ImpactMatrix::new(1.0, 2.0, 1.0),
                ..ok
            },
            |e| matches!(e, ImpactError::NotPositiveDefinite { .. }),
        ),
        (
            ImpactProblem {
                w: ImpactMatrix::new(-1.0, 0.0, -1.0),
                ..ok
            },
            |e| matches!(e, ImpactError::NotPositiveDefinite { .. }),
        ),
        (
            ImpactProblem {
                w: ImpactMatrix::new(0.0, 0.0, 1.0),
                ..ok
            },
            |e| matches!(e, ImpactError::NotPositiveDefinite { .. }),
        ),
        (
            ImpactProblem {
                w: ImpactMatrix::new(1.0, 0.0, -1e-9),
                ..ok
            },
            |e| matches!(e, ImpactError::NotPositiveDefinite { .. }),
        ),
        (
            ImpactProblem {
                v_a: ContactVelocity::new(0.0, 0.5),
                ..ok
            },
            |e| matches!(e, ImpactError::NotApproaching { .. }),
        ),
        (
            ImpactProblem {
                v_a: ContactVelocity::new(0.3, 0.5),
                ..ok
            },
            |e| matches!(e, ImpactError::NotApproaching { .. }),
        ),
        (ImpactProblem { e: 1.01, ..ok }, |e| {
            matches!(e, ImpactError::RestitutionOutOfRange { .. })
        }),
        (ImpactProblem { e: -0.01, ..ok }, |e| {
            matches!(e, ImpactError::RestitutionOutOfRange { .. })
        }),
        (ImpactProblem { mu: -0.1, ..ok }, |e| {
            matches!(e, ImpactError::NegativeFriction { .. })
        }),
    ];
    for (pb, is) in cases {
        for law in Law::ALL {
            let err = impact::solve(law, &pb).unwrap_err();
            assert!(is(&err), "{pb:?}: {err}");
        }
    }
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let fields: [ImpactProblem; 7] = [
            ImpactProblem {
                w: ImpactMatrix { nn: bad, ..ok.w },
                ..ok
            },
            ImpactProblem {
                w: ImpactMatrix { nt: bad, ..ok.w },
                ..ok
            },
            ImpactProblem {
                w: ImpactMatrix { tt: bad, ..ok.w },
                ..ok
            },
            ImpactProblem {
                v_a: ContactVelocity::new(bad, 0.5),
                ..ok
            },
            ImpactProblem {
                v_a: ContactVelocity::new(-1.0, bad),
                ..ok
            },
            ImpactProblem { e: bad, ..ok },
            ImpactProblem { mu: bad, ..ok },
        ];
        for pb in fields {
            let err = impact::solve(Law::Stronge, &pb).unwrap_err();
            assert!(matches!(err, ImpactError::NonFinite { .. }), "{err}");
            assert!(err.to_string().contains("not finite"));
        }
    }
}

// ---------------------------------------------------------------------------------------
// Singular W (the extension beyond [P, Eq. (24)], Δ = 0)

/// A singular W: rank 1, `m_tt [[k², k], [k, 1]]` (the contact velocity moves along a
/// line, as for a one-degree-of-freedom system), or `m_tt = m_nt = 0` (no tangential
/// mobility, as for a ball on a vertical slide).
fn singular() -> impl Strategy<Value = ImpactMatrix> {
    prop_oneof![
        3 => (-3.0..3.0f64, -2.0..2.0f64, any::<bool>()).prop_map(|(tt, k, neg)| {
            let tt = 10f64.powf(tt);
            let k = if neg { -(10f64.powf(k)) } else { 10f64.powf(k) };
            ImpactMatrix::new(tt * k * k, tt * k, tt)
        }),
        1 => (-3.0..3.0f64).prop_map(|nn| ImpactMatrix::new(10f64.powf(nn), 0.0, 0.0)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// With a singular W every law either solves the impact, satisfying Eqs. (22)–(23),
    /// Coulomb and its end condition, or reports a jam, and only where friction can hold
    /// the contact (`m_tt > 0`, `|m_nt| ≤ μ m_tt`: sticking is feasible and freezes v_n).
    #[test]
    fn singular_w_solves_or_jams(w in singular(), v in approach(), e in restitution(), mu in friction(), law in law()) {
        let v = if w.tt == 0.0 { ContactVelocity::new(v.n, 0.0) } else { v };
        let pb = ImpactProblem::new(w, v, e, mu);
        match impact::solve(law, &pb) {
            Ok(out) => {
                let tol = 1e-9 * vscale(&pb, &out);
                let res = momentum_residual(&pb, Vector2::new(out.impulse.n, out.impulse.t), Vector2::new(out.v_s.n, out.v_s.t));
                prop_assert!(res.norm() <= tol, "residual {res:?}");
                prop_assert!(out.impulse.t.abs() <= pb.mu * out.impulse.n * (1.0 + 1e-12));
                if matches!(law, Law::Newton | Law::KaneLevinson) {
                    prop_assert!((out.v_s.n - pb.e * -pb.v_a.n).abs() <= tol);
                }
                let escale = (out.impulse.n + out.impulse.t.abs()) * vscale(&pb, &out);
                prop_assert!((out.work_n + out.work_t - out.delta_e).abs() <= 1e-9 * escale);
                if w.tt == 0.0 {
                    prop_assert_eq!(out.impulse.t, 0.0);
                    // v_n is linear in I_n, so every law gives Newton's jump (1 + e) V.
                    prop_assert!((out.impulse.n * w.nn - (1.0 + pb.e) * -pb.v_a.n).abs() <= tol);
                }
            }
            Err(ImpactError::Jam { .. }) => {
                prop_assert!(w.tt > 0.0 && w.nt.abs() <= mu * w.tt * (1.0 + 1e-12), "jam without a holding cone: {w:?} μ {mu}");
            }
            Err(other) => prop_assert!(false, "{other}"),
        }
    }
}

#[test]
fn one_degree_of_freedom_pendulum_impact() {
    // A rank-1 W as a pendulum gives it: J_n = a, J_t = b (1×1), M = m:
    // W = [[a², ab], [ab, b²]] / m. With μ |a/b| < 1 (Case 3), Newton's reverse sliding and
    // forward sliding closed forms hold without Δ; the impact reverses the one speed u with
    // Δu = (a I_n + b I_t)/m, and v_n^S = e V means a (u + Δu) = −e a u.
    let (a, b, m) = (1.0, -0.05, 1.2);
    let w = ImpactMatrix::new(a * a / m, a * b / m, b * b / m);
    assert!(w.is_singular());
    let u = -2.0; // the contact approaches: v_n = a u < 0
    let v = ContactVelocity::new(a * u, -(b * u)); // t oriented so that v_t ≥ 0
    let w = ImpactMatrix::new(w.nn, -w.nt, w.tt);
    for law in Law::ALL {
        let out = impact::solve(law, &ImpactProblem::new(w, v, 0.7, 0.2)).unwrap();
        let du = (a * out.impulse.n - b * out.impulse.t) / m;
        if matches!(law, Law::Newton | Law::KaneLevinson) {
            assert!(
                (a * (u + du) + 0.7 * a * u).abs() < 1e-12,
                "{law:?}: u⁺ = {}",
                u + du
            );
        }
        // The energy change of the pendulum equals Eq. (29).
        let de = 0.5 * m * ((u + du).powi(2) - u * u);
        assert!(
            (de - out.delta_e).abs() < 1e-12,
            "{law:?}: {de} vs {}",
            out.delta_e
        );
    }
}

/// A singular `W` with `μ = m_nn/m_nt` (here `W = [[¼, ½], [½, 1]]`, `μ = ½`) has
/// `g = μ m_tt − m_nt = 0` and `h = m_nn − μ m_nt = 0`: on Routh's path neither forward
/// sliding (`dv_n/dI_n = h`) nor sticking (`Δ/m_tt`) raises `v_n`, so every law jams,
/// with or without tangential approach. (Newton's law divided by `h = 0` in Eq. (52) and
/// reported an incoherent `I_n = ∞`; found by the `ricochet regions` map over the row
/// `μ = m_nn/m_nt`.)
#[test]
fn singular_w_with_g_and_h_zero_jams_under_every_law() {
    let w = ImpactMatrix::new(0.25, 0.5, 1.0);
    assert_eq!(w.det(), 0.0);
    for v_t in [0.0, 0.3] {
        for law in [Law::Newton, Law::KaneLevinson, Law::Poisson, Law::Stronge] {
            let (mu, v_a) = (0.5, ContactVelocity::new(-1.0, v_t));
            // g and h of Eq. (35).
            assert_eq!((mu * w.tt - w.nt, w.nn - mu * w.nt), (0.0, 0.0));
            let pb = ImpactProblem::new(w, v_a, 0.5, mu);
            match impact::solve(law, &pb) {
                Err(ImpactError::Jam { .. }) => {}
                other => panic!("{law:?}, v_t = {v_t}: expected a jam, got {other:?}"),
            }
        }
    }
}
