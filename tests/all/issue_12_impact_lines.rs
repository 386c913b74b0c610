//! Issue 12, item 5: `ricochet impact` stopped at the first line of invalid UTF-8 (one
//! answer for three lines), 2,077 of 120,000 answers carried `null` numbers without
//! counting as failed lines, and valid lines were refused.
//!
//! The contract (`DESIGN.md`): one JSON object per input line, in order; an error line
//! `{"error": …, "line": k}` for a line that cannot be solved, and the rest still
//! processed; the exit status non-zero iff a line failed. Checked here on the
//! reproducers, then on batches of generated lines through the binary: valid problems over
//! the whole range of doubles (W and v^A from 1e-300 to 1e300, singular W), the same
//! mutated (characters deleted or inserted, numbers replaced by extreme or non-JSON
//! tokens, keys dropped, added or doubled, wrong types), garbage bytes, invalid UTF-8,
//! carriage returns, empty lines. For every line:
//! - exactly one output line, a JSON object without `null` anywhere;
//! - an answer iff the line is a valid request (parsed here by a request type of this
//!   file) whose problem `impact::solve` solves with finite numbers, else an error line
//!   naming its line number, never "incoherent" (the laws' safety net against their own
//!   bugs); for a solved line, the answer is the library's, bit for bit,
//!   and it satisfies Eqs. (22)–(23), Coulomb's cone, `I_n > 0`, `v_n^S ≥ 0`, Eq. (29) and
//!   Newton's `v_n^S = −e v_n^A`;
//! - the exit status is 1 iff some line failed, and standard error counts them.
//!
//! The default suite runs about 400 lines; the `#[ignore]`d test 10,000
//! (`cargo test --release --test all issue_12_impact_lines:: -- --ignored --nocapture`).

use std::io::Write;
use std::process::{Command, Stdio};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law, Outcome};
use serde::Deserialize;
use serde_json::Value;

/// Runs `ricochet impact` on `input`; returns stdout, stderr and the exit code.
fn run(input: &[u8]) -> (String, String, i32) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .arg("impact")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    // Write from another thread: the answers fill the pipe while we write.
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    (
        String::from_utf8(out.stdout).expect("the output is UTF-8"),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        out.status.code().unwrap(),
    )
}

/// A request as `DESIGN.md` states it, parsed independently of the binary.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    w: [f64; 3],
    v_a: [f64; 2],
    e: f64,
    mu: f64,
    law: Option<Law>,
}

/// What the line should give: the library's outcome, or `None` for an error line.
fn expected(line: &[u8]) -> Option<(Law, ImpactProblem, Outcome)> {
    let text = std::str::from_utf8(line).ok()?;
    let req: Request = serde_json::from_str(text).ok()?;
    let law = req.law.unwrap_or(Law::Newton);
    let pb = ImpactProblem::new(
        ImpactMatrix::new(req.w[0], req.w[1], req.w[2]),
        ContactVelocity::new(req.v_a[0], req.v_a[1]),
        req.e,
        req.mu,
    );
    let out = impact::solve(law, &pb).ok()?;
    out.coefficients
        .alpha()
        .is_finite()
        .then_some((law, pb, out))
}

fn has_null(v: &Value) -> bool {
    match v {
        Value::Null => true,
        Value::Array(a) => a.iter().any(has_null),
        Value::Object(o) => o.values().any(has_null),
        _ => false,
    }
}

