//! `log::repair`: an MCAP file cut short, copied into a finished one.
//!
//! Checked here:
//! - a ricochet log cut every 97 bytes (and every 7 bytes inside its last chunk, LZ4,
//!   uncompressed, and zstd with the `zstd` feature): the repair never fails once the header is whole; its output has a
//!   summary, reads whole with `mcap::MessageStream`, and holds a prefix of the original
//!   messages (topic, channel, sequence, times, payload bytes), never fewer as the cut
//!   moves on, never fewer than `mcap::MessageStream` sees in the cut file and exactly as
//!   many as `log::read` reads; a cut inside a chunk salvages messages from it;
//! - every chunk of a repaired file holds messages (its chunk index names message
//!   indexes, its time range is its messages'), also for a log whose first chunk holds
//!   only schemas and channels (ricochet's logs before `repair`), which is converted;
//! - a complete log repairs to the same messages and metadata, and repairing twice gives
//!   the same bytes;
//! - ids, order, metadata and attachments of a foreign file are kept; schemas and
//!   channels after the last message, or in a file without messages, are kept too;
//! - a tail of zeros (a power loss) stops the reading where it starts;
//! - empty, garbage, magic-only inputs are errors; a malformed attachment record is an
//!   unreadable record, not a panic.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Cursor;

use mcap::records::Record;
use ricochet::log::{
    Compression, InputEnd, LogError, LogOptions, LogWriter, RepairReport, RunLogger, repair_bytes,
};
use ricochet::sim::{MaterialOverride, Simulation};

use crate::common::mcap_check;
use mcap_check::{Msg, assert_every_chunk_has_messages, messages};

/// The log of `scenes/bouncing_ball.toml` up to `t_end`, written by the library with
/// `options`.
fn ball_log(t_end: f64, options: LogOptions) -> Vec<u8> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bouncing_ball.toml");
    let mut s = ricochet::scene::load(path).unwrap();
    s.settings.t_end = t_end;
    let overrides = MaterialOverride::default();
    let mut sim = Simulation::new(&s.model, &s.settings, overrides).unwrap();
    let writer = LogWriter::new(Cursor::new(Vec::new()), options).unwrap();
    let mut log = RunLogger::for_scene(writer, &s, &overrides, sim.scales().gap_tol).unwrap();
    let summary = sim.run(&s.initial, &mut log, None);
    log.finish(&summary).unwrap().into_inner()
}

/// The offset where the header record ends.
fn header_end(bytes: &[u8]) -> usize {
    let len = u64::from_le_bytes(bytes[9..17].try_into().unwrap());
    8 + 9 + len as usize
}

/// Repairs `original[..cut]` and checks the output against `original`'s messages; returns
/// the number of messages kept, salvaged, and seen by `mcap::MessageStream` in the cut file.
fn check_cut(original: &[u8], all: &[Msg], cut: usize) -> (u64, u64, u64) {
    let (fixed, report) =
        repair_bytes(&original[..cut]).unwrap_or_else(|e| panic!("cut {cut}: {e}"));
    assert!(
        mcap::Summary::read(&fixed).unwrap().is_some(),
        "cut {cut}: no summary"
    );
    let got = messages(&fixed);
    assert_eq!(got.len() as u64, report.messages, "cut {cut}");
    assert!(got[..] == all[..got.len()], "cut {cut}: not a prefix");
    if report.is_complete() {
        // Cut in the summary section, which is not needed.
        assert!(
            report.unused_bytes == 0 && report.stopped_at <= cut as u64,
            "{report:?}"
        );
        assert_eq!(got.len(), all.len(), "cut {cut}");
    } else {
        let end = report.stopped_at + report.unused_bytes;
        assert_eq!(end, cut as u64, "cut {cut}: {report:?}");
    }
    // No fewer than mcap's own streaming reader sees; exactly what `log::read` sees (it
    // keeps the records of a chunk cut short too).
    let seen = mcap::MessageStream::new(&original[..cut])
        .map_or(0, |stream| stream.take_while(Result::is_ok).count() as u64);
    let read: u64 = ricochet::log::read_bytes(&original[..cut])
        .unwrap()
        .message_counts
        .values()
        .sum();
    assert_eq!(read, report.messages, "cut {cut}: log::read");
    assert!(
        report.messages >= seen,
        "cut {cut}: {} < {seen}",
        report.messages
    );
    (report.messages, report.salvaged_messages, seen)
}

