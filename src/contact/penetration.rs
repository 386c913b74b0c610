//! The penetration of two overlapping convex shapes by their support functions, for when
//! parry2d's EPA gives up (thin polygons crossing, cf. dimforge/parry#415).

use std::f64::consts::TAU;

use parry2d_f64::shape::{Shape, SupportMap};

use super::gap::PairContact;
use crate::math::{Pose, Real, Vec2};

/// Directions sampled on the unit circle before refining (1° apart).
const SAMPLES: usize = 360;

/// The outward face normals of a polygonal shape in the world frame (none for round
/// shapes): where `f` has its minima for polygon pairs.
#[doc(hidden)]
pub fn face_normals(shape: &dyn Shape, pose: &Pose, out: &mut Vec<Vec2>) {
    let rot = |v: Vec2| pose.rotation * v;
    if shape.as_cuboid().is_some() {
        out.extend([Vec2::X, Vec2::Y, -Vec2::X, -Vec2::Y].map(rot));
    } else if let Some(p) = shape.as_convex_polygon() {
        out.extend(p.normals().iter().map(|&n| rot(n)));
    } else if let Some(s) = shape.as_segment() {
        if let Some(n) = (s.b - s.a).try_normalize() {
            let n = Vec2::new(-n.y, n.x);
            out.extend([n, -n].map(rot));
        }
    } else if let Some(c) = shape.as_capsule()
        && let Some(n) = (c.segment.b - c.segment.a).try_normalize()
    {
        let n = Vec2::new(-n.y, n.x);
        out.extend([n, -n].map(rot));
    }
}

/// The contact of two overlapping convex shapes `a` and `b`, oriented from `a` to `b`.
///
/// The depth is the least translation of `b` that separates them, the separating-axis
/// measure over every direction:
///
/// ```text
/// depth = min_{|n| = 1} f(n),   f(n) = h_a(n) + h_b(−n)
/// ```
///
/// where `h_s(n) = max_{x ∈ s} n·x` is a shape's support function (`f(n) > 0` for every
/// `n` when they overlap: their projections on `n` overlap by at least `f(n)`). Moving
/// `b` by `depth · n*` along the minimizer `n*` makes them touch. The candidates: the face
/// normals of polygonal shapes (`normals`, exact minima for polygon pairs), and every
/// local minimum of `f` over [`SAMPLES`] directions, refined by golden-section search. The
/// witness points are the support points `s_a(n*)` and `s_b(−n*)`.
#[doc(hidden)]
pub fn penetration(
    pose_a: &Pose,
    a: &dyn SupportMap,
    pose_b: &Pose,
    b: &dyn SupportMap,
    normals: &[Vec2],
) -> PairContact {
    let dir = |phi: Real| Vec2::new(phi.cos(), phi.sin());
    let f_n = |n: Vec2| n.dot(a.support_point(pose_a, n)) - n.dot(b.support_point(pose_b, -n));
    let f = |phi: Real| f_n(dir(phi));
    let mut best_n = Vec2::X;
    let mut best = Real::INFINITY;
    let mut consider = |n: Vec2, v: Real| {
        if v < best {
            (best_n, best) = (n, v);
        }
    };
    for &n in normals {
        consider(n, f_n(n));
    }
    let step = TAU / SAMPLES as Real;
    // On the stack (2.9 kB): the loop allocates nothing (tests/all/sim_alloc.rs).
    let values: [Real; SAMPLES] = std::array::from_fn(|k| f(k as Real * step));
    for k in 0..SAMPLES {
        let (prev, next) = (
            values[(k + SAMPLES - 1) % SAMPLES],
            values[(k + 1) % SAMPLES],
        );
        if values[k] <= prev && values[k] <= next {
            let phi = golden_minimum(&f, k as Real * step - step, k as Real * step + step);
            consider(dir(phi), f(phi));
        }
    }
    PairContact {
        gap: -best,
        point_a: a.support_point(pose_a, best_n),
        point_b: b.support_point(pose_b, -best_n),
        normal: best_n,
    }
}

/// The minimizer of `f` on `[lo, hi]` by golden-section search (to 1e-13 rad).
fn golden_minimum(f: &dyn Fn(Real) -> Real, mut lo: Real, mut hi: Real) -> Real {
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > 1e-13 {
        if f1 <= f2 {
            (hi, x2, f2) = (x2, x1, f1);
            x1 = hi - ratio * (hi - lo);
            f1 = f(x1);
        } else {
            (lo, x1, f1) = (x1, x2, f2);
            x2 = lo + ratio * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 <= f2 { x1 } else { x2 }
}
