//! [`Sink`]: the MCAP writer on a thread of its own, so that encoding the samples,
//! compressing the chunks and writing them out overlap with the simulation.
//!
//! The simulation thread checks each message (a bad number is reported at once, naming
//! the field) and puts it in a [`Batch`]: the `/state` and `/tf` samples as their numbers
//! (`samples.rs`: the bits of each `f64`, copied into one buffer of words; a sample's
//! layout, its pair or frame names, only when it changes), the other messages encoded
//! (JSON or protobuf), back to back in one buffer, and the impacts as copies of their
//! records. A full batch goes to the sink thread, which lays each sample's numbers out on
//! its own copy of the record and encodes it
//! ([`StateRecord::append_json`](super::records::StateRecord::append_json),
//! [`append_frame_transforms`](super::foxglove::append_frame_transforms)), encodes the
//! three messages of an impact (its ledger entry on `/impacts`, its arrow on `/scene`, its
//! line on `/log`) and writes every message to the `mcap::Writer`.
//!
//! Where the samples are encoded (issue 16): copied as records (vectors, names) and encoded
//! here, the copies allocated (a short run's batches are mostly new ones) and cost about
//! what the encoding does; encoded on the calling thread, they were half of what logging
//! cost the simulation thread (Kane's pendulum, 5 s at 100 Hz: 4,400 of the 8,600
//! instructions of a sample), while this thread, which compresses, had time to spare on a
//! second core. As numbers they cost the calling thread a copy of ~40 words and allocate
//! nothing: 1.9M instructions fewer per run on the simulation thread, 0.5M more over both.
//! They go as numbers only while this thread keeps up ([`Sink::defers_samples`]): where
//! the simulation is cheaper per sample than writing it (the end of that run), or with no
//! core to spare, the calling thread encodes them, as before.
//!
//! The schemas and channels are registered on the sink thread right before the first
//! message, so that they share its chunk: a chunk that held only schemas and channels
//! (which a metadata record written next would close) has no message index, and readers
//! that bundle `@mcap/core` before 2025 (Foxglove Studio 1.48 among them) refuse such a
//! file. The channel ids are fixed in advance ([`ChannelSpec::id`]), so the calling side
//! can stamp its messages before the channels exist. Batches
//! and metadata go through one bounded channel, in order, so the file's bytes are those a
//! writer on the calling thread would produce: two runs of the same scene still give
//! byte-identical logs. Sending messages in batches keeps the cost of the channel (a
//! wake-up of the other thread) off each message. The batches come back through a
//! second channel and are reused, so that a run in its steady state allocates nothing
//! per message.
//!
//! The thread is kept for the next log when its log is done ([`run_on_log_thread`]), so
//! that a short run does not pay for a thread's start and end.
//!
//! Errors: an I/O error met on the sink thread is kept and returned by a later call on the
//! calling side (a message, [`Sink::flush`] or [`Sink::finish`]); what follows it is not
//! written. A sink dropped without [`Sink::finish`] (an early return, a panic unwinding)
//! sends its open batch, closes the channel and waits for the thread to be done with the
//! log: it drops the `mcap::Writer`: its `Drop` finishes the file, so the log stays a valid MCAP file
//! holding everything given so far.

use std::io::{Seek, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};

use mcap::McapError;
use mcap::records::{MessageHeader, Metadata};

use super::LogError;
use super::draw::{self, ArrowStyle};
use super::foxglove::{
    FrameTransforms, LogLevel, SceneUpdate, append_frame_transforms, append_protobuf,
};
use super::records::{ImpactRecord, StateRecord};
use super::run::impact_line;
use super::samples::{
    apply_planar_words, apply_state_words, apply_transforms_words, planar_words, same_state_layout,
    same_transforms_layout, state_words, transforms_words,
};
use super::schemas::Topic;
use super::writer::log_message;

/// Batches that may wait in the channel for the sink thread. A full channel makes the
/// simulation wait (back-pressure) rather than grow without bound.
const QUEUE: usize = 8;

/// A batch is sent when it holds this many messages…
const BATCH_MESSAGES: usize = 64;

/// …or this many bytes.
const BATCH_BYTES: usize = 64 * 1024;

