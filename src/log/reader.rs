//! Reading a ricochet log back: the metadata, the impact ledger and message counts, from
//! the log alone, as far as the file goes.
//!
//! The file is read linearly from the start (the summary section is not needed), so a
//! file whose writer was killed before finishing it is read up to its last complete
//! record; [`RunLog::ending`] says whether the file was complete.

use std::collections::BTreeMap;
use std::path::Path;

use mcap::records::{Metadata, Record};
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

use super::LogError;
use super::records::{Audit, ImpactRecord, StateRecord};
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
    /// The file ends with its summary section, footer and magic: the writer finished it.
    Complete,
    /// The file stops early or is damaged, e.g. the process writing it was killed.
    /// Everything before the first unreadable record was read.
    Truncated {
        /// Offset of the end of the last record read (bytes).
        offset: u64,
        /// Why reading stopped.
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
/// (a metadata record, an `/impacts` or `/state` message) does not decode. A file that
/// stops early is not an error: the result holds what was read and
/// [`Ending::Truncated`].
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
    let mut topics: BTreeMap<u16, String> = BTreeMap::new();
    let mut last_state: Option<Vec<u8>> = None;
    let records = mcap::read::ChunkFlattener::new(bytes)?;
    let mut first = true;
    for record in records {
        let record = match record {
            Ok(record) => record,
            // Not even a header: not an MCAP file.
            Err(err) if first => return Err(LogError::Mcap(err)),
            Err(err) => {
                log.ending = Ending::Truncated {
                    offset: 0,
                    error: err.to_string(),
                };
                break;
            }
        };
        first = false;
        match record {
            Record::Header(header) => log.library = header.library,
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
                        last_state = Some(data.into_owned());
                    }
                    _ => {}
                }
            }
            Record::Metadata(m) => read_metadata(&mut log, m)?,
            _ => {}
        }
    }
    if let Ending::Truncated { offset, .. } = &mut log.ending {
        *offset = truncation_offset(bytes);
    }
    if let Some(data) = last_state {
        log.last_state = Some(decode(Topic::State.name(), &data)?);
    }
    Ok(log)
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

/// The offset just past the last complete top-level record of `bytes` (after the magic).
fn truncation_offset(bytes: &[u8]) -> u64 {
    let mut offset = mcap::MAGIC.len() as u64;
    let mut rest = bytes.get(mcap::MAGIC.len()..).unwrap_or_default();
    // A record is an opcode (1 byte), a length (u64 LE) and that many bytes.
    while rest.len() >= 9 {
        let mut len = [0u8; 8];
        len.copy_from_slice(&rest[1..9]);
        let Some(end) = usize::try_from(u64::from_le_bytes(len))
            .ok()
            .and_then(|len| len.checked_add(9))
            .filter(|&end| end <= rest.len())
        else {
            break;
        };
        offset += end as u64;
        rest = &rest[end..];
    }
    offset
}
