//! The broad phase of the loop (issue 15): the pairs whose event functions a step samples.
//!
//! A model's pairs are `O(n²)`; the loop samples only the *candidates* of each step, the
//! pairs whose bounding boxes, swept over the step, overlap (parry2d's `Bvh`,
//! [`crate::contact::broad`]: `O(n log n + k)`). The candidate set is built twice a step:
//!
//! 1. **Before the step** (for the step cap, `cap_for_spin`): each collider's box at the
//!    step's start grown by what it can travel within the horizon `H`,
//!
//!    ```text
//!    m_c = V_c H + ½ |g| H² + s,   V_c = |v_G| + |ω| (|c − G| + r),
//!    H = min(h_max, 1.01 · 10 h_next)
//!    ```
//!
//!    with `V_c` the speed bound of the collider's points that holds as its body turns (the
//!    rotation bound: `G` the centre of mass, `c`, `r` the centre and radius of the shape's
//!    bounding circle), `h_next` the step the integrator will try, `h_max` the cap before
//!    the spin cap, and the slack `s = 10 gap_tol` (pairs at a small positive gap stay
//!    candidates). A pair that is not a candidate has a gap `d > (V_a + V_b) H + |g| H²`
//!    (the boxes hold the shapes), so the time it takes to close it at `V = V_a + V_b`
//!    under gravity, `2d / (V + √(V² + 2|g|d))`, exceeds `H`: its term in the step cap is
//!    beyond `h_max`, or beyond the step the integrator tries (with the 1 % by which it
//!    may stretch a step to land on the stop time) and beyond the step it suggests after
//!    it (at most [`GROWTH`] times longer), which an impact's reset clips to the cap. So
//!    the cap over the candidates gives the integrator the *same steps*, bit for bit, as
//!    the cap over every pair did (`tests/all/broad_phase.rs` runs with and without it).
//! 2. **After the step** (for the event location): each collider's box is grown to hold
//!    also its boxes at the `k + 2` times where the locator samples the step (`k = 4`), each
//!    grown by `V_c(t_j) Δ`, what the collider travels in a whole sample interval `Δ` at
//!    its speed bound there: the motion the prediction left out (the forces of the joints,
//!    springs and contacts, which `H` does not bound) is seen. The locator itself sees a
//!    contact only through the gaps at these samples and their rates (one extremum
//!    between two samples; [`crate::events`]); a pair whose swept boxes stay apart has a
//!    positive gap at every sample and cannot close between two of them unless a collider
//!    moves more than twice its speed bound at the samples allows over half an interval.
//!    So the broad phase misses no event the sampling of every pair would find.
//!
//! The pairs with a closed contact point and the pairs whose gap event is disarmed are
//! always candidates (`Simulation::arm`). The candidates are kept in pair order, so the
//! events of one instant are reported in the order of the pairs, as before.

use parry2d_f64::bounding_volume::{Aabb, BoundingVolume};

use crate::contact::broad::PairFinder;
use crate::kinematics::{KinematicsError, collider_pose};
use crate::math::{Real, Vec2, perp};
use crate::model::{ColliderId, Model, PairId};
use crate::state::Data;

/// The largest growth of the step from one step to the next of the adaptive methods
/// (`fac_max`: DOPRI5 10, DOP853 6).
pub(super) const GROWTH: Real = 10.0;

/// The speed bound `V_c` of the points of collider `c` (m/s), the radius `r` of its bounding
/// circle (m) and its body's rotation rate `|ω|` (rad/s), at the positions and velocities of
/// `data`: `V_c = |v_G| + |ω| (|c − G| + r)`, which holds as the body turns (the speed of
/// the circle's centre alone changes by `|ω|` times its distance from the centre of mass
/// within a step: drop 32460 of `tests/all/spin_drops.rs`). An obstacle: `(0, r, 0)`.
pub(super) fn reach(model: &Model, data: &Data, c: ColliderId) -> (Real, Real, Real) {
    let collider = &model.colliders()[c.index()];
    let sphere = collider.shape.compute_local_bounding_sphere();
    let r = sphere.radius();
    match collider.body {
        None => (0.0, r, 0.0),
        Some(b) => {
            let (pose, twist, com) = (
                data.body_pose[b.index()],
                data.body_twist[b.index()],
                data.body_com[b.index()],
            );
            let centre = pose.transform_point(collider.pose.transform_point(sphere.center()));
            let v_com = twist.v + perp(com) * twist.w;
            let w = twist.w.abs();
            (v_com.length() + w * ((centre - com).length() + r), r, w)
        }
    }
}

