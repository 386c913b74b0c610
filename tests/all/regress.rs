//! `ricochet::regress`: the run summary, the comparison of two runs, the golden files'
//! tolerances and the drift check.
//!
//! Checked here:
//! - the summary of a run (the `Collector`) and the summary of its log are the same
//!   document, for every bundled scene, and the JSON text reads back bit-exact; with every
//!   sample kept (`Checkpoints::Every`, the Python package's `Run`), the run's samples
//!   are the log's `/state` messages, one for one;
//! - a run compared with itself: every difference exactly zero; with another `e`: the
//!   first difference is impact #0's `v_s.n`, both values against the closed form of the
//!   bouncing ball (`v_s = e √(2 g h)`); with one impact less: a count difference at that
//!   impact's time; an impact whose tangent was chosen the other way round (no tangential
//!   approach speed) is the same impact;
//! - the drift check: the energy scale is `E_0` for a ball released from rest, is the
//!   swing's for the chain released horizontally (`E_0 = 0`), and a budget holds or breaks
//!   by the relative drift.

use std::io::Cursor;
use std::path::PathBuf;

use ricochet::log::Ending;
use ricochet::log::{LogOptions, LogWriter, RunLogger};
use ricochet::math::Real;
use ricochet::model::Model;
use ricochet::regress::{
    Checkpoints, Collector, Place, RunOverrides, Summary, Tolerances, compare, run_scene,
};
use ricochet::sim::{ImpactEvent, Level, Observer, ObserverError, Sample, Simulation};

use crate::common::cli;
use cli::TempDir;

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn scene(name: &str) -> ricochet::scene::Scene {
    ricochet::scene::load(repo(&format!("scenes/{name}.toml"))).unwrap()
}

const SCENES: [&str; 9] = [
    "bouncing_ball",
    "chain",
    "falling_rod",
    "kane_double_pendulum",
    "painleve_rod",
    "pendulum_wall",
    "rimless_wheel",
    "rocking_block",
    "spinning_disk_particle",
];

const EXACT: Tolerances = Tolerances {
    rtol: 0.0,
    atol: 0.0,
    time_tol: 0.0,
};

/// Feeds one run to the log and to the collector.
struct Both<'a> {
    log: &'a mut RunLogger<Cursor<Vec<u8>>>,
    collector: &'a mut Collector,
}

impl Observer for Both<'_> {
    fn sample(&mut self, m: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        self.collector.sample(m, s)?;
        self.log.sample(m, s)
    }
    fn impact(&mut self, m: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        self.collector.impact(m, ev)?;
        self.log.impact(m, ev)
    }
    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        self.log.message(t, level, text)
    }
}

#[test]
fn a_run_and_its_log_give_the_same_summary_for_every_scene() {
    for name in SCENES {
        let mut scene = scene(name);
        if name == "chain" {
            // Its golden file's end time (see tests/golden/scenes/chain.golden.json).
            scene.settings.t_end = 0.85;
        }
        let overrides = ricochet::sim::MaterialOverride::default();
        let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
        let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).unwrap();
        let mut log =
            RunLogger::for_scene(writer, &scene, &overrides, sim.scales().gap_tol).unwrap();
        let mut collector = Collector::new(&scene.model, &scene.settings, 10);
        let end = sim.run(
            &scene.initial,
            &mut Both {
                log: &mut log,
                collector: &mut collector,
            },
            None,
        );
        let bytes = log.finish(&end).unwrap().into_inner();
        let from_run = collector.finish(&scene, (&scene.settings, &overrides), &end);
        let from_log = Summary::from_log(&bytes, Some(10)).unwrap();
        assert_eq!(from_run, from_log, "{name}");
        let text = from_run.to_json().unwrap();
        assert_eq!(text, from_log.to_json().unwrap(), "{name}");
        // What it holds, against the run itself.
        assert_eq!(
            from_run.impacts.len() as u64,
            end.counters.impacts,
            "{name}"
        );
        let last = from_run.final_state.as_ref().unwrap();
        assert_eq!(last.t, end.state.t, "{name}");
        assert_eq!(last.q, end.state.q.as_slice(), "{name}");
        assert!(from_run.checkpoints.len() >= 11, "{name}");
        // The text reads back bit-exact: the same text again.
        let dir = TempDir::new(&format!("roundtrip-{name}"));
        let path = dir.join("s.json");
        std::fs::write(&path, &text).unwrap();
        let back = ricochet::regress::read_run(&path).unwrap();
        assert_eq!(back, from_run, "{name}");
        assert_eq!(back.to_json().unwrap(), text, "{name}");
    }
}

