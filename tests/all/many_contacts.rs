//! Many contacts at one instant (issue 15): independent contacts stay independent (each a
//! one-point problem, the paper's law), and the rule for simultaneous impacts of coupled
//! points is the scene's choice (Newton's cradle).

use ricochet::impact::Law;
use ricochet::math::Real;
use ricochet::scene::Scene;
use ricochet::settings::Simultaneous;
use ricochet::sim::{ImpactCause, MaterialOverride, Recorder, RunSummary, Simulation, StopReason};

const G: Real = 9.81;

fn load_text(text: &str, name: &str) -> Scene {
    ricochet::scene::load_str(text, format!("{name}.toml")).unwrap()
}

fn load(name: &str) -> Scene {
    let path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    load_text(&std::fs::read_to_string(path).unwrap(), name)
}

fn run(scene: &Scene) -> (Recorder, RunSummary) {
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut rec = Recorder {
        keep_samples: true,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary)
}

/// `n` balls (radius 0.1 m, 1 kg) 1 m apart, their centres at height `y0` above a floor
/// (e = 0.5, μ = 0.1), dropped together: they land at the same instant and never touch
/// each other.
fn balls(n: usize, y0: Real) -> String {
    let mut s = String::from(
        "version = 1\nname = \"balls\"\ngravity = [0.0, -9.81]\n[run]\nt_end = 1.0\n\
         output_rate = 100.0\n[contact]\ne = 0.5\nmu = 0.1\n",
    );
    for i in 0..n {
        s.push_str(&format!(
            "[[body]]\nname = \"b{i}\"\nmass = 1.0\ninertia = 0.01\n\
             joint = {{ type = \"planar\", x = {i}.0, y = {y0} }}\n\
             [[body.shape]]\ntype = \"ball\"\nradius = 0.1\n"
        ));
    }
    s.push_str(
        "[[obstacle]]\nname = \"floor\"\ntype = \"halfspace\"\npoint = [0.0, 0.0]\n\
         normal = [0.0, 1.0]\n",
    );
    s
}

/// The height of a ball's centre at `t`, dropped from rest at `y0` onto a floor with
/// restitution `e` (radius `r`): the closed form of the bouncing ball.
fn bouncing_height(y0: Real, r: Real, e: Real, t: Real) -> Real {
    let mut t0 = 0.0;
    let mut v = 0.0; // upward speed at t0, at height r (after the first hop: at the floor)
    let mut y = y0;
    loop {
        // Time to the floor from (y, v): y + v τ − g τ²/2 = r.
        let tau = (v + (v * v + 2.0 * G * (y - r)).sqrt()) / G;
        if t0 + tau > t {
            let s = t - t0;
            return y + v * s - 0.5 * G * s * s;
        }
        t0 += tau;
        v = e * (G * tau - v);
        y = r;
    }
}

/// Seven balls landing on one floor at the same instant: seven independent one-point
/// impacts (a group each), not one problem of seven contacts. The repro
/// (`shared/repro/seven_balls.toml`) stopped at t = 0.428353 s with "more than the exact
/// enumeration … handles (6)". Each impact is the scene's one-point law, each ball
/// follows the closed form, and the seven motions are each that of a ball falling alone.
#[test]
fn seven_balls_landing_at_once_are_seven_one_point_impacts() {
    let scene = load_text(&balls(7, 1.0), "balls");
    let (rec, summary) = run(&scene);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{:?}",
        summary.stop
    );
    // Two bounces each in 1 s: at √(2·0.9/g) = 0.42835 s and 3 × that later (e = 0.5).
    assert_eq!(rec.impacts.len(), 14);
    let t1 = (2.0 * 0.9 / G).sqrt();
    for ev in &rec.impacts {
        assert_eq!(ev.cause, ImpactCause::Collision, "{ev:?}");
        assert_eq!(ev.outcome.law, Law::Newton);
        // The one-point law on a ball: I_n = (1 + e) m |v_n|, no tangential impulse.
        let i_n = 1.5 * ev.v_a.n.abs();
        assert!((ev.outcome.impulse.n - i_n).abs() <= 1e-12 * i_n, "{ev:?}");
        assert!(ev.outcome.impulse.t.abs() <= 1e-15, "{ev:?}");
    }
    for ev in rec.impacts.iter().take(7) {
        assert!((ev.t - t1).abs() < 1e-12, "t = {}", ev.t);
    }
    // Each ball at the end against the closed form, and against a ball falling alone.
    let alone = run(&load_text(&balls(1, 1.0), "balls"));
    let y_alone = alone.1.state.q[1];
    let y_exact = bouncing_height(1.0, 0.1, 0.5, 1.0);
    assert!((y_alone - y_exact).abs() < 1e-9, "{y_alone} vs {y_exact}");
    for i in 0..7 {
        let (x, y) = (summary.state.q[3 * i], summary.state.q[3 * i + 1]);
        assert_eq!(x, i as Real, "ball {i} moved sideways");
        assert!((y - y_exact).abs() < 1e-9, "ball {i}: {y} vs {y_exact}");
        assert!(
            (y - y_alone).abs() <= 1e-12,
            "ball {i}: {y} vs alone {y_alone}"
        );
    }
}

