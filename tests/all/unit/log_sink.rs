//! The unit tests of `log::sink` (`src/log/sink.rs`).

// The source module's own imports.
use ricochet::log::foxglove::LogLevel;
use ricochet::log::schemas::Topic;
use std::sync::mpsc::sync_channel;

use ricochet::log::sink::*;

#[test]
fn the_chunk_target_doubles_every_1024_chunks_up_to_4_mib() {
    let k = 64 * 1024;
    assert_eq!(chunk_target(k, 0), k);
    assert_eq!(chunk_target(k, 1023), k);
    assert_eq!(chunk_target(k, 1024), 2 * k);
    assert_eq!(chunk_target(k, 6 * 1024 - 1), 32 * k);
    assert_eq!(chunk_target(k, 6 * 1024), MAX_CHUNK_SIZE);
    assert_eq!(chunk_target(k, u64::MAX), MAX_CHUNK_SIZE);
    // A first target beyond the largest stays.
    assert_eq!(chunk_target(8 << 20, 5000), 8 << 20);
    assert_eq!(chunk_target(1, 1 << 40), MAX_CHUNK_SIZE);
}

/// The chunks (hence the chunk indexes the `mcap` writer keeps) of 15 GB of messages
/// in 64 KiB steps: 9,700, where a fixed 64 KiB made 229,000.
#[test]
fn a_long_log_has_few_chunks() {
    let (first, total) = (64 * 1024u64, 15_000_000_000u64);
    let (mut written, mut chunks) = (0, 0);
    while written < total {
        written += chunk_target(first, chunks);
        chunks += 1;
    }
    let bound = CHUNKS_PER_SIZE * 6 + total.div_ceil(MAX_CHUNK_SIZE);
    assert!(chunks <= bound, "{chunks} > {bound}");
    assert!(chunks * 23 < total / first, "{chunks}");
}

/// A log of `n` `/log` lines in small chunks, its bytes.
fn small_log(n: usize) -> Vec<u8> {
    let options = ricochet::log::LogOptions {
        chunk_size: 2048,
        ..ricochet::log::LogOptions::default()
    };
    let mut log = ricochet::log::LogWriter::new(std::io::Cursor::new(Vec::new()), options)
        .expect("a log in memory");
    for k in 0..n {
        log.log(k as f64 * 0.01, LogLevel::Info, &format!("line {k}"))
            .expect("a line");
    }
    log.finish().expect("finished").into_inner()
}

/// The `/log` lines of `bytes`.
fn lines(bytes: &[u8]) -> usize {
    let stream = mcap::MessageStream::new(bytes).expect("an MCAP file");
    (stream.map(|m| m.expect("a message")))
        .filter(|m| m.channel.topic == Topic::Log.name())
        .count()
}

/// Logs written one after another (on the log thread of the one before, kept) and
/// eight at once (more threads than are kept) hold every line, the same bytes each,
/// and no more idle log threads are kept than `IDLE_LOG_THREADS_KEPT`.
#[test]
fn logs_on_kept_threads_and_at_once_are_the_same_bytes() {
    let first = small_log(300);
    assert_eq!(lines(&first), 300);
    for _ in 0..5 {
        assert!(small_log(300) == first);
    }
    let at_once: Vec<Vec<u8>> = std::thread::scope(|scope| {
        let logs: Vec<_> = (0..8).map(|_| scope.spawn(|| small_log(300))).collect();
        (logs.into_iter())
            .map(|log| log.join().expect("a log"))
            .collect()
    });
    assert!(at_once.iter().all(|bytes| *bytes == first));
    let idle = IDLE_LOG_THREADS
        .lock()
        .map_or(usize::MAX, |idle| idle.len());
    assert!(
        idle <= IDLE_LOG_THREADS_KEPT,
        "{idle} idle log threads kept"
    );
}

/// A job that panics ends its thread without answering (a sink reports it as
/// `SinkFailed`), and later logs are written.
#[test]
fn a_panicking_log_job_ends_its_thread_and_later_logs_are_written() {
    let (answer, reply) = sync_channel::<()>(1);
    let job: Job = Box::new(move |_idle: &mut dyn FnMut()| {
        let _answer = answer;
        panic!("a log job panics (this test expects it)");
    });
    run_on_log_thread(job).expect("a log thread");
    assert!(reply.recv().is_err());
    assert_eq!(lines(&small_log(10)), 10);
}
