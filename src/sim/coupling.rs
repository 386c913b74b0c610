//! Which contact points are coupled: the groups of points whose rows of
//! `W = J M⁻¹ Jᵀ` couple, solved together at an instant; points of different groups are
//! separate problems.
//!
//! The speeds that move a body are those of the joints on its path from the world. Two
//! bodies' motions share a speed exactly when their paths share a joint with a free
//! coordinate, i.e. when they have the same *coupling root*: the topmost body on the path
//! (the body itself included) whose joint has a free coordinate. In a tree `M` is
//! block-diagonal between different roots, so is `M⁻¹`, and a contact point, which
//! involves the bodies of its pair's two colliders, couples with another exactly when their
//! bodies' roots are linked through a chain of points. A body whose path has no free
//! coordinate (a fixed or driven body) has no root: it moves, if at all, by its drive, and
//! couples nothing. (The nonholonomic constraints act between the speeds of one path:
//! they do not couple other bodies.)
//!
//! Seven balls landing on a floor at one instant are seven groups of one point each, so
//! each gets the paper's one-point law, exactly as if it fell alone.

use crate::model::{BodyId, Model, PairId};

/// The coupling root of every body (see the module doc), and the scratch of
/// [`Coupling::groups`].
#[derive(Clone, Debug)]
pub struct Coupling {
    root: Vec<Option<usize>>,
    /// The union–find slot of each root body (indexed by body, `usize::MAX`: none), for
    /// the roots of the current call; reset after each call through `used`.
    slot: Vec<usize>,
    /// The root bodies given a slot by the current call.
    used: Vec<usize>,
    /// The parent of each slot (a slot is its own parent at the top of its tree).
    parent: Vec<usize>,
    /// The root body of each slot.
    name: Vec<usize>,
    /// The coupling roots of each point of the current call.
    points: Vec<[Option<usize>; 2]>,
}

impl Coupling {
    /// The coupling roots of `model`'s bodies.
    pub fn new(model: &Model) -> Self {
        let free = |b: BodyId| {
            let j = &model.joints()[b.index()];
            j.drive.is_none() && j.kind.ndof() > 0
        };
        let root: Vec<Option<usize>> = (model.body_ids())
            .map(|b| {
                std::iter::once(b)
                    .chain(model.ancestors(b))
                    .filter(|&a| free(a))
                    .last()
                    .map(BodyId::index)
            })
            .collect();
        Self {
            slot: vec![usize::MAX; root.len()],
            root,
            used: Vec::new(),
            parent: Vec::new(),
            name: Vec::new(),
            points: Vec::new(),
        }
    }

    /// The coupling roots of the two bodies of `pair` (`None` for an obstacle or a body
    /// without a free coordinate on its path).
    fn roots(&self, model: &Model, pair: PairId) -> [Option<usize>; 2] {
        let p = &model.pair_of(pair);
        let root = |c: crate::model::ColliderId| {
            model.colliders()[c.index()]
                .body
                .and_then(|b| self.root[b.index()])
        };
        [root(p.a), root(p.b)]
    }

    /// The group of each point of `pairs` (one entry per point, several points may share a
    /// pair), into `groups`: points in one group are coupled, directly or through other
    /// points of the list. A group is named by its smallest coupling root (a body index),
    /// so the names stay the same as long as the same bodies touch; a point of two bodies
    /// without a root is a group of its own, named `usize::MAX − i`. Works in kept buffers:
    /// allocates nothing once they have grown to the largest set of points.
    pub fn groups(
        &mut self,
        model: &Model,
        pairs: impl Iterator<Item = PairId>,
        groups: &mut Vec<usize>,
    ) {
        // Union–find over the roots that appear.
        fn find(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut points = std::mem::take(&mut self.points);
        points.clear();
        points.extend(pairs.map(|p| self.roots(model, p)));
        self.parent.clear();
        self.name.clear();
        for roots in &points {
            let mut first: Option<usize> = None;
            for &r in roots.iter().flatten() {
                if self.slot[r] == usize::MAX {
                    self.slot[r] = self.parent.len();
                    self.used.push(r);
                    self.parent.push(self.parent.len());
                    self.name.push(r);
                }
                let s = self.slot[r];
                match first {
                    None => first = Some(s),
                    Some(f) => {
                        let (a, b) = (find(&mut self.parent, f), find(&mut self.parent, s));
                        if a != b {
                            let (keep, drop) = if self.name[a] <= self.name[b] {
                                (a, b)
                            } else {
                                (b, a)
                            };
                            self.parent[drop] = keep;
                        }
                    }
                }
            }
        }
        groups.clear();
        groups.extend(points.iter().enumerate().map(
            |(i, roots)| match roots.iter().flatten().next() {
                Some(&r) => {
                    let s = find(&mut self.parent, self.slot[r]);
                    self.name[s]
                }
                None => usize::MAX - i,
            },
        ));
        for &r in &self.used {
            self.slot[r] = usize::MAX;
        }
        self.used.clear();
        self.points = points;
    }
}

/// The distinct group names of `groups`, in the order they first appear, into `ids`.
pub fn distinct(groups: impl IntoIterator<Item = usize>, ids: &mut Vec<usize>) {
    ids.clear();
    for g in groups {
        if !ids.contains(&g) {
            ids.push(g);
        }
    }
}
