//! Writing the records kept into a new MCAP file, so that every chunk holds a message.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::{Seek, Write};

use mcap::records::{self, Record};
use mcap::{McapError, Schema};

use super::RECORD_PREFIX;
use crate::log::LogError;

/// Target size of a chunk of the repaired file before compression (bytes), as in
/// [`LogOptions::default`](crate::log::LogOptions).
const CHUNK_SIZE: u64 = 64 * 1024;

/// A schema or a channel, owned.
#[derive(Clone)]
enum Registration {
    Schema(Schema<'static>),
    Channel(records::Channel),
}

impl Registration {
    /// The schema or channel of `record`, if it is one.
    fn of(record: Record<'_>) -> Option<Self> {
        match record {
            Record::Schema { header, data } => Some(Registration::Schema(Schema {
                id: header.id,
                name: header.name,
                encoding: header.encoding,
                data: Cow::Owned(data.into_owned()),
            })),
            Record::Channel(channel) => Some(Registration::Channel(channel)),
            _ => None,
        }
    }

    /// Size of the record as written (bytes) [MCAP, §Schema, §Channel].
    fn size(&self) -> u64 {
        let string = |s: &str| 4 + s.len() as u64;
        RECORD_PREFIX as u64
            + match self {
                Registration::Schema(s) => {
                    2 + string(&s.name) + string(&s.encoding) + 4 + s.data.len() as u64
                }
                Registration::Channel(c) => {
                    let metadata: u64 = (c.metadata.iter())
                        .map(|(k, v)| string(k) + string(v))
                        .sum();
                    2 + 2 + string(&c.topic) + string(&c.message_encoding) + 4 + metadata
                }
            }
    }
}

/// What to do with a schema or a channel.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Admission {
    /// Write it.
    New,
    /// Already written, with the same content: nothing to do.
    Known,
    /// Skip it: it would be refused by `mcap::Writer` (schema id 0, unknown schema, an id
    /// redefined with other content).
    Refused,
}

/// The schemas and channels admitted so far, by id: the rules of `mcap::Writer`'s
/// `add_schema_with_id` and `add_channel_with_id`, applied before calling them, the same
/// way in both readings.
#[derive(Default)]
struct Registry {
    schemas: BTreeMap<u16, Schema<'static>>,
    channels: BTreeMap<u16, records::Channel>,
}

impl Registry {
    fn admit(&mut self, registration: &Registration) -> Admission {
        match registration {
            Registration::Schema(s) if s.id == 0 => Admission::Refused,
            Registration::Schema(s) => admit_in(&mut self.schemas, s.id, s),
            Registration::Channel(c)
                if c.schema_id != 0 && !self.schemas.contains_key(&c.schema_id) =>
            {
                Admission::Refused
            }
            Registration::Channel(c) => admit_in(&mut self.channels, c.id, c),
        }
    }

    fn has_channel(&self, id: u16) -> bool {
        self.channels.contains_key(&id)
    }
}

/// Admits `item` under `id` in `known`: new, the same as before, or a conflicting one.
fn admit_in<T: Clone + PartialEq>(known: &mut BTreeMap<u16, T>, id: u16, item: &T) -> Admission {
    match known.get(&id) {
        None => {
            known.insert(id, item.clone());
            Admission::New
        }
        Some(k) if k == item => Admission::Known,
        Some(_) => Admission::Refused,
    }
}

/// What the first reading learns for the second.
#[derive(Default)]
pub(super) struct Survey {
    registry: Registry,
    /// Messages that will be copied.
    messages: u64,
    /// Schemas and channels admitted after the last of those messages, in file order.
    trailing: Vec<Registration>,
    /// Size of all admitted schemas and channels as written (bytes).
    registration_bytes: u64,
}

impl Survey {
    /// Takes `record` into account.
    pub(super) fn see(&mut self, record: Record<'_>) {
        if let Record::Message { header, .. } = &record {
            if self.registry.has_channel(header.channel_id) {
                self.messages += 1;
                self.trailing.clear();
            }
        } else if let Some(registration) = Registration::of(record)
            && self.registry.admit(&registration) == Admission::New
        {
            self.registration_bytes += registration.size();
            self.trailing.push(registration);
        }
    }
}

/// Counts of what was copied.
#[derive(Default)]
pub(super) struct Counts {
    pub(super) messages: u64,
    pub(super) salvaged_messages: u64,
    pub(super) schemas: u64,
    pub(super) channels: u64,
    pub(super) metadata: u64,
    pub(super) attachments: u64,
    pub(super) skipped: u64,
}

