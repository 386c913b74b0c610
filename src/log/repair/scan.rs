//! Reading an MCAP file linearly, as far as it goes: its top-level records with `mcap`'s
//! reader, the records of its complete chunks with `mcap`'s decompressors, and those of
//! the chunk at which reading stops (cut short or damaged) as far as they decode. Shared
//! by [`repair`](super::repair) and [`read`](crate::log::read) (`ricochet inspect`).
//!
//! The file is untrusted: no allocation is sized from one of its length fields beyond what
//! the bytes present can hold. `mcap`'s readers are given a record length limit (the
//! input's size; for the records of a chunk, its uncompressed size clamped to what its
//! compressed bytes can expand to), and every record is checked field by field
//! ([`check_layout`]) before `mcap`'s parser sees it, which reserves a string's length
//! field (up to 4 GiB) before reading the string. The CRCs of the chunks, of the data
//! section and of the summary section are checked, so that a damaged byte anywhere is
//! reported.

use std::ops::ControlFlow;

use mcap::McapError;
use mcap::records::{self, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::{InputEnd, RECORD_PREFIX, lz4};
use crate::log::LogError;

/// Where and why the reading of an input stopped.
pub(in crate::log) struct Scanned {
    /// The input's header record.
    pub(in crate::log) header: records::Header,
    /// How the input ends.
    pub(in crate::log) end: InputEnd,
    /// See [`RepairReport::stopped_at`](super::RepairReport::stopped_at).
    pub(in crate::log) stopped_at: u64,
}

/// Reads `input` from its start and hands every record to keep (schema, channel, message,
/// metadata, attachment) to `visit`, in file order, the records of a chunk in their order
/// in it; the flag is `true` for those salvaged from the chunk at which reading stopped.
/// Returns the header and where and why reading stopped.
pub(in crate::log) fn scan(
    input: &[u8],
    visit: &mut dyn FnMut(Record<'_>, bool) -> Result<(), LogError>,
) -> Result<Scanned, LogError> {
    if input.is_empty() {
        return Err(not_mcap("the file is empty"));
    }
    if !input.starts_with(mcap::MAGIC) {
        return Err(not_mcap("it does not start with the MCAP magic bytes"));
    }
    // 1. The top-level records, up to the first that cannot be read.
    let reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_emit_chunks(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true)
            .with_record_length_limit(input.len()),
    );
    let mut reading = Reading {
        input,
        offset: mcap::MAGIC.len(),
        data_end: None,
        header: None,
    };
    let fed = each_record(reader, input, |opcode, body| {
        reading.record(opcode, body, visit)
    });
    // 2. Why reading stopped, and where.
    let (header, end, stopped_at) = reading.ending(fed)?;
    // 3. The records of the chunk at which reading stopped, as far as they decode.
    if !end.is_complete() && input.get(stopped_at) == Some(&op::CHUNK) {
        let length = record_length(&input[stopped_at..]).unwrap_or(u64::MAX);
        let end_of_record = (stopped_at as u64)
            .saturating_add(RECORD_PREFIX as u64)
            .saturating_add(length)
            .min(input.len() as u64) as usize;
        for record in salvage(&input[stopped_at..end_of_record]) {
            visit(record, true)?;
        }
    }
    Ok(Scanned {
        header,
        end,
        stopped_at: stopped_at as u64,
    })
}

/// The state of the linear reading of an input's top-level records.
struct Reading<'a> {
    input: &'a [u8],
    /// Offset of the end of the last record read.
    offset: usize,
    /// Offset of the end of the data section, once read.
    data_end: Option<usize>,
    /// The header record, once read.
    header: Option<records::Header>,
}

/// Why the reading of the top-level records was stopped from within.
enum Halt {
    /// The first record is not a header.
    NoHeader,
    /// The record starting at this offset does not decode.
    Unreadable { start: usize, error: String },
    /// The chunk starting at this offset does not decode, and its header still holds the
    /// placeholder its writer fills in when it closes the chunk ([`header_patch_cut`]):
    /// the writer was stopped while finishing it.
    Unfinished { start: usize },
    /// `visit` failed (writing the output).
    Visit(LogError),
}

