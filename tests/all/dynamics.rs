//! Dynamics: the mass matrix against the closed form of the paper's double pendulum and
//! against the kinetic energy, the bias forces against a finite-difference Lagrangian and a
//! second Newton–Euler route, the energy balance with dampers, efforts and drives, energy
//! conservation in free flight, and invariance under rigid motions of the whole scene.
#![allow(clippy::needless_range_loop)]

use crate::common::model_fixtures as fixtures;

use fixtures::{Rng, TreeOptions, chain, double_pendulum, random_tree};
use nalgebra::{DMatrix, DVector};
use ricochet::dynamics::{
    DynamicsError, bias_forces, energy, factor_mass, factor_mass_matrix, forward_dynamics,
    forward_dynamics_with, inverse_dynamics, mass_matrix, ode_rhs, power, solve_mass,
};
use ricochet::kinematics::{
    forward_kinematics, point_velocity, point_world, update_positions, update_velocities,
    velocity_product_accelerations,
};
use ricochet::math::{Pose, Real, Vec2, perp};
use ricochet::model::{Body, Joint, Model};
use ricochet::state::Data;

const DEG: Real = std::f64::consts::PI / 180.0;

/// `M(q)` at `(t, q)`.
fn mass_at(model: &Model, data: &mut Data, t: Real, q: &[Real]) -> DMatrix<Real> {
    update_positions(model, data, t, q).unwrap();
    mass_matrix(model, data);
    data.mass.to_dense()
}

/// `h(t, q, u)`.
fn bias_at(model: &Model, data: &mut Data, t: Real, q: &[Real], u: &[Real]) -> DVector<Real> {
    forward_kinematics(model, data, t, q, u).unwrap();
    bias_forces(model, data);
    data.bias.clone()
}

fn kinetic(model: &Model, data: &mut Data, t: Real, q: &[Real], u: &[Real]) -> Real {
    energy(model, data, t, q, u).unwrap().kinetic
}

fn potential(model: &Model, data: &mut Data, t: Real, q: &[Real]) -> Real {
    let zero = vec![0.0; model.nu()];
    energy(model, data, t, q, &zero).unwrap().potential
}

fn max_abs(m: &DMatrix<Real>) -> Real {
    m.iter().fold(0.0, |a: Real, x| a.max(x.abs()))
}

#[test]
fn double_pendulum_mass_matrix_is_the_closed_form() {
    // Two uniform rods (m, l), absolute angles from the downward vertical. With
    // T = ½ m (l/2)² u1² + ½ (m l²/12) u1² + ½ m |l u1 e(q1) + (l/2) u2 e(q2)|² + ½ (m l²/12) u2²,
    // e(q) = (cos q, sin q):
    //   M = m l² [[4/3, ½ cos(q1 − q2)], [½ cos(q1 − q2), 1/3]],
    // which is minus the matrix of the paper's equations of motion [P, Sect. 5]:
    //   −⅓ m l² [4 u̇1 + (3/2) cos(q1 − q2) u̇2 + …], −⅓ m l² [(3/2) cos(q1 − q2) u̇1 + u̇2 − …].
    let (m, l) = (3.0, 2.0);
    let model = double_pendulum(m, l, 9.81);
    let mut data = Data::new(&model);
    let mut rng = Rng::new(7);
    let mut states = vec![[20.0 * DEG, 30.0 * DEG]];
    states.extend((0..50).map(|_| [rng.uniform(-4.0, 4.0), rng.uniform(-4.0, 4.0)]));
    for q in states {
        let mass = mass_at(&model, &mut data, 0.0, &q);
        let c = (q[0] - q[1]).cos();
        let closed =
            DMatrix::from_row_slice(2, 2, &[4.0 / 3.0, 0.5 * c, 0.5 * c, 1.0 / 3.0]) * (m * l * l);
        assert!(
            max_abs(&(&mass - &closed)) < 1e-13,
            "q = {q:?}\nM = {mass}\nclosed = {closed}"
        );
    }
    // At the impact state: m l² = 12 kg·m², M = [[16, 5.9772], [5.9772, 4]].
    let mass = mass_at(&model, &mut data, 0.0, &[20.0 * DEG, 30.0 * DEG]);
    println!("M(20°, 30°) = {mass}");
    assert!((mass[(0, 1)] - 6.0 * (10.0 * DEG).cos()).abs() < 1e-13);
}