/// Cuts `original`, written with `compression`, every 97 bytes and every 7 bytes in its
/// last chunk. Uncompressed and LZ4 chunks cut short give up every complete record; with
/// LZ4, some cuts must keep more messages than mcap's streaming decoder yields (it stops
/// at the last complete LZ4 block). zstd chunks give up whole zstd blocks only (mcap's
/// decoder), i.e. nothing of a 16 KiB chunk.
fn sweep_cuts(original: &[u8], compression: Compression) {
    let lz4 = compression == Compression::Lz4;
    let records = matches!(compression, Compression::Lz4 | Compression::None);
    let all = messages(original);
    let summary = mcap::Summary::read(original).unwrap().unwrap();
    let chunks = &summary.chunk_indexes;
    assert!(chunks.len() >= 4, "{} chunks", chunks.len());

    // Before the header is whole: an error.
    for cut in 0..header_end(original) {
        assert!(repair_bytes(&original[..cut]).is_err(), "cut {cut}");
    }
    let mut previous = 0;
    let (mut cuts, mut salvaging, mut more_than_read) = (0, 0, 0);
    for cut in (header_end(original)..=original.len()).step_by(97) {
        let (n, s, seen) = check_cut(original, &all, cut);
        assert!(n >= previous, "cut {cut}: {n} < {previous}");
        previous = n;
        cuts += 1;
        salvaging += usize::from(s > 0);
        more_than_read += usize::from(n > seen);
        if cut % (97 * 20) == 0 {
            let (fixed, _) = repair_bytes(&original[..cut]).unwrap();
            assert_every_chunk_has_messages(&fixed);
        }
    }
    println!(
        "{cuts} cuts: {salvaging} salvage messages from a torn chunk, {more_than_read} keep \
         more messages than mcap::MessageStream sees"
    );
    assert_eq!(salvaging > 0, records);
    assert_eq!(more_than_read > 0, lz4);

    // Inside the last chunk: more messages than at its start, for some cut.
    let last = chunks.last().unwrap();
    let start = last.chunk_start_offset as usize;
    let (at_start, _, _) = check_cut(original, &all, start);
    let mut best = at_start;
    let mut previous = at_start;
    for cut in (start..start + last.chunk_length as usize).step_by(7) {
        let (n, _, _) = check_cut(original, &all, cut);
        assert!(n >= previous, "cut {cut}: {n} < {previous}");
        previous = n;
        best = best.max(n);
    }
    println!(
        "last chunk at {start}: {at_start} messages before it, up to {best} with a cut inside it"
    );
    assert_eq!(best > at_start, records);

    // The same chunk with the placeholder header mcap writes when it opens a chunk and
    // fills in when it closes it: what a writer killed while writing the chunk out leaves.
    let mut placeholder = original.to_vec();
    placeholder[start + 1..start + 9].copy_from_slice(&u64::MAX.to_le_bytes());
    placeholder[start + 9..start + 25].fill(0);
    placeholder[start + 25..start + 37].fill(0xFF);
    let name = u32::from_le_bytes(placeholder[start + 37..start + 41].try_into().unwrap());
    let compressed_size = start + 41 + name as usize;
    placeholder[compressed_size..compressed_size + 8].fill(0xFF);
    let mut previous = at_start;
    for cut in (start..start + last.chunk_length as usize).step_by(7) {
        let (n, _, _) = check_cut(&placeholder, &all, cut);
        assert!(n >= previous, "cut {cut}: {n} < {previous}");
        previous = n;
    }
    assert_eq!(previous, best);
}

#[test]
fn every_cut_of_an_lz4_log_repairs_to_a_prefix() {
    let options = LogOptions {
        chunk_size: 16 * 1024,
        ..LogOptions::default()
    };
    let original = ball_log(1.0, options);
    println!("{} bytes", original.len());
    sweep_cuts(&original, Compression::Lz4);
}

