//! [`PairMap`]: a value per contact pair, stored only for the pairs that differ from a
//! default (the modes, slips and accumulations of the loop: a few pairs among millions).

use std::collections::BTreeMap;
use std::ops::{Index, IndexMut};

use crate::model::PairId;

/// A value for every contact pair, indexed by [`PairId::index`]: the default for all but
/// the pairs written, which are kept in pair order. Writing through `IndexMut` stores the
/// pair (with the default first); [`PairMap::fill`] forgets them all.
#[derive(Clone, Debug, Default)]
pub struct PairMap<T> {
    default: T,
    #[doc(hidden)]
    pub map: BTreeMap<usize, T>,
}

impl<T: Clone> PairMap<T> {
    /// Every pair at `default`.
    pub fn new(default: T) -> Self {
        Self {
            default,
            map: BTreeMap::new(),
        }
    }

    /// Every pair at `value` again.
    pub fn fill(&mut self, value: T) {
        self.map.clear();
        self.default = value;
    }

    /// Every stored pair back at `value`, the pairs kept stored: unlike [`PairMap::fill`],
    /// the map keeps its nodes, so that writing those pairs again allocates nothing
    /// (`Simulation::reset`).
    pub fn reset_stored(&mut self, value: &T) {
        for v in self.map.values_mut() {
            v.clone_from(value);
        }
    }

    /// The pairs stored (written since the last fill or prune), in pair order.
    pub fn stored(&self) -> impl Iterator<Item = PairId> + '_ {
        self.map.keys().map(|&k| PairId(k))
    }
}

impl<T: Clone + PartialEq> PairMap<T> {
    /// The pairs stored (written since the last fill) whose value is not the default, in
    /// pair order.
    pub fn changed(&self) -> impl Iterator<Item = PairId> + '_ {
        (self.map.iter())
            .filter(|(_, v)| **v != self.default)
            .map(|(&k, _)| PairId(k))
    }

    /// Forgets the pairs at the default value (their storage).
    pub fn prune(&mut self) {
        let default = &self.default;
        self.map.retain(|_, v| v != default);
    }
}

impl<T> Index<usize> for PairMap<T> {
    type Output = T;
    fn index(&self, k: usize) -> &T {
        self.map.get(&k).unwrap_or(&self.default)
    }
}

impl<T: Clone> IndexMut<usize> for PairMap<T> {
    fn index_mut(&mut self, k: usize) -> &mut T {
        self.map.entry(k).or_insert_with(|| self.default.clone())
    }
}
