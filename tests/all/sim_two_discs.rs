//! A body–body contact: two free discs collide off-centre, without gravity, against the
//! textbook two-body collision.
//!
//! For discs the contact normal passes through both centres, so a frictionless impact
//! exerts no torque: the spins are unchanged, the total momentum is conserved, and the
//! relative normal velocity of the centres is reversed and scaled by e. With the line of
//! centres `n` and the reduced mass `m* = m_a m_b / (m_a + m_b)`, the normal impulse is
//! `I = (1 + e) m* |v_n^A|`, and `W` has `m_nn = 1/m_a + 1/m_b`,
//! `m_tt = 1/m_a + 1/m_b + r_a²/I_a + r_b²/I_b`, `m_nt = 0`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use parry2d_f64::shape::{Ball, SharedShape};
use ricochet::impact::Law;
use ricochet::math::{Pose, Real, Vec2};
use ricochet::model::{Body, Collider, Joint, Material, Model};
use ricochet::settings::{IntegratorSettings, Settings};
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, Sample, Simulation,
};
use ricochet::state::State;

struct First(Option<ImpactEvent>, Arc<AtomicBool>);

impl Observer for First {
    fn wants_samples(&self) -> bool {
        false
    }
    fn sample(&mut self, _: &Model, _: &Sample<'_>) -> Result<(), ObserverError> {
        Ok(())
    }
    fn impact(&mut self, _: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        self.0.get_or_insert_with(|| ev.clone());
        self.1.store(true, Ordering::Relaxed);
        Ok(())
    }
    fn message(&mut self, _: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        Ok(())
    }
}

#[test]
fn off_centre_disc_collision_is_the_textbook_one() {
    let (ma, mb, ra, rb) = (2.0, 0.5, 0.3, 0.2);
    let (ia, ib) = (0.5 * ma * ra * ra, 0.5 * mb * rb * rb);
    let e = 0.7;
    let mut b = Model::builder();
    b.gravity(Vec2::ZERO).default_material(Material {
        law: Law::Newton,
        e,
        mu: 0.0,
    });
    let body_a = b.add_body(
        Body::new("a", ma, Vec2::ZERO, ia),
        Joint::planar("a", None, Pose::identity()),
    );
    let body_b = b.add_body(
        Body::new("b", mb, Vec2::ZERO, ib),
        Joint::planar("b", None, Pose::identity()),
    );
    b.add_collider(Collider::new(
        "a",
        Some(body_a),
        SharedShape::new(Ball::new(ra)),
        Pose::identity(),
    ));
    b.add_collider(Collider::new(
        "b",
        Some(body_b),
        SharedShape::new(Ball::new(rb)),
        Pose::identity(),
    ));
    let model = b.build().unwrap();
    // a at the origin moving right and spinning; b ahead, offset by 0.3 m, moving left.
    let (ua, ub) = ([1.5, 0.2, 3.0], [-2.0, -0.4, -7.0]);
    let q = vec![0.0, 0.0, 0.0, 2.0, 0.3, 0.0];
    let u: Vec<Real> = ua.iter().chain(ub.iter()).copied().collect();
    let settings = Settings {
        t_end: 5.0,
        output_rate: 0.0,
        max_drift: None,
        simultaneous: Default::default(),
        integrator: IntegratorSettings {
            rtol: 1e-12,
            atol: 1e-14,
            ..Default::default()
        },
    };
    let stop = Arc::new(AtomicBool::new(false));
    let mut obs = First(None, Arc::clone(&stop));
    let mut sim = Simulation::new(&model, &settings, MaterialOverride::default()).unwrap();
    sim.run(
        &State::new(0.0, q.clone().into(), u.clone().into()),
        &mut obs,
        Some(&stop),
    );
    let ev = obs.0.expect("the discs collide");

    // When: the centres' distance reaches ra + rb along the straight flights.
    let (dx, dy) = (ub[0] - ua[0], ub[1] - ua[1]);
    let (px, py) = (q[3] - q[0], q[4] - q[1]);
    let s = ra + rb;
    // |p + d t| = s, the first root.
    let (qa, qb, qc) = (
        dx * dx + dy * dy,
        2.0 * (px * dx + py * dy),
        px * px + py * py - s * s,
    );
    let t = (-qb - (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
    assert!((ev.t - t).abs() < 1e-12, "t = {} vs {t}", ev.t);

    // W in the frame (n, t) of the impact.
    let m_nn = 1.0 / ma + 1.0 / mb;
    let m_tt = m_nn + ra * ra / ia + rb * rb / ib;
    assert!(
        (ev.w.nn - m_nn).abs() < 1e-12 && ev.w.nt.abs() < 1e-12 && (ev.w.tt - m_tt).abs() < 1e-12,
        "{:?}",
        ev.w
    );

    // The textbook outcome.
    let n = Vec2::new(px + dx * t, py + dy * t) / s; // from a to b
    let (va, vb) = (Vec2::new(ua[0], ua[1]), Vec2::new(ub[0], ub[1]));
    let approach = (vb - va).dot(n); // < 0
    let reduced = ma * mb / (ma + mb);
    let impulse = (1.0 + e) * reduced * -approach;
    let va_plus = va - impulse / ma * n;
    let vb_plus = vb + impulse / mb * n;
    let du = &ev.delta_u;
    let got_a = va + Vec2::new(du[0], du[1]);
    let got_b = vb + Vec2::new(du[3], du[4]);
    assert!((got_a - va_plus).length() < 1e-12 && (got_b - vb_plus).length() < 1e-12);
    assert!(
        du[2].abs() < 1e-12 && du[5].abs() < 1e-12,
        "the spins change: {du:?}"
    );
    assert!((ev.outcome.impulse.n - impulse).abs() < 1e-12);
    // Momentum conserved; kinetic energy lost ½ m* (1 − e²) v_n².
    let p_before = ma * va + mb * vb;
    let p_after = ma * got_a + mb * got_b;
    assert!((p_before - p_after).length() < 1e-12);
    let lost = 0.5 * reduced * (1.0 - e * e) * approach * approach;
    assert!((ev.energy_change() + lost).abs() < 1e-12 && (ev.outcome.delta_e + lost).abs() < 1e-12);
}
