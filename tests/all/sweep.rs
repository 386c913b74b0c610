//! Parameter sweeps (`ricochet::sweep`, `ricochet sweep`).
//!
//! Checked here:
//! - the parameter specs: the exact values of `start:stop:step` (`start + k·step`, the
//!   stop inclusive and exact), lists, names, the canonical form; every kind of bad spec
//!   gives an error that names it;
//! - the grid: the order of the Cartesian product against nested loops, a parameter given
//!   twice, too many runs; the shards: their syntax and that they partition the grid;
//! - a real sweep of `bouncing_ball` over `e`, `t_end` and the law: every row against a
//!   separate run of `Simulation` with the same overrides (the same numbers, bit for bit),
//!   and against the closed forms of the bouncing ball (the number of impacts, ΔE total
//!   `−m g h0 (1 − e^{2n})`, the final height and speed);
//! - a run that fails is a row (`stop = error`), not a failure of the sweep;
//! - 1 thread and 2 threads give the same table, byte for byte; shards 0/3, 1/3, 2/3
//!   (and 20 shards, most of them empty) merged give the unsharded table byte for byte;
//! - merge errors: a shard missing, a shard twice, a shard of another grid, a file that is
//!   not a table;
//! - the command line: a sweep, its shards and their merge (the same file), and bad input.

use std::io::Cursor;
use std::num::NonZeroUsize;
use std::path::PathBuf;

use ricochet::impact::Law;
use ricochet::integrate::Method;
use ricochet::scene::Scene;
use ricochet::sim::{MaterialOverride, NullObserver, Simulation};
use ricochet::sweep::{
    Grid, Param, ParamSpec, RunResult, Shard, SpecError, Sweep, SweepError, Value, merge,
    read_table, write_table,
};

use crate::common::cli;
use cli::{TempDir, ricochet};

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"))
}

fn scene(name: &str) -> Scene {
    ricochet::scene::load(scene_path(name)).unwrap()
}

fn reals(spec: &str) -> Vec<f64> {
    let p = ParamSpec::parse(spec).unwrap();
    (0..p.len())
        .map(|k| match p.value(k) {
            Value::Real(x) => x,
            v => panic!("{spec}: {v:?} is not a number"),
        })
        .collect()
}

#[test]
fn ranges_are_start_plus_k_step_with_an_exact_inclusive_stop() {
    assert_eq!(reals("e=0:1:0.25"), [0.0, 0.25, 0.5, 0.75, 1.0]);
    // 21 values; value_k = 0 + k·0.05 exactly (no accumulated sum), the last one 1.
    let v = reals("e=0:1:0.05");
    assert_eq!(v.len(), 21);
    for (k, x) in v.iter().enumerate().take(20) {
        assert_eq!(x.to_bits(), (0.0 + k as f64 * 0.05).to_bits(), "k = {k}");
    }
    assert_eq!(v[20], 1.0);
    // A sum would drift: 0.05 added 20 times is not 1 (which is why k·step is used).
    assert_ne!((0..20).fold(0.0, |s, _| s + 0.05), 1.0);
    // 3·0.1 = 0.30000000000000004: the stop is within the tolerance, so the last value is
    // the stop itself.
    assert_ne!(3.0 * 0.1, 0.3);
    assert_eq!(reals("mu=0:0.3:0.1"), [0.0, 0.1, 0.2, 0.3]);
    // A stop half a step beyond the last value is not reached.
    let v = reals("mu=0:0.95:0.1");
    assert_eq!(v.len(), 10);
    assert_eq!(v[9], 9.0 * 0.1);
    // Negative and single-value ranges, offsets.
    assert_eq!(reals("q0.ball.q=-1:1:0.5"), [-1.0, -0.5, 0.0, 0.5, 1.0]);
    assert_eq!(reals("t_end=2:2:0.5"), [2.0]);
    assert_eq!(reals("t_end=0.5:1.6:0.5"), [0.5, 1.0, 1.5]);
    assert_eq!(reals("rtol=1e-12,1e-10, 1e-8"), [1e-12, 1e-10, 1e-8]);
}

