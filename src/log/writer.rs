//! [`LogWriter`]: a thin adaptor over `mcap::Writer` that registers ricochet's schemas and
//! channels once, then writes JSON messages to known channels.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use mcap::records::{MessageHeader, Metadata};
use serde::Serialize;

use super::LogError;
use super::foxglove::{FrameTransforms, Log, LogLevel, SceneUpdate, Time, nanoseconds};
use super::records::{Audit, ImpactRecord, StateRecord};
use super::schemas::{MESSAGE_ENCODING, SCHEMA_ENCODING, Topic, metadata};
use super::sink::{Sink, append_json};

/// Compression of the MCAP chunks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compression {
    /// No compression.
    None,
    /// LZ4 frames (the default; Foxglove reads them).
    #[default]
    Lz4,
    /// Zstandard, single-threaded so that the output is deterministic (crate feature
    /// `zstd`).
    #[cfg(feature = "zstd")]
    Zstd,
}

/// Options of a [`LogWriter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogOptions {
    /// Compression of the chunks.
    pub compression: Compression,
    /// Target size of a chunk before compression (bytes). A process killed without
    /// finishing the file loses at most the chunk being written, unless
    /// [`LogWriter::flush`] was called since.
    pub chunk_size: u64,
}

impl Default for LogOptions {
    fn default() -> Self {
        Self {
            compression: Compression::Lz4,
            chunk_size: 64 * 1024,
        }
    }
}

/// The `library` field of the MCAP header. No date, host or random id goes into a file:
/// two identical runs give byte-identical logs.
const LIBRARY: &str = concat!("ricochet ", env!("CARGO_PKG_VERSION"));

/// Writes a ricochet run to an MCAP file.
///
/// The five channels of [`Topic::ALL`] and their schemas are registered when the writer is
/// created; each method then writes one message to its known channel, with
/// `log_time = publish_time =` the simulated time in nanoseconds ([`nanoseconds`]: a time
/// that is negative, NaN, infinite or beyond `2³²` s is refused with
/// [`LogError::InvalidTime`]). Messages holding a NaN or an infinity are refused with
/// [`LogError::NonFinite`] naming the field (JSON has no such numbers). A refused message
/// is not written, and the writer stays usable.
///
/// The messages are encoded as JSON on the calling thread; the `mcap::Writer` (which
/// compresses the chunks and writes them out) runs on a thread of its own, fed in order
/// through a bounded channel, so that logging overlaps with the simulation and the bytes
/// are the same as a single-threaded writer's (see `sink.rs`). An I/O error is therefore
/// reported by the call after the one whose message met it (or by `flush`, `finish`).
///
/// Ending a run: call [`finish`](LogWriter::finish), which writes the summary section and
/// reports any I/O error. If the writer is dropped instead (an early return on error, a
/// panic unwinding), `mcap::Writer`'s `Drop` still finishes the file, ignoring errors: the
/// log is a valid MCAP file holding everything written so far (dropping waits for the
/// writer thread). A process that is killed
/// outright leaves a file without a summary; [`read`](super::read()) (and `mcap`'s
/// `MessageStream`) still read it up to the last complete chunk, so call
/// [`flush`](LogWriter::flush) at points worth keeping.
///
/// ```
/// use ricochet::log::{Energy, LogOptions, LogWriter, StateRecord};
/// # fn main() -> Result<(), ricochet::log::LogError> {
/// let mut log = LogWriter::new(std::io::Cursor::new(Vec::new()), LogOptions::default())?;
/// log.scene("ball", "name = \"ball\"\n")?;
/// log.state(&StateRecord::new(0.0, vec![1.0], vec![0.0], Energy::new(0.0, 9.81), vec![], 0))?;
/// let bytes = log.finish()?.into_inner();
/// assert!(bytes.starts_with(b"\x89MCAP0\r\n"));
/// # Ok(())
/// # }
/// ```
pub struct LogWriter<W: Write + Seek + Send + 'static> {
    mcap: Sink<W>,
    /// Channel id of each topic, indexed by [`Topic::index`].
    channels: [u16; Topic::ALL.len()],
    /// Next sequence number of each topic.
    sequences: [u32; Topic::ALL.len()],
}

