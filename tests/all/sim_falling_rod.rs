//! `scenes/falling_rod.toml`: the first impact against the analytic free flight and the
//! impact law on a hand-derived `W`.
//!
//! The rod (m = 1 kg, L = 1 m, I = m L²/12, a capsule of radius r = 1 cm) is released from
//! rest with its centre at y0 = 1 m, tilted by θ = 30°. In free flight it falls without
//! turning: its lower end's lowest point is `y − (L/2) sin θ − r`, so it lands at
//! `t1 = √(2 (y0 − (L/2) sin θ − r) / g)` with `u⁻ = (0, −g t1, 0)`. For a free planar body
//! with coordinates (x, y, θ), the contact point at `ρ` from the centre has
//! `J = [I₂ | perp(ρ)]`, `M = diag(m, m, I)`, hence
//! `W = I₂/m + perp(ρ) perp(ρ)ᵀ / I` in the frame (n, t).

use nalgebra::{Matrix3, Vector2, Vector3};
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};
use ricochet::sim::{MaterialOverride, Recorder, Simulation};

const G: f64 = 9.81;

#[test]
fn first_impact_matches_free_flight_and_the_law() {
    let mut scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/falling_rod.toml"
    ))
    .unwrap();
    scene.settings.integrator.rtol = 1e-12;
    scene.settings.integrator.atol = 1e-14;
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut rec = Recorder::default();
    sim.run(&scene.initial, &mut rec, None);
    let ev = &rec.impacts[0];

    // Free flight.
    let (m, len, r, th, y0) = (1.0, 1.0, 0.01, 30f64.to_radians(), 1.0);
    let inertia = m * len * len / 12.0;
    let t1 = (2.0 * (y0 - 0.5 * len * th.sin() - r) / G).sqrt();
    assert!((ev.t - t1).abs() < 1e-12, "t = {} vs {t1}", ev.t);
    let u_minus = Vector3::new(0.0, -G * t1, 0.0);

    // The contact point: the lower end's centre plus r below it.
    let rho = Vector2::new(-0.5 * len * th.cos(), -0.5 * len * th.sin() - r);
    let pt = ev.frame.point();
    assert!(
        (pt.x - rho.x).abs() < 1e-12 && (pt.y - (y0 - 0.5 * G * t1 * t1 + rho.y)).abs() < 1e-12
    );
    let perp_rho = Vector2::new(-rho.y, rho.x);
    let (n, t) = (
        Vector2::new(ev.frame.n.x, ev.frame.n.y),
        Vector2::new(ev.frame.t.x, ev.frame.t.y),
    );
    assert!((n - Vector2::new(0.0, 1.0)).norm() < 1e-15);
    let w = ImpactMatrix::new(
        1.0 / m + perp_rho.dot(&n).powi(2) / inertia,
        perp_rho.dot(&n) * perp_rho.dot(&t) / inertia,
        1.0 / m + perp_rho.dot(&t).powi(2) / inertia,
    );
    assert!(
        (ev.w.nn - w.nn).abs() < 1e-12
            && (ev.w.nt - w.nt).abs() < 1e-12
            && (ev.w.tt - w.tt).abs() < 1e-12
    );
    let v_a = ContactVelocity::new(-G * t1, 0.0);
    assert!((ev.v_a.n - v_a.n).abs() < 1e-12 && ev.v_a.t.abs() < 1e-12);

    // The law on this W, and Δu = M⁻¹ Jᵀ (I_n n + I_t t).
    let out = impact::solve(Law::Newton, &ImpactProblem::new(w, v_a, 0.5, 0.4)).unwrap();
    let p = out.impulse.n * n + out.impulse.t * t;
    let jt_p = Vector3::new(p.x, p.y, perp_rho.dot(&p));
    let m_inv = Matrix3::from_diagonal(&Vector3::new(1.0 / m, 1.0 / m, 1.0 / inertia));
    let du = m_inv * jt_p;
    for k in 0..3 {
        assert!(
            (ev.delta_u[k] - du[k]).abs() < 1e-11,
            "Δu[{k}] {} vs {}",
            ev.delta_u[k],
            du[k]
        );
    }
    assert_eq!(ev.outcome.kind, out.kind);
    // After the impact the lower end separates at e |v_n^A|.
    let u_plus = u_minus + du;
    let v_plus = Vector2::new(u_plus[0], u_plus[1]) + u_plus[2] * perp_rho;
    assert!((v_plus.dot(&n) - 0.5 * G * t1).abs() < 1e-11);
}
