//! A check of the chunks of an MCAP file: every chunk holds messages and is indexed with
//! them. Readers that bundle `@mcap/core` before 2025 (Foxglove Studio 1.48 among them)
//! throw "Chunks without message indexes are not currently supported" on a chunk whose
//! index lists no message index.

use mcap::Summary;

/// Panics, naming the chunk, unless the file has a summary whose every chunk index lists
/// at least one message index (a channel with messages in it), with message times set by
/// those messages; returns the number of chunks.
#[allow(dead_code)]
pub fn assert_every_chunk_has_messages(bytes: &[u8]) -> usize {
    let summary = Summary::read(bytes)
        .expect("a readable summary")
        .expect("a summary section");
    for (k, chunk) in summary.chunk_indexes.iter().enumerate() {
        assert!(
            !chunk.message_index_offsets.is_empty(),
            "chunk {k} (at byte {}) has no message index",
            chunk.chunk_start_offset
        );
        // The chunk's own records: at least one message, within the indexed times.
        let messages = summary
            .stream_chunk(bytes, chunk)
            .expect("a readable chunk");
        let times: Vec<u64> = messages.map(|m| m.expect("a message").log_time).collect();
        assert!(!times.is_empty(), "chunk {k} holds no message");
        assert_eq!(
            (times.iter().min(), times.iter().max()),
            (
                Some(&chunk.message_start_time),
                Some(&chunk.message_end_time)
            ),
            "chunk {k}: message times"
        );
    }
    summary.chunk_indexes.len()
}
