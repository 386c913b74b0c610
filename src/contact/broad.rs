//! The broad phase: the contact pairs whose bounding boxes, each grown by a margin, overlap
//! — found through parry2d's bounding volume hierarchy ([`Bvh`]) in `O(n log n + k)` for
//! `n` colliders and `k` overlaps, instead of the `O(n²)` pairs.
//!
//! Two shapes whose axis-aligned boxes are disjoint do not touch; grown by `m_a` and `m_b`,
//! disjoint boxes keep the shapes apart as long as each moves by less than its margin.
//! A half-space has an unbounded box: it overlaps every box, and its pairs are always
//! candidates.

use parry2d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};

use crate::kinematics::{KinematicsError, collider_pose};
use crate::math::Real;
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
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, boxes);
    let mut out = Vec::new();
    for (i, aabb) in boxes.iter().enumerate() {
        for j in bvh.intersect_aabb(aabb) {
            let j = j as usize;
            if j > i
                && let Some(p) = model.pair_between(ColliderId(i), ColliderId(j))
            {
                out.push(p);
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}
