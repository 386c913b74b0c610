//! Lemke's workspace allocates nothing once warmed up: a counting global allocator (per
//! thread) watches `Lemke::solve` on a problem no larger than one it has solved, and the
//! contact problem's whole Lemke path (`lcp::solutions_into` on many points).

use crate::common::alloc::allocations;
use crate::lcp_lemke::dumped;

use nalgebra::{DMatrix, DVector};
use ricochet::lcp::lemke::{Lemke, LemkeStatus};
use ricochet::lcp::{self, Solution, Solver};

#[test]
fn a_warm_lemke_workspace_allocates_nothing() {
    // A positive definite M (diagonally dominant), q with negative entries: pivots happen.
    let problem = |k: usize| {
        let m = DMatrix::from_fn(k, k, |i, j| {
            if i == j {
                4.0
            } else {
                ((i * 7 + j * 3) % 5) as f64 * 0.1 - 0.2
            }
        });
        let q = DVector::from_fn(k, |i, _| {
            if i % 3 == 0 {
                1.0
            } else {
                -1.0 - i as f64 * 0.01
            }
        });
        (m, q)
    };
    let (m32, q32) = problem(32);
    let (m20, q20) = problem(20);
    let mut lemke = Lemke::new();
    assert!(matches!(lemke.solve(&m32, &q32), Ok(LemkeStatus::Solved { pivots }) if pivots > 0));
    let before = allocations();
    let a = lemke.solve(&m32, &q32);
    let b = lemke.solve(&m20, &q20);
    let after = allocations();
    assert!(matches!(a, Ok(LemkeStatus::Solved { pivots }) if pivots > 0));
    assert!(matches!(b, Ok(LemkeStatus::Solved { pivots }) if pivots > 0));
    assert_eq!(
        after,
        before,
        "Lemke allocated {} times once warm",
        after - before
    );
}

/// Lemke's path of the contact problem (`lcp::solutions_into` beyond the enumeration:
/// the LCP's assembly, Lemke's pivots along `d = 1` and the other covering vectors, the
/// solution's modes, its polish and the repair of its modes) allocates nothing once its
/// buffers have grown: the problems the chains on the floor posed (6 to 29 points, the
/// 29 solved along the second covering vector), each solved three times on one solver,
/// in turn, with `out` holding the last call's solutions; the third round allocates
/// nothing (on stop 34's code: 39 a round), and every call gives a fresh solver's
/// solution, bit for bit.
#[test]
fn a_warm_lemke_path_allocates_nothing() {
    let problems: Vec<_> = [
        include_str!("../data/lcp/chain32_6_contacts.txt"),
        include_str!("../data/lcp/chain32_8_contacts.txt"),
        include_str!("../data/lcp/chain16_11_contacts.txt"),
        include_str!("../data/lcp/chain32_28_contacts.txt"),
        include_str!("../data/lcp/chain32_29_contacts_pivots.txt"),
    ]
    .into_iter()
    .map(dumped)
    .collect();
    let fresh: Vec<Solution> = (problems.iter())
        .map(|(a, b, allowed)| Solver::new().solve(a, b, allowed).unwrap())
        .collect();
    let bits = |s: &Solution| {
        let v = |v: &DVector<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (s.modes.clone(), v(&s.x), v(&s.w))
    };
    let (mut solver, mut out) = (Solver::new(), Vec::new());
    for round in 0..3 {
        let before = allocations();
        for (a, b, allowed) in &problems {
            lcp::solutions_into(&mut solver, a, b, allowed, &mut out).unwrap();
        }
        let allocated = allocations() - before;
        println!("round {round}: {allocated} allocations");
        if round == 2 {
            assert_eq!(allocated, 0, "Lemke's path allocated once warm");
        }
        // The last problem's solution, and every other's again, are a fresh solver's.
        for ((a, b, allowed), fresh) in problems.iter().zip(&fresh) {
            lcp::solutions_into(&mut solver, a, b, allowed, &mut out).unwrap();
            assert_eq!(out.len(), 1);
            assert!(bits(&out[0]) == bits(fresh), "round {round}");
        }
    }
}
