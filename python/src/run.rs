//! `Run`: a run's samples as arrays, its ledger as a dict of arrays, its audit, counters
//! and stop reason; built from the library's run summary ([`Summary`]), which a run
//! (through `Collector`) and its log (through `Summary::from_log`) give alike. And
//! `read_log`.

use std::ffi::CString;
use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyRuntimeWarning;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use ricochet::log::{Ending, ImpactRecord};
use ricochet::regress::{Snapshot, Summary};

use crate::errors;

/// The samples, ledger, audit and stop reason of one run (see `ricochet/_ricochet.pyi`).
#[pyclass(frozen, name = "Run", module = "ricochet")]
pub struct PyRun {
    /// The scene's name (`None` for a log without its scene record).
    #[pyo3(get)]
    scene_name: Option<String>,
    /// Sample times (s), shape (n,).
    #[pyo3(get)]
    t: Py<PyAny>,
    /// Generalized coordinates, shape (n, nq).
    #[pyo3(get)]
    q: Py<PyAny>,
    /// Generalized speeds, shape (n, nu).
    #[pyo3(get)]
    u: Py<PyAny>,
    /// Kinetic energy (J), shape (n,).
    #[pyo3(get)]
    kinetic: Py<PyAny>,
    /// Potential energy (J), shape (n,).
    #[pyo3(get)]
    potential: Py<PyAny>,
    /// Total mechanical energy (J), shape (n,).
    #[pyo3(get)]
    total: Py<PyAny>,
    /// The names of the columns of `q`.
    #[pyo3(get)]
    coordinates: Vec<String>,
    /// The names of the columns of `u`.
    #[pyo3(get)]
    speeds: Vec<String>,
    /// The ledger: one array per field of the `/impacts` record.
    #[pyo3(get)]
    impacts: Py<PyDict>,
    /// The energy audit (J) and `t_stop` (s); `None` for a log of a run that did not
    /// finish.
    #[pyo3(get)]
    audit: Option<Py<PyDict>>,
    /// The work counters.
    #[pyo3(get)]
    counters: Option<Py<PyDict>>,
    /// `t_end`, `interrupted`, `error`, or `unfinished` (a log without its audit).
    #[pyo3(get)]
    stop: String,
    /// The stop reason in words, as the log's audit says it.
    #[pyo3(get)]
    stop_reason: String,
    /// The drift check: `integration_drift`, `energy_scale`, `relative`, `max_drift`,
    /// `broken`.
    #[pyo3(get)]
    drift: Option<Py<PyDict>>,
    /// The run settings, as the log's `settings` record holds them.
    #[pyo3(get)]
    settings: Option<Py<PyAny>>,
    /// The log file, if the run wrote one or was read from one.
    #[pyo3(get)]
    log: Option<String>,
    /// `complete`, or how the log read ends (`truncated at byte …: …`).
    #[pyo3(get)]
    ending: String,
}

#[pymethods]
impl PyRun {
    fn __repr__(&self, py: Python<'_>) -> String {
        let samples = self.t.bind(py).len().unwrap_or(0);
        let impacts = self.impacts.bind(py).get_item("t").ok().flatten();
        let impacts = impacts.and_then(|a| a.len().ok()).unwrap_or(0);
        format!(
            "Run(scene={:?}, samples={samples}, impacts={impacts}, stop={:?})",
            self.scene_name.as_deref().unwrap_or(""),
            self.stop
        )
    }
}

/// A float64 array of shape `(rows, width)` from row-major values.
fn matrix<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    rows: usize,
    width: usize,
) -> PyResult<Py<PyAny>> {
    Ok(PyArray1::from_vec(py, values)
        .reshape([rows, width])?
        .into_any()
        .unbind())
}

fn vector(py: Python<'_>, values: Vec<f64>) -> Py<PyAny> {
    PyArray1::from_vec(py, values).into_any().unbind()
}

/// A numpy array of strings (`<U` dtype).
pub(crate) fn strings<'py>(py: Python<'py>, values: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", py.import("builtins")?.getattr("str")?)?;
    numpy.call_method("array", (PyList::new(py, values)?,), Some(&kwargs))
}

/// A JSON value as Python objects (through `json.loads`: serde_json writes the shortest
/// decimal that reads back, and Python reads it back exactly).
fn json_to_py(py: Python<'_>, value: &serde_json::Value) -> PyResult<Py<PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    Ok(py.import("json")?.call_method1("loads", (text,))?.unbind())
}