impl LogWriter<BufWriter<File>> {
    /// Creates (or truncates) the file at `path` and starts a log in it.
    pub fn create(path: impl AsRef<Path>, options: LogOptions) -> Result<Self, LogError> {
        let path = path.as_ref();
        let file = File::create(path).map_err(|source| LogError::Create {
            path: path.to_owned(),
            source,
        })?;
        LogWriter::new(BufWriter::new(file), options)
    }
}

impl<W: Write + Seek + Send + 'static> LogWriter<W> {
    /// Starts a log in `writer`: the MCAP header, then the schemas and channels of every
    /// topic, in a first chunk that is flushed at once.
    pub fn new(writer: W, options: LogOptions) -> Result<Self, LogError> {
        let mut mcap = mcap_options(options).create(writer)?;
        let mut channels = [0; Topic::ALL.len()];
        for topic in Topic::ALL {
            let schema = mcap.add_schema(
                topic.schema_name(),
                SCHEMA_ENCODING,
                topic.schema().as_bytes(),
            )?;
            channels[topic.index()] =
                mcap.add_channel(schema, topic.name(), MESSAGE_ENCODING, &BTreeMap::new())?;
        }
        mcap.flush()?;
        Ok(LogWriter {
            mcap: Sink::spawn(mcap)?,
            channels,
            sequences: [0; Topic::ALL.len()],
        })
    }

    /// Writes the `scene` metadata record: the scene's `name` and its file `text`.
    pub fn scene(&mut self, name: &str, text: &str) -> Result<(), LogError> {
        let metadata = BTreeMap::from([
            ("name".to_owned(), name.to_owned()),
            ("text".to_owned(), text.to_owned()),
        ]);
        self.metadata(metadata::SCENE, metadata)
    }

    /// Writes the `settings` metadata record: each top-level field of `settings` (which
    /// must serialize to a JSON object, e.g. [`Settings`](crate::settings::Settings)) as a
    /// key whose value is the field's compact JSON text.
    pub fn settings<S: Serialize>(&mut self, settings: &S) -> Result<(), LogError> {
        let map = json_fields(metadata::SETTINGS, settings)?;
        self.metadata(metadata::SETTINGS, map)
    }

    /// Writes the `audit` metadata record (each field of [`Audit`] as a key whose value is
    /// its JSON text). Written once, when the run ends; a log without it is of a run that
    /// stopped early.
    pub fn audit(&mut self, audit: &Audit) -> Result<(), LogError> {
        if let Some(field) = audit.first_non_finite() {
            return Err(LogError::NonFinite {
                what: metadata::AUDIT,
                t: audit.t_stop,
                field,
            });
        }
        let map = json_fields(metadata::AUDIT, audit)?;
        self.metadata(metadata::AUDIT, map)
    }

    /// Writes one `/state` sample at its time `state.t` (encoded on the writer thread).
    pub fn state(&mut self, state: &StateRecord) -> Result<(), LogError> {
        if let Some(field) = state.first_non_finite() {
            return Err(LogError::NonFinite {
                what: Topic::State.name(),
                t: state.t,
                field,
            });
        }
        let header = self.header(Topic::State, nanoseconds(state.t)?);
        self.mcap.push_state(header, state)?;
        self.advance(Topic::State);
        Ok(())
    }

    /// Writes one entry of the impact ledger on `/impacts` at its time `impact.t`.
    pub fn impact(&mut self, impact: &ImpactRecord) -> Result<(), LogError> {
        if let Some(field) = impact.first_non_finite() {
            return Err(LogError::NonFinite {
                what: Topic::Impacts.name(),
                t: impact.t,
                field,
            });
        }
        self.write(Topic::Impacts, impact.t, impact)
    }

    /// Writes a scene update on `/scene` at simulated time `t` (s). The entities carry their
    /// own timestamps, which the 3-D panel uses; normally they equal `t`.
    pub fn scene_update(&mut self, t: f64, update: &SceneUpdate) -> Result<(), LogError> {
        self.write_checked(Topic::Scene, t, update)
    }

    /// Writes frame transforms on `/tf` at simulated time `t` (s) (encoded on the writer
    /// thread).
    pub fn transforms(&mut self, t: f64, transforms: &FrameTransforms) -> Result<(), LogError> {
        let time = nanoseconds(t)?;
        if let Some(field) = first_non_finite_transform(transforms) {
            return Err(LogError::NonFinite {
                what: Topic::Tf.name(),
                t,
                field,
            });
        }
        let header = self.header(Topic::Tf, time);
        self.mcap.push_transforms(header, transforms)?;
        self.advance(Topic::Tf);
        Ok(())
    }

    /// Writes a text message on `/log` at simulated time `t` (s), from `ricochet`.
    pub fn log(&mut self, t: f64, level: LogLevel, message: &str) -> Result<(), LogError> {
        let log = Log {
            timestamp: Time::from_seconds(t)?,
            level,
            message: message.to_owned(),
            name: "ricochet".to_owned(),
            file: String::new(),
            line: 0,
        };
        self.write(Topic::Log, t, &log)
    }

    /// Closes the current chunk and flushes it to the underlying writer, so that a process
    /// killed later still leaves everything written so far readable.
    pub fn flush(&mut self) -> Result<(), LogError> {
        self.mcap.flush()
    }

    /// Finishes the file (the summary section, the footer) and returns the underlying
    /// writer, flushed.
    pub fn finish(self) -> Result<W, LogError> {
        self.mcap.finish()
    }

    /// Serializes `message` and writes it on `topic` at simulated time `t` (s).
    fn write<M: Serialize>(&mut self, topic: Topic, t: f64, message: &M) -> Result<(), LogError> {
        let time = nanoseconds(t)?;
        let start = self.encode(topic, message)?;
        self.write_encoded(topic, time, start)
    }

    /// [`write`](Self::write) for a message whose numbers are not checked beforehand:
    /// refuses it if it holds a NaN or an infinity, which `serde_json` writes as `null`
    /// (the Foxglove schemas have no nullable field, so a `null` can only come from one).
    /// The encoded bytes are scanned for `null`; only if they hold one (which a name may
    /// also do) is the message examined field by field.
    fn write_checked<M: Serialize>(
        &mut self,
        topic: Topic,
        t: f64,
        message: &M,
    ) -> Result<(), LogError> {
        let time = nanoseconds(t)?;
        let start = self.encode(topic, message)?;
        let encoded = &self.mcap.buffer()[start..];
        if encoded.windows(4).any(|w| w == b"null")
            && let Err(e) = check_finite(topic, t, message)
        {
            self.mcap.buffer().truncate(start);
            return Err(e);
        }
        self.write_encoded(topic, time, start)
    }

    /// Appends `message`'s JSON to the sink's buffer; returns where it starts. On an
    /// error the buffer is left as it was.
    fn encode<M: Serialize>(&mut self, topic: Topic, message: &M) -> Result<usize, LogError> {
        let buffer = self.mcap.buffer();
        let start = buffer.len();
        append_json(buffer, topic, message)?;
        Ok(start)
    }

    /// Hands the message encoded from `start` on to the sink, on `topic` at `time` (ns).
    fn write_encoded(&mut self, topic: Topic, time: u64, start: usize) -> Result<(), LogError> {
        let header = self.header(topic, time);
        self.mcap.push(header, start)?;
        self.advance(topic);
        Ok(())
    }

    /// The header of the next message on `topic` at `time` (ns).
    fn header(&self, topic: Topic, time: u64) -> MessageHeader {
        let i = topic.index();
        MessageHeader {
            channel_id: self.channels[i],
            sequence: self.sequences[i],
            log_time: time,
            publish_time: time,
        }
    }

    /// Counts a message written on `topic`.
    fn advance(&mut self, topic: Topic) {
        let i = topic.index();
        self.sequences[i] = self.sequences[i].wrapping_add(1);
    }

    fn metadata(&mut self, name: &str, map: BTreeMap<String, String>) -> Result<(), LogError> {
        self.mcap.metadata(Metadata {
            name: name.to_owned(),
            metadata: map,
        })
    }
}

