//! `ricochet compare A B`: two runs (logs, summaries or golden files) side by side; exit 0
//! within the tolerances, 1 beyond, 2 on an error.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use ricochet::math::Real;
use ricochet::regress::{Tolerances, compare, read_run};

use crate::output::tell;

/// Options of `ricochet compare`.
#[derive(clap::Args)]
pub struct Args {
    /// Run A: an MCAP log, a run summary (`run --summary`, `inspect --json`) or a golden file.
    a: PathBuf,
    /// Run B, likewise.
    b: PathBuf,
    /// Relative tolerance: |a − b| ≤ atol + rtol·max(|a|, |b|, S), S the field's largest
    /// magnitude in either run (for energies, the run's energy scale).
    #[arg(long, default_value = "1e-9", allow_negative_numbers = true)]
    rtol: Real,
    /// Absolute tolerance, in the unit of each quantity.
    #[arg(long, default_value = "1e-12", allow_negative_numbers = true)]
    atol: Real,
    /// Tolerance on times: impact times, sample times, the stop time (s).
    #[arg(long, default_value = "1e-9", allow_negative_numbers = true)]
    time_tol: Real,
    /// Print the comparison as JSON (`format = "ricochet.comparison"`).
    #[arg(long)]
    json: bool,
}

/// Compares the runs; an error (a missing or unreadable file, a bad tolerance) is exit 2,
/// not 1, so that a script tells "moved" from "could not tell".
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    match compare_runs(&args) {
        Ok(code) => Ok(code),
        Err(err) => {
            tell!("error: {err:#}");
            Ok(ExitCode::from(2))
        }
    }
}

fn compare_runs(args: &Args) -> anyhow::Result<ExitCode> {
    let tol = Tolerances {
        rtol: args.rtol,
        atol: args.atol,
        time_tol: args.time_tol,
    };
    tol.validate()?;
    let a = read_run(&args.a)?;
    let b = read_run(&args.b)?;
    let comparison = compare(&a, &b, &tol);
    let text = if args.json {
        comparison.to_json()?
    } else {
        comparison.to_text((&args.a.display().to_string(), &args.b.display().to_string()))
    };
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        // A closed pipe (`ricochet compare … | head`) does not change the verdict.
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => return Err(e.into()),
        _ => {}
    }
    Ok(if comparison.within {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

#[cfg(test)]
mod tests {
    use clap::Parser;
    use ricochet::regress::Tolerances;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: super::Args,
    }

    #[test]
    fn the_defaults_are_the_librarys() {
        let cli = Cli::parse_from(["compare", "a", "b"]);
        let a = &cli.args;
        let tol = Tolerances {
            rtol: a.rtol,
            atol: a.atol,
            time_tol: a.time_tol,
        };
        assert_eq!(tol, Tolerances::default());
    }
}
