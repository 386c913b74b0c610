//! No missed events: randomized drops of a free planar body (balls, capsules down to 1 mm
//! thick, segments of zero thickness, boxes, triangles), fast, spinning or grazing, onto
//! half-spaces, zero-thickness segments and thin slabs. The simulator's first impact is
//! compared with an independent determination of the first contact.
//!
//! The reference uses neither the integrator, nor the event locator, nor the model: the
//! free flight is analytic (`x = x0 + vx t`, `y = y0 + vy t − ½ g t²`, `θ = θ0 + ω t`), the
//! distance is parry2d's (GJK), and the first contact is found by *conservative advancement*: from a
//! gap `g > 0`, no point of the body moves faster than `B = |v_c|max + |ω| R` (R the
//! body's radius about its centre), so no contact can happen before `t + g/B`. Stepping
//! by `g/B` never passes the first contact; it stops when `g < 1e-11` m.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use parry2d_f64::query;
use parry2d_f64::shape::{Ball, Capsule, ConvexPolygon, Cuboid, HalfSpace, Segment, SharedShape};
use ricochet::impact::Law;
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{Body, Collider, Joint, Material, Model};
use ricochet::settings::{IntegratorSettings, Settings};
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, Sample, Simulation,
};
use ricochet::state::State;

const G: Real = 9.81;

use crate::common::rng;
use rng::Rng;

/// One drop: a body shape, its initial pose and velocity, an obstacle.
struct Drop {
    kind: &'static str,
    shape: SharedShape,
    obstacle: SharedShape,
    obstacle_pose: Pose,
    q0: [Real; 3],
    u0: [Real; 3],
    t_max: Real,
}

fn body_shape(rng: &mut Rng, thin: bool) -> SharedShape {
    let s = rng.range(0.05, 0.5);
    let r = if thin { 1e-3 } else { rng.range(0.01, 0.2) };
    match rng.pick(5) {
        0 => SharedShape::new(Ball::new(r.max(0.02))),
        1 => SharedShape::new(Capsule::new_x(s, r)),
        2 => SharedShape::new(Segment::new(Vec2::new(-s, 0.0), Vec2::new(s, 0.1 * s))),
        3 => SharedShape::new(Cuboid::new(Vec2::new(s, if thin { 1e-3 } else { 0.3 * s }))),
        _ => SharedShape::new(
            ConvexPolygon::from_convex_polyline(vec![
                Vec2::new(-s, -0.4 * s),
                Vec2::new(s, -0.2 * s),
                Vec2::new(0.1 * s, 0.7 * s),
            ])
            .unwrap(),
        ),
    }
}

/// The pose of the body at `t` in free flight.
fn pose_at(d: &Drop, t: Real) -> Pose {
    Pose::new(
        Vec2::new(
            d.q0[0] + d.u0[0] * t,
            d.q0[1] + d.u0[1] * t - 0.5 * G * t * t,
        ),
        d.q0[2] + d.u0[2] * t,
    )
}

/// The distance between the body and the obstacle at `t` (0 when they overlap):
/// parry's GJK alone, which conservative advancement needs only while they are apart.
fn gap(d: &Drop, t: Real) -> Real {
    query::distance(
        &d.obstacle_pose,
        &*d.obstacle.0,
        &pose_at(d, t),
        &*d.shape.0,
    )
    .unwrap()
    .distance
}

/// The first contact by conservative advancement, or `None` before `t_max`.
fn first_contact(d: &Drop) -> Option<Real> {
    let bs = d.shape.compute_local_bounding_sphere();
    let radius = bs.center().length() + bs.radius();
    let speed = |t: Real| {
        let vy = d.u0[1].abs() + G * t;
        (d.u0[0] * d.u0[0] + vy * vy).sqrt() + d.u0[2].abs() * radius
    };
    let mut t = 0.0;
    for _ in 0..50_000_000u64 {
        let g = gap(d, t);
        if g < 1e-11 {
            return Some(t);
        }
        // A bound on the closing speed over the next step, at its end (speeds only grow).
        let mut dt = g / speed(t);
        while g / speed(t + dt) < dt {
            dt = g / speed(t + dt);
        }
        t += dt;
        if t > d.t_max {
            return None;
        }
    }
    panic!("conservative advancement did not converge for {}", d.kind);
}

