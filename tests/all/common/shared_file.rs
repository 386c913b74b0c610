//! A `Write + Seek` whose bytes can be looked at while a writer owns it (shared by the
//! log tests).

use std::io::{Cursor, Seek, SeekFrom, Write};
use std::sync::{Arc, Mutex};

/// A `Write + Seek` whose bytes can be looked at while a writer owns it: what a killed
/// process leaves on disk (no user-space buffer).
#[derive(Clone, Default)]
pub struct SharedFile(Arc<Mutex<Cursor<Vec<u8>>>>);

impl SharedFile {
    /// The bytes written so far.
    pub fn snapshot(&self) -> Vec<u8> {
        self.0.lock().unwrap().get_ref().clone()
    }
}

impl Write for SharedFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for SharedFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.0.lock().unwrap().seek(pos)
    }
}
