//! Simple nonholonomic systems (issue 14): knife edges and wheels, generalized speeds
//! distinct from `q̇`, impacts with the constraints in force.
//!
//! - The Chaplygin sleigh's free motion against its closed form.
//! - Every impact of the three nonholonomic scenes against a second method: the same
//!   system in full coordinates (`q̇` as speeds, no constraint in the model) with the
//!   blades as impulsive Lagrange multipliers.
//! - The energy audit over a run with many impacts, and the blades holding along it.
//! - `ricochet regions` from a nonholonomic scene's state.

use nalgebra::{DMatrix, DVector, Matrix2xX};
use ricochet::constraints::cross_velocities;
use ricochet::dynamics::{coordinate_rates, mass_matrix};
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem};
use ricochet::kinematics::{point_jacobian, update_positions, update_velocities};
use ricochet::math::{Real, Vec2};
use ricochet::model::{BodyId, Model};
use ricochet::scene::Scene;
use ricochet::sim::{ImpactCause, MaterialOverride, Recorder, Simulation, StopReason};
use ricochet::state::Data;

fn scene_text(name: &str) -> String {
    std::fs::read_to_string(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn load(name: &str) -> Scene {
    ricochet::scene::load_str(&scene_text(name), format!("{name}.toml")).unwrap()
}

/// The scene's text without its `[[body.constraint]]` tables: the same bodies and shapes
/// in full coordinates, every planar speed a coordinate rate.
fn without_constraints(text: &str) -> String {
    let mut out = String::new();
    let mut skipping = false;
    for line in text.lines() {
        if line.starts_with("[[") || line.starts_with('[') {
            skipping = line.trim() == "[[body.constraint]]";
        }
        if !skipping {
            // Body-frame initial speeds need the constraint to complete them; the twin's
            // initial state is not used.
            let line = line.replace("vx_body", "vx");
            out.push_str(&line);
            out.push('\n');
        }
    }
    out
}

fn run(scene: &Scene, keep_samples: bool) -> (Recorder, ricochet::sim::RunSummary) {
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut rec = Recorder {
        keep_samples,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary)
}

/// Gudermann's function `gd(x) = ∫₀ˣ sech = 2 atan(tanh(x/2))`.
fn gd(x: Real) -> Real {
    2.0 * (0.5 * x).tanh().atan()
}

/// The Chaplygin sleigh (mass `m`, inertia `I` about its centre of mass `G`, blade point
/// `P` a distance `a` behind `G` along the blade) moves, with `v` the blade point's
/// forward speed and `ω` its rate of turn, by Kane's equations in the two speeds
///
/// ```text
/// m v̇ = m a ω²,     (I + m a²) ω̇ = −m a v ω
/// ```
///
/// (derived from `v_G = v e₁ + a ω e₂`). The energy `E = ½ m v² + ½ (I + m a²) ω²` is
/// conserved, so with `V = √(2E/m)`, `k = m a / (I + m a²)`, `c₀ = atanh(v₀/V)`:
///
/// ```text
/// v(t) = V tanh(k V t + c₀),   ω(t) = ω₀ cosh c₀ / cosh(k V t + c₀),
/// θ(t) = θ₀ + ω₀ cosh c₀ / (k V) · (gd(k V t + c₀) − gd(c₀))
/// ```
///
/// and the known asymptotic motion: `ω → 0`, `v → V`, a straight line at the heading
/// `θ∞ = θ₀ + ω₀ cosh c₀ / (k V) · (π/2 − gd(c₀))`, the centre of mass ahead of the blade.
///
/// The angular momentum about the blade's point is *not* conserved when `a ≠ 0`: about
/// the moving point `P` it is `(I + m a²) ω`, whose rate is `−m a v ω`. What holds is that
/// the blade's force passes through `P`: the angular momentum about the *fixed* point at
/// `P(t₀)` has zero rate at `t₀` (checked below by a central difference).
#[test]
fn sleigh_free_motion_matches_its_closed_form() {
    let text = scene_text("chaplygin_sleigh").replace("t_end = 6.0", "t_end = 12.0");
    let text = text.replace("point = [2.5, 0.0]", "point = [1e3, 0.0]");
    let mut scene = ricochet::scene::load_str(&text, "sleigh.toml").unwrap();
    scene.settings.integrator.rtol = 1e-12;
    scene.settings.integrator.atol = 1e-14;
    let (rec, summary) = run(&scene, true);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    assert!(rec.impacts.is_empty());
    let (m, a) = (2.0, 0.3);
    // m (w² + h²)/12 with w = 0.8, h = 0.4, as the scene says.
    let i = scene.model.bodies()[0].inertia;
    assert!((i - m * (0.64 + 0.16) / 12.0).abs() < 1e-15);
    let j = i + m * a * a;
    let (v0, w0, th0) = (1.0, 2.0, 5.0_f64.to_radians());
    assert!((scene.initial.q[2] - th0).abs() < 1e-16);
    let e = 0.5 * m * v0 * v0 + 0.5 * j * w0 * w0;
    let big_v = (2.0 * e / m).sqrt();
    let k = m * a / j;
    let c0 = (v0 / big_v).atanh();
    let (mut worst_v, mut worst_w, mut worst_th, mut worst_e): (Real, Real, Real, Real) =
        (0.0, 0.0, 0.0, 0.0);
    for (t, q, u, energy) in &rec.samples {
        let x = k * big_v * t + c0;
        let v = big_v * x.tanh();
        let w = w0 * c0.cosh() / x.cosh();
        let th = th0 + w0 * c0.cosh() / (k * big_v) * (gd(x) - gd(c0));
        worst_v = worst_v.max((u[0] - v).abs());
        worst_w = worst_w.max((u[1] - w).abs());
        worst_th = worst_th.max((q[2] - th).abs());
        worst_e = worst_e.max((energy - e).abs() / e);
    }
    println!(
        "sleigh, {} samples to 12 s: |Δv| ≤ {worst_v:.1e} m/s, |Δω| ≤ {worst_w:.1e} rad/s, \
         |Δθ| ≤ {worst_th:.1e} rad, |ΔE|/E ≤ {worst_e:.1e}",
        rec.samples.len()
    );
    assert!(
        worst_v < 1e-9,
        "forward speed off its closed form by {worst_v:e}"
    );
    assert!(
        worst_w < 1e-9,
        "rate of turn off its closed form by {worst_w:e}"
    );
    assert!(
        worst_th < 1e-9,
        "heading off its closed form by {worst_th:e}"
    );
    assert!(worst_e < 1e-10, "energy drift {worst_e:e}");
    // The asymptotic motion: at 12 s (k V t ≈ 29) the turning has died out.
    let (_, q, u, _) = rec.samples.last().unwrap();
    let th_inf = th0 + w0 * c0.cosh() / (k * big_v) * (std::f64::consts::FRAC_PI_2 - gd(c0));
    assert!((u[0] - big_v).abs() < 1e-9 && u[1].abs() < 1e-9, "{u:?}");
    assert!((q[2] - th_inf).abs() < 1e-9, "θ = {}, θ∞ = {th_inf}", q[2]);
    // The centre of mass moves along the heading: its velocity is (V cos θ∞, V sin θ∞).
    let n = rec.samples.len();
    let (t1, q1, ..) = &rec.samples[n - 2];
    let (t2, q2, ..) = &rec.samples[n - 1];
    let vel = Vec2::new(q2[0] - q1[0], q2[1] - q1[1]) / (t2 - t1);
    let dir = Vec2::new(th_inf.cos(), th_inf.sin());
    assert!(
        (vel - dir * big_v).length() < 1e-8,
        "{vel:?} vs {:?}",
        dir * big_v
    );

    // The blade's force passes through P: the angular momentum about the fixed point at
    // P(t₀) has zero rate at t₀, while the one about the moving P changes at −m a v ω.
    let momentum_about = |o: Vec2, q: &[Real], u: &[Real]| -> Real {
        let (s, c) = q[2].sin_cos();
        let g = Vec2::new(q[0], q[1]);
        // v_G = vx_body e₁ + (a ω) e₂ in the body's axes.
        let vg = Vec2::new(c * u[0] - s * a * u[1], s * u[0] + c * a * u[1]);
        let r = g - o;
        i * u[1] + m * (r.x * vg.y - r.y * vg.x)
    };
    for s in [40, 100, 200] {
        let (t0, q0, u0, _) = &rec.samples[s];
        let (ta, qa, ua, _) = &rec.samples[s - 1];
        let (tb, qb, ub, _) = &rec.samples[s + 1];
        let p0 = Vec2::new(q0[0], q0[1]) - Vec2::new(q0[2].cos(), q0[2].sin()) * a;
        let rate = (momentum_about(p0, qb, ub) - momentum_about(p0, qa, ua)) / (tb - ta);
        let moving = -m * a * u0[0] * u0[1];
        println!("t = {t0:.3}: dL_O/dt = {rate:.2e}, d((I + m a²) ω)/dt = {moving:.3e}");
        assert!(rate.abs() < 1e-3 * moving.abs(), "{rate} vs {moving}");
    }
}

/// The second method at one impact: the twin model in full coordinates (`q̇` as speeds)
/// at the state before the impact, the constraints `C q̇ = 0` as impulsive Lagrange
/// multipliers,
///
/// ```text
/// [M  Cᵀ] [X]   [Jᵀ]
/// [C  0 ] [Λ] = [0 ],    W = J X,   Δq̇ = X I
/// ```
///
/// (`J` the contact rows `nᵀ J_P`, `tᵀ J_P` in `q̇`). Returns `(W, v^A, Δq̇ per unit
/// impulse X, C)`.
fn full_coordinates_impact(
    twin: &Model,
    model: &Model,
    t: Real,
    q: &[Real],
    qdot: &[Real],
    frame: &ricochet::contact::ContactFrame,
) -> (ImpactMatrix, ContactVelocity, DMatrix<Real>, DMatrix<Real>) {
    let nq = twin.nq();
    let mut data = Data::new(twin);
    update_positions(twin, &mut data, t, q).unwrap();
    update_velocities(twin, &mut data, qdot).unwrap();
    mass_matrix(twin, &mut data);
    let jac_of = |body: BodyId, p: Vec2| -> Matrix2xX<Real> {
        let mut jac = Matrix2xX::zeros(nq);
        point_jacobian(twin, &data, body, p, &mut jac).unwrap();
        jac
    };
    // The contact rows: body a's point minus body b's (none for an obstacle).
    let pair = model.pair(frame.pair).unwrap();
    let body_a = model.colliders()[pair.a.index()].body.unwrap();
    let mut jp = jac_of(body_a, frame.point_a);
    if let Some(body_b) = model.colliders()[pair.b.index()].body {
        jp -= jac_of(body_b, frame.point_b);
    }
    let mut jrows = DMatrix::zeros(2, nq);
    for c in 0..nq {
        let col = Vec2::new(jp[(0, c)], jp[(1, c)]);
        jrows[(0, c)] = frame.n.dot(col);
        jrows[(1, c)] = frame.t.dot(col);
    }
    // The blades' rows, from the twin's kinematics (the constraint is not in it).
    let m_c = model.constraints().len();
    let mut crows = DMatrix::zeros(m_c, nq);
    for (k, c) in model.constraints().iter().enumerate() {
        let pose = data.body_pose[c.body.index()];
        let p = pose.transform_point(c.point);
        let n = pose.transform_vector(ricochet::math::perp(c.direction));
        let jb = jac_of(c.body, p);
        for col in 0..nq {
            crows[(k, col)] = n.dot(Vec2::new(jb[(0, col)], jb[(1, col)]));
        }
    }
    let mut kkt = DMatrix::zeros(nq + m_c, nq + m_c);
    kkt.view_mut((0, 0), (nq, nq))
        .copy_from(&data.mass.to_dense());
    kkt.view_mut((0, nq), (nq, m_c))
        .copy_from(&crows.transpose());
    kkt.view_mut((nq, 0), (m_c, nq)).copy_from(&crows);
    let mut rhs = DMatrix::zeros(nq + m_c, 2);
    rhs.view_mut((0, 0), (nq, 2)).copy_from(&jrows.transpose());
    let sol = kkt.lu().solve(&rhs).unwrap();
    let x = sol.rows(0, nq).into_owned();
    let w = &jrows * &x;
    let va = &jrows * DVector::from_column_slice(qdot);
    (
        ImpactMatrix::new(w[(0, 0)], 0.5 * (w[(0, 1)] + w[(1, 0)]), w[(1, 1)]),
        ContactVelocity::new(va[0], va[1]),
        x,
        crows,
    )
}

fn rel(a: Real, b: Real, scale: Real) -> Real {
    (a - b).abs() / scale
}

#[test]
fn every_impact_agrees_with_the_full_coordinates_and_impulsive_multipliers() {
    let mut checked = 0;
    for name in ["chaplygin_sleigh", "wagon_curb", "sled_rock"] {
        let scene = load(name);
        let twin = ricochet::scene::load_str(
            &without_constraints(&scene_text(name)),
            format!("{name}_full.toml"),
        )
        .unwrap()
        .model;
        assert!(twin.is_holonomic() && twin.nq() == scene.model.nq());
        assert!(scene.model.nu() < scene.model.nq());
        let (rec, summary) = run(&scene, true);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "{name}: {}",
            summary.stop
        );
        assert!(!rec.impacts.is_empty(), "{name} has no impact");
        let model = &scene.model;
        let mut data = Data::new(model);
        let one_point = |e: &&ricochet::sim::ImpactEvent| {
            matches!(
                e.cause,
                ImpactCause::Collision | ImpactCause::AccumulationEnd
            )
        };
        for ev in rec.impacts.iter().filter(one_point) {
            // An accumulation's end is the same law, plastic.
            let e_law = match ev.cause {
                ImpactCause::AccumulationEnd => 0.0,
                _ => ev.material.e,
            };
            // The state just before: the first of the two samples at the impact instant.
            let (t, q, u, _) = rec.samples.iter().find(|s| s.0 == ev.t).unwrap();
            let (t, q, u) = (*t, q.as_slice(), u.as_slice());
            update_positions(model, &mut data, t, q).unwrap();
            update_velocities(model, &mut data, u).unwrap();
            let mut qdot = vec![0.0; model.nq()];
            coordinate_rates(model, &data, u, &mut qdot);
            let (w, va, x, crows) = full_coordinates_impact(&twin, model, t, q, &qdot, &ev.frame);
            let wscale = w.nn.abs().max(w.tt.abs());
            let vscale = va.n.abs().max(va.t.abs());
            for (what, a, b, scale) in [
                ("m_nn", w.nn, ev.w.nn, wscale),
                ("m_nt", w.nt, ev.w.nt, wscale),
                ("m_tt", w.tt, ev.w.tt, wscale),
                ("v_n^A", va.n, ev.v_a.n, vscale),
                ("v_t^A", va.t, ev.v_a.t, vscale),
            ] {
                assert!(rel(a, b, scale) < 1e-12, "{name}: {what} {a} vs {b}");
            }
            let out = impact::solve(
                ev.outcome.law,
                &ImpactProblem::new(w, va, e_law, ev.material.mu),
            )
            .unwrap();
            let iscale = out.impulse.n.abs();
            assert_eq!(out.kind, ev.outcome.kind, "{name}");
            assert!(
                rel(out.impulse.n, ev.outcome.impulse.n, iscale) < 1e-11,
                "{name}"
            );
            assert!(
                rel(out.impulse.t, ev.outcome.impulse.t, iscale) < 1e-11,
                "{name}"
            );
            let escale = out.delta_e.abs();
            assert!(
                rel(out.delta_e, ev.outcome.delta_e, escale) < 1e-10,
                "{name}"
            );
            // The jump: q̇⁺ = q̇⁻ + X I against A u⁺, and the blades hold through it.
            let dq = &x * DVector::from_vec(vec![out.impulse.n, out.impulse.t]);
            let u_after: Vec<Real> = u.iter().zip(&ev.delta_u).map(|(a, b)| a + b).collect();
            update_velocities(model, &mut data, &u_after).unwrap();
            let mut qdot_after = vec![0.0; model.nq()];
            coordinate_rates(model, &data, &u_after, &mut qdot_after);
            let qscale = qdot.iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
            for r in 0..model.nq() {
                let full = qdot[r] + dq[r];
                assert!(
                    rel(full, qdot_after[r], qscale) < 1e-11,
                    "{name}: q̇⁺[{r}] {full} vs {}",
                    qdot_after[r]
                );
            }
            let slip = &crows * DVector::from_vec(qdot_after.clone());
            assert!(
                slip.amax() < 1e-13 * qscale,
                "{name}: the blade slips {slip}"
            );
            checked += 1;
        }
    }
    println!("{checked} impacts agree with the full coordinates");
    assert!(checked >= 10, "{checked}");
}

/// A sleigh in a box of four walls, 3 m × 2 m: many impacts. Elastic and frictionless
/// (e = 1, μ = 0) every impact keeps the energy (Eq. 29 gives ΔE = 0), so `E` stays `E₀`
/// to the integration error; with e = 0.9, μ = 0.2 the audit closes. The blade's point
/// never moves across it: its cross velocity (from `u`) and the cross component of its
/// path (the positions' central difference, which `q̇ = A u` integrates) stay at the
/// rounding and at the difference's error.
#[test]
fn a_sleigh_in_a_box_balances_its_energy_and_keeps_its_blade() {
    for (e, mu, at_least) in [(1.0, 0.0, 20), (0.9, 0.2, 10)] {
        let mut text = scene_text("chaplygin_sleigh").replace("t_end = 6.0", "t_end = 30.0");
        text = text.replace("e = 0.6", &format!("e = {e:?}"));
        text = text.replace("mu = 0.3", &format!("mu = {mu:?}"));
        text = text.replace("output_rate = 200.0", "output_rate = 2000.0");
        text = text.replace("point = [2.5, 0.0]", "point = [1.5, 0.0]");
        text = text.replace(
            "x = -0.5, y = 0.2, angle = \"5 deg\"",
            "x = 0.0, y = 0.0, angle = \"0 deg\"",
        );
        for (name, point, normal) in [
            ("left", "[-1.5, 0.0]", "[1.0, 0.0]"),
            ("bottom", "[0.0, -1.0]", "[0.0, 1.0]"),
            ("top", "[0.0, 1.0]", "[0.0, -1.0]"),
        ] {
            text.push_str(&format!(
                "\n[[obstacle]]\nname = \"{name}\"\ntype = \"halfspace\"\npoint = {point}\nnormal = {normal}\n"
            ));
        }
        let scene = ricochet::scene::load_str(&text, "sleigh_box.toml").unwrap();
        let (rec, summary) = run(&scene, true);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "{}",
            summary.stop
        );
        let a = &summary.audit;
        let e0 = a.initial.total();
        println!(
            "sleigh in a box (e = {e}, μ = {mu}), 30 s: {} impacts, E {e0:.9} → {:.9} J, \
             ΣΔE(29) = {:.3e} J, drift {:.2e} J",
            rec.impacts.len(),
            a.end.total(),
            a.impact_delta_e,
            a.drift()
        );
        assert!(
            rec.impacts.len() >= at_least,
            "{} impacts",
            rec.impacts.len()
        );
        assert!(a.drift().abs() < 1e-8 * e0, "drift {}", a.drift());
        if e == 1.0 {
            assert!(a.impact_delta_e.abs() < 1e-13 * e0, "{}", a.impact_delta_e);
            assert!((a.end.total() - e0).abs() < 1e-8 * e0);
        } else {
            assert!(a.impact_delta_e < -0.1 * e0, "{}", a.impact_delta_e);
        }
        // Every impact's ledger: ΔE of Eq. (29) is the model's energy change.
        for ev in &rec.impacts {
            let de = ev.energy_after.total() - ev.energy_before.total();
            assert!(
                (de - ev.outcome.delta_e).abs() < 1e-12 * e0,
                "{de} vs {}",
                ev.outcome.delta_e
            );
        }
        // The blade along the whole run.
        let model = &scene.model;
        let mut data = Data::new(model);
        let mut worst_cross: Real = 0.0;
        let mut worst_path: Real = 0.0;
        let blade = &model.constraints()[0];
        let blade_point = |q: &[Real]| {
            let (s, c) = q[2].sin_cos();
            let p = blade.point;
            Vec2::new(q[0] + c * p.x - s * p.y, q[1] + s * p.x + c * p.y)
        };
        let s = &rec.samples;
        for k in 1..s.len() - 1 {
            let (t, q, u, _) = &s[k];
            update_positions(model, &mut data, *t, q).unwrap();
            update_velocities(model, &mut data, u).unwrap();
            let speed = u[0].abs() + u[1].abs();
            let cross = cross_velocities(model, &data).next().unwrap();
            worst_cross = worst_cross.max(cross.abs() / speed.max(1e-300));
            // Central difference of the blade point's path, away from the impacts (the
            // speeds jump there).
            let (ta, qa, ..) = &s[k - 1];
            let (tb, qb, ..) = &s[k + 1];
            let near_impact = rec.impacts.iter().any(|e| (e.t - t).abs() < 2e-3);
            if !near_impact && tb - ta > 1e-4 {
                let v = (blade_point(qb) - blade_point(qa)) / (tb - ta);
                let n = ricochet::math::perp(Vec2::new(q[2].cos(), q[2].sin()));
                worst_path = worst_path.max(n.dot(v).abs() / speed.max(1e-300));
            }
        }
        println!(
            "  cross velocity ≤ {worst_cross:.1e} (relative), path across the blade ≤ {worst_path:.1e}"
        );
        assert!(worst_cross < 1e-13, "{worst_cross:e}");
        // The central difference's own error at 0.5 ms is of order h² |P'''| / (6 |v|).
        assert!(worst_path < 1e-5, "{worst_path:e}");
    }
}