/// The box of every collider at the positions of `data`, grown by `margin(V_c)` (m), into
/// `boxes` (one per collider), and the grown region of every half-space into `planes`
/// (see [`Plane`]). A margin that is not finite grows the box to the whole plane (the
/// collider is a candidate with every other).
pub(super) fn grown_boxes(
    model: &Model,
    data: &Data,
    (boxes, planes): (&mut Vec<Aabb>, &mut Vec<Plane>),
    margin: impl Fn(Real) -> Real,
) -> Result<(), KinematicsError> {
    boxes.clear();
    planes.clear();
    for c in model.collider_ids() {
        let (b, p) = grown_box(model, data, c, &margin)?;
        boxes.push(b);
        planes.push(p);
    }
    Ok(())
}

/// Grows each of `boxes` (and `planes`) to hold the collider's box (region) at the
/// positions of `data`, itself grown by `margin(V_c)`.
pub(super) fn sweep_boxes(
    model: &Model,
    data: &Data,
    (boxes, planes): (&mut [Aabb], &mut [Plane]),
    margin: impl Fn(Real) -> Real,
) -> Result<(), KinematicsError> {
    for (k, c) in model.collider_ids().enumerate() {
        let (b, p) = grown_box(model, data, c, &margin)?;
        boxes[k].merge(&b);
        planes[k] = match (planes[k], p) {
            (Some((n, a)), Some((m, b))) if n == m => Some((n, a.max(b))),
            _ => None,
        };
    }
    Ok(())
}

/// The region of a half-space collider for the broad phase, `{x : n·x ≤ offset}` in the
/// world (`n` its outward normal, `offset = n·p + margin` for a point `p` of its boundary):
/// `None` for every other collider, or where the region is the whole plane. A half-space's
/// box is the whole plane, so without it every collider would be a candidate with every
/// half-space (a floor pairs with each of 2,000 balls at every step).
pub(crate) type Plane = crate::contact::broad::HalfPlane;

fn grown_box(
    model: &Model,
    data: &Data,
    c: ColliderId,
    margin: &impl Fn(Real) -> Real,
) -> Result<(Aabb, Plane), KinematicsError> {
    let collider = &model.colliders()[c.index()];
    let pose = collider_pose(model, data, c)?;
    let aabb = collider.shape.compute_aabb(&pose);
    let m = margin(reach(model, data, c).0);
    // The box of every possible position (parry's half-space box: half the largest
    // number, so that merging and loosening stay finite).
    let everywhere = Vec2::splat(0.5 * Real::MAX);
    let finite = m < 0.25 * Real::MAX;
    let plane = match collider.shape.as_halfspace() {
        Some(h) if finite => {
            let n = pose.rotation * h.normal;
            Some((n, n.dot(pose.translation) + m.max(0.0)))
        }
        _ => None,
    };
    let aabb = if finite {
        aabb.loosened(m.max(0.0))
    } else {
        Aabb::new(-everywhere, everywhere)
    };
    Ok((aabb, plane))
}

/// The pairs a sample lists (the `/state` contract), into `out`, in pair order: `all` when
/// the model has at most [`LISTED_PAIRS`](super::LISTED_PAIRS) pairs (then `Some`); beyond,
/// the pairs whose bounding boxes overlap at the positions of `data`, and `in_contact`.
pub(super) fn listed_pairs(
    model: &Model,
    data: &Data,
    all: Option<&[PairId]>,
    in_contact: impl Iterator<Item = PairId>,
    (boxes, planes, finder): (&mut Vec<Aabb>, &mut Vec<Plane>, &mut PairFinder),
    out: &mut Vec<PairId>,
) -> Result<(), KinematicsError> {
    out.clear();
    if let Some(all) = all {
        out.extend_from_slice(all);
        return Ok(());
    }
    grown_boxes(model, data, (boxes, planes), |_| 0.0)?;
    finder.overlapping_pairs(model, (boxes, planes), out);
    out.extend(in_contact);
    out.sort_unstable();
    out.dedup();
    Ok(())
}

/// Every pair of `model`, if it has at most [`LISTED_PAIRS`](super::LISTED_PAIRS).
pub(super) fn all_pairs_if_few(model: &Model) -> Option<Vec<PairId>> {
    let listed: Vec<PairId> = model.pair_ids().take(super::LISTED_PAIRS + 1).collect();
    (listed.len() <= super::LISTED_PAIRS).then_some(listed)
}
