//! Issue 12: the bundled scenes, mutated as a careless or hostile user would (deleted and
//! doubled lines, extreme and non-finite numbers, wrong types, odd shapes, garbage bytes,
//! truncation), through `load` (what `ricochet check` does), then a short run of those
//! that load. Never a panic, never a hang (the run is watched by a clock and must stop
//! within its budget), and every refused scene names its file, line and field.
//!
//! A few hundred cases run in the default suite; `cargo test --release --test all
//! fuzz_scenes:: -- --ignored` runs 10,000.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use ricochet::scene::{self, SceneError};
use ricochet::sim::{MaterialOverride, MoreauJean, NullObserver, Simulation, StopReason};

/// Values that replace a number: extremes, non-finite, wrong types, odd vectors.
const VALUES: [&str; 24] = [
    "0",
    "-1",
    "0.0",
    "-0.0",
    "1e-320",
    "1e308",
    "-1e308",
    "1e6",
    "1e7",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "\"x\"",
    "true",
    "[1.0, 2.0, 3.0]",
    "[]",
    "[\"a\", 1]",
    "{}",
    "\"1e30 deg\"",
    "\"nan rad\"",
    "\"-inf rad/s\"",
    "[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]",
    "[[0, 1], [0.95, 0.31], [-0.59, -0.81], [0.59, -0.81], [-0.95, 0.31]]",
];

/// One edit of a scene text.
#[derive(Clone, Debug)]
enum Mutation {
    /// Delete line `k` (mod the line count).
    DeleteLine(usize),
    /// Write line `k` twice.
    DoubleLine(usize),
    /// Replace the `k`-th number of the text with `VALUES[v]`.
    Number(usize, usize),
    /// Replace the value after the `k`-th `=` with `VALUES[v]`.
    Value(usize, usize),
    /// Insert bytes at a position (a fraction of the length), as lossy UTF-8.
    Garbage(f64, Vec<u8>),
    /// Keep only a fraction of the text.
    Truncate(f64),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0usize..200).prop_map(Mutation::DeleteLine),
        (0usize..200).prop_map(Mutation::DoubleLine),
        (0usize..200, 0..VALUES.len()).prop_map(|(k, v)| Mutation::Number(k, v)),
        (0usize..200, 0..VALUES.len()).prop_map(|(k, v)| Mutation::Value(k, v)),
        (0.0..1.0f64, proptest::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(at, b)| Mutation::Garbage(at, b)),
        (0.0..1.0f64).prop_map(Mutation::Truncate),
    ]
}

/// The byte ranges of the numbers of `text` outside comments and strings.
fn numbers(text: &str) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    for (start, line) in line_starts(text) {
        let code = line.split('#').next().unwrap_or("");
        let bytes = code.as_bytes();
        let mut i = 0;
        let mut in_string = false;
        while i < bytes.len() {
            let c = bytes[i];
            if c == b'"' {
                in_string = !in_string;
            }
            let begins = (c.is_ascii_digit() || c == b'-')
                && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
            if !in_string && begins {
                let j = (i + 1..bytes.len())
                    .find(|&j| !(bytes[j].is_ascii_alphanumeric() || b".-+_".contains(&bytes[j])))
                    .unwrap_or(bytes.len());
                if bytes[i..j].iter().any(u8::is_ascii_digit) {
                    out.push(start + i..start + j);
                }
                i = j;
            } else {
                i += 1;
            }
        }
    }
    out
}

fn line_starts(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split_inclusive('\n').scan(0, |at, line| {
        let start = *at;
        *at += line.len();
        Some((start, line))
    })
}