/// The second reading: copies records into an `mcap::Writer`.
pub(super) struct Copier<W: Write + Seek> {
    writer: mcap::Writer<W>,
    registry: Registry,
    /// Schemas and channels admitted but not written yet: they go right before the next
    /// message.
    pending: Vec<Registration>,
    /// Whether schemas and channels wait for a message (the file has some).
    lazy: bool,
    /// From the survey: schemas and channels that no message follows, written before the
    /// last message.
    trailing: Vec<Registration>,
    /// Messages still to copy.
    messages_left: u64,
    counts: Counts,
}

impl<W: Write + Seek> Copier<W> {
    pub(super) fn new(
        output: W,
        header: &records::Header,
        survey: Survey,
    ) -> Result<Self, LogError> {
        let lazy = survey.messages > 0;
        // The chunk that schemas and channels open is never closed before the message
        // that follows them, since they fit in it: a chunk is closed before a message
        // only if it already holds more than the chunk size.
        let chunk_size = CHUNK_SIZE.max(survey.registration_bytes);
        // ricochet's deterministic options (`writer.rs`), with the input's header. A file
        // without messages has no chunk at all.
        let writer = mcap::WriteOptions::new()
            .profile(header.profile.clone())
            .library(header.library.clone())
            .compression(Some(mcap::Compression::Lz4))
            .chunk_size(Some(chunk_size))
            .use_chunks(lazy)
            .create(output)?;
        Ok(Copier {
            writer,
            registry: Registry::default(),
            pending: Vec::new(),
            lazy,
            trailing: survey.trailing,
            messages_left: survey.messages,
            counts: Counts::default(),
        })
    }

    /// Copies `record` (or schedules it, for a schema or a channel).
    pub(super) fn record(&mut self, record: Record<'_>, salvaged: bool) -> Result<(), LogError> {
        match record {
            Record::Message { header, data } => {
                if !self.registry.has_channel(header.channel_id) || self.messages_left == 0 {
                    self.counts.skipped += 1;
                    return Ok(());
                }
                if self.messages_left == 1 {
                    for registration in std::mem::take(&mut self.trailing) {
                        self.schedule(registration)?;
                    }
                }
                for registration in std::mem::take(&mut self.pending) {
                    self.register(&registration)?;
                }
                self.writer.write_to_known_channel(&header, &data)?;
                self.messages_left -= 1;
                self.counts.messages += 1;
                self.counts.salvaged_messages += u64::from(salvaged);
            }
            Record::Metadata(metadata) => {
                self.writer.write_metadata(&metadata)?;
                self.counts.metadata += 1;
            }
            Record::Attachment { header, data, .. } => {
                self.writer.attach(&mcap::Attachment {
                    log_time: header.log_time,
                    create_time: header.create_time,
                    name: header.name,
                    media_type: header.media_type,
                    data,
                })?;
                self.counts.attachments += 1;
            }
            record => {
                if let Some(registration) = Registration::of(record) {
                    self.schedule(registration)?;
                }
            }
        }
        Ok(())
    }

    /// Admits a schema or channel: holds it for the next message, or writes it at once in
    /// a file without messages.
    fn schedule(&mut self, registration: Registration) -> Result<(), LogError> {
        match self.registry.admit(&registration) {
            Admission::New if self.lazy => self.pending.push(registration),
            Admission::New => self.register(&registration)?,
            Admission::Known => {}
            Admission::Refused => self.counts.skipped += 1,
        }
        Ok(())
    }

    /// Writes a schema or a channel, with its id.
    fn register(&mut self, registration: &Registration) -> Result<(), LogError> {
        match registration {
            Registration::Schema(s) => {
                (self.writer).add_schema_with_id(s.id, &s.name, &s.encoding, &s.data)?;
                self.counts.schemas += 1;
            }
            Registration::Channel(c) => {
                let (topic, encoding) = (&c.topic, &c.message_encoding);
                (self.writer).add_channel_with_id(
                    c.id,
                    c.schema_id,
                    topic,
                    encoding,
                    &c.metadata,
                )?;
                self.counts.channels += 1;
            }
        }
        Ok(())
    }

    /// Finishes the file. Schemas and channels still pending (a channel after the last
    /// message whose schema came after it) are skipped: they would make a chunk without
    /// messages.
    pub(super) fn finish(mut self) -> Result<Counts, LogError> {
        self.counts.skipped += self.pending.len() as u64;
        self.writer.finish()?;
        let mut output = self.writer.into_inner();
        output.flush().map_err(McapError::from)?;
        Ok(self.counts)
    }
}
