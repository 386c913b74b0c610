//! [`LogWriter`]: a thin adaptor over `mcap::Writer` that registers ricochet's schemas and
//! channels once, then writes messages to known channels: ricochet's records as JSON,
//! Foxglove's types protobuf-encoded by Foxglove's SDK.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

use mcap::records::{MessageHeader, Metadata};
use serde::Serialize;

use super::LogError;
use super::draw::ArrowStyle;
use super::foxglove::{
    Encode, FrameTransforms, Log, LogLevel, SceneUpdate, append_frame_transforms, append_protobuf,
    first_non_finite_scene, first_non_finite_transforms, nanoseconds, timestamp,
};
use super::records::{Audit, ImpactRecord, StateRecord};
use super::samples::plain_transforms;
use super::schemas::{FORMAT_VERSION, Topic, metadata};
use super::sink::{ChannelSpec, Sink, append_json};

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
    /// Target size of the messages of the first chunks before compression (bytes); it
    /// doubles after every 1,024 chunks, up to 4 MiB (the writer keeps an index of every
    /// chunk in memory until the end). A process killed without finishing the file loses
    /// at most the chunk being written, unless [`LogWriter::flush`] was called since.
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
/// The six channels of [`Topic::ALL`] have fixed ids (1 to 6, in that order); their
/// schemas and channels are written right before the first message, in its chunk, so that
/// no chunk of the file is without messages (see `sink.rs`). Each method writes one
/// message to its known channel, with `log_time = publish_time =` the simulated time in
/// nanoseconds ([`nanoseconds`]: a time that is negative, NaN, infinite or beyond `2³²` s
/// is refused with [`LogError::InvalidTime`]). Messages holding a NaN or an infinity are
/// refused with [`LogError::NonFinite`] naming the field. A refused message is not
/// written, and the writer stays usable.
///
/// Messages are encoded on the calling thread (a `/state` or `/tf` sample is copied as its
/// numbers unless the writer thread is behind, an impact's three messages as its record,
/// and encoded on the writer thread) and handed in batches, in order, through a bounded channel to the
/// thread of the `mcap::Writer`, which compresses the chunks and writes them out, so that
/// logging overlaps with the simulation and the bytes are the same as a single-threaded
/// writer's (see `sink.rs`). An I/O error is therefore reported by the call after the one whose message
/// met it (or by `flush`, `finish`).
///
/// Ending a run: call [`finish`](LogWriter::finish), which writes the summary section and
/// reports any I/O error. If the writer is dropped instead (an early return on error, a
/// panic unwinding), `mcap::Writer`'s `Drop` still finishes the file, ignoring errors: the
/// log is a valid MCAP file holding everything written so far (dropping waits for the
/// writer thread). A process that is killed outright leaves a file without a summary;
/// [`read`](super::read()) still reads it up to the last complete chunk, and
/// [`repair`](super::repair()) makes it a finished file; call
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
    /// Next sequence number of each topic, indexed by [`Topic::index`].
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
    /// Starts a log in `writer`: the MCAP header and the `ricochet` metadata record (the
    /// log format version); the channels follow with the first message.
    pub fn new(writer: W, options: LogOptions) -> Result<Self, LogError> {
        let mut mcap = mcap_options(options).create(writer)?;
        mcap.write_metadata(&Metadata {
            name: metadata::RICOCHET.to_owned(),
            metadata: BTreeMap::from([
                ("format_version".to_owned(), FORMAT_VERSION.to_string()),
                ("version".to_owned(), env!("CARGO_PKG_VERSION").to_owned()),
            ]),
        })?;
        let channels = (Topic::ALL.into_iter())
            .map(|topic| ChannelSpec {
                id: channel_id(topic),
                topic,
            })
            .collect();
        Ok(LogWriter {
            mcap: Sink::spawn(mcap, channels, options.chunk_size)?,
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

    /// Writes one `/state` sample at its time `state.t`.
    pub fn state(&mut self, state: &StateRecord) -> Result<(), LogError> {
        if let Some(field) = state.first_non_finite() {
            return Err(LogError::NonFinite {
                what: Topic::State.name(),
                t: state.t,
                field,
            });
        }
        let time = nanoseconds(state.t)?;
        if self.mcap.defers_samples() {
            let header = self.header(Topic::State, time);
            self.mcap.push_state(header, state)?;
            self.advance(Topic::State);
            return Ok(());
        }
        let start = self.mcap.buffer().len();
        state.append_json(self.mcap.buffer());
        self.push(Topic::State, time, start)
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
        let time = nanoseconds(impact.t)?;
        let start = self.mcap.buffer().len();
        append_json(self.mcap.buffer(), Topic::Impacts, impact)?;
        self.push(Topic::Impacts, time, start)
    }

    /// Writes an impact: its ledger entry on `/impacts`, its arrow on `/scene`
    /// ([`draw::impulse_arrow`](super::draw::impulse_arrow), `length` m long in `style`)
    /// and its line on `/log`, all at `impact.t`. The record is copied; the three messages
    /// are encoded on the writer thread.
    pub fn impact_drawn(
        &mut self,
        impact: &ImpactRecord,
        (length, style): (f64, ArrowStyle),
    ) -> Result<(), LogError> {
        if let Some(field) = impact.first_non_finite() {
            return Err(LogError::NonFinite {
                what: Topic::Impacts.name(),
                t: impact.t,
                field,
            });
        }
        let c = style.color;
        let numbers = [length, style.length, style.elevation, c.r, c.g, c.b, c.a];
        if !numbers.iter().all(|x| x.is_finite()) {
            // The slow path names the field.
            let update = super::sink::arrow_update(impact, (length, style))?;
            let field = first_non_finite_scene(&update).unwrap_or_default();
            return Err(LogError::NonFinite {
                what: Topic::Scene.name(),
                t: impact.t,
                field,
            });
        }
        let time = nanoseconds(impact.t)?;
        let topics = [Topic::Impacts, Topic::Scene, Topic::Log];
        let headers = topics.map(|topic| self.header(topic, time));
        self.mcap.push_impact(headers, impact, (length, style))?;
        for topic in topics {
            self.advance(topic);
        }
        Ok(())
    }

    /// Writes the drawing of every body and obstacle on `/geometry` at simulated time `t`
    /// (s). The entities carry their own timestamps, which the 3-D panel uses.
    pub fn geometry(&mut self, t: f64, update: &SceneUpdate) -> Result<(), LogError> {
        self.scene_on(Topic::Geometry, t, update)
    }

    /// Writes transient drawings (impulse arrows) on `/scene` at simulated time `t` (s).
    pub fn scene_update(&mut self, t: f64, update: &SceneUpdate) -> Result<(), LogError> {
        self.scene_on(Topic::Scene, t, update)
    }

    /// Writes frame transforms on `/tf` at simulated time `t` (s).
    pub fn transforms(&mut self, t: f64, transforms: &FrameTransforms) -> Result<(), LogError> {
        let time = nanoseconds(t)?;
        if let Some(field) = first_non_finite_transforms(transforms) {
            return Err(LogError::NonFinite {
                what: Topic::Tf.name(),
                t,
                field,
            });
        }
        if self.mcap.defers_samples() && plain_transforms(transforms) {
            let header = self.header(Topic::Tf, time);
            self.mcap.push_transforms(header, transforms)?;
            self.advance(Topic::Tf);
            return Ok(());
        }
        let start = self.mcap.buffer().len();
        append_frame_transforms(self.mcap.buffer(), transforms);
        self.push(Topic::Tf, time, start)
    }

    /// Writes the planar frame transforms of `layout` on `/tf` at simulated time `t` (s),
    /// each frame's numbers `[x, y, cos θ, sin θ]` from `frames` (one per transform of
    /// `layout`, in order): each transform at time `t`, translated by `(x, y, 0)` and
    /// rotated by [`about_z`](super::foxglove::about_z)`(atan2(sin θ, cos θ))`, byte for
    /// byte what [`transforms`](Self::transforms) writes for those transforms. The
    /// numbers are handed to the writer thread, which computes the rotations and encodes
    /// the message (issue 16).
    ///
    /// Returns `false`, writing nothing, if the writer thread is behind (see
    /// `Sink::defers_samples`) or a number is not finite: the caller then writes the
    /// transforms with [`transforms`](Self::transforms), which encodes them on this
    /// thread or refuses them naming the non-finite field.
    pub(crate) fn planar_transforms(
        &mut self,
        t: f64,
        layout: &FrameTransforms,
        frames: impl Iterator<Item = [f64; 4]>,
    ) -> Result<bool, LogError> {
        if !self.mcap.defers_samples() {
            return Ok(false);
        }
        let time = nanoseconds(t)?;
        let header = self.header(Topic::Tf, time);
        let taken = self.mcap.push_planar(header, layout, time, frames)?;
        if taken {
            self.advance(Topic::Tf);
        }
        Ok(taken)
    }

    /// Writes a text message on `/log` at simulated time `t` (s), from `ricochet`.
    pub fn log(&mut self, t: f64, level: LogLevel, message: &str) -> Result<(), LogError> {
        self.log_message(&log_message(t, level, message)?)
    }

    /// Writes `log` on `/log` at its timestamp.
    pub fn log_message(&mut self, log: &Log) -> Result<(), LogError> {
        let t = log.timestamp.as_ref().map_or(0.0, super::foxglove::seconds);
        self.write_protobuf(Topic::Log, t, log)
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

    /// Tests: samples as numbers (`Some(true)`), encoded here (`Some(false)`), or as the
    /// writer thread's progress decides (`None`).
    #[doc(hidden)]
    pub fn defer_samples(&mut self, defer: Option<bool>) {
        self.mcap.defer = defer;
    }

    /// A scene update on `topic`, refused if it holds a NaN or an infinity.
    fn scene_on(&mut self, topic: Topic, t: f64, update: &SceneUpdate) -> Result<(), LogError> {
        if let Some(field) = first_non_finite_scene(update) {
            return Err(LogError::NonFinite {
                what: topic.name(),
                t,
                field,
            });
        }
        self.write_protobuf(topic, t, update)
    }

    /// Encodes `message` as protobuf and writes it on `topic` at simulated time `t` (s).
    fn write_protobuf<M: Encode>(
        &mut self,
        topic: Topic,
        t: f64,
        message: &M,
    ) -> Result<(), LogError> {
        let time = nanoseconds(t)?;
        let start = self.mcap.buffer().len();
        append_protobuf(self.mcap.buffer(), topic.name(), message)?;
        self.push(topic, time, start)
    }

    /// Hands the message encoded from `start` on to the sink, on `topic` at `time` (ns).
    fn push(&mut self, topic: Topic, time: u64, start: usize) -> Result<(), LogError> {
        let header = self.header(topic, time);
        self.mcap.push(header, start)?;
        self.advance(topic);
        Ok(())
    }

    /// The header of the next message on `topic` at `time` (ns).
    fn header(&self, topic: Topic, time: u64) -> MessageHeader {
        let i = topic.index();
        MessageHeader {
            channel_id: channel_id(topic),
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

/// The `/log` message `message` from `ricochet`, at simulated time `t` (s).
pub fn log_message(t: f64, level: LogLevel, message: &str) -> Result<Log, LogError> {
    Ok(Log {
        timestamp: Some(timestamp(t)?),
        level: level as i32,
        message: message.to_owned(),
        name: "ricochet".to_owned(),
        file: String::new(),
        line: 0,
    })
}

/// The channel id of `topic`: its position in [`Topic::ALL`], from 1.
fn channel_id(topic: Topic) -> u16 {
    topic.index() as u16 + 1
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
        // The sink closes the chunks (see `sink.rs`): mcap's own limit could close a chunk
        // holding only schemas and channels.
        .chunk_size(None);
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
