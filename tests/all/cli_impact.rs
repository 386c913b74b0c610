//! `ricochet impact`: the JSON Lines contract of `DESIGN.md`.

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

use serde_json::Value;

/// Runs `ricochet impact ARGS` on `input`; returns the output lines and the exit code.
fn run(args: &[&str], input: &str) -> (Vec<Value>, i32) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .arg("impact")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let lines = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    (lines, out.status.code().unwrap())
}

/// W and v^A of the Sect. 5 pendulum, to 17 digits.
const PENDULUM: &str = r#""w": [0.33652009683469625, -0.5071028860035925, 0.8134460152321034], "v_a": [-0.268404028, 0.534348688]"#;

#[test]
fn design_example_round_trip() {
    let (out, code) = run(
        &[],
        &format!("{{{PENDULUM}, \"e\": 0.5, \"mu\": 0.2, \"law\": \"newton\"}}\n"),
    );
    assert_eq!(code, 0);
    let a = &out[0];
    assert_eq!(a["law"], "newton");
    assert_eq!(a["type"], "reverse_sliding");
    assert_eq!(a["case"], 3);
    let f = |k: &str| a[k].as_f64().unwrap();
    let close = |x: f64, y: f64| (x - y).abs() <= 0.5e-4;
    assert!(close(f("alpha"), 1.9908) && close(f("i_n"), 1.0242) && close(f("i_t"), -0.1143));
    assert!(
        close(a["v_s"][0].as_f64().unwrap(), 0.1342)
            && close(a["v_s"][1].as_f64().unwrap(), -0.0780)
    );
    assert!(close(f("delta_e"), -0.0948));
    assert!((f("work_n") + f("work_t") - f("delta_e")).abs() < 1e-15);
    // Extensions: g, h, p, q and the phases (forward sliding, then reverse sliding).
    assert!(f("p") < 0.0 && f("g") > 0.0);
    let phases = a["phases"].as_array().unwrap();
    assert_eq!(phases.len(), 2);
    assert_eq!(
        (phases[0]["type"].as_str(), phases[1]["type"].as_str()),
        (Some("forward_sliding"), Some("reverse_sliding"))
    );
    assert_eq!(phases[1]["i_n"], a["i_n"]);
    assert_eq!(phases[1]["i_t"], a["i_t"]);
}

#[test]
fn law_default_and_per_line_override() {
    let line = |law: &str| format!("{{{PENDULUM}, \"e\": 0.9, \"mu\": 0.5{law}}}\n");
    let input = [
        line(""),
        line(", \"law\": \"kane-levinson\""),
        line(", \"law\": \"poisson\""),
        line(", \"law\": \"stronge\""),
    ]
    .concat();
    let (out, code) = run(&[], &input);
    assert_eq!(code, 0);
    let laws: Vec<_> = out.iter().map(|a| a["law"].as_str().unwrap()).collect();
    assert_eq!(laws, ["newton", "kane-levinson", "poisson", "stronge"]);
    let (out, _) = run(&["--law", "stronge"], &line(""));
    assert_eq!(out[0]["law"], "stronge");
    // Kane–Levinson on Table 2 row 5 (upper half): reverse sliding with an energy gain.
    assert!(
        run(&["--law", "kane-levinson"], &line("")).0[0]["delta_e"]
            .as_f64()
            .unwrap()
            > 0.6
    );
}

#[test]
fn every_kind_of_bad_line_is_an_error_line_and_the_rest_is_processed() {
    let good = format!("{{{PENDULUM}, \"e\": 0.5, \"mu\": 0.2}}");
    let bad = [
        ("not json", "bad input"),
        ("", "bad input"),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, 0], "e": 0.5}"#,
            "missing field `mu`",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, 0], "e": 0.5, "mu": 0.1, "lwa": "newton"}"#,
            "unknown field `lwa`",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, 0], "e": 0.5, "mu": 0.1, "law": "hertz"}"#,
            "unknown variant `hertz`",
        ),
        (
            r#"{"w": [1, 0], "v_a": [-1, 0], "e": 0.5, "mu": 0.1}"#,
            "bad input",
        ),
        (
            r#"{"w": [1, 2, 1], "v_a": [-1, 0], "e": 0.5, "mu": 0.1}"#,
            "not positive semidefinite",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [0, 1], "e": 0.5, "mu": 0.1}"#,
            "do not approach",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [0.5, 1], "e": 0.5, "mu": 0.1}"#,
            "do not approach",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, 0], "e": 1.5, "mu": 0.1}"#,
            "outside [0, 1]",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, 0], "e": 0.5, "mu": -0.1}"#,
            "negative",
        ),
        (
            r#"{"w": [1, 0, 1e400], "v_a": [-1, 0], "e": 0.5, "mu": 0.1}"#,
            "out of range",
        ),
        (
            r#"{"w": [1, 0, 1], "v_a": [-1, NaN], "e": 0.5, "mu": 0.1}"#,
            "bad input",
        ),
    ];
    let mut input = String::new();
    for (line, _) in &bad {
        input.push_str(&good);
        input.push('\n');
        input.push_str(line);
        input.push('\n');
    }
    input.push_str(&good);
    input.push('\n');
    let (out, code) = run(&[], &input);
    assert_eq!(code, 1, "any failed line makes the exit status non-zero");
    assert_eq!(
        out.len(),
        2 * bad.len() + 1,
        "one output line per input line"
    );
    for (k, (line, expected)) in bad.iter().enumerate() {
        let ok = &out[2 * k];
        assert_eq!(ok["type"], "reverse_sliding");
        let err = &out[2 * k + 1];
        let msg = err["error"]
            .as_str()
            .unwrap_or_else(|| panic!("no error for {line:?}: {err}"));
        assert!(msg.contains(expected), "{line:?}: {msg}");
        assert_eq!(err["line"], 2 * k + 2);
    }
    assert_eq!(out.last().unwrap()["type"], "reverse_sliding");
}

#[test]
fn negative_tangential_approach_is_reported_in_the_callers_frame() {
    let (out, _) = run(
        &[],
        "{\"w\": [0.3365, 0.5071, 0.8134], \"v_a\": [-0.2684, -0.5343], \"e\": 0.5, \"mu\": 0.2}\n",
    );
    let (mirror, _) = run(
        &[],
        "{\"w\": [0.3365, -0.5071, 0.8134], \"v_a\": [-0.2684, 0.5343], \"e\": 0.5, \"mu\": 0.2}\n",
    );
    assert_eq!(
        out[0]["i_t"].as_f64().unwrap(),
        -mirror[0]["i_t"].as_f64().unwrap()
    );
    assert_eq!(
        out[0]["v_s"][1].as_f64().unwrap(),
        -mirror[0]["v_s"][1].as_f64().unwrap()
    );
    assert_eq!(out[0]["alpha"], mirror[0]["alpha"]);
}

#[test]
fn answers_each_line_as_it_arrives() {
    // A co-process writes a line and waits for its answer before writing the next.
    let mut child = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .arg("impact")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    for e in [0.2, 0.5, 0.8] {
        writeln!(stdin, "{{{PENDULUM}, \"e\": {e}, \"mu\": 0.2}}").unwrap();
        stdin.flush().unwrap();
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        let v: Value = serde_json::from_str(&line).unwrap();
        assert!((v["v_s"][0].as_f64().unwrap() - e * 0.268404028).abs() < 1e-12);
    }
    drop(stdin);
    assert!(child.wait().unwrap().success());
}
