//! `ricochet impact`: one impact per JSON line.

use std::process::ExitCode;

use ricochet::impact::Law;

/// Options of `ricochet impact`.
#[derive(clap::Args)]
pub struct Args {
    /// The law for lines that do not name one.
    #[arg(long, default_value = "newton")]
    law: Law,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let _ = args.law;
    anyhow::bail!("not implemented yet")
}
