//! The broad phase: the contact pairs whose bounding boxes, each grown by a margin, overlap
//! — found through parry2d's bounding volume hierarchy ([`Bvh`]) in `O(n log n + k)` for
//! `n` colliders and `k` overlaps, instead of the `O(n²)` pairs.
//!
//! Two shapes whose axis-aligned boxes are disjoint do not touch; grown by `m_a` and `m_b`,
//! disjoint boxes keep the shapes apart as long as each moves by less than its margin.
//! A half-space has an unbounded box: it overlaps every box, and its pairs are always
//! candidates.

use parry2d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

use crate::kinematics::{KinematicsError, collider_pose};
use crate::math::{Real, Vec2};
use crate::model::{ColliderId, Model, PairId};
use crate::state::Data;

/// The world bounding box of each collider at the positions of `data` (after
/// `update_positions`), grown by `margin(collider)` (m) on every side.
pub fn collider_boxes(
    model: &Model,
    data: &Data,
    mut margin: impl FnMut(ColliderId) -> Real,
) -> Result<Vec<Aabb>, KinematicsError> {
    model
        .collider_ids()
        .map(|c| {
            let pose = collider_pose(model, data, c)?;
            let aabb = model.colliders()[c.index()].shape.compute_aabb(&pose);
            Ok(aabb.loosened(margin(c).max(0.0)))
        })
        .collect()
}

/// The pairs of `model` whose boxes `boxes` (one per collider, [`collider_boxes`])
/// overlap, in pair order.
pub fn overlapping_pairs(model: &Model, boxes: &[Aabb]) -> Vec<PairId> {
    let mut out = Vec::new();
    PairFinder::default().overlapping_pairs(model, (boxes, &[]), &mut out);
    out
}

/// The region `{x : n·x ≤ offset}` of a half-space collider, `Some((n, offset))`, for
/// [`PairFinder::overlapping_pairs`]; `None` for a collider without one.
pub type HalfPlane = Option<(Vec2, Real)>;

/// Whether `aabb` reaches the region `{x : n·x ≤ offset}`: its lowest corner along `n`.
fn reaches(aabb: &Aabb, (n, offset): (Vec2, Real)) -> bool {
    let corner = Vec2::new(
        if n.x >= 0.0 { aabb.mins.x } else { aabb.maxs.x },
        if n.y >= 0.0 { aabb.mins.y } else { aabb.maxs.y },
    );
    n.dot(corner) <= offset
}

/// [`overlapping_pairs`] with its hierarchy kept between calls: the simulation loop asks
/// for the overlapping pairs several times a step, and after the first call of a size
/// this allocates nothing. The leaves' boxes are updated in place and the tree refitted
/// (parry's `insert_or_update_partially`, `refit`), and rebuilt every [`Self::REBUILD`]
/// calls so that its quality does not decay as the bodies move. The pairs found do not
/// depend on the tree's shape: the same as a fresh tree's, in pair order.
#[derive(Clone, Default)]
pub struct PairFinder {
    bvh: Bvh,
    workspace: BvhWorkspace,
    /// Calls since the tree was last built.
    calls: usize,
}

impl PairFinder {
    /// Calls between two rebuilds of the tree.
    pub const REBUILD: usize = 64;

    /// The pairs whose boxes overlap into `out` (cleared first), in pair order. `planes`
    /// (one per collider, or empty) gives the region of a half-space collider,
    /// `{x : n·x ≤ offset}` (its box is the whole plane): its pairs are those whose other
    /// box reaches that region.
    pub fn overlapping_pairs(
        &mut self,
        model: &Model,
        (boxes, planes): (&[Aabb], &[HalfPlane]),
        out: &mut Vec<PairId>,
    ) {
        let plane = |k: usize| planes.get(k).copied().flatten();
        let n = boxes.len();
        if self.bvh.leaf_count() as usize != n || self.calls >= Self::REBUILD {
            if self.bvh.leaf_count() as usize == n {
                // Same leaves: rebuild in place, in the kept buffers.
                for (i, aabb) in boxes.iter().enumerate() {
                    self.bvh.insert_or_update_partially(*aabb, i as u32, 0.0);
                }
                self.bvh.refit(&mut self.workspace);
                self.bvh
                    .rebuild(&mut self.workspace, BvhBuildStrategy::Binned);
            } else {
                self.bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, boxes);
            }
            self.calls = 0;
        } else {
            for (i, aabb) in boxes.iter().enumerate() {
                self.bvh.insert_or_update_partially(*aabb, i as u32, 0.0);
            }
            self.bvh.refit(&mut self.workspace);
        }
        self.calls += 1;
        out.clear();
        for (i, aabb) in boxes.iter().enumerate() {
            for j in self.bvh.intersect_aabb(aabb) {
                let j = j as usize;
                let in_region = match (plane(i), plane(j)) {
                    (Some(h), None) => reaches(&boxes[j], h),
                    (None, Some(h)) => reaches(aabb, h),
                    _ => true,
                };
                if j > i
                    && in_region
                    && let Some(p) = model.pair_between(ColliderId(i), ColliderId(j))
                {
                    out.push(p);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}
