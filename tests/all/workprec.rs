//! `ricochet::workprec`: the error metrics on artificial traces with known errors, the
//! closed-form ball against its defining equations, a CSV round trip, and (feature
//! `rapier`) the rapier translation of a scene against the scene's masses and shapes.

use ricochet::workprec::metrics::errors;
use ricochet::workprec::reference::Ball;
use ricochet::workprec::table::{self, Row};
use ricochet::workprec::{ImpactRecord, Trace};

fn record(t: f64, vn: f64, vt: f64, e: f64) -> ImpactRecord {
    ImpactRecord {
        t,
        v_s: [vn, vt],
        energy_after: e,
    }
}

fn reference() -> Trace {
    Trace {
        impacts: vec![record(1.0, 3.0, 4.0, 6.0), record(2.0, 1.0, 0.0, 2.0)],
        energy_initial: 10.0,
        t_end: 3.0,
        q: vec![3.0],
        u: vec![4.0],
    }
}

#[test]
fn metrics_recover_known_errors() {
    let r = reference();
    // Time off by 1e-3 and 2e-3; velocities off by (0.03, 0.04) (1 % of |(3, 4)| = 5) and
    // by 0.5 % of 1; energy after the second off by 0.08 (1 % of the loss 10 − 2 = 8);
    // end state off by (0.03, −0.04): 1 % of |(3, 4)|.
    let run = Trace {
        impacts: vec![
            record(1.001, 3.03, 4.04, 6.5),
            record(2.002, 1.005, 0.0, 2.08),
        ],
        energy_initial: 10.0,
        t_end: 3.0,
        q: vec![3.03],
        u: vec![3.96],
    };
    let e = errors(&run, &r, 2);
    assert!((e.impact_time - 2e-3).abs() < 1e-12, "{e:?}");
    assert!((e.velocity - 1e-2).abs() < 1e-12, "{e:?}");
    assert!((e.energy - 1e-2).abs() < 1e-12, "{e:?}");
    assert!((e.end_state - 1e-2).abs() < 1e-12, "{e:?}");
    // Over the first impact only: its own errors.
    let e1 = errors(&run, &r, 1);
    assert!((e1.impact_time - 1e-3).abs() < 1e-12);
    assert!((e1.energy - 0.5 / 4.0).abs() < 1e-12);
}

#[test]
fn a_missed_impact_or_an_early_stop_is_an_infinite_error() {
    let r = reference();
    let mut run = r.clone();
    run.impacts.pop();
    let e = errors(&run, &r, 2);
    assert!(e.impact_time.is_infinite() && e.velocity.is_infinite() && e.energy.is_infinite());
    assert_eq!(e.end_state, 0.0);
    run.t_end = 2.5;
    assert!(errors(&run, &r, 1).end_state.is_infinite());
    // The reference against itself: no error.
    let z = errors(&r, &r, 2);
    assert_eq!(
        (z.impact_time, z.velocity, z.energy, z.end_state),
        (0.0, 0.0, 0.0, 0.0)
    );
}

#[test]
fn impulses_at_one_instant_are_one_impact() {
    let mut t = Trace::default();
    t.push(record(1.0, 0.5, 0.0, 1.0));
    t.push(record(1.0, 0.7, 0.1, 0.9));
    t.push(record(1.0, 0.6, 0.0, 0.8));
    t.push(record(2.0, 0.1, 0.0, 0.5));
    assert_eq!(t.impacts.len(), 2);
    assert_eq!(t.impacts[0], record(1.0, 0.7, 0.1, 0.9));
}

