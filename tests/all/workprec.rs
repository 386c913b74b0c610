//! `ricochet::workprec`: the error metrics on artificial traces with known errors, the
//! closed-form ball against its defining equations, a CSV round trip, and (feature
//! `rapier`) the rapier translation of a scene against the scene's masses and shapes; the
//! rope on the floor of the chain scaling (`chain_floor`): its 32 links against
//! `scenes/chain_floor.toml`, its length, mass, inertia and shape at every size, its
//! measurement (window, counters, budget), its CSV rows and the exponent fit.

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

mod chain_floor {
    use ricochet::kinematics::update_positions;
    use ricochet::math::{Real, Vec2};
    use ricochet::sim::{MaterialOverride, PairMode, Recorder, Simulation};
    use ricochet::state::Data;
    use ricochet::workprec::chain::power_law_exponent;
    use ricochet::workprec::chain_floor::{
        self, FloorSettings, PIVOT_HEIGHT, ROPE_LENGTH, ROPE_MASS, common_window, wall_at,
    };
    use ricochet::workprec::table::{self, FloorRow};

    /// The rope cut into 32 links is `scenes/chain_floor.toml`: the same model (bodies,
    /// joints, shapes, pairs and materials), initial state and settings.
    #[test]
    fn the_32_link_rope_is_the_chain_floor_file() {
        let path = format!("{}/scenes/chain_floor.toml", env!("CARGO_MANIFEST_DIR"));
        let file = ricochet::scene::load(&path).unwrap();
        let rope = chain_floor::scene(32).unwrap();
        assert_eq!(rope.model.bodies(), file.model.bodies());
        assert_eq!(
            format!("{:?}", rope.model.joints()),
            format!("{:?}", file.model.joints())
        );
        assert_eq!(
            format!("{:?}", rope.model.colliders()),
            format!("{:?}", file.model.colliders())
        );
        assert_eq!(rope.model.pair_count(), file.model.pair_count());
        let (a, b): (Vec<_>, Vec<_>) = (rope.model.pairs().collect(), file.model.pairs().collect());
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
        assert_eq!(rope.model.gravity(), file.model.gravity());
        assert_eq!(rope.initial.q, file.initial.q);
        assert_eq!(rope.initial.u, file.initial.u);
        assert_eq!(rope.settings, file.settings);
        assert_eq!(rope.overlap_tolerance, file.overlap_tolerance);
    }

    /// At every size the rope is 3.2 m and 1.6 kg, straight and horizontal from the pivot
    /// 1 m above the floor, with capsules of radius L/10; its moment of inertia about the
    /// pivot is that of a uniform rod, Σ mᵢ (L²/12 + dᵢ²) = M (N L)²/3 exactly (the sum of
    /// (i − ½)² over i ≤ N is N (4N² − 1)/12).
    #[test]
    fn the_rope_keeps_its_length_mass_inertia_and_shape_at_every_size() {
        for n in [1, 2, 3, 4, 8, 16, 64, 128, 256] {
            let scene = chain_floor::scene(n).unwrap();
            let model = &scene.model;
            assert_eq!(model.bodies().len(), n, "{n} links");
            let l = ROPE_LENGTH / n as Real;
            let mass: Real = model.bodies().iter().map(|b| b.mass).sum();
            assert!((mass - ROPE_MASS).abs() < 1e-12, "{n} links: mass {mass}");
            let mut data = Data::for_kinematics(model);
            update_positions(model, &mut data, 0.0, scene.initial.q.as_slice()).unwrap();
            let mut inertia = 0.0;
            let mut length = 0.0;
            for (k, body) in model.bodies().iter().enumerate() {
                let pose = data.body_pose[k];
                let c = pose.transform_point(body.com);
                inertia += body.inertia + body.mass * c.length_squared();
                // Horizontal, end to end from the pivot.
                assert!(c.y.abs() < 1e-12, "{n} links: link {k} at {c:?}");
                assert!((c.x.abs() - (k as Real + 0.5) * l).abs() < 1e-12);
                let capsule = model.colliders()[k].shape.as_capsule().unwrap();
                assert!((capsule.radius - 0.1 * l).abs() < 1e-15, "{n} links");
                length += capsule.segment.length();
            }
            assert!(
                (length - ROPE_LENGTH).abs() < 1e-12,
                "{n} links: {length} m"
            );
            let rod = ROPE_MASS * ROPE_LENGTH * ROPE_LENGTH / 3.0;
            assert!(
                (inertia - rod).abs() < 1e-12 * rod,
                "{n} links: {inertia} against {rod}"
            );
            let floor = model.colliders()[n].shape.as_halfspace().unwrap();
            assert_eq!(floor.normal, Vec2::new(0.0, 1.0));
            assert_eq!(
                model.colliders()[n].pose.translation,
                Vec2::new(0.0, -PIVOT_HEIGHT)
            );
            // Every link with the floor, every two links at least two apart.
            assert_eq!(
                model.pair_count(),
                n + n * (n - 1) / 2 - (n - 1),
                "{n} links"
            );
        }
    }