#[test]
fn lists_names_and_the_canonical_form() {
    let p = ParamSpec::parse("law=newton,stronge").unwrap();
    assert_eq!(p.param, Param::Law);
    assert_eq!(p.len(), 2);
    assert_eq!(p.value(1), Value::Law(Law::Stronge));
    let p = ParamSpec::parse("method=moreau-jean").unwrap();
    assert_eq!(p.value(0), Value::Method(Method::MoreauJean));
    assert_eq!(
        ParamSpec::parse("u0.rod.theta=3").unwrap().param,
        Param::U0("rod.theta".into())
    );
    // Equal values print alike.
    assert_eq!(
        ParamSpec::parse("e=.0:1.0:.25").unwrap().canonical(),
        "e=0:1:0.25"
    );
    assert_eq!(
        ParamSpec::parse("mu=0.10, 1e0,1e-7").unwrap().canonical(),
        "mu=0.1,1,1e-7"
    );
    assert_eq!(
        ParamSpec::parse("law = kane-levinson").unwrap().canonical(),
        "law=kane-levinson"
    );
}

#[test]
fn bad_specs_are_errors_that_name_the_spec() {
    let malformed = [
        "e",
        "e=",
        "e=0:1",
        "e=0:1:2:3",
        "e=0:1:0",
        "e=0:1:-0.1",
        "e=1:0:0.1",
        "e=0:1:x",
        "e=a",
        "e=0,,1",
        "law=0:1:1",
        "law=foo",
        "method=euler",
        "e=0:1:1e-12",
    ];
    for spec in malformed {
        let err = ParamSpec::parse(spec).unwrap_err();
        assert!(
            matches!(err, SpecError::Malformed { .. }),
            "{spec}: {err:?}"
        );
        assert!(err.to_string().contains(&format!("`{spec}`")), "{err}");
    }
    let out_of_range = [
        "e=1.5",
        "e=-0.1:1:0.1",
        "e=0:1.5:0.5",
        "e=nan",
        "mu=-0.1",
        "mu=inf",
        "t_end=0",
        "rtol=-1",
        "atol=0",
        "dt=-1e-3",
        "h_max=0",
        "q0.ball.q=inf",
    ];
    for spec in out_of_range {
        let err = ParamSpec::parse(spec).unwrap_err();
        assert!(
            matches!(err, SpecError::OutOfRange { .. }),
            "{spec}: {err:?}"
        );
        assert!(err.to_string().contains(&format!("`{spec}`")), "{err}");
    }
    for spec in ["x=1", "=1", "q0.=1", "E=0.5", "q.ball.q=1"] {
        let err = ParamSpec::parse(spec).unwrap_err();
        assert!(
            matches!(err, SpecError::UnknownParam { .. }),
            "{spec}: {err:?}"
        );
        assert!(err.to_string().contains(&format!("`{spec}`")), "{err}");
    }
    // A coordinate the scene does not have.
    let s = scene("bouncing_ball");
    let grid = Grid::new(vec![ParamSpec::parse("q0.ball.y=1").unwrap()]).unwrap();
    let err = Sweep::new(&s, grid).unwrap_err();
    assert!(
        matches!(&err, SpecError::UnknownCoordinate { name, .. } if name == "ball.y"),
        "{err:?}"
    );
    assert!(err.to_string().contains("q0.ball.y") && err.to_string().contains("ball.q"));
}

#[test]
fn the_grid_is_the_product_in_nested_loop_order() {
    let a = ParamSpec::parse("e=0.1,0.2,0.3").unwrap();
    let b = ParamSpec::parse("law=newton,poisson").unwrap();
    let c = ParamSpec::parse("t_end=1:2:0.5").unwrap();
    let grid = Grid::new(vec![a.clone(), b.clone(), c.clone()]).unwrap();
    assert_eq!(grid.len(), 18);
    let mut index = 0;
    for i in 0..a.len() {
        for j in 0..b.len() {
            for k in 0..c.len() {
                assert_eq!(grid.value(index, 0), a.value(i));
                assert_eq!(grid.value(index, 1), b.value(j));
                assert_eq!(grid.value(index, 2), c.value(k));
                index += 1;
            }
        }
    }
    // No parameter: one run, the scene as it is.
    assert_eq!(Grid::new(vec![]).unwrap().len(), 1);
    // A parameter twice; too many runs.
    let err = Grid::new(vec![a.clone(), b, a]).unwrap_err();
    assert_eq!(err, SpecError::Duplicate { name: "e".into() });
    let err = Grid::new(vec![
        ParamSpec::parse("e=0:1:0.0001").unwrap(),
        ParamSpec::parse("mu=0:1:0.0001").unwrap(),
    ])
    .unwrap_err();
    assert!(matches!(err, SpecError::TooLarge { .. }), "{err:?}");
}

