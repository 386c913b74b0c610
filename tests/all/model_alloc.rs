//! The right-hand side allocates nothing: a counting global allocator (per thread, so that
//! tests running in parallel do not disturb each other) watches `forward_dynamics`,
//! `ode_rhs`, the energies, the powers, `solve_mass` and the point kinematics once `Data`
//! exists.

use crate::common::model_fixtures as fixtures;

use crate::common::alloc::allocations;

use fixtures::{Rng, TreeOptions, chain, random_tree};
use nalgebra::Matrix2xX;
use ricochet::dynamics::{
    forward_dynamics, kinetic_energy, ode_rhs, potential_energy, power, solve_mass,
};
use ricochet::kinematics::{point_jacobian, point_velocity, point_world};
use ricochet::math::{Pose, Vec2};
use ricochet::state::Data;

#[test]
fn the_right_hand_side_allocates_nothing() {
    // The counter sees allocations on this thread.
    let a0 = allocations();
    std::hint::black_box(Vec::<u8>::with_capacity(8));
    assert_eq!(allocations(), a0 + 1);

    let mut models = vec![chain(16, 0.1, 0.1, 9.81)];
    models.extend((0..20).map(|seed| random_tree(seed, TreeOptions::EVERYTHING, Pose::identity())));
    for model in &models {
        let mut data = Data::new(model);
        let mut jac = Matrix2xX::zeros(model.nu());
        let mut rng = Rng::new(3);
        let n = model.nq();
        let y = rng.vector(2 * n, 1.0);
        let mut dy = vec![0.0; 2 * n];
        let mut b = vec![1.0; n];
        let body = model.body_ids().last().unwrap();

        let before = allocations();
        for k in 0..10 {
            let t = 0.1 * k as f64;
            forward_dynamics(model, &mut data, t, &y[..n], &y[n..]).unwrap();
            let e = kinetic_energy(model, &data) + potential_energy(model, &data);
            let p = power(model, &mut data);
            solve_mass(&mut data, &mut b).unwrap();
            let x = point_world(model, &data, body, Vec2::new(0.1, 0.2)).unwrap();
            let v = point_velocity(model, &data, body, x).unwrap();
            point_jacobian(model, &data, body, x, &mut jac).unwrap();
            ode_rhs(model, &mut data, t, &y, &mut dy).unwrap();
            assert!(e.is_finite() && p.drives.is_finite() && v.total.is_finite());
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{} allocations in 10 evaluations",
            after - before
        );
    }
}