#[test]
fn double_pendulum_bias_is_the_closed_form() {
    // From the paper's equations [P, Sect. 5] (velocity products) plus gravity
    // V = −(3/2) m g l cos q1 − ½ m g l cos q2:
    //   h1 =  ½ m l² sin(q1 − q2) u2² + (3/2) m g l sin q1
    //   h2 = −½ m l² sin(q1 − q2) u1² + ½ m g l sin q2
    let (m, l, g) = (3.0, 2.0, 9.81);
    let model = double_pendulum(m, l, g);
    let mut data = Data::new(&model);
    let mut rng = Rng::new(8);
    for _ in 0..50 {
        let q = [rng.uniform(-4.0, 4.0), rng.uniform(-4.0, 4.0)];
        let u = [rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0)];
        let h = bias_at(&model, &mut data, 0.0, &q, &u);
        let s = (q[0] - q[1]).sin();
        let h1 = 0.5 * m * l * l * s * u[1] * u[1] + 1.5 * m * g * l * q[0].sin();
        let h2 = -0.5 * m * l * l * s * u[0] * u[0] + 0.5 * m * g * l * q[1].sin();
        assert!(
            (h[0] - h1).abs() < 1e-12 && (h[1] - h2).abs() < 1e-12,
            "q {q:?} u {u:?}: h {h} vs ({h1}, {h2})"
        );
    }
}

#[test]
fn relative_angles_give_the_transformed_mass_matrix() {
    // The same pendulum with the angle of B measured from A: φ = (q1, q1 + q2) = T q,
    // T = [[1, 0], [1, 1]], so M_rel(q) = Tᵀ M_abs(T q) T.
    let (m, l) = (3.0, 2.0);
    let mut b = Model::builder();
    let rod = |name: &str| Body::new(name, m, Vec2::new(0.0, -l / 2.0), m * l * l / 12.0);
    let a = b.add_body(rod("rodA"), Joint::revolute("rodA", None, Pose::identity()));
    b.add_body(
        rod("rodB"),
        Joint::revolute("rodB", Some(a), Pose::translation(0.0, -l)),
    );
    let relative = b.build().unwrap();
    let absolute = double_pendulum(m, l, 0.0);
    let (mut dr, mut da) = (Data::new(&relative), Data::new(&absolute));
    let t = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 1.0, 1.0]);
    let mut rng = Rng::new(9);
    for _ in 0..20 {
        let q = [rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0)];
        let m_rel = mass_at(&relative, &mut dr, 0.0, &q);
        let m_abs = mass_at(&absolute, &mut da, 0.0, &[q[0], q[0] + q[1]]);
        let expected = t.transpose() * m_abs * &t;
        assert!(max_abs(&(&m_rel - &expected)) < 1e-12);
    }
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_the_hessian_of_the_kinetic_energy() {
    // Without prescribed motion T = ½ uᵀ M u, so by polarization
    // M_rs = T(e_r + e_s) − T(e_r) − T(e_s), with T from the body sum of [P, Eq. (70)].
    let mut rng = Rng::new(10);
    for seed in 0..300 {
        let opts = TreeOptions {
            prescribed: false,
            ..TreeOptions::EVERYTHING
        };
        let model = random_tree(seed, opts, Pose::identity());
        let mut data = Data::new(&model);
        let n = model.nu();
        let q = rng.vector(n, 3.0);
        let mass = mass_at(&model, &mut data, 0.0, &q);
        assert_eq!(mass, mass.transpose(), "seed {seed}: M not symmetric");
        let eig = mass.clone().symmetric_eigenvalues();
        assert!(eig.min() > 0.0, "seed {seed}: eigenvalues {eig}");
        let unit = |r: usize| {
            (0..n)
                .map(|i| if i == r { 1.0 } else { 0.0 })
                .collect::<Vec<_>>()
        };
        for r in 0..n {
            for s in 0..n {
                let ers: Vec<Real> = unit(r).iter().zip(unit(s)).map(|(a, b)| a + b).collect();
                let polar = kinetic(&model, &mut data, 0.0, &q, &ers)
                    - kinetic(&model, &mut data, 0.0, &q, &unit(r))
                    - kinetic(&model, &mut data, 0.0, &q, &unit(s));
                let expected = if r == s {
                    2.0 * kinetic(&model, &mut data, 0.0, &q, &unit(r))
                } else {
                    polar
                };
                assert!(
                    (mass[(r, s)] - expected).abs() < 1e-11 * (1.0 + max_abs(&mass)),
                    "seed {seed} M[{r},{s}] = {} vs {expected}",
                    mass[(r, s)]
                );
            }
        }
    }
}