fn make_drop(rng: &mut Rng, k: usize) -> Drop {
    let floor = (SharedShape::new(HalfSpace::new(Vec2::Y)), Pose::identity());
    match k % 5 {
        // A: any shape, random spin and velocity, onto a floor.
        0 => Drop {
            kind: "drop",
            shape: body_shape(rng, false),
            obstacle: floor.0,
            obstacle_pose: floor.1,
            q0: [
                rng.range(-1.0, 1.0),
                rng.range(0.8, 2.0),
                rng.range(-3.2, 3.2),
            ],
            u0: [
                rng.range(-3.0, 3.0),
                rng.range(-5.0, 3.0),
                rng.range(-10.0, 10.0),
            ],
            t_max: 2.0,
        },
        // B: fast and thin through a zero-thickness segment or a 2 mm slab.
        1 => {
            let obstacle = if rng.next() < 0.5 {
                SharedShape::new(Segment::new(Vec2::new(-2.0, 0.0), Vec2::new(2.0, 0.0)))
            } else {
                SharedShape::new(Cuboid::new(Vec2::new(2.0, 1e-3)))
            };
            Drop {
                kind: "fast thin",
                shape: body_shape(rng, true),
                obstacle,
                obstacle_pose: Pose::identity(),
                q0: [
                    rng.range(-0.5, 0.5),
                    rng.range(0.6, 1.5),
                    rng.range(-3.2, 3.2),
                ],
                u0: [
                    rng.range(-5.0, 5.0),
                    rng.range(-60.0, -20.0),
                    rng.range(-5.0, 5.0),
                ],
                t_max: 0.2,
            }
        }
        // C: a spinning rod above the floor, its ends sweeping down.
        2 => {
            let half = rng.range(0.2, 0.6);
            Drop {
                kind: "spinning rod",
                shape: SharedShape::new(Capsule::new_x(half, 5e-3)),
                obstacle: floor.0,
                obstacle_pose: floor.1,
                q0: [0.0, half + rng.range(0.02, 0.3), rng.range(-3.2, 3.2)],
                u0: [
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-80.0, 80.0),
                ],
                t_max: 1.0,
            }
        }
        // D: grazing — a ball thrown straight up passes under a tilted ceiling with a
        // clearance of ±1 µm at its apex. The ceiling's plane through (0, c) with normal
        // (sin τ, −cos τ) is at distance cos τ (c − y) from the centre (0, y), least at the
        // apex y_top = y0 + vy²/(2g): clearance δ needs c = y_top + (r + δ)/cos τ.
        3 => {
            let r = rng.range(0.05, 0.2);
            let (y0, vy) = (rng.range(0.0, 0.5), rng.range(1.0, 4.0));
            let y_top = y0 + vy * vy / (2.0 * G);
            let clearance = if rng.next() < 0.5 { 1e-6 } else { -1e-6 };
            let tilt = rng.range(-0.3, 0.3);
            Drop {
                kind: if clearance > 0.0 {
                    "grazing miss"
                } else {
                    "grazing touch"
                },
                shape: SharedShape::new(Ball::new(r)),
                obstacle: SharedShape::new(HalfSpace::new(Vec2::new(0.0, -1.0))),
                obstacle_pose: Pose::new(
                    Vec2::new(0.0, y_top + (r + clearance) / tilt.cos()),
                    tilt,
                ),
                q0: [0.0, y0, 0.0],
                u0: [0.0, vy, rng.range(-5.0, 5.0)],
                t_max: 2.0 * vy / G,
            }
        }
        // E: a tilted floor, boxes and triangles tumbling onto it.
        _ => Drop {
            kind: "tilted floor",
            shape: body_shape(rng, false),
            obstacle: SharedShape::new(HalfSpace::new(Vec2::Y)),
            obstacle_pose: Pose::new(Vec2::ZERO, rng.range(-0.6, 0.6)),
            q0: [
                rng.range(-0.5, 0.5),
                rng.range(1.0, 2.0),
                rng.range(-3.2, 3.2),
            ],
            u0: [
                rng.range(-2.0, 2.0),
                rng.range(-3.0, 1.0),
                rng.range(-20.0, 20.0),
            ],
            t_max: 2.0,
        },
    }
}

