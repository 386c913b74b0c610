//! The Python exceptions raised by the module: classes of `ricochet/_errors.py`, built
//! here with their attributes (the line and field of a scene error, the row of an impact
//! error, the run of a failed run).

use std::error::Error;

use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ricochet::scene::SceneError;

/// An exception of class `class` (of `ricochet._errors`) with the message `message` and
/// the keyword attributes that `attrs` sets on a dict.
pub(crate) fn raise(
    py: Python<'_>,
    class: &str,
    message: impl Into<String>,
    attrs: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>,
) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let class = py.import("ricochet._errors")?.getattr(class)?;
        let kwargs = PyDict::new(py);
        attrs(&kwargs)?;
        let value = class.call((message.into(),), Some(&kwargs))?;
        Ok(PyErr::from_value(value))
    };
    build().unwrap_or_else(|e| e)
}

/// An exception without attributes.
pub(crate) fn plain(py: Python<'_>, class: &str, message: impl Into<String>) -> PyErr {
    raise(py, class, message, |_| Ok(()))
}

/// `OSError(errno, strerror, filename)`: Python makes it the subclass of the errno
/// (`FileNotFoundError`, `PermissionError`, …).
pub(crate) fn os_error(error: &std::io::Error, path: &std::path::Path) -> PyErr {
    let code = error.raw_os_error();
    let text = error.to_string();
    // Rust's message ends with ` (os error N)`, which Python's `[Errno N]` already says.
    let text = match code {
        Some(n) => {
            (text.strip_suffix(&format!(" (os error {n})"))).map_or(text.clone(), str::to_owned)
        }
        None => text,
    };
    PyOSError::new_err((code.unwrap_or(0), text, path.display().to_string()))
}

/// A scene that does not load: `SceneError` with its `path`, `line`, `column`, `field`
/// and `detail` (what is wrong), or the `OSError` of a file that cannot be read.
pub(crate) fn scene_error(py: Python<'_>, error: SceneError) -> PyErr {
    let message = error.to_string();
    match error {
        SceneError::Io { path, error } => os_error(&error, &path),
        SceneError::At {
            path,
            line,
            column,
            field,
            message: detail,
        } => raise(py, "SceneError", message, |k| {
            k.set_item("path", path.display().to_string())?;
            k.set_item("line", line)?;
            k.set_item("column", column)?;
            k.set_item("field", field)?;
            k.set_item("detail", detail)
        }),
        SceneError::Model { path, error } => raise(py, "SceneError", message, |k| {
            k.set_item("path", path.display().to_string())?;
            k.set_item("detail", error.to_string())
        }),
    }
}

/// The message of `error` and of its causes, each said once (`sim::describe`, the
/// command line's `error:` line).
pub(crate) fn chain(error: &(dyn Error + 'static)) -> String {
    ricochet::sim::describe(error)
}
