//! The command-line tests' scaffolding: a fresh temporary folder per test, and the
//! `ricochet` binary run in it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The `ricochet` binary built for the tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_ricochet");

/// A fresh, empty temporary folder for one test, removed when dropped (named after the
/// test binary, the process, a number drawn once per folder and the test, so that tests
/// running at once never share one, even two of one binary that give the same name).
pub struct TempDir(PathBuf);

/// The number of the next `TempDir` of this process.
static NEXT: AtomicUsize = AtomicUsize::new(0);

impl TempDir {
    pub fn new(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!(
            "ricochet-{}-{}-{}-{test}",
            env!("CARGO_CRATE_NAME"),
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    pub fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `ricochet <args>` in `dir`, stdin closed, stdout and stderr captured.
pub fn ricochet(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}
