//! `ricochet sweep SCENE --param e=0:1:0.05 --param mu=0,0.3 [--shard i/N] [-o OUT.csv]`:
//! runs a grid of overrides of a scene in parallel and writes one CSV row per run;
//! `ricochet sweep --merge SHARD.csv… [-o OUT.csv]` joins the shards of a sweep.

use std::fs::File;
use std::io::{BufReader, BufWriter, IsTerminal, Write};
use std::num::NonZeroUsize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use ricochet::sweep::{
    Grid, ParamSpec, Shard, Sweep, Table, merge, read_table, thread_pool, write_table,
};

use crate::output::tell;
use crate::run::{SIGHUP, SIGTERM, install_interrupt, interrupted_status};

/// Options of `ricochet sweep`.
#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML); with --merge, the shard tables to join.
    #[arg(required = true, num_args = 1..)]
    inputs: Vec<PathBuf>,
    /// A swept parameter, `name=start:stop:step` (stop inclusive) or `name=v1,v2,…`;
    /// repeat for a grid (the first varies slowest). Names: e, mu, law, method,
    /// simultaneous, t_end, rtol, atol, dt, h_max, q0.<coordinate>, u0.<coordinate>.
    #[arg(short, long = "param", value_name = "SPEC", conflicts_with = "merge")]
    params: Vec<String>,
    /// Run only the share i/N of the grid (the runs whose index is i modulo N), e.g.
    /// `--shard $SLURM_ARRAY_TASK_ID/16`.
    #[arg(long, value_name = "i/N", conflicts_with = "merge")]
    shard: Option<String>,
    /// Threads (default: one per core, or RAYON_NUM_THREADS).
    #[arg(long, value_name = "N", conflicts_with = "merge")]
    threads: Option<NonZeroUsize>,
    /// The CSV file to write (default: `<scene>_sweep.csv` in the current folder, or
    /// `<scene>_sweep.shard-<i>-of-<N>.csv` for a shard).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Join the shard tables given as inputs into the table of the whole sweep.
    #[arg(long)]
    merge: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if args.merge {
        return merge_shards(&args.inputs, args.output);
    }
    let [scene_path] = &args.inputs[..] else {
        bail!(
            "give one scene file (or --merge with shard tables), not {} inputs",
            args.inputs.len()
        );
    };
    let scene = ricochet::scene::load(scene_path)?;
    let specs = args
        .params
        .iter()
        .map(|p| ParamSpec::parse(p))
        .collect::<Result<Vec<_>, _>>()?;
    let sweep = Sweep::new(&scene, Grid::new(specs)?)?;
    let shard: Shard = match &args.shard {
        Some(s) => s.parse()?,
        None => Shard::ALL,
    };
    let output = args.output.unwrap_or_else(|| {
        PathBuf::from(if shard == Shard::ALL {
            format!("{}_sweep.csv", scene.name)
        } else {
            format!(
                "{}_sweep.shard-{}-of-{}.csv",
                scene.name, shard.index, shard.count
            )
        })
    });
    let runs = shard.runs(sweep.grid().len()).len();
    let progress = std::io::stderr().is_terminal().then(|| {
        let bar = ProgressBar::new(runs as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{bar:40}] {pos}/{len} runs, {elapsed}, eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    });
    let pool = thread_pool(args.threads)?;
    let threads = pool.current_num_threads();
    let interrupt = Arc::new(AtomicBool::new(false));
    let signal = Arc::new(AtomicUsize::new(0));
    install_interrupt(&interrupt, &signal)?;
    let start = Instant::now();
    let rows = sweep.run_until(
        &pool,
        shard,
        &|_| {
            if let Some(bar) = &progress {
                bar.inc(1);
            }
        },
        Some(&interrupt),
    );
    if let Some(bar) = &progress {
        bar.finish_and_clear();
    }
    let elapsed = start.elapsed().as_secs_f64();
    // Interrupted: the rows of the runs that finished, the table marked incomplete.
    let mut header = sweep.header(shard);
    let signal = signal.load(Ordering::SeqCst);
    let interrupted = interrupt.load(Ordering::SeqCst) && rows.len() < runs;
    if interrupted {
        header.incomplete = Some(format!(
            "{} of {runs} runs finished: interrupted by {}",
            rows.len(),
            signal_name(signal)
        ));
    }
    write_atomically(&output, |w| Ok(sweep.write_table_under(w, &header, &rows)?))?;

    // What stopped the runs, in a fixed order.
    let mut stops: Vec<(&str, usize)> = Vec::new();
    for r in &rows {
        match stops.iter_mut().find(|(s, _)| *s == r.stop()) {
            Some((_, n)) => *n += 1,
            None => stops.push((r.stop(), 1)),
        }
    }
    stops.sort();
    let stops: Vec<String> = stops.iter().map(|(s, n)| format!("{n} {s}")).collect();
    let threads = match threads {
        1 => "1 thread".to_owned(),
        n => format!("{n} threads"),
    };
    crate::output::print(&format!(
        "{}: {} of {} runs (shard {shard}) on {threads} in {elapsed:.2} s; stops: {}\nwrote {}\n",
        scene.name,
        rows.len(),
        sweep.grid().len(),
        if stops.is_empty() {
            "none".to_owned()
        } else {
            stops.join(", ")
        },
        output.display()
    ))?;
    if let Some(why) = &header.incomplete {
        tell!(
            "{}: {why}; the table holds those runs and is marked incomplete (`--merge` \
             refuses it: run the shard again)",
            output.display()
        );
        return Ok(ExitCode::from(interrupted_status(signal)));
    }
    let failed = rows.iter().filter(|r| r.stop() != END_TIME).count();
    if failed > 0 {
        tell!(
            "{failed} of {} runs failed (stop = error or panic): their rows say why (stop_detail)",
            rows.len()
        );
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}