#[test]
fn shards_parse_and_partition_the_grid() {
    assert_eq!("2/3".parse::<Shard>().unwrap(), Shard::new(2, 3).unwrap());
    assert_eq!("0/1".parse::<Shard>().unwrap(), Shard::ALL);
    for bad in ["3/3", "1/0", "-1/3", "a/3", "1", "1/3/4", "", "1/"] {
        let err = bad.parse::<Shard>().unwrap_err();
        assert!(err.to_string().contains(&format!("`{bad}`")), "{err}");
    }
    for len in [0, 1, 7, 10, 31] {
        for n in 1..=12 {
            let mut seen = vec![0; len];
            for i in 0..n {
                let shard = Shard::new(i, n).unwrap();
                let runs: Vec<usize> = shard.runs(len).collect();
                assert!(runs.windows(2).all(|w| w[0] < w[1]));
                for r in runs {
                    assert!(shard.contains(r));
                    seen[r] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "len {len}, {n} shards");
        }
    }
}

/// `bouncing_ball` (m = 0.1 kg, r = 0.1 m, dropped from h0 = 1 m, g = 9.81 m/s²) at rtol
/// 1e-12: 3 values of e × 3 end times × 2 laws (Newton's and Stronge's restitution agree
/// for a frictionless central impact), none near an impact time or the accumulation.
fn ball_grid() -> Vec<ParamSpec> {
    [
        "e=0.5:0.8:0.15",
        "t_end=0.4,1,1.3",
        "law=newton,stronge",
        "rtol=1e-12",
    ]
    .map(|s| ParamSpec::parse(s).unwrap())
    .into()
}

fn real(v: Value) -> f64 {
    match v {
        Value::Real(x) => x,
        v => panic!("{v:?} is not a number"),
    }
}

#[test]
fn a_sweep_of_the_bouncing_ball_agrees_with_single_runs_and_the_closed_forms() {
    let s = scene("bouncing_ball");
    let sweep = Sweep::new(&s, Grid::new(ball_grid()).unwrap()).unwrap();
    let rows = sweep
        .run(Shard::ALL, NonZeroUsize::new(2), &|_| {})
        .unwrap();
    assert_eq!(rows.len(), 18);
    let (m, r, h0, g): (f64, f64, f64, f64) = (0.1, 0.1, 1.0, 9.81);
    let t1 = (2.0 * h0 / g).sqrt();
    let v1 = (2.0 * g * h0).sqrt();
    let mut impacts_seen = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.index, k);
        let (e, t_end) = (real(row.values[0]), real(row.values[1]));
        let Value::Law(law) = row.values[2] else {
            panic!()
        };
        let got = row.outcome.as_ref().unwrap();

        // A second method: the same run through `Simulation` with the same overrides.
        let mut settings = s.settings.clone();
        settings.t_end = t_end;
        settings.integrator.rtol = 1e-12;
        let overrides = MaterialOverride {
            law: Some(law),
            e: Some(e),
            mu: None,
        };
        let mut sim = Simulation::new(&s.model, &settings, overrides).unwrap();
        let single = RunResult::from(sim.run(&s.initial, &mut NullObserver, None));
        assert_eq!(got, &single, "run {k}");

        // The closed form: impact n at t_n = t1 + (2 v1/g) Σ_{j=1}^{n−1} e^j.
        let mut n = 0;
        let mut t_n = t1;
        while t_n < t_end {
            assert!((t_end - t_n).abs() > 1e-3, "an impact too close to t_end");
            n += 1;
            t_n += 2.0 * v1 / g * e.powi(n);
        }
        let t_last = t_n - 2.0 * v1 / g * e.powi(n);
        assert_eq!(got.stop, "t_end");
        assert_eq!(
            got.counters.impacts, n as u64,
            "run {k}: e = {e}, t_end = {t_end}"
        );
        impacts_seen.push(n);
        // ΔE total = Σ −½ m (e^j v1)² (1 − e²) = −m g h0 (1 − e^{2n}).
        let delta_e = -m * g * h0 * (1.0 - e.powi(2 * n));
        assert!(
            (got.audit.impact_delta_e - delta_e).abs() <= 1e-9 * m * g * h0,
            "run {k}: ΔE {} against {delta_e}",
            got.audit.impact_delta_e
        );
        // The final state: a free flight from the floor at e^n v1 since t_n (before the
        // first impact: the drop from h0).
        let (y, u) = if n == 0 {
            (r + h0 - 0.5 * g * t_end * t_end, -g * t_end)
        } else {
            let tau = t_end - t_last;
            let w = e.powi(n) * v1;
            (r + w * tau - 0.5 * g * tau * tau, w - g * tau)
        };
        assert_eq!(got.state.t, t_end);
        assert!(
            (got.state.q[0] - y).abs() < 1e-9,
            "run {k}: y {} against {y}",
            got.state.q[0]
        );
        assert!(
            (got.state.u[0] - u).abs() < 1e-9,
            "run {k}: u {} against {u}",
            got.state.u[0]
        );
    }
    // The grid covers 0 to 5 impacts.
    assert_eq!(impacts_seen.iter().min(), Some(&0));
    assert_eq!(impacts_seen.iter().max(), Some(&5));
}