fn apply(text: &str, m: &Mutation) -> String {
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    if lines.is_empty() {
        return text.to_owned();
    }
    match m {
        Mutation::DeleteLine(k) => {
            let k = k % lines.len();
            lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| *l)
                .collect()
        }
        Mutation::DoubleLine(k) => {
            let k = k % lines.len();
            let mut out = String::new();
            for (i, l) in lines.iter().enumerate() {
                out.push_str(l);
                if i == k {
                    out.push_str(l);
                }
            }
            out
        }
        Mutation::Number(k, v) => {
            let spans = numbers(text);
            if spans.is_empty() {
                return text.to_owned();
            }
            let r = spans[k % spans.len()].clone();
            format!("{}{}{}", &text[..r.start], VALUES[*v], &text[r.end..])
        }
        Mutation::Value(k, v) => {
            let eqs: Vec<usize> = line_starts(text)
                .filter(|(_, l)| !l.trim_start().starts_with('#'))
                .filter_map(|(s, l)| l.find(" = ").map(|i| s + i + 3))
                .collect();
            if eqs.is_empty() {
                return text.to_owned();
            }
            let at = eqs[k % eqs.len()];
            let end = text[at..].find('\n').map_or(text.len(), |e| at + e);
            // Keep a trailing `}` of an inline table when the value sits inside one.
            let tail = if text[at..end].trim_end().ends_with('}') && text[..at].contains('{') {
                " }"
            } else {
                ""
            };
            format!("{}{}{tail}{}", &text[..at], VALUES[*v], &text[end..])
        }
        Mutation::Garbage(at, bytes) => {
            let mut raw = text.as_bytes().to_vec();
            let i = ((*at * raw.len() as f64) as usize).min(raw.len());
            raw.splice(i..i, bytes.iter().copied());
            String::from_utf8_lossy(&raw).into_owned()
        }
        Mutation::Truncate(f) => {
            let mut i = (*f * text.len() as f64) as usize;
            while !text.is_char_boundary(i) {
                i -= 1;
            }
            text[..i].to_owned()
        }
    }
}

/// What one case did.
#[derive(Default, Debug)]
struct Tally {
    refused: usize,
    ran: usize,
    failed_runs: usize,
}

/// Loads the mutated text; if it loads, runs it for at most 0.05 s of simulated time
/// under a 20 s watchdog. Errors are strings naming the case.
fn case(name: &str, text: &str, tally: &mut Tally) -> Result<(), String> {
    let path = format!("{name}.toml");
    let loaded = std::panic::catch_unwind(|| scene::load_str(text, &path))
        .map_err(|_| format!("load panicked on\n{text}"))?;
    let mut scene = match loaded {
        Err(err) => {
            tally.refused += 1;
            return match &err {
                SceneError::At { line, field, .. } if *line >= 1 && !field.is_empty() => {
                    let shown = err.to_string();
                    if shown.starts_with(&format!("{path}:{line}:")) {
                        Ok(())
                    } else {
                        Err(format!(
                            "message does not start with the file and line: {shown}"
                        ))
                    }
                }
                other => Err(format!(
                    "an error without a line and field: {other}\n{text}"
                )),
            };
        }
        Ok(s) => s,
    };
    tally.ran += 1;
    scene.settings.t_end = scene.settings.t_end.min(0.05);
    scene.settings.output_rate = 100.0;
    let stop = Arc::new(AtomicBool::new(false));
    let (done_tx, done_rx) = mpsc::channel::<()>();
    let watch = Arc::clone(&stop);
    let watchdog = std::thread::spawn(move || {
        let fired = done_rx.recv_timeout(Duration::from_secs(20)).is_err();
        if fired {
            watch.store(true, Ordering::SeqCst);
        }
        fired
    });
    let started = Instant::now();
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let overrides = MaterialOverride::default();
        if scene.settings.integrator.method == ricochet::integrate::Method::MoreauJean {
            MoreauJean::new(&scene.model, &scene.settings, overrides)
                .map(|mut mj| mj.run(&scene.initial, &mut NullObserver, Some(&stop)))
        } else {
            Simulation::new(&scene.model, &scene.settings, overrides)
                .map(|mut sim| sim.run(&scene.initial, &mut NullObserver, Some(&stop)))
        }
    }));
    let _ = done_tx.send(());
    let hung = watchdog.join().unwrap_or(false);
    let summary = run.map_err(|_| format!("run panicked on\n{text}"))?;
    if hung {
        return Err(format!(
            "run did not stop within 20 s ({:.1} s) on\n{text}",
            started.elapsed().as_secs_f64()
        ));
    }
    match summary {
        Ok(s) => match s.stop {
            StopReason::EndTime => Ok(()),
            StopReason::Failed(e) => {
                tally.failed_runs += 1;
                let shown = e.to_string();
                if shown.contains("NaN") || shown.is_empty() {
                    Err(format!("a failure that says nothing: {shown}\n{text}"))
                } else {
                    Ok(())
                }
            }
            other => Err(format!("stopped early: {other}\n{text}")),
        },
        Err(e) => {
            tally.failed_runs += 1;
            let _ = e.to_string();
            Ok(())
        }
    }
}