impl Reading<'_> {
    /// Reads the top-level record `opcode`/`body`: the header first, then the data section,
    /// whose records to keep go to `visit`; the summary section is skipped.
    fn record(
        &mut self,
        opcode: u8,
        body: &[u8],
        visit: &mut dyn FnMut(Record<'_>, bool) -> Result<(), LogError>,
    ) -> ControlFlow<Halt> {
        let start = self.offset;
        self.offset += RECORD_PREFIX + body.len();
        if self.data_end.is_some() {
            return ControlFlow::Continue(());
        }
        if self.header.is_none() {
            let header = (opcode == op::HEADER).then(|| parse(opcode, body));
            return match header {
                Some(Ok(Record::Header(h))) => {
                    self.header = Some(h);
                    ControlFlow::Continue(())
                }
                _ => ControlFlow::Break(Halt::NoHeader),
            };
        }
        let records = match opcode {
            op::DATA_END => {
                self.data_end = Some(self.offset);
                return ControlFlow::Continue(());
            }
            // A footer without a Data End record before it: the data section ends too.
            op::FOOTER => {
                self.data_end = Some(start);
                return ControlFlow::Continue(());
            }
            op::CHUNK => match chunk_records(&self.input[start..self.offset]) {
                Err(_) if header_patch_cut(body) => {
                    return ControlFlow::Break(Halt::Unfinished { start });
                }
                records => records,
            },
            _ => kept(opcode, body).map(|r| r.into_iter().collect()),
        };
        match records {
            Ok(records) => (records.into_iter())
                .try_for_each(|r| visit(r, false))
                .map_or_else(
                    |e| ControlFlow::Break(Halt::Visit(e)),
                    ControlFlow::Continue,
                ),
            Err(error) => ControlFlow::Break(Halt::Unreadable { start, error }),
        }
    }

    /// The header, how the input ends and where reading stopped, from how it did.
    fn ending(self, fed: Fed<Halt>) -> Result<(records::Header, InputEnd, usize), LogError> {
        let Some(header) = self.header else {
            return Err(match fed {
                Fed::Stopped(Halt::NoHeader) => not_mcap("its first record is not a header"),
                _ => not_mcap("its header record is cut short"),
            });
        };
        let (end, stopped_at) = match (fed, self.data_end) {
            (Fed::Stopped(Halt::Visit(e)), _) => return Err(e),
            (Fed::Stopped(Halt::Unreadable { start, error }), _) => {
                (InputEnd::Unreadable { error }, start)
            }
            (Fed::Stopped(Halt::Unfinished { start }), _) => {
                (InputEnd::InsideRecord { opcode: op::CHUNK }, start)
            }
            (Fed::Failed(e), Some(end)) => {
                let error = e.to_string();
                (InputEnd::SummaryDamaged { error }, end)
            }
            (Fed::Failed(e), None) => (why_stopped(self.input, self.offset, &e), self.offset),
            // The reader ends only after the closing magic, which a footer precedes (and a
            // footer ends the data section); it halts for a header only before the header.
            (Fed::Done | Fed::Stopped(Halt::NoHeader), end) => {
                (InputEnd::Complete, end.unwrap_or(self.offset))
            }
        };
        Ok((header, end, stopped_at))
    }
}

/// Why a reader failed at `offset` of `input` (the start of the record it could not read).
fn why_stopped(input: &[u8], offset: usize, error: &McapError) -> InputEnd {
    let rest = &input[offset.min(input.len())..];
    match (rest.first(), record_length(rest)) {
        (None, _) => InputEnd::BetweenRecords,
        (Some(&opcode), None) => InputEnd::InsideRecord { opcode },
        (Some(&opcode), Some(length)) if length > (rest.len() - RECORD_PREFIX) as u64 => {
            InputEnd::InsideRecord { opcode }
        }
        (Some(_), Some(_)) => InputEnd::Unreadable {
            error: match error {
                McapError::BadDataCrc { .. } => format!(
                    "{error}: a byte of the data section before this record (the data end) \
                     was damaged"
                ),
                _ => describe(error),
            },
        },
    }
}

