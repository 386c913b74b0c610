//! `ricochet run --summary`, `inspect --json`, `compare`, `golden record|check` and the
//! drift budget, run as a user runs them: the built binary in a fresh temporary folder.
//!
//! Checked here:
//! - `run --summary` and `inspect --json` of its log write the same document;
//! - `compare` of a log with itself: exit 0, every difference zero (`--json`); logs
//!   against summaries and summaries against logs the same; a run at another `e`: exit 1
//!   naming impact #0 and `v_s.n`; a summary with one impact less: exit 1 naming it;
//!   missing, corrupted, foreign and future files and bad tolerances: exit 2 and a
//!   message naming the file;
//! - `golden record` then `golden check` on an unchanged tree: exit 0; a one-line change
//!   of a mass in one scene: exit 1 naming that scene, the other ok; `--update`, then
//!   exit 0; a coefficient changed: exit 1 naming impact #0 and `v_s.n`, the table with
//!   `--verbose`, the same exit with stdout closed; a scene gone: exit 2;
//! - drift budgets: `--max-drift` and `[run] max_drift` met (exit 0) and broken (exit 1,
//!   by how much, with a finished log); `golden check` of a scene that breaks its budget.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use serde_json::Value;

use crate::common::cli;
use cli::{BIN, TempDir};

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn scene_path(name: &str) -> String {
    repo(&format!("scenes/{name}.toml")).display().to_string()
}