/// The speeds `(θ̇₁ … θ̇₅)` just before and just after the first impact instant of a
/// cradle run: the first and last samples taken at that instant.
fn around_first_impact(rec: &Recorder) -> (Vec<Real>, Vec<Real>) {
    let t = rec.impacts[0].t;
    let at: Vec<&(Real, Vec<Real>, Vec<Real>, Real)> =
        rec.samples.iter().filter(|s| s.0 == t).collect();
    assert!(at.len() >= 2, "samples at the impact: {}", at.len());
    (at[0].2.clone(), at[at.len() - 1].2.clone())
}

fn cradle(rule: Simultaneous) -> (Recorder, RunSummary) {
    let mut scene = load("newtons_cradle");
    scene.settings.simultaneous = rule;
    run(&scene)
}

/// Newton's cradle under the sequential rule: the one-point law [P] one contact at a
/// time passes the rate of ball 1 down the row — for equal pendulums and e = 1 each
/// impact exchanges the two rates — so balls 1–4 stop and ball 5 leaves with ball 1's
/// rate; four impacts at one instant, energy kept.
#[test]
fn newtons_cradle_sequential_passes_the_momentum_down_the_row() {
    let (rec, summary) = cradle(Simultaneous::Sequential);
    assert!(matches!(summary.stop, StopReason::EndTime));
    let (before, after) = around_first_impact(&rec);
    let w = before[0];
    assert!(w > 1.0, "ball 1 swings in: {before:?}");
    for (k, b) in before.iter().enumerate().skip(1) {
        assert_eq!(*b, 0.0, "ball {} at rest before", k + 1);
    }
    for (k, a) in after.iter().enumerate().take(4) {
        assert!(a.abs() <= 1e-13 * w, "ball {} after: {after:?}", k + 1);
    }
    assert!((after[4] - w).abs() <= 1e-13 * w, "{after:?}");
    let first: Vec<_> = (rec.impacts.iter())
        .filter(|ev| ev.t == rec.impacts[0].t)
        .collect();
    assert_eq!(first.len(), 4);
    for (k, ev) in first.iter().enumerate() {
        assert_eq!(ev.cause, ImpactCause::Collision);
        assert!(
            ev.frame.pair.colliders(5).is_some(),
            "a pair of the five balls"
        );
        // e = 1: each contact separates as fast as it approached.
        assert!(
            (ev.outcome.v_s.n + ev.v_a.n).abs() <= 1e-13,
            "impact {k}: {ev:?}"
        );
    }
    // Energy, kept by e = 1 without friction: every impact's Eq. (29) is zero to rounding,
    // and the model's total drifts only by the integration error, relative to the energy
    // in the swing, m g L (1 − cos 30°).
    let swing = 0.5 * G * 0.4 * (1.0 - (30.0 as Real).to_radians().cos());
    for ev in &rec.impacts {
        assert!(ev.outcome.delta_e.abs() <= 1e-14 * swing, "{ev:?}");
    }
    let e0 = rec.samples[0].3;
    let e_end = rec.samples.last().unwrap().3;
    assert!((e_end - e0).abs() <= 1e-8 * swing, "{e0} → {e_end}");
}