/// The ledger as a dict of arrays, one per field of the `/impacts` record (nested fields
/// dotted: `v_s.n`, `w.mnn`, `support.i_n`; `delta_u.<speed>`); absent values (α without
/// approach speed, the support of all but a rocking end) are NaN.
fn impact_columns<'py>(
    py: Python<'py>,
    impacts: &[ImpactRecord],
    speeds: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let real = |f: &dyn Fn(&ImpactRecord) -> f64| -> Py<PyAny> {
        vector(py, impacts.iter().map(f).collect())
    };
    let text = |f: &dyn Fn(&ImpactRecord) -> String| strings(py, impacts.iter().map(f).collect());
    out.set_item("t", real(&|i| i.t))?;
    let index: Vec<i64> = impacts.iter().map(|i| i.index as i64).collect();
    out.set_item("index", PyArray1::from_vec(py, index))?;
    out.set_item("pair", text(&|i| i.pair.clone())?)?;
    out.set_item("body_a", text(&|i| i.body_a.clone())?)?;
    out.set_item("body_b", text(&|i| i.body_b.clone())?)?;
    out.set_item("law", text(&|i| i.law.name().to_owned())?)?;
    out.set_item("type", text(&|i| i.impact_type.name().to_owned())?)?;
    let case: Vec<i64> = impacts.iter().map(|i| i64::from(i.case)).collect();
    out.set_item("case", PyArray1::from_vec(py, case))?;
    out.set_item("cause", text(&|i| i.cause.name().to_owned())?)?;
    out.set_item("alpha", real(&|i| i.alpha.unwrap_or(f64::NAN)))?;
    out.set_item("w.mnn", real(&|i| i.w.nn))?;
    out.set_item("w.mnt", real(&|i| i.w.nt))?;
    out.set_item("w.mtt", real(&|i| i.w.tt))?;
    out.set_item("g", real(&|i| i.g))?;
    out.set_item("h", real(&|i| i.h))?;
    out.set_item("p", real(&|i| i.p))?;
    out.set_item("q", real(&|i| i.q))?;
    out.set_item("v_a.n", real(&|i| i.v_a.n))?;
    out.set_item("v_a.t", real(&|i| i.v_a.t))?;
    out.set_item("v_s.n", real(&|i| i.v_s.n))?;
    out.set_item("v_s.t", real(&|i| i.v_s.t))?;
    out.set_item("i_n", real(&|i| i.i_n))?;
    out.set_item("i_t", real(&|i| i.i_t))?;
    let support = |f: fn(&ricochet::log::SupportRecord) -> f64| {
        move |i: &ImpactRecord| i.support.as_ref().map_or(f64::NAN, f)
    };
    out.set_item("support.i_n", real(&support(|s| s.i_n)))?;
    out.set_item("support.i_t", real(&support(|s| s.i_t)))?;
    out.set_item("support.duration", real(&support(|s| s.duration)))?;
    for (k, name) in speeds.iter().enumerate() {
        let du = real(&|i| i.delta_u.get(k).copied().unwrap_or(f64::NAN));
        out.set_item(format!("delta_u.{name}"), du)?;
    }
    out.set_item("energy_before", real(&|i| i.energy_before))?;
    out.set_item("energy_after", real(&|i| i.energy_after))?;
    out.set_item("delta_e", real(&|i| i.delta_e))?;
    out.set_item("work_n", real(&|i| i.work_n))?;
    out.set_item("work_t", real(&|i| i.work_t))?;
    out.set_item("e", real(&|i| i.e))?;
    out.set_item("mu", real(&|i| i.mu))?;
    out.set_item("prescribed_work", real(&|i| i.prescribed_work))?;
    out.set_item("point.x", real(&|i| i.point.x))?;
    out.set_item("point.y", real(&|i| i.point.y))?;
    out.set_item("normal.x", real(&|i| i.normal.x))?;
    out.set_item("normal.y", real(&|i| i.normal.y))?;
    out.set_item("tangent.x", real(&|i| i.tangent.x))?;
    out.set_item("tangent.y", real(&|i| i.tangent.y))?;
    Ok(out)
}

