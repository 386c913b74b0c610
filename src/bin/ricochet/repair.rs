//! `ricochet repair BROKEN.mcap [-o FIXED.mcap] [--force]`: copies an MCAP log cut short
//! (its writer killed) into a finished one, and says what was kept and lost.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use ricochet::log::{InputEnd, RepairReport};

/// Options of `ricochet repair`.
#[derive(clap::Args)]
pub struct Args {
    /// The MCAP file to repair (it is only read).
    input: PathBuf,
    /// The repaired file to write (default: `<input stem>.repaired.mcap` beside the input).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Overwrite the output file if it exists.
    #[arg(short, long)]
    force: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let output = match args.output {
        Some(output) => output,
        None => default_output(&args.input)?,
    };
    let bytes = std::fs::read(&args.input)
        .with_context(|| format!("cannot read {}", args.input.display()))?;
    if same_file(&args.input, &output)? {
        bail!(
            "the output {} is the input: give another file with -o",
            output.display()
        );
    }
    if output.exists() && !args.force {
        bail!(
            "{} already exists: give another file with -o, or --force to overwrite it",
            output.display()
        );
    }

    let report = write_atomically(&output, |file| {
        ricochet::log::repair(&bytes, file)
            .with_context(|| format!("cannot repair {}", args.input.display()))
    })?;
    print_report(&args.input, bytes.len(), &output, &report)?;
    Ok(ExitCode::SUCCESS)
}

/// `<stem>.repaired.mcap` in the input's folder.
fn default_output(input: &Path) -> anyhow::Result<PathBuf> {
    let Some(stem) = input.file_stem() else {
        bail!("{} is not a file name", input.display());
    };
    let mut name = stem.to_os_string();
    name.push(".repaired.mcap");
    Ok(input.with_file_name(name))
}

/// Whether `output` names the file `input` (which exists), through any path.
fn same_file(input: &Path, output: &Path) -> anyhow::Result<bool> {
    let input = input
        .canonicalize()
        .with_context(|| format!("cannot resolve {}", input.display()))?;
    // The output may not exist yet: resolve its folder.
    let output = match output.canonicalize() {
        Ok(path) => path,
        Err(_) => match (output.parent(), output.file_name()) {
            (Some(dir), Some(name)) => {
                let dir = if dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    dir
                };
                match dir.canonicalize() {
                    Ok(dir) => dir.join(name),
                    Err(_) => return Ok(false),
                }
            }
            _ => return Ok(false),
        },
    };
    Ok(input == output)
}

/// Writes `path` through a temporary file in the same folder, renamed to `path` once
/// `write` and the flush succeeded; on an error the temporary file is removed, and `path`
/// is untouched.
fn write_atomically<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let Some(name) = path.file_name() else {
        bail!("{} is not a file name", path.display());
    };
    let mut temp_name = std::ffi::OsString::from(".");
    temp_name.push(name);
    temp_name.push(format!(".{}.tmp", std::process::id()));
    let temp = path.with_file_name(temp_name);
    let result = (|| {
        let file =
            File::create(&temp).with_context(|| format!("cannot create {}", temp.display()))?;
        let mut file = BufWriter::new(file);
        let value = write(&mut file)?;
        let file = file
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("cannot write {}", temp.display()))?;
        file.sync_all()
            .with_context(|| format!("cannot write {}", temp.display()))?;
        std::fs::rename(&temp, path)
            .with_context(|| format!("cannot rename {} to {}", temp.display(), path.display()))?;
        Ok(value)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temp);
    }
    result
}

fn print_report(
    input: &Path,
    size: usize,
    output: &Path,
    report: &RepairReport,
) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}: {} bytes, {}", input.display(), size, report.end)?;
    match &report.end {
        InputEnd::Complete | InputEnd::SummaryDamaged { .. } => {
            writeln!(out, "lost: nothing (the input was complete)")?;
        }
        InputEnd::BetweenRecords => {
            writeln!(
                out,
                "lost: nothing in the file (it stops between two records)"
            )?;
        }
        InputEnd::InsideRecord { .. } | InputEnd::Unreadable { .. } => {
            write!(
                out,
                "lost: the last {} bytes (from byte {})",
                report.unused_bytes, report.stopped_at
            )?;
            if report.salvaged_messages > 0 {
                write!(
                    out,
                    "; {} messages salvaged from them",
                    report.salvaged_messages
                )?;
            }
            writeln!(out)?;
        }
    }
    writeln!(
        out,
        "kept: {} messages, {} schemas, {} channels, {} metadata records, {} attachments",
        report.messages, report.schemas, report.channels, report.metadata, report.attachments
    )?;
    if report.skipped > 0 {
        writeln!(
            out,
            "skipped: {} records (unknown channel or schema, or a redefined id)",
            report.skipped
        )?;
    }
    writeln!(out, "repaired: {}", output.display())?;
    Ok(())
}