/// Whether the body of a chunk record still ends its header with the placeholder of an
/// unfinished chunk: the writer (`mcap`'s `ChunkWriter`) opens a chunk with a header whose
/// record length and sizes are all ones (`!0`) and, once the chunk's data is written,
/// seeks back and overwrites that header in one write, from its start. A writer killed
/// during that write can leave its first bytes written and the rest not (Linux stops a
/// write between two pages for a fatal signal): the record length is then the true one,
/// and the header's last field, the compressed size, keeps at least its most significant
/// byte `0xFF` — 2⁵⁶ bytes or more, which no chunk has. Such a chunk is cut short, not
/// damaged (a file with the length still all ones reads as cut short already: its record
/// runs past the end of the file).
///
/// The header: start and end times (u64 each), uncompressed size (u64), uncompressed CRC
/// (u32), the compression's name (u32 length and bytes), compressed size (u64).
fn header_patch_cut(body: &[u8]) -> bool {
    let Some(&[a, b, c, d]) = body.get(28..32) else {
        return false;
    };
    let name = u32::from_le_bytes([a, b, c, d]) as usize;
    // The most significant byte of the compressed size (little-endian).
    let last = 32usize.checked_add(name).and_then(|at| at.checked_add(7));
    last.and_then(|at| body.get(at)) == Some(&0xFF)
}

/// `error` with its causes (mcap's "Record parse failed" hides binrw's message).
fn describe(error: &McapError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        text = format!("{text}: {cause}");
        source = cause.source();
    }
    text
}

/// The body length of the record starting `bytes`, if its prefix is whole.
fn record_length(bytes: &[u8]) -> Option<u64> {
    let mut r = Bytes(bytes);
    r.u8()?;
    r.u64()
}

/// How feeding bytes to a reader ended.
enum Fed<B> {
    /// The reader reached the end it expects (the closing magic; or, when it expects
    /// none, the end of the bytes between two records).
    Done,
    /// The callback stopped it.
    Stopped(B),
    /// A record could not be read: the bytes end inside it, or it is malformed.
    Failed(McapError),
}

/// Feeds `bytes` to `reader` as it asks for them, and hands each record it yields (opcode,
/// body) to `f` until `f` breaks.
fn each_record<B>(
    mut reader: LinearReader,
    mut bytes: &[u8],
    mut f: impl FnMut(u8, &[u8]) -> ControlFlow<B>,
) -> Fed<B> {
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(n)) => {
                let n = n.min(bytes.len());
                reader.insert(n).copy_from_slice(&bytes[..n]);
                reader.notify_read(n);
                bytes = &bytes[n..];
            }
            Ok(LinearReadEvent::Record { opcode, data }) => {
                if let ControlFlow::Break(b) = f(opcode, data) {
                    return Fed::Stopped(b);
                }
            }
            Err(e) => return Fed::Failed(e),
        }
    }
    Fed::Done
}

/// The record `opcode`/`body` parsed, if it is of a kind that is copied (schema, channel,
/// message, metadata, attachment); `None` for the other kinds (indexes, statistics,
/// unknown opcodes: not needed); an error for a record that does not decode, or opcode
/// 0, which is no record (zeroed bytes).
fn kept(opcode: u8, body: &[u8]) -> Result<Option<Record<'_>>, String> {
    match opcode {
        0 => Err("opcode 0x00 (zeroed bytes?)".to_owned()),
        op::SCHEMA | op::CHANNEL | op::MESSAGE | op::METADATA | op::ATTACHMENT => {
            parse(opcode, body).map(Some)
        }
        _ => Ok(None),
    }
}

/// The record `opcode`/`body` parsed by `mcap`, once [`check_layout`] has found its length
/// fields within it.
fn parse(opcode: u8, body: &[u8]) -> Result<Record<'_>, String> {
    check_layout(opcode, body)?;
    mcap::parse_record(opcode, body).map_err(|e| describe(&e))
}