impl PyRun {
    /// The run of `summary`, whose checkpoints are every sample of the run
    /// (`Checkpoints::Every`); `speeds` names the columns of `u`.
    pub(crate) fn from_summary(
        py: Python<'_>,
        summary: Summary,
        speeds: Vec<String>,
        log: Option<String>,
        ending: String,
    ) -> PyResult<PyRun> {
        let samples: &[Snapshot] = &summary.checkpoints;
        let n = samples.len();
        let nq = samples
            .first()
            .map_or(summary.coordinates.len(), |s| s.q.len());
        let nu = samples.first().map_or(speeds.len(), |s| s.u.len());
        let flat = |f: fn(&Snapshot) -> &[f64]| -> Vec<f64> {
            samples.iter().flat_map(|s| f(s).iter().copied()).collect()
        };
        let each = |f: fn(&Snapshot) -> f64| -> Vec<f64> { samples.iter().map(f).collect() };
        let (stop, stop_reason) = match &summary.audit {
            Some(a) => {
                let name = a.stop_reason.split(':').next().unwrap_or_default();
                (name.to_owned(), a.stop_reason.clone())
            }
            None => (
                "unfinished".to_owned(),
                "the log has no audit: the run did not finish".to_owned(),
            ),
        };
        let audit = (summary.audit.as_ref())
            .map(|a| -> PyResult<_> {
                let d = PyDict::new(py);
                d.set_item("t_stop", a.t_stop)?;
                d.set_item("energy_initial", a.energy_initial)?;
                d.set_item("energy_final", a.energy_final)?;
                d.set_item("impact_delta_e", a.impact_delta_e)?;
                d.set_item("applied_work", a.applied_work)?;
                d.set_item("contact_work", a.contact_work)?;
                d.set_item("prescribed_work", a.prescribed_work)?;
                d.set_item("integration_drift", a.integration_drift)?;
                let c = &a.counters;
                let counters = PyDict::new(py);
                counters.set_item("impacts", c.impacts)?;
                counters.set_item("steps", c.steps)?;
                counters.set_item("rejected_steps", c.rejected_steps)?;
                counters.set_item("rhs_evaluations", c.rhs_evaluations)?;
                counters.set_item("events", c.events)?;
                counters.set_item("state_samples", c.state_samples)?;
                Ok((d.unbind(), counters.unbind()))
            })
            .transpose()?;
        let (audit, counters) = audit.unzip();
        let drift = (summary.drift.as_ref())
            .map(|d| -> PyResult<_> {
                let out = PyDict::new(py);
                out.set_item("integration_drift", d.integration_drift)?;
                out.set_item("energy_scale", d.energy_scale)?;
                out.set_item("relative", d.relative)?;
                out.set_item("max_drift", d.max_drift)?;
                out.set_item("broken", d.broken())?;
                Ok(out.unbind())
            })
            .transpose()?;
        let settings = (summary.settings.as_ref())
            .map(|m| json_to_py(py, &serde_json::Value::Object(m.clone())))
            .transpose()?;
        Ok(PyRun {
            scene_name: summary.scene.as_ref().map(|s| s.name.clone()),
            t: vector(py, each(|s| s.t)),
            q: matrix(py, flat(|s| &s.q), n, nq)?,
            u: matrix(py, flat(|s| &s.u), n, nu)?,
            kinetic: vector(py, each(|s| s.energy.kinetic)),
            potential: vector(py, each(|s| s.energy.potential)),
            total: vector(py, each(|s| s.energy.total)),
            impacts: impact_columns(py, &summary.impacts, &speeds)?.unbind(),
            coordinates: summary.coordinates.clone(),
            speeds,
            audit,
            counters,
            stop,
            stop_reason,
            drift,
            settings,
            log,
            ending,
        })
    }
}

/// `read_log(path)`: the run in a log, as `Scene.run` returns it (every `/state` sample,
/// every `/impacts` record, the audit). A log cut short gives what it holds, with a
/// `RuntimeWarning`; a damaged one raises `LogError` with what was read before.
#[pyfunction]
pub(crate) fn read_log(py: Python<'_>, path: PathBuf) -> PyResult<PyRun> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(&path).map_err(|e| errors::os_error(&e, &path))?;
    let (summary, log) = py
        .detach(|| Summary::from_log_read(&bytes, None))
        .map_err(|e| errors::plain(py, "LogError", format!("{shown}: {}", errors::chain(&e))))?;
    // The speeds' names from the scene the log holds, when it still loads.
    let speeds = (log.scene.as_ref())
        .and_then(|s| ricochet::scene::load_str(&s.text, format!("{}.toml", s.name)).ok())
        .map_or_else(
            || summary.coordinates.clone(),
            |s| crate::speed_names(&s.model),
        );
    let ending = log.ending;
    let ending_text = match &ending {
        Ending::Complete => "complete".to_owned(),
        Ending::Truncated { offset, error } => format!("truncated at byte {offset}: {error}"),
        Ending::Damaged { offset, error } => format!("damaged at byte {offset}: {error}"),
    };
    let run = PyRun::from_summary(
        py,
        summary,
        speeds,
        Some(shown.clone()),
        ending_text.clone(),
    )?;
    match ending {
        Ending::Complete => Ok(run),
        Ending::Truncated { .. } => {
            let message = CString::new(format!(
                "{shown}: the log is {ending_text}; the run holds what was read (`ricochet \
                 repair` makes the file whole)"
            ))
            .unwrap_or_default();
            PyErr::warn(py, &py.get_type::<PyRuntimeWarning>(), &message, 1)?;
            Ok(run)
        }
        Ending::Damaged { offset, .. } => {
            let run = Py::new(py, run)?;
            Err(errors::raise(
                py,
                "LogError",
                format!("{shown}: {ending_text}"),
                |k| {
                    k.set_item("run", run)?;
                    k.set_item("offset", offset)
                },
            ))
        }
    }
}
