//! parry2d's `query::contact` with its penetration fallback kept between calls.
//!
//! For two support-mapped shapes that overlap (capsule ends pressed into each other,
//! a polygon corner sunk into a box), parry's GJK finds the origin inside their Minkowski
//! difference and falls back on the expanding polytope algorithm (EPA), which it builds
//! anew at every call: three allocations per query, in the loop's right-hand side and
//! event functions (issue 16: no allocation in the loop). Here the EPA is a thread's own,
//! reused (parry documents its reuse: `EPA::new`, "the same `EPA` instance can be reused
//! for multiple queries"; `closest_points` clears it first). Everything else is parry's
//! own code path, in parry's order of dispatch (`DefaultQueryDispatcher::contact`), so the
//! results are parry's bit for bit.

use std::cell::{Cell, RefCell};
use std::thread::LocalKey;

use parry2d_f64::math::{Pose, Real, Vector};
use parry2d_f64::query::epa::EPA;
use parry2d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry2d_f64::query::{Contact, DefaultQueryDispatcher, QueryDispatcher, Unsupported};
use parry2d_f64::shape::{HalfSpace, Shape, SupportMap};

thread_local! {
    /// The EPA of this thread's queries (see the module doc), grown at its creation.
    static KEPT_EPA: RefCell<EPA> = RefCell::new(grown_epa());
}

/// `f` on this thread's kept value of `kept` (a buffer that keeps its capacity between
/// calls), or on a `fresh` one if the kept one is borrowed already (never nested in
/// practice: a fallback, not an error).
pub(crate) fn with_kept<T, R>(
    kept: &'static LocalKey<RefCell<T>>,
    fresh: impl FnOnce() -> T,
    f: impl FnOnce(&mut T) -> R,
) -> R {
    kept.with(|cell| match cell.try_borrow_mut() {
        Ok(mut value) => f(&mut value),
        Err(_) => f(&mut fresh()),
    })
}

/// An EPA whose buffers already hold the most any query can put in them, so that no later
/// query grows them inside the loop (a kept buffer grows the first time a problem needs
/// more: the 8-link chain met its largest polytope after a second of motion). parry's EPA
/// stops after 101 expansions (`epa2.rs`, `niter > 100`), each adding one vertex, two faces
/// and at most two entries of its heap, unless it converges first; it is taken there once,
/// on a disc whose support points move outwards at every call ([`Swelling`]), on which no
/// expansion converges (103 evaluations of its support function: the two of GJK's start,
/// then one per expansion; the test `the_kept_epa_never_grows`).
fn grown_epa() -> EPA {
    let mut epa = EPA::new();
    let (disc, point) = (Swelling(Cell::new(1.0)), parry2d_f64::shape::Ball::new(0.0));
    let pos12 = Pose::IDENTITY;
    let mut simplex = VoronoiSimplex::new();
    simplex.reset(CsoPoint::from_shapes(&pos12, &disc, &point, Vector::X));
    if gjk::closest_points(&pos12, &disc, &point, 0.0, true, &mut simplex)
        == GJKResult::Intersection
    {
        let _ = epa.closest_points(&pos12, &disc, &point, &simplex);
    }
    epa
}

/// A unit disc about the origin whose radius grows by one part in 10¹² at every evaluation
/// of its support function. In the EPA of [`grown_epa`] no support point is ever nearer
/// than the best so far (parry's test of a stalled expansion) and the faces of ~100
/// points on a circle stay a sagitta (~5e-4) below the best (its test of convergence),
/// so it runs to its last expansion.
struct Swelling(Cell<Real>);

impl SupportMap for Swelling {
    fn local_support_point(&self, dir: Vector) -> Vector {
        let r = self.0.get();
        self.0.set(r * (1.0 + 1e-12));
        dir.try_normalize().unwrap_or(Vector::X) * r
    }
}

/// `parry2d_f64::query::contact(pos1, g1, pos2, g2, prediction)`, the same numbers, with
/// the EPA of two overlapping support maps kept between calls.
pub fn contact(
    pos1: &Pose,
    g1: &dyn Shape,
    pos2: &Pose,
    g2: &dyn Shape,
    prediction: Real,
) -> Result<Option<Contact>, Unsupported> {
    let pos12 = pos1.inv_mul(pos2);
    let mut result = match support_maps_only(g1, g2) {
        Some((s1, s2)) => Ok(contact_support_maps(&pos12, s1, s2, prediction)),
        None => DefaultQueryDispatcher.contact(&pos12, g1, g2, prediction),
    };
    if let Ok(Some(contact)) = &mut result {
        contact.transform_by_mut(pos1, pos2);
    }
    result
}

/// The two shapes as support maps when parry's dispatcher would send them to its general
/// support-map query: both support maps, and none of the pairs it tries first (two balls,
/// a half-space and a support map, a ball and a convex shape).
fn support_maps_only<'a>(
    g1: &'a dyn Shape,
    g2: &'a dyn Shape,
) -> Option<(&'a dyn SupportMap, &'a dyn SupportMap)> {
    let (ball1, ball2) = (g1.as_ball().is_some(), g2.as_ball().is_some());
    let first = (ball1 && ball2)
        || g1.as_shape::<HalfSpace>().is_some()
        || g2.as_shape::<HalfSpace>().is_some()
        || (ball1 && g2.is_convex())
        || (g1.is_convex() && ball2);
    if first {
        return None;
    }
    Some((g1.as_support_map()?, g2.as_support_map()?))
}

/// parry's `contact_support_map_support_map` (GJK, then EPA inside the difference), with
/// the thread's kept EPA.
fn contact_support_maps(
    pos12: &Pose,
    g1: &dyn SupportMap,
    g2: &dyn SupportMap,
    prediction: Real,
) -> Option<Contact> {
    let simplex = &mut VoronoiSimplex::new();
    let dir = (pos12.translation).try_normalize().unwrap_or(Vector::X);
    simplex.reset(CsoPoint::from_shapes(pos12, g1, g2, dir));
    let mut cpts = gjk::closest_points(pos12, g1, g2, prediction, true, simplex);
    if cpts == GJKResult::Intersection {
        cpts = with_kept(&KEPT_EPA, EPA::new, |epa| {
            epa.closest_points(pos12, g1, g2, simplex)
        })
        .map_or(GJKResult::NoIntersection(Vector::X), |(p1, p2, n)| {
            GJKResult::ClosestPoints(p1, p2, n)
        });
    }
    match cpts {
        GJKResult::ClosestPoints(point1, point2_1, normal1) => {
            let dist = (point2_1 - point1).dot(normal1);
            let point2 = pos12.inverse_transform_point(point2_1);
            let normal2 = pos12.rotation.inverse() * -normal1;
            Some(Contact::new(point1, point2, normal1, normal2, dist))
        }
        _ => None,
    }
}
