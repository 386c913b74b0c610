//! `scenes/bouncing_ball.toml` without friction against its closed forms: dropped from
//! rest with its lowest point h0 = 1 m above the floor, it first lands at
//! `t1 = √(2 h0/g)` with speed `v1 = √(2 g h0)`; bounce k leaves at `e^k v1`, rises to
//! `e^(2k) h0` and lasts `2 e^k v1 / g`; the impacts accumulate at
//! `t∞ = t1 + (2 v1/g) e/(1 − e)`.

use ricochet::integrate::Method;
use ricochet::sim::{ImpactCause, MaterialOverride, PairMode, Recorder, Simulation, StopReason};

const G: f64 = 9.81;
const H0: f64 = 1.0;
const RADIUS: f64 = 0.1;

fn run_to(
    e: f64,
    rtol: f64,
    t_end: f64,
) -> (Recorder, ricochet::sim::RunSummary, ricochet::sim::Scales) {
    run_with(Method::Dopri5, e, rtol, t_end)
}

fn run_with(
    method: Method,
    e: f64,
    rtol: f64,
    t_end: f64,
) -> (Recorder, ricochet::sim::RunSummary, ricochet::sim::Scales) {
    let mut scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/bouncing_ball.toml"
    ))
    .unwrap();
    scene.settings.integrator.method = method;
    scene.settings.integrator.rtol = rtol;
    scene.settings.integrator.atol = 1e-14;
    scene.settings.t_end = t_end;
    let overrides = MaterialOverride {
        e: Some(e),
        mu: Some(0.0),
        ..Default::default()
    };
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let mut rec = Recorder {
        keep_samples: true,
        ..Default::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary, sim.scales())
}

/// The first twenty impacts of DOPRI5 (rtol 1e-12) and DOP853 (rtol 1e-12, and 1e-9:
/// its event location on the order-7 dense output and the re-step to the event keep the
/// impact times within 1e-9 at a far looser tolerance), against the closed form.
#[test]
fn first_twenty_impacts_match_the_closed_form() {
    for (method, rtol) in [
        (Method::Dopri5, 1e-12),
        (Method::Dop853, 1e-12),
        (Method::Dop853, 1e-9),
    ] {
        first_twenty_impacts(method, rtol);
    }
}

fn first_twenty_impacts(method: Method, rtol: f64) {
    let e = 0.8;
    let (rec, summary, _) = run_with(method, e, rtol, 30.0);
    assert!(
        rec.impacts.len() >= 20,
        "{} impacts, {}",
        rec.impacts.len(),
        summary.stop
    );
    let v1 = (2.0 * G * H0).sqrt();
    let mut t_exact = (2.0 * H0 / G).sqrt();
    let (mut worst_t, mut worst_h) = (0.0f64, 0.0f64);
    for (k, ev) in rec.impacts.iter().take(20).enumerate() {
        // Impact k + 1 (k from 0): time, and the apex of the hop that follows.
        let rel_t = (ev.t - t_exact).abs() / t_exact;
        let apex = ev.outcome.v_s.n.powi(2) / (2.0 * G);
        let apex_exact = e.powi(2 * (k as i32 + 1)) * H0;
        let rel_h = (apex - apex_exact).abs() / apex_exact;
        assert!(
            rel_t <= 1e-9,
            "impact {}: t = {} vs {t_exact} ({rel_t:e})",
            k + 1,
            ev.t
        );
        assert!(
            rel_h <= 1e-9,
            "impact {}: apex {apex} vs {apex_exact} ({rel_h:e})",
            k + 1
        );
        worst_t = worst_t.max(rel_t);
        worst_h = worst_h.max(rel_h);
        t_exact += 2.0 * e.powi(k as i32 + 1) * v1 / G;
    }
    println!(
        "{method} rtol {rtol:.0e}, 20 impacts: worst relative error of times {worst_t:.2e}, of \
         apex heights {worst_h:.2e}; {} rhs evaluations",
        summary.counters.rhs_evals
    );
}