#[test]
fn mass_matrix_sets_every_stored_entry() {
    // `mass_matrix` does not zero the tree matrix before the composite rigid body
    // algorithm (every stored entry, `(r, c)` with `c = r` or an ancestor of `r`, is
    // written): storage left full of NaN by anything before must give the matrix of a
    // fresh workspace, bit for bit, on trees of every joint kind.
    let mut rng = Rng::new(11);
    for seed in 0..300 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let q = rng.vector(model.nq(), 3.0);
        let fresh = mass_at(&model, &mut Data::new(&model), 0.5, &q);
        let mut data = Data::new(&model);
        data.mass.allocate();
        for r in 0..data.mass.nrows() {
            data.mass.row_mut(r).fill(Real::NAN);
        }
        let reused = mass_at(&model, &mut data, 0.5, &q);
        assert!(
            fresh
                .iter()
                .zip(reused.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "seed {seed}: {reused} vs {fresh}"
        );
    }
}

/// Forward dynamics by its stages, each a walk over the tree: kinematics, `h`, the factor of
/// `M`, then `u̇ = M⁻¹ (τ − h)` by [`solve_mass`].
fn forward_dynamics_by_stages(
    model: &Model,
    data: &mut Data,
    (t, q, u): (Real, &[Real], &[Real]),
    tau: Option<&[Real]>,
) -> Result<(), DynamicsError> {
    update_positions(model, data, t, q)?;
    update_velocities(model, data, u)?;
    bias_forces(model, data);
    factor_mass(model, data, t)?;
    let mut x: Vec<Real> = match tau {
        Some(tau) => tau
            .iter()
            .zip(data.bias.iter())
            .map(|(f, h)| f - h)
            .collect(),
        None => data.bias.iter().map(|h| 0.0 - h).collect(),
    };
    solve_mass(data, &mut x)?;
    data.udot.copy_from_slice(&x);
    Ok(())
}

/// A chain of `n` links hanging from the origin, each angle measured from the world (the
/// paper's double pendulum for `n = 2`).
fn absolute_chain(n: usize) -> Model {
    let mut b = Model::builder();
    b.gravity(Vec2::new(0.3, -9.81));
    let mut parent = None;
    for i in 0..n {
        let name = format!("link{i}");
        let body = Body::new(&name, 1.0 + 0.1 * i as Real, Vec2::new(0.05, -0.4), 0.06);
        let joint = match parent {
            None => Joint::revolute(&name, None, Pose::identity()),
            Some(_) => Joint::revolute_absolute(&name, parent, Pose::translation(0.0, -0.8)),
        };
        parent = Some(b.add_body(body, joint));
    }
    b.build().expect("absolute chain")
}

/// Every number [`forward_dynamics_with`] writes, as text (Rust's shortest round-trip
/// representation: equal strings are equal numbers, `−0` included).
fn written_by_forward_dynamics(data: &Data) -> Vec<String> {
    vec![
        format!("time {:?}", data.time),
        format!("joint_q {:?}", data.joint_q),
        format!("joint_qd {:?}", data.joint_qd),
        format!("joint_qdd_prescribed {:?}", data.joint_qdd_prescribed),
        format!("joint_frame {:?}", data.joint_frame),
        format!("subspace {:?}", data.subspace),
        format!("body_pose {:?}", data.body_pose),
        format!("body_com {:?}", data.body_com),
        format!("body_inertia {:?}", data.body_inertia),
        format!("body_twist {:?}", data.body_twist),
        format!("body_twist_remainder {:?}", data.body_twist_remainder),
        format!("body_accel_vp {:?}", data.body_accel_vp),
        format!("body_accel {:?}", data.body_accel),
        format!("body_wrench {:?}", data.body_wrench),
        format!("composite {:?}", data.composite),
        format!("joint_effort {:?}", data.joint_effort),
        format!("mass {:?}", data.mass.values()),
        format!("bias {:?}", data.bias.as_slice()),
        format!("udot {:?}", data.udot.as_slice()),
    ]
}

