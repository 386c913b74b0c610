//! `ricochet run SCENE [-o OUT.mcap]`: simulates a scene, writes its MCAP log, prints the
//! impact table and the energy audit.

use std::io::{IsTerminal, Seek, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use ricochet::impact::Law;
use ricochet::integrate::Method;
use ricochet::log::{LogOptions, LogWriter, RunLogger};
use ricochet::math::Real;
use ricochet::model::Model;
use ricochet::regress::{Collector, DriftCheck, RunOverrides};
use ricochet::settings::Simultaneous;
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, MoreauJean, Observer, ObserverError, RunSummary, Sample,
    Simulation, StopReason,
};

use crate::output::tell;

/// Options of `ricochet run`.
#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML).
    scene: PathBuf,
    /// The MCAP log to write (default: the scene's name with `.mcap`, in the current
    /// folder).
    #[arg(short, long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    overrides: OverrideArgs,
    /// Also write the run summary (JSON: settings, audit, drift, every ledger row, the final
    /// state and checkpoints) to this file.
    #[arg(long, value_name = "FILE.json")]
    summary: Option<PathBuf>,
    /// About how many checkpoints (states on the output grid) the summary keeps.
    #[arg(long, default_value_t = ricochet::regress::DEFAULT_CHECKPOINTS, value_name = "N")]
    checkpoints: u64,
    /// Print only the summary line, not the impact table and the audit.
    #[arg(short, long)]
    quiet: bool,
    #[command(flatten)]
    live: crate::live::LiveArgs,
}

/// The options that override a scene's settings: `ricochet run`'s, and those
/// `ricochet golden record` writes in a golden file.
#[derive(clap::Args)]
pub struct OverrideArgs {
    /// End time (s), instead of the scene's.
    #[arg(long, allow_negative_numbers = true)]
    t_end: Option<Real>,
    /// Impact law for every contact: newton, kane-levinson, poisson, stronge.
    #[arg(long)]
    law: Option<Law>,
    /// Coefficient of restitution for every contact, in [0, 1].
    #[arg(long, allow_negative_numbers = true)]
    e: Option<Real>,
    /// Coefficient of friction for every contact, ≥ 0.
    #[arg(long, allow_negative_numbers = true)]
    mu: Option<Real>,
    /// Integration method: dopri5, dop853, rk4 (event-driven), moreau-jean (time-stepping).
    #[arg(long)]
    method: Option<Method>,
    /// Relative tolerance of DOPRI5 and DOP853 (the integrator's).
    #[arg(long, allow_negative_numbers = true)]
    rtol: Option<Real>,
    /// Absolute tolerance of DOPRI5 and DOP853.
    #[arg(long, allow_negative_numbers = true)]
    atol: Option<Real>,
    /// Step of RK4 and of Moreau–Jean (s).
    #[arg(long, allow_negative_numbers = true)]
    dt: Option<Real>,
    /// Energy-drift budget, relative to the run's energy scale (instead of the scene's
    /// `[run] max_drift`): a run whose audit drifts more fails (exit 1), after writing its
    /// log.
    #[arg(long, allow_negative_numbers = true)]
    max_drift: Option<Real>,
    /// The rule for simultaneous impacts of coupled contact points: generalized-newton
    /// (Moreau's law over the touching points at once) or sequential (the one-point law,
    /// one point at a time), instead of the scene's `[contact] simultaneous`.
    #[arg(long)]
    simultaneous: Option<Simultaneous>,
}

impl OverrideArgs {
    /// The overrides given.
    pub fn overrides(&self) -> RunOverrides {
        RunOverrides {
            t_end: self.t_end,
            law: self.law,
            e: self.e,
            mu: self.mu,
            method: self.method,
            rtol: self.rtol,
            atol: self.atol,
            dt: self.dt,
            max_drift: self.max_drift,
            simultaneous: self.simultaneous,
        }
    }
}

/// One row of the impact table.
struct Row {
    t: Real,
    pair: String,
    law: Law,
    kind: &'static str,
    case: u8,
    alpha: Real,
    i_n: Real,
    i_t: Real,
    v_s: (Real, Real),
    delta_e: Real,
}

/// The observer of the command: the log, a progress bar, the impact table.
struct Terminal<W: Write + Seek + Send + 'static> {
    log: RunLogger<W>,
    progress: Option<ProgressBar>,
    t_end: Real,
    rows: Table,
    /// The run summary and the drift check.
    collector: Collector,
    /// Whether the summary is written (`--summary`): else the collector keeps no impact
    /// (each holds its `Δu`, `nu` numbers: 2,000 balls' 2,084 impacts held 100 MB).
    summary_impacts: bool,
}

