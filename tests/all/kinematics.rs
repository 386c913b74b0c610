//! Kinematics: point positions, velocities and Jacobians against closed forms and against
//! finite differences of point positions.
#![allow(clippy::needless_range_loop)]

use crate::common::model_fixtures as fixtures;

use fixtures::{Rng, TreeOptions, double_pendulum, random_tree};
use nalgebra::Matrix2xX;
use ricochet::kinematics::{
    angular_jacobian, forward_kinematics, point_jacobian, point_velocity, point_world,
    update_positions,
};
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{BodyId, Model};
use ricochet::state::Data;

const DEG: Real = std::f64::consts::PI / 180.0;

/// The world position of the body point `p` (body frame) at `(t, q)`.
fn position(model: &Model, data: &mut Data, body: BodyId, p: Vec2, t: Real, q: &[Real]) -> Vec2 {
    update_positions(model, data, t, q).unwrap();
    point_world(model, data, body, p).unwrap()
}

/// The world angle of `body` relative to its angle at `(t0, q0)`, for small changes.
fn angle_change(
    model: &Model,
    data: &mut Data,
    body: BodyId,
    t: Real,
    q: &[Real],
    reference: Pose,
) -> Real {
    update_positions(model, data, t, q).unwrap();
    let rel = reference.rotation.inverse() * data.body_pose[body.index()].rotation;
    rel.angle()
}

#[test]
fn kane_double_pendulum_velocity_of_approach() {
    // [P, Sect. 5]: at q1 = 20°, q2 = 30°, u1 = −0.1, u2 = −0.2 rad/s, m = 3 kg, l = 2 m,
    // the tip of B moves with v^A = −0.2684 n + 0.5343 t, n = +y (the floor's normal),
    // t = −x (paper/ERRATA.md). Closed form: v = l (u1 cos q1 + u2 cos q2,
    // u1 sin q1 + u2 sin q2).
    let (l, q1, q2, u1, u2) = (2.0, 20.0 * DEG, 30.0 * DEG, -0.1, -0.2);
    let model = double_pendulum(3.0, l, 9.81);
    let mut data = Data::new(&model);
    forward_kinematics(&model, &mut data, 0.0, &[q1, q2], &[u1, u2]).unwrap();
    let rod_b = model.body_by_name("rodB").unwrap();
    let tip = point_world(&model, &data, rod_b, Vec2::new(0.0, -l)).unwrap();
    let tip_closed = Vec2::new(l * (q1.sin() + q2.sin()), -l * (q1.cos() + q2.cos()));
    assert!((tip - tip_closed).length() < 1e-15, "tip {tip:?}");

    let v = point_velocity(&model, &data, rod_b, tip).unwrap();
    let closed = Vec2::new(
        l * (u1 * q1.cos() + u2 * q2.cos()),
        l * (u1 * q1.sin() + u2 * q2.sin()),
    );
    println!("v^B = {:?} (closed form {closed:?})", v.total);
    assert!((v.total - closed).length() < 1e-15);
    assert_eq!(v.remainder, Vec2::ZERO);
    let (n, t) = (Vec2::Y, -Vec2::X);
    assert!(
        (v.total.dot(n) - -0.2684).abs() < 5e-5,
        "v_n^A = {}",
        v.total.dot(n)
    );
    assert!(
        (v.total.dot(t) - 0.5343).abs() < 5e-5,
        "v_t^A = {}",
        v.total.dot(t)
    );

    // J u reproduces it, with the partial velocities l (cos q_i, sin q_i).
    let mut jac = Matrix2xX::zeros(2);
    point_jacobian(&model, &data, rod_b, tip, &mut jac).unwrap();
    for (i, qi) in [q1, q2].into_iter().enumerate() {
        assert!((jac[(0, i)] - l * qi.cos()).abs() < 1e-15);
        assert!((jac[(1, i)] - l * qi.sin()).abs() < 1e-15);
    }
    // Absolute angles: rod B turns with u2 only.
    let mut row = [0.0; 2];
    angular_jacobian(&model, &data, rod_b, &mut row).unwrap();
    assert_eq!(row, [0.0, 1.0]);
}

