//! `ricochet repair`, run as a user runs it: the built binary in a fresh temporary folder.
//!
//! Checked here:
//! - a long `ricochet run` killed with SIGKILL leaves a log without a summary; `ricochet
//!   repair` on it exits 0, says what it kept and lost, leaves the input as it was, and
//!   writes `<stem>.repaired.mcap`, which has a summary, reads whole with
//!   `mcap::MessageStream`, holds at least the messages `log::read` saw in the broken log,
//!   has no chunk without messages, and which `ricochet inspect` reads;
//! - on a complete log it says the input was complete, and `-o` writes where told;
//! - errors (exit 1, a clear message, no file written, no temporary file left): `-o` naming
//!   the input (through another spelling too), an existing output without `--force` (with
//!   it, the output is replaced), a missing input, an input that is not MCAP.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ricochet::log::Ending;

use crate::common::mcap_check;
use mcap_check::{assert_every_chunk_has_messages, messages};

use crate::common::cli;
use cli::{BIN, TempDir, ricochet};

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"))
}

impl TempDir {
    /// The names of the files in the folder, sorted.
    fn files(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).unwrap()
}

/// Runs `ricochet <args>`, expects exit 0; returns stdout.
fn ok(dir: &Path, args: &[&str]) -> String {
    let out = ricochet(dir, args);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(
        out.status.success(),
        "ricochet {args:?}: {:?}\n{stdout}\n{stderr}",
        out.status
    );
    stdout
}

/// Runs `ricochet <args>`, expects exit 1 and every needle in stderr.
fn fails(dir: &Path, args: &[&str], needles: &[&str]) {
    let out = ricochet(dir, args);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "ricochet {args:?}: {stderr}");
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "ricochet {args:?}: {stderr:?} lacks {needle:?}"
        );
    }
}

/// A long run (`pendulum_wall`, elastic, `t_end = 10⁶` s, as in `tests/all/cli_run.rs`)
/// killed with SIGKILL once its log holds several chunks.
#[test]
fn a_killed_run_is_repaired() {
    let dir = TempDir::new("sigkill");
    let scene = scene_path("pendulum_wall");
    let log_path = dir.join("long.mcap");
    let mut child = Command::new(BIN)
        .args(["run", scene.to_str().unwrap(), "--e", "1", "--t-end", "1e6"])
        .args(["-o", "long.mcap"])
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let len = std::fs::metadata(&log_path).map_or(0, |m| m.len());
        if len > 512 * 1024 {
            break;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended by itself"
        );
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the log did not grow: {len} bytes after 60 s");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();

    // The broken log: no summary; `log::read` reads it as far as it goes.
    let broken = std::fs::read(&log_path).unwrap();
    assert!(
        !matches!(mcap::Summary::read(&broken), Ok(Some(_))),
        "a killed run left a summary"
    );
    let seen = ricochet::log::read_bytes(&broken).unwrap();
    assert!(
        matches!(seen.ending, Ending::Truncated { .. }),
        "{:?}",
        seen.ending
    );
    let seen_messages: u64 = seen.message_counts.values().sum();

    let stdout = ok(dir.path(), &["repair", "long.mcap"]);
    println!("{stdout}");
    assert!(stdout.contains("long.mcap: "), "{stdout}");
    assert!(stdout.contains("cut short"), "{stdout}");
    assert!(stdout.contains("repaired: long.repaired.mcap"), "{stdout}");
    assert!(
        std::fs::read(&log_path).unwrap() == broken,
        "the input changed"
    );
    assert_eq!(dir.files(), ["long.mcap", "long.repaired.mcap"]);

    let fixed = std::fs::read(dir.join("long.repaired.mcap")).unwrap();
    assert!(mcap::Summary::read(&fixed).unwrap().is_some(), "no summary");
    let all = messages(&fixed);
    assert!(
        all.len() as u64 >= seen_messages,
        "{} < {seen_messages}",
        all.len()
    );
    assert!(stdout.contains(&format!(
        "kept: {} messages, 5 schemas, 6 channels",
        all.len()
    )));
    assert_every_chunk_has_messages(&fixed);
    // The same run for ricochet's reader, now complete: the scene and settings, every
    // impact seen, no audit (the run never finished).
    let log = ricochet::log::read_bytes(&fixed).unwrap();
    assert_eq!(log.ending, Ending::Complete);
    assert_eq!(log.scene, seen.scene);
    assert_eq!(log.settings, seen.settings);
    assert!(log.audit.is_none());
    assert!(log.impacts.len() >= seen.impacts.len());
    assert_eq!(log.impacts[..seen.impacts.len()], seen.impacts[..]);
    let inspect = ok(dir.path(), &["inspect", "long.repaired.mcap"]);
    assert!(inspect.contains("pendulum_wall"), "{inspect}");
}