/// The answer `a` against the library's outcome (bit for bit) and the defining equations.
fn check_answer(a: &Value, law: Law, pb: &ImpactProblem, out: &Outcome) -> Result<(), String> {
    let f = |x: &Value| x.as_f64().ok_or(format!("{x} is not a number"));
    let (i_n, i_t) = (f(&a["i_n"])?, f(&a["i_t"])?);
    let (vs_n, vs_t) = (f(&a["v_s"][0])?, f(&a["v_s"][1])?);
    let (de, wn, wt) = (f(&a["delta_e"])?, f(&a["work_n"])?, f(&a["work_t"])?);
    let same = [
        (i_n, out.impulse.n),
        (i_t, out.impulse.t),
        (vs_n, out.v_s.n),
        (vs_t, out.v_s.t),
        (de, out.delta_e),
        (wn, out.work_n),
        (wt, out.work_t),
        (f(&a["alpha"])?, out.coefficients.alpha()),
    ];
    if same.iter().any(|(x, y)| x.to_bits() != y.to_bits()) || a["law"] != law.name() {
        return Err(format!("not the library's answer {out:?}"));
    }
    // Eqs. (22)–(23), at the scale of each term. A number in the subnormal range (below
    // 2.2e-308) is exact to a few units of 2^-1074 only: `tiny` bounds what that does to
    // a term.
    let tiny = 4.0 * 2f64.powi(-1074);
    let (w, v) = (&pb.w, pb.v_a);
    let residuals = [
        (
            vs_n - v.n - (w.nn * i_n + w.nt * i_t),
            [vs_n, v.n, w.nn * i_n, w.nt * i_t],
            w.nn.abs() + w.nt.abs(),
        ),
        (
            vs_t - v.t - (w.nt * i_n + w.tt * i_t),
            [vs_t, v.t, w.nt * i_n, w.tt * i_t],
            w.nt.abs() + w.tt.abs(),
        ),
    ];
    for (r, terms, w_row) in residuals {
        let scale: f64 = terms.iter().map(|x| x.abs()).sum();
        if r.abs() > 1e-9 * scale + tiny * (1.0 + w_row) {
            return Err(format!("Eqs. (22)–(23): residual {r:e} at scale {scale:e}"));
        }
    }
    let speed = v.n.abs() + v.t.abs() + vs_n.abs() + vs_t.abs();
    if !(i_n > 0.0
        && vs_n >= -1e-9 * speed - tiny
        && i_t.abs() <= pb.mu * i_n * (1.0 + 1e-9) + tiny)
    {
        return Err(format!(
            "I_n = {i_n}, v_n^S = {vs_n}, |I_t| = {} > μ I_n",
            i_t.abs()
        ));
    }
    // Eq. (29) and its split.
    let eq29 = 0.5 * i_n * (vs_n + v.n) + 0.5 * i_t * (vs_t + v.t);
    let etol = 1e-9 * 0.5 * (i_n.abs() + i_t.abs()) * speed + tiny * (1.0 + speed);
    if (de - eq29).abs() > etol || (wn + wt - de).abs() > etol {
        return Err(format!(
            "ΔE = {de} against Eq. (29) {eq29}, works {wn} + {wt}"
        ));
    }
    if matches!(law, Law::Newton | Law::KaneLevinson)
        && (vs_n + pb.e * v.n).abs() > 1e-9 * speed + tiny
    {
        return Err(format!("v_n^S = {vs_n} ≠ −e v_n^A"));
    }
    Ok(())
}

/// Counts of what the lines gave.
#[derive(Debug, Default)]
struct Tally {
    lines: usize,
    answers: usize,
    errors: usize,
    valid_requests_refused: usize,
    /// The error lines by the start of their message.
    kinds: std::collections::BTreeMap<String, usize>,
}