/// Checks that every length field of a header, schema, channel, message, metadata or
/// attachment record (`body`: after its opcode and length) lies within the record, as the
/// fields are laid out [MCAP, §Records]: `mcap`'s parser reserves a string's length (a
/// `u32`) before reading it (a damaged length asked for up to 4 GiB per string), and
/// slices an attachment's body before checking that its CRC is there (a panic).
///
/// ```text
/// header      profile: string, library: string
/// schema      id: u16, name: string, encoding: string, data: u32 length + bytes
/// channel     id: u16, schema_id: u16, topic: string, message_encoding: string,
///             metadata: map<string, string>
/// message     channel_id: u16, sequence: u32, log_time: u64, publish_time: u64, data
/// metadata    name: string, metadata: map<string, string>
/// attachment  log_time: u64, create_time: u64, name: string, media_type: string,
///             data: u64 length + bytes, crc: u32
/// ```
/// (A string is a `u32` length and that many bytes; a map a `u32` length in bytes and its
/// entries.) Other kinds are not checked: `mcap` parses them only on request.
fn check_layout(opcode: u8, body: &[u8]) -> Result<(), String> {
    let mut r = Bytes(body);
    let fits = match opcode {
        op::HEADER => r.string().and_then(|_| r.string()),
        op::SCHEMA => (r.take(2))
            .and_then(|_| r.string())
            .and_then(|_| r.string())
            .and_then(|_| r.string()),
        op::CHANNEL => (r.take(4))
            .and_then(|_| r.string())
            .and_then(|_| r.string())
            .and_then(|_| r.string_map()),
        op::MESSAGE => r.take(2 + 4 + 8 + 8),
        op::METADATA => r.string().and_then(|_| r.string_map()),
        op::ATTACHMENT => (r.take(16))
            .and_then(|_| r.string())
            .and_then(|_| r.string())
            .and_then(|_| r.u64())
            .and_then(|n| r.take(usize::try_from(n).ok()?))
            .and_then(|_| r.take(4)),
        _ => Some(&[][..]),
    };
    match fits {
        Some(_) => Ok(()),
        None => Err(format!(
            "{} record too short: a length field runs past its end ({} bytes)",
            super::record_name(opcode),
            body.len()
        )),
    }
}

/// The records to keep of the complete chunk record `record` (opcode to end), decompressed
/// by `mcap` and checked against the chunk's CRC; an error if any of it does not decode.
fn chunk_records(record: &[u8]) -> Result<Vec<Record<'static>>, String> {
    let Some(chunk) = ChunkStart::parse(record) else {
        return Err("chunk header cut short".to_owned());
    };
    let options = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(chunk.records_limit(record.len()));
    match records_in(record, options) {
        (records, None) => Ok(records),
        (_, Some(error)) => Err(error),
    }
}

/// The records to keep of the chunk record `record` (opcode to end, cut short or damaged),
/// as far as they decode (see [`repair`](super::repair)).
fn salvage(record: &[u8]) -> Vec<Record<'static>> {
    let Some(chunk) = ChunkStart::parse(record) else {
        return vec![];
    };
    if chunk.compression == b"lz4" {
        let bytes = lz4::decompress_prefix(chunk.records, decompressed_limit(record.len()));
        records_in(&bytes, LinearReaderOptions::default()).0
    } else {
        // Uncompressed chunks, and zstd ones with the `zstd` feature: mcap's streaming
        // reader yields each record as soon as its bytes are there.
        let reframed = chunk.reframed();
        let limit = chunk.records_limit(reframed.len());
        let options = LinearReaderOptions::default().with_record_length_limit(limit);
        records_in(&reframed, options).0
    }
}

/// The records to keep among the records of `bytes` (no magic, e.g. one chunk record, or
/// the records of a decompressed chunk), read with `options` (the record length limit
/// defaults to the length of `bytes`), up to the first that cannot be read, and why it
/// could not.
fn records_in(
    bytes: &[u8],
    options: LinearReaderOptions,
) -> (Vec<Record<'static>>, Option<String>) {
    let limit = options.record_length_limit.unwrap_or(bytes.len());
    let reader = LinearReader::new_with_options(
        options
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_record_length_limit(limit),
    );
    let mut records = Vec::new();
    let fed = each_record(reader, bytes, |opcode, body| match kept(opcode, body) {
        Ok(record) => {
            records.extend(record.map(Record::into_owned));
            ControlFlow::Continue(())
        }
        Err(error) => ControlFlow::Break(error),
    });
    let error = match fed {
        Fed::Done => None,
        Fed::Stopped(error) => Some(error),
        Fed::Failed(e) => Some(describe(&e)),
    };
    (records, error)
}

/// The most that `compressed` bytes of LZ4 may decompress to: 256 times as much (LZ4's
/// largest ratio is 255) and 64 KiB (a frame's header and a block), so that a damaged length
/// cannot ask for an absurd allocation.
fn decompressed_limit(compressed: usize) -> usize {
    compressed.saturating_mul(256).saturating_add(64 << 10)
}

/// The start of a chunk record [MCAP, §Chunk]: its header and its compressed records as
/// far as the bytes go.
struct ChunkStart<'a> {
    /// The record up to its compressed records: opcode, length, header fields.
    head: &'a [u8],
    /// The size of its records decompressed, as the header says (bytes).
    uncompressed_size: u64,
    /// The compression, e.g. `lz4`; empty if none.
    compression: &'a [u8],
    /// The compressed records, cut where the bytes end.
    records: &'a [u8],
}