/// A channel to register before the first message, with its schema.
pub(super) struct ChannelSpec {
    /// The channel id (also the schema id), fixed in advance.
    pub id: u16,
    /// The topic.
    pub topic: Topic,
}

/// What a message of a batch holds.
enum Payload {
    /// Encoded bytes, `bytes[start..end]` of the batch.
    Bytes { start: usize, end: usize },
    /// A `/state` sample: its numbers from `words[at..]`, laid out on the sink thread's
    /// record, which first becomes a copy of `state_layouts[k]` for a `layout` `Some(k)`
    /// (see `samples.rs`).
    State { at: usize, layout: Option<usize> },
    /// A `/tf` sample: likewise, on the sink thread's transforms (`tf_layouts`).
    Transforms { at: usize, layout: Option<usize> },
    /// A planar `/tf` sample: its time and each frame's position and rotation as a
    /// complex number from `words[at..]`, laid out on the sink thread's transforms
    /// (`tf_layouts`, as for `Transforms`) by `samples::apply_planar_words`.
    Planar { at: usize, layout: Option<usize> },
    /// The ledger entry of impact slot `k` (`/impacts`, JSON).
    Impact(usize),
    /// The arrow of impact slot `k` (`/scene`, protobuf).
    Arrow(usize),
    /// The `/log` line of impact slot `k` (protobuf).
    ImpactLine(usize),
}

/// An impact to write: its ledger entry, and the length (m) and style of its arrow.
struct ImpactSlot {
    record: ImpactRecord,
    arrow: (f64, ArrowStyle),
}

/// Messages in order, with the bytes and impact records they refer to. Its vectors and the
/// records in its slots keep their allocations when the batch is cleared and reused.
#[derive(Default)]
pub(super) struct Batch {
    messages: Vec<(MessageHeader, Payload)>,
    /// Bytes of the messages encoded on the calling thread, back to back.
    bytes: Vec<u8>,
    /// Numbers of the `/state` and `/tf` samples, back to back (see `samples.rs`).
    words: Vec<u64>,
    /// New layouts of `/state` samples (rare: the first sample, a change of listed pairs).
    state_layouts: Vec<StateRecord>,
    /// New layouts of `/tf` samples.
    tf_layouts: Vec<FrameTransforms>,
    /// Impacts; the first `n_impacts` are in use.
    impacts: Vec<ImpactSlot>,
    n_impacts: usize,
}

impl Batch {
    fn clear(&mut self) {
        self.messages.clear();
        self.bytes.clear();
        self.words.clear();
        self.state_layouts.clear();
        self.tf_layouts.clear();
        self.n_impacts = 0;
    }

    /// An empty batch with the capacities of this one's buffers.
    fn empty_like(&self) -> Batch {
        Batch {
            messages: Vec::with_capacity(self.messages.capacity()),
            bytes: Vec::with_capacity(self.bytes.capacity()),
            words: Vec::with_capacity(self.words.capacity()),
            ..Batch::default()
        }
    }

    fn is_full(&self) -> bool {
        self.messages.len() >= BATCH_MESSAGES || self.bytes.len() >= BATCH_BYTES
    }

    /// A copy of `impact` and its arrow in the next free slot; its index.
    fn add_impact(&mut self, impact: &ImpactRecord, arrow: (f64, ArrowStyle)) -> usize {
        let k = self.n_impacts;
        match self.impacts.get_mut(k) {
            Some(slot) => {
                slot.record.clone_from(impact);
                slot.arrow = arrow;
            }
            None => self.impacts.push(ImpactSlot {
                record: impact.clone(),
                arrow,
            }),
        }
        self.n_impacts += 1;
        k
    }
}

/// What the sink thread is asked to do, in order.
enum Command {
    /// Write the messages of a batch to their known channels.
    Messages(Batch),
    /// Write a metadata record.
    Metadata(Metadata),
    /// Close the current chunk, flush it, and answer.
    Flush(SyncSender<Result<(), McapError>>),
    /// Write the summary section and the footer, and hand the writer back.
    Finish,
}