/// Runs the lines (joined by `\n`, with a final `\n` when `final_newline`) and checks
/// every output line.
fn check_batch(lines: &[Vec<u8>], final_newline: bool, tally: &mut Tally) -> Result<(), String> {
    let mut input = lines.join(&b'\n');
    if final_newline {
        input.push(b'\n');
    }
    let (stdout, stderr, code) = run(&input);
    let out: Vec<&str> = stdout.lines().collect();
    if out.len() != lines.len() {
        return Err(format!("{} lines gave {} answers", lines.len(), out.len()));
    }
    let mut failed = 0;
    for (k, (line, answer)) in lines.iter().zip(&out).enumerate() {
        let what = || format!("line {} {:?}", k + 1, String::from_utf8_lossy(line));
        let a: Value =
            serde_json::from_str(answer).map_err(|e| format!("{}: {answer}: {e}", what()))?;
        if has_null(&a) || !a.is_object() {
            return Err(format!("{}: {answer}", what()));
        }
        let error = a.get("error");
        match (expected(line), error) {
            (Some((law, pb, outcome)), None) => {
                check_answer(&a, law, &pb, &outcome).map_err(|e| format!("{}: {e}", what()))?;
                tally.answers += 1;
            }
            (None, Some(message)) => {
                let message = message.as_str().unwrap_or_default();
                if message.is_empty() || a["line"] != k + 1 {
                    return Err(format!("{}: {answer}", what()));
                }
                // An error for a request the library solves is a refused valid line.
                failed += 1;
                tally.errors += 1;
                // "Incoherent" is a law's safety net against its own bugs: never for data.
                if message.starts_with("incoherent") {
                    return Err(format!("{}: {message}", what()));
                }
                let kind: String = message.chars().take(40).collect();
                *tally.kinds.entry(kind).or_default() += 1;
            }
            (Some(_), Some(message)) => {
                tally.valid_requests_refused += 1;
                return Err(format!("{}: refused: {message}", what()));
            }
            (None, None) => return Err(format!("{}: answered: {answer}", what())),
        }
    }
    tally.lines += lines.len();
    let want = if failed > 0 { 1 } else { 0 };
    if code != want {
        return Err(format!("exit status {code} with {failed} failed lines"));
    }
    if failed > 0 && !stderr.contains(&format!("{failed} line(s) failed")) {
        return Err(format!("stderr: {stderr}"));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Generators

/// A positive semidefinite W of order one (rank 1 in one case of six).
fn unit_w() -> impl Strategy<Value = [f64; 3]> {
    (
        0.0..std::f64::consts::PI,
        prop_oneof![1 => Just(0.0), 5 => -6.0..0.0f64],
    )
        .prop_map(|(th, k)| {
            let (l1, l2) = (1.0, if k == 0.0 { 0.0 } else { 10f64.powf(k) });
            let (c, s) = (th.cos(), th.sin());
            [
                c * c * l1 + s * s * l2,
                c * s * (l1 - l2),
                s * s * l1 + c * c * l2,
            ]
        })
}

/// A valid request: W and v^A of order one times scales anywhere in the range.
fn valid_request() -> impl Strategy<Value = String> {
    let scale = prop_oneof![
        3 => -3.0..3.0f64,
        1 => -300.0..300.0f64,
        1 => Just(-307.0),
        1 => Just(307.0),
    ];
    let law = prop_oneof![
        Just(None),
        Just(Some("newton")),
        Just(Some("kane-levinson")),
        Just(Some("poisson")),
        Just(Some("stronge")),
    ];
    (
        unit_w(),
        scale.clone(),
        scale,
        (-1.0..-1e-3f64, -2.0..2.0f64),
        prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64],
        prop_oneof![Just(0.0), 0.0..3.0f64],
        law,
    )
        .prop_map(|(w, sw, sv, (vn, vt), e, mu, law)| {
            let (sw, sv) = (10f64.powf(sw), 10f64.powf(sv));
            let w = [w[0] * sw, w[1] * sw, w[2] * sw];
            let v = [vn * sv, vt * sv];
            let law = law.map(|l| format!(", \"law\": \"{l}\"")).unwrap_or_default();
            format!(
                "{{\"w\": [{:?}, {:?}, {:?}], \"v_a\": [{:?}, {:?}], \"e\": {e:?}, \"mu\": {mu:?}{law}}}",
                w[0], w[1], w[2], v[0], v[1]
            )
        })
}

/// Tokens that replace a number of a request.
const TOKENS: &[&str] = &[
    "1e999",
    "-1e999",
    "NaN",
    "Infinity",
    "-Infinity",
    "null",
    "true",
    "\"1\"",
    "[]",
    "{}",
    "-0",
    "0",
    "-0.0",
    "5e-324",
    "-5e-324",
    "1.7976931348623157e308",
    "-1.7976931348623157e308",
    "2.2250738585072014e-308",
    "1e-400",
    "1e308",
    "-1e-300",
    "0x10",
    "01",
    "1.",
    ".5",
    "+1",
    "1e",
    "--1",
    "18446744073709551616",
    "1e3000000000",
];

/// A damage done to a valid request.
#[derive(Clone, Debug)]
enum Mutation {
    /// A number replaced by a token.
    Token(prop::sample::Index, &'static str),
    /// Bytes deleted.
    Delete(prop::sample::Index, usize),
    /// Bytes inserted (any byte but a newline: invalid UTF-8 too).
    Insert(prop::sample::Index, Vec<u8>),
    /// A text replaced: a key dropped, doubled, renamed or added; the law misspelt; a
    /// wrong type.
    Replace(&'static str, &'static str),
}

impl Mutation {
    fn apply(&self, s: &str) -> Vec<u8> {
        let b = s.as_bytes();
        match self {
            Mutation::Token(i, token) => {
                let starts: Vec<usize> = (s.char_indices())
                    .filter(|&(k, c)| {
                        let after = |p: char| p.is_ascii_alphanumeric() || ".-+".contains(p);
                        (c.is_ascii_digit() || c == '-') && !s[..k].ends_with(after)
                    })
                    .map(|(k, _)| k)
                    .collect();
                if starts.is_empty() {
                    return b.to_vec();
                }
                let at = starts[i.index(starts.len())];
                let end = s[at..]
                    .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
                    .map_or(s.len(), |n| at + n);
                format!("{}{token}{}", &s[..at], &s[end..]).into_bytes()
            }
            Mutation::Delete(i, n) => {
                let at = i.index(b.len());
                [&b[..at], &b[(at + n).min(b.len())..]].concat()
            }
            Mutation::Insert(i, bytes) => {
                let at = i.index(b.len() + 1);
                let bytes: Vec<u8> = (bytes.iter())
                    .map(|&x| if x == b'\n' { 0xC3 } else { x })
                    .collect();
                [&b[..at], &bytes[..], &b[at..]].concat()
            }
            Mutation::Replace(from, to) => s.replacen(from, to, 1).into_bytes(),
        }
    }
}

fn mutated_request() -> impl Strategy<Value = Vec<u8>> {
    let index = any::<prop::sample::Index>;
    let mutation = prop_oneof![
        (index(), prop::sample::select(TOKENS)).prop_map(|(i, t)| Mutation::Token(i, t)),
        (index(), 1usize..8).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (index(), prop::collection::vec(any::<u8>(), 1..6))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        prop::sample::select(vec![
            ("\"mu\": ", "\"mu\": 0.1, \"mu\": "),
            ("\"e\": ", "\"E\": "),
            ("\"w\": [", "\"w\": [1, "),
            ("\"w\": [", "\"w\": [["),
            ("\"v_a\": [", "\"v_a\": {\"n\": "),
            ("{", "{\"extra\": 1, "),
            ("{", "[{"),
            ("\"law\": \"", "\"law\": \"NEWTON"),
            ("\"e\": ", "\"e\": \"0.5\", \"x\": "),
            ("}", ", \"law\": null}"),
            ("}", "} {}"),
        ])
        .prop_map(|(from, to)| Mutation::Replace(from, to)),
    ];
    (valid_request(), mutation).prop_map(|(s, m)| m.apply(&s))
}

/// Bytes that are no request.
fn garbage() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..64),
        Just(vec![]),
        Just(b"\r".to_vec()),
        Just(b"{}".to_vec()),
        Just(vec![0xFF, 0xFE, b'{']),
        Just("{\"w\": [1, 0, 1], \"v_a\": [-1, 0.5], \"e\": 0.5, \"mu\": 0.2, \"law\": \"new\u{FFFD}ton\"}".as_bytes().to_vec()),
        Just(b"[".repeat(200)),
    ]
    .prop_map(|b| b.into_iter().map(|x| if x == b'\n' { b' ' } else { x }).collect())
}