#[test]
fn every_cut_of_an_uncompressed_log_repairs_to_a_prefix() {
    let options = LogOptions {
        compression: Compression::None,
        chunk_size: 16 * 1024,
    };
    let original = ball_log(0.5, options);
    println!("{} bytes", original.len());
    sweep_cuts(&original, Compression::None);
}

#[cfg(feature = "zstd")]
#[test]
fn every_cut_of_a_zstd_log_repairs_to_a_prefix() {
    let options = LogOptions {
        compression: Compression::Zstd,
        chunk_size: 16 * 1024,
    };
    let original = ball_log(1.0, options);
    println!("{} bytes", original.len());
    sweep_cuts(&original, Compression::Zstd);
}

#[test]
fn a_complete_log_repairs_to_the_same_log_and_twice_to_the_same_bytes() {
    let original = ball_log(1.0, LogOptions::default());
    let (fixed, report) = repair_bytes(&original).unwrap();
    assert_eq!(report.end, InputEnd::Complete);
    assert!(report.is_complete());
    assert_eq!(
        (
            report.unused_bytes,
            report.salvaged_messages,
            report.skipped
        ),
        (0, 0, 0)
    );
    assert_eq!(
        // Format 2: five schemas (`/geometry` and `/scene` share one), six channels, and
        // the ricochet, scene, settings and audit records.
        (report.schemas, report.channels, report.metadata),
        (5, 6, 4)
    );
    assert_eq!(messages(&fixed), messages(&original));
    assert_every_chunk_has_messages(&fixed);
    // The same log for ricochet's reader: scene, settings, audit, impacts, counts.
    let before = ricochet::log::read_bytes(&original).unwrap();
    let after = ricochet::log::read_bytes(&fixed).unwrap();
    assert_eq!(after, before);
    // Idempotent, and deterministic.
    let (again, report_again) = repair_bytes(&fixed).unwrap();
    assert!(again == fixed, "repairing a repaired log changed it");
    // The same report, but for the end of the data section, which moved.
    assert_eq!(
        RepairReport {
            stopped_at: report.stopped_at,
            ..report_again
        },
        report
    );
    assert!(repair_bytes(&original).unwrap().0 == fixed);
}

#[test]
fn a_log_cut_in_its_summary_loses_nothing() {
    let original = ball_log(0.2, LogOptions::default());
    let (whole, _) = repair_bytes(&original).unwrap();
    let (fixed, report) = repair_bytes(&original[..original.len() - 40]).unwrap();
    assert!(
        matches!(report.end, InputEnd::SummaryDamaged { .. }),
        "{:?}",
        report.end
    );
    assert!(report.is_complete() && report.unused_bytes == 0);
    assert!(fixed == whole);
}

#[test]
fn a_tail_of_zeros_stops_the_reading_where_it_starts() {
    let original = ball_log(1.0, LogOptions::default());
    let all = messages(&original);
    let summary = mcap::Summary::read(&original).unwrap().unwrap();
    // Zeros from the middle of the second chunk on, the file's length kept: the chunk is
    // whole but its bytes are not (a power loss after the file grew).
    let chunk = &summary.chunk_indexes[1];
    let zero_from = (chunk.chunk_start_offset + chunk.chunk_length / 2) as usize;
    let mut damaged = original.clone();
    damaged[zero_from..].fill(0);
    let (fixed, report) = repair_bytes(&damaged).unwrap();
    assert!(
        matches!(report.end, InputEnd::Unreadable { .. }),
        "{:?}",
        report.end
    );
    assert_eq!(report.stopped_at, chunk.chunk_start_offset);
    let got = messages(&fixed);
    assert!(got[..] == all[..got.len()]);
    assert!(report.salvaged_messages > 0, "{report:?}");
    assert_every_chunk_has_messages(&fixed);
    // Zeros after a whole chunk: the reading stops at them.
    let next = summary.chunk_indexes[2].chunk_start_offset as usize;
    let mut zeroed = original[..next].to_vec();
    zeroed.resize(next + 5000, 0);
    let (_, report) = repair_bytes(&zeroed).unwrap();
    assert!(
        matches!(report.end, InputEnd::Unreadable { .. }),
        "{:?}",
        report.end
    );
    assert!(report.stopped_at >= chunk.chunk_start_offset + chunk.chunk_length);
}