/// Issue 5: the run goes through the accumulation point to the end time. When the hops
/// fall below the resting speed the ball is brought to rest (a closing impulse, e = 0 in
/// the ledger) and stays on the floor; the reported end of the hops, extrapolated from
/// the last two, is the closed form t∞ within 1e-6 s.
#[test]
fn the_ball_comes_to_rest_at_the_accumulation_point() {
    let v1 = (2.0 * G * H0).sqrt();
    for e in [0.5, 0.8, 0.95] {
        let t_inf = (2.0 * H0 / G).sqrt() + 2.0 * v1 / G * e / (1.0 - e);
        // To 10 s, or 2 s past t∞ (17.6 s for e = 0.95).
        let t_end = (t_inf + 2.0).max(10.0);
        let (rec, summary, scales) = run_to(e, 1e-10, t_end);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "e = {e}: {}",
            summary.stop
        );
        assert_eq!(summary.state.t, t_end);
        let rest = (rec.transitions.iter())
            .find(|tr| tr.t_accumulation.is_some())
            .unwrap_or_else(|| panic!("e = {e}: no accumulation"));
        let t_acc = rest.t_accumulation.unwrap();
        println!(
            "e = {e}: t∞ = {t_acc} (closed form {t_inf}, {:.1e})",
            t_acc - t_inf
        );
        // The passage to rest is stamped at t∞ (in /log and in the samples' mode), and t∞
        // is the closed form to 1e-9 s.
        assert!(
            (t_acc - t_inf).abs() <= 1e-9,
            "e = {e}: t∞ = {t_acc} vs {t_inf}"
        );
        assert_eq!(rest.t, t_acc);
        assert_eq!((rest.from, rest.to), (PairMode::Free, PairMode::Sticking));
        // The last impact is the plastic one that ends the accumulation, before t∞; no
        // impact after it, and no impulse of the ledger pulls.
        let closing = rec.impacts.last().unwrap();
        assert_eq!(
            (closing.cause, closing.material.e),
            (ImpactCause::AccumulationEnd, 0.0)
        );
        assert!(closing.t < t_acc && closing.v_a.n < 0.0);
        assert!(closing.outcome.v_s.n.abs() <= 1e-15);
        for ev in &rec.impacts {
            assert!(
                ev.outcome.impulse.n > 0.0,
                "e = {e}: {:?}",
                ev.outcome.impulse
            );
        }
        // The samples show the ball free until t∞, then sticking.
        assert!(rec.sample_modes.len() > 100);
        for (t, modes) in &rec.sample_modes {
            let expected = if *t < t_acc {
                PairMode::Free
            } else {
                PairMode::Sticking
            };
            assert_eq!(modes[0], expected, "e = {e}: t = {t}");
        }
        let (y, v) = (summary.state.q[0], summary.state.u[0]);
        assert!((y - RADIUS).abs() <= scales.gap_tol, "e = {e}: y = {y}");
        assert!(v.abs() <= 1e-12, "e = {e}: v = {v}");
        // Never below the floor beyond the closed-contact tolerance: every impact at zero
        // gap, every sample above −gap_tol.
        for ev in &rec.impacts {
            assert!(ev.frame.gap.abs() < 1e-12, "gap {}", ev.frame.gap);
        }
        for (t, q, _, _) in &rec.samples {
            assert!(
                q[0] - RADIUS >= -scales.gap_tol,
                "e = {e}: t = {t}, gap {}",
                q[0] - RADIUS
            );
        }
        // The ledger closes the energy: E_end − E_0 = ΣΔE to rounding, and the ball ends
        // with the potential energy of its resting height.
        assert!(summary.audit.drift().abs() <= 1e-12, "{:?}", summary.audit);
        assert!((summary.audit.end.total() - 0.1 * G * RADIUS).abs() <= 1e-9);
    }
}