/// The first non-finite number of `tf`, named as in its JSON (`transforms[1].rotation.w`).
fn first_non_finite_transform(tf: &FrameTransforms) -> Option<String> {
    tf.transforms.iter().enumerate().find_map(|(k, f)| {
        let (p, r) = (f.translation, f.rotation);
        [
            ("translation.x", p.x),
            ("translation.y", p.y),
            ("translation.z", p.z),
            ("rotation.x", r.x),
            ("rotation.y", r.y),
            ("rotation.z", r.z),
            ("rotation.w", r.w),
        ]
        .into_iter()
        .find(|(_, v)| !v.is_finite())
        .map(|(name, _)| format!("transforms[{k}].{name}"))
    })
}

/// Refuses a message with a NaN or an infinity (a `null` in its JSON), naming the field.
fn check_finite<M: Serialize>(topic: Topic, t: f64, message: &M) -> Result<(), LogError> {
    let what = topic.name();
    let json = serde_json::to_value(message).map_err(|source| LogError::Encode { what, source })?;
    match first_null(&json) {
        None => Ok(()),
        Some(field) => Err(LogError::NonFinite { what, t, field }),
    }
}

/// The path (`entities[0].cubes[1].size.x`) of the first `null` in `value`, if any.
fn first_null(value: &serde_json::Value) -> Option<String> {
    use serde_json::Value;
    match value {
        Value::Null => Some(String::new()),
        Value::Array(items) => (items.iter().enumerate())
            .find_map(|(i, v)| first_null(v).map(|rest| format!("[{i}]{}", dotted(&rest)))),
        Value::Object(fields) => (fields.iter())
            .find_map(|(k, v)| first_null(v).map(|rest| format!("{k}{}", dotted(&rest)))),
        _ => None,
    }
}