/// The rows of the impact table that are printed: the first and the last
/// [`TABLE_ROWS`]` / 2` (a long run's memory must not grow with its impacts).
#[derive(Default)]
struct Table {
    /// The first rows.
    head: Vec<Row>,
    /// The last rows, after the head.
    tail: std::collections::VecDeque<Row>,
    /// All the impacts seen.
    count: usize,
}

impl Table {
    fn push(&mut self, row: Row) {
        self.count += 1;
        if self.head.len() < TABLE_ROWS / 2 {
            self.head.push(row);
        } else {
            if self.tail.len() == TABLE_ROWS / 2 {
                self.tail.pop_front();
            }
            self.tail.push_back(row);
        }
    }

    /// The rows kept, with their index among all the impacts.
    fn rows(&self) -> impl Iterator<Item = (usize, &Row)> {
        let tail_start = self.count - self.tail.len();
        (self.head.iter().enumerate())
            .chain((self.tail.iter().enumerate()).map(move |(k, r)| (tail_start + k, r)))
    }
}

impl<W: Write + Seek + Send + 'static> Observer for Terminal<W> {
    fn sample(&mut self, model: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        if let Some(bar) = &self.progress {
            bar.set_position((1000.0 * s.t / self.t_end) as u64);
        }
        self.collector.sample(model, s)?;
        self.log.sample(model, s)
    }

    fn impact(&mut self, model: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        let pair = model.pair_of(ev.frame.pair);
        let name = |c: ricochet::model::ColliderId| model.colliders()[c.index()].name.clone();
        self.rows.push(Row {
            t: ev.t,
            pair: format!("{}/{}", name(pair.a), name(pair.b)),
            law: ev.outcome.law,
            kind: ev.outcome.kind.name(),
            case: ev.outcome.case.number(),
            alpha: ev.outcome.coefficients.alpha(),
            i_n: ev.impulse().n,
            i_t: ev.impulse().t,
            v_s: (ev.outcome.v_s.n, ev.outcome.v_s.t),
            delta_e: ev.outcome.delta_e,
        });
        if self.summary_impacts {
            self.collector.impact(model, ev)?;
        }
        self.log.impact(model, ev)
    }

    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        // The stop is reported at the end; other warnings as they come.
        if level != Level::Info && !text.starts_with("run stopped") {
            let line = format!("t = {t:.6} s: {text}");
            match &self.progress {
                Some(bar) => bar.println(line),
                None => tell!("{line}"),
            }
        }
        self.log.message(t, level, text)
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let mut scene = ricochet::scene::load(&args.scene)?;
    // Overrides of the scene's settings.
    let overrides = apply_overrides(&args.overrides.overrides(), &mut scene.settings)?;
    let output = args
        .output
        .unwrap_or_else(|| PathBuf::from(format!("{}.mcap", scene.name)));

    // The event-driven loop, or the Moreau–Jean time-stepping.
    let mut runner = match scene.settings.integrator.method {
        Method::MoreauJean => MoreauJean::new(&scene.model, &scene.settings, overrides)
            .map(|mj| Runner::MoreauJean(Box::new(mj))),
        Method::Dopri5 | Method::Dop853 | Method::Rk4 => {
            Simulation::new(&scene.model, &scene.settings, overrides)
                .map(|sim| Runner::EventDriven(Box::new(sim)))
        }
    }
    .with_context(|| format!("{}: cannot simulate", args.scene.display()))?;
    let gap_tol = match &runner {
        Runner::EventDriven(sim) => sim.scales().gap_tol,
        Runner::MoreauJean(mj) => mj.scales().gap_tol,
    };
    let live = crate::live::start(&args.live)?;
    // The summary's file is created before the run, so that a path that cannot be written
    // fails at once, not after the run.
    let summary_file = (args.summary.as_ref())
        .map(|path| {
            std::fs::File::create(path)
                .with_context(|| format!("cannot create the summary {}", path.display()))
        })
        .transpose()?;
    let cannot_write = || format!("cannot write the log {}", output.display());
    let writer = LogWriter::create(&output, LogOptions::default())
        .inspect_err(|_| {
            if let Some(path) = &args.summary {
                let _ = std::fs::remove_file(path);
            }
        })
        .with_context(cannot_write)?;
    let log =
        RunLogger::for_scene(writer, &scene, &overrides, gap_tol).with_context(cannot_write)?;
    let log = match live {
        Some(tap) => log.with_tap(tap),
        None => log,
    };
    let progress = std::io::stderr().is_terminal().then(|| {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{bar:40}] {percent:>3}% of simulated time, {elapsed}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    });
    let mut terminal = Terminal {
        log,
        progress,
        t_end: scene.settings.t_end,
        rows: Table::default(),
        collector: Collector::new(&scene.model, &scene.settings, args.checkpoints),
        summary_impacts: args.summary.is_some(),
    };

    let interrupt = Arc::new(AtomicBool::new(false));
    let signal = Arc::new(AtomicUsize::new(0));
    install_interrupt(&interrupt, &signal)?;
    let summary = match &mut runner {
        Runner::EventDriven(sim) => sim.run(&scene.initial, &mut terminal, Some(&interrupt)),
        Runner::MoreauJean(mj) => mj.run(&scene.initial, &mut terminal, Some(&interrupt)),
    };
    if let Some(bar) = &terminal.progress {
        bar.finish_and_clear();
    }
    let rows = std::mem::take(&mut terminal.rows);
    let finished = terminal.log.finish(&summary);

    let document = (terminal.collector).finish(&scene, (&scene.settings, &overrides), &summary);
    if let (Some(mut file), Some(path)) = (summary_file, &args.summary) {
        let text = (document.to_json())
            .with_context(|| format!("cannot write the summary {}", path.display()))?;
        (file.write_all(text.as_bytes()))
            .with_context(|| format!("cannot write the summary {}", path.display()))?;
    }
    let drift = document.drift;
    // The report, even when the log could not be finished (a full disk: the report says
    // when the run stopped, the error why the log is incomplete).
    let printed = report(&scene.name, &output, (&summary, drift), &rows, args.quiet);
    finished.with_context(|| format!("cannot finish the log {}", output.display()))?;
    let signal = signal.load(Ordering::SeqCst);
    match crate::output::unless_closed(printed) {
        // After SIGHUP the terminal is gone: the log is finished, the report is not needed.
        Err(_) if signal == SIGHUP => {}
        printed => printed?,
    }
    let broken = drift.filter(|d| d.broken());
    if let Some(d) = broken {
        tell!("error: the energy-drift budget is broken: {}", d.describe());
    }
    Ok(match summary.stop {
        StopReason::EndTime if broken.is_some() => ExitCode::FAILURE,
        StopReason::EndTime => ExitCode::SUCCESS,
        StopReason::Interrupted { .. } => ExitCode::from(interrupted_status(signal)),
        StopReason::Failed(_) => ExitCode::FAILURE,
    })
}

