//! The unit tests of `articulated` (`src/articulated.rs`).

// The source module's own imports.
use nalgebra::Vector3;
use ricochet::math::Vec2;
use ricochet::model::spatial::{Inertia, Twist};

use ricochet::articulated::*;

#[test]
fn matrices_act_as_the_spatial_operations() {
    let inertia = Inertia::from_body(1.3, Vec2::new(0.4, -0.7), 0.21);
    let s = Twist::new(0.9, Vec2::new(-1.1, 0.35));
    let f = inertia.mul_twist(&s);
    let fm = inertia_matrix(&inertia) * twist_vector(&s);
    assert!((fm - Vector3::new(f.n, f.f.x, f.f.y)).amax() < 1e-15);
    let a = Vec2::new(-0.3, 1.7);
    let p = s.projected_at(a);
    let pm = projection_matrix(a) * twist_vector(&s);
    assert!((pm - twist_vector(&p)).amax() < 1e-15);
    assert!((project_twist(a, &twist_vector(&s)) - pm).amax() < 1e-15);
    let fv = Vector3::new(f.n, f.f.x, f.f.y);
    let pf = f.projected_at(a);
    assert!((project_wrench(a, &fv) - Vector3::new(pf.n, pf.f.x, pf.f.y)).amax() < 1e-15);
    assert!((projection_matrix(a).transpose() * fv - project_wrench(a, &fv)).amax() < 1e-15);
}