#[test]
fn a_failed_run_is_a_row() {
    let s = scene("bouncing_ball");
    let grid = Grid::new(vec![
        ParamSpec::parse("q0.ball.q=1e300,1.1").unwrap(),
        ParamSpec::parse("t_end=0.3").unwrap(),
    ])
    .unwrap();
    let sweep = Sweep::new(&s, grid).unwrap();
    let rows = sweep.run(Shard::ALL, None, &|_| {}).unwrap();
    assert_eq!(rows[0].stop(), "error");
    assert_eq!(rows[1].stop(), "t_end");
    let mut bytes = Vec::new();
    sweep.write_table(&mut bytes, Shard::ALL, &rows).unwrap();
    let table = read_table(Cursor::new(&bytes), "mem").unwrap();
    let stop = table.columns.iter().position(|c| c == "stop").unwrap();
    let detail = table
        .columns
        .iter()
        .position(|c| c == "stop_detail")
        .unwrap();
    assert_eq!(&table.rows[0].1[stop], "error");
    assert!(table.rows[0].1[detail].starts_with("failed: "));
}

/// Issue 12: `sweep -p q0.ball.q=-5` put the ball 5 m inside the floor and "reached the end
/// time": the overlap check of a scene's initial state was skipped for swept states. It
/// is an error row naming the overlap, as `check` would say; the valid value still runs.
#[test]
fn a_swept_initial_state_inside_an_obstacle_is_an_error_row() {
    let s = scene("bouncing_ball");
    let grid = Grid::new(vec![ParamSpec::parse("q0.ball.q=-5,1").unwrap()]).unwrap();
    let sweep = Sweep::new(&s, grid).unwrap();
    let rows = sweep.run(Shard::ALL, None, &|_| {}).unwrap();
    assert_eq!(rows[0].stop(), "error");
    let detail = &rows[0].outcome.as_ref().unwrap_err().detail;
    assert!(
        detail.contains("`ball` and `floor` overlap by 5.100e0 m at the start"),
        "{detail}"
    );
    assert_eq!(rows[1].stop(), "t_end");
}

