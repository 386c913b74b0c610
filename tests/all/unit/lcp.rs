//! The unit tests of `lcp` (`src/lcp/mod.rs`).

// The source module's own imports.
use ricochet::lcp::friction::Solver;
use ricochet::math::Real;

use nalgebra::{DMatrix, DVector};
use ricochet::lcp::*;

/// [`solutions_into`] on storage reused from earlier calls — of other sizes, with
/// more or fewer solutions, `out` still holding them — gives the solutions of a fresh
/// [`solutions`] (a new solver), bit for bit (modes, `x`, `w`), or the same error, on
/// 4,000 random problems of 1 to 5 contacts (`A = Yᵀ Y` of full or deficient rank,
/// slips known or not, points that may not open): the enumeration, and Lemke's
/// algorithm beyond four contacts or where the enumeration finds none. Solved again,
/// a problem is written into the same buffers (their addresses unchanged).
#[test]
fn solutions_into_reused_storage_is_a_fresh_call_to_the_bit() {
    use crate::unit::linalg::Lcg;
    let mut rng = Lcg(23);
    let (mut solver, mut out) = (Solver::new(), Vec::new());
    let bits = |v: &DVector<Real>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let same = |a: &[Solution], b: &[Solution]| {
        a.len() == b.len()
            && a.iter().zip(b).all(|(a, b)| {
                a.modes == b.modes && bits(&a.x) == bits(&b.x) && bits(&a.w) == bits(&b.w)
            })
    };
    // How many problems had no solution (or an error), one, several.
    let mut counts = [0usize; 3];
    let mut rewritten = 0;
    for case in 0..4000 {
        let n = 1 + case % 5;
        let rank = 1 + (rng.unit() * (2 * n) as Real) as usize;
        let scale = 10f64.powi((case % 7) as i32 - 3);
        let y = DMatrix::from_fn(rank, 2 * n, |_, _| rng.next() * scale);
        let a = y.transpose() * &y;
        let b = DVector::from_fn(2 * n, |_, _| 5.0 * rng.next());
        let allowed: Vec<Allowed> = (0..n)
            .map(|_| Allowed {
                mu: 1.5 * rng.unit(),
                open: rng.unit() < 0.9,
                slip: match (rng.unit() * 4.0) as usize {
                    0 => Some(1.0),
                    1 => Some(-1.0),
                    _ => None,
                },
            })
            .collect();
        let fresh = solutions(&mut Solver::new(), &a, &b, &allowed);
        let reused = solutions_into(&mut solver, &a, &b, &allowed, &mut out);
        match (&fresh, &reused) {
            (Ok(all), Ok(())) => {
                assert!(same(all, &out), "case {case}: {all:?} against {out:?}");
                counts[all.len().min(2)] += 1;
            }
            (Err(e), Err(f)) => {
                assert_eq!(format!("{e:?}"), format!("{f:?}"), "case {case}");
                assert!(out.is_empty(), "case {case}: {out:?}");
                counts[0] += 1;
            }
            _ => panic!("case {case}: {fresh:?} against {reused:?}"),
        }
        // The same problem again: the same solutions, in the same buffers.
        if case % 10 == 0 && !out.is_empty() && out.len() == fresh.as_ref().unwrap().len() {
            let at = |out: &[Solution]| {
                (out.iter())
                    .map(|s| (s.modes.as_ptr(), s.x.as_ptr(), s.w.as_ptr()))
                    .collect::<Vec<_>>()
            };
            let before = at(&out);
            solutions_into(&mut solver, &a, &b, &allowed, &mut out).unwrap();
            assert!(same(fresh.as_ref().unwrap(), &out), "case {case}, again");
            // Lemke's one solution is a new one; the enumeration's are rewritten.
            if allowed.len() <= ENUMERATED_UP_TO && out.len() > 1 {
                let mut after = at(&out);
                let mut before = before;
                after.sort();
                before.sort();
                assert_eq!(before, after, "case {case}: other buffers");
                rewritten += 1;
            }
        }
    }
    println!(
        "none {}, one {}, several {}; {rewritten} rewritten in place",
        counts[0], counts[1], counts[2]
    );
    assert!(counts.iter().all(|&c| c > 100), "{counts:?}");
    assert!(rewritten >= 5, "{rewritten} rewritten in place");
}

#[test]
fn a_negative_normal_force_opens_its_contact_and_w_follows() {
    // Two coupled contacts, the first sliding with x_n = −1e-13 (rounding), the
    // second sticking.
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            2.0, 0.3, 0.5, 0.1, //
            0.3, 1.0, 0.2, 0.4, //
            0.5, 0.2, 3.0, 0.6, //
            0.1, 0.4, 0.6, 1.5,
        ],
    );
    let b = DVector::from_column_slice(&[1e-13, 0.2, -1.2, 0.05]);
    let x = DVector::from_column_slice(&[-1e-13, 5e-14, 0.4, -0.03]);
    let mut sol = Solution {
        modes: vec![Mode::Slide(-1.0), Mode::Stick],
        w: &a * &x + &b,
        x,
    };
    assert_eq!(sol.open_negative_normals(&a, &b), 1);
    assert_eq!(sol.modes, vec![Mode::Open, Mode::Stick]);
    assert_eq!((sol.x[0], sol.x[1]), (0.0, 0.0));
    assert_eq!((sol.x[2], sol.x[3]), (0.4, -0.03));
    // w = A x + b of the new forces.
    let w = &a * &sol.x + &b;
    assert!((&sol.w - &w).amax() < 1e-15);
    // Nothing left to open.
    assert_eq!(sol.open_negative_normals(&a, &b), 0);
}