#[test]
fn forward_dynamics_is_its_stages_bit_for_bit() {
    // `forward_dynamics_with` walks a holonomic tree once down and once up, computing the
    // kinematics, the Newton–Euler pass, the composite inertias and the rows of M together
    // (and factors and solves two speeds on the stack); the stages walk it four times. Both
    // must write the same numbers to the bit — kinematics, Newton–Euler scratch, composite
    // inertias, M, h, u̇, and the factor (a solve with it) — on random trees of every joint
    // kind with drives, springs, dampers and efforts, on chains of relative and of absolute
    // angles of 1 to 10 links (the 2 × 2, dense, sparse and articulated factors), with and
    // without a generalized force, each workspace reused from state to state.
    let mut models: Vec<Model> = (0..400)
        .map(|seed| random_tree(seed, TreeOptions::EVERYTHING, Pose::identity()))
        .collect();
    for n in 1..=10 {
        models.push(chain(n, 1.5, 0.7, 9.81));
        models.push(absolute_chain(n));
    }
    models.push(double_pendulum(3.0, 2.0, 9.81));
    let mut rng = Rng::new(29);
    let mut two_speeds = 0;
    for (m, model) in models.iter().enumerate() {
        let (mut fused, mut staged) = (Data::new(model), Data::new(model));
        two_speeds += usize::from(model.nu() == 2 && model.is_holonomic());
        for case in 0..6 {
            let t = rng.uniform(0.0, 3.0);
            let q = rng.vector(model.nq(), 3.0);
            let u = rng.vector(model.nu(), 3.0);
            let tau = rng.vector(model.nu(), 5.0);
            let tau = (case % 2 == 1).then_some(tau.as_slice());
            let a = forward_dynamics_with(model, &mut fused, t, &q, &u, tau);
            let b = forward_dynamics_by_stages(model, &mut staged, (t, &q, &u), tau);
            assert_eq!(a, b, "model {m} case {case}");
            assert_eq!(
                written_by_forward_dynamics(&fused),
                written_by_forward_dynamics(&staged),
                "model {m} case {case}"
            );
            let rhs = rng.vector(model.nu(), 1.0);
            let (mut x, mut y) = (rhs.clone(), rhs);
            assert_eq!(
                solve_mass(&mut fused, &mut x),
                solve_mass(&mut staged, &mut y)
            );
            assert_eq!(format!("{x:?}"), format!("{y:?}"), "model {m} case {case}");
        }
    }
    assert!(two_speeds > 20, "only {two_speeds} models of two speeds");
}

#[test]
fn forward_dynamics_leaves_the_velocity_product_accelerations() {
    // Persistent contact takes the bodies' spatial accelerations at u̇ = 0 (the velocity
    // products of its closed vertices) from `data.body_accel` after the forward dynamics of
    // a holonomic model, instead of `velocity_product_accelerations`: they must be its
    // numbers to the bit — on random holonomic trees of every joint kind with drives (their
    // prescribed q̈ in the sums), springs, dampers and efforts, and on chains of relative and
    // of absolute angles (the fused pass, the dense, sparse and articulated factors), with
    // and without a generalized force, each workspace reused from state to state.
    let mut models: Vec<Model> = (0..400)
        .map(|seed| random_tree(seed, TreeOptions::EVERYTHING, Pose::identity()))
        .filter(Model::is_holonomic)
        .collect();
    for n in 1..=10 {
        models.push(chain(n, 1.5, 0.7, 9.81));
        models.push(absolute_chain(n));
    }
    models.push(double_pendulum(3.0, 2.0, 9.81));
    assert!(models.len() > 150, "only {} holonomic models", models.len());
    let mut rng = Rng::new(31);
    let bits = |a: &[ricochet::model::spatial::Twist]| -> Vec<[u64; 3]> {
        (a.iter())
            .map(|t| [t.w.to_bits(), t.v.x.to_bits(), t.v.y.to_bits()])
            .collect()
    };
    let (mut driven, mut compared) = (0, 0);
    for (m, model) in models.iter().enumerate() {
        let mut data = Data::new(model);
        let mut out = vec![ricochet::model::spatial::Twist::ZERO; model.bodies().len()];
        driven += usize::from(model.joints().iter().any(|j| j.drive.is_some()));
        for case in 0..6 {
            let t = rng.uniform(0.0, 3.0);
            let q = rng.vector(model.nq(), 3.0);
            let u = rng.vector(model.nu(), 3.0);
            let tau = rng.vector(model.nu(), 5.0);
            let tau = (case % 2 == 1).then_some(tau.as_slice());
            if forward_dynamics_with(model, &mut data, t, &q, &u, tau).is_err() {
                continue;
            }
            velocity_product_accelerations(model, &data, &mut out);
            assert_eq!(bits(&data.body_accel), bits(&out), "model {m} case {case}");
            compared += 1;
        }
    }
    assert!(driven > 20, "only {driven} driven models");
    assert!(compared > 6 * 150, "only {compared} states compared");
}

