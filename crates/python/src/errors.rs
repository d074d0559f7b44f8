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
            let rendered = lang::render::render(path, source, diagnostics);
            scene_error(error, &rendered, &|at| in_text(path, source, at), diagnostics)
        }
        // Rendered against the expression itself, which is not a line of the file.
        engine::Error::Expression { diagnostics, text } => {
            let rendered = lang::render::render(EXPRESSION, text, diagnostics);
            scene_error(error, &rendered, &|at| in_text(EXPRESSION, text, at), diagnostics)
        }
        // The scene's diagnostics against the file, the argument's against the argument, named
        // by its keyword.
        engine::Error::WithArgument { diagnostics, source, setting, argument } => {
            let name = setting.name();
            let scene = (path, source.as_str());
            let rendered = lang::render::render_with_argument(scene, (name, argument), diagnostics);
            let start = lang::render::argument_start(source);
            let locate = |at: usize| match at.checked_sub(start) {
                Some(offset) => in_text(name, argument, offset),
                None => in_text(path, source, at),
            };
            scene_error(error, &rendered, &locate, diagnostics)
        }
        engine::Error::Input(message) => PyValueError::new_err(message.clone()),
        engine::Error::Setting(_) => PyValueError::new_err(error.worded(keyword)),
        engine::Error::Numeric(message) => numeric_error(message.clone()),
    }
}

/// What the diagnostics of an expression given besides the scene name as their file.
const EXPRESSION: &str = "expression";

/// The file, line and column of an offset into `text`, named `name`.
fn in_text<'a>(name: &'a str, text: &str, at: usize) -> (&'a str, usize, usize) {
    let (line, column) = engine::line_col(text, at);
    (name, line, column)
}

/// Diagnostics as a `lagrange.SceneError`: `rendered` as the `lagrange` command prints them,
/// `locate` the file, line and column of an offset their spans name.
fn scene_error<'a>(
    error: &engine::Error,
    rendered: &str,
    locate: &dyn Fn(usize) -> (&'a str, usize, usize),
    diagnostics: &[lang::Diagnostic],
) -> PyErr {
    Python::attach(|py| {
        let first = diagnostics
            .iter()
            .find(|d| d.severity == Severity::Error)
            .or_else(|| diagnostics.first());
        let located = first.map(|d| locate(d.span.start));
        let build = || -> PyResult<Bound<'_, PyDict>> {
            let attributes = PyDict::new(py);
            let file = located.map_or_else(|| locate(0).0, |(file, ..)| file);
            attributes.set_item("file", file)?;
            attributes.set_item("line", located.map(|(_, line, _)| line))?;
            attributes.set_item("column", located.map(|(.., column)| column))?;
            attributes.set_item("rendered", rendered)?;
            let items = PyList::empty(py);
            for d in diagnostics {
                let (_, line, column) = locate(d.span.start);
                let severity = match d.severity {
                    Severity::Error => "error",
                    Severity::Warning => "warning",
                };
                items.append((severity, d.message.clone(), line, column))?;
            }
            attributes.set_item("diagnostics", items)?;
            Ok(attributes)
        };
        let message = match (first, located) {
            (Some(d), Some((file, line, column))) => {
                // The hint ("did you mean `g`?") is often the answer: str(e) keeps it.
                match &d.hint {
                    Some(hint) => format!("{file}:{line}:{column}: {} ({hint})", d.message),
                    None => format!("{file}:{line}:{column}: {}", d.message),
                }
            }
            _ => error.to_string(),
        };
        match build() {
            Ok(attributes) => exception("SceneError", message, Some(attributes)),
            Err(e) => e,
        }
    })
}

/// A setting as a Python caller writes it: the keyword argument, `set={"gg": …}`.
fn keyword(piece: &engine::Piece) -> String {
    match piece {
        engine::Piece::Text(text) => text.clone(),
        engine::Piece::Setting(s) => format!("`{}`", s.name()),
        engine::Piece::Given(engine::Setting::Set, name) => format!("`set={{{name:?}: …}}`"),
        // A number as Python writes it, anything else (a sweep's text) as a string.
        engine::Piece::Given(s, given) if given.parse::<f64>().is_ok() => {
            format!("`{}={given}`", s.name())
        }
        engine::Piece::Given(s, given) => format!("`{}={given:?}`", s.name()),
    }
}