/// The first I/O error of the sink thread, shared with the calling side.
#[derive(Default)]
struct Failure {
    /// Set once `error` holds an error (cheap to test at every message).
    failed: AtomicBool,
    error: Mutex<Option<LogError>>,
    /// The error's text with its causes, kept for the calls after the one that got it.
    text: Mutex<String>,
}

impl Failure {
    fn set(&self, error: LogError) {
        // The mcap crate reports an I/O error met while binrw writes a record as a parse
        // error; the caller sees the I/O error itself (a full disk, a closed pipe).
        let error = match error {
            LogError::Mcap(McapError::Parse(binrw::Error::Io(io))) => {
                LogError::Mcap(McapError::Io(io))
            }
            other => other,
        };
        if let Ok(mut slot) = self.error.lock()
            && slot.is_none()
            && !self.failed.load(Ordering::Acquire)
        {
            if let Ok(mut text) = self.text.lock() {
                *text = crate::sim::describe(&error);
            }
            *slot = Some(error);
        }
        self.failed.store(true, Ordering::Release);
    }

    /// The error, once: later calls see `Err(SinkFailed)`, which repeats its text.
    fn take(&self) -> Result<(), LogError> {
        if !self.failed.load(Ordering::Acquire) {
            return Ok(());
        }
        match self.error.lock().ok().and_then(|mut slot| slot.take()) {
            Some(error) => Err(error),
            None => Err(self.stopped()),
        }
    }

    /// `SinkFailed` with the first error's text, or `otherwise` if there was none.
    fn stopped_or(&self, otherwise: &str) -> LogError {
        let text = self.text.lock().map(|t| t.clone()).unwrap_or_default();
        LogError::SinkFailed {
            cause: if text.is_empty() {
                otherwise.to_owned()
            } else {
                text
            },
        }
    }

    /// `SinkFailed` after the first error.
    fn stopped(&self) -> LogError {
        self.stopped_or("its thread ended unexpectedly")
    }
}

/// The `mcap::Writer` on its own thread (see the module doc).
pub(super) struct Sink<W: Write + Seek + Send + 'static> {
    commands: Option<SyncSender<Command>>,
    /// The batch being filled.
    open: Batch,
    /// The layout of the last `/state` sample sent, which the sink thread holds.
    state_layout: Option<StateRecord>,
    /// The layout of the last `/tf` sample sent.
    tf_layout: Option<FrameTransforms>,
    /// Batches coming back from the sink thread, for reuse.
    spare: Receiver<Batch>,
    failure: Arc<Failure>,
    /// Batches sent to the sink thread.
    sent: u64,
    /// Batches the sink thread has written (it counts them).
    written: Arc<AtomicU64>,
    /// Tests: whether samples go as numbers whatever the sink thread's progress.
    pub(super) defer: Option<bool>,
    /// What [`serve`] returns, once it has returned: disconnected without it if the
    /// thread panicked.
    done: Option<Receiver<Option<Result<W, McapError>>>>,
}

