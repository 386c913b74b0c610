//! Parameter sweeps: a scene run over a grid of overrides, in parallel, one CSV row per
//! run; a grid split into shards for a batch scheduler, and the shards joined again.
//!
//! - [`spec`]: one parameter, `name=start:stop:step` (`value_k = start + k·step`, the
//!   stop inclusive within [`spec::RANGE_TOLERANCE`] steps) or `name=v1,v2,…`. The
//!   parameters: `e`, `mu`, `law`, `method`, `simultaneous`, `t_end`, `rtol`, `atol`, `dt`, `h_max`, and
//!   the initial state by coordinate name, `q0.<coordinate>`, `u0.<coordinate>`
//!   (`q0.ball.y`).
//! - [`grid`]: the Cartesian product (the first parameter varies slowest; the run index is
//!   the mixed-radix number of the value indices) and the shard `i/N` (the runs with
//!   `index mod N = i`).
//! - [`run`]: one point of the grid (the overrides applied to the scene's settings,
//!   materials and initial state, run without a log) gives a [`Row`]; [`Sweep::run`]
//!   maps a shard's points in parallel (rayon) and returns the rows in index order.
//! - [`table`]: the CSV file with its `#` header lines (which sweep, which shard), read
//!   back, and merged.
//!
//! The table is a function of the scene, the grid and ricochet's version alone: no wall
//! time in it, rows in index order, numbers in the shortest decimal that reads back to the
//! same `f64`. So it is byte for byte the same whatever the number of threads, and
//! the merge of the shards is byte for byte the unsharded table.
//!
//! ```no_run
//! use ricochet::sweep::{Grid, ParamSpec, Shard, Sweep};
//! let scene = ricochet::scene::load("scenes/bouncing_ball.toml")?;
//! let grid = Grid::new(vec![
//!     ParamSpec::parse("e=0:1:0.25")?,
//!     ParamSpec::parse("t_end=0.6")?,
//! ])?;
//! let sweep = Sweep::new(&scene, grid)?;
//! let rows = sweep.run(Shard::ALL, None, &|_| {})?;
//! sweep.write_table(std::io::stdout().lock(), Shard::ALL, &rows)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod grid;
pub mod run;
pub mod spec;
pub mod table;

pub use grid::{Grid, Shard};
pub use run::{NotRun, RESULT_COLUMNS, Row, RunResult, Sweep, thread_pool};
pub use spec::{Param, ParamSpec, Value, Values, format_real};
pub use table::{Header, Table, merge, read_table, write_table};

/// A parameter spec that cannot be used. Every message names the spec.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    /// Not `name=start:stop:step` nor `name=v1,v2,…`.
    #[error("bad parameter spec `{spec}`: {reason}")]
    Malformed {
        /// The spec as given.
        spec: String,
        /// What is wrong.
        reason: String,
    },
    /// A parameter that cannot be swept.
    #[error(
        "unknown parameter `{name}` in `{spec}` (expected one of: {})",
        spec::PARAM_NAMES
    )]
    UnknownParam {
        /// The spec as given.
        spec: String,
        /// The name.
        name: String,
    },
    /// A value outside the parameter's range.
    #[error("bad parameter spec `{spec}`: {value}: {reason}")]
    OutOfRange {
        /// The spec as given.
        spec: String,
        /// The value.
        value: String,
        /// The range.
        reason: &'static str,
    },
    /// `q0.`/`u0.` with a name that is no coordinate of the scene.
    #[error(
        "bad parameter `{param}`: the scene {scene} has no {} `{name}` (it has: {known})", if param.starts_with("u0.") { "generalized speed" } else { "coordinate" }
    )]
    UnknownCoordinate {
        /// The parameter, `q0.<name>` or `u0.<name>`.
        param: String,
        /// The name given.
        name: String,
        /// The scene.
        scene: String,
        /// Its coordinates.
        known: String,
    },
    /// A parameter given twice.
    #[error("the parameter `{name}` is given twice")]
    Duplicate {
        /// Its name.
        name: String,
    },
    /// Too many runs.
    #[error("the grid has more than {max} runs")]
    TooLarge {
        /// The limit.
        max: usize,
    },
}

/// A shard that is not `i/N` with `0 ≤ i < N`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("bad shard `{text}`: {reason}")]
pub struct ShardError {
    /// The shard as given.
    pub text: String,
    /// What is wrong.
    pub reason: &'static str,
}

/// A failure of a sweep (not of one of its runs: those are rows) or of a merge.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A bad parameter spec.
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// A bad shard.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// The thread pool could not be built.
    #[error("cannot start the threads: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    /// Reading or writing a table failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Reading or writing CSV failed.
    #[error("CSV: {0}")]
    Csv(#[from] csv::Error),
    /// A table that is not a sweep table.
    #[error("{file}: {reason}")]
    Format {
        /// The file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// Nothing to merge.
    #[error("no shard to merge")]
    NoShards,
    /// Two tables of different sweeps.
    #[error(
        "{file} is not a shard of the same sweep as {other}: its {what} is `{got}`, not `{expected}`"
    )]
    Mismatch {
        /// The table that differs.
        file: String,
        /// The first table.
        other: String,
        /// What differs.
        what: String,
        /// Its value there.
        got: String,
        /// The value in the first table.
        expected: String,
    },
    /// A row that does not belong to its table's shard.
    #[error("{file}: run {index} is not in its shard {shard} of {runs} runs")]
    ForeignRow {
        /// The table.
        file: String,
        /// The run index.
        index: usize,
        /// The table's shard.
        shard: Shard,
        /// Runs of the grid.
        runs: usize,
    },
    /// A run in two tables (or twice in one).
    #[error("run {index} appears twice: in {file} and in {other}")]
    Duplicate {
        /// The run index.
        index: usize,
        /// Where it was seen the second time.
        file: String,
        /// Where it was seen first.
        other: String,
    },
    /// A table of a sweep that was interrupted: it lacks runs that did not finish.
    #[error("{file} is incomplete ({why}): run its shard again before merging")]
    Incomplete {
        /// The table.
        file: String,
        /// Its `# incomplete` line.
        why: String,
    },
    /// Runs in no table.
    #[error("{count} of {runs} runs are missing: {first}")]
    Missing {
        /// How many.
        count: usize,
        /// Runs of the grid.
        runs: usize,
        /// The first of them (and the shards not given).
        first: String,
    },
}
