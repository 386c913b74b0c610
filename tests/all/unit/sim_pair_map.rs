//! The unit tests of `sim::pair_map` (`src/sim/pair_map.rs`).

// The source module's own imports.
use ricochet::model::PairId;

use ricochet::sim::pair_map::PairMap;

#[test]
fn only_written_pairs_are_stored() {
    let mut m = PairMap::new(0i8);
    assert_eq!(m[7], 0);
    m[7] = 1;
    m[3] = 0;
    m[5] = -1;
    assert_eq!((m[7], m[5], m[3], m[4]), (1, -1, 0, 0));
    assert_eq!(m.changed().collect::<Vec<_>>(), vec![PairId(5), PairId(7)]);
    m.prune();
    assert_eq!(m.map.len(), 2);
    m.fill(2);
    assert_eq!((m[7], m[0]), (2, 2));
    assert_eq!(m.changed().count(), 0);
}
