//! A result's data (`results::Data`) as Python objects: maps as dicts, lists as lists,
//! numeric arrays and matrices as NumPy arrays, complex numbers as `complex`, exact
//! expressions as SymPy.

use pyo3::prelude::*;
use pyo3::types::{PyComplex, PyDict, PyList};
use results::Data;

use crate::sympy::ToSympy;

/// `data` as the Python object it stands for.
pub fn to_python<'py>(py: Python<'py>, data: &Data) -> PyResult<Bound<'py, PyAny>> {
    let mut s = ToSympy::new(py)?;
    let numpy = py.import("numpy")?;
    convert(py, &numpy, &mut s, data)
}

fn convert<'py>(
    py: Python<'py>,
    numpy: &Bound<'py, PyModule>,
    s: &mut ToSympy<'py>,
    data: &Data,
) -> PyResult<Bound<'py, PyAny>> {
    let list = |s: &mut ToSympy<'py>, items: &[Data]| -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for item in items {
            list.append(convert(py, numpy, s, item)?)?;
        }
        Ok(list)
    };
    Ok(match data {
        Data::Null => py.None().into_bound(py),
        Data::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Data::Int(n) => n.into_pyobject(py)?.into_any(),
        Data::Float(v) => v.into_pyobject(py)?.into_any(),
        Data::Text(t) => t.into_pyobject(py)?.into_any(),
        Data::List(items) => list(s, items)?.into_any(),
        Data::Array(items) => numpy.call_method1("array", (list(s, items)?,))?,
        Data::Map(entries) => {
            let dict = PyDict::new(py);
            for (key, value) in entries {
                dict.set_item(key, convert(py, numpy, s, value)?)?;
            }
            dict.into_any()
        }
        Data::Complex(re, im) => PyComplex::from_doubles(py, *re, *im).into_any(),
        // An empty list has no shape for NumPy: the matrix gives its columns.
        Data::Matrix { rows, columns } => {
            let a = numpy.call_method1("array", (rows.clone(),))?;
            a.call_method1("reshape", (rows.len(), *columns))?
        }
        Data::Exact(e) => s.term(&e.term)?,
        Data::ExactMatrix(rows) => s.terms(rows)?,
    })
}