    /// A short rope through a short window: the window starts at its first impact, the
    /// counters are the window's, and the closed pairs at the end are those of the run's
    /// last sample.
    #[test]
    fn measure_runs_the_window_after_the_first_impact() {
        let settings = FloorSettings {
            window: 0.5,
            budget: 600.0,
        };
        let mut readings = Vec::new();
        let row = chain_floor::measure(8, settings, &mut readings).unwrap();
        println!("{row:?}");
        let t1 = row.t_first_impact.unwrap();
        assert!((0.40..0.47).contains(&t1), "{t1}");
        assert_eq!(row.stop, "t_end");
        assert!(!row.budget_limited);
        assert!((row.t_reached - (t1 + 0.5)).abs() < 1e-12);
        assert!((row.window_reached_s - 0.5).abs() < 1e-12);
        assert!(row.steps > 0 && row.rhs_evals > 6 * row.steps && row.impacts > 1);
        assert!(row.impact_instants <= row.impacts);
        assert!(row.window_wall_s > 0.0 && row.window_wall_s < row.wall_s);
        assert!((row.wall_per_sim_s - row.window_wall_s / 0.5).abs() < 1e-12);
        // The thread's CPU time, where Linux gives it: at most the wall time (and the
        // scheduler's tick of rounding).
        if let Some(cpu) = row.window_cpu_s {
            assert!(cpu > 0.0 && cpu <= row.window_wall_s + 1e-2, "{cpu}");
        }
        assert!(row.closed_points_end >= row.closed_pairs_end);
        assert!(row.max_closed_pairs >= row.closed_pairs_end);
        // The readings start at the first impact and end at the end of the window.
        assert_eq!(readings.first().map(|r| r.0), Some(0.0));
        assert!((readings.last().unwrap().0 - 0.5).abs() < 1e-12);
        // The same run with samples: its last sample's closed pairs.
        let scene = chain_floor::scene(8).unwrap();
        let mut s = scene.settings.clone();
        s.t_end = row.t_reached;
        let mut rec = Recorder {
            keep_samples: true,
            ..Default::default()
        };
        let summary = Simulation::new(&scene.model, &s, MaterialOverride::default())
            .unwrap()
            .run(&scene.initial, &mut rec, None);
        assert_eq!(summary.state.t, row.t_reached);
        let (_, modes) = rec.sample_modes.last().unwrap();
        let closed = (modes.iter())
            .filter(|m| matches!(m, PairMode::Sticking | PairMode::Sliding))
            .count();
        assert_eq!(closed, row.closed_pairs_end as usize);
        assert_eq!(
            summary.counters.steps - row.free_fall_steps,
            row.steps,
            "the window's steps"
        );
    }

    /// A budget spent before the rope lands: no window, marked budget-limited.
    #[test]
    fn a_spent_budget_is_a_budget_limited_row() {
        let settings = FloorSettings {
            window: 0.5,
            budget: 1e-9,
        };
        let row = chain_floor::measure(16, settings, &mut Vec::new()).unwrap();
        assert!(row.budget_limited);
        assert_eq!(row.stop, "budget");
        assert_eq!(row.t_first_impact, None);
        assert_eq!(row.window_reached_s, 0.0);
        assert!(row.t_reached < 0.4);
    }