impl<W: Write + Seek + Send + 'static> Sink<W> {
    /// Moves `mcap` (which must not limit its chunks' size itself) to a log thread (an
    /// idle one, or a new one: [`run_on_log_thread`]) that writes what the sink is given, registering `channels` right before the first
    /// message, and closing a chunk once its messages reach `chunk_size` bytes.
    pub(super) fn spawn(
        mcap: mcap::Writer<W>,
        channels: Vec<ChannelSpec>,
        chunk_size: u64,
    ) -> Result<Self, LogError> {
        let writing = Writing {
            mcap,
            channels,
            chunk_size: chunk_size.max(1),
            in_chunk: 0,
            chunks: 0,
            encoded: Vec::new(),
            state: None,
            tf: None,
        };
        let (commands, inbox) = sync_channel(QUEUE);
        let (recycle, spare) = sync_channel(QUEUE + 2);
        let failure = Arc::new(Failure::default());
        let shared = Arc::clone(&failure);
        let written = Arc::new(AtomicU64::new(0));
        let counter = Arc::clone(&written);
        let (answer, done) = sync_channel(1);
        run_on_log_thread(Box::new(move |idle: &mut dyn FnMut()| {
            let result = serve(writing, &inbox, &recycle, (&shared, &counter));
            // Idle before answering, so that a log started as soon as this one is
            // finished finds the thread free.
            idle();
            let _ = answer.send(result);
        }))?;
        Ok(Sink {
            commands: Some(commands),
            open: Batch::default(),
            state_layout: None,
            tf_layout: None,
            spare,
            failure,
            sent: 0,
            written,
            defer: None,
            done: Some(done),
        })
    }

    /// The buffer to encode the next message into: append its bytes, then call
    /// [`push`](Self::push) with the length the buffer had before, or truncate it back
    /// to that length to drop the message.
    pub(super) fn buffer(&mut self) -> &mut Vec<u8> {
        &mut self.open.bytes
    }

    /// Adds the message encoded in [`buffer`](Self::buffer) from `start` on, to be
    /// written with `header`.
    pub(super) fn push(&mut self, header: MessageHeader, start: usize) -> Result<(), LogError> {
        if let Err(e) = self.failure.take() {
            self.open.bytes.truncate(start);
            return Err(e);
        }
        let end = self.open.bytes.len();
        self.open
            .messages
            .push((header, Payload::Bytes { start, end }));
        self.send_if_full()
    }

    /// Whether to hand the next sample to the sink thread as numbers, to be encoded there
    /// (see `samples.rs`): unless that thread is behind, a whole batch waiting for it
    /// besides the one it writes. Where the simulation is cheap (a pendulum sliding
    /// steadily: ~1 µs of its thread per sample) and the sink thread slower than it
    /// (writing and compressing a sample's two messages: ~2 µs), the calling thread
    /// encodes the samples itself again, so that less remains to do when the run ends;
    /// with no second core to spare, it thus does what it did before samples went as
    /// numbers. The bytes are the same either way.
    pub(super) fn defers_samples(&self) -> bool {
        if let Some(defer) = self.defer {
            return defer;
        }
        self.sent
            .saturating_sub(self.written.load(Ordering::Acquire))
            < 2
    }

    /// Adds the `/state` sample `state` (its numbers, and its layout if it is new; encoded
    /// on the sink thread), to be written with `header`.
    pub(super) fn push_state(
        &mut self,
        header: MessageHeader,
        state: &StateRecord,
    ) -> Result<(), LogError> {
        self.failure.take()?;
        let batch = &mut self.open;
        let layout = new_layout(
            &mut self.state_layout,
            &mut batch.state_layouts,
            state,
            same_state_layout,
        );
        let at = batch.words.len();
        state_words(&mut batch.words, state);
        batch.messages.push((header, Payload::State { at, layout }));
        self.send_if_full()
    }

    /// Adds the `/tf` sample `tf`, which must be
    /// [plain](super::samples::plain_transforms) (its numbers, and its layout if it is
    /// new; encoded on the sink thread), to be written with `header`.
    pub(super) fn push_transforms(
        &mut self,
        header: MessageHeader,
        tf: &FrameTransforms,
    ) -> Result<(), LogError> {
        self.failure.take()?;
        let batch = &mut self.open;
        let layout = new_layout(
            &mut self.tf_layout,
            &mut batch.tf_layouts,
            tf,
            same_transforms_layout,
        );
        let at = batch.words.len();
        transforms_words(&mut batch.words, tf);
        (batch.messages).push((header, Payload::Transforms { at, layout }));
        self.send_if_full()
    }

    /// Adds the planar `/tf` sample of the transforms `layout` (their frames' names) at
    /// `time` (ns): each frame's `[x, y, cos θ, sin θ]` from `frames` (one per transform
    /// of `layout`; the angle, its quaternion and the message computed on the sink
    /// thread), to be written with `header`. Returns `false`, adding nothing, if a number
    /// is not finite.
    pub(super) fn push_planar(
        &mut self,
        header: MessageHeader,
        layout: &FrameTransforms,
        time: u64,
        frames: impl Iterator<Item = [f64; 4]>,
    ) -> Result<bool, LogError> {
        self.failure.take()?;
        let batch = &mut self.open;
        let at = batch.words.len();
        if !planar_words(&mut batch.words, time, (layout.transforms.len(), frames)) {
            return Ok(false);
        }
        let layout = new_layout(
            &mut self.tf_layout,
            &mut batch.tf_layouts,
            layout,
            same_transforms_layout,
        );
        (batch.messages).push((header, Payload::Planar { at, layout }));
        self.send_if_full()?;
        Ok(true)
    }

    /// Adds an impact (copied; its three messages encoded on the sink thread) with the
    /// headers of its ledger entry, its arrow and its log line.
    pub(super) fn push_impact(
        &mut self,
        headers: [MessageHeader; 3],
        impact: &ImpactRecord,
        arrow: (f64, ArrowStyle),
    ) -> Result<(), LogError> {
        self.failure.take()?;
        let k = self.open.add_impact(impact, arrow);
        let [ledger, scene, log] = headers;
        (self.open.messages).extend([
            (ledger, Payload::Impact(k)),
            (scene, Payload::Arrow(k)),
            (log, Payload::ImpactLine(k)),
        ]);
        self.send_if_full()
    }

    fn send_if_full(&mut self) -> Result<(), LogError> {
        if self.open.is_full() {
            self.send_batch()?;
        }
        Ok(())
    }

    /// Sends a metadata record to be written (after the messages given before it).
    pub(super) fn metadata(&mut self, metadata: Metadata) -> Result<(), LogError> {
        self.send_batch()?;
        self.send(Command::Metadata(metadata))
    }

    /// Waits until everything given so far is written and flushed out of the writer.
    pub(super) fn flush(&mut self) -> Result<(), LogError> {
        self.send_batch()?;
        let (answer, reply) = sync_channel(1);
        self.send(Command::Flush(answer))?;
        let result = reply.recv().map_err(|_| self.failure.stopped())?;
        self.failure.take()?;
        Ok(result?)
    }

    /// Finishes the file and returns the underlying writer.
    pub(super) fn finish(mut self) -> Result<W, LogError> {
        self.send_batch()?;
        self.send(Command::Finish)?;
        self.commands = None;
        let done = self.done.take().ok_or_else(|| self.failure.stopped())?;
        match done.recv() {
            Ok(Some(result)) => Ok(result?),
            Ok(None) => {
                self.failure.take()?;
                Err(self.failure.stopped())
            }
            Err(_) => Err(self.failure.stopped_or("its thread panicked")),
        }
    }

    /// Sends the open batch, if it holds anything, and opens a spare one.
    fn send_batch(&mut self) -> Result<(), LogError> {
        if self.open.messages.is_empty() {
            return Ok(());
        }
        // A new batch (the sink thread still holds the others) starts with the capacities
        // of this one, so that it does not grow message by message.
        let mut next = (self.spare.try_recv()).unwrap_or_else(|_| self.open.empty_like());
        next.clear();
        let full = std::mem::replace(&mut self.open, next);
        self.sent += 1;
        self.send(Command::Messages(full))
    }

    fn send(&mut self, command: Command) -> Result<(), LogError> {
        self.failure.take()?;
        let commands = (self.commands.as_ref()).ok_or_else(|| self.failure.stopped())?;
        commands.send(command).map_err(|_| self.failure.stopped())
    }
}