/// A nonholonomic scene has fewer generalized speeds than coordinates (the Chaplygin
/// sleigh: `q = (x, y, angle)`, `u = (vx_body, omega)`): its table has a `u.` column per
/// speed, named after the speed, and holds the final state of a single run bit for bit.
/// The columns used to repeat the coordinates for `u`, and every sweep of such a scene
/// failed to write its table ("found record with 25 fields, but the previous record has
/// 26 fields"), losing every run.
#[test]
fn a_nonholonomic_scene_has_a_column_per_speed() {
    let s = scene("chaplygin_sleigh");
    assert!(s.model.nu() < s.model.nq());
    let grid = Grid::new(vec![
        ParamSpec::parse("e=0.2,0.6").unwrap(),
        ParamSpec::parse("t_end=4").unwrap(),
    ])
    .unwrap();
    let sweep = Sweep::new(&s, grid).unwrap();
    let rows = sweep.run(Shard::ALL, None, &|_| {}).unwrap();
    let mut bytes = Vec::new();
    sweep.write_table(&mut bytes, Shard::ALL, &rows).unwrap();
    let table = read_table(Cursor::new(&bytes), "mem").unwrap();
    let speeds: Vec<String> = s
        .model
        .speeds()
        .iter()
        .map(|v| format!("u.{}", v.name))
        .collect();
    let u_columns: Vec<String> = (table.columns.iter())
        .filter(|c| c.starts_with("u."))
        .map(str::to_owned)
        .collect();
    assert_eq!(u_columns, speeds);
    let coordinates = table.columns.iter().filter(|c| c.starts_with("q.")).count();
    assert_eq!(coordinates, s.model.nq());
    // The run with e = 0.6 against a single run with the same override.
    let mut single = Simulation::new(
        &s.model,
        &ricochet::settings::Settings {
            t_end: 4.0,
            ..s.settings.clone()
        },
        MaterialOverride {
            e: Some(0.6),
            ..MaterialOverride::default()
        },
    )
    .unwrap();
    let end = single.run(&s.initial, &mut NullObserver, None);
    assert_eq!(rows[1].stop(), "t_end");
    assert!(end.counters.impacts > 0, "the sleigh reaches the wall");
    let row = &table.rows[1].1;
    for (k, name) in speeds.iter().enumerate() {
        let at = table.columns.iter().position(|c| c == name).unwrap();
        assert_eq!(
            row[at].parse::<f64>().unwrap().to_bits(),
            end.state.u[k].to_bits(),
            "{name}"
        );
    }
}

fn table_bytes(sweep: &Sweep, shard: Shard, threads: usize) -> Vec<u8> {
    let rows = sweep
        .run(shard, NonZeroUsize::new(threads), &|_| {})
        .unwrap();
    let mut bytes = Vec::new();
    sweep.write_table(&mut bytes, shard, &rows).unwrap();
    bytes
}

fn merged(shards: &[&[u8]]) -> Result<Vec<u8>, SweepError> {
    let tables = shards
        .iter()
        .enumerate()
        .map(|(k, b)| read_table(Cursor::new(b), &format!("shard{k}.csv")).unwrap())
        .collect();
    let (header, columns, rows) = merge(tables)?;
    let mut out = Vec::new();
    write_table(&mut out, &header, &columns, &rows)?;
    Ok(out)
}

#[test]
fn threads_and_shards_give_the_same_table_byte_for_byte() {
    let s = scene("bouncing_ball");
    let sweep = Sweep::new(&s, Grid::new(ball_grid()).unwrap()).unwrap();
    let whole = table_bytes(&sweep, Shard::ALL, 1);
    assert_eq!(table_bytes(&sweep, Shard::ALL, 2), whole);
    let text = String::from_utf8(whole.clone()).unwrap();
    assert!(text.starts_with("# ricochet sweep 1\n"), "{text}");
    assert!(text.contains("\n# shard 0/1\nrun,e,t_end,law,rtol,stop,impacts,delta_e,"));
    assert_eq!(text.lines().filter(|l| !l.starts_with('#')).count(), 1 + 18);

    let shards: Vec<Vec<u8>> = (0..3)
        .map(|i| table_bytes(&sweep, Shard::new(i, 3).unwrap(), 1 + i % 2))
        .collect();
    assert!(String::from_utf8_lossy(&shards[1]).contains("\n# shard 1/3\n"));
    // In any order of the files.
    let refs: Vec<&[u8]> = vec![&shards[2], &shards[0], &shards[1]];
    assert_eq!(merged(&refs).unwrap(), whole);
    // 20 shards of 18 runs: two are empty.
    let many: Vec<Vec<u8>> = (0..20)
        .map(|i| table_bytes(&sweep, Shard::new(i, 20).unwrap(), 2))
        .collect();
    let refs: Vec<&[u8]> = many.iter().map(Vec::as_slice).collect();
    assert_eq!(merged(&refs).unwrap(), whole);
    // The whole table merges to itself.
    assert_eq!(merged(&[&whole]).unwrap(), whole);
}