/// `ricochet <args>` in `dir`; its exit code, stdout and stderr.
fn ricochet(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out: Output = cli::ricochet(dir, args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// Expects exit `code`; returns stdout and stderr.
fn expect(dir: &Path, args: &[&str], code: i32) -> (String, String) {
    let (got, stdout, stderr) = ricochet(dir, args);
    assert_eq!(got, code, "ricochet {args:?}\n{stdout}\n{stderr}");
    (stdout, stderr)
}

#[test]
fn run_summary_and_inspect_json_are_the_same_document() {
    let dir = TempDir::new("summary");
    let kane = scene_path("kane_double_pendulum");
    expect(
        dir.path(),
        &["run", &kane, "-o", "k.mcap", "--summary", "k.json", "-q"],
        0,
    );
    let (inspected, _) = expect(dir.path(), &["inspect", "k.mcap", "--json"], 0);
    let written = std::fs::read_to_string(dir.join("k.json")).unwrap();
    assert_eq!(inspected, written);
    let doc: Value = serde_json::from_str(&written).unwrap();
    assert_eq!(doc["format"], "ricochet.summary");
    assert_eq!(doc["version"], 1);
    assert_eq!(doc["scene"]["name"], "kane_double_pendulum");
    assert_eq!(doc["coordinates"], serde_json::json!(["rodA.q", "rodB.q"]));
    // The paper's impact, first row of the ledger (Table 2 row 1, printed digits).
    let first = &doc["impacts"][0];
    assert_eq!(
        (first["type"].as_str(), first["case"].as_u64()),
        (Some("reverse_sliding"), Some(3))
    );
    assert!((first["i_n"].as_f64().unwrap() - 1.0242).abs() < 5e-5);
    assert_eq!(doc["audit"]["stop_reason"], "t_end: reached the end time");
    // One impact per line: the ledger is as many lines as impacts.
    let n = doc["impacts"].as_array().unwrap().len();
    assert_eq!(
        written
            .lines()
            .filter(|l| l.trim_start().starts_with("{\"t\":"))
            .count(),
        n + doc["checkpoints"].as_array().unwrap().len()
    );
    // A summary that cannot be written fails before the run, leaving no log.
    let (_, err) = expect(
        dir.path(),
        &["run", &kane, "-o", "no.mcap", "--summary", "missing/k.json"],
        1,
    );
    assert!(
        err.contains("cannot create the summary missing/k.json"),
        "{err}"
    );
    assert!(!dir.join("no.mcap").exists());
    // Fewer checkpoints on request.
    let (two, _) = expect(
        dir.path(),
        &["inspect", "k.mcap", "--json", "--checkpoints", "2"],
        0,
    );
    let two: Value = serde_json::from_str(&two).unwrap();
    let times: Vec<f64> = (two["checkpoints"].as_array().unwrap().iter())
        .map(|c| c["t"].as_f64().unwrap())
        .collect();
    // t = 0 (three samples: the start and the two of the impact at t = 0), 1 s and 2 s.
    assert_eq!(times, [0.0, 0.0, 0.0, 1.0, 2.0]);
}

#[test]
fn compare_exits_0_within_1_beyond_2_on_errors() {
    let dir = TempDir::new("compare");
    let d = dir.path();
    let kane = scene_path("kane_double_pendulum");
    expect(
        d,
        &["run", &kane, "-o", "a.mcap", "--summary", "a.json", "-q"],
        0,
    );
    expect(d, &["run", &kane, "-o", "e06.mcap", "--e", "0.6", "-q"], 0);

    // A log with itself: every difference exactly zero.
    let (out, _) = expect(d, &["compare", "a.mcap", "a.mcap", "--json"], 0);
    let c: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (c["format"].as_str(), c["within"].as_bool()),
        (Some("ricochet.comparison"), Some(true))
    );
    for q in c["quantities"].as_array().unwrap() {
        assert_eq!(
            (q["max_abs"].as_f64(), q["beyond"].as_u64()),
            (Some(0.0), Some(0)),
            "{q}"
        );
    }
    // Logs against summaries, summaries against logs: the same run.
    for (a, b) in [
        ("a.mcap", "a.json"),
        ("a.json", "a.mcap"),
        ("a.json", "a.json"),
    ] {
        let (out, _) = expect(d, &["compare", a, b], 0);
        assert!(out.contains("within the tolerances"), "{out}");
    }
    // Another e: the first impact, and the field.
    let (out, _) = expect(d, &["compare", "a.mcap", "e06.mcap"], 1);
    assert!(
        out.contains("first difference: impact #0 rodB/floor at t = 0 s: v_s.n: A 0.134202"),
        "{out}"
    );
    assert!(out.contains("BEYOND the tolerances"), "{out}");
    assert!(
        out.contains("note: the settings differ: material_overrides.e null and 0.6"),
        "{out}"
    );
    // 11 impacts against 14: the first unmatched one is named.
    assert!(out.contains("(none in A)"), "{out}");

    // One impact less (the last row deleted from the summary): exit 1, named.
    let mut doc: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("a.json")).unwrap()).unwrap();
    let last = doc["impacts"].as_array_mut().unwrap().pop().unwrap();
    std::fs::write(dir.join("less.json"), serde_json::to_string(&doc).unwrap()).unwrap();
    let (out, _) = expect(d, &["compare", "a.json", "less.json"], 1);
    let index = last["index"].as_u64().unwrap();
    assert!(
        out.contains(&format!("impact #{index} (none in B)")),
        "{out}"
    );

    // Loose enough tolerances take in the change of e... but never the count.
    let (out, _) = expect(
        d,
        &[
            "compare",
            "a.json",
            "less.json",
            "--rtol",
            "1",
            "--atol",
            "1e9",
            "--time-tol",
            "1e9",
        ],
        1,
    );
    assert!(out.contains("impacts.count"), "{out}");

    // Errors: exit 2 and a message naming the file.
    std::fs::write(dir.join("garbage.mcap"), b"\x89MCAP0\r\n not really").unwrap();
    std::fs::write(
        dir.join("text.json"),
        "{\"format\": \"ricochet.summary\", \"version\": 1,",
    )
    .unwrap();
    std::fs::write(dir.join("other.json"), "{\"format\": \"something.else\"}").unwrap();
    doc["version"] = Value::from(99);
    std::fs::write(
        dir.join("future.json"),
        serde_json::to_string(&doc).unwrap(),
    )
    .unwrap();
    doc["version"] = Value::from(1);
    doc["impacts"][0]["i_n"] = Value::from("big");
    std::fs::write(
        dir.join("badfield.json"),
        serde_json::to_string(&doc).unwrap(),
    )
    .unwrap();
    for (file, words) in [
        (
            "missing.json",
            &["cannot read missing.json", "No such file"][..],
        ),
        ("garbage.mcap", &["garbage.mcap", "cannot read the log"]),
        (
            "text.json",
            &[
                "text.json",
                "neither a ricochet log",
                "EOF while parsing",
                "line 1",
            ],
        ),
        (
            "other.json",
            &["other.json", "\"something.else\", not \"ricochet.summary\""],
        ),
        (
            "future.json",
            &["future.json", "version 99 is not supported"],
        ),
        (
            "badfield.json",
            &[
                "badfield.json",
                "not a valid ricochet.summary document",
                "invalid type: string \"big\"",
            ],
        ),
    ] {
        let (_, err) = expect(d, &["compare", "a.json", file], 2);
        for w in words {
            assert!(err.contains(w), "{file}: {w}: {err}");
        }
    }
    let (_, err) = expect(d, &["compare", "a.json", "a.json", "--rtol=-1"], 2);
    assert!(
        err.contains("`rtol` must be a finite number ≥ 0, not -1"),
        "{err}"
    );
}

/// A copy of a bundled scene in `dir`, under the name `file`.
fn copy_scene(dir: &Path, name: &str, file: &str) -> PathBuf {
    let to = dir.join(file);
    std::fs::copy(repo(&format!("scenes/{name}.toml")), &to).unwrap();
    to
}

