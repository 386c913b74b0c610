//! [`Sink`]: the MCAP writer on a thread of its own, so that compressing the chunks and
//! writing them out overlaps with the simulation.
//!
//! The simulation thread encodes each message as JSON (where a bad number is caught and
//! reported at once) and sends the bytes; the sink thread writes them to the
//! `mcap::Writer`, which compresses a chunk when it is full. The commands go through one
//! bounded channel, in order, so the file's bytes are those a writer on the calling thread
//! would produce: two runs of the same scene still give byte-identical logs. The message
//! buffers come back through a second channel and are reused, so that a run in its steady
//! state allocates nothing per message.
//!
//! Errors: an I/O error met on the sink thread is kept and returned by the next call
//! on the calling side (a write, [`Sink::flush`] or [`Sink::finish`]); what follows it is not
//! written. A sink dropped without [`Sink::finish`] (an early return, a panic unwinding)
//! closes the channel and waits for the thread, which drops the `mcap::Writer`: its `Drop`
//! finishes the file, so the log stays a valid MCAP file holding everything sent so far.

use std::io::{Seek, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use mcap::McapError;
use mcap::records::{MessageHeader, Metadata};

use super::LogError;

/// Messages that may wait in the channel for the sink thread. A full channel makes the
/// simulation wait (back-pressure) rather than grow without bound.
const QUEUE: usize = 256;

/// What the sink thread is asked to do, in order.
enum Command {
    /// Write a message (its JSON bytes) to a known channel.
    Message {
        header: MessageHeader,
        data: Vec<u8>,
    },
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
    error: Mutex<Option<McapError>>,
}

impl Failure {
    fn set(&self, error: McapError) {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(error);
        }
        self.failed.store(true, Ordering::Release);
    }

    /// The error, once: later calls see `Err(SinkFailed)`.
    fn take(&self) -> Result<(), LogError> {
        if !self.failed.load(Ordering::Acquire) {
            return Ok(());
        }
        match self.error.lock().ok().and_then(|mut slot| slot.take()) {
            Some(error) => Err(error.into()),
            None => Err(LogError::SinkFailed),
        }
    }
}

/// The `mcap::Writer` on its own thread (see the module doc).
pub(super) struct Sink<W: Write + Seek + Send + 'static> {
    commands: Option<SyncSender<Command>>,
    /// Message buffers coming back from the sink thread, for reuse.
    spare: Receiver<Vec<u8>>,
    failure: Arc<Failure>,
    thread: Option<JoinHandle<Option<Result<W, McapError>>>>,
}

impl<W: Write + Seek + Send + 'static> Sink<W> {
    /// Moves `mcap` to a new thread that writes what the sink is given.
    pub(super) fn spawn(mcap: mcap::Writer<W>) -> Result<Self, LogError> {
        let (commands, inbox) = sync_channel(QUEUE);
        let (recycle, spare) = sync_channel(QUEUE + 2);
        let failure = Arc::new(Failure::default());
        let shared = Arc::clone(&failure);
        let thread = std::thread::Builder::new()
            .name("ricochet-log".to_owned())
            .spawn(move || serve(mcap, &inbox, &recycle, &shared))
            .map_err(LogError::Thread)?;
        Ok(Sink {
            commands: Some(commands),
            spare,
            failure,
            thread: Some(thread),
        })
    }

    /// An empty buffer to encode the next message into: a returned one if any.
    pub(super) fn buffer(&mut self) -> Vec<u8> {
        let mut buffer = self.spare.try_recv().unwrap_or_default();
        buffer.clear();
        buffer
    }

    /// Sends a message (its bytes in `data`) to be written with `header`.
    pub(super) fn message(&mut self, header: MessageHeader, data: Vec<u8>) -> Result<(), LogError> {
        self.send(Command::Message { header, data })
    }

    /// Sends a metadata record to be written.
    pub(super) fn metadata(&mut self, metadata: Metadata) -> Result<(), LogError> {
        self.send(Command::Metadata(metadata))
    }

    /// Waits until everything sent so far is written and flushed out of the writer.
    pub(super) fn flush(&mut self) -> Result<(), LogError> {
        let (answer, reply) = sync_channel(1);
        self.send(Command::Flush(answer))?;
        let result = reply.recv().map_err(|_| LogError::SinkFailed)?;
        self.failure.take()?;
        Ok(result?)
    }

    /// Finishes the file and returns the underlying writer.
    pub(super) fn finish(mut self) -> Result<W, LogError> {
        self.send(Command::Finish)?;
        self.commands = None;
        let thread = self.thread.take().ok_or(LogError::SinkFailed)?;
        match thread.join() {
            Ok(Some(result)) => Ok(result?),
            Ok(None) => {
                self.failure.take()?;
                Err(LogError::SinkFailed)
            }
            Err(_) => Err(LogError::SinkFailed),
        }
    }

    fn send(&mut self, command: Command) -> Result<(), LogError> {
        self.failure.take()?;
        let commands = self.commands.as_ref().ok_or(LogError::SinkFailed)?;
        commands.send(command).map_err(|_| LogError::SinkFailed)
    }
}

impl<W: Write + Seek + Send + 'static> Drop for Sink<W> {
    /// Closes the channel and waits for the thread, which finishes the file if
    /// [`Sink::finish`] was not called.
    fn drop(&mut self) {
        self.commands = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The sink thread: carries out the commands in order until `Finish` (returns the writer,
/// or `None` after an error) or the channel closes (returns `None`; dropping `mcap`
/// finishes the file).
fn serve<W: Write + Seek>(
    mut mcap: mcap::Writer<W>,
    inbox: &Receiver<Command>,
    recycle: &SyncSender<Vec<u8>>,
    failure: &Failure,
) -> Option<Result<W, McapError>> {
    let mut broken = false;
    for command in inbox {
        match command {
            Command::Message { header, data } => {
                if !broken && let Err(e) = mcap.write_to_known_channel(&header, &data) {
                    broken = true;
                    failure.set(e);
                }
                // The buffer goes back for reuse; if the pool is full, it is dropped.
                let _ = recycle.try_send(data);
            }
            Command::Metadata(metadata) => {
                if !broken && let Err(e) = mcap.write_metadata(&metadata) {
                    broken = true;
                    failure.set(e);
                }
            }
            Command::Flush(answer) => {
                let result = if broken { Ok(()) } else { mcap.flush() };
                let _ = answer.send(result);
            }
            Command::Finish if broken => return None,
            Command::Finish => {
                return Some(mcap.finish().and_then(|_summary| {
                    let mut inner = mcap.into_inner();
                    inner.flush().map_err(McapError::from)?;
                    Ok(inner)
                }));
            }
        }
    }
    None
}