#[test]
fn merge_errors() {
    let s = scene("bouncing_ball");
    let grid = || {
        Grid::new(vec![
            ParamSpec::parse("e=0.5,0.8").unwrap(),
            ParamSpec::parse("t_end=0.3:0.5:0.1").unwrap(),
        ])
        .unwrap()
    };
    let sweep = Sweep::new(&s, grid()).unwrap();
    let shard = |i| table_bytes(&sweep, Shard::new(i, 3).unwrap(), 1);
    let (a, b, c) = (shard(0), shard(1), shard(2));

    let err = merged(&[&a, &c]).unwrap_err();
    assert!(
        matches!(
            err,
            SweepError::Missing {
                count: 2,
                runs: 6,
                ..
            }
        ),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("1, 4") && msg.contains("1/3 not given"),
        "{msg}"
    );

    let err = merged(&[&a, &b, &c, &b]).unwrap_err();
    assert!(
        matches!(err, SweepError::Duplicate { index: 1, .. }),
        "{err:?}"
    );

    // A shard of another grid (t_end to 0.6).
    let other = Sweep::new(
        &s,
        Grid::new(vec![
            ParamSpec::parse("e=0.5,0.8").unwrap(),
            ParamSpec::parse("t_end=0.3:0.6:0.1").unwrap(),
        ])
        .unwrap(),
    )
    .unwrap();
    let foreign = table_bytes(&other, Shard::new(2, 3).unwrap(), 1);
    let err = merged(&[&a, &b, &foreign]).unwrap_err();
    assert!(
        matches!(&err, SweepError::Mismatch { what, .. } if what == "parameters"),
        "{err:?}"
    );
    // Another scene.
    let rod = scene("falling_rod");
    let rod_sweep = Sweep::new(&rod, grid()).unwrap();
    let foreign = table_bytes(&rod_sweep, Shard::new(2, 3).unwrap(), 1);
    let err = merged(&[&a, &b, &foreign]).unwrap_err();
    assert!(
        matches!(&err, SweepError::Mismatch { what, .. } if what == "scene"),
        "{err:?}"
    );
    // A row that is not in its file's shard (the header of shard 2/3 over rows of 1/3).
    let text = String::from_utf8(b.clone()).unwrap();
    let edited = text.replace("# shard 1/3", "# shard 2/3");
    let err = merged(&[&a, &b, edited.as_bytes()]).unwrap_err();
    assert!(matches!(err, SweepError::ForeignRow { .. }), "{err:?}");
    // Not a table.
    let err = read_table(Cursor::new(b"run,e\n0,0.5\n"), "plain.csv").unwrap_err();
    assert!(matches!(err, SweepError::Format { .. }), "{err:?}");
    assert!(merge(vec![]).is_err());
}

