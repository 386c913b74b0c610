//! The impact laws over arrays: `ricochet.impact` (the Python wrapper in
//! `ricochet/__init__.py` shapes the arrays; [`solve_rows`] solves them).
//!
//! Each row is what one line of `ricochet impact` is: `impact::solve` on
//! `(W, v^A, e, μ)` under its law, and an error for a problem that has no answer or whose
//! answer has a number that is not finite (the command line's JSON cannot carry it; an
//! array could, but a row is an answer here exactly when it is one there).

use std::str::FromStr;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law, Outcome};

use crate::errors;

/// The answers of `n` rows, column by column; a failed row holds NaN and type and case 0.
struct Columns {
    i_n: Vec<f64>,
    i_t: Vec<f64>,
    /// `[v_n^S, v_t^S]` of each row, row-major (n × 2).
    v_s: Vec<f64>,
    delta_e: Vec<f64>,
    work_n: Vec<f64>,
    work_t: Vec<f64>,
    alpha: Vec<f64>,
    g: Vec<f64>,
    h: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    /// The type number of [P, Table 2] (1 sticking, 2 reverse, 3 forward sliding), 0 for
    /// a failed row.
    kind: Vec<u8>,
    /// The sign case 1–5 of Table 1, 0 for a failed row.
    case: Vec<u8>,
    /// The failed rows and why, in row order.
    errors: Vec<(usize, String)>,
}

impl Columns {
    fn with_capacity(n: usize) -> Columns {
        let v = || Vec::with_capacity(n);
        Columns {
            i_n: v(),
            i_t: v(),
            v_s: Vec::with_capacity(2 * n),
            delta_e: v(),
            work_n: v(),
            work_t: v(),
            alpha: v(),
            g: v(),
            h: v(),
            p: v(),
            q: v(),
            kind: Vec::with_capacity(n),
            case: Vec::with_capacity(n),
            errors: Vec::new(),
        }
    }

    fn push(&mut self, row: usize, answer: Result<Outcome, String>) {
        let nan = f64::NAN;
        let (numbers, kind, case) = match &answer {
            Ok(out) => {
                let c = &out.coefficients;
                (
                    [
                        out.impulse.n,
                        out.impulse.t,
                        out.v_s.n,
                        out.v_s.t,
                        out.delta_e,
                        out.work_n,
                        out.work_t,
                        c.alpha(),
                        c.g,
                        c.h,
                        c.p,
                        c.q,
                    ],
                    out.kind.number(),
                    out.case.number(),
                )
            }
            Err(_) => ([nan; 12], 0, 0),
        };
        let [i_n, i_t, vs_n, vs_t, de, wn, wt, alpha, g, h, p, q] = numbers;
        self.i_n.push(i_n);
        self.i_t.push(i_t);
        self.v_s.extend([vs_n, vs_t]);
        self.delta_e.push(de);
        self.work_n.push(wn);
        self.work_t.push(wt);
        self.alpha.push(alpha);
        self.g.push(g);
        self.h.push(h);
        self.p.push(p);
        self.q.push(q);
        self.kind.push(kind);
        self.case.push(case);
        if let Err(why) = answer {
            self.errors.push((row, why));
        }
    }
}

/// Solves one problem as `ricochet impact` solves one line (`src/bin/ricochet/impact.rs`,
/// `answer`): `impact::solve`, then the answer refused when one of its numbers is not
/// finite, with the same messages.
fn solve_one(law: Law, w: [f64; 3], v_a: [f64; 2], e: f64, mu: f64) -> Result<Outcome, String> {
    let problem = ImpactProblem::new(
        ImpactMatrix::new(w[0], w[1], w[2]),
        ContactVelocity::new(v_a[0], v_a[1]),
        e,
        mu,
    );
    let out = impact::solve(law, &problem).map_err(|e| e.to_string())?;
    let c = &out.coefficients;
    let alpha = c.alpha();
    if !alpha.is_finite() {
        return Err(format!(
            "α = v_t^A/|v_n^A| = {alpha} is beyond the range of doubles (|v_n^A| is too small \
             against v_t^A)"
        ));
    }
    let numbers = [
        ("i_n", out.impulse.n),
        ("i_t", out.impulse.t),
        ("v_s[0]", out.v_s.n),
        ("v_s[1]", out.v_s.t),
        ("delta_e", out.delta_e),
        ("work_n", out.work_n),
        ("work_t", out.work_t),
        ("g", c.g),
        ("h", c.h),
        ("p", c.p),
        ("q", c.q),
    ];
    let phases = (out.phases.iter())
        .flat_map(|ph| [("phases[].i_n", ph.end.i.n), ("phases[].i_t", ph.end.i.t)]);
    match numbers
        .into_iter()
        .chain(phases)
        .find(|(_, x)| !x.is_finite())
    {
        None => Ok(out),
        Some((what, value)) => Err(format!("the answer's {what} is not finite ({value})")),
    }
}

