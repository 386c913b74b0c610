//! `Scene`: a scene file loaded (`Scene.load`, `Scene.from_toml`) and run
//! (`Scene.run`), as `ricochet run` runs it: the same overrides (`RunOverrides`), the same
//! loops, the same observers (`Collector`, and `RunLogger` when a log is asked for).

use std::io::{Seek, Write};
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::atomic::AtomicBool;

use numpy::PyArray1;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use ricochet::impact::Law;
use ricochet::integrate::Method;
use ricochet::log::{LogError, LogOptions, LogWriter, RunLogger};
use ricochet::math::Real;
use ricochet::model::Model;
use ricochet::regress::{Checkpoints, Collector, RunOverrides, Summary};
use ricochet::scene::Scene;
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, MoreauJean, Observer, ObserverError, RunSummary, Sample,
    SimError, Simulation, StopReason, Transition,
};

use crate::errors;
use crate::run::PyRun;

/// A scene: its model, initial state and run settings (see `ricochet/_ricochet.pyi`).
#[pyclass(frozen, name = "Scene", module = "ricochet")]
pub struct PyScene {
    pub(crate) scene: Scene,
}

/// The observer of a run: the collector of the summary (every sample), and the log.
struct Recorder<W: Write + Seek + Send + 'static> {
    collector: Collector,
    log: Option<RunLogger<W>>,
}

impl<W: Write + Seek + Send + 'static> Observer for Recorder<W> {
    fn sample(&mut self, model: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        self.collector.sample(model, s)?;
        self.log.as_mut().map_or(Ok(()), |log| log.sample(model, s))
    }

    fn impact(&mut self, model: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        self.collector.impact(model, ev)?;
        self.log
            .as_mut()
            .map_or(Ok(()), |log| log.impact(model, ev))
    }

    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        self.log
            .as_mut()
            .map_or(Ok(()), |log| log.message(t, level, text))
    }

    fn transition(&mut self, model: &Model, tr: &Transition) -> Result<(), ObserverError> {
        self.log
            .as_mut()
            .map_or(Ok(()), |log| log.transition(model, tr))
    }
}

/// Why a run gave no summary.
enum RunError {
    /// The settings are refused (`Simulation::new`).
    Start(SimError),
    /// The log cannot be created or written.
    Log(LogError),
}

/// What a run gave: how it ended, its summary (every sample as a checkpoint), and the
/// error that kept its log from being finished.
struct Ran {
    run: RunSummary,
    summary: Summary,
    log_error: Option<LogError>,
}

