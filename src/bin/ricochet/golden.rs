//! `ricochet golden record SCENE… --dir DIR` and `ricochet golden check --dir DIR
//! [--update]`: golden runs of a user's scenes. Exit 0 when every scene holds, 1 when one
//! moved or broke its drift budget, 2 on an error (a missing scene, an unreadable file).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Subcommand;
use ricochet::math::Real;
use ricochet::regress::golden::{self, Checked};
use ricochet::regress::{DEFAULT_CHECKPOINTS, Tolerances};

use crate::output::tell;

/// `println!` through an [`Out`].
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {
        $out.line(format!($($arg)*))?
    };
}

/// Options of `ricochet golden`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run scenes and write one golden file per scene, `DIR/<scene file stem>.golden.json`.
    Record(RecordArgs),
    /// Re-run every scene recorded in DIR with its recorded settings and compare, one line per scene.
    Check(CheckArgs),
}

/// Options of `ricochet golden record`.
#[derive(clap::Args)]
struct RecordArgs {
    /// The scene files (TOML).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// The folder of the golden files (created if missing).
    #[arg(long)]
    dir: PathBuf,
    /// The overrides of the scenes' settings (recorded in the files).
    #[command(flatten)]
    overrides: crate::run::OverrideArgs,
    /// Relative tolerance of the comparison, written in the golden file.
    #[arg(long, default_value = "1e-9", allow_negative_numbers = true)]
    cmp_rtol: Real,
    /// Absolute tolerance of the comparison, written in the golden file.
    #[arg(long, default_value = "1e-12", allow_negative_numbers = true)]
    cmp_atol: Real,
    /// Tolerance on times of the comparison (s), written in the golden file.
    #[arg(long, default_value = "1e-9", allow_negative_numbers = true)]
    time_tol: Real,
    /// About how many checkpoints (states on the output grid) to keep.
    #[arg(long, default_value_t = DEFAULT_CHECKPOINTS, value_name = "N")]
    checkpoints: u64,
}

/// Options of `ricochet golden check`.
#[derive(clap::Args)]
struct CheckArgs {
    /// The folder of the golden files.
    #[arg(long)]
    dir: PathBuf,
    /// Rewrite the golden files of the scenes that moved with their new runs (keeping
    /// their overrides and tolerances).
    #[arg(long)]
    update: bool,
    /// Also print the comparison table of each scene that moved (as `ricochet compare`).
    #[arg(short, long)]
    verbose: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let result = match args.command {
        Command::Record(a) => record(&a),
        Command::Check(a) => check(&a),
    };
    match result {
        Ok(code) => Ok(code),
        Err(err) => {
            tell!("error: {err:#}");
            Ok(ExitCode::from(2))
        }
    }
}

fn record(args: &RecordArgs) -> anyhow::Result<ExitCode> {
    let overrides = args.overrides.overrides();
    // The overrides and tolerances are checked once, before any run.
    crate::run::apply_overrides(&overrides, &mut ricochet::settings::Settings::default())?;
    let tolerances = Tolerances {
        rtol: args.cmp_rtol,
        atol: args.cmp_atol,
        time_tol: args.time_tol,
    };
    tolerances.validate().map_err(|e| {
        anyhow::anyhow!(
            "{}",
            e.to_string()
                .replace("`rtol`", "`cmp_rtol`")
                .replace("`atol`", "`cmp_atol`")
        )
    })?;
    let mut seen: BTreeMap<PathBuf, &Path> = BTreeMap::new();
    for scene in &args.scenes {
        let path = golden::golden_path(&args.dir, scene);
        if let Some(other) = seen.insert(path.clone(), scene) {
            bail!(
                "{} and {} would both record to {}: record them into different folders",
                other.display(),
                scene.display(),
                path.display()
            );
        }
    }
    std::fs::create_dir_all(&args.dir)
        .with_context(|| format!("cannot create the folder {}", args.dir.display()))?;
    let mut out = Out::default();
    let (mut errors, mut drifts) = (0, 0);
    for scene in &args.scenes {
        match golden::record(
            scene,
            &args.dir,
            &overrides,
            (&tolerances, args.checkpoints),
        ) {
            Ok((path, g)) => {
                let s = &g.summary;
                let stop = (s.audit.as_ref())
                    .map(|a| format!("stopped at t = {} s, {}", a.t_stop, a.stop_reason))
                    .unwrap_or_default();
                say!(
                    out,
                    "recorded {} → {}: {} impacts, {} checkpoints, {stop}",
                    scene.display(),
                    path.display(),
                    s.impacts.len(),
                    s.checkpoints.len()
                );
                if let Some(d) = s.drift.filter(|d| d.broken()) {
                    drifts += 1;
                    say!(out, "DRIFT    {}: {}", scene.display(), d.describe());
                }
            }
            Err(err) => {
                errors += 1;
                say!(
                    out,
                    "ERROR    {}: {:#}",
                    scene.display(),
                    anyhow::Error::new(err)
                );
            }
        }
    }
    Ok(exit(errors, drifts))
}