/// The laws of the rows: one name for all, or one per row.
enum Laws {
    One(Law),
    Each(Vec<Law>),
}

impl Laws {
    fn of(law: &Bound<'_, PyAny>, n: usize) -> PyResult<Laws> {
        let parse = |name: &str, row: Option<usize>| {
            Law::from_str(name).map_err(|e| match row {
                Some(k) => PyValueError::new_err(format!("law of row {k}: {e}")),
                None => PyValueError::new_err(e.to_string()),
            })
        };
        if let Ok(name) = law.cast::<PyString>() {
            return Ok(Laws::One(parse(name.to_str()?, None)?));
        }
        let names = law.cast::<PyList>().map_err(|_| {
            PyValueError::new_err("law must be a law's name or a list of names, one per row")
        })?;
        if names.len() != n {
            return Err(PyValueError::new_err(format!(
                "law has {} names for {n} rows",
                names.len()
            )));
        }
        let laws = (names.iter().enumerate())
            .map(|(k, name)| parse(name.cast::<PyString>()?.to_str()?, Some(k)))
            .collect::<PyResult<Vec<Law>>>()?;
        Ok(Laws::Each(laws))
    }

    fn get(&self, row: usize) -> Law {
        match self {
            Laws::One(law) => *law,
            Laws::Each(laws) => laws[row],
        }
    }
}

/// `_solve_rows(w, v_a, e, mu, law, raise_errors)`: `w` (n, 3) and `v_a` (n, 2) C-ordered
/// float64, `e` and `mu` (n,) float64, `law` a name or a list of n names. Returns a dict
/// of arrays (`i_n`, `i_t`, `v_s` (n, 2), `delta_e`, `work_n`, `work_t`, `alpha`, `g`,
/// `h`, `p`, `q`, `type_number`, `case`) and `errors`, a list of `(row, message)`; with
/// `raise_errors`, raises `ImpactError` at the first failed row instead. The rows are
/// solved with the GIL released.
#[pyfunction]
#[pyo3(name = "_solve_rows")]
pub(crate) fn solve_rows<'py>(
    py: Python<'py>,
    w: PyReadonlyArray2<'py, f64>,
    v_a: PyReadonlyArray2<'py, f64>,
    e: PyReadonlyArray1<'py, f64>,
    mu: PyReadonlyArray1<'py, f64>,
    law: &Bound<'py, PyAny>,
    raise_errors: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let n = w.shape()[0];
    if w.shape() != [n, 3] || v_a.shape() != [n, 2] || e.len() != n || mu.len() != n {
        return Err(PyValueError::new_err(format!(
            "shapes: w {:?}, v_a {:?}, e {:?}, mu {:?}; expected (n, 3), (n, 2), (n,), (n,)",
            w.shape(),
            v_a.shape(),
            e.shape(),
            mu.shape()
        )));
    }
    let laws = Laws::of(law, n)?;
    let (w, v_a, e, mu) = (
        w.as_slice()?,
        v_a.as_slice()?,
        e.as_slice()?,
        mu.as_slice()?,
    );
    let cols = py.detach(|| {
        let mut cols = Columns::with_capacity(n);
        for k in 0..n {
            let row = [w[3 * k], w[3 * k + 1], w[3 * k + 2]];
            let answer = solve_one(laws.get(k), row, [v_a[2 * k], v_a[2 * k + 1]], e[k], mu[k]);
            let failed = answer.is_err();
            cols.push(k, answer);
            if failed && raise_errors {
                break;
            }
        }
        cols
    });
    if raise_errors && let Some((row, why)) = cols.errors.first() {
        let (row, why) = (*row, why.clone());
        return Err(errors::raise(
            py,
            "ImpactError",
            format!("row {row}: {why}"),
            |k| {
                k.set_item("row", row)?;
                k.set_item("detail", why)
            },
        ));
    }
    let out = PyDict::new(py);
    for (name, column) in [
        ("i_n", cols.i_n),
        ("i_t", cols.i_t),
        ("delta_e", cols.delta_e),
        ("work_n", cols.work_n),
        ("work_t", cols.work_t),
        ("alpha", cols.alpha),
        ("g", cols.g),
        ("h", cols.h),
        ("p", cols.p),
        ("q", cols.q),
    ] {
        out.set_item(name, PyArray1::from_vec(py, column))?;
    }
    out.set_item("v_s", PyArray1::from_vec(py, cols.v_s).reshape([n, 2])?)?;
    out.set_item("type_number", PyArray1::from_vec(py, cols.kind))?;
    out.set_item("case", PyArray1::from_vec(py, cols.case))?;
    out.set_item("errors", cols.errors)?;
    Ok(out)
}
