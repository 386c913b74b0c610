//! `ricochet._ricochet`: the Python extension module of ricochet (pyo3), re-exported by the
//! package `ricochet` (`ricochet/__init__.py`).
//!
//! Everything here is glue: the numbers come from the library's own functions, the ones
//! the command line uses — `impact::solve` (`ricochet impact`), the scene loader, the
//! `Simulation`/`MoreauJean` loops with the `Collector` and `RunLogger` observers
//! (`ricochet run`), the log reader and `Summary::from_log` (`ricochet inspect`), and
//! `Sweep` (`ricochet sweep`). Long work runs with the GIL released; runs and sweeps run on
//! a worker thread while the calling thread watches for Ctrl-C (see [`interruptible`]).
//!
//! - `impact.rs`: the impact laws over arrays of problems;
//! - `scene.rs`: `Scene` (load, from_toml, run);
//! - `run.rs`: `Run`, the arrays of a run or of a log, and `read_log`;
//! - `sweep.rs`: `sweep`, a grid of runs as a table of arrays;
//! - `errors.rs`: the Python exceptions (defined in `ricochet/_errors.py`).

mod errors;
mod impact;
mod run;
mod scene;
mod sweep;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;
use ricochet::model::Model;

/// The names of the generalized speeds `u`, in order: the coordinates' names for a
/// holonomic model (`u = q̇`), their own for a nonholonomic one (`Model::speeds`, e.g.
/// `sleigh.vx_body`, `sleigh.omega`).
pub(crate) fn speed_names(model: &Model) -> Vec<String> {
    (model.speeds().iter()).map(|s| s.name.clone()).collect()
}

/// The names of the generalized coordinates `q`, in order.
pub(crate) fn coordinate_names(model: &Model) -> Vec<String> {
    (model.coordinates().iter())
        .map(|c| c.name.clone())
        .collect()
}

/// How often the calling thread looks for a signal (Ctrl-C) while the work runs.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` with the GIL released, on a worker thread, while this thread checks
/// Python's signal handlers every [`SIGNAL_POLL`]: on Ctrl-C (a `KeyboardInterrupt`, or
/// whatever a handler raises) the flag given to `work` is set, `work` is waited for (a run
/// stops at its next step and finishes its log) and the handler's exception is returned.
/// Python runs signal handlers on the main thread only, and only with the GIL: a run
/// holding the calling thread could not be interrupted.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let flag = AtomicBool::new(false);
    let mut raised: Option<PyErr> = None;
    let out = py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = mpsc::channel::<()>();
            let flag = &flag;
            let worker = s.spawn(move || {
                let out = work(flag);
                let _ = done.send(());
                out
            });
            loop {
                match finished.recv_timeout(SIGNAL_POLL) {
                    Err(mpsc::RecvTimeoutError::Timeout) if raised.is_none() => {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            raised = Some(e);
                            flag.store(true, Ordering::SeqCst);
                        }
                    }
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                    // Finished (or its sender dropped by a panic).
                    _ => break,
                }
            }
            worker.join()
        })
    });
    let out = out.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    match raised {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// The module `ricochet._ricochet`.
#[pymodule]
fn _ricochet(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "LAWS",
        (ricochet::impact::Law::ALL.iter())
            .map(|l| l.name())
            .collect::<Vec<_>>(),
    )?;
    m.add(
        "METHODS",
        (ricochet::integrate::Method::ALL.iter())
            .map(|l| l.name())
            .collect::<Vec<_>>(),
    )?;
    m.add_function(wrap_pyfunction!(impact::solve_rows, m)?)?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<run::PyRun>()?;
    m.add_function(wrap_pyfunction!(run::read_log, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    Ok(())
}