/// Records the first impact and stops the run there.
struct FirstImpact {
    t: Option<Real>,
    stop: Arc<AtomicBool>,
}

impl Observer for FirstImpact {
    fn wants_samples(&self) -> bool {
        false
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        Ok(())
    }
    fn impact(&mut self, _: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        self.t.get_or_insert(ev.t);
        self.stop.store(true, Ordering::Relaxed);
        Ok(())
    }
    fn message(&mut self, _: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        Ok(())
    }
}

fn simulate(d: &Drop) -> Option<Real> {
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.0, -G)).default_material(Material {
        law: Law::Newton,
        e: 0.5,
        mu: 0.3,
    });
    let body = b.add_body(
        Body::new("body", 1.0, Vec2::ZERO, 0.01),
        Joint::planar("body", None, Pose::identity()),
    );
    b.add_collider(Collider::new(
        "shape",
        Some(body),
        d.shape.clone(),
        Pose::identity(),
    ));
    b.add_collider(Collider::new(
        "obstacle",
        None,
        d.obstacle.clone(),
        d.obstacle_pose,
    ));
    let model = b.build().unwrap();
    let settings = Settings {
        t_end: d.t_max,
        output_rate: 0.0,
        max_drift: None,
        simultaneous: Default::default(),
        integrator: IntegratorSettings::default(),
    };
    let mut sim = Simulation::new(&model, &settings, MaterialOverride::default()).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let mut obs = FirstImpact {
        t: None,
        stop: Arc::clone(&stop),
    };
    let state = State::new(0.0, d.q0.to_vec().into(), d.u0.to_vec().into());
    let summary = sim.run(&state, &mut obs, Some(&stop));
    if let ricochet::sim::StopReason::Failed(e) = summary.stop {
        panic!(
            "{}: {e} ({:?} on {:?} at {:?}, q0 {:?}, u0 {:?})",
            d.kind,
            d.shape.as_cuboid().map(|c| c.half_extents),
            d.obstacle.shape_type(),
            d.obstacle_pose,
            d.q0,
            d.u0
        );
    }
    obs.t
}

#[test]
fn a_thousand_drops_find_their_first_contact() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut n, mut worst, mut counts) = (0, 0.0f64, std::collections::BTreeMap::new());
    let mut k = 0;
    while n < 1000 {
        let d = make_drop(&mut rng, k);
        k += 1;
        if gap(&d, 0.0) < 1e-3 {
            continue; // starts in contact: not a drop
        }
        let reference = first_contact(&d);
        let sim = simulate(&d);
        match (reference, sim) {
            (Some(tr), Some(ts)) => {
                let err = (ts - tr).abs();
                assert!(
                    err <= 1e-7,
                    "{} #{k}: first contact at {tr}, simulator at {ts}",
                    d.kind
                );
                worst = worst.max(err);
            }
            (None, None) => {}
            (r, s) => panic!("{} #{k}: reference {r:?}, simulator {s:?}", d.kind),
        }
        *counts.entry((d.kind, reference.is_some())).or_insert(0) += 1;
        n += 1;
    }
    println!("{n} drops, worst time difference {worst:.2e} s; (kind, contact) counts: {counts:?}");
    // Every kind was exercised, with and without contact where it applies.
    assert!(counts[&("grazing touch", true)] > 50 && counts[&("grazing miss", false)] > 50);
    assert!(counts[&("fast thin", true)] > 100 && counts[&("spinning rod", true)] > 100);
}