/// What the Python package's `Run` rests on: a collector that keeps every sample gives the
/// summary of the log read with every sample, and those are the run's samples, as many
/// as the log's `/state` messages.
#[test]
fn a_run_keeping_every_sample_is_its_log() {
    for name in ["kane_double_pendulum", "rocking_block", "bouncing_ball"] {
        let scene = scene(name);
        let overrides = ricochet::sim::MaterialOverride::default();
        let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
        let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).unwrap();
        let mut log =
            RunLogger::for_scene(writer, &scene, &overrides, sim.scales().gap_tol).unwrap();
        let mut collector = Collector::with_rule(&scene.model, Checkpoints::Every);
        let end = sim.run(
            &scene.initial,
            &mut Both {
                log: &mut log,
                collector: &mut collector,
            },
            None,
        );
        let bytes = log.finish(&end).unwrap().into_inner();
        let from_run = collector.finish(&scene, (&scene.settings, &overrides), &end);
        let (from_log, read) = Summary::from_log_read(&bytes, None).unwrap();
        assert_eq!(from_run, from_log, "{name}");
        assert_eq!(read.ending, Ending::Complete, "{name}");
        assert_eq!(read.scene.as_ref().unwrap().text, scene.text, "{name}");
        let samples = from_run.checkpoints.len() as u64;
        assert_eq!(samples, end.counters.samples, "{name}");
        assert_eq!(samples, read.count(ricochet::log::Topic::State), "{name}");
        assert!(samples > 300, "{name}: {samples}");
        // The output grid, and two samples at each impact instant.
        let grid = (scene.settings.t_end * scene.settings.output_rate) as u64 + 1;
        let mut instants: Vec<Real> = from_run.impacts.iter().map(|i| i.t).collect();
        instants.dedup();
        assert!(
            samples >= grid + 2 * instants.len() as u64,
            "{name}: {samples}"
        );
    }
}

#[test]
fn a_run_compared_with_itself_has_every_difference_zero() {
    let (_, s) = run_scene(&scene("kane_double_pendulum"), &RunOverrides::default(), 10).unwrap();
    let c = compare(&s, &s, &EXACT);
    assert!(c.within && c.first.is_none() && c.beyond == 0);
    assert!(c.compared > 400, "{}", c.compared);
    for q in &c.quantities {
        assert_eq!(
            (q.max_abs, q.max_rel, q.beyond),
            (0.0, 0.0, 0),
            "{}",
            q.name
        );
        assert!(q.compared > 0, "{}", q.name);
    }
}

#[test]
fn another_e_names_the_first_impact_and_its_field() {
    // The ball falls from rest at 1 m above the floor (its centre at 1.1 m, radius 0.1 m):
    // v_a = −√(2 g h), v_s = e √(2 g h) at the first impact.
    let ball = scene("bouncing_ball");
    let v = (2.0 * 9.81 * 1.0_f64).sqrt();
    let (_, a) = run_scene(&ball, &RunOverrides::default(), 10).unwrap();
    let e07 = RunOverrides {
        e: Some(0.7),
        ..RunOverrides::default()
    };
    let (_, b) = run_scene(&ball, &e07, 10).unwrap();
    let c = compare(&a, &b, &Tolerances::default());
    assert!(!c.within);
    let first = c.first.as_ref().unwrap();
    assert_eq!(
        first.place,
        Place::Impact {
            a: Some(0),
            b: Some(0),
            pair: "ball/floor".to_owned()
        },
        "{}",
        first.to_text()
    );
    assert_eq!(first.field, "v_s.n");
    let (va, vb) = (first.a.as_f64().unwrap(), first.b.as_f64().unwrap());
    assert!((va - 0.8 * v).abs() < 1e-9, "{va}");
    assert!((vb - 0.7 * v).abs() < 1e-9, "{vb}");
    assert!((first.abs.unwrap() - 0.1 * v).abs() < 1e-9);
    // The impact times agree up to the first impact and part after it.
    let t = c.quantities.iter().find(|q| q.name == "impacts.t").unwrap();
    let first_t = t.first.as_ref().unwrap();
    assert_eq!(
        first_t.place,
        Place::Impact {
            a: Some(1),
            b: Some(1),
            pair: "ball/floor".to_owned()
        }
    );
    // The settings differ and say so, without being a difference of their own.
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("material_overrides.e null and 0.7")),
        "{:?}",
        c.notes
    );
}