/// A complete log: repaired, and the report says nothing was lost; `-o` writes where told.
#[test]
fn a_complete_log_is_said_to_be_complete() {
    let dir = TempDir::new("complete");
    let scene = scene_path("bouncing_ball");
    ok(
        dir.path(),
        &[
            "run",
            scene.to_str().unwrap(),
            "--t-end",
            "1",
            "-o",
            "ball.mcap",
        ],
    );
    let stdout = ok(dir.path(), &["repair", "ball.mcap", "-o", "fixed.mcap"]);
    assert!(stdout.contains("ball.mcap: "), "{stdout}");
    assert!(stdout.contains("complete"), "{stdout}");
    assert!(stdout.contains("lost: nothing"), "{stdout}");
    assert!(stdout.ends_with("repaired: fixed.mcap\n"), "{stdout}");
    assert_eq!(dir.files(), ["ball.mcap", "fixed.mcap"]);
    let original = std::fs::read(dir.join("ball.mcap")).unwrap();
    let fixed = std::fs::read(dir.join("fixed.mcap")).unwrap();
    assert_eq!(messages(&fixed), messages(&original));
    assert_every_chunk_has_messages(&fixed);
}

#[test]
fn bad_requests_give_a_clear_message_and_write_nothing() {
    let dir = TempDir::new("errors");
    let scene = scene_path("bouncing_ball");
    ok(
        dir.path(),
        &[
            "run",
            scene.to_str().unwrap(),
            "--t-end",
            "0.2",
            "-o",
            "ball.mcap",
        ],
    );
    let ball = std::fs::read(dir.join("ball.mcap")).unwrap();

    // The output is the input, however spelled.
    for output in ["ball.mcap", "./ball.mcap", "../{dir}/ball.mcap"] {
        let name = dir.path().file_name().unwrap().to_str().unwrap();
        let output = output.replace("{dir}", name);
        fails(
            dir.path(),
            &["repair", "ball.mcap", "-o", &output],
            &["is the input"],
        );
    }
    // An existing output, without --force; then with it.
    std::fs::write(dir.join("ball.repaired.mcap"), b"keep me").unwrap();
    fails(
        dir.path(),
        &["repair", "ball.mcap"],
        &["ball.repaired.mcap already exists", "--force"],
    );
    assert_eq!(
        std::fs::read(dir.join("ball.repaired.mcap")).unwrap(),
        b"keep me"
    );
    ok(dir.path(), &["repair", "ball.mcap", "--force"]);
    let fixed = std::fs::read(dir.join("ball.repaired.mcap")).unwrap();
    assert_eq!(messages(&fixed), messages(&ball));
    // A missing input; an input that is not MCAP.
    fails(
        dir.path(),
        &["repair", "missing.mcap"],
        &["cannot read missing.mcap"],
    );
    std::fs::write(dir.join("notes.txt"), b"not an MCAP file at all").unwrap();
    fails(
        dir.path(),
        &["repair", "notes.txt"],
        &["cannot repair notes.txt", "not an MCAP file"],
    );
    // No other file, no temporary file left behind.
    assert_eq!(
        dir.files(),
        ["ball.mcap", "ball.repaired.mcap", "notes.txt"]
    );
    assert!(std::fs::read(dir.join("ball.mcap")).unwrap() == ball);
}