fn line() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        4 => valid_request().prop_map(String::into_bytes),
        1 => valid_request().prop_map(|s| format!("{s}\r").into_bytes()),
        4 => mutated_request(),
        1 => garbage(),
    ]
}

fn run_batches(cases: u32) {
    let mut config = Config::with_cases(cases);
    config.failure_persistence = None;
    let rng = TestRng::deterministic_rng(RngAlgorithm::ChaCha);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let tally = std::cell::RefCell::new(Tally::default());
    let batch = (prop::collection::vec(line(), 1..40), any::<bool>());
    runner
        .run(&batch, |(lines, final_newline)| {
            // A batch without a final newline must not end with an empty line (there is
            // no such line to answer).
            let final_newline = final_newline || lines.last().is_some_and(Vec::is_empty);
            check_batch(&lines, final_newline, &mut tally.borrow_mut()).map_err(TestCaseError::fail)
        })
        .unwrap();
    println!("{:#?}", tally.borrow());
}

#[test]
fn generated_lines_get_one_answer_each() {
    run_batches(20);
}

#[test]
#[ignore = "10,000 lines: run with --ignored"]
fn generated_lines_get_one_answer_each_10k() {
    run_batches(520);
}

// ---------------------------------------------------------------------------------------
// The reproducers

/// `impact_invalid_utf8.jsonl`: three lines, the second with a byte of invalid UTF-8 in
/// its law's name. One answer came out, then "stream did not contain valid UTF-8".
#[test]
fn a_line_of_invalid_utf8_is_an_error_line_and_the_rest_is_answered() {
    let good = r#"{"w": [1.0, 0.0, 1.0], "v_a": [-1.0, 0.5], "e": 0.5, "mu": 0.2}"#;
    let mut input = format!("{good}\n").into_bytes();
    input.extend_from_slice(
        br#"{"w": [1.0, 0.0, 1.0], "v_a": [-1.0, 0.5], "e": 0.5, "mu": 0.2, "law": "new"#,
    );
    input.push(0xFF);
    input.extend_from_slice(b"ton\"}\n");
    input.extend_from_slice(format!("{good}\n").as_bytes());
    let (stdout, stderr, code) = run(&input);
    let out: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(out.len(), 3, "{stdout}");
    assert_eq!(out[0]["type"], "forward_sliding");
    assert!(
        out[1]["error"]
            .as_str()
            .unwrap()
            .contains("not valid UTF-8"),
        "{}",
        out[1]
    );
    assert_eq!(out[1]["line"], 2);
    assert_eq!(out[2], out[0]);
    assert_eq!(code, 1);
    assert!(stderr.contains("1 line(s) failed"), "{stderr}");
}

