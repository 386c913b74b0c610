//! The unit tests of `impact::scale` (`src/impact/scale.rs`).

// The source module's own imports.
use ricochet::impact::coefficients::Coefficients;
use ricochet::impact::problem::{ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem};
use ricochet::math::Real;

use ricochet::impact::scale::*;
use ricochet::impact::{
    Law, apply, energy_change, is_clearly_coherent, paper_frame, solve_at_order_one,
};

/// The one pass of [`solve`](ricochet::impact::solve) (the law at order one, then a
/// product by each power of two, [`Factors::outcome`]) gives the general path's answer
/// ([`solve_at_order_one`], then [`ldexp`] after [`beyond_range`]) bit for bit, and
/// declines, beyond the general path's errors and the scales beyond `2^±340`, less
/// than once in a thousand. Random problems over the whole range of scales
/// (`W = L Lᵀ`, singular one time in seven), every law.
#[test]
fn one_pass_is_the_general_path() {
    let mut rnd = crate::unit::uniform_numbers(0x2545_F491_4F6C_DD1D);
    let one_pass = |law: Law, pb: &ImpactProblem| {
        let (f, unit) = pb.at_moderate_scale()?;
        assert_eq!(Ok(unit), pb.at_order_one().map(|(_, unit)| unit));
        // The mirror folded into the powers of two: the same bits (Debug tells −0
        // from 0), declined only where v_t^A · 2^-b underflows.
        let Some((_, folded, folded_mirrored)) = pb.at_moderate_scale_in_paper_frame() else {
            assert!(unit.v_a.t == 0.0 && pb.v_a.t != 0.0, "{pb:?}");
            return None;
        };
        let (pb, mirrored) = paper_frame(&unit);
        assert_eq!(
            format!("{:?}", (folded, folded_mirrored)),
            format!("{:?}", (pb, mirrored))
        );
        let c = Coefficients::new(&pb.w, pb.mu, pb.v_a);
        let case = c.sign_case();
        let sol = apply(law, &pb, &c, case);
        let delta_e = energy_change(sol.impulse, pb.v_a, sol.v_s);
        if sol.failure.is_some() || !is_clearly_coherent(&pb, &sol) {
            return None;
        }
        (f.keep_in_range(&sol, delta_e)).then(|| f.outcome(law, case, &c, &sol, delta_e, mirrored))
    };
    let (mut in_place, mut declined, mut errors, mut needless) = (0, 0, 0, 0);
    for k in 0..20_000 {
        let far = |r: Real| pow2((r * 2000.0 - 1000.0) as i32);
        let s = if k % 4 == 0 {
            far(rnd())
        } else {
            rnd() * 8.0 + 0.1
        };
        let c = if k % 4 == 1 {
            far(rnd())
        } else {
            rnd() * 8.0 + 0.1
        };
        let (a, b, d) = (rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd());
        let d = if k % 7 == 0 { 0.0 } else { d };
        let w = ImpactMatrix::new(s * a * a, s * a * b, s * (b * b + d * d));
        let v_a = ContactVelocity::new(-c * (rnd() + 1e-3), c * (rnd() * 2.0 - 1.0));
        let pb = ImpactProblem::new(w, v_a, rnd(), rnd() * 2.0);
        let Ok((scale, unit)) = pb.at_order_one() else {
            continue;
        };
        for law in Law::ALL {
            let Ok(out) = solve_at_order_one(law, &unit) else {
                assert_eq!(one_pass(law, &pb), None);
                continue;
            };
            let general = scale.up(out);
            if let Some(fast) = one_pass(law, &pb) {
                in_place += 1;
                // Debug prints every double exactly (and −0 apart from 0).
                assert_eq!(
                    format!("{general:?}"),
                    format!("{:?}", Ok::<_, ImpactError>(fast))
                );
            } else {
                // Declined: extreme scales, an error of the general path, or (rarely)
                // a solution not clearly coherent or near the range's limit.
                declined += 1;
                let beyond_moderate = pb.at_moderate_scale().is_none();
                errors += usize::from(general.is_err());
                needless += usize::from(general.is_ok() && !beyond_moderate);
            }
        }
    }
    assert!(in_place > 40_000, "{in_place}");
    assert!(errors > 100 && declined > errors, "{declined} {errors}");
    assert!(needless * 1000 < in_place, "{needless} of {in_place}");

    // I_n > 0 that the one pass brings to 0 while its scales are moderate:
    // W ≈ 2^340, v_t^A = 2^-340, v_n^A = −2^-740 (I_n ≈ 2^-400 · 2^-680 at order one).
    let w = ImpactMatrix::new(pow2(340), pow2(337), pow2(340));
    let pb = ImpactProblem::new(w, ContactVelocity::new(-pow2(-740), pow2(-340)), 0.5, 0.3);
    let (scale, unit) = pb.at_order_one().unwrap();
    assert!(pb.at_moderate_scale().is_some());
    for law in Law::ALL {
        let out = solve_at_order_one(law, &unit).unwrap();
        assert!(out.impulse.n > 0.0);
        assert_eq!(one_pass(law, &pb), None, "{law}");
        assert!(
            matches!(
                scale.up(out),
                Err(ImpactError::OutOfRange { what: "I_n", .. })
            ),
            "{law}"
        );
    }
}

