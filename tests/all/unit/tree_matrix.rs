//! The unit tests of `tree_matrix` (`src/tree_matrix.rs`).

// The source module's own imports.

use ricochet::tree_matrix::*;

#[test]
fn a_chain_is_the_full_triangle_and_a_forest_its_diagonal() {
    assert_eq!(TreePattern::dense(4).entries(), 10);
    assert_eq!(TreePattern::new(&[None; 5]).unwrap().entries(), 5);
    assert!(TreePattern::new(&[None, Some(1)]).is_none());
}

#[test]
fn the_factor_of_a_star() {
    // Root 0 with children 1, 2: M = [[4, 1, 1], [1, 2, 0], [1, 0, 3]].
    let p = TreePattern::new(&[None, Some(0), Some(0)]).unwrap();
    let mut m = TreeMatrix::zeros(p.clone());
    for (i, j, v) in [
        (0, 0, 4.0),
        (1, 0, 1.0),
        (2, 0, 1.0),
        (1, 1, 2.0),
        (2, 2, 3.0),
    ] {
        assert!(m.set(i, j, v));
    }
    assert!(!m.set(1, 2, 5.0), "(1, 2) is outside the pattern");
    let mut l = TreeMatrix::zeros(p);
    l.factor_ltl_from(&m).unwrap();
    let ld = l.to_dense_lower();
    assert!((ld.transpose() * &ld - m.to_dense()).amax() < 1e-15);
    let mut x = vec![1.0, 2.0, 3.0];
    l.solve_ltl(&mut x);
    let r = m.to_dense() * nalgebra::DVector::from_column_slice(&x);
    assert!((r - nalgebra::DVector::from_column_slice(&[1.0, 2.0, 3.0])).amax() < 1e-14);
}