/// A file written the way ricochet's logs were before `repair`: schemas and channels in
/// a first chunk of their own, closed by metadata records.
fn old_style_file(messages_per_channel: u32) -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .library("old writer")
        .profile("x")
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let schema = w.add_schema("S", "jsonschema", b"{}").unwrap();
    let a = w
        .add_channel(schema, "/a", "json", &BTreeMap::new())
        .unwrap();
    let b = w
        .add_channel(schema, "/b", "json", &BTreeMap::new())
        .unwrap();
    w.flush().unwrap();
    let meta = |name: &str| mcap::records::Metadata {
        name: name.to_owned(),
        metadata: BTreeMap::from([("k".to_owned(), "v".to_owned())]),
    };
    w.write_metadata(&meta("scene")).unwrap();
    for i in 0..messages_per_channel {
        for (channel, t) in [(a, 2 * i as u64), (b, 2 * i as u64 + 1)] {
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: i,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&header, format!("{{\"i\":{i}}}").as_bytes())
                .unwrap();
        }
    }
    w.write_metadata(&meta("audit")).unwrap();
    w.finish().unwrap();
    w.into_inner().into_inner()
}

#[test]
fn an_old_style_log_gets_no_chunk_without_messages() {
    let old = old_style_file(3000);
    let summary = mcap::Summary::read(&old).unwrap().unwrap();
    assert!(summary.chunk_indexes[0].message_index_offsets.is_empty());
    let (fixed, report) = repair_bytes(&old).unwrap();
    assert_eq!(report.end, InputEnd::Complete);
    assert_eq!(
        (
            report.messages,
            report.schemas,
            report.channels,
            report.metadata
        ),
        (6000, 1, 2, 2)
    );
    assert_every_chunk_has_messages(&fixed);
    assert_eq!(messages(&fixed), messages(&old));
    let header = mcap::read::LinearReader::new(&fixed)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    let Record::Header(header) = header else {
        panic!("{header:?}")
    };
    assert_eq!(
        (header.profile.as_str(), header.library.as_str()),
        ("x", "old writer")
    );
    // The metadata records, in their order.
    let names: Vec<String> = (mcap::read::LinearReader::new(&fixed).unwrap())
        .filter_map(|r| match r.unwrap() {
            Record::Metadata(m) => Some(m.name),
            _ => None,
        })
        .collect();
    assert_eq!(names, ["scene", "audit"]);
}

/// A file with unusual ids, a metadata record and an attachment among the messages, and a
/// schema and a channel after the last message.
fn foreign_file() -> Vec<u8> {
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let s7 = w
        .add_schema_with_id(7, "S7", "jsonschema", b"{\"type\":\"object\"}")
        .unwrap();
    let c42 = w
        .add_channel_with_id(42, s7, "/x", "json", &BTreeMap::new())
        .unwrap();
    let c0 = w
        .add_channel_with_id(
            0,
            0,
            "/raw",
            "",
            &BTreeMap::from([("a".into(), "b".into())]),
        )
        .unwrap();
    let msg = |w: &mut mcap::Writer<Cursor<Vec<u8>>>, channel: u16, sequence: u32, t: u64| {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence,
            log_time: t,
            publish_time: t + 1,
        };
        w.write_to_known_channel(&header, &[sequence as u8; 3])
            .unwrap();
    };
    msg(&mut w, c42, 10, 5);
    msg(&mut w, c0, 20, 3);
    w.attach(&mcap::Attachment {
        log_time: 4,
        create_time: 9,
        name: "notes.txt".into(),
        media_type: "text/plain".into(),
        data: Cow::Borrowed(b"hello"),
    })
    .unwrap();
    msg(&mut w, c42, 11, 6);
    w.write_metadata(&mcap::records::Metadata {
        name: "m".into(),
        metadata: BTreeMap::new(),
    })
    .unwrap();
    msg(&mut w, c0, 21, 7);
    let s9 = w.add_schema_with_id(9, "S9", "jsonschema", b"{}").unwrap();
    w.add_channel_with_id(300, s9, "/late", "json", &BTreeMap::new())
        .unwrap();
    w.finish().unwrap();
    w.into_inner().into_inner()
}