/// `v_t^A < 0` whose scaled number underflows to −0: the problem at order one is not
/// mirrored (its `v_t^A` is not negative), so the one pass, which decides the mirror
/// on the caller's `v_t^A`, declines it, and `solve` gives the general path's answer.
#[test]
fn an_underflowing_tangential_velocity_is_not_mirrored() {
    let w = ImpactMatrix::new(1.0, 0.2, 2.0);
    let pb = ImpactProblem::new(w, ContactVelocity::new(-pow2(100), -1e-320), 0.5, 0.3);
    let (scale, unit) = pb.at_order_one().unwrap();
    assert_eq!(unit.v_a.t.to_bits(), (-0.0 as Real).to_bits());
    assert!(pb.at_moderate_scale().is_some());
    assert!(pb.at_moderate_scale_in_paper_frame().is_none());
    for law in Law::ALL {
        let general = scale.up(solve_at_order_one(law, &unit).unwrap());
        let out = ricochet::impact::solve(law, &pb);
        assert!(!out.as_ref().unwrap().mirrored, "{law}");
        assert_eq!(format!("{out:?}"), format!("{general:?}"), "{law}");
    }
}

#[test]
fn exponent_and_ldexp_are_exact() {
    for (x, k) in [
        (1.0, 0),
        (1.5, 0),
        (2.0, 1),
        (0.75, -1),
        (Real::MAX, 1023),
        (Real::MIN_POSITIVE, -1022),
        (5e-324, -1074),
        (-3e-310, -1029),
    ] {
        assert_eq!(exponent(x), k, "{x}");
        let m = ldexp(x, -k);
        assert!((1.0..2.0).contains(&m.abs()), "{x} → {m}");
        assert_eq!(ldexp(m, k), x, "{x}");
    }
    assert_eq!(ldexp(1.0, 1024), Real::INFINITY);
    assert_eq!(ldexp(1.0, -1074), 5e-324);
    assert_eq!(ldexp(1.0, -1076), 0.0);
    assert_eq!(ldexp(1.5, -2000), 0.0);
    assert_eq!(ldexp(1.5, 2000), Real::INFINITY);
    assert_eq!(ldexp(ldexp(1.5, 1000), -2000), ldexp(1.5, -1000));
}

/// A subnormal entry of `W` in the caller's data, left subnormal at order one: its
/// `I_n` overflows there and the laws fail. That is the data's scales, not a bug of the
/// law (`ricochet impact` said "incoherent … I_n = inf" for this line of a fuzz run).
/// The other lines of that run that failed so, each law's, with their failure.
#[test]
fn a_subnormal_entry_is_beyond_the_precision_of_doubles() {
    let pb = ImpactProblem::new(
        ImpactMatrix::new(5e-324, 2.6074255549412655e-227, 0.7331219096757096),
        ContactVelocity::new(-2.5636740263993447e224, 3.548460286730535e83),
        2.4421318579176934e-258,
        1e-300,
    );
    for law in Law::ALL {
        match ricochet::impact::solve(law, &pb) {
            Err(ImpactError::IllConditioned { why, .. }) => {
                assert!(
                    why.starts_with("m_nn = 5e-324 is more than"),
                    "{law}: {why}"
                )
            }
            other => panic!("{law}: {other:?}"),
        }
    }
    // (W, v^A, e, μ, the laws that said "incoherent"): entries of W or v^A 2^511 to
    // 2^1000 times smaller than the largest of their kind, all normal doubles.
    let n = Law::Newton;
    let (kl, s) = (Law::KaneLevinson, Law::Stronge);
    type Case<'a> = ([Real; 3], [Real; 2], Real, Real, &'a [Law]);
    let cases: [Case<'_>; 7] = [
        (
            [1e-300, 1.0912652478146486e-150, 1.2764985112186802],
            [-1e-300, -2.836251404990221e-230],
            1e-300,
            0.0,
            &[n],
        ),
        (
            [
                2.1842429464248966e-252,
                -1.3856853741779596e-140,
                9.643760599220835e-29,
            ],
            [-4.568938637465665e110, 1.4187973825886904e-99],
            0.0,
            1e-300,
            &[n],
        ),
        (
            [3e-308, 1.543166671095174e-154, 1.1337195545293361],
            [-3.689761663477451e95, -963064.9485314045],
            1.0,
            1e-12,
            &[n, kl, s],
        ),
        (
            [3e-308, 3.7e-300, 1.4151059552086736e-139],
            [-3.517042291331083e-12, -1e-200],
            0.0,
            0.0,
            &[n],
        ),
        (
            [
                1.6061773811227796e307,
                2.262955760800605e153,
                0.49227304648181347,
            ],
            [-5.645823590128225e-122, -4.0866660558594084e135],
            0.5,
            1e300,
            &[kl, s],
        ),
        // Stronge's phase-by-phase march said "restitution work never reached"; its
        // closed form (stop 31) solves it (v_n^S = −e v_n^A, work_n = 0 at e = 1).
        (
            [
                1.027463552207789e-285,
                1.7213246192259076e-143,
                1.1481830682434242,
            ],
            [-1.0336514846813672e-236, -4.970568423889004e-36],
            1.0,
            1e-300,
            &[],
        ),
        // μ m_nt ≈ 3e-396 at order one: underflows.
        (
            [2e-320, 2.8137707659243152e-288, 1.7013493255848718e-192],
            [-8.956875141956504e-223, -2.068760905660855e-199],
            0.5,
            1e-300,
            &[n],
        ),
    ];
    for (w, v, e, mu, failed) in cases {
        let pb = ImpactProblem::new(
            ImpactMatrix::new(w[0], w[1], w[2]),
            ContactVelocity::new(v[0], v[1]),
            e,
            mu,
        );
        for law in Law::ALL {
            // The laws that solved, or failed otherwise (`OutOfRange`), still may.
            match ricochet::impact::solve(law, &pb) {
                Err(ImpactError::IllConditioned { .. }) => {}
                Err(ImpactError::Incoherent { .. }) => panic!("{law} {pb:?}: incoherent"),
                other => assert!(!failed.contains(&law), "{law} {pb:?}: {other:?}"),
            }
        }
    }
}
