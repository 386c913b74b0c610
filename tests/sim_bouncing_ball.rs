//! `scenes/bouncing_ball.toml` without friction against its closed forms: dropped from
//! rest with its lowest point h0 = 1 m above the floor, it first lands at
//! `t1 = √(2 h0/g)` with speed `v1 = √(2 g h0)`; bounce k leaves at `e^k v1`, rises to
//! `e^(2k) h0` and lasts `2 e^k v1 / g`; the impacts accumulate at
//! `t∞ = t1 + (2 v1/g) e/(1 − e)`.

use ricochet::sim::{MaterialOverride, Recorder, Simulation, StopReason};

const G: f64 = 9.81;
const H0: f64 = 1.0;

fn run(e: f64, rtol: f64) -> (Recorder, ricochet::sim::RunSummary) {
    let mut scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/bouncing_ball.toml"
    ))
    .unwrap();
    scene.settings.integrator.rtol = rtol;
    scene.settings.integrator.atol = 1e-14;
    scene.settings.t_end = 30.0; // beyond t∞ = 17.6 s for e = 0.95
    let overrides = MaterialOverride {
        e: Some(e),
        mu: Some(0.0),
        ..Default::default()
    };
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let mut rec = Recorder::default();
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary)
}

#[test]
fn first_twenty_impacts_match_the_closed_form() {
    let e = 0.8;
    let (rec, summary) = run(e, 1e-12);
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
        "20 impacts: worst relative error of times {worst_t:.2e}, of apex heights {worst_h:.2e}"
    );
}

#[test]
fn the_run_stops_at_the_accumulation_point() {
    // Until persistent contact exists the run stops when the hops fall below what the
    // tolerance resolves: before t∞, within the time the remaining hops would take.
    for e in [0.5, 0.8, 0.95] {
        let (rec, summary) = run(e, 1e-10);
        let v1 = (2.0 * G * H0).sqrt();
        let t_inf = (2.0 * H0 / G).sqrt() + 2.0 * v1 / G * e / (1.0 - e);
        let StopReason::Accumulation { t, .. } = summary.stop else {
            panic!("e = {e}: {}", summary.stop);
        };
        let last = rec.impacts.last().unwrap();
        assert_eq!(t, last.t);
        // The hops left after the last one sum to 2 v_s / g / (1 − e).
        let remaining = 2.0 * last.outcome.v_s.n / G / (1.0 - e);
        assert!(
            t < t_inf && (t_inf - t - remaining).abs() < 1e-9,
            "e = {e}: stopped at {t}, t∞ = {t_inf}"
        );
        // The ball is never below the floor by more than rounding: every impact happens
        // at zero gap (the ball's centre at its radius).
        for ev in &rec.impacts {
            assert!(ev.frame.gap.abs() < 1e-12, "gap {}", ev.frame.gap);
        }
    }
}