impl<W: Write + Seek + Send + 'static> Drop for Sink<W> {
    /// Sends the open batch, closes the channel and waits for the thread to be done with
    /// the log; it finishes the file if [`Sink::finish`] was not called.
    fn drop(&mut self) {
        let _ = self.send_batch();
        self.commands = None;
        if let Some(done) = self.done.take() {
            let _ = done.recv();
        }
    }
}

/// The index in `layouts` (a batch's) of the layout of `now` if it is not the `last` one
/// handed to the sink thread: then it is added there and becomes `last`. `None` when the
/// sink thread has it already (`same`).
fn new_layout<T: Clone>(
    last: &mut Option<T>,
    layouts: &mut Vec<T>,
    now: &T,
    same: fn(&T, &T) -> bool,
) -> Option<usize> {
    if last.as_ref().is_some_and(|last| same(last, now)) {
        return None;
    }
    layouts.push(now.clone());
    *last = Some(now.clone());
    Some(layouts.len() - 1)
}

/// A log's work for a log thread: it calls its argument once it is done with the log
/// (which offers the thread to the next log) and then answers.
#[doc(hidden)]
pub type Job = Box<dyn FnOnce(&mut dyn FnMut()) + Send>;

/// Log threads that wait for a log to write, each as the sender of its jobs.
#[doc(hidden)]
pub static IDLE_LOG_THREADS: Mutex<Vec<SyncSender<Job>>> = Mutex::new(Vec::new());