/// A plastic cradle (e = 0, found by fuzzing the bundled scenes): the sequential rule's
/// pairwise impacts among the five touching balls converge without end (each plastic
/// impact leaves the pair together and the next one behind it approaching, ~12 % slower),
/// so the instant does not settle in its rounds: a failure whose message says so and
/// names the rule that resolves the group at once. Moreau's generalized Newton law does:
/// all five balls leave the instant at ball 1's rate over five (momentum of equal
/// pendulums), to the end time.
#[test]
fn a_plastic_cradle_needs_the_generalized_law() {
    let mut scene = load("newtons_cradle");
    scene.settings.t_end = 0.4;
    let plastic = MaterialOverride {
        e: Some(0.0),
        ..MaterialOverride::default()
    };
    let mut sim = Simulation::new(&scene.model, &scene.settings, plastic).unwrap();
    let summary = sim.run(&scene.initial, &mut Recorder::default(), None);
    let StopReason::Failed(e) = &summary.stop else {
        panic!("{}", summary.stop)
    };
    let message = e.to_string();
    assert!(
        message.contains("did not settle") && message.contains("generalized-newton"),
        "{message}"
    );
    scene.settings.simultaneous = Simultaneous::GeneralizedNewton;
    let mut sim = Simulation::new(&scene.model, &scene.settings, plastic).unwrap();
    let mut rec = Recorder {
        keep_samples: true,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let (before, after) = around_first_impact(&rec);
    let v = before[0] / 5.0;
    for (k, w) in after.iter().enumerate() {
        assert!(
            (w - v).abs() < 1e-9 * v.abs(),
            "ball {k}: {w} vs {v} ({after:?})"
        );
    }
}

/// Newton's cradle under the generalized Newton law. Ball 1 strikes ball 2 alone: the
/// one-point law, the rates exchange (ω₂ = ω). Ball 2 then strikes the row 3–5 it
/// touches: Moreau's law over the three touching contacts 2–3, 3–4, 4–5 with the
/// pendulums' equal effective mass m̄ at the contacts, `W = (1/m̄) tridiag(−1, 2, −1)`,
/// `v⁻ = (−v, 0, 0)`; all three closed, `v⁺ = −e v⁻ = (v, 0, 0)`, so
/// `P = W⁻¹ (2v, 0, 0) = m̄ v (3/2, 1, 1/2) ≥ 0` (consistent): ball 2 goes back at
/// −v/2, balls 3–5 leave at v/2. Then ball 2 strikes ball 1, at rest: the rates
/// exchange. After the instant: (−ω/2, 0, ω/2, ω/2, ω/2); momentum and energy kept.
#[test]
fn newtons_cradle_generalized_law_moves_the_whole_row() {
    let (rec, summary) = cradle(Simultaneous::GeneralizedNewton);
    assert!(matches!(summary.stop, StopReason::EndTime));
    let (before, after) = around_first_impact(&rec);
    let w = before[0];
    let expected = [-0.5 * w, 0.0, 0.5 * w, 0.5 * w, 0.5 * w];
    for k in 0..5 {
        assert!(
            (after[k] - expected[k]).abs() <= 1e-12 * w,
            "ball {}: {} vs {} ({after:?})",
            k + 1,
            after[k],
            expected[k]
        );
    }
    let causes: Vec<ImpactCause> = (rec.impacts.iter())
        .filter(|ev| ev.t == rec.impacts[0].t)
        .map(|ev| ev.cause)
        .collect();
    assert_eq!(causes[0], ImpactCause::Collision);
    assert!(
        causes[1..].contains(&ImpactCause::Simultaneous),
        "{causes:?}"
    );
}

/// The rule is read from the scene and from the overrides, and a bad name is a located
/// error.
#[test]
fn the_rule_is_a_scene_setting_with_a_located_error() {
    assert_eq!(
        load("newtons_cradle").settings.simultaneous,
        Simultaneous::Sequential
    );
    let text = std::fs::read_to_string(format!(
        "{}/scenes/newtons_cradle.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("simultaneous"))
        .unwrap();
    let bad = text.replace("simultaneous = \"sequential\"", "simultaneous = \"both\"");
    let err = ricochet::scene::load_str(&bad, "cradle.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&format!("cradle.toml:{line}:")) && err.contains("simultaneous"),
        "{err}"
    );
    let mut settings = ricochet::settings::Settings::default();
    ricochet::regress::RunOverrides {
        simultaneous: Some(Simultaneous::Sequential),
        ..Default::default()
    }
    .apply(&mut settings)
    .unwrap();
    assert_eq!(settings.simultaneous, Simultaneous::Sequential);
    assert_eq!(
        "generalized-newton".parse::<Simultaneous>().unwrap(),
        Simultaneous::GeneralizedNewton
    );
}

/// A block 0.4 m × 0.2 m (2 kg) on a slope through the origin at `theta_deg`, resting on
/// its two lower corners (its centre 0.1 m above the slope), at rest; friction `mu`,
/// e = 0.
fn block_on_slope(theta_deg: Real, mu: Real) -> String {
    let th = theta_deg.to_radians();
    let n = (-th.sin(), th.cos());
    format!(
        "version = 1\nname = \"slope\"\ngravity = [0.0, -9.81]\n[run]\nt_end = 1.0\n\
         output_rate = 100.0\n[contact]\ne = 0.0\nmu = {mu}\n[[body]]\nname = \"block\"\n\
         mass = 2.0\ninertia = 0.03333333333333333\n\
         joint = {{ type = \"planar\", x = {:?}, y = {:?}, angle = \"{theta_deg} deg\" }}\n\
         [[body.shape]]\ntype = \"cuboid\"\nhalf_extents = [0.2, 0.1]\n[[obstacle]]\n\
         name = \"slope\"\ntype = \"halfspace\"\npoint = [0.0, 0.0]\nnormal = [{:?}, {:?}]\n",
        0.1 * n.0,
        0.1 * n.1,
        n.0,
        n.1
    )
}

/// A block on two corners on a 30° slope: below tan 30° it slides down along the slope
/// as s = ½ g (sin θ − μ cos θ) t² without turning; from μ = tan 30° = 0.577 on it stays
/// where it is, whatever the split of the friction between its corners (statically
/// indeterminate with both sticking). Before issue 15 it stuck only from μ = 0.812 (what
/// an equal split needs: the lower corner carries more of the weight) and reported "no
/// consistent mode" or stalled in between.
#[test]
fn a_block_on_two_corners_slides_or_sticks_on_a_slope_as_coulomb_says() {
    let th = (30.0 as Real).to_radians();
    for mu in [0.0, 0.3, 0.5, 0.57, 0.58, 0.6, 0.7, 0.81, 0.9, 1.5] {
        let scene = load_text(&block_on_slope(30.0, mu), "slope");
        let q0 = scene.initial.q.clone();
        let (rec, summary) = run(&scene);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "μ = {mu}: {:?}",
            summary.stop
        );
        assert!(
            rec.impacts.is_empty(),
            "μ = {mu}: {} impacts",
            rec.impacts.len()
        );
        let q = &summary.state.q;
        // Displacement down the slope, along −(cos θ, sin θ); and off it, along n.
        let (dx, dy) = (q[0] - q0[0], q[1] - q0[1]);
        let down = -(dx * th.cos() + dy * th.sin());
        let off = -dx * th.sin() + dy * th.cos();
        let s = 0.5 * G * (th.sin() - mu * th.cos()).max(0.0);
        assert!(
            (down - s).abs() <= 1e-9 * (1.0 + s),
            "μ = {mu}: {down} vs {s}"
        );
        assert!(off.abs() <= 1e-9, "μ = {mu}: off the slope by {off}");
        assert!(
            (q[2] - q0[2]).abs() <= 1e-9,
            "μ = {mu}: turned by {}",
            q[2] - q0[2]
        );
    }
}

/// A block (0.4 m × 0.2 m) dropped flat from 0.3 m onto a floor, e = 0.5, no friction:
/// both lower corners strike at once, one problem of two coupled points (Moreau's law,
/// symmetric): it rebounds at half its impact speed √(2 g h) without turning.
#[test]
fn a_block_landing_flat_rebounds_at_half_speed_without_turning() {
    let text = "version = 1\nname = \"flat\"\ngravity = [0.0, -9.81]\n[run]\nt_end = 0.3\n\
                output_rate = 100.0\n[contact]\ne = 0.5\nmu = 0.0\n[[body]]\nname = \"block\"\n\
                mass = 2.0\ninertia = 0.03333333333333333\n\
                joint = { type = \"planar\", x = 0.0, y = 0.4 }\n[[body.shape]]\n\
                type = \"cuboid\"\nhalf_extents = [0.2, 0.1]\n[[obstacle]]\nname = \"floor\"\n\
                type = \"halfspace\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n";
    let (rec, summary) = run(&load_text(text, "flat"));
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{:?}",
        summary.stop
    );
    let t1 = (2.0 * 0.3 / G).sqrt();
    let v = G * t1;
    let at: Vec<_> = rec
        .impacts
        .iter()
        .filter(|ev| ev.t == rec.impacts[0].t)
        .collect();
    assert_eq!(at.len(), 2, "both corners");
    assert!((at[0].t - t1).abs() < 1e-12);
    for ev in &at {
        assert_eq!(ev.cause, ImpactCause::Simultaneous);
        // Each corner: v_n⁺ = −e v_n⁻ and half the momentum jump (1 + e) m v.
        assert!((ev.v_a.n + v).abs() <= 1e-12 * v, "{ev:?}");
        assert!((ev.outcome.v_s.n - 0.5 * v).abs() <= 1e-12 * v, "{ev:?}");
        assert!((ev.outcome.impulse.n - 0.5 * 1.5 * 2.0 * v).abs() <= 1e-12 * v);
    }
    let after = (rec.samples.iter())
        .rfind(|s| s.0 == at[0].t)
        .expect("a sample after the impact");
    assert!(
        (after.2[1] - 0.5 * v).abs() <= 1e-12 * v,
        "v_y {}",
        after.2[1]
    );
    assert!(
        after.2[0].abs() <= 1e-12 * v && after.2[2].abs() <= 1e-12 * v,
        "{:?}",
        after.2
    );
}
