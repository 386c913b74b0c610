//! Issue 12, item 8: messages. A runtime error repeated its context three or four times
//! (`stopped at t = 0.5 s, failed: at t = 0.5: at t = 0.5: q[0] is not finite (NaN): at
//! t = 0.5: q[0] is not finite (NaN)`: each layer said its time and its cause's message,
//! and the chain was printed after it); a disk that filled up during a run said "the log
//! writer has stopped after an earlier error", not why nor which file; `ricochet run … |
//! head -1` ended with "Broken pipe" and exit 1 although the run had completed.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

use ricochet::dynamics::DynamicsError;
use ricochet::impact::ImpactError;
use ricochet::integrate::IntegrateError;
use ricochet::sim::{Nested, SimError, StopReason};

const BIN: &str = env!("CARGO_BIN_EXE_ricochet");

fn count(text: &str, part: &str) -> usize {
    text.matches(part).count()
}

fn non_finite(t: f64) -> SimError {
    SimError::Dynamics {
        t,
        source: DynamicsError::NonFinite {
            t,
            what: "q",
            index: 0,
            value: f64::NAN,
        },
    }
}

#[test]
fn a_failure_says_its_time_and_cause_once() {
    let cases = [
        (non_finite(0.5), "q[0] is not finite (NaN)"),
        (
            SimError::Integrate(IntegrateError::Rhs {
                t: 0.5,
                source: Nested(Box::new(non_finite(0.5))),
            }),
            "q[0] is not finite (NaN)",
        ),
        (
            SimError::Impact {
                t: 0.5,
                pair: 0,
                name: "ball/floor".to_owned(),
                source: ImpactError::Jam { law: "newton" },
            },
            "the contact jams under newton",
        ),
    ];
    for (error, cause) in cases {
        let text = StopReason::Failed(error).to_string();
        assert_eq!(count(&text, "t = 0.5"), 1, "{text}");
        assert_eq!(count(&text, cause), 1, "{text}");
        assert!(text.starts_with("failed: "), "{text}");
    }
    // Without the time, for a line that says it already.
    let error = SimError::Integrate(IntegrateError::Rhs {
        t: 0.5,
        source: Nested(Box::new(non_finite(0.5))),
    });
    assert_eq!(error.time(), Some(0.5));
    assert_eq!(
        error.what(),
        "right-hand side failed: q[0] is not finite (NaN)"
    );
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"))
}

/// Runs `sh -c script` with `$RICOCHET` and `$SCENE` set.
fn sh(script: &str, scene_name: &str, dir: &Path) -> Output {
    Command::new("sh")
        .args(["-c", script])
        .env("RICOCHET", BIN)
        .env("SCENE", scene(scene_name))
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// `command` started with its standard output and error piped, its input `stdin`.
fn piped(command: &mut Command, stdin: Stdio) -> Child {
    (command
        .stdin(stdin)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped()))
    .spawn()
    .unwrap()
}

fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ricochet-msg-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Checks the output of a run whose log could not be written past some size: the reason
/// of the operating system and the file, once each, and exit 1.
fn check_log_write_failure(out: &Output, file: &str, reason: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{stderr}");
    let error = stderr
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| {
            panic!("no error line: {stderr}");
        });
    assert!(error.contains(reason) && error.contains(file), "{error}");
    assert_eq!(count(&stderr, reason), 1, "{stderr}");
    assert!(!stderr.contains("earlier error"), "{stderr}");
}