/// `impact_null_alpha.jsonl`: `α = v_t^A/|v_n^A|` overflows (`v_n^A = −1e-320`), and the
/// impulse of W = 1e-300 at 1e10 m/s (1.5e310 N·s) is beyond the doubles: the answers
/// carried `null` and did not count as failed. Both are error lines now.
#[test]
fn answers_that_doubles_cannot_hold_are_error_lines() {
    let input = concat!(
        r#"{"w":[1,0,1],"v_a":[-1e-320,1.0],"e":0.5,"mu":0.2}"#,
        "\n",
        r#"{"w":[1e-300,0,1e-300],"v_a":[-1e10,1e10],"e":0.5,"mu":0.2}"#,
        "\n",
        r#"{"w":[1,0,1],"v_a":[-1e-300,1.0],"e":0.5,"mu":0.2}"#,
        "\n",
    );
    let (stdout, stderr, code) = run(input.as_bytes());
    assert!(!stdout.contains("null"), "{stdout}");
    let out: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(out.len(), 3);
    assert!(
        out[0]["error"].as_str().unwrap().contains("α"),
        "{}",
        out[0]
    );
    assert!(
        out[1]["error"].as_str().unwrap().contains("I_n ≈ 1.5e310"),
        "{}",
        out[1]
    );
    // α = 1e300 is a double: answered.
    assert_eq!(out[2]["alpha"].as_f64(), Some(1.0 / 1e-300));
    assert_eq!(code, 1);
    assert!(stderr.contains("2 line(s) failed"), "{stderr}");
}

/// A line of 2 MiB is an error line; the next is answered (the line is not kept whole).
#[test]
fn an_overlong_line_is_an_error_line() {
    let mut input = vec![b' '; 2 << 20];
    input.extend_from_slice(b"\n{\"w\":[1,0,1],\"v_a\":[-1,0],\"e\":0.5,\"mu\":0.1}");
    let (stdout, _, code) = run(&input);
    let out: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(out.len(), 2);
    assert!(
        out[0]["error"].as_str().unwrap().contains("2097152 bytes"),
        "{}",
        out[0]
    );
    assert_eq!(out[1]["type"], "sticking");
    assert_eq!(code, 1);
}
