//! `ricochet inspect`: the summary of a run from its MCAP log alone, as a table or as the
//! JSON run summary (`--json`).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use ricochet::log::{Audit, Ending, ImpactRecord, RunLog, Topic};
use ricochet::regress::Summary;

/// Options of `ricochet inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// The MCAP log of a run.
    file: PathBuf,
    /// Print the run summary as JSON instead (the document of `ricochet run --summary`).
    #[arg(long)]
    json: bool,
    /// With `--json`: about how many checkpoints (states on the output grid) to keep.
    #[arg(long, default_value_t = ricochet::regress::DEFAULT_CHECKPOINTS, value_name = "N")]
    checkpoints: u64,
}

/// Prints the scene, the settings, the impact ledger and the energy audit of a log. A log
/// cut short (a killed process) or without an audit (a run that stopped early) is read as
/// far as it goes, and the summary says so (exit 0). A damaged log (a record that does not
/// decode, a CRC that does not match) is read up to the damage, and the summary of what
/// was read is printed, then an error naming the offset (exit 1); so is a file that is not
/// a ricochet log.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if args.json {
        let bytes = std::fs::read(&args.file)
            .with_context(|| format!("cannot read {}", args.file.display()))?;
        let summary = Summary::from_log(&bytes, Some(args.checkpoints))
            .with_context(|| format!("cannot inspect {}", args.file.display()))?;
        let text = summary
            .to_json()
            .with_context(|| format!("cannot summarize {}", args.file.display()))?;
        use std::io::Write as _;
        return match std::io::stdout().lock().write_all(text.as_bytes()) {
            // A closed pipe (`ricochet inspect … --json | head`) is not an error of the log.
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
            _ => Ok(ExitCode::SUCCESS),
        };
    }
    let log = ricochet::log::read(&args.file)
        .with_context(|| format!("cannot inspect {}", args.file.display()))?;
    crate::output::print(&report(&log, &args.file.display().to_string()))?;
    if let Ending::Damaged { offset, error } = &log.ending {
        anyhow::bail!(
            "{} is damaged at byte {offset}: {error} (the summary above stops there)",
            args.file.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The whole summary as text.
fn report(log: &RunLog, file: &str) -> String {
    let mut out = String::new();
    header(&mut out, log, file);
    settings(&mut out, log);
    ledger(&mut out, &log.impacts);
    audit(&mut out, log);
    out
}

fn header(out: &mut String, log: &RunLog, file: &str) {
    let scene = log
        .scene
        .as_ref()
        .map_or("(no scene record)", |s| s.name.as_str());
    let _ = writeln!(out, "scene: {scene}");
    let _ = writeln!(
        out,
        "file: {file}, written by {}, log format {}",
        or_unknown(&log.library),
        log.format_version
    );
    match &log.ending {
        Ending::Complete => {
            let _ = writeln!(out, "  complete");
        }
        Ending::Truncated { offset, error } => {
            let _ = writeln!(
                out,
                "  truncated after byte {offset} ({error}): the process writing it stopped \
                 early; everything before was read (`ricochet repair` makes it a finished file)"
            );
        }
        Ending::Damaged { offset, error } => {
            let _ = writeln!(
                out,
                "  DAMAGED at byte {offset} ({error}): everything before was read \
                 (`ricochet repair` copies the records that are whole)"
            );
        }
    }
    let mut counts: Vec<String> = (Topic::ALL.iter())
        .map(|t| format!("{} {}", t.name(), log.count(*t)))
        .collect();
    counts.extend(
        (log.message_counts.iter())
            .filter(|(topic, _)| Topic::from_name(topic).is_none())
            .map(|(topic, n)| format!("{topic} {n}")),
    );
    let span = log
        .time_range
        .map(|(a, b)| format!(", t = {} … {} s", num(a), num(b)))
        .unwrap_or_default();
    let _ = writeln!(out, "messages: {}{span}", counts.join(", "));
}

fn settings(out: &mut String, log: &RunLog) {
    let _ = writeln!(out, "\nsettings:");
    match &log.settings {
        None => {
            let _ = writeln!(out, "  (no settings record)");
        }
        Some(fields) => {
            let width = fields.keys().map(|k| k.chars().count()).max().unwrap_or(0);
            for (key, value) in fields {
                let _ = writeln!(out, "  {key:<width$}  {value}");
            }
        }
    }
}

fn ledger(out: &mut String, impacts: &[ImpactRecord]) {
    let _ = writeln!(out, "\nimpacts: {}", impacts.len());
    if impacts.is_empty() {
        return;
    }
    let head = [
        "t [s]",
        "pair",
        "law",
        "type",
        "case",
        "α",
        "I_n [N·s]",
        "I_t [N·s]",
        "v_s.n [m/s]",
        "v_s.t [m/s]",
        "ΔE [J]",
    ];
    let rows: Vec<Vec<String>> = (impacts.iter())
        .map(|i| {
            vec![
                format!("{:.6}", i.t),
                i.pair.clone(),
                i.law.to_string(),
                i.impact_type.name().to_owned(),
                i.case.to_string(),
                i.alpha.map_or("—".to_owned(), num),
                num(i.i_n),
                num(i.i_t),
                num(i.v_s.n),
                num(i.v_s.t),
                num(i.delta_e),
            ]
        })
        .collect();
    // Text columns (pair, law, type) align left, numbers right.
    let left = [
        false, true, true, true, false, false, false, false, false, false, false,
    ];
    table(out, &head, &rows, &left);
}

fn audit(out: &mut String, log: &RunLog) {
    let _ = writeln!(out, "\nenergy audit:");
    let Some(a) = &log.audit else {
        let _ = writeln!(
            out,
            "  no audit record: the run did not finish (it stopped on an error, was \
             interrupted, or its process was killed)"
        );
        if let Some(s) = &log.last_state {
            let _ = writeln!(
                out,
                "  last state: t = {} s, E = {} J ({} impacts)",
                num(s.t),
                num(s.energy.total),
                s.impact_count
            );
        }
        return;
    };
    let c = &a.counters;
    let lines = [
        (
            "stop reason",
            format!("{} at t = {} s", a.stop_reason, num(a.t_stop)),
        ),
        ("E_0", joules(a.energy_initial)),
        ("E_end", joules(a.energy_final)),
        ("E_end − E_0", joules(a.energy_final - a.energy_initial)),
        ("impacts ΣΔE", joules(a.impact_delta_e)),
        ("applied work", joules(a.applied_work)),
        ("contact work", joules(a.contact_work)),
        ("prescribed work", joules(a.prescribed_work)),
        ("integration drift", joules(a.integration_drift)),
        (
            "counters",
            format!(
                "{} impacts, {} steps ({} rejected), {} rhs evaluations, {} events, {} samples",
                c.impacts, c.steps, c.rejected_steps, c.rhs_evaluations, c.events, c.state_samples
            ),
        ),
    ];
    let width = lines
        .iter()
        .map(|(k, _)| k.chars().count())
        .max()
        .unwrap_or(0);
    for (key, value) in lines {
        let pad = width - key.chars().count();
        let _ = writeln!(out, "  {key}{:pad$}  {value}", "");
    }
    check_ledger(out, a, &log.impacts);
}

/// Says so when the audit's impact sum disagrees with the ledger (a damaged or spliced
/// log).
fn check_ledger(out: &mut String, a: &Audit, impacts: &[ImpactRecord]) {
    let sum: f64 = impacts.iter().map(|i| i.delta_e).sum();
    let scale = sum.abs().max(a.impact_delta_e.abs()).max(1e-300);
    if impacts.len() as u64 != a.counters.impacts || (sum - a.impact_delta_e).abs() > 1e-9 * scale {
        let _ = writeln!(
            out,
            "  note: the ledger holds {} impacts with ΣΔE = {}, the audit counts {}",
            impacts.len(),
            joules(sum),
            a.counters.impacts
        );
    }
}

/// Writes an aligned table: a header row, a rule, the rows.
fn table(out: &mut String, head: &[&str], rows: &[Vec<String>], left: &[bool]) {
    let width = |col: usize| {
        (rows.iter().map(|r| r[col].chars().count()))
            .chain([head[col].chars().count()])
            .max()
            .unwrap_or(0)
    };
    let widths: Vec<usize> = (0..head.len()).map(width).collect();
    let line = |cells: Vec<&str>| {
        let cells: Vec<String> = (cells.iter().enumerate())
            .map(|(c, s)| {
                let pad = " ".repeat(widths[c] - s.chars().count());
                if left[c] {
                    format!("{s}{pad}")
                } else {
                    format!("{pad}{s}")
                }
            })
            .collect();
        format!("  {}", cells.join("  ").trim_end())
    };
    let _ = writeln!(out, "{}", line(head.to_vec()));
    let rule: Vec<String> = widths.iter().map(|w| "─".repeat(*w)).collect();
    let _ = writeln!(out, "{}", line(rule.iter().map(String::as_str).collect()));
    for row in rows {
        let _ = writeln!(out, "{}", line(row.iter().map(String::as_str).collect()));
    }
}

/// A number with 6 significant digits, like C's `%g`.
fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exp = x.abs().log10().floor() as i32;
    if !(-4..6).contains(&exp) {
        return format!("{x:.5e}");
    }
    let decimals = (5 - exp).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

fn joules(x: f64) -> String {
    format!("{} J", num(x))
}

fn or_unknown(s: &str) -> &str {
    if s.is_empty() { "an unknown writer" } else { s }
}
