//! Issue 12, item 7: sweeps lost results. Ctrl-C or SIGTERM during `ricochet sweep` wrote
//! no CSV at all (the signal killed the process), and the exit status was 0 even when
//! every run failed.
//!
//! Now: a signal stops the runs under way and writes the rows of the runs that finished,
//! the table marked incomplete in its header (`# incomplete …`); `--merge` refuses such a
//! table; the exit status is 0 when every run reached its end time, 1 when a run failed
//! (the table is written, its rows say why), 128 + the signal's number when interrupted.

use std::io::Cursor;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ricochet::sweep::{Grid, ParamSpec, Shard, Sweep, SweepError, merge, read_table};

use crate::common::cli;
use cli::{BIN, TempDir, ricochet};

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"))
}

/// A sweep with a failed run (the ball 1e300 m up: its first step is refused) exits 1 and
/// still writes every row; one where every run reaches its end exits 0.
#[test]
fn the_exit_status_says_whether_every_run_succeeded() {
    let dir = TempDir::new("status");
    let scene = scene_path("bouncing_ball");
    let scene = scene.to_str().unwrap();
    let out = ricochet(
        dir.path(),
        &[
            "sweep",
            scene,
            "-p",
            "q0.ball.q=1e300,1.1",
            "-p",
            "t_end=0.3",
            "-o",
            "a.csv",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("1 of 2 runs failed"), "{stderr}");
    let table = read_table(
        Cursor::new(std::fs::read(dir.join("a.csv")).unwrap()),
        "a.csv",
    )
    .unwrap();
    assert_eq!(table.rows.len(), 2);
    assert_eq!(table.header.incomplete, None);

    let out = ricochet(
        dir.path(),
        &[
            "sweep",
            scene,
            "-p",
            "q0.ball.q=1.1,1.2",
            "-p",
            "t_end=0.3",
            "-o",
            "b.csv",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{out:?}");
}

/// SIGINT and SIGTERM during a sweep whose last run lasts minutes: the three short runs
/// before it are written, the table says it is incomplete, the exit status is 128 + the
/// signal, and `--merge` refuses the table.
#[test]
fn a_signal_writes_the_finished_rows_marked_incomplete() {
    let dir = TempDir::new("signal");
    let scene = scene_path("rimless_wheel");
    for (signal, number) in [("INT", 2), ("TERM", 15)] {
        let csv = format!("wheel_{signal}.csv");
        let child = Command::new(BIN)
            .args([
                "sweep",
                scene.to_str().unwrap(),
                "-p",
                "t_end=0.1,0.2,0.3,100000",
            ])
            .args(["--threads", "1", "-o", &csv])
            .current_dir(dir.path())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The short runs take milliseconds; the long one 10 minutes.
        std::thread::sleep(Duration::from_secs(2));
        let status = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let start = Instant::now();
        let out = child.wait_with_output().unwrap();
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the sweep did not stop"
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(128 + number), "{signal}: {stderr}");
        let bytes = std::fs::read(dir.join(&csv))
            .unwrap_or_else(|e| panic!("{signal}: no table ({e}): {stderr}"));
        let table = read_table(Cursor::new(&bytes), &csv).unwrap();
        let indices: Vec<usize> = table.rows.iter().map(|(i, _)| *i).collect();
        assert_eq!(indices, [0, 1, 2], "{signal}");
        let stop = table.columns.iter().position(|c| c == "stop").unwrap();
        assert!(table.rows.iter().all(|(_, r)| &r[stop] == "t_end"));
        let incomplete = table.header.incomplete.clone().unwrap();
        assert!(
            incomplete.contains("3 of 4 runs") && incomplete.contains(&format!("SIG{signal}")),
            "{incomplete}"
        );
        assert!(String::from_utf8_lossy(&bytes).contains("\n# incomplete "));
        // The merge refuses it, naming the file.
        let err = merge(vec![table]).unwrap_err();
        assert!(matches!(err, SweepError::Incomplete { .. }), "{err}");
        assert!(err.to_string().contains(&csv), "{err}");
        let out = ricochet(dir.path(), &["sweep", "--merge", &csv, "-o", "merged.csv"]);
        assert_eq!(out.status.code(), Some(1));
        assert!(String::from_utf8_lossy(&out.stderr).contains("incomplete"));
        assert!(!dir.join("merged.csv").exists());
    }
}

/// The library: the runs of a shard under an interrupt flag already set give no rows, and
/// a complete table reads back with no `incomplete` mark (the bytes of a complete table
/// are unchanged).
#[test]
fn an_interrupt_before_the_runs_gives_no_rows() {
    let scene = ricochet::scene::load(scene_path("bouncing_ball")).unwrap();
    let grid = Grid::new(vec![ParamSpec::parse("e=0.5,0.6").unwrap()]).unwrap();
    let sweep = Sweep::new(&scene, grid).unwrap();
    let pool = ricochet::sweep::thread_pool(None).unwrap();
    let flag = std::sync::atomic::AtomicBool::new(true);
    assert!(
        sweep
            .run_until(&pool, Shard::ALL, &|_| {}, Some(&flag))
            .is_empty()
    );
    flag.store(false, std::sync::atomic::Ordering::SeqCst);
    let rows = sweep.run_until(&pool, Shard::ALL, &|_| {}, Some(&flag));
    assert_eq!(rows, sweep.run_in(&pool, Shard::ALL, &|_| {}));
    let mut bytes = Vec::new();
    sweep.write_table(&mut bytes, Shard::ALL, &rows).unwrap();
    assert!(!String::from_utf8_lossy(&bytes).contains("incomplete"));
}
