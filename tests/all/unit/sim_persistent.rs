//! The unit tests of `sim::persistent` (`src/sim/persistent.rs`).

// The source module's own imports.
use ricochet::contact::{ClosedVertex, ManifoldWorkspace};
use ricochet::math::Real;
use ricochet::sim::Scales;
use ricochet::state::Data;

use ricochet::kinematics::forward_kinematics;
use ricochet::sim::persistent::*;
use ricochet::sim::{MaterialOverride, Simulation};

/// The bundled scene `name`, its simulation's scales, and its kinematics at the initial
/// state.
fn at_start(name: &str) -> (ricochet::scene::Scene, Scales, Data) {
    let path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let scene = ricochet::scene::load(std::path::Path::new(&path)).unwrap();
    let model = &scene.model;
    let sim = Simulation::new(model, &scene.settings, MaterialOverride::default());
    let scales = sim.unwrap().scales();
    let mut data = Data::new(model);
    let (q0, u0) = (&scene.initial.q, &scene.initial.u);
    forward_kinematics(model, &mut data, 0.0, q0.as_slice(), u0.as_slice()).unwrap();
    (scene, scales, data)
}

/// The exact velocity products of vertices on the floor ([`Persistent::vertex_products`])
/// agree with the central differences ([`Persistent::velocity_products`]) at states
/// around the scenes' initial contacts, with speeds of up to 3 (rad/s, m/s): a
/// segment on a revolute joint (Kane's pendulum), a box and a rod on planar joints.
#[test]
fn vertex_products_agree_with_the_differences() {
    for name in ["kane_double_pendulum", "rocking_block", "painleve_rod"] {
        let (scene, scales, mut data) = at_start(name);
        let model = &scene.model;
        let (q0, u0) = (&scene.initial.q, &scene.initial.u);
        // The contact points of every pair at the initial state, as closed points.
        let mut ws = ManifoldWorkspace::default();
        let mut closed = Vec::new();
        for pair in model.pair_ids() {
            for (_, local) in pair_points(model, &data, pair, 1e-6, &mut ws).unwrap() {
                closed.push(Closed {
                    pair,
                    local,
                    hold: Hold::Slide(1.0),
                    slip_margin: 0.0,
                    reference: (0.0, 0.0),
                });
            }
        }
        assert!(!closed.is_empty(), "{name}: no contact point at the start");
        let mut p = Persistent::new(model, scales);
        p.set(closed.clone(), vec![0.3; closed.len()]);
        let mut worst: Real = 0.0;
        for k in 0..20 {
            // A state near the start: small turns, speeds in [−3, 3].
            let wave = |i: usize, f: Real| ((k * 7 + i * 3) as Real * f).sin();
            let q: Vec<Real> = (q0.iter().enumerate())
                .map(|(i, x)| x + 1e-3 * wave(i, 1.3))
                .collect();
            let u: Vec<Real> = (0..u0.len()).map(|i| 3.0 * wave(i, 0.7)).collect();
            let t = 0.01 * k as Real;
            forward_kinematics(model, &mut data, t, &q, &u).unwrap();
            p.set_exact_products(true);
            p.velocity_products(model, &data, (t, &q, &u), Accel::Compute)
                .unwrap();
            assert_eq!(p.planes.len(), closed.len(), "{name}: not the exact path");
            let exact = p.c.clone();
            p.set_exact_products(false);
            p.velocity_products(model, &data, (t, &q, &u), Accel::Compute)
                .unwrap();
            let scale = p.c.amax().max(1.0);
            let err = (&exact - &p.c).amax() / scale;
            worst = worst.max(err);
            assert!(
                err < 1e-10,
                "{name}, state {k}: exact {exact:?} differences {:?}",
                p.c
            );
        }
        println!(
            "{name}: {} points, worst relative difference {worst:.1e}",
            closed.len()
        );
    }
}