/// A file size limit (`ulimit -f`, SIGXFSZ ignored) makes the log's writes fail after
/// 64 KiB: "File too large" and the log's name reach the user.
#[test]
fn a_log_that_cannot_grow_says_why_and_which_file() {
    let dir = temp_dir("fsize");
    let out = sh(
        r#"trap '' XFSZ; ulimit -f 128; exec "$RICOCHET" run "$SCENE" --t-end 200 -o wheel.mcap"#,
        "rimless_wheel",
        &dir,
    );
    check_log_write_failure(&out, "wheel.mcap", "File too large");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A full disk: a 200 KiB tmpfs (needs the right to mount; skipped, and said so, without
/// it). "No space left on device" and the log's name reach the user.
#[test]
fn a_full_disk_says_so() {
    let dir = temp_dir("enospc");
    let mount = dir.join("small");
    std::fs::create_dir_all(&mount).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=200k", "tmpfs"])
        .arg(&mount)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        println!("skipped: cannot mount a tmpfs here (the ulimit test covers the same path)");
        return;
    }
    let out = sh(
        r#"exec "$RICOCHET" run "$SCENE" --t-end 200 -o small/wheel.mcap"#,
        "rimless_wheel",
        &dir,
    );
    let _ = Command::new("umount").arg(&mount).status();
    check_log_write_failure(&out, "small/wheel.mcap", "No space left on device");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Standard output closed before anything is printed (`| head -0`, a reader gone): the
/// commands finish their work, print nothing more, and exit as they would have.
#[test]
fn a_closed_standard_output_is_not_an_error() {
    let dir = temp_dir("pipe");
    // As the issue has it (the status of a pipeline is that of `head`).
    let out = sh(
        r#""$RICOCHET" run "$SCENE" -o ball.mcap | head -1"#,
        "bouncing_ball",
        &dir,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("Broken pipe") && !stderr.contains("panicked"),
        "{stderr}"
    );
    // The exit status of ricochet itself, its standard output a pipe closed at once.
    for args in [
        vec![
            "run".to_owned(),
            scene("bouncing_ball").display().to_string(),
            "-o".into(),
            "ball.mcap".into(),
        ],
        vec!["inspect".to_owned(), "ball.mcap".to_owned()],
        vec![
            "check".to_owned(),
            scene("bouncing_ball").display().to_string(),
        ],
    ] {
        let mut child = piped(
            Command::new(BIN).args(&args).current_dir(&dir),
            Stdio::null(),
        );
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("Broken pipe") && !stderr.contains("panicked"),
            "{args:?}: {stderr}"
        );
    }
    assert!(ricochet::log::read(dir.join("ball.mcap")).is_ok());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Standard error closed (`2>&1 | head -1`, a reader gone): the warnings printed during a
/// run (and `impact`'s count of failed lines) were `eprintln!`, which panicked on the
/// closed pipe and killed the run with exit 101 at its first warning. Now the run goes on
/// to its end, writes the same log as with standard error open, and exits as it would have.
#[test]
fn a_closed_standard_error_is_not_an_error() {
    let dir = temp_dir("stderr");
    let run = |closed: bool, log: &str| {
        let mut child = piped(
            Command::new(BIN)
                .args(["run", &scene("chain_floor").display().to_string()])
                .args(["--t-end", "0.46", "-o", log])
                .current_dir(&dir),
            Stdio::null(),
        );
        if closed {
            drop(child.stdout.take());
            drop(child.stderr.take());
        }
        // Both pipes read at once (or none, closed).
        let out = child.wait_with_output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    // Open: the run warns on standard error (else this test could not fail) and ends well.
    let (code, stderr) = run(false, "open.mcap");
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stderr.contains("t = 0.44"), "{stderr}");
    // Closed: the same exit status and the same log, byte for byte.
    let (code, _) = run(true, "closed.mcap");
    assert_eq!(code, Some(0));
    let open = std::fs::read(dir.join("open.mcap")).unwrap();
    let closed = std::fs::read(dir.join("closed.mcap")).unwrap();
    assert!(open == closed, "the logs differ");
    assert!(ricochet::log::read(dir.join("closed.mcap")).is_ok());

    // `impact`: one bad line; its count goes to standard error, closed here: exit 1.
    let mut child = piped(Command::new(BIN).arg("impact"), Stdio::piped());
    drop(child.stdout.take());
    drop(child.stderr.take());
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().unwrap();
        // A closed stdout may end the command before it reads everything: ignore EPIPE.
        let _ = stdin.write_all(b"not json\n");
    }
    assert_eq!(child.wait().unwrap().code(), Some(1));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Numbers in messages are short and exact: `{}` of a double writes `1e-300` with 300
/// zeros (an `impact` line with `v_n^A = 1e-300` said so in 320 characters).
#[test]
fn numbers_in_messages_are_short_and_exact() {
    use ricochet::model::ModelError;
    let cases = [
        (
            ImpactError::NotApproaching { vn: 1e-300 }.to_string(),
            "the points do not approach: v_n^A = 1e-300 must be negative",
        ),
        (
            ImpactError::NotPositiveDefinite {
                nn: -1e200,
                nt: 0.5,
                tt: 2.0,
                det: -2e200,
            }
            .to_string(),
            "W is not positive semidefinite with m_nn > 0: m_nn = -1e200, m_nt = 0.5, \
             m_tt = 2, Δ = m_nn m_tt − m_nt² = -2e200",
        ),
        (
            ImpactError::RestitutionOutOfRange { e: 1.0000001 }.to_string(),
            "the coefficient of restitution e = 1.0000001 is outside [0, 1]",
        ),
        (
            ModelError::BadMass {
                body: "b".into(),
                mass: 5e-324,
            }
            .to_string(),
            "body `b`: the mass must be positive and finite, got 5e-324 kg",
        ),
    ];
    for (shown, expected) in cases {
        assert_eq!(shown, expected);
    }
}
