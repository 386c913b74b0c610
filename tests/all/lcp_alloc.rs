//! Lemke's workspace allocates nothing once warmed up: a counting global allocator (per
//! thread) watches `Lemke::solve` on a problem no larger than one it has solved.

use crate::common::alloc::allocations;

use nalgebra::{DMatrix, DVector};
use ricochet::lcp::lemke::{Lemke, LemkeStatus};

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
