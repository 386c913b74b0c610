//! Standard output and standard error that may close under us: `ricochet run … | head -1`
//! closes the pipe after one line (`2>&1 | head -1` closes standard error too), and what is
//! left to print has no reader. That is not a failure of the command, which goes on with
//! its work (a log, a table): the rest is not printed, and the command exits as it would
//! have. The commands print through [`say!`] and [`tell!`], never `println!`/`eprintln!`,
//! which panic on a closed pipe.

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

/// `println!` for the commands: a closed standard output is not an error (see the module);
/// any other error writing it is returned.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::output::print(&format!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use say;

/// Prints `text` and a newline to standard error. An error there is dropped: standard error
/// is where the command would report it, and the command's work does not depend on it.
pub fn tell_line(text: &str) {
    let mut err = io::stderr().lock();
    let _ = writeln!(err, "{text}").and_then(|()| err.flush());
}

/// `eprintln!` for the commands: a closed (or failing) standard error is not an error; see
/// [`tell_line`].
macro_rules! tell {
    ($($arg:tt)*) => {
        $crate::output::tell_line(&format!($($arg)*))
    };
}
pub(crate) use tell;