#[test]
fn point_jacobians_match_finite_differences_of_point_positions() {
    // J[:, r] = ∂p/∂q_r, by central differences of the world position of a body point.
    let h = 1e-6;
    let mut worst: Real = 0.0;
    for seed in 0..200 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let mut rng = Rng::new(1000 + seed);
        let t = rng.uniform(0.0, 3.0);
        let q = rng.vector(model.nq(), 2.0);
        let mut jac = Matrix2xX::zeros(model.nu());
        let mut row = vec![0.0; model.nu()];
        for body in model.body_ids() {
            let p_local = rng.vec2(1.0);
            let p = position(&model, &mut data, body, p_local, t, &q);
            let reference = data.body_pose[body.index()];
            point_jacobian(&model, &data, body, p, &mut jac).unwrap();
            angular_jacobian(&model, &data, body, &mut row).unwrap();
            for r in 0..model.nq() {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[r] += h;
                qm[r] -= h;
                let fd = (position(&model, &mut data, body, p_local, t, &qp)
                    - position(&model, &mut data, body, p_local, t, &qm))
                    / (2.0 * h);
                let col = Vec2::new(jac[(0, r)], jac[(1, r)]);
                let err = (fd - col).length() / (1.0 + col.length());
                worst = worst.max(err);
                assert!(
                    err < 1e-8,
                    "seed {seed} body {body:?} coordinate {r}: J {col:?} FD {fd:?}"
                );
                let dphi = (angle_change(&model, &mut data, body, t, &qp, reference)
                    - angle_change(&model, &mut data, body, t, &qm, reference))
                    / (2.0 * h);
                assert!(
                    (dphi - row[r]).abs() < 1e-8,
                    "seed {seed} body {body:?} ω-row {r}: {} vs FD {dphi}",
                    row[r]
                );
            }
        }
    }
    println!("worst relative Jacobian error {worst:.2e}");
}

#[test]
fn point_velocity_is_the_time_derivative_of_the_position_along_the_motion() {
    // v = J u + v_t = d/dt p(t, q + u (t − t0)), with prescribed joints moving in time;
    // v_t = ∂p/∂t at fixed q (the remainder velocity of [P, Eq. (2)]).
    let h = 1e-6;
    for seed in 0..200 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let mut rng = Rng::new(5000 + seed);
        let t = rng.uniform(0.0, 3.0);
        let q = rng.vector(model.nq(), 2.0);
        let u = rng.vector(model.nu(), 2.0);
        let mut jac = Matrix2xX::zeros(model.nu());
        let uv = nalgebra::DVector::from_column_slice(&u);
        for body in model.body_ids() {
            let p_local = rng.vec2(1.0);
            forward_kinematics(&model, &mut data, t, &q, &u).unwrap();
            let p = point_world(&model, &data, body, p_local).unwrap();
            let v = point_velocity(&model, &data, body, p).unwrap();
            point_jacobian(&model, &data, body, p, &mut jac).unwrap();
            let ju = &jac * &uv;
            let split = Vec2::new(ju[0], ju[1]) + v.remainder;
            assert!(
                (split - v.total).length() < 1e-12 * (1.0 + v.total.length()),
                "seed {seed}: J u + v_t ≠ v"
            );

            let qp: Vec<Real> = q.iter().zip(&u).map(|(q, u)| q + h * u).collect();
            let qm: Vec<Real> = q.iter().zip(&u).map(|(q, u)| q - h * u).collect();
            let fd = (position(&model, &mut data, body, p_local, t + h, &qp)
                - position(&model, &mut data, body, p_local, t - h, &qm))
                / (2.0 * h);
            assert!(
                (fd - v.total).length() < 1e-7 * (1.0 + fd.length()),
                "seed {seed} body {body:?}: v {:?} FD {fd:?}",
                v.total
            );
            let fd_t = (position(&model, &mut data, body, p_local, t + h, &q)
                - position(&model, &mut data, body, p_local, t - h, &q))
                / (2.0 * h);
            assert!(
                (fd_t - v.remainder).length() < 1e-7 * (1.0 + fd_t.length()),
                "seed {seed} body {body:?}: v_t {:?} FD {fd_t:?}",
                v.remainder
            );
        }
    }
}