impl<'a> ChunkStart<'a> {
    /// Parses the chunk record `record` (from its opcode); `None` if its header is cut.
    fn parse(record: &'a [u8]) -> Option<Self> {
        let mut r = Bytes(record);
        r.take(RECORD_PREFIX)?;
        // message_start_time, message_end_time, uncompressed_size, uncompressed_crc.
        r.take(8 + 8)?;
        let uncompressed_size = r.u64()?;
        r.take(4)?;
        let n = r.u32()?;
        let compression = r.take(usize::try_from(n).ok()?)?;
        let compressed_size = r.u64()?;
        let head = &record[..record.len() - r.0.len()];
        let records = r.take_up_to(usize::try_from(compressed_size).unwrap_or(usize::MAX));
        Some(ChunkStart {
            head,
            uncompressed_size,
            compression,
            records,
        })
    }

    /// The record length limit of `mcap`'s reader for this chunk, whose record is `len`
    /// bytes long: the uncompressed size of its header, at least `len` (the reader buffers
    /// compressed bytes up to the limit) and at most what `len` bytes can expand to
    /// (LZ4: [`decompressed_limit`]; zstd, which can expand further: 64 MiB more), so that
    /// no damaged length asks for more.
    fn records_limit(&self, len: usize) -> usize {
        let most = match self.compression {
            b"" => len,
            b"lz4" => decompressed_limit(len),
            _ => decompressed_limit(len).saturating_add(64 << 20),
        };
        usize::try_from(self.uncompressed_size)
            .unwrap_or(usize::MAX)
            .clamp(len, most)
    }

    /// The chunk record holding only the compressed records that are there: its length
    /// and compressed size set to match them. (mcap writes `0xFF…` in both when it opens a
    /// chunk and the real values when it closes it; a writer killed in between leaves the
    /// placeholders, which mcap's reader refuses.)
    fn reframed(&self) -> Vec<u8> {
        let mut bytes = [self.head, self.records].concat();
        let length = (bytes.len() - RECORD_PREFIX) as u64;
        bytes[1..RECORD_PREFIX].copy_from_slice(&length.to_le_bytes());
        let n = self.head.len();
        bytes[n - 8..n].copy_from_slice(&(self.records.len() as u64).to_le_bytes());
        bytes
    }
}

/// A cursor over little-endian bytes: each read takes bytes off the front, `None` when
/// too few remain.
#[doc(hidden)]
pub struct Bytes<'a>(pub(super) &'a [u8]);

impl<'a> Bytes<'a> {
    pub(super) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, rest) = (self.0.len() >= n).then(|| self.0.split_at(n))?;
        self.0 = rest;
        Some(head)
    }
    /// The next `n` bytes, or all that remain if fewer.
    pub(super) fn take_up_to(&mut self, n: usize) -> &'a [u8] {
        let (head, rest) = self.0.split_at(n.min(self.0.len()));
        self.0 = rest;
        head
    }
    fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.0.split_first_chunk::<N>()?;
        self.0 = rest;
        Some(*head)
    }
    pub(super) fn u8(&mut self) -> Option<u8> {
        self.array::<1>().map(|[b]| b)
    }
    pub(super) fn u16(&mut self) -> Option<u16> {
        self.array().map(u16::from_le_bytes)
    }
    pub(super) fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }
    pub(super) fn u64(&mut self) -> Option<u64> {
        self.array().map(u64::from_le_bytes)
    }
    /// A string [MCAP, §Serialization]: a `u32` length and that many bytes.
    fn string(&mut self) -> Option<&'a [u8]> {
        let n = self.u32()?;
        self.take(usize::try_from(n).ok()?)
    }
    /// A map of strings to strings: a `u32` length in bytes, then that many bytes of
    /// key–value pairs, each string within them.
    fn string_map(&mut self) -> Option<&'a [u8]> {
        let n = self.u32()?;
        let map = self.take(usize::try_from(n).ok()?)?;
        let mut entries = Bytes(map);
        while !entries.0.is_empty() {
            entries.string()?;
            entries.string()?;
        }
        Some(map)
    }
}

fn not_mcap(reason: &'static str) -> LogError {
    LogError::NotMcap { reason }
}