#[test]
fn samples_pair_with_their_own_time_under_a_loose_time_tolerance() {
    // B lacks A's sample at t = 0.5 s (as a run without an impact there lacks its two
    // samples): under time_tol = 1 s A's other samples still meet their own times.
    let (_, a) = run_scene(&scene("pendulum_wall"), &RunOverrides::default(), 20).unwrap();
    let mut b = a.clone();
    let k = b.checkpoints.iter().position(|s| s.t == 0.5).unwrap();
    b.checkpoints.remove(k);
    let loose = Tolerances {
        time_tol: 1.0,
        ..EXACT
    };
    let c = compare(&a, &b, &loose);
    assert!(c.within, "{:?}", c.first.map(|f| f.to_text()));
    let q = c.quantities.iter().find(|q| q.name == "samples.q").unwrap();
    assert_eq!(q.compared as usize, b.checkpoints.len());
}

#[test]
fn one_impact_less_is_a_difference_at_its_time() {
    let (_, a) = run_scene(&scene("pendulum_wall"), &RunOverrides::default(), 10).unwrap();
    let mut b = a.clone();
    let gone = b.impacts.remove(4);
    let c = compare(&a, &b, &Tolerances::default());
    assert!(!c.within);
    let first = c.first.as_ref().unwrap();
    // Matched per pair in order: impacts 0–3 match, A's #4 meets B's #5 and so on; the
    // first difference is at #4's time (its partner is another impact).
    assert_eq!(first.t, Some(gone.t), "{}", first.to_text());
    let count = c
        .quantities
        .iter()
        .find(|q| q.name == "impacts.count")
        .unwrap();
    assert_eq!(count.beyond, 2, "the unmatched impact and the total");
    assert_eq!(count.compared, 2);
    let unmatched = count.first.as_ref().unwrap();
    assert_eq!(
        unmatched.place,
        Place::Impact {
            a: Some(a.impacts.len() as u64 - 1),
            b: None,
            pair: gone.pair.clone()
        }
    );
    // A different type is a difference whatever the tolerances.
    let mut d = a.clone();
    d.impacts[2].case = 5;
    let loose = Tolerances {
        rtol: 1.0,
        atol: 1e9,
        time_tol: 1e9,
    };
    let c = compare(&a, &d, &loose);
    assert!(!c.within);
    assert_eq!(c.first.as_ref().unwrap().field, "case");
}

#[test]
fn a_tangent_chosen_the_other_way_round_is_the_same_impact() {
    let (_, a) = run_scene(&scene("falling_rod"), &RunOverrides::default(), 10).unwrap();
    // Row 3 written in the frame (n, −t) by hand: the same impact.
    let mut b = a.clone();
    let r = &mut b.impacts[3];
    (r.w.nt, r.v_a.t, r.v_s.t, r.i_t) = (-r.w.nt, -r.v_a.t, -r.v_s.t, -r.i_t);
    (r.tangent.x, r.tangent.y) = (-r.tangent.x, -r.tangent.y);
    (r.g, r.p, r.h, r.q) = (r.p, r.g, r.q, r.h);
    r.alpha = r.alpha.map(|x| -x);
    use ricochet::impact::CollisionType::*;
    r.impact_type = match r.impact_type {
        ForwardSliding => ReverseSliding,
        ReverseSliding => ForwardSliding,
        Sticking => Sticking,
    };
    // The impulse on the body in the world frame is unchanged.
    let (ia, ib) = (a.impacts[3].impulse(), b.impacts[3].impulse());
    assert_eq!((ia.x, ia.y), (ib.x, ib.y));
    let c = compare(&a, &b, &EXACT);
    assert!(c.within, "{:?}", c.first.map(|f| f.to_text()));
    assert!(
        c.notes
            .iter()
            .any(|n| n.starts_with("1 impacts of B have the tangent opposite"))
    );
    // A real difference in the mirrored row is still one.
    b.impacts[3].i_t *= 1.0 + 1e-6;
    let c = compare(&a, &b, &Tolerances::default());
    assert_eq!(c.first.as_ref().unwrap().field, "i_t");
}

