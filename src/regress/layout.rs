//! The layout of ricochet's JSON documents (run summaries, golden files, comparisons):
//! objects one member per line, arrays one element per line, and each element of an array
//! on a line of its own, compact. A ledger of 40 impacts is 40 lines, so that a `diff` of
//! two documents names the impact that moved and a file stays small.
//!
//! Numbers are written by `serde_json` (the shortest decimal that reads back to the same
//! `f64`, `ryu`); with its `float_roundtrip` feature they read back bit-exact, and so does
//! Python's `json` module (`float(repr)` is correctly rounded).

use std::io::{self, Write};

use serde::Serialize;
use serde_json::ser::Formatter;

/// How a container is laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Each member or element on a line of its own, indented.
    Lines,
    /// On one line: `{"t": 0.5, "q": [1.0, 2.0]}`.
    Compact,
}

/// A container being written.
#[derive(Clone, Copy, Debug)]
struct Frame {
    mode: Mode,
    /// Whether it is an object (else an array).
    object: bool,
    has_value: bool,
}

/// The formatter: the root and the objects that are members of laid-out objects are laid
/// out one member per line; an array that is a member of such an object is one element per
/// line; everything inside an array element is compact.
#[derive(Debug, Default)]
pub(crate) struct Layout {
    stack: Vec<Frame>,
}

impl Layout {
    /// The mode of a container opened now.
    fn child_mode(&self) -> Mode {
        match self.stack.last() {
            None => Mode::Lines,
            Some(f) if f.mode == Mode::Lines && f.object => Mode::Lines,
            Some(_) => Mode::Compact,
        }
    }

    fn open<W: ?Sized + Write>(&mut self, w: &mut W, object: bool) -> io::Result<()> {
        let mode = self.child_mode();
        self.stack.push(Frame {
            mode,
            object,
            has_value: false,
        });
        w.write_all(if object { b"{" } else { b"[" })
    }

    fn close<W: ?Sized + Write>(&mut self, w: &mut W, object: bool) -> io::Result<()> {
        if let Some(f) = self.stack.pop()
            && f.mode == Mode::Lines
            && f.has_value
        {
            self.newline(w)?;
        }
        w.write_all(if object { b"}" } else { b"]" })
    }

    /// A new line indented to the depth of the open containers.
    fn newline<W: ?Sized + Write>(&self, w: &mut W) -> io::Result<()> {
        w.write_all(b"\n")?;
        for _ in 0..self.stack.len() {
            w.write_all(b"  ")?;
        }
        Ok(())
    }

    /// Before a member or element.
    fn item<W: ?Sized + Write>(&self, w: &mut W, first: bool) -> io::Result<()> {
        match self.stack.last().map(|f| f.mode) {
            Some(Mode::Lines) => {
                if !first {
                    w.write_all(b",")?;
                }
                self.newline(w)
            }
            _ if first => Ok(()),
            _ => w.write_all(b", "),
        }
    }

    fn mark(&mut self) {
        if let Some(f) = self.stack.last_mut() {
            f.has_value = true;
        }
    }
}

impl Formatter for Layout {
    fn begin_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.open(w, false)
    }
    fn end_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.close(w, false)
    }
    fn begin_array_value<W: ?Sized + Write>(&mut self, w: &mut W, first: bool) -> io::Result<()> {
        self.item(w, first)
    }
    fn end_array_value<W: ?Sized + Write>(&mut self, _: &mut W) -> io::Result<()> {
        self.mark();
        Ok(())
    }
    fn begin_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.open(w, true)
    }
    fn end_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.close(w, true)
    }
    fn begin_object_key<W: ?Sized + Write>(&mut self, w: &mut W, first: bool) -> io::Result<()> {
        self.item(w, first)
    }
    fn begin_object_value<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        w.write_all(b": ")
    }
    fn end_object_value<W: ?Sized + Write>(&mut self, _: &mut W) -> io::Result<()> {
        self.mark();
        Ok(())
    }
}

/// `value` as JSON text in the [`Layout`], with a final newline. A non-finite number would
/// be written as `null`: callers check for them first.
#[doc(hidden)]
pub fn to_string<T: Serialize + ?Sized>(value: &T) -> Result<String, serde_json::Error> {
    let mut out = Vec::new();
    let mut ser = serde_json::Serializer::with_formatter(&mut out, Layout::default());
    value.serialize(&mut ser)?;
    out.push(b'\n');
    // serde_json writes UTF-8 only.
    Ok(String::from_utf8_lossy(&out).into_owned())
}