/// `rest` as the continuation of a path: `.x`, `[3]`, or nothing.
fn dotted(rest: &str) -> String {
    if rest.is_empty() || rest.starts_with('[') {
        rest.to_owned()
    } else {
        format!(".{rest}")
    }
}

/// The mcap options for `options`: chunked, CRCs and indexes on, deterministic.
fn mcap_options(options: LogOptions) -> mcap::WriteOptions {
    let compression = match options.compression {
        Compression::None => None,
        Compression::Lz4 => Some(mcap::Compression::Lz4),
        #[cfg(feature = "zstd")]
        Compression::Zstd => Some(mcap::Compression::Zstd),
    };
    let opts = mcap::WriteOptions::new()
        .profile("")
        .library(LIBRARY)
        .compression(compression)
        .chunk_size(Some(options.chunk_size.max(1)));
    // zstd's multithreaded mode (mcap's default: one worker per core) is single-threaded
    // here, so that the bytes do not depend on the machine.
    #[cfg(feature = "zstd")]
    let opts = opts.compression_threads(0);
    opts
}

/// The top-level fields of `value` (a JSON object) as keys, each with its compact JSON
/// text as value.
fn json_fields<S: Serialize>(
    what: &'static str,
    value: &S,
) -> Result<BTreeMap<String, String>, LogError> {
    let json = serde_json::to_value(value).map_err(|source| LogError::Encode { what, source })?;
    let serde_json::Value::Object(fields) = json else {
        return Err(LogError::NotAnObject { what });
    };
    (fields.into_iter())
        .map(|(key, value)| {
            let text = serde_json::to_string(&value)
                .map_err(|source| LogError::Encode { what, source })?;
            Ok((key, text))
        })
        .collect()
}