/// Runs `scene` with `settings` (the overrides applied) and `material`, writing the log
/// `log` if given, stopping when `interrupt` is set: `ricochet run` (src/bin/ricochet/run.rs)
/// without its terminal.
fn simulate(
    scene: &Scene,
    (settings, material): (&ricochet::settings::Settings, MaterialOverride),
    log: Option<&PathBuf>,
    interrupt: &AtomicBool,
) -> Result<Ran, RunError> {
    enum Runner<'m> {
        EventDriven(Box<Simulation<'m>>),
        MoreauJean(Box<MoreauJean<'m>>),
    }
    let model = &scene.model;
    let mut runner = match settings.integrator.method {
        Method::MoreauJean => {
            MoreauJean::new(model, settings, material).map(|m| Runner::MoreauJean(Box::new(m)))
        }
        Method::Dopri5 | Method::Dop853 | Method::Rk4 => {
            Simulation::new(model, settings, material).map(|s| Runner::EventDriven(Box::new(s)))
        }
    }
    .map_err(RunError::Start)?;
    let gap_tol = match &runner {
        Runner::EventDriven(sim) => sim.scales().gap_tol,
        Runner::MoreauJean(mj) => mj.scales().gap_tol,
    };
    let logger = log
        .map(|path| {
            let writer = LogWriter::create(path, LogOptions::default())?;
            RunLogger::new(
                writer,
                model,
                (&scene.name, &scene.text),
                (settings, &material),
                &scene.initial,
                gap_tol,
            )
        })
        .transpose()
        .map_err(RunError::Log)?;
    let mut recorder = Recorder {
        collector: Collector::with_rule(model, Checkpoints::Every),
        log: logger,
    };
    let run = match &mut runner {
        Runner::EventDriven(sim) => sim.run(&scene.initial, &mut recorder, Some(interrupt)),
        Runner::MoreauJean(mj) => mj.run(&scene.initial, &mut recorder, Some(interrupt)),
    };
    let log_error = recorder
        .log
        .map(|log| log.finish(&run))
        .and_then(Result::err);
    let summary = recorder
        .collector
        .finish(scene, (settings, &material), &run);
    Ok(Ran {
        run,
        summary,
        log_error,
    })
}

/// A name of `T` (`law`, `method`), as a `ValueError` naming the keyword.
fn parse<T: FromStr>(keyword: &str, name: Option<&str>) -> PyResult<Option<T>>
where
    T::Err: std::fmt::Display,
{
    name.map(|n| T::from_str(n).map_err(|e| PyValueError::new_err(format!("{keyword}: {e}"))))
        .transpose()
}

#[pymethods]
impl PyScene {
    /// `Scene.load(path)`: reads and checks a scene file.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        let scene = ricochet::scene::load(&path).map_err(|e| errors::scene_error(py, e))?;
        Ok(PyScene { scene })
    }

    /// `Scene.from_toml(text, path="<string>")`: checks a scene given as text; `path` is
    /// the name its errors give.
    #[staticmethod]
    #[pyo3(signature = (text, path = "<string>"))]
    fn from_toml(py: Python<'_>, text: &str, path: &str) -> PyResult<PyScene> {
        let scene =
            ricochet::scene::load_str(text, path).map_err(|e| errors::scene_error(py, e))?;
        Ok(PyScene { scene })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> &str {
        &self.scene.name
    }

    /// Its description.
    #[getter]
    fn description(&self) -> &str {
        &self.scene.description
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> String {
        self.scene.path.display().to_string()
    }

    /// The scene file's text.
    #[getter]
    fn text(&self) -> &str {
        &self.scene.text
    }

    /// The names of the generalized coordinates `q`.
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        crate::coordinate_names(&self.scene.model)
    }

    /// The names of the generalized speeds `u`.
    #[getter]
    fn speeds(&self) -> Vec<String> {
        crate::speed_names(&self.scene.model)
    }

    /// The initial coordinates.
    #[getter]
    fn q0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.scene.initial.q.as_slice())
    }

    /// The initial speeds.
    #[getter]
    fn u0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.scene.initial.u.as_slice())
    }

    /// The run's end time in the scene (s).
    #[getter]
    fn t_end(&self) -> f64 {
        self.scene.settings.t_end
    }

    /// The output rate of the samples in the scene (Hz).
    #[getter]
    fn output_rate(&self) -> f64 {
        self.scene.settings.output_rate
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name={:?}, path={:?}, coordinates={:?})",
            self.scene.name,
            self.scene.path.display().to_string(),
            crate::coordinate_names(&self.scene.model)
        )
    }

    /// `scene.run(*, t_end=None, law=None, e=None, mu=None, method=None, rtol=None,
    /// atol=None, dt=None, max_drift=None, log=None)`: see `ricochet/_ricochet.pyi`.
    #[pyo3(signature = (*, t_end=None, law=None, e=None, mu=None, method=None, rtol=None,
                        atol=None, dt=None, max_drift=None, log=None))]
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        py: Python<'_>,
        t_end: Option<f64>,
        law: Option<&str>,
        e: Option<f64>,
        mu: Option<f64>,
        method: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        dt: Option<f64>,
        max_drift: Option<f64>,
        log: Option<PathBuf>,
    ) -> PyResult<PyRun> {
        let overrides = RunOverrides {
            t_end,
            law: parse::<Law>("law", law)?,
            e,
            mu,
            method: parse::<Method>("method", method)?,
            rtol,
            atol,
            dt,
            max_drift,
            // The scene's rule for simultaneous impacts (not a keyword yet).
            simultaneous: None,
        };
        let scene = &self.scene;
        let mut settings = scene.settings.clone();
        let material = overrides
            .apply(&mut settings)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let ran = crate::interruptible(py, |flag| {
            simulate(scene, (&settings, material), log.as_ref(), flag)
        });
        let ran = match ran {
            Ok(Ok(ran)) => ran,
            // Ctrl-C before the run gave anything (it always gives a summary once started).
            Err(interrupt) => return Err(interrupt),
            Ok(Err(RunError::Start(e))) => {
                let message = format!(
                    "{}: cannot simulate: {}",
                    scene.path.display(),
                    errors::chain(&e)
                );
                return Err(errors::plain(py, "SimulationError", message));
            }
            // The log's file cannot be created: the OSError of its path.
            Ok(Err(RunError::Log(LogError::Create { path, source }))) => {
                return Err(errors::os_error(&source, &path));
            }
            Ok(Err(RunError::Log(e))) => {
                let path = log
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default();
                let message = format!("cannot write the log {path}: {}", errors::chain(&e));
                return Err(errors::plain(py, "SimulationError", message));
            }
        };
        let shown = log.as_ref().map(|p| p.display().to_string());
        if let Some(e) = ran.log_error {
            let message = format!(
                "cannot finish the log {}: {}",
                shown.unwrap_or_default(),
                errors::chain(&e)
            );
            return Err(errors::plain(py, "SimulationError", message));
        }
        let drift = ran.summary.drift;
        let speeds = crate::speed_names(&scene.model);
        let run = PyRun::from_summary(py, ran.summary, speeds, shown, "complete".to_owned())?;
        let t = ran.run.state.t;
        match ran.run.stop {
            StopReason::EndTime => match drift.filter(|d| d.broken()) {
                None => Ok(run),
                Some(d) => {
                    let message = format!(
                        "{}: the energy-drift budget is broken: {}",
                        scene.name,
                        d.describe()
                    );
                    let run = Py::new(py, run)?;
                    Err(errors::raise(py, "DriftBudgetError", message, |k| {
                        k.set_item("run", run)?;
                        k.set_item("t", t)
                    }))
                }
            },
            StopReason::Interrupted { .. } => Err(PyKeyboardInterrupt::new_err(format!(
                "{}: interrupted at t = {t} s (its log, if any, is finished)",
                scene.name
            ))),
            StopReason::Failed(e) => {
                let message = format!("{}: stopped at t = {t} s, failed: {}", scene.name, e.what());
                let run = Py::new(py, run)?;
                Err(errors::raise(py, "SimulationError", message, |k| {
                    k.set_item("run", run)?;
                    k.set_item("t", t)
                }))
            }
        }
    }
}