/// Applies the command line's overrides to `settings`; an error names the option.
pub fn apply_overrides(
    cli: &RunOverrides,
    settings: &mut ricochet::settings::Settings,
) -> anyhow::Result<MaterialOverride> {
    cli.apply(settings).map_err(|e| {
        anyhow::anyhow!(
            "--{} {}, not {}",
            e.field.replace('_', "-"),
            e.requirement(),
            e.value
        )
    })
}

/// The loop that runs a scene.
enum Runner<'m> {
    /// Event-driven: an ODE stepper between located impacts.
    EventDriven(Box<Simulation<'m>>),
    /// Moreau–Jean time-stepping.
    MoreauJean(Box<MoreauJean<'m>>),
}

/// The signal numbers of SIGINT (Ctrl-C), SIGTERM (`kill`, a service manager stopping the
/// run) and SIGHUP (the terminal closed), which stop a run; POSIX fixes them.
pub(crate) const SIGINT: usize = 2;
pub(crate) const SIGTERM: usize = 15;
pub(crate) const SIGHUP: usize = 1;
#[cfg(unix)]
const _: () = assert!(
    SIGINT as i32 == signal_hook::consts::SIGINT
        && SIGTERM as i32 == signal_hook::consts::SIGTERM
        && SIGHUP as i32 == signal_hook::consts::SIGHUP
);

/// The exit status of a run stopped by `signal` (0 if none was recorded): 128 + its number,
/// the shell's convention (130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP).
pub(crate) fn interrupted_status(signal: usize) -> u8 {
    let signal = if signal == 0 { SIGINT } else { signal };
    u8::try_from(128 + signal).unwrap_or(130)
}

/// On a first SIGINT (Ctrl-C), SIGTERM or SIGHUP the run stops at its next step and
/// finishes its log, and `signal` records which came; a second one (of any of the three)
/// ends the process at once, with 128 + its number.
pub(crate) fn install_interrupt(
    flag: &Arc<AtomicBool>,
    signal: &Arc<AtomicUsize>,
) -> anyhow::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::flag;
        for (number, name) in [(SIGINT, "Ctrl-C"), (SIGTERM, "SIGTERM"), (SIGHUP, "SIGHUP")] {
            let context = || format!("cannot install the {name} handler");
            let sig = number as i32;
            // In this order: a handler sees the flag as the previous signal left it.
            flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(flag))
                .with_context(context)?;
            flag::register_usize(sig, Arc::clone(signal), number).with_context(context)?;
            flag::register(sig, Arc::clone(flag)).with_context(context)?;
        }
    }
    #[cfg(not(unix))]
    let _ = (flag, signal);
    Ok(())
}