#[test]
fn bias_forces_match_a_finite_difference_lagrangian() {
    // Lagrange's equations with L = T − V, p = ∂T/∂u (T of [P, Eq. (70)], prescribed
    // motions included):  M u̇ + h = τ  with
    //   h = ∂p/∂t + (∂p/∂q) u − ∂T/∂q + ∂V/∂q − Q_nc,   Q_nc = −c q̇ + τ_joint.
    // p by central differences of T in u (exact for a quadratic), its derivative along
    // (t, q) ↦ (t + δ, q + δ u), ∂T/∂q and ∂V/∂q by central differences.
    let mut worst: Real = 0.0;
    for seed in 0..300 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let n = model.nu();
        let mut rng = Rng::new(2000 + seed);
        let t = rng.uniform(0.0, 2.0);
        let q = rng.vector(n, 2.0);
        let u = rng.vector(n, 2.0);
        let h = bias_at(&model, &mut data, t, &q, &u);

        let shifted = |v: &[Real], dir: &[Real], s: Real| -> Vec<Real> {
            v.iter().zip(dir).map(|(a, b)| a + s * b).collect()
        };
        let unit = |r: usize| {
            (0..n)
                .map(|i| if i == r { 1.0 } else { 0.0 })
                .collect::<Vec<Real>>()
        };
        let momentum = |data: &mut Data, t: Real, q: &[Real], r: usize| {
            let d = 0.5;
            (kinetic(&model, data, t, q, &shifted(&u, &unit(r), d))
                - kinetic(&model, data, t, q, &shifted(&u, &unit(r), -d)))
                / (2.0 * d)
        };
        let (dt, dq) = (1e-5, 1e-6);
        let mut expected = vec![0.0; n];
        for r in 0..n {
            let dp = (momentum(&mut data, t + dt, &shifted(&q, &u, dt), r)
                - momentum(&mut data, t - dt, &shifted(&q, &u, -dt), r))
                / (2.0 * dt);
            let dtdq = (kinetic(&model, &mut data, t, &shifted(&q, &unit(r), dq), &u)
                - kinetic(&model, &mut data, t, &shifted(&q, &unit(r), -dq), &u))
                / (2.0 * dq);
            let dvdq = (potential(&model, &mut data, t, &shifted(&q, &unit(r), dq))
                - potential(&model, &mut data, t, &shifted(&q, &unit(r), -dq)))
                / (2.0 * dq);
            expected[r] = dp - dtdq + dvdq;
        }
        // Non-conservative joint forces.
        for body in model.body_ids() {
            let joint = model.joint(body.joint()).unwrap();
            if let (Some(s), 1) = (model.q_index(body.joint()), joint.kind.ndof()) {
                expected[s] -= -joint.force.damping * u[s] + joint.force.effort;
            }
        }
        let scale = 1.0 + h.amax();
        for r in 0..n {
            let err = (h[r] - expected[r]).abs() / scale;
            worst = worst.max(err);
            assert!(
                err < 1e-6,
                "seed {seed}: h[{r}] = {} vs Lagrangian {}",
                h[r],
                expected[r]
            );
        }
    }
    println!("worst relative bias error {worst:.2e}");
}