fn fuzz(cases: u32) {
    // Every bundled scene, in name order.
    let dir = format!("{}/scenes", env!("CARGO_MANIFEST_DIR"));
    let mut texts: Vec<(String, String)> = (std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&p).unwrap())
        })
        .collect();
    texts.sort();
    // A fixed seed: the same cases on every run and machine.
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    // FUZZ_SEED=random draws new cases.
    let mut runner = if std::env::var("FUZZ_SEED").is_ok_and(|s| s == "random") {
        TestRunner::new(config)
    } else {
        let rng = proptest::test_runner::TestRng::deterministic_rng(config.rng_algorithm);
        TestRunner::new_with_rng(config, rng)
    };
    let tally = std::cell::RefCell::new(Tally::default());
    let strategy = (0..texts.len(), proptest::collection::vec(mutation(), 1..4));
    let result = runner.run(&strategy, |(k, edits)| {
        let (name, base) = &texts[k];
        let text = edits.iter().fold(base.clone(), |t, m| apply(&t, m));
        case(name, &text, &mut tally.borrow_mut()).map_err(TestCaseError::fail)
    });
    let t = tally.into_inner();
    println!(
        "{cases} mutated scenes: {} refused (each naming its line and field), {} loaded and \
         ran ({} of them failed cleanly)",
        t.refused, t.ran, t.failed_runs
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

#[test]
fn mutated_scenes_never_panic_hang_or_lose_their_location() {
    fuzz(300);
}

#[test]
#[ignore]
fn ten_thousand_mutated_scenes() {
    fuzz(10_000);
}

/// The reproducers of issue 12, each refused with its file, line and field (they were
/// accepted), and the polyline that panicked now runs.
#[test]
fn the_hostile_reproducers() {
    let dir = format!("{}/tests/data/repro", env!("CARGO_MANIFEST_DIR"));
    for (file, line, field, says) in [
        ("empty_scene", 4, "name", "the scene has no body"),
        (
            "gravity_five_elements",
            14,
            "gravity",
            "invalid length 5, expected a list of exactly two values",
        ),
        (
            "pentagram_rod",
            32,
            "body[\"rod\"].shape[0].points",
            "the points turn 2 times around: a polygon must be simple",
        ),
        (
            "subnormal_mass_block",
            31,
            "body[\"block\"].mass",
            "the mass must be within [1e-9, 1e9] kg, got 1e-320 kg",
        ),
    ] {
        let err = scene::load(format!("{dir}/{file}.toml")).unwrap_err();
        println!("{err}");
        assert_eq!(err.line(), Some(line), "{err}");
        assert_eq!(err.field(), Some(field), "{err}");
        assert!(err.to_string().contains(says), "{err}");
    }
    // A ball coming to rest on a polyline: parry's manifold workspace pointed into the
    // manifolds of the previous call and panicked (index out of bounds). It bounces and
    // comes to rest on the floor, like the same scene with a segment.
    let scene = scene::load(format!("{dir}/ball_on_polyline.toml")).unwrap();
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let summary = sim.run(&scene.initial, &mut NullObserver, None);
    assert!(
        matches!(summary.stop, StopReason::EndTime),
        "{}",
        summary.stop
    );
    let (y, v) = (summary.state.q[1], summary.state.u[1]);
    assert!(
        (y - 0.1).abs() <= 1e-8 && v.abs() <= 1e-8,
        "y = {y}, v = {v}"
    );
}
