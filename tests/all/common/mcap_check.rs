//! Checks of MCAP files (shared by the log and repair tests).
//! Readers that bundle `@mcap/core` before 2025 (Foxglove Studio 1.48 among them) throw
//! "Chunks without message indexes are not currently supported" on a chunk whose index
//! lists no message index.
#![allow(dead_code)]

use mcap::records::Record;

/// One message, as read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Msg {
    pub topic: String,
    pub channel: u16,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: Vec<u8>,
}

/// Every message of `bytes`, read with `mcap::MessageStream`; panics on any error.
pub fn messages(bytes: &[u8]) -> Vec<Msg> {
    mcap::MessageStream::new(bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            Msg {
                topic: m.channel.topic.clone(),
                channel: m.channel.id,
                sequence: m.sequence,
                log_time: m.log_time,
                publish_time: m.publish_time,
                data: m.data.into_owned(),
            }
        })
        .collect()
}

/// Fails on any chunk without messages, found two ways: the summary's chunk indexes (a
/// message index for some channel, and a time range that is its messages'), and the chunk
/// records read linearly (each holds a message record).
pub fn assert_every_chunk_has_messages(bytes: &[u8]) {
    let summary = mcap::Summary::read(bytes).unwrap().expect("a summary");
    for index in &summary.chunk_indexes {
        assert!(
            !index.message_index_offsets.is_empty(),
            "chunk at {} has no message index",
            index.chunk_start_offset
        );
        let times: Vec<u64> = (summary.stream_chunk(bytes, index).unwrap())
            .map(|m| m.unwrap().log_time)
            .collect();
        assert!(
            !times.is_empty(),
            "chunk at {} holds no message",
            index.chunk_start_offset
        );
        let (min, max) = (times.iter().min().unwrap(), times.iter().max().unwrap());
        assert_eq!(
            (index.message_start_time, index.message_end_time),
            (*min, *max),
            "chunk at {}: its time range is not its messages'",
            index.chunk_start_offset
        );
    }
    let mut chunks = 0;
    for record in mcap::read::LinearReader::new(bytes).unwrap() {
        if let Record::Chunk { header, data } = record.unwrap() {
            chunks += 1;
            let has_message = mcap::read::ChunkReader::new(header, &data)
                .unwrap()
                .any(|r| matches!(r.unwrap(), Record::Message { .. }));
            assert!(has_message, "a chunk record without a message record");
        }
    }
    assert_eq!(chunks, summary.chunk_indexes.len());
}