#[test]
fn the_energy_scale_and_the_budget() {
    // A ball released from rest above the datum: E_ref = E_0 (the largest K + |V| of its
    // samples is the first, up to rounding of K + V).
    let budget = RunOverrides {
        max_drift: Some(1e-12),
        ..RunOverrides::default()
    };
    let (_, ball) = run_scene(&scene("bouncing_ball"), &budget, 10).unwrap();
    let (audit, drift) = (ball.audit.as_ref().unwrap(), ball.drift.unwrap());
    assert!((drift.energy_scale - audit.energy_initial).abs() <= 1e-15 * audit.energy_initial);
    assert_eq!(drift.integration_drift, audit.integration_drift);
    assert_eq!(
        drift.relative,
        Some(audit.integration_drift.abs() / drift.energy_scale)
    );
    assert_eq!(drift.max_drift, Some(1e-12));
    assert!(!drift.broken(), "{}", drift.describe());
    // The chain hangs from its pivot, released horizontally: E_0 = 0 to rounding; the
    // scale is its swing's K + |V| (the links' weight times their fall: at least a few J).
    let (_, chain) = run_scene(
        &scene("chain"),
        &RunOverrides {
            t_end: Some(0.85),
            max_drift: Some(1e-300),
            ..RunOverrides::default()
        },
        10,
    )
    .unwrap();
    let (audit, drift) = (chain.audit.as_ref().unwrap(), chain.drift.unwrap());
    assert!(
        audit.energy_initial.abs() < 1e-12,
        "{}",
        audit.energy_initial
    );
    let peak = (chain.checkpoints.iter())
        .map(|s| s.energy.kinetic + s.energy.potential.abs())
        .fold(0.0, Real::max);
    assert!(drift.energy_scale >= peak && peak > 1.0, "{drift:?}");
    let relative = drift.relative.unwrap();
    assert!(relative < 1e-9, "{relative:e}");
    assert!(drift.broken(), "a budget of 1e-300 breaks");
}

#[test]
fn a_rocking_ends_support_is_compared() {
    let (_, a) = run_scene(&scene("rocking_block"), &RunOverrides::default(), 10).unwrap();
    let k = (a.impacts.iter())
        .position(|i| i.support.is_some())
        .expect("a rocking end");
    let mut b = a.clone();
    b.impacts[k].support.as_mut().unwrap().i_n *= 1.0 + 1e-6;
    let c = compare(&a, &b, &Tolerances::default());
    assert_eq!(c.first.as_ref().unwrap().field, "support.i_n");
    b.impacts[k].support = None;
    let c = compare(&a, &b, &Tolerances::default());
    let first = c.first.as_ref().unwrap();
    assert_eq!(
        (first.field.as_str(), first.t),
        ("support", Some(a.impacts[k].t))
    );
}

/// Two equal pendulums striking head-on (Newton's cradle) have `m_nt = 0`, and with μ = 0
/// the sign case of Table 1 follows the sign of its rounding (g = −m_nt, p = m_nt). A
/// case that differs only because such a coefficient changed sign within the tolerances is
/// the same impact ([P, Comment g]: the same solution either side); the same flip beyond
/// the tolerances is a difference.
#[test]
fn a_sign_case_at_a_boundary_of_table_1_is_the_same_impact() {
    use ricochet::impact::{Coefficients, ContactVelocity, ImpactMatrix};
    let (_, a) = run_scene(&scene("newtons_cradle"), &RunOverrides::default(), 10).unwrap();
    let tol = Tolerances {
        rtol: 1e-8,
        atol: 1e-12,
        time_tol: 1e-9,
    };
    let flip = |nt: Real| {
        let mut b = a.clone();
        let r = &mut b.impacts[0];
        r.w = ImpactMatrix { nt, ..r.w };
        (r.g, r.p) = (-nt, nt);
        let v_a = ContactVelocity {
            n: r.v_a.n,
            t: r.v_a.t,
        };
        r.case = Coefficients::new(&r.w, 0.0, v_a).sign_case().number();
        b
    };
    let r0 = &a.impacts[0];
    assert!(r0.w.nt.abs() < 1e-12 * r0.w.nn, "m_nt = {}", r0.w.nt);
    // Within rounding of zero, the other sign: another case, the same impact.
    let tiny = if r0.w.nt > 0.0 { -1e-16 } else { 1e-16 } * r0.w.nn;
    let b = flip(tiny);
    assert_ne!(b.impacts[0].case, a.impacts[0].case);
    let c = compare(&a, &b, &tol);
    assert!(c.within, "{:?}", c.first.map(|f| f.to_text()));
    assert!(
        c.notes.iter().any(|n| n.contains("Comment g")),
        "{:?}",
        c.notes
    );
    // The same flip of a real m_nt is a difference, in the case too.
    let b = flip(tiny.signum() * 0.1 * r0.w.nn);
    assert_ne!(b.impacts[0].case, a.impacts[0].case);
    let c = compare(&a, &b, &tol);
    assert!(!c.within);
    assert_eq!(c.first.as_ref().unwrap().field, "case");
}