/// The stop of a run that reached its end time ([`StopReason::name`](ricochet::sim::StopReason::name)).
const END_TIME: &str = "t_end";

/// The name of the signal `number` that interrupted a sweep.
fn signal_name(number: usize) -> &'static str {
    match number {
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "SIGINT (Ctrl-C)",
    }
}

/// `ricochet sweep --merge SHARD… [-o OUT]`.
fn merge_shards(inputs: &[PathBuf], output: Option<PathBuf>) -> anyhow::Result<ExitCode> {
    let tables = inputs
        .iter()
        .map(|p| {
            let f = File::open(p).with_context(|| format!("cannot open {}", p.display()))?;
            Ok(read_table(BufReader::new(f), &p.display().to_string())?)
        })
        .collect::<anyhow::Result<Vec<Table>>>()?;
    let (header, columns, rows) = merge(tables)?;
    let output = output.unwrap_or_else(|| PathBuf::from(format!("{}_sweep.csv", header.scene)));
    if let Some(p) = inputs.iter().find(|p| same_file(p, &output)) {
        bail!("the output {} is one of the shards", p.display());
    }
    write_atomically(&output, |w| Ok(write_table(w, &header, &columns, &rows)?))?;
    crate::output::print(&format!(
        "{}: merged {} shards, {} runs\nwrote {}\n",
        header.scene,
        inputs.len(),
        rows.len(),
        output.display()
    ))?;
    Ok(ExitCode::SUCCESS)
}

/// Whether `a` and `b` name the same existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Writes `path` through a temporary file beside it, renamed when complete: a sweep that
/// is killed leaves no partial table.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".part");
    let tmp = PathBuf::from(tmp);
    let file = File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    let mut w = BufWriter::new(file);
    write(&mut w).with_context(|| format!("cannot write {}", tmp.display()))?;
    w.flush()
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    drop(w);
    std::fs::rename(&tmp, path)
        .with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))?;
    Ok(())
}
