//! The MCAP log of a run: message types, the writer, the reader.
//!
//! A ricochet log (format version [`FORMAT_VERSION`]) is an MCAP file whose messages are
//! stamped with *simulated* time (nanoseconds since `t = 0`). ricochet's own records are
//! JSON with a `jsonschema` schema (scripts read them); Foxglove's well-known types are
//! protobuf, encoded by Foxglove's SDK (the `foxglove` crate) with its schemas:
//!
//! | topic | schema | content |
//! |---|---|---|
//! | `/state` | `ricochet.State` (JSON) | [`StateRecord`]: `t`, `q[]`, `u[]`, `energy`, contact modes |
//! | `/impacts` | `ricochet.Impact` (JSON) | [`ImpactRecord`]: one entry of the impact ledger per impact |
//! | `/geometry` | `foxglove.SceneUpdate` | every body (collision shapes and visuals) and obstacle ([`draw`]) |
//! | `/scene` | `foxglove.SceneUpdate` | the impulse of each impact: an arrow and its value |
//! | `/tf` | `foxglove.FrameTransforms` | `world → body_<name>`, `world → view` |
//! | `/log` | `foxglove.Log` | one line per impact, warnings and mode changes |
//!
//! Metadata records make a log self-describing: `ricochet` (the format version), `scene`
//! (the scene's name and file text), `settings` (the run settings as JSON) and, when the
//! run ends, `audit` (the [`Audit`] energy balance and stop reason). The schemas are
//! embedded in the file; ricochet's are shipped in `schemas/ricochet/`.
//!
//! Every chunk of a log holds messages (see `sink.rs` for why it matters). Output is
//! deterministic: no wall-clock time, host name or random id is written, so two identical
//! runs give byte-identical files.
//!
//! - [`LogWriter`] writes a log (see its docs for finishing and interruption);
//! - [`read`] reads one back, as far as it goes;
//! - [`repair()`] turns a log cut short (a killed writer) into a finished MCAP file;
//! - [`draw`] turns parry2d shapes and impacts into Foxglove scene entities;
//! - [`RunLogger`] is the simulation's observer that writes a run.

use std::path::PathBuf;

pub mod draw;
pub mod foxglove;
#[cfg(feature = "live")]
#[doc(hidden)]
pub mod live;
mod reader;
#[doc(hidden)]
pub mod records;
#[doc(hidden)]
pub mod repair;
#[doc(hidden)]
pub mod run;
#[doc(hidden)]
pub mod samples;
pub mod schemas;
#[doc(hidden)]
pub mod sink;
#[doc(hidden)]
pub mod writer;

pub use foxglove::{FrameTransform, FrameTransforms, Log, LogLevel, SceneEntity, SceneUpdate};
#[cfg(feature = "live")]
pub use live::{LiveOptions, LiveView};
pub use reader::{Ending, RunLog, SceneInfo, read, read_bytes, read_bytes_with, read_with};
pub use records::{
    Audit, ContactMode, ContactState, Counters, Energy, ImpactCause, ImpactRecord, Planar,
    StateRecord, SupportRecord,
};
pub use repair::{InputEnd, RepairReport, repair, repair_bytes};
pub use run::{LedgerNames, RunLogger, RunSettings, Tap};
pub use schemas::{FORMAT_VERSION, Topic};
pub use writer::{Compression, LogOptions, LogWriter};

/// An error of the log layer. Causes are reported through `source()`, not repeated in the
/// message (print the chain, e.g. with anyhow's `{:#}`).
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// A simulated time that cannot stamp a message.
    #[error(
        "invalid simulated time {t} s: log times must be finite, ≥ 0 and < 2³² s",
        t = crate::math::Shown(*.t)
    )]
    InvalidTime {
        /// The time (s).
        t: f64,
    },
    /// A record holding a NaN or an infinity, which JSON cannot carry.
    #[error("non-finite `{field}` in {what} at t = {t} s")]
    NonFinite {
        /// The topic or metadata record.
        what: &'static str,
        /// Simulated time of the record (s).
        t: f64,
        /// The first non-finite field, e.g. `q[2]`.
        field: String,
    },
    /// The log file could not be created.
    #[error("cannot create the log file {path}")]
    Create {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The log file could not be read.
    #[error("cannot read the log file {path}")]
    Open {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A message or metadata value that does not serialize to JSON.
    #[error("cannot encode {what} as JSON")]
    Encode {
        /// The topic or metadata record.
        what: &'static str,
        /// The cause.
        source: serde_json::Error,
    },
    /// A Foxglove message that protobuf cannot encode.
    #[error("cannot encode {what} as protobuf: {message}")]
    Protobuf {
        /// The topic.
        what: &'static str,
        /// prost's message.
        message: String,
    },
    /// Settings or an audit that do not serialize to a JSON object.
    #[error("{what} must serialize to a JSON object")]
    NotAnObject {
        /// The metadata record.
        what: &'static str,
    },
    /// A logged record that does not decode as the type of its topic.
    #[error("cannot decode {what}")]
    Decode {
        /// The topic or metadata field.
        what: String,
        /// The cause.
        source: serde_json::Error,
    },
    /// The body poses of the initial state could not be computed.
    #[error("cannot compute the initial body poses")]
    Kinematics(#[source] crate::kinematics::KinematicsError),
    /// A metadata value of ricochet's that does not have the expected form.
    #[error("bad metadata {what}: {value:?}")]
    BadMetadata {
        /// The record and key, e.g. `ricochet.format_version`.
        what: String,
        /// The value found.
        value: String,
    },
    /// The live view (`ricochet run --live`) could not start.
    #[error("cannot serve the live view on {address}: {message}")]
    Live {
        /// The address asked for, `host:port`.
        address: String,
        /// What went wrong.
        message: String,
    },
    /// A shape that [`draw::add_shape`] cannot draw.
    #[error("cannot draw a parry2d {shape} shape")]
    UnsupportedShape {
        /// parry2d's name of the shape type.
        shape: String,
    },
    /// Bytes that are not an MCAP file, or not enough of one to repair (see
    /// [`repair()`]).
    #[error("not an MCAP file: {reason}")]
    NotMcap {
        /// What is missing, e.g. `it does not start with the MCAP magic bytes`.
        reason: &'static str,
    },
    /// An error of the MCAP layer: I/O, or a file that is not MCAP.
    #[error("MCAP error")]
    Mcap(#[from] mcap::McapError),
    /// The thread that writes the log could not be started.
    #[error("cannot start the log writer thread")]
    Thread(#[source] std::io::Error),
    /// The log writer stopped after an error that was already reported (or its thread
    /// ended unexpectedly); nothing more is written.
    #[error("the log writer has stopped after an error: {cause}")]
    SinkFailed {
        /// The first error, with its causes (e.g. `No space left on device`), or why the
        /// writer's thread ended.
        cause: String,
    },
}
