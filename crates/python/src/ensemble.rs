//! `Scene.ensemble(...)`: `lagrange ensemble` from Python (the `ensemble` crate), its table as
//! NumPy columns. The scene is derived and lowered once per call, the runs go on the
//! ensemble's own threads with the GIL released, and Ctrl-C stops them between the calling
//! thread's runs.

use ::ensemble::{Ensemble, Table};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::engine_error;
use crate::runs::SignalCheck;

/// What to run: the ensemble's options, the threads (`None`: one per core) and the range of
/// its runs (`None` at the end: to the last), for a front end that spreads chunks itself.
pub struct Request {
    pub options: ::ensemble::Options,
    pub threads: Option<usize>,
    pub from: usize,
    pub to: Option<usize>,
}

/// Builds and runs the ensemble of `source`; its table as a dict of `columns` (name to a
/// NumPy array, a value per run), `varied` (how many of the columns are the varied values),
/// `failures` (a reason or `None` per run), `axes` (each grid axis's name and values),
/// `random` and `runs` (how many the whole ensemble has).
pub fn ensemble<'py>(
    py: Python<'py>,
    source: &str,
    path: &str,
    request: Request,
) -> PyResult<Bound<'py, PyDict>> {
    if request.threads == Some(0) {
        return Err(PyValueError::new_err("`threads` must be a positive whole number, not 0"));
    }
    let mut check = SignalCheck::new();
    let built = py.detach(|| {
        let ensemble = Ensemble::new(source, &request.options)?;
        let total = ensemble.runs();
        let threads = request.threads.unwrap_or_else(::ensemble::cores);
        // A chunk's end past the last run ends at it, as a slice does (a front end spreads
        // chunks of a fixed size); a start past it, or a range backwards, would give a table
        // with no rows that reads as if every run had been done.
        let to = request.to.unwrap_or(total).min(total);
        if request.from > to || (request.from == total && total > 0) {
            return Err(engine::Error::Input(format!(
                "runs {}..{to} are not a range of this ensemble's {total} runs (0..{total})",
                request.from
            )));
        }
        Ok::<_, engine::Error>((ensemble.run(request.from..to, threads, &mut check), total))
    });
    if let Some(raised) = check.raised {
        return Err(raised);
    }
    let (table, total) = built.map_err(|e| engine_error(&e, path))?;
    table_dict(py, &table, total)
}

/// The table as the dict the Python `EnsembleTable` wraps.
fn table_dict<'py>(py: Python<'py>, table: &Table, total: usize) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let columns = PyDict::new(py);
    for (k, name) in table.columns.iter().enumerate() {
        let values = table.rows.iter().map(|row| row.get(k).copied().unwrap_or(f64::NAN));
        columns.set_item(name, PyArray1::from_iter(py, values))?;
    }
    out.set_item("columns", columns)?;
    out.set_item("varied", table.varied)?;
    out.set_item("failures", PyList::new(py, &table.failures)?)?;
    let axes = PyList::empty(py);
    for (name, values) in &table.axes {
        axes.append((name, PyArray1::from_slice(py, values)))?;
    }
    out.set_item("axes", axes)?;
    out.set_item("random", table.random)?;
    out.set_item("runs", total)?;
    Ok(out)
}
