//! Reading a ricochet log back: the metadata, the impact ledger and message counts, from
//! the log alone, as far as the file goes.
//!
//! The file is read linearly from the start (the summary section is not needed), so a
//! file whose writer was killed before finishing it is read up to its last complete
//! record (with those of a chunk cut short, as far as they decode); [`RunLog::ending`] says whether the file was complete. The file is untrusted:
//! it is read by the linear reading of [`repair`](super::repair), which sizes no
//! allocation from a length field beyond what the file's bytes can hold and checks every
//! CRC (chunks, data section, summary), so that a damaged byte is reported as
//! [`Ending::Damaged`], never a panic or an abort.

use std::collections::BTreeMap;
use std::path::Path;

use mcap::records::{Metadata, Record};
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

use super::LogError;
use super::records::{Audit, ImpactRecord, StateRecord};
use super::repair::InputEnd;
use super::repair::scan::scan;
use super::schemas::{Topic, metadata};

/// The `scene` metadata of a log.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneInfo {
    /// The scene's name.
    pub name: String,
    /// The scene file, verbatim.
    pub text: String,
}

/// How a log file ends.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Ending {
    /// The file ends with its summary section, footer and magic, and every CRC matches:
    /// the writer finished it and nothing was changed since.
    Complete,
    /// The file stops early, e.g. the process writing it was killed. Everything before the
    /// first record cut short was read.
    Truncated {
        /// Offset of the end of the last record read (bytes).
        offset: u64,
        /// Why reading stopped.
        error: String,
    },
    /// A record of the file does not decode, or a CRC does not match its bytes: the file
    /// was damaged after it was written. Everything before the damaged record was read;
    /// when it is the data section's CRC that fails (checked at its end), some record read
    /// was damaged but none can tell which (the records of chunks are covered by their
    /// chunk's CRC, the metadata records only by the data section's).
    Damaged {
        /// Offset of the record that does not decode, or of the end of the data section
        /// (bytes).
        offset: u64,
        /// What is wrong.
        error: String,
    },
}

/// What a ricochet log holds, as read back by [`read`] or [`read_bytes`].
#[derive(Clone, Debug, PartialEq)]
pub struct RunLog {
    /// The `library` field of the MCAP header (e.g. `ricochet 0.1.0`).
    pub library: String,
    /// The log format version, from the `ricochet` metadata record; logs written before
    /// the record existed are of version 1.
    pub format_version: u32,
    /// The scene, if the `scene` metadata record was read.
    pub scene: Option<SceneInfo>,
    /// The settings, if the `settings` metadata record was read: one entry per top-level
    /// field.
    pub settings: Option<Map<String, Value>>,
    /// The energy audit, if the `audit` metadata record was read. A log without it is of a
    /// run that stopped before its end (an error, an interruption, a killed process).
    pub audit: Option<Audit>,
    /// Every `/impacts` message, in file order.
    pub impacts: Vec<ImpactRecord>,
    /// The last `/state` sample read.
    pub last_state: Option<StateRecord>,
    /// Number of messages read per topic (every channel in the file, ricochet's or not).
    pub message_counts: BTreeMap<String, u64>,
    /// Smallest and largest message log time (s), if any message was read.
    pub time_range: Option<(f64, f64)>,
    /// Whether the whole file was read.
    pub ending: Ending,
}

impl RunLog {
    /// Number of messages read on `topic`.
    pub fn count(&self, topic: Topic) -> u64 {
        self.message_counts.get(topic.name()).copied().unwrap_or(0)
    }
}

/// Reads the log at `path` (see [`read_bytes`]).
pub fn read(path: impl AsRef<Path>) -> Result<RunLog, LogError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| LogError::Open {
        path: path.to_owned(),
        source,
    })?;
    read_bytes(&bytes)
}

/// Reads the log at `path` as [`read_bytes_with`] does.
pub fn read_with(
    path: impl AsRef<Path>,
    on_state: &mut dyn FnMut(StateRecord),
) -> Result<RunLog, LogError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| LogError::Open {
        path: path.to_owned(),
        source,
    })?;
    read_bytes_with(&bytes, on_state)
}

/// Reads a log held in memory, as [`read_bytes`] does, and hands every `/state` sample
/// to `on_state`, in file order, as it is read (a long log's samples are not all held
/// at once).
pub fn read_bytes_with(
    bytes: &[u8],
    on_state: &mut dyn FnMut(StateRecord),
) -> Result<RunLog, LogError> {
    read_log(bytes, Some(on_state))
}

/// Reads a log held in memory, as far as it goes.
///
/// Errors only when the bytes are not an MCAP file at all, or when a record of ricochet's
/// (a metadata record, an `/impacts` or `/state` message) does not decode, or a message
/// is on a channel that was not declared. A file that stops early or is damaged is not an
/// error: the result holds what was read and [`Ending::Truncated`] or
/// [`Ending::Damaged`].
///
/// Memory: the records of one chunk at a time, decompressed; no allocation beyond 256
/// times the length of `bytes` (LZ4's largest expansion), whatever its length fields say.
///
/// Numbers decode bit-exactly only when `serde_json`'s `float_roundtrip` feature is on
/// (the tests have it, through the `jsonschema` dev-dependency); without it about 7 % of
/// arbitrary `f64`s come back one ulp off.
pub fn read_bytes(bytes: &[u8]) -> Result<RunLog, LogError> {
    read_log(bytes, None)
}