#[test]
fn ids_order_metadata_attachments_and_late_channels_are_kept() {
    let foreign = foreign_file();
    let (fixed, report) = repair_bytes(&foreign).unwrap();
    assert_eq!(
        (
            report.messages,
            report.schemas,
            report.channels,
            report.metadata,
            report.attachments
        ),
        (4, 2, 3, 1, 1)
    );
    assert_eq!(report.skipped, 0);
    assert_every_chunk_has_messages(&fixed);
    assert_eq!(messages(&fixed), messages(&foreign));
    let summary = mcap::Summary::read(&fixed).unwrap().unwrap();
    let mut channels: Vec<(u16, String, u16)> = (summary.channels.values())
        .map(|c| (c.id, c.topic.clone(), c.schema.as_ref().map_or(0, |s| s.id)))
        .collect();
    channels.sort();
    assert_eq!(
        channels,
        [
            (0, "/raw".into(), 0),
            (42, "/x".into(), 7),
            (300, "/late".into(), 9)
        ]
    );
    assert_eq!(summary.channels[&0].metadata["a"], "b");
    // The records in order: messages, attachment and metadata where they were.
    let order: Vec<String> = (mcap::read::ChunkFlattener::new(&fixed).unwrap())
        .filter_map(|r| match r.unwrap() {
            Record::Message { header, .. } => Some(format!("m{}", header.sequence)),
            Record::Attachment { header, data, .. } => {
                assert_eq!((header.log_time, header.create_time), (4, 9));
                assert_eq!(
                    (header.media_type.as_str(), &data[..]),
                    ("text/plain", &b"hello"[..])
                );
                Some(header.name)
            }
            Record::Metadata(m) => Some(m.name),
            _ => None,
        })
        .collect();
    assert_eq!(order, ["m10", "m20", "notes.txt", "m11", "m", "m21"]);
    let (again, _) = repair_bytes(&fixed).unwrap();
    assert!(again == fixed);
}

#[test]
fn a_file_without_messages_keeps_its_schemas_and_channels_without_chunks() {
    // The old-style file cut right after its metadata record: no message.
    let old = old_style_file(10);
    let summary = mcap::Summary::read(&old).unwrap().unwrap();
    let first_metadata = summary.metadata_indexes[0].offset as usize;
    let cut = first_metadata + summary.metadata_indexes[0].length as usize;
    let (fixed, report) = repair_bytes(&old[..cut]).unwrap();
    assert_eq!(report.end, InputEnd::BetweenRecords);
    assert_eq!(
        (
            report.messages,
            report.schemas,
            report.channels,
            report.metadata
        ),
        (0, 1, 2, 1)
    );
    let summary = mcap::Summary::read(&fixed).unwrap().unwrap();
    assert!(summary.chunk_indexes.is_empty());
    assert_eq!(summary.channels.len(), 2);
    assert!(messages(&fixed).is_empty());
}

#[test]
fn what_is_not_mcap_is_an_error() {
    let original = ball_log(0.1, LogOptions::default());
    let header = header_end(&original);
    for (what, bytes) in [
        ("empty", &b""[..]),
        (
            "text",
            &b"this is not an MCAP file, only text that is long enough"[..],
        ),
        ("magic only", &original[..8]),
        ("header cut", &original[..header - 1]),
    ] {
        match repair_bytes(bytes) {
            Err(e @ LogError::NotMcap { .. }) => println!("{what}: {e}"),
            other => panic!("{what}: {other:?}"),
        }
    }
    // The magic, then something else than a header.
    let mut no_header = original[..8].to_vec();
    no_header.extend_from_slice(&original[header..]);
    assert!(matches!(
        repair_bytes(&no_header),
        Err(LogError::NotMcap { .. })
    ));
    // The header whole: repaired, with nothing in it.
    let (fixed, report) = repair_bytes(&original[..header]).unwrap();
    assert_eq!(report.end, InputEnd::BetweenRecords);
    assert_eq!(report.messages, 0);
    assert!(mcap::Summary::read(&fixed).unwrap().is_some());
}

