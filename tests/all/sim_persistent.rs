//! Issue 5, event-driven: persistent contact after an accumulation of impacts, rocking
//! and walking against their closed forms, Painlevé's paradox flagged above its bound and
//! not below, and simultaneous impacts of a block and a rod landing flat.

use ricochet::sim::{
    ImpactCause, ImpactEvent, Level, MaterialOverride, PairMode, Recorder, RunSummary, Scales,
    Simulation, StopReason,
};

fn load(name: &str) -> ricochet::scene::Scene {
    ricochet::scene::load(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// Runs `scene` with `overrides`, keeping the samples.
pub(crate) fn run(
    scene: &ricochet::scene::Scene,
    overrides: MaterialOverride,
) -> (Recorder, RunSummary, Scales) {
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let mut rec = Recorder {
        keep_samples: true,
        ..Default::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary, sim.scales())
}

/// The generalized speeds just before and just after the impacts at `t`: the first and the
/// last sample taken at that instant.
fn speeds_around(rec: &Recorder, t: f64) -> (Vec<f64>, Vec<f64>) {
    let at: Vec<_> = rec.samples.iter().filter(|s| s.0 == t).collect();
    assert!(at.len() >= 2, "no samples around the impact at {t}");
    (at[0].2.clone(), at[at.len() - 1].2.clone())
}

/// The impacts of the scene's law: those that approached (a closing impulse at the end
/// of an accumulation does not).
fn law_impacts(rec: &Recorder) -> Vec<&ImpactEvent> {
    rec.impacts.iter().filter(|i| i.v_a.n < -1e-9).collect()
}

/// The energy audit closes: the drift is at the integrator's accuracy, and the ledger adds
/// up to the audit's ΣΔE.
fn assert_balanced(name: &str, rec: &Recorder, summary: &RunSummary) {
    let a = summary.audit;
    let scale = crate::common::energy_scale(&a, 1e-3);
    assert!(
        a.drift().abs() <= 1e-9 * scale,
        "{name}: drift {} of {scale}",
        a.drift()
    );
    let sum: f64 = rec.impacts.iter().map(|i| i.outcome.delta_e).sum();
    assert!((sum - a.impact_delta_e).abs() <= 1e-12 * scale, "{name}");
}

#[test]
fn falling_rod_comes_to_rest_flat_on_the_floor() {
    let scene = load("falling_rod");
    let (rec, summary, scales) = run(&scene, MaterialOverride::default());
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let (q, u) = (&summary.state.q, &summary.state.u);
    // Flat (θ = 0 mod π), the centre at the capsule's radius above the floor, at rest.
    let radius = 0.01;
    let tilt = q[2].sin().abs();
    println!(
        "falling_rod at {} s: tilt {tilt:.1e}, height − r {:.1e} m, |u| {:.1e}; {} impacts",
        summary.state.t,
        q[1] - radius,
        u.amax(),
        rec.impacts.len()
    );
    assert!(tilt <= 1e-9, "tilt {tilt}");
    assert!((q[1] - radius).abs() <= scales.gap_tol, "height {}", q[1]);
    assert!(u.amax() <= 1e-9, "speeds {u}");
    // Both ends held, not slipping: the last transition leaves the pair sticking.
    let last = rec.transitions.last().unwrap();
    assert_eq!(last.to, PairMode::Sticking, "{last:?}");
    // Its energy is the potential energy of the resting rod, E = m g r; the ledger, the
    // friction work while it slid, and the drift explain the loss.
    let e_end = summary.audit.end.total();
    assert!((e_end - 9.81 * radius).abs() <= 1e-9, "E_end = {e_end}");
    assert_balanced("falling_rod", &rec, &summary);
}

#[test]
fn rocking_block_loses_housners_ratio_at_every_impact() {
    // Plastic impacts that stick on a corner: the angular momentum about the new corner is
    // conserved, ω⁺/ω⁻ = 1 − (3/2) sin²α with tan α = b/h (Housner 1963).
    let scene = load("rocking_block");
    let (rec, summary, _) = run(&scene, MaterialOverride::default());
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let alpha = (0.2f64 / 0.5).atan();
    let housner = 1.0 - 1.5 * alpha.sin().powi(2);
    let impacts = law_impacts(&rec);
    assert!(impacts.len() >= 20, "{} impacts", impacts.len());
    // The accumulation ends at the instant of its plastic impact, reported with the
    // passage to rest at t∞ (later); at that instant the lifting corner is held down
    // (rocking_end), so the ratio holds for the impacts before it.
    let rest = (rec.transitions.iter())
        .find(|tr| tr.t_accumulation.is_some())
        .unwrap();
    assert_eq!(Some(rest.t), rest.t_accumulation);
    let ending = (rec.impacts.iter())
        .find(|i| i.cause == ImpactCause::AccumulationEnd)
        .unwrap();
    assert!(ending.t < rest.t, "{} {}", ending.t, rest.t);
    let t_rest = ending.t;
    let mut worst = 0.0f64;
    for ev in impacts.iter().filter(|ev| ev.t < t_rest) {
        assert_eq!(ev.outcome.kind.name(), "sticking");
        let (before, after) = speeds_around(&rec, ev.t);
        let ratio = after[2] / before[2];
        worst = worst.max((ratio - housner).abs());
        assert!(
            (ratio - housner).abs() <= 1e-9,
            "t = {}: ω⁺/ω⁻ = {ratio} vs {housner}",
            ev.t
        );
    }
    println!(
        "rocking_block: Housner's ratio {housner:.6}, worst error {worst:.1e}; rests at {t_rest:.6} s"
    );
    // It ends resting on its base: flat, at rest, with E = m g h.
    assert!(summary.state.q[2].abs() <= 1e-9 && summary.state.u.amax() <= 1e-9);
    assert!((summary.audit.end.total() - 10.0 * 9.81 * 0.5).abs() <= 1e-8);
    assert_balanced("rocking_block", &rec, &summary);
}

/// The contact impulse a tight run delivers at each corner of the rocking block from the
/// end of the impact at `t0` until its own rocking end (whose entries include their
/// support until its `t∞`): its impacts, and the force of the pivot corner over each hop
/// between them, from the momentum balance of the hop, `m Δv − m g Δt` (one corner
/// touches). Corners by the sign of `x − x_c`; world components `(x, y)`.
fn delivered_after(rec: &Recorder, t0: f64) -> [[f64; 2]; 2] {
    let (m, g) = (10.0, 9.81);
    let corner = |ev: &ImpactEvent, q: &[f64]| usize::from(ev.frame.point().x > q[0]);
    let mut total = [[0.0; 2]; 2];
    let times: Vec<f64> = {
        let mut ts: Vec<f64> = (rec.impacts.iter())
            .filter(|i| i.t >= t0)
            .map(|i| i.t)
            .collect();
        ts.dedup();
        ts
    };
    for (k, &t) in times.iter().enumerate() {
        let (before, after) = speeds_around(rec, t);
        let q = &rec.samples.iter().find(|s| s.0 == t).unwrap().1;
        let here: Vec<&ImpactEvent> = rec.impacts.iter().filter(|i| i.t == t).collect();
        if k > 0 {
            for ev in &here {
                let i = ev.impulse();
                let w = i.n * ev.frame.n + i.t * ev.frame.t;
                total[corner(ev, q)][0] += w.x;
                total[corner(ev, q)][1] += w.y;
            }
        }
        // The hop that follows, on the corner struck last at t.
        let Some(&next) = times.get(k + 1) else { break };
        if here.iter().any(|i| i.cause == ImpactCause::RockingEnd) {
            break;
        }
        let pivot = corner(here.last().unwrap(), q);
        let (arrive, _) = speeds_around(rec, next);
        total[pivot][0] += m * (arrive[0] - after[0]);
        total[pivot][1] += m * (arrive[1] - after[1]) + m * g * (next - t);
        let _ = before;
    }
    total
}

#[test]
fn rocking_end_reports_the_impulse_of_the_hops_left_never_a_pull() {
    // Issue 11: the end of a rocking accumulation pulled the lifting corner down
    // (I_n = −6.9e-3 N·s). Its entries now report the contact impulse of the hops left —
    // the jump that stops them plus the support of the closed corners until t∞ — which
    // must be ≥ 0, in the friction cone, and equal to what a run that resolves those hops
    // (tolerances 1000 times tighter: about 15 more hops) delivers at each corner.
    let scene = load("rocking_block");
    let (loose, _, _) = run(&scene, MaterialOverride::default());
    let ends: Vec<&ImpactEvent> = (loose.impacts.iter())
        .filter(|i| i.cause == ImpactCause::RockingEnd)
        .collect();
    assert_eq!(ends.len(), 2, "both corners");
    for ev in &ends {
        let (i, s) = (ev.impulse(), ev.support.unwrap());
        assert!(i.n > 0.0 && i.t.abs() <= ev.material.mu * i.n, "{i:?}");
        // The jump is what Eq. (16) applied: Δu = M⁻¹ Jᵀ (I − S), and Eq. (29) is its.
        assert_eq!(ev.outcome.impulse.n + s.impulse.n, i.n);
        assert!(s.duration > 0.0 && s.impulse.n > 0.0, "{s:?}");
    }
    // Every other entry is an impulse ≥ 0 of the scene's law.
    assert!(loose.impacts.iter().all(|i| i.impulse().n > 0.0));
    let t_c = ends[0].t;
    let mut tight_scene = load("rocking_block");
    tight_scene.settings.integrator.rtol = 1e-13;
    tight_scene.settings.integrator.atol = 1e-15;
    let (tight, summary, _) = run(&tight_scene, MaterialOverride::default());
    assert!(matches!(summary.stop, StopReason::EndTime));
    let resolved = (tight.impacts.iter())
        .filter(|i| i.t > t_c + 1e-9 && i.cause != ImpactCause::RockingEnd)
        .count();
    assert!(resolved >= 10, "{resolved} hops resolved after {t_c}");
    // The tight run's impact at t_c (the same one, to its integration error).
    let t0 = (tight.impacts.iter())
        .map(|i| i.t)
        .min_by(|a, b| (a - t_c).abs().total_cmp(&(b - t_c).abs()))
        .unwrap();
    assert!((t0 - t_c).abs() <= 1e-8, "{t0} vs {t_c}");
    let delivered = delivered_after(&tight, t0);
    let q_c = &loose.samples.iter().find(|s| s.0 == t_c).unwrap().1;
    // The normal impulse of each corner is determined (the balances of momentum along y
    // and of angular momentum); along x only their sum is: two corners at one height
    // can share a horizontal impulse in any way (an internal force of the rigid body).
    let mut x_sum = [0.0; 2];
    for ev in &ends {
        let c = usize::from(ev.frame.point().x > q_c[0]);
        let i = ev.impulse();
        let w = i.n * ev.frame.n + i.t * ev.frame.t;
        let dy = w.y - delivered[c][1];
        println!(
            "rocking end, corner {c}: ({:.6e}, {:.6e}) N·s reported, ({:.6e}, {:.6e}) delivered \
             by {resolved} resolved hops; normal difference {dy:.1e}",
            w.x, w.y, delivered[c][0], delivered[c][1]
        );
        assert!(dy.abs() <= 1e-5 * w.y.abs(), "normal: {dy} of {}", w.y);
        x_sum[0] += w.x;
        x_sum[1] += delivered[c][0];
    }
    let dx = x_sum[0] - x_sum[1];
    println!(
        "both corners along x: {:.6e} reported, {:.6e} delivered",
        x_sum[0], x_sum[1]
    );
    assert!(dx.abs() <= 1e-5 * ends[0].impulse().n, "along x: {dx}");
}

#[test]
fn rimless_wheel_loses_the_closed_form_ratio_at_every_step_and_settles_into_a_gait() {
    // A plastic impact that sticks at the new spoke tip while the old one leaves: the
    // angular momentum about the new tip is conserved, so the hub's angular speed drops by
    // (I + m L² cos 2α)/(I + m L²), with 2α the angle between spokes.
    let scene = load("rimless_wheel");
    let (rec, summary, _) = run(&scene, MaterialOverride::default());
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let (m, l, i_c) = (2.4f64, 0.5f64, 8.0 * 0.05 * 0.25 / 3.0);
    let two_alpha = std::f64::consts::PI / 4.0;
    let ratio_exact = (i_c + m * l * l * two_alpha.cos()) / (i_c + m * l * l);
    let impacts = law_impacts(&rec);
    assert!(impacts.len() >= 15, "{} impacts", impacts.len());
    let mut worst = 0.0f64;
    for ev in &impacts {
        assert_eq!(ev.outcome.kind.name(), "sticking", "t = {}", ev.t);
        let (before, after) = speeds_around(&rec, ev.t);
        let ratio = after[2] / before[2];
        worst = worst.max((ratio - ratio_exact).abs());
        assert!(
            (ratio - ratio_exact).abs() <= 1e-9,
            "t = {}: {ratio} vs {ratio_exact}",
            ev.t
        );
    }
    // The periodic gait: each step loses at its impact what it gains going down the slope,
    // m g (2 L sin α) sin γ.
    let gain = m * 9.81 * 2.0 * l * (two_alpha / 2.0).sin() * 0.1f64.sin();
    let last = impacts.last().unwrap().outcome.delta_e;
    println!(
        "rimless_wheel: ratio {ratio_exact:.6}, worst error {worst:.1e}; last step ΔE {last:.6} J vs −{gain:.6} J"
    );
    assert!((last + gain).abs() <= 1e-3 * gain, "{last} vs {gain}");
    assert_balanced("rimless_wheel", &rec, &summary);
}

fn painleve(mu: f64) -> (Recorder, RunSummary) {
    let scene = load("painleve_rod");
    let overrides = MaterialOverride {
        mu: Some(mu),
        ..Default::default()
    };
    let (rec, summary, _) = run(&scene, overrides);
    (rec, summary)
}

#[test]
fn painleve_rod_is_flagged_above_the_bound_and_not_below() {
    // The rod slides on its end A at θ = 60°: the normal acceleration of A per unit normal
    // force is (1 + 3 cos²θ − 3 μ sin θ cos θ)/m, which vanishes at μ = 1.347 here (and the
    // bound over all θ is μ = 4/3).
    let theta = 60f64.to_radians();
    let coefficient =
        |mu: f64| 1.0 + 3.0 * theta.cos().powi(2) - 3.0 * mu * theta.sin() * theta.cos();
    assert!(coefficient(1.5) < 0.0 && coefficient(1.3) > 0.0);

    let (rec, summary) = painleve(1.5);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let flagged: Vec<_> = (rec.messages.iter())
        .filter(|(_, _, m)| m.contains("Painlevé"))
        .collect();
    assert!(!flagged.is_empty());
    let (t, level, text) = flagged[0];
    assert_eq!((*t, *level), (0.0, Level::Warning));
    assert!(
        text.contains("rod/floor") && text.contains("t = 0 s"),
        "{text}"
    );
    // The reported coefficient is the closed form (m = 1 kg), and the rule applied is an
    // impact without collision: the first impact, at t = 0 with no approach, sticks.
    let reported = format!("{:.4e}", coefficient(1.5));
    assert!(text.contains(&reported), "{text} vs {reported}");
    let iwc = &rec.impacts[0];
    assert_eq!((iwc.t, iwc.v_a.n), (0.0, 0.0));
    assert_eq!(iwc.outcome.kind.name(), "sticking");
    assert!(iwc.outcome.v_s.t.abs() <= 1e-12, "{:?}", iwc.outcome.v_s);
    assert_balanced("painleve_rod μ = 1.5", &rec, &summary);

    for mu in [0.3, 1.0, 1.3] {
        let (rec, summary) = painleve(mu);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "μ = {mu}: {}",
            summary.stop
        );
        assert!(
            rec.messages.iter().all(|(_, _, m)| !m.contains("Painlevé")),
            "μ = {mu}: {:?}",
            rec.messages
        );
        // It slides from the start: no impact at t = 0.
        assert!(rec.impacts.iter().all(|i| i.t > 0.0), "μ = {mu}");
        assert_eq!(rec.transitions[0].to, PairMode::Sliding, "μ = {mu}");
        assert_balanced(&format!("painleve_rod μ = {mu}"), &rec, &summary);
    }
}

/// A body dropped flat from rest, its base `drop` above the floor (e = 0.5, μ = 0.5).
fn flat_scene(shape: &str) -> ricochet::scene::Scene {
    let text = format!(
        r#"
version = 1
name = "flat"
gravity = [0.0, -9.81]
[run]
t_end = 2.0
output_rate = 200.0
[contact]
law = "newton"
e = 0.5
mu = 0.5
[[body]]
name = "body"
mass = 2.0
inertia = 0.1
joint = {{ type = "planar", x = 0.3, y = 0.5, angle = "0 rad" }}
[[body.shape]]
{shape}
[[obstacle]]
name = "floor"
type = "halfspace"
point = [0.0, 0.0]
normal = [0.0, 1.0]
"#
    );
    ricochet::scene::load_str(&text, "flat.toml").unwrap()
}

#[test]
fn a_block_and_a_rod_landing_flat_strike_at_both_ends_at_once() {
    // Base 0.5 − 0.1 = 0.4 m above the floor for both.
    for (what, shape) in [
        ("block", "type = \"cuboid\"\nhalf_extents = [0.4, 0.1]"),
        (
            "rod",
            "type = \"capsule\"\na = [-0.5, 0.0]\nb = [0.5, 0.0]\nradius = 0.1",
        ),
    ] {
        let scene = flat_scene(shape);
        let (rec, summary, scales) = run(&scene, MaterialOverride::default());
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "{what}: {}",
            summary.stop
        );
        // The first landing: both ends at once, one ledger entry each, at the closed form
        // t1 = √(2 h / g), with equal impulses m (1 + e) v1 / 2 and no friction (no
        // tangential motion), the body staying level.
        let (g, h, m, e) = (9.81f64, 0.4f64, 2.0f64, 0.5f64);
        let (t1, v1) = ((2.0 * h / g).sqrt(), (2.0 * g * h).sqrt());
        let first: Vec<_> = rec
            .impacts
            .iter()
            .filter(|i| i.t == rec.impacts[0].t)
            .collect();
        assert_eq!(
            first.len(),
            2,
            "{what}: {:?}",
            rec.impacts.iter().map(|i| i.t).collect::<Vec<_>>()
        );
        assert!(
            (first[0].t - t1).abs() <= 1e-9,
            "{what}: {} vs {t1}",
            first[0].t
        );
        let closed_form = m * (1.0 + e) * v1 / 2.0;
        for ev in &first {
            assert!(
                (ev.outcome.impulse.n - closed_form).abs() <= 1e-9 * closed_form,
                "{what}: {ev:?}"
            );
            assert!(ev.outcome.impulse.t.abs() <= 1e-12, "{what}");
        }
        assert!(
            rec.messages.iter().any(|(t, l, m)| *t == first[0].t
                && *l == Level::Warning
                && m.contains("simultaneous impact")),
            "{what}: {:?}",
            rec.messages
        );
        // Every landing is level: the angle and the spin stay zero through all samples.
        for (t, q, u, _) in &rec.samples {
            assert!(
                q[2].abs() <= 1e-12 && u[2].abs() <= 1e-12,
                "{what}: t = {t}: θ {} ω {}",
                q[2],
                u[2]
            );
        }
        // It comes to rest on its base, flat, when the hops accumulate.
        let rest = rec
            .transitions
            .iter()
            .find(|tr| tr.t_accumulation.is_some())
            .unwrap();
        let t_inf = t1 + 2.0 * v1 / g * e / (1.0 - e);
        assert!(
            (rest.t_accumulation.unwrap() - t_inf).abs() <= 1e-6,
            "{what}: {rest:?} vs {t_inf}"
        );
        assert!(
            (summary.state.q[1] - 0.1).abs() <= scales.gap_tol,
            "{what}: {}",
            summary.state.q[1]
        );
        assert!(summary.state.u.amax() <= 1e-9, "{what}");
        assert_balanced(what, &rec, &summary);
    }
}