    /// The wall time inside a window from the clock readings, and the common window.
    #[test]
    fn the_common_window_reads_each_rows_clock() {
        let readings = [(0.0, 0.0), (0.1, 1.0), (0.3, 2.0)];
        assert_eq!(wall_at(&readings, 0.0), Some(0.0));
        assert_eq!(wall_at(&readings, 0.1), Some(1.0));
        assert!((wall_at(&readings, 0.2).unwrap() - 1.5).abs() < 1e-12);
        assert_eq!(wall_at(&readings, 0.31), None);
        let row = |links, reached| FloorRow {
            window_reached_s: reached,
            ..sample_row(links)
        };
        let mut rows = vec![row(1, 0.5), row(2, 0.2), row(4, 0.3)];
        let clocks = vec![
            vec![(0.0, 0.0), (0.5, 1.0)],
            vec![(0.0, 0.0), (0.2, 8.0)],
            vec![(0.0, 0.0), (0.1, 4.0), (0.3, 5.0)],
        ];
        common_window(&mut rows, &clocks);
        for r in &rows {
            assert_eq!(r.common_window_s, Some(0.2));
        }
        let cost: Vec<Real> = rows
            .iter()
            .map(|r| r.common_wall_per_sim_s.unwrap())
            .collect();
        assert!((cost[0] - 0.4 / 0.2).abs() < 1e-12);
        assert!((cost[1] - 8.0 / 0.2).abs() < 1e-12);
        assert!((cost[2] - 4.5 / 0.2).abs() < 1e-12);
    }

    fn sample_row(links: u32) -> FloorRow {
        FloorRow {
            links,
            pairs: 3 * links,
            window_s: 0.5,
            budget_s: 900.0,
            t_first_impact: Some(0.4479),
            free_fall_wall_s: 0.184,
            free_fall_wall_per_sim_s: 0.411,
            free_fall_cpu_s: Some(0.18),
            free_fall_steps: 1540,
            t_reached: 0.9479,
            window_reached_s: 0.5,
            wall_s: 2.58,
            window_wall_s: 2.398,
            wall_per_sim_s: 4.796,
            window_cpu_s: Some(2.2),
            cpu_per_sim_s: Some(4.4),
            common_window_s: None,
            common_wall_per_sim_s: None,
            steps: 2000,
            rejected: 40,
            rhs_evals: 14_000,
            events: 150,
            impacts: 1200,
            impact_instants: 100,
            closed_pairs_end: 20,
            closed_points_end: 40,
            max_closed_pairs: 22,
            budget_limited: false,
            stop: "t_end".into(),
            load_before: Some(2.37),
        }
    }

    #[test]
    fn floor_rows_survive_the_csv_round_trip() {
        let rows = vec![
            FloorRow {
                common_window_s: Some(0.123_456_789),
                common_wall_per_sim_s: Some(1.234_567_890_123e3),
                ..sample_row(32)
            },
            FloorRow {
                t_first_impact: None,
                wall_per_sim_s: Real::NAN,
                window_cpu_s: None,
                cpu_per_sim_s: None,
                budget_limited: true,
                stop: "budget".into(),
                ..sample_row(256)
            },
        ];
        let dir = std::env::temp_dir().join(format!("ricochet-floor-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("chain_floor.csv");
        table::write(&path, &rows).unwrap();
        let back: Vec<FloorRow> = table::read(&path).unwrap();
        assert_eq!(back[0], rows[0]);
        assert_eq!(back[1].t_first_impact, None);
        assert!(back[1].wall_per_sim_s.is_nan());
        assert!(back[1].budget_limited);
        assert_eq!(back[1].common_window_s, None);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The fit recovers the exponent of an exact power law, and of one with a constant
    /// factor of noise whose logarithms have no trend.
    #[test]
    fn the_exponent_fit_recovers_a_power_law() {
        let exact: Vec<(Real, Real)> = [8.0, 16.0, 32.0, 64.0, 128.0]
            .iter()
            .map(|&n: &Real| (n, 2.5e-4 * n.powf(2.9)))
            .collect();
        assert!((power_law_exponent(&exact) - 2.9).abs() < 1e-12);
        let noisy: Vec<(Real, Real)> = (exact.iter().zip([1.1, 0.9, 0.9, 1.1]))
            .map(|(&(x, y), f)| (x, y * f))
            .collect();
        let p = power_law_exponent(&noisy);
        assert!((p - 2.9).abs() < 0.1, "{p}");
    }
}