/// Idle log threads kept for later logs; more end with their log.
#[doc(hidden)]
pub const IDLE_LOG_THREADS_KEPT: usize = 4;

/// Runs `job` on an idle log thread, or on a new one (`ricochet-log`).
///
/// A log's thread is kept for the next log rather than spawned for each (issue 16): Kane's
/// pendulum, 5 s at 100 Hz, is a run of ~1.5 ms, and spawning the thread cost its
/// simulation ~25 µs at the start, joining it ~30–50 µs at the end (the thread's exit and
/// the wake-up), and each new thread took fresh memory for the log's buffers (the
/// allocator gives a new thread an arena whose freed memory goes back to the system):
/// ~100 page faults of a run. A thread that panics ends, and is not kept.
#[doc(hidden)]
pub fn run_on_log_thread(mut job: Job) -> Result<(), LogError> {
    loop {
        let idle = IDLE_LOG_THREADS.lock().ok().and_then(|mut idle| idle.pop());
        let Some(thread) = idle else { break };
        match thread.send(job) {
            Ok(()) => return Ok(()),
            // That thread has ended (not expected: it ends only by a panic of its log's
            // job, before it offers itself again).
            Err(std::sync::mpsc::SendError(back)) => job = back,
        }
    }
    let (jobs, inbox) = sync_channel::<Job>(1);
    std::thread::Builder::new()
        .name("ricochet-log".to_owned())
        .spawn(move || log_thread(job, &jobs, &inbox))
        .map(drop)
        .map_err(LogError::Thread)
}

/// A log thread: runs `job`, offers itself for another (`me` into
/// [`IDLE_LOG_THREADS`], unless enough wait there), and runs the next from `inbox`.
fn log_thread(mut job: Job, me: &SyncSender<Job>, inbox: &Receiver<Job>) {
    loop {
        let mut kept = false;
        job(&mut || {
            if let Ok(mut idle) = IDLE_LOG_THREADS.lock()
                && idle.len() < IDLE_LOG_THREADS_KEPT
            {
                idle.push(me.clone());
                kept = true;
            }
        });
        if !kept {
            return;
        }
        match inbox.recv() {
            Ok(next) => job = next,
            Err(_) => return,
        }
    }
}

/// Bytes a message record adds to a chunk besides its data: opcode (1), record length
/// (8), channel id (2), sequence (4), log and publish times (8 + 8).
const MESSAGE_RECORD: u64 = 31;

/// Chunks closed at one target size before the target doubles (see [`chunk_target`]).
#[doc(hidden)]
pub const CHUNKS_PER_SIZE: u64 = 1024;

/// The largest chunk target the doubling reaches (bytes), the MCAP command line tool's
/// default chunk size: a reader decompresses a whole chunk to reach one of its messages.
#[doc(hidden)]
pub const MAX_CHUNK_SIZE: u64 = 4 << 20;

/// The target size of the messages of a chunk (before compression, bytes) after `closed`
/// chunks of a log whose first chunks' target is `first`: `first`, doubled after every
/// [`CHUNKS_PER_SIZE`] chunks, up to `max(first, MAX_CHUNK_SIZE)`.
///
/// The `mcap` writer keeps an index of every chunk in memory until it writes the summary
/// (about 260 bytes of heap, 700 of resident memory, per chunk): with a fixed 64 KiB, a log
/// of 1.7 GB (15 GB of messages) held 240,000 of them, 168 MB. Doubling the target keeps
/// a short run's chunks small (a killed run loses at most its open chunk; a viewer seeks
/// by chunks) and the chunk count of a long run `1024 log2(4 MiB / first) + bytes / 4 MiB`:
/// 6,144 + 3,600 for those 15 GB.
#[doc(hidden)]
pub fn chunk_target(first: u64, closed: u64) -> u64 {
    let doublings = u32::try_from(closed / CHUNKS_PER_SIZE).map_or(63, |d| d.min(63));
    (first.saturating_mul(1 << doublings)).min(first.max(MAX_CHUNK_SIZE))
}