#[test]
fn mode_changes_reach_the_log_and_the_state_messages() {
    use ricochet::log::{ContactMode, LogOptions, LogWriter, RunLogger, Topic};
    use std::io::Cursor;
    let scene = load("falling_rod");
    let overrides = MaterialOverride::default();
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).unwrap();
    let mut log = RunLogger::for_scene(writer, &scene, &overrides, sim.scales().gap_tol).unwrap();
    let summary = sim.run(&scene.initial, &mut log, None);
    let bytes = log.finish(&summary).unwrap().into_inner();
    let read = ricochet::log::read_bytes(&bytes).unwrap();
    // The rod ends lying on the floor: its contact is sticking in the last /state.
    let last = read.last_state.as_ref().unwrap();
    assert_eq!(last.contacts.len(), 1);
    assert_eq!(last.contacts[0].mode, ContactMode::Sticking);
    assert_eq!(last.mode, ContactMode::Sticking);
    // Every transition and the accumulation's end are on /log, with the run's own
    // messages (a recorder of the same run sees them).
    let mut rec = Recorder::default();
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    sim.run(&scene.initial, &mut rec, None);
    assert!(!rec.transitions.is_empty());
    // The run's messages and one line per impact.
    assert_eq!(
        read.count(Topic::Log),
        (rec.messages.len() + rec.impacts.len()) as u64
    );
    for tr in &rec.transitions {
        assert!(
            rec.messages
                .iter()
                .any(|(t, _, m)| *t == tr.t && m.contains(&tr.note)),
            "{tr:?}"
        );
    }
}

