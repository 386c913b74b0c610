//! [`repair`]: an MCAP file cut short (its writer killed, the machine powered off, the
//! disk full) copied into a finished MCAP file holding every complete message.
//!
//! The input is read linearly from its start, record by record (opcode, length, body:
//! [MCAP, §Records]), with `mcap`'s own reader; the summary section of a complete input is
//! not needed and not read. The records kept are copied, in order, into a new file written
//! by `mcap::Writer` with ricochet's deterministic options.
//!
//! [MCAP] The MCAP file format specification, <https://mcap.dev/spec>.

use std::fmt;
use std::io::{Cursor, Seek, Write};

use mcap::records::op;

use super::LogError;

mod copy;
#[doc(hidden)]
pub mod lz4;
#[doc(hidden)]
pub mod scan;

use copy::{Copier, Survey};
use scan::scan;

/// Bytes of a record before its body: the opcode (1) and the body's length (u64).
const RECORD_PREFIX: usize = 9;

/// How the input of [`repair`] ends: why reading stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum InputEnd {
    /// A finished MCAP file: the data section ends with its Data End record, followed by
    /// the summary section, the footer and the closing magic. Nothing was lost.
    Complete,
    /// The data section ends with its Data End record, but what follows it (the summary
    /// section, the footer, the closing magic) is cut short or damaged. Nothing was lost:
    /// the summary is not needed.
    SummaryDamaged {
        /// Why the summary could not be read.
        error: String,
    },
    /// The input stops right after a whole record of its data section: its writer stopped
    /// between two records (e.g. was killed right after flushing a chunk).
    BetweenRecords,
    /// The input stops inside a record of its data section, at
    /// [`RepairReport::stopped_at`]: typically the chunk being written when the writer was
    /// killed.
    InsideRecord {
        /// The record's opcode (`0x06` for a chunk).
        opcode: u8,
    },
    /// A record of the data section that does not decode, at [`RepairReport::stopped_at`]:
    /// a damaged file, or bytes zeroed by a crash. Nothing after it is read.
    Unreadable {
        /// What is wrong with it.
        error: String,
    },
}

impl InputEnd {
    /// Whether the whole data section was read: nothing was lost.
    pub fn is_complete(&self) -> bool {
        matches!(self, InputEnd::Complete | InputEnd::SummaryDamaged { .. })
    }
}

impl fmt::Display for InputEnd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputEnd::Complete => f.write_str("complete"),
            InputEnd::SummaryDamaged { error } => {
                write!(
                    f,
                    "data section complete, summary cut short or damaged ({error})"
                )
            }
            InputEnd::BetweenRecords => f.write_str("cut short between two records"),
            InputEnd::InsideRecord { opcode } => {
                write!(f, "cut short inside a {} record", record_name(*opcode))
            }
            InputEnd::Unreadable { error } => write!(f, "damaged: unreadable record ({error})"),
        }
    }
}

/// What [`repair`] kept and lost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RepairReport {
    /// How the input ends.
    pub end: InputEnd,
    /// Where reading stopped (byte offset in the input): the end of the data section of a
    /// complete input, else the start of the first record that could not be read whole
    /// (the length of the input if it stops between two records).
    pub stopped_at: u64,
    /// Bytes from `stopped_at` to the end of the input: 0 when the data section is
    /// complete (the summary section is not counted). A chunk cut short counts whole here,
    /// even when messages were salvaged from it.
    pub unused_bytes: u64,
    /// Messages copied.
    pub messages: u64,
    /// Of [`messages`](Self::messages), those salvaged from the chunk at which reading
    /// stopped (cut short or damaged).
    pub salvaged_messages: u64,
    /// Schemas copied.
    pub schemas: u64,
    /// Channels copied.
    pub channels: u64,
    /// Metadata records copied.
    pub metadata: u64,
    /// Attachments copied.
    pub attachments: u64,
    /// Records read but not copied: a message whose channel is unknown at that point, a
    /// channel whose schema is unknown, a schema or channel that redefines an id with other
    /// content, a schema with id 0. None occurs in a file that was merely cut short.
    pub skipped: u64,
}

impl RepairReport {
    /// Whether the whole data section of the input was read (nothing lost).
    pub fn is_complete(&self) -> bool {
        self.end.is_complete()
    }
}