/// The writer and its state on the sink thread.
struct Writing<W: Write + Seek> {
    mcap: mcap::Writer<W>,
    /// The channels to register before the first message (empty once registered).
    channels: Vec<ChannelSpec>,
    /// Target size of the first chunks' messages, before compression (bytes); see
    /// [`chunk_target`].
    chunk_size: u64,
    /// Size of the messages in the open chunk (bytes).
    in_chunk: u64,
    /// Chunks closed so far.
    chunks: u64,
    /// The messages encoded here, reused.
    encoded: Vec<u8>,
    /// The `/state` record that samples are laid out on (see `samples.rs`).
    state: Option<StateRecord>,
    /// The `/tf` transforms that samples are laid out on.
    tf: Option<FrameTransforms>,
}

impl<W: Write + Seek> Writing<W> {
    /// Writes the messages of `batch`, registering the channels before the first one.
    ///
    /// The chunks are closed here, once their messages reach `chunk_size`, rather than by
    /// mcap's writer: it checks the size of the open chunk *before* writing a message, so a
    /// chunk holding schemas and channels larger than the target would be closed before
    /// the first message, without one.
    fn messages(&mut self, batch: &Batch) -> Result<(), LogError> {
        if !self.channels.is_empty() {
            register(&mut self.mcap, std::mem::take(&mut self.channels))?;
        }
        for (header, payload) in &batch.messages {
            let data = match *payload {
                Payload::Bytes { start, end } => &batch.bytes[start..end],
                Payload::State { at, layout } => {
                    if let Some(k) = layout {
                        self.state = batch.state_layouts.get(k).cloned();
                    }
                    let state = self.state.as_mut().ok_or_else(no_layout)?;
                    apply_state_words(state, batch.words.get(at..).unwrap_or_default());
                    self.encoded.clear();
                    state.append_json(&mut self.encoded);
                    &self.encoded[..]
                }
                Payload::Transforms { at, layout } | Payload::Planar { at, layout } => {
                    if let Some(k) = layout {
                        self.tf = batch.tf_layouts.get(k).cloned();
                    }
                    let tf = self.tf.as_mut().ok_or_else(no_layout)?;
                    let words = batch.words.get(at..).unwrap_or_default();
                    if let Payload::Planar { .. } = payload {
                        apply_planar_words(tf, words);
                    } else {
                        apply_transforms_words(tf, words);
                    }
                    self.encoded.clear();
                    append_frame_transforms(&mut self.encoded, tf);
                    &self.encoded[..]
                }
                Payload::Impact(k) => {
                    self.encoded.clear();
                    let record = &batch.impacts[k].record;
                    append_json(&mut self.encoded, Topic::Impacts, record)?;
                    &self.encoded[..]
                }
                Payload::Arrow(k) => {
                    self.encoded.clear();
                    let ImpactSlot { record, arrow } = &batch.impacts[k];
                    append_protobuf(
                        &mut self.encoded,
                        Topic::Scene.name(),
                        &arrow_update(record, *arrow)?,
                    )?;
                    &self.encoded[..]
                }
                Payload::ImpactLine(k) => {
                    self.encoded.clear();
                    let record = &batch.impacts[k].record;
                    let line = log_message(record.t, LogLevel::Info, &impact_line(record))?;
                    append_protobuf(&mut self.encoded, Topic::Log.name(), &line)?;
                    &self.encoded[..]
                }
            };
            self.mcap.write_to_known_channel(header, data)?;
            self.in_chunk += data.len() as u64 + MESSAGE_RECORD;
            if self.in_chunk >= chunk_target(self.chunk_size, self.chunks) {
                self.close_chunk()?;
            }
        }
        Ok(())
    }

    /// Closes the open chunk, if any, and flushes the writer.
    fn close_chunk(&mut self) -> Result<(), McapError> {
        self.chunk_closed();
        self.mcap.flush()
    }

