//! Issue 12, item 9: a long run's memory grew with its log (168 MB for a 1.7 GB log). What
//! grew is the `mcap` writer's list of chunk indexes, which it keeps for the summary: one
//! per 64 KiB chunk, about 700 bytes of resident memory each (measured: the rimless wheel
//! at 1 kHz for 1000 s wrote 18,316 chunks and its peak RSS rose by 14 MB).
//!
//! The log's chunk target now doubles after every 1,024 chunks, up to 4 MiB, so that a
//! long log has `1024 log2(4 MiB / 64 KiB) + bytes / 4 MiB` chunks instead of
//! `bytes / 64 KiB`. Checked here on the chunks that the writer actually closes, read back
//! from the summary of a log written with a 1 KiB first target.

use std::io::Cursor;

use ricochet::log::{ContactMode, ContactState, Energy, LogOptions, LogWriter, StateRecord};

fn state(i: usize) -> StateRecord {
    let t = i as f64 * 1e-3;
    let q = vec![0.1 * t, (7.0 * t).cos(), t / 3.0];
    let u = vec![0.1, -1.75 * (7.0 * t).sin(), 1.0 / 3.0];
    let contacts = vec![ContactState::new("ball/ground", ContactMode::Free, 0.3 + t)];
    StateRecord::new(t, q, u, Energy::new(1.0 + t, 2.0), contacts, i as u64)
}

#[test]
fn the_chunks_of_a_long_log_grow() {
    let first = 1024;
    let options = LogOptions {
        chunk_size: first,
        ..LogOptions::default()
    };
    let mut log = LogWriter::new(Cursor::new(Vec::new()), options).unwrap();
    // Enough messages for four targets and a half: 1, 2, 4, 8 KiB, then 16 KiB.
    let mut i = 0;
    let mut bytes = 0u64;
    while bytes < 1024 * (1 + 2 + 4 + 8 + 8) * 1024 {
        let s = state(i);
        bytes += serde_json::to_vec(&s).unwrap().len() as u64 + 31;
        log.state(&s).unwrap();
        i += 1;
    }
    let file = log.finish().unwrap().into_inner();
    let summary = mcap::Summary::read(&file).unwrap().unwrap();
    let chunks = &summary.chunk_indexes;
    println!("{i} messages, {} chunks", chunks.len());
    // Every chunk that the size closed is at least its target, and less than the target
    // and one message more (the first also holds the schemas and channels; the last is
    // closed by `finish`).
    let message = 400;
    for (k, c) in chunks[..chunks.len() - 1].iter().enumerate().skip(1) {
        let target = first << (k / 1024).min(12);
        assert!(
            (target..target + message).contains(&c.uncompressed_size),
            "chunk {k}: {} bytes, target {target}",
            c.uncompressed_size
        );
    }
    // Four full targets and part of the fifth: at a fixed 1 KiB, 23,000 chunks.
    assert!(
        (4 * 1024..5 * 1024).contains(&chunks.len()),
        "{}",
        chunks.len()
    );
    assert!(bytes / first > 4 * chunks.len() as u64);
}
