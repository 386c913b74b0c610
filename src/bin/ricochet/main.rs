//! The `ricochet` command-line program.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod bench;
mod check;
mod compare;
mod golden;
mod impact;
mod inspect;
mod live;
mod output;
mod regions;
mod repair;
mod run;
mod sweep;

/// Planar multibody simulator with event-driven rigid impacts.
#[derive(Parser)]
#[command(name = "ricochet", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve one-point impact problems read as JSON Lines from standard input.
    Impact(impact::Args),
    /// Validate a scene and print its coordinates, initial state, mass matrix and energies as JSON.
    Check(check::Args),
    /// Simulate a scene, write its MCAP log, print the impacts and the energy audit.
    ///
    /// Exit status: 0 when the run reached its end time, 1 when it failed (a stall of
    /// impacts or contact modes at one instant is a failure, and so is a run that breaks
    /// its energy-drift budget, after writing its log), 130 when interrupted by Ctrl-C (SIGINT), 143 by SIGTERM,
    /// 129 by SIGHUP. The first signal stops the run at its next step and finishes its log;
    /// a second one exits at once.
    Run(run::Args),
    /// Print the scene, settings, impact ledger and energy audit of a run's MCAP log.
    ///
    /// Exit status: 0 for a complete log or one cut short (read as far as it goes), 1 for a
    /// damaged log (what was read is printed, then the error) or a file that is not a log.
    Inspect(inspect::Args),
    /// Compare two runs (logs, summaries or golden files): impacts, energies, states.
    ///
    /// Exit status: 0 within the tolerances, 1 beyond them, 2 on an error.
    Compare(compare::Args),
    /// Golden runs of scenes: record them, check them again (one line per scene).
    ///
    /// Exit status: 0 when every scene holds, 1 when one moved or broke its drift budget,
    /// 2 on an error.
    Golden(golden::Args),
    /// Copy an MCAP log cut short (its writer killed) into a finished one that every reader opens.
    Repair(repair::Args),
    /// Run a scene over a grid of parameters in parallel (one CSV row per run), one shard
    /// of it, or merge the shards.
    ///
    /// Exit status: 0 when every run reached its end time; 1 when a run failed (the table
    /// is written, its rows say why) or the sweep or merge could not be done (nothing is
    /// written); 130 when interrupted by Ctrl-C (SIGINT), 143 by SIGTERM, 129 by SIGHUP:
    /// the runs under way stop, and the table of the runs that finished is written, marked
    /// incomplete (`--merge` refuses it). A second signal exits at once.
    Sweep(sweep::Args),
    /// Draw maps (SVG) of the collision type and the sign of ΔE over the (α, μ) plane, for each law.
    Regions(regions::Args),
    /// Measure work-precision (error against wall time) of the methods, and the chain scaling; write CSV and SVG charts.
    Bench(bench::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Impact(args) => impact::run(args),
        Command::Check(args) => check::run(args),
        Command::Run(args) => run::run(args),
        Command::Inspect(args) => inspect::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Golden(args) => golden::run(args),
        Command::Repair(args) => repair::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Regions(args) => regions::run(args),
        Command::Bench(args) => bench::run(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            // The chain of causes, each said once (layers that print their cause and
            // also return it as their source would repeat it).
            let messages = err.chain().map(ToString::to_string);
            output::tell!("error: {}", ricochet::sim::describe_messages(messages));
            ExitCode::FAILURE
        }
    }
}