    /// Writes a metadata record (which closes the open chunk).
    fn metadata(&mut self, metadata: &Metadata) -> Result<(), McapError> {
        self.chunk_closed();
        self.mcap.write_metadata(metadata)
    }

    /// Counts the open chunk, if it holds messages, as closed.
    fn chunk_closed(&mut self) {
        if self.in_chunk > 0 {
            self.chunks += 1;
        }
        self.in_chunk = 0;
    }
}

/// The sink thread: carries out the commands in order until `Finish` (returns the writer,
/// or `None` after an error) or the channel closes (returns `None`; dropping `mcap`
/// finishes the file).
fn serve<W: Write + Seek>(
    mut writing: Writing<W>,
    inbox: &Receiver<Command>,
    recycle: &SyncSender<Batch>,
    (failure, done): (&Failure, &AtomicU64),
) -> Option<Result<W, McapError>> {
    let mut broken = false;
    for command in inbox {
        let result = match command {
            Command::Messages(batch) => {
                let written = if broken {
                    Ok(())
                } else {
                    writing.messages(&batch)
                };
                done.fetch_add(1, Ordering::Release);
                // The batch goes back for reuse; if the pool is full, it is dropped.
                let _ = recycle.try_send(batch);
                written
            }
            Command::Metadata(_) if broken => Ok(()),
            Command::Metadata(metadata) => writing.metadata(&metadata).map_err(LogError::from),
            Command::Flush(answer) => {
                let result = if broken {
                    Ok(())
                } else {
                    writing.close_chunk()
                };
                let _ = answer.send(result);
                Ok(())
            }
            Command::Finish if broken => return None,
            Command::Finish => {
                let mut mcap = writing.mcap;
                return Some(mcap.finish().and_then(|_summary| {
                    let mut inner = mcap.into_inner();
                    inner.flush().map_err(McapError::from)?;
                    Ok(inner)
                }));
            }
        };
        if let Err(e) = result {
            broken = true;
            failure.set(e);
        }
    }
    None
}

/// A sample reached the sink thread before its layout (which the calling side sends
/// first: not expected).
fn no_layout() -> LogError {
    LogError::SinkFailed {
        cause: "a sample reached the log writer's thread without its layout".to_owned(),
    }
}

/// The `/scene` update of an impact: its arrow, `length` (m) long in `style`.
pub(super) fn arrow_update(
    impact: &ImpactRecord,
    (length, style): (f64, ArrowStyle),
) -> Result<SceneUpdate, LogError> {
    Ok(SceneUpdate {
        deletions: vec![],
        entities: vec![draw::impulse_arrow(impact, length, &style)?],
    })
}

/// Appends `message` as JSON to `buffer`; on an error `buffer` is left as it was. The one
/// JSON encoding of the log's messages, on either thread.
pub(super) fn append_json<M: serde::Serialize>(
    buffer: &mut Vec<u8>,
    topic: Topic,
    message: &M,
) -> Result<(), LogError> {
    let start = buffer.len();
    serde_json::to_writer(&mut *buffer, message).map_err(|source| {
        buffer.truncate(start);
        LogError::Encode {
            what: topic.name(),
            source,
        }
    })
}

/// Registers the schemas and channels of `channels`, with their fixed ids. Topics of the
/// same schema share one schema record, whose id is that of the first of them.
fn register<W: Write + Seek>(
    mcap: &mut mcap::Writer<W>,
    channels: Vec<ChannelSpec>,
) -> Result<(), McapError> {
    let mut schemas: Vec<(&str, u16)> = Vec::new();
    for spec in channels {
        let topic = spec.topic;
        let schema_id = match schemas
            .iter()
            .find(|(name, _)| *name == topic.schema_name())
        {
            Some(&(_, id)) => id,
            None => {
                mcap.add_schema_with_id(
                    spec.id,
                    topic.schema_name(),
                    topic.schema_encoding(),
                    &topic.schema(),
                )?;
                schemas.push((topic.schema_name(), spec.id));
                spec.id
            }
        };
        mcap.add_channel_with_id(
            spec.id,
            schema_id,
            topic.name(),
            topic.message_encoding(),
            &std::collections::BTreeMap::new(),
        )?;
    }
    Ok(())
}