#[test]
fn inverse_dynamics_agrees_with_mass_matrix_and_bias() {
    // Two routes to the same forces: Newton–Euler with u̇ gives τ = M u̇ + h, with M from the
    // composite rigid body algorithm and h from Newton–Euler with u̇ = 0. And the forward
    // dynamics solves it: τ(u̇_forward) = 0.
    for seed in 0..300 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let n = model.nu();
        let mut rng = Rng::new(3000 + seed);
        let t = rng.uniform(0.0, 2.0);
        let q = rng.vector(n, 2.0);
        let u = rng.vector(n, 2.0);
        let udot = DVector::from_vec(rng.vector(n, 5.0));
        forward_kinematics(&model, &mut data, t, &q, &u).unwrap();
        mass_matrix(&model, &mut data);
        bias_forces(&model, &mut data);
        let expected = data.mass.to_dense() * &udot + &data.bias;
        inverse_dynamics(&model, &mut data, udot.as_slice()).unwrap();
        let scale = 1.0 + expected.amax();
        assert!(
            (&data.tau - &expected).amax() < 1e-12 * scale,
            "seed {seed}: τ {} vs M u̇ + h {}",
            data.tau,
            expected
        );

        forward_dynamics(&model, &mut data, t, &q, &u).unwrap();
        let solved = data.udot.clone();
        inverse_dynamics(&model, &mut data, solved.as_slice()).unwrap();
        assert!(
            data.tau.amax() < 1e-11 * scale,
            "seed {seed}: residual {}",
            data.tau
        );
    }
}

#[test]
fn newton_euler_accelerations_are_the_derivatives_of_point_velocities() {
    // With u̇ = 0 (and the prescribed accelerations), the Newton–Euler pass's spatial
    // acceleration A_b gives the classical acceleration of a body point p:
    //   a(p) = A.v + A.ω perp(p) + ω perp(v(p)),
    // to be compared with d/dt v(p) along (t, q + u (t − t0), u).
    let h = 1e-6;
    for seed in 0..200 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let n = model.nu();
        let mut rng = Rng::new(4000 + seed);
        let t = rng.uniform(0.0, 2.0);
        let q = rng.vector(n, 2.0);
        let u = rng.vector(n, 2.0);
        for body in model.body_ids() {
            let local = rng.vec2(1.0);
            let velocity = |data: &mut Data, s: Real| {
                let qs: Vec<Real> = q.iter().zip(&u).map(|(q, u)| q + s * u).collect();
                forward_kinematics(&model, data, t + s, &qs, &u).unwrap();
                let p = point_world(&model, data, body, local).unwrap();
                point_velocity(&model, data, body, p).unwrap().total
            };
            let fd = (velocity(&mut data, h) - velocity(&mut data, -h)) / (2.0 * h);
            let v = velocity(&mut data, 0.0);
            bias_forces(&model, &mut data);
            let p = point_world(&model, &data, body, local).unwrap();
            let a = data.body_accel[body.index()];
            let w = data.body_twist[body.index()].w;
            let acc = a.v + perp(p) * a.w + perp(v) * w;
            assert!(
                (acc - fd).length() < 1e-6 * (1.0 + fd.length()),
                "seed {seed} body {body:?}: {acc:?} vs FD {fd:?}"
            );
        }
    }
}

#[test]
fn energy_balance_accounts_for_dampers_efforts_and_drives() {
    // dE/dt along the motion = Σ(−c q̇²) + Σ τ q̇ + Σ Q_p q̇_p, with dE/dt from central
    // differences of E = T + V along (t, q, u) ↦ (t + δ, q + δ u, u + δ u̇).
    let d = 1e-5;
    let mut checked_drives = 0;
    for seed in 0..300 {
        let model = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut data = Data::new(&model);
        let n = model.nu();
        let mut rng = Rng::new(6000 + seed);
        let t = rng.uniform(0.0, 2.0);
        let q = rng.vector(n, 2.0);
        let u = rng.vector(n, 2.0);
        forward_dynamics(&model, &mut data, t, &q, &u).unwrap();
        let udot = data.udot.clone();
        let p = power(&model, &mut data);
        let e_at = |data: &mut Data, s: Real| {
            let qs: Vec<Real> = q.iter().zip(&u).map(|(q, u)| q + s * u).collect();
            let us: Vec<Real> = u.iter().zip(udot.iter()).map(|(u, a)| u + s * a).collect();
            energy(&model, data, t + s, &qs, &us).unwrap().total()
        };
        let de = (e_at(&mut data, d) - e_at(&mut data, -d)) / (2.0 * d);
        let total = p.damping + p.applied + p.drives;
        let scale = 1.0 + p.damping.abs() + p.applied.abs() + p.drives.abs();
        assert!(
            (de - total).abs() < 1e-6 * scale,
            "seed {seed}: dE/dt = {de}, powers {p:?}"
        );
        assert!(p.damping <= 0.0);
        if p.drives != 0.0 {
            checked_drives += 1;
        }
    }
    assert!(
        checked_drives > 50,
        "only {checked_drives} trees had a working drive"
    );
}