/// An attachment record too short to hold its CRC (on which mcap 0.26's parser panics)
/// is an unreadable record, or, first in the file, no header.
#[test]
fn a_short_attachment_record_is_unreadable() {
    let mut body = Vec::new();
    body.extend_from_slice(&[0; 16]);
    for field in [&b"a"[..], b"b"] {
        body.extend_from_slice(&(field.len() as u32).to_le_bytes());
        body.extend_from_slice(field);
    }
    body.extend_from_slice(&0u64.to_le_bytes());
    let mut attachment = vec![0x09];
    attachment.extend_from_slice(&(body.len() as u64).to_le_bytes());
    attachment.extend_from_slice(&body);

    let original = old_style_file(1);
    let header = header_end(&original);
    let mut bytes = original[..header].to_vec();
    bytes.extend_from_slice(&attachment);
    let (_, report) = repair_bytes(&bytes).unwrap();
    assert_eq!(
        report.end,
        InputEnd::Unreadable {
            error: "attachment record too short: a length field runs past its end (34 bytes)"
                .into()
        }
    );
    assert_eq!(report.stopped_at, header as u64);

    let mut first = original[..8].to_vec();
    first.extend_from_slice(&attachment);
    assert!(matches!(
        repair_bytes(&first),
        Err(LogError::NotMcap { .. })
    ));
}

/// A writer killed while it overwrites a chunk's placeholder header with the true one (one
/// write, which Linux may stop between two pages for SIGKILL) leaves the header's first
/// bytes true and the rest still the placeholder: every such state, from none of the header
/// written to all of it, with the file ending at the chunk's end (its message indexes come
/// after the header). Each is cut short — not "damaged", which said a byte changed after
/// it was written (`cli_repair::a_killed_run_is_repaired` met one once) — and the chunk's
/// messages are all salvaged: `log::read` and `repair` keep as many as with the whole
/// header written.
#[test]
fn a_chunk_header_cut_while_being_filled_in_is_cut_short() {
    let options = LogOptions {
        chunk_size: 16 * 1024,
        ..LogOptions::default()
    };
    let original = ball_log(1.0, options);
    let all = messages(&original);
    let summary = mcap::Summary::read(&original).unwrap().unwrap();
    let chunk = &summary.chunk_indexes[1];
    let (start, length) = (
        chunk.chunk_start_offset as usize,
        chunk.chunk_length as usize,
    );
    // The placeholder mcap writes when it opens a chunk: length, sizes and CRC all ones,
    // times zero, the compression's name as in the true header.
    let name = u32::from_le_bytes(original[start + 37..start + 41].try_into().unwrap()) as usize;
    let header = 41 + name + 8;
    let truth = &original[start..start + header];
    let mut placeholder = truth.to_vec();
    placeholder[1..9].fill(0xFF);
    placeholder[9..25].fill(0);
    placeholder[25..37].fill(0xFF);
    placeholder[header - 8..].fill(0xFF);

    let cut_at = |written: usize| -> Vec<u8> {
        let mut bytes = original[..start + length].to_vec();
        bytes[start..start + header].copy_from_slice(&placeholder);
        bytes[start..start + written].copy_from_slice(&truth[..written]);
        bytes
    };
    let whole = cut_at(header);
    let (_, whole_report) = repair_bytes(&whole).unwrap();
    assert_eq!(whole_report.end, InputEnd::BetweenRecords);
    let kept = whole_report.messages;
    assert!(
        kept > 0 && (kept as usize) < all.len(),
        "{kept} of {}",
        all.len()
    );
    for written in 0..header {
        let bytes = cut_at(written);
        let read = ricochet::log::read_bytes(&bytes).unwrap();
        assert!(
            matches!(read.ending, ricochet::log::Ending::Truncated { .. }),
            "{written} bytes of the header written: {:?}",
            read.ending
        );
        assert_eq!(read.message_counts.values().sum::<u64>(), kept, "{written}");
        let (fixed, report) = repair_bytes(&bytes).unwrap();
        assert_eq!(
            report.end,
            InputEnd::InsideRecord { opcode: 0x06 },
            "{written} bytes of the header written"
        );
        assert_eq!(report.stopped_at, start as u64, "{written}");
        assert_eq!(report.messages, kept, "{written}");
        let got = messages(&fixed);
        assert!(got[..] == all[..got.len()], "{written}: not a prefix");
    }
}
