//! Energy: conservation through many elastic impacts, the audit of a run (checked on every
//! bundled scene, with its log, by `sim_log`), and the work of prescribed motion at an
//! impact [P, Eq. (28), Appendix B].

use ricochet::scene::Scene;
use ricochet::sim::{ImpactEvent, MaterialOverride, Recorder, RunSummary, Simulation, StopReason};

fn load(name: &str) -> ricochet::scene::Scene {
    ricochet::scene::load(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn elastic_pendulum_keeps_its_energy_over_a_thousand_impacts() {
    // pendulum_wall with e = 1, μ = 0: every impact is elastic (ΔE = 0 by Eq. 29), so the
    // total energy stays E0 to the integrator's accuracy.
    let mut scene = load("pendulum_wall");
    scene.settings.integrator.rtol = 1e-12;
    scene.settings.integrator.atol = 1e-14;
    scene.settings.t_end = 1e4;
    let overrides = MaterialOverride {
        e: Some(1.0),
        mu: Some(0.0),
        ..Default::default()
    };
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    // Stop after 1000 impacts.
    struct Count {
        rec: Recorder,
        stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    }
    impl ricochet::sim::Observer for Count {
        fn wants_samples(&self) -> bool {
            false
        }
        fn sample(
            &mut self,
            _: &ricochet::model::Model,
            _: &ricochet::sim::Sample<'_>,
        ) -> Result<(), ricochet::sim::ObserverError> {
            Ok(())
        }
        fn impact(
            &mut self,
            m: &ricochet::model::Model,
            ev: &ricochet::sim::ImpactEvent,
        ) -> Result<(), ricochet::sim::ObserverError> {
            self.rec.impact(m, ev)?;
            if self.rec.impacts.len() == 1000 {
                self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
            }
            Ok(())
        }
        fn message(
            &mut self,
            t: f64,
            l: ricochet::sim::Level,
            s: &str,
        ) -> Result<(), ricochet::sim::ObserverError> {
            self.rec.message(t, l, s)
        }
    }
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let mut obs = Count {
        rec: Recorder::default(),
        stop: stop.clone(),
    };
    let summary = sim.run(&scene.initial, &mut obs, Some(&stop));
    assert!(
        matches!(summary.stop, StopReason::Interrupted { .. }),
        "{}",
        summary.stop
    );
    assert_eq!(obs.rec.impacts.len(), 1000);
    let a = summary.audit;
    let e0 = a.initial.total();
    let rel = (a.end.total() - e0).abs() / e0.abs();
    println!(
        "1000 elastic impacts in {:.1} s: |E_end − E_0| / |E_0| = {rel:.2e}, ΣΔE = {:.2e} J, {} steps",
        summary.state.t, a.impact_delta_e, summary.counters.steps
    );
    assert!(rel <= 1e-9, "relative energy drift {rel:e}");
    // Every impact is elastic and frictionless: ΔE of Eq. (29) vanishes to rounding, and
    // the model's energies agree.
    for ev in &obs.rec.impacts {
        assert!(
            ev.outcome.delta_e.abs() < 1e-12,
            "ΔE = {}",
            ev.outcome.delta_e
        );
        assert!(ev.energy_change().abs() < 1e-12);
    }
}

/// The audit of a bundled scene's run at its own settings:
/// E_end − E_0 = ΣΔE (Eq. 29) + Σ Eq. (28) + works of dampers, efforts and drives + drift,
/// with the drift at the integrator's accuracy; and at every impact of a scene without prescribed motion the
/// model's energy jump is Eq. (29). Checked on every bundled scene by
/// `sim_log::every_bundled_scene_logs_the_whole_mechanism_and_balances_its_audit`, on the
/// run whose log it reads (one run of each scene for both: `chain_floor` alone takes
/// ~7 s; a log and a recorder change nothing in a run, `samples_or_not`).
pub(crate) fn assert_the_audit_balances(
    name: &str,
    scene: &Scene,
    summary: &RunSummary,
    impacts: &[ImpactEvent],
) {
    assert!(
        !matches!(summary.stop, StopReason::Failed(_)),
        "{name}: {}",
        summary.stop
    );
    let a = summary.audit;
    let scale = crate::common::energy_scale(&a, 1e-3);
    println!(
        "{name}: {} at t = {:.4}; {} impacts; drift {:.2e} J ({:.1e} of the energy scale)",
        summary.stop.name(),
        summary.state.t,
        impacts.len(),
        a.drift(),
        a.drift().abs() / scale
    );
    assert!(
        a.drift().abs() <= 1e-8 * scale,
        "{name}: drift {} J",
        a.drift()
    );
    let sum: f64 = impacts.iter().map(|i| i.outcome.delta_e).sum();
    assert!((sum - a.impact_delta_e).abs() <= 1e-12 * scale);
    if !scene.model.has_prescribed_motion() {
        for ev in impacts {
            assert!(
                (ev.energy_change() - ev.outcome.delta_e).abs() <= 1e-11 * scale,
                "{name} impact {}: model {} vs Eq. (29) {}",
                ev.index,
                ev.energy_change(),
                ev.outcome.delta_e
            );
        }
    }
}

#[test]
fn prescribed_motion_supplies_the_energy_gain_of_appendix_b() {
    // spinning_disk_particle: e = 1 and friction on a disk driven at a constant rate. The
    // model's energy rises at the impact while Eq. (29) says it falls; the difference is
    // the left-hand side of Eq. (28),
    //   −I_n v_t^R·n − I_t v_t^R·t + Σ m_i v_t^{P_i}·Δv^{P_i},
    // whose sum vanishes here (the disk's velocity is prescribed, Δv = 0; the particle
    // has no remainder velocity), with v_t^R the remainder part of the relative velocity.
    let scene = load("spinning_disk_particle");
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut rec = Recorder::default();
    let summary = sim.run(&scene.initial, &mut rec, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    assert_eq!(rec.impacts.len(), 1);
    let ev = &rec.impacts[0];
    let (i, f) = (ev.outcome.impulse, ev.frame);
    let eq28 = -i.n * f.v_rem.dot(f.n) - i.t * f.v_rem.dot(f.t);
    assert!(
        (ev.prescribed_work() - eq28).abs() < 1e-12,
        "{} vs {eq28}",
        ev.prescribed_work()
    );
    // The disk's rim moves at Ω R = 5 m/s under the particle: that is the remainder.
    assert!((f.v_rem.length() - 5.0).abs() < 1e-12);
    assert!(ev.energy_change() > 0.0 && ev.outcome.delta_e < 0.0);
    // The audit credits the gain to the prescribed motion, and balances.
    let a = summary.audit;
    assert!((a.impact_prescribed_work - eq28).abs() < 1e-12);
    assert!(a.drift().abs() < 1e-9, "drift {}", a.drift());
}
