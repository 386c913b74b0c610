//! The unit tests of `model::pairs` (`src/model/pairs.rs`).

// The source module's own imports.

use ricochet::model::pairs::{decode, encode};

/// The ids of the couples of n colliders increase in the order of (i, j), and decode
/// back to their couple; ids of no couple decode to nothing.
#[test]
fn ids_follow_the_couples_in_order_and_decode() {
    for n in [0, 1, 2, 3, 7, 64, 1000, 20_001] {
        let step = if n > 1000 { 997 } else { 1 };
        let mut last = None;
        for i in (0..n).step_by(step) {
            for j in (i + 1..n).step_by(step) {
                let id = encode(n, i, j).0;
                assert!(last < Some(id), "n {n}, ({i}, {j})");
                assert_eq!(decode(n, id), Some((i, j)), "n {n}, id {id}");
                last = Some(id);
            }
        }
    }
    assert_eq!(decode(5, encode(5, 1, 4).0 + 1), None, "j = n");
    assert_eq!(decode(5, (3 << 32) | 3), None, "i = j");
    assert_eq!(decode(5, (4 << 32) | 3), None, "i > j");
}