#[test]
fn the_command_line_sweeps_shards_and_merges() {
    let dir = TempDir::new("cli");
    let scene_file = scene_path("bouncing_ball");
    let scene_arg = scene_file.to_str().unwrap();
    let params = ["-p", "e=0.5:0.8:0.15", "--param", "t_end=0.4,1"];
    let args = |extra: &[&'static str]| -> Vec<&str> {
        let mut v = vec!["sweep", scene_arg];
        v.extend(params);
        v.extend(extra);
        v
    };
    let out = ricochet(dir.path(), &args(&["--threads", "2"]));
    assert!(out.status.success(), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("6 of 6 runs") && stdout.contains("6 t_end"),
        "{stdout}"
    );
    // The default name; no progress bar on a pipe.
    let whole = std::fs::read(dir.join("bouncing_ball_sweep.csv")).unwrap();
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The library's table, byte for byte.
    let s = scene("bouncing_ball");
    let specs = params[1..]
        .iter()
        .step_by(2)
        .map(|p| ParamSpec::parse(p).unwrap())
        .collect();
    let sweep = Sweep::new(&s, Grid::new(specs).unwrap()).unwrap();
    assert_eq!(whole, table_bytes(&sweep, Shard::ALL, 1));

    for i in ["0/2", "1/2"] {
        let out = ricochet(dir.path(), &args(&["--shard", i, "--threads", "1"]));
        assert!(out.status.success(), "{out:?}");
    }
    let out = ricochet(
        dir.path(),
        &[
            "sweep",
            "--merge",
            "bouncing_ball_sweep.shard-1-of-2.csv",
            "bouncing_ball_sweep.shard-0-of-2.csv",
            "-o",
            "merged.csv",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    assert_eq!(std::fs::read(dir.join("merged.csv")).unwrap(), whole);

    // A shard missing.
    let out = ricochet(
        dir.path(),
        &[
            "sweep",
            "--merge",
            "bouncing_ball_sweep.shard-1-of-2.csv",
            "-o",
            "bad.csv",
        ],
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("0/2 not given"), "{stderr}");
    assert!(!dir.join("bad.csv").exists());

    // Bad input: a malformed spec, an unknown parameter, a bad shard; no file written.
    for (extra, culprit) in [
        (vec!["-p", "e=0:1"], "`e=0:1`"),
        (vec!["-p", "gravity=1"], "unknown parameter `gravity`"),
        (vec!["-p", "e=0.5", "--shard", "2/2"], "bad shard `2/2`"),
    ] {
        let mut a = vec!["sweep", scene_arg, "-o", "x.csv"];
        a.extend(extra);
        let out = ricochet(dir.path(), &a);
        assert!(!out.status.success(), "{a:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(culprit), "{a:?}: {stderr}");
        assert!(!dir.join("x.csv").exists());
    }
}

/// `simultaneous` is a sweep parameter (issue 15: the rule for simultaneous impacts is a
/// per-scene choice; a sweep compares them). Newton's cradle, 0.08 s after the first ball
/// strikes the row: every row is a separate run with the same rule (bit for bit), and the
/// rows show what the scene file says of each rule — sequential: balls 1–4 at rest, ball 5
/// swings out; generalized Newton: balls 3–5 leave together, ball 2 stops after striking
/// ball 1, which swings back as fast as the three (the same pendulums from the same speed).
#[test]
fn a_sweep_over_the_simultaneous_rule_gives_each_rule_s_cradle() {
    let s = scene("newtons_cradle");
    let grid = Grid::new(vec![
        ParamSpec::parse("simultaneous=generalized-newton,sequential").unwrap(),
        ParamSpec::parse("t_end=0.4").unwrap(),
    ])
    .unwrap();
    assert_eq!(
        grid.params()[0].canonical(),
        "simultaneous=generalized-newton,sequential"
    );
    let sweep = Sweep::new(&s, grid).unwrap();
    let rows = sweep
        .run(Shard::ALL, NonZeroUsize::new(2), &|_| {})
        .unwrap();
    assert_eq!(rows.len(), 2);
    for row in &rows {
        let Value::Simultaneous(rule) = row.values[0] else {
            panic!("{:?}", row.values[0])
        };
        let got = row.outcome.as_ref().unwrap();
        assert_eq!(got.stop, "t_end");
        let mut settings = s.settings.clone();
        settings.t_end = 0.4;
        settings.simultaneous = rule;
        let mut sim = Simulation::new(&s.model, &settings, MaterialOverride::default()).unwrap();
        let single = RunResult::from(sim.run(&s.initial, &mut NullObserver, None));
        assert_eq!(got, &single, "{rule:?}");
        let u = &got.state.u;
        println!("{}: u = {u:?}", rule.name());
        assert!(u[4] > 0.5, "{u:?}");
        match rule {
            ricochet::settings::Simultaneous::Sequential => {
                assert!(u.rows(0, 4).iter().all(|w| w.abs() < 1e-9), "{u:?}");
            }
            ricochet::settings::Simultaneous::GeneralizedNewton => {
                assert!(u[1].abs() < 1e-9, "{u:?}");
                assert!((u[2] - u[4]).abs() < 1e-9 && (u[3] - u[4]).abs() < 1e-9);
                assert!((u[0] + u[4]).abs() < 1e-6 * u[4], "{u:?}");
            }
        }
    }
    assert!(ParamSpec::parse("simultaneous=both").is_err());
}
