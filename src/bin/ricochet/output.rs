//! Standard output that may close under us: `ricochet run … | head -1` closes the pipe
//! after one line, and what is left to print has no reader. That is not a failure of the
//! command, which has done its work: the rest is not printed, and the command exits as it
//! would have.

use std::io::{self, Write};

/// Whether `error` says that the reader of the output is gone (`EPIPE`).
pub fn is_broken_pipe(error: &io::Error) -> bool {
    error.kind() == io::ErrorKind::BrokenPipe
}

/// `result` with a closed output taken for success.
pub fn unless_closed(result: io::Result<()>) -> io::Result<()> {
    match result {
        Err(e) if is_broken_pipe(&e) => Ok(()),
        other => other,
    }
}

/// Prints `text` to standard output; a closed output is not an error (see the module).
pub fn print(text: &str) -> io::Result<()> {
    let mut out = io::stdout().lock();
    unless_closed(out.write_all(text.as_bytes()).and_then(|()| out.flush()))
}