/// The closed form satisfies its defining equations: free fall between impacts (the
/// height at each impact time is the radius: r + v τ − g τ²/2 = r after a flight
/// τ = 2 v / g), Newton's law v_{k+1} = e v_k, energy ½ m v² + m g r after each.
#[test]
fn closed_form_ball_obeys_free_fall_and_newtons_law() {
    let ball = Ball {
        g: 9.81,
        y0: 1.1,
        r: 0.1,
        m: 0.1,
        e: 0.8,
    };
    let tr = ball.closed_form(3.0);
    assert_eq!(tr.impacts.len(), 6);
    // First impact: y0 − g t²/2 = r, and the speed before it is g t.
    let t1 = tr.impacts[0].t;
    assert!((ball.y0 - 0.5 * ball.g * t1 * t1 - ball.r).abs() < 1e-14);
    assert!((tr.impacts[0].v_s[0] - ball.e * ball.g * t1).abs() < 1e-14);
    for w in tr.impacts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let tau = b.t - a.t;
        let v = a.v_s[0];
        assert!(
            (v * tau - 0.5 * ball.g * tau * tau).abs() < 1e-13,
            "lands on the floor"
        );
        assert!((b.v_s[0] - ball.e * (v - ball.g * tau).abs()).abs() < 1e-13);
        assert!(
            (b.energy_after - (0.5 * ball.m * b.v_s[0].powi(2) + ball.m * ball.g * ball.r)).abs()
                < 1e-14
        );
    }
    // The end state is on the last flight: energy conserved since the last impact.
    let last = tr.impacts.last().unwrap();
    let e_end = 0.5 * ball.m * tr.u[0].powi(2) + ball.m * ball.g * tr.q[0];
    assert!((e_end - last.energy_after).abs() < 1e-13);
    assert!(tr.q[0] >= ball.r);
}

#[test]
fn csv_round_trip_keeps_every_field_and_non_finite_errors() {
    let rows = vec![
        Row {
            scene: "bouncing_ball".into(),
            method: "dopri5".into(),
            parameter: "rtol".into(),
            value: 1e-10,
            wall_median_s: 1.234_567_890_123e-4,
            wall_min_s: 1e-4,
            wall_max_s: 2e-4,
            repeats: 5,
            steps: 123,
            rhs_evals: Some(900),
            impacts: 6,
            compared: 5,
            stop: "t_end".into(),
            reference: "closed form".into(),
            err_impact_time: 1.5e-13,
            err_velocity: f64::INFINITY,
            err_energy: 0.0,
            err_end_state: 3.3e-12,
        },
        Row {
            method: "rapier".into(),
            rhs_evals: None,
            err_velocity: 0.1,
            err_energy: f64::NAN,
            ..Default::default()
        },
    ];
    let dir = std::env::temp_dir().join(format!("ricochet-workprec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rows.csv");
    table::write(&path, &rows).unwrap();
    let back: Vec<Row> = table::read(&path).unwrap();
    assert_eq!(back.len(), 2);
    assert_eq!(back[0], rows[0]);
    assert!(back[1].err_energy.is_nan());
    assert_eq!(back[1].rhs_evals, None);
    assert_eq!(back[1].method, "rapier");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(feature = "rapier")]
#[test]
fn rapier_bodies_have_the_scenes_mass_properties_and_shapes() {
    use ricochet::workprec::rapier::RapierWorld;
    for name in [
        "bouncing_ball",
        "falling_rod",
        "kane_double_pendulum",
        "pendulum_wall",
    ] {
        let scene =
            ricochet::scene::load(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR")))
                .unwrap();
        let mut w = RapierWorld::new(&scene, 1e-3).unwrap();
        // The state reads back as the scene's initial state.
        let (mut q, mut u) = (vec![0.0; scene.model.nq()], vec![0.0; scene.model.nu()]);
        w.read(&mut q, &mut u);
        for i in 0..q.len() {
            assert!((q[i] - scene.initial.q[i]).abs() < 1e-12, "{name}: q[{i}]");
            assert!((u[i] - scene.initial.u[i]).abs() < 1e-12, "{name}: u[{i}]");
        }
        // rapier computes the mass properties in its first step.
        w.step();
        for (k, body) in scene.model.bodies().iter().enumerate() {
            let rb = &w.world.bodies[w.bodies[k]];
            let mp = rb.mass_properties().local_mprops;
            assert!(
                (mp.mass() - body.mass).abs() < 1e-12,
                "{name}: mass {}",
                mp.mass()
            );
            assert!(
                (mp.principal_inertia() - body.inertia).abs() < 1e-12,
                "{name}: inertia"
            );
            assert!((mp.local_com - body.com).length() < 1e-12, "{name}: com");
        }
        // One rapier collider per shape of the scene.
        assert_eq!(w.world.colliders.len(), scene.model.colliders().len());
    }
}