/// Newton's cradle under RK4 (its fixed step, 1e-3 s): after the first instant balls 1–4
/// rest touching, three closed points with forces of rounding (1.9e-17 N at the
/// selection). At t = 0.9578 s their `b` fell to 1.8e-32 and the right-hand side refused
/// regular equations whose solution `x_ref + δ` carried the rounding of the reference
/// (tolerance of the solution's own scale): "the forces of the closed contact points have
/// no solution", the run stopped (nothing drifted: normal velocities of 1e-33 m/s). Now it
/// reaches its end with the three instants of DOPRI5's run (four impacts each) and its
/// energy kept.
#[test]
fn newtons_cradle_under_rk4_reaches_its_end() {
    let mut scene = load("newtons_cradle");
    scene.settings.integrator.method = ricochet::integrate::Method::Rk4;
    let (rec, summary, _) = run(&scene, MaterialOverride::default());
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    assert_eq!(rec.impacts.len(), 12);
    let mut instants: Vec<f64> = rec.impacts.iter().map(|i| i.t).collect();
    instants.dedup();
    assert_eq!(instants.len(), 3, "{instants:?}");
    let (e0, e_end) = (rec.samples[0].3, rec.samples.last().unwrap().3);
    assert!((e_end - e0).abs() <= 1e-10 * e0.abs(), "{e0} → {e_end}");
}