/// The cached contact of a closed vertex ([`ClosedVertex::contact`], found once per
/// set of closed points) gives the point of the query ([`PointScratch::point`] without
/// it: the pair's manifold, the candidate nearest the closed point) to the bit — its
/// frame, velocities and Jacobian rows — at 2,000 random states of each bundled
/// scene's polygonal shapes on half-spaces (a segment on a pendulum, a box, a rod, the
/// rimless wheel's spokes): turns of up to ±1.5 rad and shifts of up to ±0.75 m from
/// the start, speeds up to ±3. Where the support feature turned away from the vertex
/// (a box tipped past its side) or the vertex rose beyond the tolerance, it gives
/// none, the query is taken, and the query's nearest point is indeed another vertex or
/// none. A capsule (rounded: its contact point moves on it as it rolls) has no cached
/// vertex.
#[test]
fn closed_vertices_give_the_query_s_points() {
    use crate::unit::contact_manifold::bitwise;
    use crate::unit::linalg::Lcg;
    let mut rng = Lcg(11);
    for name in [
        "kane_double_pendulum",
        "rocking_block",
        "painleve_rod",
        "rimless_wheel",
        "falling_rod",
    ] {
        let (scene, scales, mut data) = at_start(name);
        let (model, tolerance) = (&scene.model, scales.length);
        let (q0, u0) = (&scene.initial.q, &scene.initial.u);
        // Every vertex of the support features at the start, as a closed point.
        let mut ws = ManifoldWorkspace::default();
        let mut closed = Vec::new();
        for pair in model.pair_ids() {
            let p = model.pair_of(pair);
            for (_, local) in pair_points(model, &data, pair, 1e6, &mut ws).unwrap() {
                let v = ClosedVertex::of(model, &p, local, 1e-9 * tolerance, 1e-6 * tolerance);
                closed.push((pair, p, local, v));
            }
        }
        let cached = closed.iter().filter(|c| c.3.is_some()).count();
        if name == "falling_rod" {
            assert!(!closed.is_empty() && cached == 0, "{name}: {closed:?}");
            continue;
        }
        assert_eq!(cached, closed.len(), "{name}: {closed:?}");
        let mut scratch = PointScratch::new(model);
        let (mut taken, mut fallbacks, mut turned) = (0, 0, 0);
        for k in 0..2000 {
            let q: Vec<Real> = q0.iter().map(|x| x + 1.5 * (rng.unit() - 0.5)).collect();
            let u: Vec<Real> = u0.iter().map(|_| 6.0 * (rng.unit() - 0.5)).collect();
            let t = 0.001 * k as Real;
            forward_kinematics(model, &mut data, t, &q, &u).unwrap();
            for &(pair, p, local, v) in &closed {
                let with = scratch.point(model, &data, (pair, &p), (local, v), tolerance);
                let with = with
                    .unwrap()
                    .map(|pt| (pt, scratch.j_n.clone(), scratch.j_t.clone()));
                let query = scratch.point(model, &data, (pair, &p), (local, None), tolerance);
                let query = query
                    .unwrap()
                    .map(|pt| (pt, scratch.j_n.clone(), scratch.j_t.clone()));
                assert!(
                    bitwise(&with, &query),
                    "{name}, state {k}: {with:?} {query:?}"
                );
                let v = v.unwrap();
                if v.contact(model, &data, &p, tolerance).unwrap().is_some() {
                    taken += 1;
                } else {
                    fallbacks += 1;
                    // Within the tolerance of the plane: the feature turned away.
                    let (ca, cb) = (
                        &model.colliders()[p.a.index()],
                        &model.colliders()[p.b.index()],
                    );
                    let body = ca.body.unwrap().index();
                    let x = (data.body_pose[body] * ca.pose).transform_point(v.vertex());
                    let n = cb.pose.rotation * cb.shape.as_halfspace().unwrap().normal;
                    if n.dot(x - cb.pose.translation) <= tolerance {
                        turned += 1;
                    }
                    // The vertex is not the query's point any more.
                    let other = query.map(|(pt, _, _)| pt.local);
                    assert!(
                        other.is_none_or(|l| (l - local).length() > 1e-6 * tolerance),
                        "{name}, state {k}: {other:?} at {local:?}"
                    );
                }
            }
        }
        println!(
            "{name}: {} closed vertices, {taken} cached, {fallbacks} fallbacks ({turned} \
             with the feature turned away)",
            closed.len()
        );
        assert!(taken > 1000, "{name}: {taken} cached");
        if name == "rocking_block" {
            assert!(
                turned > 20,
                "{name}: {turned} fallbacks of a turned feature"
            );
        }
    }
}
