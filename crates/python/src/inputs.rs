//! What drives a scene's inputs in a call of `rhs`, `rhs.batch` or `rhs.jac`: `u=` read into
//! one [`Source`] per input (a number, one number per row of a batch, or a Python callable of
//! (t, y)), each evaluated into its input's parameter slot before the equations are. Inputs
//! are not parameters: `p=` and `parameters` leave them out, as `Derivation.parameters` does.

use numpy::{AllowTypeChange, PyArray1, PyArrayLike1};
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyMapping;

/// What gives one input its value in a call.
pub enum Source {
    Value(f64),
    /// One value per row of a batch.
    PerRow(Vec<f64>),
    /// A callable of (t, y) returning a number: a feedback law, a signal of time.
    Law(Py<PyAny>),
}

/// The sources `given` names, the `declared` values for the inputs it does not (all of them
/// when it is `None`). A mapping names inputs; anything else is an array of every input's
/// value in the order of `names`. `rows` is the size of a batch, for which a mapping's value
/// may be an array of one value per row.
pub fn sources(
    names: &[String],
    declared: &[f64],
    parameters: &[String],
    given: Option<&Bound<'_, PyAny>>,
    rows: Option<usize>,
) -> PyResult<Vec<Source>> {
    let mut sources: Vec<Source> = declared.iter().map(|v| Source::Value(*v)).collect();
    let Some(given) = given else { return Ok(sources) };
    let Ok(mapping) = given.cast::<PyMapping>() else {
        let values = every_value(names, given)?;
        return Ok(values.into_iter().map(Source::Value).collect());
    };
    for item in mapping.items()?.iter() {
        let (name, value): (String, Bound<'_, PyAny>) = item.extract()?;
        let Some(k) = names.iter().position(|n| *n == name) else {
            return Err(unknown_input(names, parameters, &name));
        };
        sources[k] = source(&name, &value, rows)?;
    }
    Ok(sources)
}

fn source(name: &str, value: &Bound<'_, PyAny>, rows: Option<usize>) -> PyResult<Source> {
    if let Ok(v) = value.extract::<f64>() {
        return Ok(Source::Value(finite(name, v)?));
    }
    if value.is_callable() {
        return Ok(Source::Law(value.clone().unbind()));
    }
    let wrong = || {
        let per_row = if rows.is_some() { ", an array of one value per row" } else { "" };
        PyTypeError::new_err(format!(
            "input `{name}` takes a number{per_row} or a callable of (t, y), not {}",
            value.get_type().name().map_or_else(|_| "that".into(), |n| n.to_string())
        ))
    };
    let (Some(rows), Ok(array)) = (rows, value.extract::<PyArrayLike1<'_, f64, AllowTypeChange>>())
    else {
        return Err(wrong());
    };
    let values: Vec<f64> = array.as_array().iter().copied().collect();
    if values.len() != rows {
        return Err(PyValueError::new_err(format!(
            "input `{name}` has {} values for {rows} states",
            values.len()
        )));
    }
    values.iter().try_for_each(|v| finite(name, *v).map(|_| ()))?;
    Ok(Source::PerRow(values))
}

fn every_value(names: &[String], given: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let form = PyTypeError::new_err(format!(
        "inputs are a dict of name to a number or a callable of (t, y), or an array of {} \
         values ({})",
        names.len(),
        names.join(", ")
    ));
    in_order(names, given, "input", form)
}

/// The values of `names`, each a `what` (parameter, input), from an array of them all in
/// their order, each finite; `form` when `given` is not an array.
pub fn in_order(
    names: &[String],
    given: &Bound<'_, PyAny>,
    what: &str,
    form: PyErr,
) -> PyResult<Vec<f64>> {
    let array: PyArrayLike1<'_, f64, AllowTypeChange> = given.extract().map_err(|_| form)?;
    let values: Vec<f64> = array.as_array().iter().copied().collect();
    if values.len() != names.len() {
        return Err(PyValueError::new_err(format!(
            "{} {what} values for the {} {what}s ({})",
            values.len(),
            names.len(),
            names.join(", ")
        )));
    }
    names.iter().zip(values).map(|(name, v)| finite_value(what, name, v)).collect()
}

fn unknown_input(names: &[String], parameters: &[String], name: &str) -> PyErr {
    if parameters.iter().any(|p| p == name) {
        return PyKeyError::new_err(format!(
            "`{name}` is a parameter, not an input: give it with p="
        ));
    }
    if names.is_empty() {
        return PyKeyError::new_err(format!(
            "no input `{name}`: the scene declares none (`input NAME = VALUE UNIT`)"
        ));
    }
    PyKeyError::new_err(format!("no input `{name}`; the inputs are {}", names.join(", ")))
}

fn finite(name: &str, v: f64) -> PyResult<f64> {
    finite_value("input", name, v)
}

/// `v`, or why a `what` (parameter, input) may not take it.
pub fn finite_value(what: &str, name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PyValueError::new_err(format!("{what} `{name}` must be finite, not {v}")))
    }
}

/// The inputs' values at (t, y), row `row` of a batch: a law is called with t and y as a
/// NumPy array, and must return a finite number.
pub fn values(
    py: Python<'_>,
    names: &[String],
    sources: &[Source],
    t: f64,
    y: &[f64],
    row: usize,
) -> PyResult<Vec<f64>> {
    let mut values = Vec::with_capacity(sources.len());
    for (name, source) in names.iter().zip(sources) {
        let value = match source {
            Source::Value(v) => *v,
            Source::PerRow(v) => v[row],
            Source::Law(law) => {
                let returned = law.call1(py, (t, PyArray1::from_slice(py, y)))?;
                let v = returned.extract::<f64>(py).map_err(|_| {
                    PyTypeError::new_err(format!(
                        "the callable for input `{name}` returned {}, not a number",
                        returned
                            .bind(py)
                            .repr()
                            .map_or_else(|_| "something".into(), |r| r.to_string())
                    ))
                })?;
                if !v.is_finite() {
                    return Err(PyValueError::new_err(format!(
                        "the callable for input `{name}` gave {v} at t = {t}"
                    )));
                }
                v
            }
        };
        values.push(value);
    }
    Ok(values)
}

/// ∂u/∂y of a law at (t, y) by central differences, one row of the state's length: a callable
/// has no exact derivative to give.
pub fn law_gradient(py: Python<'_>, law: &Py<PyAny>, t: f64, y: &[f64]) -> PyResult<Vec<f64>> {
    let at = |state: &[f64]| -> PyResult<f64> {
        law.call1(py, (t, PyArray1::from_slice(py, state)))?.extract::<f64>(py)
    };
    let mut state = y.to_vec();
    let mut gradient = Vec::with_capacity(y.len());
    for i in 0..y.len() {
        let h = central_step(y[i]);
        state[i] = y[i] + h;
        let up = at(&state)?;
        state[i] = y[i] - h;
        let down = at(&state)?;
        state[i] = y[i];
        gradient.push((up - down) / (2.0 * h));
    }
    Ok(gradient)
}

/// The step of a central difference at x: ε^(1/3) in scale, which balances its truncation
/// error (of order h²) against rounding (of order ε/h).
pub fn central_step(x: f64) -> f64 {
    6.055454452393343e-6 * x.abs().max(1.0)
}