/// The longest impact table printed in full; longer ones show their head and tail.
const TABLE_ROWS: usize = 40;

fn report(
    name: &str,
    output: &std::path::Path,
    (summary, drift): (&RunSummary, Option<DriftCheck>),
    rows: &Table,
    quiet: bool,
) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    let c = &summary.counters;
    // The line says the time: the failure without it.
    let stop = match &summary.stop {
        StopReason::Failed(e) => format!("failed: {}", e.what()),
        stop => stop.to_string(),
    };
    writeln!(
        out,
        "{name}: stopped at t = {:.6} s, {stop}\n{} impacts, {} steps ({} rejected), {} rhs evaluations",
        summary.state.t, c.impacts, c.steps, c.rejected, c.rhs_evals
    )?;
    if !quiet {
        if rows.count > 0 {
            writeln!(out)?;
            writeln!(
                out,
                "{:>5} {:>12} {:<16} {:<13} {:<15} {:>4} {:>9} {:>11} {:>11} {:>11} {:>11} {:>11}",
                "#",
                "t [s]",
                "pair",
                "law",
                "type",
                "case",
                "alpha",
                "I_n [Ns]",
                "I_t [Ns]",
                "v_n^S [m/s]",
                "v_t^S [m/s]",
                "dE [J]"
            )?;
            for (k, r) in rows.rows() {
                if rows.count > TABLE_ROWS && k == rows.count - TABLE_ROWS / 2 {
                    writeln!(
                        out,
                        "{:>5} … {} more impacts …",
                        "",
                        rows.count - TABLE_ROWS
                    )?;
                }
                writeln!(
                    out,
                    "{:>5} {:>12.6} {:<16} {:<13} {:<15} {:>4} {:>9} {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e}",
                    k,
                    r.t,
                    r.pair,
                    r.law.name(),
                    r.kind,
                    r.case,
                    short(r.alpha),
                    r.i_n,
                    r.i_t,
                    r.v_s.0,
                    r.v_s.1,
                    r.delta_e
                )?;
            }
        }
        let a = &summary.audit;
        writeln!(out)?;
        writeln!(out, "energy audit [J]")?;
        writeln!(
            out,
            "  E_0                          {:>16.9e}",
            a.initial.total()
        )?;
        writeln!(
            out,
            "  E_end                        {:>16.9e}",
            a.end.total()
        )?;
        writeln!(
            out,
            "  E_end − E_0                  {:>16.9e}",
            a.end.total() - a.initial.total()
        )?;
        writeln!(
            out,
            "  impacts, Eq. (29)            {:>16.9e}",
            a.impact_delta_e
        )?;
        writeln!(
            out,
            "  prescribed motion at impacts {:>16.9e}   (Eq. 28)",
            a.impact_prescribed_work
        )?;
        writeln!(
            out,
            "  prescribed drives            {:>16.9e}",
            a.drive_work
        )?;
        writeln!(
            out,
            "  dampers                      {:>16.9e}",
            a.damping_work
        )?;
        writeln!(
            out,
            "  applied efforts              {:>16.9e}",
            a.applied_work
        )?;
        writeln!(
            out,
            "  persistent contact forces    {:>16.9e}",
            a.contact_work
        )?;
        let relative = (drift.and_then(|d| d.relative))
            .map_or_else(|| "unmeasurable".to_owned(), |r| format!("{r:.1e}"));
        writeln!(
            out,
            "  integration drift            {:>16.9e}   ({relative} relative)",
            a.drift(),
        )?;
    }
    if let Some(d) = drift.filter(|d| d.max_drift.is_some()) {
        writeln!(out, "drift budget: {}", d.describe())?;
    }
    writeln!(out, "log: {}", output.display())?;
    out.flush()
}

/// `x` in at most 9 characters: fixed below 10⁴, scientific above (α is unbounded as the
/// approach speed vanishes).
fn short(x: Real) -> String {
    if !x.is_finite() {
        // No approach speed, no α (as in the log, where it is absent).
        "—".to_owned()
    } else if x.abs() < 1e4 {
        format!("{x:.4}")
    } else {
        format!("{x:.2e}")
    }
}
