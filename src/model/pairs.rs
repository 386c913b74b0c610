//! The contact pairs of a model, answered on demand from its rules (issue 15: big
//! mechanisms in linear memory).
//!
//! A model does not list its pairs: a 4,000-link chain has 8 million of them, 2,000 free
//! balls 2 million. It keeps the *rules* — the default rule (different bodies, or a body and
//! the world, not a parent and its child) with the default material, and the sparse
//! overrides of the builder's [`pair`](super::ModelBuilder::pair) and
//! [`disable_pair`](super::ModelBuilder::disable_pair) (the scenes' `[[contact.pair]]`) — and
//! answers "may these two touch, with what material" for any two colliders, in
//! `O(log r)` for `r` overrides.
//!
//! ## Pair ids
//!
//! A [`PairId`] is derived from the two collider indices `i < j`:
//!
//! ```text
//! id(i, j) = i · 2³² + j
//! ```
//!
//! so it is stable (it does not depend on which other pairs are allowed, nor on the number
//! of colliders), ordered as the pairs were listed before (smaller, then larger collider
//! index), and decoded back to `(i, j)` by a shift and a mask (the loop asks for a pair's
//! colliders at every evaluation of its gap). It needs 64-bit indices (`usize`), and at
//! most 2³² colliders. Logs name a pair by its colliders (`<a>/<b>`), never by its id.

use super::{BodyId, Collider, ColliderId, ContactPair, Joint, Material, PairId};

/// The contact rules of a model: the default material and the overrides, sorted by pair.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairRules {
    /// The material of the pairs that the default rule lets touch.
    pub(crate) default: Material,
    /// `(smaller, larger)` collider index → the material of an enabled pair, `None` for a
    /// disabled one; sorted by pair, one entry per pair (the last rule on it).
    pub(crate) overrides: Vec<((usize, usize), Option<Material>)>,
}

/// The id of the couple `i < j` of `n` colliders (see the [module](self) doc).
#[inline]
#[doc(hidden)]
pub fn encode(n: usize, i: usize, j: usize) -> PairId {
    debug_assert!(i < j && j < n);
    PairId((i << 32) | j)
}

/// The couple `(i, j)`, `i < j < n`, of the id `k` (the inverse of [`encode`]); `None` for
/// an id that is not one of `n` colliders.
#[inline]
#[doc(hidden)]
pub fn decode(n: usize, k: usize) -> Option<(usize, usize)> {
    let (i, j) = (k >> 32, k & 0xFFFF_FFFF);
    (i < j && j < n).then_some((i, j))
}

/// The default rule: different bodies (or a body and the world), not parent and child.
pub(crate) fn default_touch(colliders: &[Collider], joints: &[Joint], i: usize, j: usize) -> bool {
    match (colliders[i].body, colliders[j].body) {
        (None, None) => false,
        (Some(_), None) | (None, Some(_)) => true,
        (Some(a), Some(b)) => {
            a != b && joints[a.0].parent != Some(b) && joints[b.0].parent != Some(a)
        }
    }
}

impl PairRules {
    /// The material of the colliders `i < j`, or `None` if they may not touch.
    pub(crate) fn material(
        &self,
        colliders: &[Collider],
        joints: &[Joint],
        i: usize,
        j: usize,
    ) -> Option<Material> {
        match self.overrides.binary_search_by_key(&(i, j), |r| r.0) {
            Ok(k) => self.overrides[k].1,
            Err(_) => default_touch(colliders, joints, i, j).then_some(self.default),
        }
    }

    /// The pair of the colliders `i < j` with `material`: `a` on a body, `b` on a body or
    /// the world.
    pub(crate) fn contact_pair(
        colliders: &[Collider],
        i: usize,
        j: usize,
        material: Material,
    ) -> ContactPair {
        let (a, b) = if colliders[i].body.is_some() {
            (i, j)
        } else {
            (j, i)
        };
        ContactPair {
            a: ColliderId(a),
            b: ColliderId(b),
            material,
        }
    }

    /// The number of pairs that may touch: the couples walked one by one, nothing stored
    /// (`O(n²)` time, `O(1)` memory; 8 million couples of a 4,000-link chain in ~20 ms).
    pub(crate) fn count(&self, colliders: &[Collider], joints: &[Joint]) -> usize {
        let n = colliders.len();
        let bodies: Vec<Option<BodyId>> = colliders.iter().map(|c| c.body).collect();
        let parent = |b: BodyId| joints[b.0].parent;
        let mut count = 0usize;
        for i in 0..n {
            for j in i + 1..n {
                count += match (bodies[i], bodies[j]) {
                    (None, None) => 0,
                    (Some(_), None) | (None, Some(_)) => 1,
                    (Some(a), Some(b)) => {
                        usize::from(a != b && parent(a) != Some(b) && parent(b) != Some(a))
                    }
                };
            }
        }
        // The overrides that change the default rule's answer.
        for &((i, j), m) in &self.overrides {
            match (default_touch(colliders, joints, i, j), m.is_some()) {
                (true, false) => count -= 1,
                (false, true) => count += 1,
                _ => {}
            }
        }
        count
    }
}