/// Copies every complete record of the MCAP file `input` into a finished MCAP file
/// written to `output`; returns what was kept and lost.
///
/// Made for a file whose writer never finished it (a process killed by `SIGKILL`, a power
/// loss, a full disk): such a file has no summary section, so indexed readers (Foxglove)
/// refuse it, and its last chunk is usually cut short.
///
/// **Recovered**, in file order: the header's profile and library; every schema and
/// channel (with its id), message (with its channel, sequence, log and publish times,
/// payload), metadata record and attachment of the data section, from top-level records
/// and from the records of every complete chunk; then, from the chunk at which reading
/// stops (cut short, or damaged: a bad CRC, bytes zeroed by a crash), every record that
/// decodes whole:
/// - uncompressed chunks: every complete record;
/// - LZ4 chunks: every complete record of the part that decompresses, sequence by
///   sequence, from the bytes present (liblz4's own decoder would stop at the last
///   complete LZ4 block, i.e. usually keep nothing of a torn chunk);
/// - zstd chunks (crate feature `zstd`): what `mcap`'s streaming decoder yields.
///
/// (A ricochet run killed while it logs usually leaves only the opened chunk's header: the
/// LZ4 encoder holds a block back until it is full, i.e. until the chunk is closed. The
/// salvage counts when a chunk was being written out: a full disk, a power loss.)
///
/// **Not recovered**: anything from the first record that cannot be read on (the
/// linear reading stops there, even if whole records follow a damaged one); the part of a
/// record cut short (a message half written is dropped); records that are not copied
/// by nature (message and chunk indexes, statistics, unknown opcodes: the new file has its
/// own indexes and summary). The summary section of a complete input is not read. Records
/// salvaged from a torn chunk are not covered by any CRC (a complete chunk's CRC is
/// checked): if the bytes were damaged rather than cut, they may be wrong.
///
/// **The output** is a finished MCAP file (summary, indexes, CRCs), LZ4-compressed in
/// 64 KiB chunks with the input's profile and library, deterministic (the same input gives
/// the same bytes; repairing a repaired file gives it back unchanged), in which **every
/// chunk holds at least one message**: each schema and channel is written right before the
/// next message after it in the input, so in that message's chunk (those after the last
/// message, right before the last message), and metadata and attachments, which close
/// the current chunk, are written where they were. Readers bundling `@mcap/core` older
/// than 2025 (Foxglove Studio 1.48, say) refuse a chunk without a message index.
/// This also converts a complete ricochet log written before the `repair` module existed,
/// whose first chunk holds only the schemas and channels, into a file that Foxglove
/// Studio 1.48 opens. A file without any message is written without chunks.
///
/// Errors: [`LogError::NotMcap`] when `input` is not an MCAP file (empty, no magic, no
/// whole header record); [`LogError::Mcap`] when writing `output` fails.
///
/// Cost: `input` is read twice (a survey, then the copy), one chunk decompressed at a
/// time; the output is written as it goes.
///
/// ```
/// use ricochet::log::{InputEnd, LogOptions, LogWriter, repair_bytes};
/// # fn main() -> Result<(), ricochet::log::LogError> {
/// let mut log = LogWriter::new(std::io::Cursor::new(Vec::new()), LogOptions::default())?;
/// log.scene("ball", "name = \"ball\"\n")?;
/// let whole = log.finish()?.into_inner();
/// // Cut inside the summary section: nothing of the data is lost.
/// let (fixed, report) = repair_bytes(&whole[..whole.len() - 30])?;
/// assert!(matches!(report.end, InputEnd::SummaryDamaged { .. }));
/// // The `ricochet` (format version) and `scene` records.
/// assert!(report.is_complete() && report.metadata == 2);
/// assert!(mcap::Summary::read(&fixed).is_ok());
/// # Ok(())
/// # }
/// ```
pub fn repair<W: Write + Seek>(input: &[u8], output: W) -> Result<RepairReport, LogError> {
    // 1. Survey: the header, the messages that can be copied, the schemas and channels
    //    that no message follows, the size of all schemas and channels.
    let mut survey = Survey::default();
    let scanned = scan(input, &mut |record, _| {
        survey.see(record);
        Ok(())
    })?;
    // 2. Copy, in a second reading, the same records in the same order.
    let mut copy = Copier::new(output, &scanned.header, survey)?;
    scan(input, &mut |record, salvaged| copy.record(record, salvaged))?;
    let counts = copy.finish()?;
    let unused_bytes = (input.len() as u64).saturating_sub(scanned.stopped_at);
    Ok(RepairReport {
        unused_bytes: if scanned.end.is_complete() {
            0
        } else {
            unused_bytes
        },
        end: scanned.end,
        stopped_at: scanned.stopped_at,
        messages: counts.messages,
        salvaged_messages: counts.salvaged_messages,
        schemas: counts.schemas,
        channels: counts.channels,
        metadata: counts.metadata,
        attachments: counts.attachments,
        skipped: counts.skipped,
    })
}

/// [`repair`] into memory: the repaired file's bytes and the report.
pub fn repair_bytes(input: &[u8]) -> Result<(Vec<u8>, RepairReport), LogError> {
    let mut output = Cursor::new(Vec::new());
    let report = repair(input, &mut output)?;
    Ok((output.into_inner(), report))
}

/// The name of a record type [MCAP, §Records], for messages.
fn record_name(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "header",
        op::FOOTER => "footer",
        op::SCHEMA => "schema",
        op::CHANNEL => "channel",
        op::MESSAGE => "message",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index",
        op::CHUNK_INDEX => "chunk index",
        op::ATTACHMENT => "attachment",
        op::ATTACHMENT_INDEX => "attachment index",
        op::STATISTICS => "statistics",
        op::METADATA => "metadata",
        op::METADATA_INDEX => "metadata index",
        op::SUMMARY_OFFSET => "summary offset",
        op::DATA_END => "data end",
        _ => "unknown",
    }
}