/// The regions map of a nonholonomic scene's state: the sleigh placed at the instant its
/// corner meets the wall, `W` from its two speeds as the impact law saw it in the run.
#[test]
fn regions_map_from_a_nonholonomic_scene() {
    let scene = load("chaplygin_sleigh");
    let (rec, _) = run(&scene, true);
    let ev = &rec.impacts[0];
    let (_, q, u, _) = rec.samples.iter().find(|s| s.0 == ev.t).unwrap();
    // The scene started at that state (positions and the two speeds, written exactly).
    let text = scene_text("chaplygin_sleigh").replace(
        "joint = { type = \"planar\", x = -0.5, y = 0.2, angle = \"5 deg\", vx_body = 1.0, rate = \"2 rad/s\" }",
        &format!(
            "joint = {{ type = \"planar\", x = {:?}, y = {:?}, angle = \"{:?} rad\", vx_body = {:?}, rate = \"{:?} rad/s\" }}",
            q[0], q[1], q[2], u[0], u[1]
        ),
    );
    let at_impact = ricochet::scene::load_str(&text, "sleigh_at_impact.toml").unwrap();
    // (vx_body goes through the joint's axes and back: rounding.)
    for (a, b) in at_impact.initial.u.iter().zip(u) {
        assert!((a - b).abs() <= 1e-15 * b.abs().max(1.0), "{a} vs {b}");
    }
    let contact =
        ricochet::regions::scene_contact(&at_impact.model, &at_impact.initial, None).unwrap();
    let w = contact.w;
    let wscale = w.nn.abs().max(w.tt.abs());
    for (a, b) in [(w.nn, ev.w.nn), (w.nt, ev.w.nt), (w.tt, ev.w.tt)] {
        assert!(rel(a, b, wscale) < 1e-12, "{w:?} vs {:?}", ev.w);
    }
    let alpha = contact.alpha().unwrap();
    let ledger_alpha = ev.outcome.coefficients.alpha();
    assert!(
        (alpha - ledger_alpha).abs() < 1e-9,
        "{alpha} vs {ledger_alpha}"
    );
    // W is in the speeds (vx_body, ω): not the W of the free board, whose sideways
    // velocity the blade takes away.
    let free = ricochet::scene::load_str(&without_constraints(&text), "free.toml").unwrap();
    let wf = ricochet::regions::scene_contact(&free.model, &free.initial, None)
        .unwrap()
        .w;
    // A constraint only takes mobility away: W_free − W_blade is positive semidefinite
    // (and here not zero).
    let (dnn, dnt, dtt) = (wf.nn - w.nn, wf.nt - w.nt, wf.tt - w.tt);
    assert!(dnn >= 0.0 && dtt >= 0.0, "free {wf:?} vs blade {w:?}");
    assert!(
        dnn * dtt - dnt * dnt >= -1e-12 * wscale * wscale,
        "{wf:?} vs {w:?}"
    );
    assert!(
        dnn + dtt > 1e-2 * (w.nn + w.tt),
        "free {wf:?} vs blade {w:?}"
    );
    // The command line draws the map from the file.
    let dir = std::env::temp_dir().join(format!("ricochet_nh_regions_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sleigh_at_impact.toml");
    std::fs::write(&path, &text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args(["regions", "--scene"])
        .arg(&path)
        .args(["--law", "newton", "--resolution", "41", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{stdout}");
    let svgs: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "svg"))
        .collect();
    assert!(!svgs.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Careless and hostile constraint tables: each error names the file, the line and the
/// field, and says what to do.
#[test]
fn bad_constraints_are_located_errors() {
    let sleigh = scene_text("chaplygin_sleigh");
    let wagon = scene_text("wagon_curb");
    let blade2 = "[[body.constraint]]\ntype = \"knife_edge\"\nname = \"blade2\"\nat = [-0.3, 0.1]\ndirection = \"0 deg\"\n\n[[obstacle]]";
    let cases: Vec<(String, &str, &str)> = vec![
        (
            sleigh.replace("vx_body = 1.0", "vx = 1.0, vy = 1.0"),
            "constraint[\"blade\"].name",
            "the initial velocity breaks constraint `blade`: it removes the speed `sleigh.vy_body`, which it makes 0.6 m/s, and the joint's initial velocity gives 0.909",
        ),
        (
            sleigh.replace(
                "direction = \"0 deg\"  ",
                "removes = \"sleigh.nope\"\ndirection = \"0 deg\"  ",
            ),
            "constraint[\"blade\"].removes",
            "no speed is named `sleigh.nope`",
        ),
        (
            sleigh.replacen("[[obstacle]]", blade2, 1),
            "constraint[\"blade2\"].name",
            "the blade involves no speed of `sleigh`'s joint that the constraints before it leave",
        ),
        (
            sleigh.replace("direction = \"0 deg\"  ", "direction = 0.0  "),
            "constraint[\"blade\"].direction",
            "an angle needs its unit",
        ),
        (
            sleigh.replace("type = \"knife_edge\"", "type = \"skate\""),
            "constraint[\"blade\"].type",
            "unknown variant `skate`",
        ),
        (
            sleigh.replace("vx_body = 1.0", "vx_body = 1.0, vx = 0.5"),
            "joint.vx",
            "either along the joint's axes",
        ),
        (
            wagon.replace(
                "at = [-0.06, 0.0]                    # behind",
                "at = [0.0, 0.0] # at",
            ),
            "constraint[\"front_axle\"].name",
            "name the speed it removes with `removes`",
        ),
        (
            wagon
                .replace(
                    "at = [-0.06, 0.0]                    # behind",
                    "at = [0.0, 0.0] # at",
                )
                .replace(
                    "name = \"front_axle\"",
                    "name = \"front_axle\"\nremoves = \"wagon.omega\"",
                )
                .replace("angle = \"20 deg\" }", "angle = \"90 deg\" }"),
            "constraint[\"front_axle\"].name",
            "the speed `wagon.omega` removed by constraint `front_axle` cannot be solved for at this configuration",
        ),
        (
            wagon.replace(
                "name = \"front_axle\"",
                "name = \"front_axle\"\nremoves = \"wagon.vy_body\"",
            ),
            "constraint[\"front_axle\"].removes",
            "`wagon.vy_body` is already removed by `rear_axle`",
        ),
    ];
    for (k, (text, field, message)) in cases.iter().enumerate() {
        let err = ricochet::scene::load_str(text, "bad.toml")
            .err()
            .unwrap_or_else(|| {
                panic!("case {k} loaded");
            });
        let shown = err.to_string();
        println!("{shown}");
        assert!(shown.starts_with("bad.toml:"), "case {k}: {shown}");
        assert!(shown.contains(field), "case {k}: {shown}");
        assert!(shown.contains(message), "case {k}: {shown}");
    }
}

/// `ricochet check` prints the speeds, the constraints and `q̇ = A u + b`; the sleigh's
/// `A` is known by hand: `ẋ = cos θ vx − sin θ (a ω)`, `ẏ = sin θ vx + cos θ (a ω)`,
/// `θ̇ = ω`.
#[test]
fn check_prints_the_speeds_and_the_kinematic_equations() {
    let dir = std::env::temp_dir().join(format!("ricochet_nh_check_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sleigh.toml");
    let theta: Real = 0.7;
    std::fs::write(
        &path,
        scene_text("chaplygin_sleigh")
            .replace("angle = \"5 deg\"", &format!("angle = \"{theta:?} rad\"")),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .arg("check")
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        v["speeds"],
        serde_json::json!(["sleigh.vx_body", "sleigh.omega"])
    );
    assert_eq!(v["speed_units"], serde_json::json!(["m/s", "rad/s"]));
    assert_eq!(v["constraints"][0]["removes"], "sleigh.vy_body");
    assert_eq!(v["constraints"][0]["type"], "knife_edge");
    let a = &v["kinematic_equations"]["a"];
    let (s, c, arm) = (theta.sin(), theta.cos(), 0.3);
    let expected = [[c, -s * arm], [s, c * arm], [0.0, 1.0]];
    for (r, row) in expected.iter().enumerate() {
        for (col, x) in row.iter().enumerate() {
            let got = a[r][col].as_f64().unwrap();
            assert!(
                (got - x).abs() < 1e-15,
                "A[{r}][{col}] = {got}, expected {x}"
            );
        }
    }
    assert_eq!(v["mass_matrix"].as_array().unwrap().len(), 2);
    // A holonomic scene prints its coordinates as speeds and no kinematic equations.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .arg("check")
        .arg(format!(
            "{}/scenes/falling_rod.toml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["speeds"], v["coordinates"]);
    assert!(v.get("kinematic_equations").is_none() && v.get("constraints").is_none());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sweep over a generalized speed of a nonholonomic scene: `u0.` names the speeds.
#[test]
fn sweeps_name_the_generalized_speeds() {
    use ricochet::sweep::{Grid, ParamSpec, Sweep};
    let grid_of = |spec: &str| Grid::new(vec![ParamSpec::parse(spec).unwrap()]).unwrap();
    let scene = load("chaplygin_sleigh");
    let grid = grid_of("u0.sleigh.omega=0:2:1");
    let sweep = Sweep::new(&scene, grid).unwrap();
    for k in 0..3 {
        let row = sweep.run_point(k);
        assert!(row.outcome.is_ok(), "{:?}", row.outcome);
    }
    let bad = grid_of("u0.sleigh.vy_body=0:1:1");
    let err = Sweep::new(&scene, bad).unwrap_err().to_string();
    assert!(
        err.contains("no generalized speed `sleigh.vy_body`"),
        "{err}"
    );
    assert!(err.contains("sleigh.vx_body, sleigh.omega"), "{err}");
}

/// Several blades on one body: a cart whose two axles are both fixed to it (parallel, one
/// behind the other) keeps one speed, its rolling speed (`omega` is removed by the second
/// axle): pushed at an angle, it runs straight at constant heading, and gravity along
/// its axis accelerates it by `g · e₁` exactly as a particle on an inclined line.
#[test]
fn two_fixed_axles_leave_one_speed_and_a_straight_line() {
    let text = r#"
version = 1
name = "rigid_cart"
gravity = [0.0, -2.0]
[run]
t_end = 2.0
[[body]]
name = "cart"
mass = 3.0
inertia = 0.2
joint = { type = "planar", x = 1.0, y = 2.0, angle = "30 deg", vx_body = 0.5 }
[[body.constraint]]
type = "wheel"
name = "rear"
at = [-0.3, 0.0]
[[body.constraint]]
type = "wheel"
name = "front"
at = [0.3, 0.0]
"#;
    let scene = ricochet::scene::load_str(text, "rigid_cart.toml").unwrap();
    let names: Vec<&str> = scene
        .model
        .speeds()
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(names, ["cart.vx_body"]);
    let removed: Vec<&str> = (scene.model.dependent_speeds().iter())
        .map(|&d| scene.model.tree_speeds()[d].name.as_str())
        .collect();
    assert_eq!(removed, ["cart.vy_body", "cart.omega"]);
    let (rec, summary) = run(&scene, true);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let th: Real = 30.0_f64.to_radians();
    let along = Vec2::new(th.cos(), th.sin()).dot(Vec2::new(0.0, -2.0));
    for (t, q, u, _) in &rec.samples {
        let s = 0.5 * t + 0.5 * along * t * t;
        let v = 0.5 + along * t;
        assert!((q[0] - (1.0 + s * th.cos())).abs() < 1e-12, "x at {t}");
        assert!((q[1] - (2.0 + s * th.sin())).abs() < 1e-12, "y at {t}");
        assert!((q[2] - th).abs() < 1e-15, "θ at {t}");
        assert!((u[0] - v).abs() < 1e-12, "v at {t}");
    }
}

/// Three Chaplygin sleighs side by side: nine coordinates, three blades, six speeds.
fn three_sleighs() -> Scene {
    let mut text = String::from(
        "version = 1\nname = \"three_sleighs\"\ngravity = [0.0, 0.0]\n[run]\nt_end = 1.0\n",
    );
    for (k, (x, angle, blade)) in [(-1.0, 5.0, -0.3), (0.0, -40.0, 0.1), (1.5, 120.0, 0.25)]
        .into_iter()
        .enumerate()
    {
        text.push_str(&format!(
            "[[body]]\nname = \"sleigh{k}\"\nmass = {m}\ninertia = 0.13\n\
             joint = {{ type = \"planar\", x = {x}, y = 0.2, angle = \"{angle} deg\", vx_body = 1.0, rate = \"2 rad/s\" }}\n\
             [[body.constraint]]\ntype = \"knife_edge\"\nname = \"blade{k}\"\nat = [{blade}, 0.05]\ndirection = \"{d} deg\"\n",
            m = 2.0 + k as f64,
            d = 10.0 * k as f64,
        ));
    }
    ricochet::scene::load_str(&text, "three_sleighs.toml").unwrap()
}

/// `M = Sᵀ M_v S` (Kane's generalized inertia forces in the speeds) of more than five
/// speeds: nalgebra's `gemm` hands `M_v S` to `matrixmultiply`, which allocates a packing
/// buffer at every call and picks its kernel (fused or not) from the processor. It is
/// now `linalg::product_into`: no allocation once the workspace exists, and every entry
/// of `M_v S` the fused sum over the coordinates, `fma(m_ik, s_kj, ·)` from +0 in
/// increasing k, on every machine. The oracle is that sum written out here, and
/// `Sᵀ (M_v S)` by dot products as nalgebra's `gemm_tr` takes them.
#[test]
fn the_mass_matrix_of_six_speeds_is_the_fused_product_and_allocates_nothing() {
    use crate::common::alloc::allocations;
    let scene = three_sleighs();
    let model = &scene.model;
    assert_eq!((model.nq(), model.nu()), (9, 6));
    let mut data = Data::new(model);
    let q: Vec<Real> = scene.initial.q.iter().copied().collect();
    update_positions(model, &mut data, 0.0, &q).unwrap();
    mass_matrix(model, &mut data);

    for k in 0..5 {
        let q: Vec<Real> = (q.iter().enumerate())
            .map(|(i, x)| x + 0.1 * (k * 9 + i) as Real)
            .collect();
        let before = allocations();
        update_positions(model, &mut data, 0.0, &q).unwrap();
        mass_matrix(model, &mut data);
        assert_eq!(allocations(), before, "allocations at round {k}");

        let (mv, s) = (&data.mass_tree, &data.speed_map);
        let (n, p) = (s.nrows(), s.ncols());
        let mut mv_s = DMatrix::zeros(n, p);
        for i in 0..n {
            for j in 0..p {
                let sum = (0..n).fold(0.0, |acc: Real, k| mv[(i, k)].mul_add(s[(k, j)], acc));
                mv_s[(i, j)] = sum + 0.0;
            }
        }
        assert_eq!(data.mass_map, mv_s, "M_v S at round {k}");
        let m = s.tr_mul(&mv_s);
        for i in 0..p {
            for j in 0..=i {
                assert_eq!(
                    data.mass.get(i, j).to_bits(),
                    m[(i, j)].to_bits(),
                    "M[{i}, {j}] at round {k}"
                );
            }
        }
    }
}