fn check(args: &CheckArgs) -> anyhow::Result<ExitCode> {
    let files = golden::golden_files(&args.dir)?;
    if files.is_empty() {
        bail!(
            "no golden files (*{}) in {}: record some with `ricochet golden record SCENE… --dir {}`",
            golden::GOLDEN_SUFFIX,
            args.dir.display(),
            args.dir.display()
        );
    }
    let mut out = Out::default();
    let (mut ok, mut moved, mut updated, mut drifts, mut errors) = (0, 0, 0, 0, 0);
    for file in &files {
        let name = file
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let checked = match golden::check(file) {
            Ok(c) => c,
            Err(err) => {
                errors += 1;
                say!(out, "ERROR    {name}: {:#}", anyhow::Error::new(err));
                continue;
            }
        };
        let scene = scene_name(&checked);
        let changed = if checked.scene_changed() {
            " (the scene file changed since the recording)"
        } else {
            ""
        };
        let c = &checked.comparison;
        if !checked.moved() {
            ok += 1;
            say!(
                out,
                "ok       {scene} ({name}): {} impacts, {} values within the tolerances{changed}",
                checked.fresh.impacts.len(),
                c.compared
            );
        } else {
            let first = c.first.as_ref().map(|d| d.to_text()).unwrap_or_default();
            let verdict = format!(
                "{} of {} values beyond the tolerances",
                c.beyond, c.compared
            );
            if args.update {
                checked
                    .update()
                    .with_context(|| format!("cannot update {}", file.display()))?;
                updated += 1;
                say!(
                    out,
                    "UPDATED  {scene} ({name}): was {first}; {verdict}{changed}"
                );
            } else {
                moved += 1;
                say!(
                    out,
                    "MOVED    {scene} ({name}): {first}; {verdict}{changed}"
                );
            }
            if args.verbose {
                let fresh = format!("{scene} now");
                say!(out, "{}", c.to_text((&file.display().to_string(), &fresh)));
            }
        }
        if let Some(d) = checked.drift().filter(|d| d.broken()) {
            drifts += 1;
            say!(out, "DRIFT    {scene} ({name}): {}", d.describe());
        }
    }
    say!(
        out,
        "{} golden files in {}: {ok} ok, {moved} moved, {updated} updated, {drifts} beyond their drift budget, {errors} errors",
        files.len(),
        args.dir.display()
    );
    if moved > 0 && !args.verbose {
        say!(
            out,
            "the tables of what moved: `ricochet golden check --dir {} --verbose`",
            args.dir.display()
        );
    }
    Ok(exit(errors, moved + drifts))
}

/// Standard output that a closed pipe silences (`ricochet golden check … | head`): the
/// checks go on, and the exit status still says how they went.
#[derive(Default)]
struct Out {
    closed: bool,
}

impl Out {
    fn line(&mut self, text: String) -> anyhow::Result<()> {
        if self.closed {
            return Ok(());
        }
        match writeln!(std::io::stdout().lock(), "{text}") {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(())
            }
            other => Ok(other?),
        }
    }
}

/// 2 if anything failed, else 1 if anything moved or drifted, else 0.
fn exit(errors: usize, failures: usize) -> ExitCode {
    if errors > 0 {
        ExitCode::from(2)
    } else if failures > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

fn scene_name(c: &Checked) -> String {
    (c.golden.summary.scene.as_ref())
        .map(|s| s.name.clone())
        .unwrap_or_else(|| c.golden.scene.clone())
}

#[cfg(test)]
mod tests {
    use clap::Parser;
    use ricochet::regress::Tolerances;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: super::RecordArgs,
    }

    #[test]
    fn the_defaults_are_the_librarys() {
        let cli = Cli::parse_from(["record", "x.toml", "--dir", "g"]);
        let a = &cli.args;
        let tol = Tolerances {
            rtol: a.cmp_rtol,
            atol: a.cmp_atol,
            time_tol: a.time_tol,
        };
        assert_eq!(tol, Tolerances::default());
    }
}