/// Reads a log, decoding every `/state` sample for `on_state` if given, else only the
/// last.
fn read_log(
    bytes: &[u8],
    mut on_state: Option<&mut dyn FnMut(StateRecord)>,
) -> Result<RunLog, LogError> {
    let mut log = RunLog {
        library: String::new(),
        format_version: 1,
        scene: None,
        settings: None,
        audit: None,
        impacts: vec![],
        last_state: None,
        message_counts: BTreeMap::new(),
        time_range: None,
        ending: Ending::Complete,
    };
    let mut reading = Reading::default();
    // The records of the chunk at which reading stopped (as far as they decode) are kept
    // aside until it is known whether the chunk was cut short (they are what was written)
    // or damaged (they may not be).
    let mut salvaged = vec![];
    let scanned = scan(bytes, &mut |record, torn| {
        if torn {
            salvaged.push(record.into_owned());
            Ok(())
        } else {
            reading.record(&mut log, record, &mut on_state)
        }
    })?;
    if matches!(scanned.end, InputEnd::InsideRecord { .. }) {
        for record in salvaged {
            reading.record(&mut log, record, &mut on_state)?;
        }
    }
    log.library = scanned.header.library;
    log.ending = ending(bytes, scanned.end, scanned.stopped_at);
    if let Some(data) = reading.last_state {
        log.last_state = Some(decode(Topic::State.name(), &data)?);
    }
    Ok(log)
}

/// What [`read_bytes`] keeps between records.
#[derive(Default)]
struct Reading {
    /// The topic of each channel id.
    topics: BTreeMap<u16, String>,
    /// The payload of the last `/state` message.
    last_state: Option<Vec<u8>>,
}

impl Reading {
    /// Reads a channel, message or metadata record into `log`.
    fn record(
        &mut self,
        log: &mut RunLog,
        record: Record<'_>,
        on_state: &mut Option<&mut dyn FnMut(StateRecord)>,
    ) -> Result<(), LogError> {
        let Reading { topics, last_state } = self;
        match record {
            Record::Channel(channel) => {
                topics.insert(channel.id, channel.topic);
            }
            Record::Message { header, data } => {
                let topic = topics.get(&header.channel_id).ok_or_else(|| {
                    LogError::Mcap(mcap::McapError::UnknownChannel(
                        header.sequence,
                        header.channel_id,
                    ))
                })?;
                *log.message_counts.entry(topic.clone()).or_default() += 1;
                let t = header.log_time as f64 / 1e9;
                log.time_range = Some(match log.time_range {
                    None => (t, t),
                    Some((a, b)) => (a.min(t), b.max(t)),
                });
                match Topic::from_name(topic) {
                    Some(Topic::Impacts) => log.impacts.push(decode(Topic::Impacts.name(), &data)?),
                    Some(Topic::State) => {
                        if let Some(f) = on_state.as_mut() {
                            f(decode(Topic::State.name(), &data)?);
                        }
                        *last_state = Some(data.into_owned());
                    }
                    _ => {}
                }
            }
            Record::Metadata(m) => read_metadata(log, m)?,
            _ => {}
        }
        Ok(())
    }
}

/// How a file read by [`scan`] ends, from how its reading stopped at `offset`.
fn ending(bytes: &[u8], end: InputEnd, offset: u64) -> Ending {
    match end {
        InputEnd::Complete => Ending::Complete,
        // The data was all read; what follows it is cut short, or damaged if the file
        // still ends with the magic.
        InputEnd::SummaryDamaged { error } if bytes.ends_with(mcap::MAGIC) => Ending::Damaged {
            offset,
            error: format!("the summary section: {error}"),
        },
        InputEnd::Unreadable { error } => Ending::Damaged { offset, error },
        end => Ending::Truncated {
            offset,
            error: end.to_string(),
        },
    }
}

/// Stores a metadata record of ricochet's in `log`; ignores others.
fn read_metadata(log: &mut RunLog, m: Metadata) -> Result<(), LogError> {
    match m.name.as_str() {
        metadata::RICOCHET => {
            let version = m.metadata.get("format_version").map(String::as_str);
            log.format_version =
                (version.and_then(|v| v.parse().ok())).ok_or_else(|| LogError::BadMetadata {
                    what: format!("{}.format_version", metadata::RICOCHET),
                    value: version.unwrap_or_default().to_owned(),
                })?;
        }
        metadata::SCENE => {
            let mut map = m.metadata;
            log.scene = Some(SceneInfo {
                name: map.remove("name").unwrap_or_default(),
                text: map.remove("text").unwrap_or_default(),
            });
        }
        metadata::SETTINGS => log.settings = Some(json_fields(metadata::SETTINGS, m.metadata)?),
        metadata::AUDIT => {
            let fields = json_fields(metadata::AUDIT, m.metadata)?;
            log.audit = Some(
                serde_json::from_value(Value::Object(fields)).map_err(|source| {
                    LogError::Decode {
                        what: metadata::AUDIT.to_owned(),
                        source,
                    }
                })?,
            );
        }
        _ => {}
    }
    Ok(())
}

/// The values of a metadata record written by `json_fields` of the writer: each a JSON
/// text.
fn json_fields(what: &str, map: BTreeMap<String, String>) -> Result<Map<String, Value>, LogError> {
    (map.into_iter())
        .map(|(key, text)| {
            let value = serde_json::from_str(&text).map_err(|source| LogError::Decode {
                what: format!("{what}.{key}"),
                source,
            })?;
            Ok((key, value))
        })
        .collect()
}

fn decode<T: DeserializeOwned>(what: &str, data: &[u8]) -> Result<T, LogError> {
    serde_json::from_slice(data).map_err(|source| LogError::Decode {
        what: what.to_owned(),
        source,
    })
}