#[test]
fn kinematics_reports_wrong_sizes_and_unknown_bodies() {
    let model = double_pendulum(3.0, 2.0, 9.81);
    let mut data = Data::new(&model);
    let err = update_positions(&model, &mut data, 0.0, &[0.0]).unwrap_err();
    assert_eq!(err.to_string(), "q has length 1, expected 2");
    let other = fixtures::chain(5, 1.0, 1.0, 9.81);
    let far = other.body_ids().last().unwrap();
    assert!(point_world(&model, &data, far, Vec2::ZERO).is_err());
    let mut jac = Matrix2xX::zeros(3);
    assert!(
        point_jacobian(
            &model,
            &data,
            model.body_ids().next().unwrap(),
            Vec2::ZERO,
            &mut jac
        )
        .is_err()
    );
}

/// `Data::copy_kinematics_from` gives, bit for bit, what `update_positions` and
/// `update_velocities` write at the source's state (the sharing of the right-hand side's
/// kinematics with the event functions and the broad phase rests on it): every bundled
/// scene (revolute chains, free bodies, prescribed drives, the nonholonomic blades of the
/// sleigh and the wagon), at its initial state and at perturbed states and times, the
/// source evaluated by the forward dynamics as the right-hand side does, the destination
/// holding another state's kinematics before the copy.
#[test]
fn copied_kinematics_are_the_computed_ones_bit_for_bit() {
    use ricochet::dynamics::forward_dynamics;
    use ricochet::kinematics::update_velocities;
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let mut rng = Rng::new(0x5eed_c0de);
    let mut scenes = 0;
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    for path in paths {
        let scene = ricochet::scene::load(&path).unwrap();
        let model = &scene.model;
        let (q0, u0) = (scene.initial.q.as_slice(), scene.initial.u.as_slice());
        let mut source = Data::new(model);
        let mut copy = Data::for_kinematics(model);
        let mut computed = Data::new(model);
        for k in 0..6 {
            let perturb = |x: &[Real], rng: &mut Rng, scale: Real| -> Vec<Real> {
                x.iter()
                    .map(|&v| v + scale * rng.uniform(-1.0, 1.0))
                    .collect()
            };
            let scale = if k == 0 { 0.0 } else { 0.05 };
            let (q, u) = (perturb(q0, &mut rng, scale), perturb(u0, &mut rng, scale));
            let t = 0.37 * k as Real;
            // The copy's former content: another state's kinematics.
            let (qa, ua) = (perturb(q0, &mut rng, 0.1), perturb(u0, &mut rng, 0.1));
            update_positions(model, &mut copy, t + 1.0, &qa).unwrap();
            update_velocities(model, &mut copy, &ua).unwrap();
            forward_dynamics(model, &mut source, t, &q, &u).unwrap();
            copy.copy_kinematics_from(&source);
            update_positions(model, &mut computed, t, &q).unwrap();
            update_velocities(model, &mut computed, &u).unwrap();
            let bits = |d: &Data| {
                format!(
                    "{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
                    d.time.to_bits(),
                    d.joint_q,
                    d.joint_qd,
                    d.joint_qdd_prescribed,
                    d.joint_frame,
                    d.subspace,
                    d.body_pose,
                    d.body_com,
                    d.body_inertia,
                    d.body_twist,
                    d.body_twist_remainder,
                    d.body_accel_vp,
                    d.constraint_frame,
                    d.constraint_rows,
                    d.constraint_lu,
                    d.constraint_pivots,
                    d.speed_map,
                    d.tree_speed,
                )
            };
            assert_eq!(
                bits(&copy),
                bits(&computed),
                "{}: state {k}",
                path.display()
            );
            // And what is read from them: the world velocity of a body point.
            for body in model.body_ids() {
                let p = Vec2::new(0.3, -0.2);
                let (vc, vd) = (
                    ricochet::kinematics::point_velocity(model, &copy, body, p).unwrap(),
                    ricochet::kinematics::point_velocity(model, &computed, body, p).unwrap(),
                );
                assert_eq!(
                    (vc.total.x.to_bits(), vc.total.y.to_bits()),
                    (vd.total.x.to_bits(), vd.total.y.to_bits())
                );
            }
        }
        scenes += 1;
    }
    assert!(scenes >= 14, "only {scenes} scenes");
}
