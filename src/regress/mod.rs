//! Regression tests of a user's own scenes: the machine-readable run summary, the
//! comparison of two runs, golden files, and energy-drift budgets.
//!
//! - [`Summary`] (`summary.rs`): the run summary, a versioned JSON document (`ricochet run
//!   --summary`, `ricochet inspect --json`), built from a run by the [`Collector`]
//!   observer (`collect.rs`) or from a log ([`Summary::from_log`]); [`read_run`] reads a
//!   log, a summary or a golden file as a summary.
//! - [`compare()`] (`compare.rs`): two runs, the impacts matched in order and by contact
//!   pair, every quantity's largest difference and the first place beyond [`Tolerances`].
//! - [`golden`]: one file per scene, recorded and checked.
//! - [`DriftCheck`] (`drift.rs`): the audit's integration drift against the run's energy
//!   scale and the scene's `[run] max_drift`.
//! - [`RunOverrides`] (`overrides.rs`): the command line's overrides of a scene's settings,
//!   which a golden file records.
//!
//! The documents are laid out by `layout.rs`: one member per line, one impact per line;
//! numbers as `serde_json` writes them, which read back bit-exact.

mod collect;
pub mod compare;
#[doc(hidden)]
pub mod drift;
pub mod golden;
#[doc(hidden)]
pub mod layout;
#[doc(hidden)]
pub mod overrides;
#[doc(hidden)]
pub mod summary;

use std::path::{Path, PathBuf};

pub use collect::{Collector, run_scene};
pub use compare::{Comparison, Difference, Kind, Place, Quantity, Tolerances, compare};
pub use drift::DriftCheck;
pub use golden::Golden;
pub use overrides::{OverrideError, RunOverrides};
pub use summary::{
    Checkpoints, DEFAULT_CHECKPOINTS, SUMMARY_FORMAT, SUMMARY_VERSION, SceneId, Snapshot, Summary,
};

use crate::log::LogError;
use crate::scene::SceneError;
use crate::sim::SimError;

/// An error of a summary, a comparison or a golden file. Causes are reported through
/// `source()` (print the chain, e.g. with anyhow's `{:#}`).
#[derive(Debug, thiserror::Error)]
pub enum RegressError {
    /// A file could not be read.
    #[error("cannot read {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write {path}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file that is neither an MCAP log nor JSON.
    #[error("{path}: neither a ricochet log (MCAP) nor a JSON document")]
    Json {
        /// The file.
        path: PathBuf,
        /// The JSON parser's error, with its line and column.
        #[source]
        source: serde_json::Error,
    },
    /// A JSON document of another kind.
    #[error("{path}: `format` is {found:?}, not {expected:?}")]
    NotADocument {
        /// The file.
        path: PathBuf,
        /// The format expected.
        expected: &'static str,
        /// The format found (empty when there is none).
        found: String,
    },
    /// A document of a version this ricochet does not read.
    #[error(
        "{path}: {what} version {found} is not supported (this ricochet reads 1 to {supported})"
    )]
    Version {
        /// The file.
        path: PathBuf,
        /// The format.
        what: &'static str,
        /// The version found, as written.
        found: String,
        /// The latest version supported.
        supported: u32,
    },
    /// A document whose fields do not decode.
    #[error("{path}: not a valid {what} document")]
    Document {
        /// The file.
        path: PathBuf,
        /// The format.
        what: &'static str,
        /// The decoder's error, naming the field, line and column.
        #[source]
        source: serde_json::Error,
    },
    /// A document with a value out of range.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A log that does not read.
    #[error("{path}: cannot read the log")]
    Log {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: LogError,
    },
    /// A scene that does not load.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A scene whose run cannot start.
    #[error("{scene}: cannot simulate")]
    Start {
        /// The scene file.
        scene: PathBuf,
        /// Why.
        #[source]
        source: Box<SimError>,
    },
    /// An override out of range.
    #[error(transparent)]
    Override(#[from] OverrideError),
    /// A tolerance out of range.
    #[error("the tolerance `{field}` must be a finite number ≥ 0, not {value}")]
    Tolerance {
        /// `rtol`, `atol` or `time_tol`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// A number that JSON cannot carry.
    #[error("non-finite `{field}`: JSON has no NaN or infinity, so it cannot be written")]
    NonFinite {
        /// The first non-finite field, e.g. `final_state.q[2]`.
        field: String,
    },
    /// A document that does not encode.
    #[error("cannot encode the document")]
    Encode(#[source] serde_json::Error),
}

/// Reads a run from `path` as a summary: an MCAP log (with every sample of the log as its
/// checkpoints), a run summary, or a golden file (its recorded summary).
pub fn read_run(path: &Path) -> Result<Summary, RegressError> {
    let bytes = std::fs::read(path).map_err(|source| RegressError::Read {
        path: path.to_owned(),
        source,
    })?;
    if bytes.starts_with(mcap::MAGIC) {
        return Summary::from_log(&bytes, None).map_err(|source| RegressError::Log {
            path: path.to_owned(),
            source,
        });
    }
    let text = String::from_utf8_lossy(&bytes);
    let value = parse_json(&text, path)?;
    match value.get("format").and_then(serde_json::Value::as_str) {
        Some(golden::GOLDEN_FORMAT) => Ok(Golden::from_text(&text, path)?.summary),
        _ => {
            summary::check_format(&value, path, SUMMARY_FORMAT, SUMMARY_VERSION)?;
            serde_json::from_str(&text).map_err(|source| RegressError::Document {
                path: path.to_owned(),
                what: SUMMARY_FORMAT,
                source,
            })
        }
    }
}

/// The text of the file at `path`.
fn read_text(path: &Path) -> Result<String, RegressError> {
    std::fs::read_to_string(path).map_err(|source| RegressError::Read {
        path: path.to_owned(),
        source,
    })
}

/// `text` as a JSON value; errors name `path`, the line and the column.
fn parse_json(text: &str, path: &Path) -> Result<serde_json::Value, RegressError> {
    serde_json::from_str(text).map_err(|source| RegressError::Json {
        path: path.to_owned(),
        source,
    })
}
