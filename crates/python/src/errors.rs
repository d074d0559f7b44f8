//! Engine errors as Python exceptions: a scene's mistakes as `lagrange.SceneError` (with the
//! file, line and column of the first error and the diagnostics rendered as the `lagrange`
//! command prints them), bad input as `ValueError` (settings named by their keywords), a
//! numeric fault as `lagrange.NumericError`. The exception classes are defined in
//! `lagrange/_errors.py`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use lang::Severity;

fn exception(name: &str, message: String, attributes: Option<Bound<'_, PyDict>>) -> PyErr {
    Python::attach(|py| {
        let made = py
            .import("lagrange._errors")
            .and_then(|m| m.getattr(name))
            .and_then(|class| class.call((message.clone(),), attributes.as_ref()));
        match made {
            Ok(value) => PyErr::from_value(value),
            Err(e) => e,
        }
    })
}

/// A numeric fault as `lagrange.NumericError`.
pub fn numeric_error(message: String) -> PyErr {
    exception("NumericError", message, None)
}

/// An engine error as the Python exception that says it; `path` names the scene's file in
/// rendered diagnostics.
pub fn engine_error(error: &engine::Error, path: &str) -> PyErr {
    match error {
        engine::Error::Scene { diagnostics, source } => {
            scene_error(error, path, source, diagnostics)
        }
        // Rendered against the expression itself, which is not a line of the file.
        engine::Error::Expression { diagnostics, text } => {
            scene_error(error, EXPRESSION, text, diagnostics)
        }
        engine::Error::Input(message) => PyValueError::new_err(message.clone()),
        engine::Error::Setting(_) => PyValueError::new_err(error.worded(keyword)),
        engine::Error::Numeric(message) => numeric_error(message.clone()),
    }
}

/// What the diagnostics of an expression given besides the scene name as their file.
const EXPRESSION: &str = "expression";

/// Diagnostics with spans into `source` as a `lagrange.SceneError`.
fn scene_error(
    error: &engine::Error,
    path: &str,
    source: &str,
    diagnostics: &[lang::Diagnostic],
) -> PyErr {
    {
        Python::attach(|py| {
            let rendered = lang::render::render(path, source, diagnostics);
            let first = diagnostics
                .iter()
                .find(|d| d.severity == Severity::Error)
                .or_else(|| diagnostics.first());
            let (line, column) = first.map(|d| engine::line_col(source, d.span.start)).unzip();
            let build = || -> PyResult<Bound<'_, PyDict>> {
                let attributes = PyDict::new(py);
                attributes.set_item("file", path)?;
                attributes.set_item("line", line)?;
                attributes.set_item("column", column)?;
                attributes.set_item("rendered", &rendered)?;
                let items = PyList::empty(py);
                for d in diagnostics {
                    let (line, column) = engine::line_col(source, d.span.start);
                    let severity = match d.severity {
                        Severity::Error => "error",
                        Severity::Warning => "warning",
                    };
                    items.append((severity, d.message.clone(), line, column))?;
                }
                attributes.set_item("diagnostics", items)?;
                Ok(attributes)
            };
            let message = match first {
                Some(d) => {
                    let (line, column) = (line.unwrap_or(1), column.unwrap_or(1));
                    // The hint ("did you mean `g`?") is often the answer: str(e) keeps it.
                    match &d.hint {
                        Some(hint) => format!("{path}:{line}:{column}: {} ({hint})", d.message),
                        None => format!("{path}:{line}:{column}: {}", d.message),
                    }
                }
                None => error.to_string(),
            };
            match build() {
                Ok(attributes) => exception("SceneError", message, Some(attributes)),
                Err(e) => e,
            }
        })
    }
}

/// A setting as a Python caller writes it: the keyword argument, `set={"gg": …}`.
fn keyword(piece: &engine::Piece) -> String {
    match piece {
        engine::Piece::Text(text) => text.clone(),
        engine::Piece::Setting(s) => format!("`{}`", s.name()),
        engine::Piece::Given(engine::Setting::Set, name) => format!("`set={{{name:?}: …}}`"),
        engine::Piece::Given(s, given) => format!("`{}={given:?}`", s.name()),
    }
}
