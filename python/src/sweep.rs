//! `ricochet.sweep(scene, params, threads=None)`: the library's `Sweep` over the grid of
//! `params` on every core, as `ricochet sweep` runs it, its rows as a dict of arrays (the
//! columns of the CSV file, in its order).

use std::num::NonZeroUsize;

use numpy::PyArray1;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use ricochet::sweep::{
    Grid, ParamSpec, RESULT_COLUMNS, Row, Shard, Sweep, Value, format_real, thread_pool,
};

use crate::errors;
use crate::run::strings;
use crate::scene::PyScene;

/// The spec `name=v1,v2,…` of one parameter (or `name=start:stop:step` when the value is
/// such a string), as the command line's `--param` takes it: numbers in the shortest
/// decimal that reads back to the same double, so the values are the caller's, bit for bit.
fn spec(name: &str, values: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(text) = values.cast::<PyString>() {
        return Ok(format!("{name}={}", text.to_str()?));
    }
    let items = values
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("the values of `{name}` are not iterable")))?;
    let mut texts = Vec::new();
    for item in items {
        let item = item?;
        texts.push(match item.cast::<PyString>() {
            Ok(s) => s.to_str()?.to_owned(),
            Err(_) => format_real(item.extract::<f64>().map_err(|_| {
                PyTypeError::new_err(format!(
                    "a value of `{name}` is neither a number nor a name: {item}"
                ))
            })?),
        });
    }
    if texts.is_empty() {
        return Err(PyValueError::new_err(format!("`{name}` has no values")));
    }
    Ok(format!("{name}={}", texts.join(",")))
}

/// `sweep(scene, params, *, threads=None)`: see `ricochet/_ricochet.pyi`.
#[pyfunction]
#[pyo3(signature = (scene, params, *, threads = None))]
pub(crate) fn sweep<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    params: &Bound<'py, PyDict>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let loaded;
    let scene = match scene.cast::<PyScene>() {
        Ok(s) => &s.get().scene,
        Err(_) => {
            let path: std::path::PathBuf = scene.extract().map_err(|_| {
                PyTypeError::new_err("scene must be a ricochet.Scene or a scene file's path")
            })?;
            loaded = ricochet::scene::load(&path).map_err(|e| errors::scene_error(py, e))?;
            &loaded
        }
    };
    let specs = (params.iter())
        .map(|(name, values)| {
            let name: String = name
                .extract()
                .map_err(|_| PyTypeError::new_err("parameter names are strings"))?;
            let spec = spec(&name, &values)?;
            ParamSpec::parse(&spec).map_err(|e| PyValueError::new_err(e.to_string()))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let value_error = |e: &dyn std::error::Error| PyValueError::new_err(e.to_string());
    let grid = Grid::new(specs).map_err(|e| value_error(&e))?;
    let sweep = Sweep::new(scene, grid).map_err(|e| value_error(&e))?;
    let threads = match threads {
        None => None,
        Some(n) => {
            Some(NonZeroUsize::new(n).ok_or_else(|| PyValueError::new_err("threads must be ≥ 1"))?)
        }
    };
    let pool = thread_pool(threads).map_err(|e| value_error(&e))?;
    let rows = crate::interruptible(py, |flag| {
        sweep.run_until(&pool, Shard::ALL, &|_| {}, Some(flag))
    })?;
    table(py, &sweep, &rows)
}

/// The columns of the table (those of [`Sweep::columns`]) as arrays: integers for `run`,
/// `impacts` and the counters, numbers for the others, strings for `stop`, `stop_detail`
/// and the named parameters. A run that did not start has NaN numbers and −1 counters.
fn table<'py>(py: Python<'py>, sweep: &Sweep<'_>, rows: &[Row]) -> PyResult<Bound<'py, PyDict>> {
    let columns = sweep.columns();
    let nq = sweep.scene().model.nq();
    let nu = sweep.scene().model.nu();
    let out = PyDict::new(py);
    let integers = |k: usize| -> Vec<i64> {
        (rows.iter())
            .map(|r| match &r.outcome {
                Ok(run) => {
                    let c = &run.counters;
                    let v = match RESULT_COLUMNS[k] {
                        "impacts" => c.impacts,
                        "steps" => c.steps,
                        "rejected" => c.rejected,
                        "rhs_evals" => c.rhs_evals,
                        _ => c.events,
                    };
                    v as i64
                }
                Err(_) => -1,
            })
            .collect()
    };
    let index: Vec<i64> = rows.iter().map(|r| r.index as i64).collect();
    out.set_item(&columns[0], PyArray1::from_vec(py, index))?;
    // The parameters, in the grid's order.
    let nparams = sweep.grid().params().len();
    for j in 0..nparams {
        let name = &columns[1 + j];
        match rows.first().map(|r| r.values[j]) {
            Some(Value::Real(_)) | None => {
                let v: Vec<f64> = (rows.iter())
                    .map(|r| match r.values[j] {
                        Value::Real(x) => x,
                        _ => f64::NAN,
                    })
                    .collect();
                out.set_item(name, PyArray1::from_vec(py, v))?;
            }
            Some(_) => {
                let v = rows.iter().map(|r| r.values[j].to_string()).collect();
                out.set_item(name, strings(py, v)?)?;
            }
        }
    }
    // The results.
    for (k, name) in RESULT_COLUMNS.iter().enumerate() {
        match *name {
            "stop" => out.set_item(
                name,
                strings(py, rows.iter().map(|r| r.stop().to_owned()).collect())?,
            )?,
            "impacts" | "steps" | "rejected" | "rhs_evals" | "events" => {
                out.set_item(name, PyArray1::from_vec(py, integers(k)))?
            }
            _ => {
                let v: Vec<f64> = (rows.iter())
                    .map(|r| match &r.outcome {
                        Ok(run) => {
                            let a = &run.audit;
                            match *name {
                                "delta_e" => a.impact_delta_e,
                                "energy_0" => a.initial.total(),
                                "energy_end" => a.end.total(),
                                "impact_prescribed_work" => a.impact_prescribed_work,
                                "damping_work" => a.damping_work,
                                "applied_work" => a.applied_work,
                                "drive_work" => a.drive_work,
                                "contact_work" => a.contact_work,
                                _ => a.drift(),
                            }
                        }
                        Err(_) => f64::NAN,
                    })
                    .collect();
                out.set_item(name, PyArray1::from_vec(py, v))?
            }
        }
    }
    // The final state: `t`, `q.<coordinate>`…, `u.<speed>`…
    let state = |f: &dyn Fn(&ricochet::state::State) -> f64| -> Vec<f64> {
        (rows.iter())
            .map(|r| r.outcome.as_ref().map_or(f64::NAN, |run| f(&run.state)))
            .collect()
    };
    let first = 1 + nparams + RESULT_COLUMNS.len();
    out.set_item(&columns[first], PyArray1::from_vec(py, state(&|s| s.t)))?;
    for i in 0..nq {
        out.set_item(
            &columns[first + 1 + i],
            PyArray1::from_vec(py, state(&|s| s.q[i])),
        )?;
    }
    for i in 0..nu {
        let name = &columns[first + 1 + nq + i];
        out.set_item(name, PyArray1::from_vec(py, state(&|s| s.u[i])))?;
    }
    let detail = (rows.iter())
        .map(|r| match &r.outcome {
            Ok(run) => run.detail.clone(),
            Err(n) => n.detail.clone(),
        })
        .collect();
    out.set_item(&columns[first + 1 + nq + nu], strings(py, detail)?)?;
    Ok(out)
}