/// Integrates `ẏ = f(t, y)` with the classical RK4 at the step `dt` for `steps` steps and
/// returns the largest |E(t) − E(0)| seen, and the largest kinetic energy.
fn rk4_energy_drift(model: &Model, y0: &[Real], dt: Real, steps: usize) -> (Real, Real, Real) {
    let mut data = Data::new(model);
    let n = y0.len();
    let nq = model.nq();
    let e = |data: &mut Data, y: &[Real]| energy(model, data, 0.0, &y[..nq], &y[nq..]).unwrap();
    let e0 = e(&mut data, y0).total();
    let mut y = y0.to_vec();
    let (mut k1, mut k2, mut k3, mut k4, mut tmp) = (
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
    );
    let (mut drift, mut t_max): (Real, Real) = (0.0, 0.0);
    for _ in 0..steps {
        ode_rhs(model, &mut data, 0.0, &y, &mut k1).unwrap();
        for i in 0..n {
            tmp[i] = y[i] + 0.5 * dt * k1[i];
        }
        ode_rhs(model, &mut data, 0.0, &tmp, &mut k2).unwrap();
        for i in 0..n {
            tmp[i] = y[i] + 0.5 * dt * k2[i];
        }
        ode_rhs(model, &mut data, 0.0, &tmp, &mut k3).unwrap();
        for i in 0..n {
            tmp[i] = y[i] + dt * k3[i];
        }
        ode_rhs(model, &mut data, 0.0, &tmp, &mut k4).unwrap();
        for i in 0..n {
            y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        let en = e(&mut data, &y);
        drift = drift.max((en.total() - e0).abs());
        t_max = t_max.max(en.kinetic);
    }
    (drift, t_max, e0)
}

#[test]
fn free_motion_conserves_energy() {
    // Contact-free, conservative (gravity and springs): E = T + V is a first integral. RK4
    // at a small step keeps it to ≤ 1e-10 relative over many periods (its energy error is
    // O(dt⁴) per unit time); a wrong h or M would break it at the first digits.
    let mut cases: Vec<(String, Model, Vec<Real>, Real, usize)> = Vec::new();
    // The double pendulum released from 90°, 60°: chaotic, periods ≈ 3 s; 30 s.
    cases.push((
        "double pendulum".into(),
        double_pendulum(3.0, 2.0, 9.81),
        vec![90.0 * DEG, 60.0 * DEG, 0.0, 0.0],
        2e-4,
        150_000,
    ));
    // A 4-link chain (relative angles) from the horizontal; 10 s. The whip makes it the
    // hardest case: at dt = 1e-4 the drift was 3.6e-10, at 5e-5 it is 16 times smaller,
    // as RK4's O(dt⁴) predicts.
    cases.push((
        "chain of 4".into(),
        chain(4, 0.5, 0.5, 9.81),
        vec![90.0 * DEG, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -0.5],
        5e-5,
        200_000,
    ));
    // Random trees with springs and gravity; 5 s.
    let mut rng = Rng::new(77);
    for seed in [3, 11, 19, 27] {
        let model = random_tree(seed, TreeOptions::CONSERVATIVE, Pose::identity());
        let y0 = rng.vector(2 * model.nq(), 1.0);
        cases.push((format!("random tree {seed}"), model, y0, 1e-4, 50_000));
    }
    for (name, model, y0, dt, steps) in cases {
        let (drift, t_max, e0) = rk4_energy_drift(&model, &y0, dt, steps);
        let rel = drift / e0.abs().max(t_max);
        println!(
            "{name}: dt = {dt}, {steps} steps, max |E − E0| = {drift:.3e} J, relative {rel:.3e}"
        );
        assert!(rel <= 1e-10, "{name}: relative energy drift {rel:.3e}");
    }
}

#[test]
fn rigid_motion_of_the_scene_leaves_kinetic_energy_and_dynamics_unchanged() {
    // Moving and turning everything fixed in the world (joint placements on the world,
    // absolute angle references, gravity) by one rigid motion leaves T, M and u̇ as they
    // were at the same (q, u), and changes V by a constant.
    let motions = [
        Pose::new(Vec2::new(3.0, -2.0), 0.0),
        Pose::new(Vec2::ZERO, 1.3),
        Pose::new(Vec2::new(-1.5, 4.0), -2.4),
    ];
    for seed in 0..100 {
        let base = random_tree(seed, TreeOptions::EVERYTHING, Pose::identity());
        let mut db = Data::new(&base);
        let n = base.nu();
        let mut rng = Rng::new(8000 + seed);
        let t = rng.uniform(0.0, 2.0);
        let (q, u) = (rng.vector(n, 2.0), rng.vector(n, 2.0));
        let q2 = rng.vector(n, 2.0);
        forward_dynamics(&base, &mut db, t, &q, &u).unwrap();
        let (m0, a0) = (db.mass.to_dense(), db.udot.clone());
        let e0 = energy(&base, &mut db, t, &q, &u).unwrap();
        let v0b = potential(&base, &mut db, t, &q2);
        for motion in motions {
            let moved = random_tree(seed, TreeOptions::EVERYTHING, motion);
            let mut dm = Data::new(&moved);
            forward_dynamics(&moved, &mut dm, t, &q, &u).unwrap();
            let scale = 1.0 + max_abs(&m0);
            assert!(
                max_abs(&(dm.mass.to_dense() - &m0)) < 1e-11 * scale,
                "seed {seed}: M changed"
            );
            assert!(
                (&dm.udot - &a0).amax() < 1e-10 * (1.0 + a0.amax()),
                "seed {seed}: u̇ {} vs {}",
                dm.udot,
                a0
            );
            let e1 = energy(&moved, &mut dm, t, &q, &u).unwrap();
            assert!(
                (e1.kinetic - e0.kinetic).abs() < 1e-11 * (1.0 + e0.kinetic),
                "seed {seed}: T changed"
            );
            let v1b = potential(&moved, &mut dm, t, &q2);
            let shift = (e1.potential - e0.potential) - (v1b - v0b);
            assert!(
                shift.abs() < 1e-10 * (1.0 + e0.potential.abs() + v0b.abs()),
                "seed {seed}: V changed by more than a constant"
            );
        }
    }
}

#[test]
fn the_factor_solves_mass_systems_and_reports_failures() {
    let model = random_tree(5, TreeOptions::EVERYTHING, Pose::identity());
    let mut data = Data::new(&model);
    let n = model.nu();
    let mut b = vec![1.0; n];
    assert_eq!(
        solve_mass(&mut data, &mut b),
        Err(DynamicsError::NotFactored)
    );
    let mut rng = Rng::new(1);
    let q = rng.vector(n, 1.0);
    let u = rng.vector(n, 1.0);
    forward_dynamics(&model, &mut data, 0.5, &q, &u).unwrap();
    let rhs = DVector::from_vec(rng.vector(n, 1.0));
    let mut x = rhs.clone();
    solve_mass(&mut data, x.as_mut_slice()).unwrap();
    let mass = data.mass.to_dense();
    assert!((&mass * &x - &rhs).amax() < 1e-12 * (1.0 + max_abs(&mass) * x.amax()));
    // M = Lᵀ L [F, §6.5] (or L Lᵀ for a full pattern).
    let product = data.mass_factor.product().unwrap();
    assert!(max_abs(&(product - &mass)) < 1e-12 * max_abs(&mass));

    // A matrix that is not positive definite is reported with its smallest eigenvalue and t.
    data.mass.clear();
    assert!(data.mass.set(0, 0, -1.0));
    let err = factor_mass_matrix(&mut data, 1.25).unwrap_err();
    assert_eq!(
        err,
        DynamicsError::NotPositiveDefinite {
            t: 1.25,
            min_eigenvalue: -1.0
        }
    );
    assert!(err.to_string().contains("t = 1.25"));
    assert_eq!(
        solve_mass(&mut data, &mut b),
        Err(DynamicsError::NotFactored)
    );

    // Non-finite input is reported, not propagated.
    let mut bad = q.clone();
    bad[n - 1] = Real::NAN;
    let err = forward_dynamics(&model, &mut data, 2.0, &bad, &u).unwrap_err();
    assert!(
        matches!(err, DynamicsError::NonFinite { t: 2.0, what: "q", index, .. } if index == n - 1),
        "{err}"
    );
}