/// Replaces the one line of the file at `path` that starts with `start` by `line`.
fn edit_line(path: &Path, start: &str, line: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with(start)).count(),
        1,
        "{start}"
    );
    let edited: Vec<&str> = (text.lines())
        .map(|l| if l.starts_with(start) { line } else { l })
        .collect();
    std::fs::write(path, edited.join("\n") + "\n").unwrap();
}

#[test]
fn golden_record_check_update() {
    let dir = TempDir::new("golden");
    let d = dir.path();
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    let ball = copy_scene(d, "bouncing_ball", "scenes/ball.toml");
    copy_scene(d, "pendulum_wall", "scenes/wall.toml");
    let (out, _) = expect(
        d,
        &[
            "golden",
            "record",
            "scenes/ball.toml",
            "scenes/wall.toml",
            "--dir",
            "golden",
        ],
        0,
    );
    assert!(
        out.contains("recorded scenes/ball.toml → golden/ball.golden.json: 47 impacts"),
        "{out}"
    );
    let file = std::fs::read_to_string(dir.join("golden/ball.golden.json")).unwrap();
    let g: Value = serde_json::from_str(&file).unwrap();
    assert_eq!(g["scene"], "../scenes/ball.toml");
    assert_eq!(
        g["tolerances"],
        serde_json::json!({"rtol": 1e-9, "atol": 1e-12, "time_tol": 1e-9})
    );

    // Unchanged tree: exit 0, one line per scene, from any folder.
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden"], 0);
    assert!(
        out.contains("ok       bouncing_ball (ball.golden.json): 47 impacts"),
        "{out}"
    );
    assert!(
        out.contains("ok       pendulum_wall (wall.golden.json)"),
        "{out}"
    );
    let elsewhere = dir.join("scenes");
    expect(&elsewhere, &["golden", "check", "--dir", "../golden"], 0);

    // A one-line change: the ball's mass. Its energies move; the motion of a ball does not
    // depend on its mass, the energies do.
    edit_line(&ball, "mass =", "mass = 0.2");
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden"], 1);
    assert!(
        out.contains(
            "MOVED    bouncing_ball (ball.golden.json): sample at t = 0 s: energy.potential"
        ),
        "{out}"
    );
    assert!(
        out.contains("(the scene file changed since the recording)"),
        "{out}"
    );
    assert!(out.contains("ok       pendulum_wall"), "{out}");
    assert!(
        out.contains("2 golden files in golden: 1 ok, 1 moved"),
        "{out}"
    );

    // --update rewrites it, keeping its tolerances; then all is well.
    let loose = file.replace("\"rtol\": 1e-9", "\"rtol\": 1e-8");
    std::fs::write(dir.join("golden/ball.golden.json"), loose).unwrap();
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden", "--update"], 0);
    assert!(out.contains("UPDATED  bouncing_ball"), "{out}");
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden"], 0);
    assert!(out.contains("2 ok, 0 moved"), "{out}");
    let updated: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("golden/ball.golden.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(updated["tolerances"]["rtol"], 1e-8);
    let e0 = updated["summary"]["audit"]["energy_initial"]
        .as_f64()
        .unwrap();
    assert!((e0 - 0.2 * 9.81 * 1.1).abs() < 1e-15, "{e0}");

    // A coefficient: the wall's restitution, in the file's own words.
    let wall = dir.join("scenes/wall.toml");
    edit_line(&wall, "e = ", "e = 0.69");
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden"], 1);
    assert!(
        out.contains("MOVED    pendulum_wall (wall.golden.json): impact #0 bob/wall"),
        "{out}"
    );
    assert!(out.contains("v_s.n"), "{out}");

    let (out, _) = expect(d, &["golden", "check", "--dir", "golden", "--verbose"], 1);
    assert!(
        out.contains("first beyond the tolerances") && out.contains("B  pendulum_wall now"),
        "{out}"
    );
    // A reader that stops reading (`| head`) does not change the verdict.
    let mut child = Command::new(BIN)
        .args(["golden", "check", "--dir", "golden", "--verbose"])
        .current_dir(d)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // A scene gone, a broken golden file: exit 2, the others still checked.
    std::fs::remove_file(&wall).unwrap();
    std::fs::write(dir.join("golden/bad.golden.json"), "{}").unwrap();
    let (out, _) = expect(d, &["golden", "check", "--dir", "golden"], 2);
    assert!(
        out.contains("ERROR    wall.golden.json: ") && out.contains("wall.toml"),
        "{out}"
    );
    assert!(
        out.contains("ERROR    bad.golden.json: ") && out.contains("`format` is \"\""),
        "{out}"
    );
    assert!(out.contains("ok       bouncing_ball"), "{out}");

    // Bad use: no golden files, two scenes of one name, bad overrides.
    let (_, err) = expect(d, &["golden", "check", "--dir", "scenes"], 2);
    assert!(err.contains("no golden files"), "{err}");
    std::fs::create_dir_all(dir.join("other")).unwrap();
    copy_scene(d, "bouncing_ball", "other/ball.toml");
    let (_, err) = expect(
        d,
        &[
            "golden",
            "record",
            "scenes/ball.toml",
            "other/ball.toml",
            "--dir",
            "g2",
        ],
        2,
    );
    assert!(
        err.contains("would both record to g2/ball.golden.json"),
        "{err}"
    );
    let (_, err) = expect(
        d,
        &[
            "golden",
            "record",
            "scenes/ball.toml",
            "--dir",
            "g2",
            "--e",
            "2",
        ],
        2,
    );
    assert!(err.contains("--e must lie in [0, 1], not 2"), "{err}");
    let (_, err) = expect(
        d,
        &[
            "golden",
            "record",
            "scenes/ball.toml",
            "--dir",
            "g2",
            "--cmp-rtol",
            "nan",
        ],
        2,
    );
    assert!(
        err.contains("`cmp_rtol` must be a finite number ≥ 0, not NaN"),
        "{err}"
    );
}

#[test]
fn a_drift_budget_met_and_broken() {
    let dir = TempDir::new("drift");
    let d = dir.path();
    let kane = scene_path("kane_double_pendulum");
    // The drift of this run: 3.06e-10 J of E_ref = 114.8 J, 2.7e-12 relative.
    let (out, _) = expect(
        d,
        &[
            "run",
            &kane,
            "-o",
            "ok.mcap",
            "--max-drift",
            "1e-9",
            "--summary",
            "ok.json",
        ],
        0,
    );
    assert!(out.contains("drift budget: integration drift"), "{out}");
    assert!(out.contains("within the budget max_drift = 1e-9"), "{out}");
    let doc: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ok.json")).unwrap()).unwrap();
    let drift = &doc["drift"];
    let relative = drift["relative"].as_f64().unwrap();
    assert_eq!(
        relative,
        drift["integration_drift"].as_f64().unwrap().abs()
            / drift["energy_scale"].as_f64().unwrap()
    );
    assert!(relative > 1e-13 && relative < 1e-10, "{relative}");

    // Broken: exit 1 after a finished log, saying by how much.
    let (out, err) = expect(
        d,
        &["run", &kane, "-o", "bad.mcap", "--max-drift", "1e-13"],
        1,
    );
    assert!(out.contains("BEYOND the budget max_drift = 1e-13"), "{out}");
    assert!(
        err.contains("error: the energy-drift budget is broken"),
        "{err}"
    );
    let times = relative / 1e-13;
    assert!(
        err.contains(&format!("({times:.3} times the budget")),
        "{err}"
    );
    let (log, _) = expect(d, &["inspect", "bad.mcap"], 0);
    assert!(
        log.contains("t_end: reached the end time") && log.contains("max_drift"),
        "{log}"
    );

    // In the scene: `[run] max_drift`, and `golden check` of it.
    let text = std::fs::read_to_string(&kane).unwrap();
    let with_budget = |b: &str| text.replacen("[run]\n", &format!("[run]\nmax_drift = {b}\n"), 1);
    std::fs::write(dir.join("tight.toml"), with_budget("1e-13")).unwrap();
    std::fs::write(dir.join("loose.toml"), with_budget("1e-9")).unwrap();
    expect(d, &["run", "tight.toml", "-q"], 1);
    expect(d, &["run", "loose.toml", "-q"], 0);
    let (out, _) = expect(
        d,
        &["golden", "record", "tight.toml", "loose.toml", "--dir", "g"],
        1,
    );
    assert!(out.contains("DRIFT    tight.toml"), "{out}");
    let (out, _) = expect(d, &["golden", "check", "--dir", "g"], 1);
    assert!(
        out.contains("ok       kane_double_pendulum (tight.golden.json)"),
        "{out}"
    );
    assert!(
        out.contains("DRIFT    kane_double_pendulum (tight.golden.json): integration drift"),
        "{out}"
    );
    assert!(out.contains("1 beyond their drift budget"), "{out}");
    // The command line's budget overrides the scene's.
    expect(d, &["run", "tight.toml", "-q", "--max-drift", "1e-9"], 0);
    let (_, err) = expect(d, &["run", "tight.toml", "-q", "--max-drift", "0"], 1);
    assert!(
        err.contains("--max-drift must be a positive number, not 0"),
        "{err}"
    );
}
