//! `Scene.derive()`: the forms a `derive` report shows (engine's `derived`), handed to Python
//! as SymPy objects in a dict that the Python `Derivation` class wraps, with a LaTeX rendering
//! of the equations for notebooks.

use cas::{ExprId, Pool, Style};
use engine::derived::{collect, Derivation, Derived, NumericValue, ShownAtStart};
use model::Value;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::sympy::ToSympy;

/// Parameter values in declaration order, `None` where a parameter has none (or it is not a
/// finite number), by the scene's one way to them (`model::ParameterValues`).
pub fn parameter_values(d: &Derivation) -> Vec<(String, Option<f64>)> {
    let values = model::ParameterValues::new(&d.model).scene_values();
    d.model.params.iter().zip(values).map(|(p, v)| (p.name.clone(), v)).collect()
}

/// Everything `derive` shows, as a dict of SymPy objects.
pub fn derive<'py>(py: Python<'py>, d: &mut Derivation) -> PyResult<Bound<'py, PyDict>> {
    let derived = collect(d);
    // Each coordinate with its rate and acceleration, which every scene may name.
    let mut named_symbols: Vec<cas::SymId> = d.model.constants().iter().map(|c| c.0).collect();
    for c in d.model.coords.clone() {
        let rate = d.model.pool.rate(c.sym);
        let acceleration = rate.and_then(|r| d.model.pool.rate(r));
        named_symbols.extend([Some(c.sym), rate, acceleration].into_iter().flatten());
    }
    named_symbols.extend(d.model.constraints.iter().map(|c| c.force_symbol));
    let pool = &d.model.pool;
    let mut s = ToSympy::new(py)?;
    let out = PyDict::new(py);
    out.set_item("title", d.model.title.clone())?;
    out.set_item("t", s.time())?;

    let list = |s: &mut ToSympy<'py>, syms: &[cas::SymId]| -> PyResult<Bound<'py, PyList>> {
        let items: Vec<_> = syms.iter().map(|q| s.symbol(pool, *q)).collect::<PyResult<_>>()?;
        PyList::new(py, items)
    };
    out.set_item("coordinates", list(&mut s, &d.coords)?)?;
    out.set_item("rates", list(&mut s, &d.rates)?)?;
    out.set_item("accelerations", list(&mut s, &d.accels)?)?;
    let lambdas: Vec<cas::SymId> = d.multipliers.iter().map(|m| m.lambda).collect();
    out.set_item("multipliers", list(&mut s, &lambdas)?)?;

    let parameters = PyDict::new(py);
    for (name, value) in parameter_values(d) {
        parameters.set_item(name, value)?;
    }
    out.set_item("parameters", parameters)?;
    // Each derived parameter with the parameters its value names: they are the ones to set.
    let plan = model::ParameterValues::new(&d.model);
    let follows = PyDict::new(py);
    for i in plan.derived() {
        follows.set_item(&d.model.params[i].name, plan.sources(i))?;
    }
    out.set_item("derived_parameters", follows)?;

    // Every name of the scene, as it spells it, to the SymPy object that stands for it.
    let symbols = PyDict::new(py);
    for sym in named_symbols {
        symbols.set_item(&pool.symbol(sym).name, s.symbol(pool, sym)?)?;
    }
    out.set_item("symbols", symbols)?;

    out.set_item("mass_matrix", s.matrix(pool, &derived.mass_matrix)?)?;
    out.set_item("forcing", s.column(pool, &derived.forcing)?)?;
    let equations: Vec<_> = derived
        .equations
        .iter()
        .map(|eq| s.equation(pool, eq.lhs, eq.rhs))
        .collect::<PyResult<_>>()?;
    out.set_item("equations", PyList::new(py, equations)?)?;
    out.set_item("kinetic", s.expr(pool, derived.kinetic)?)?;
    out.set_item("potential", s.expr(pool, derived.potential)?)?;
    let lagrangian = match derived.lagrangian {
        Some(e) => s.expr(pool, e)?,
        None => s.expr(pool, d.lagrangian)?,
    };
    out.set_item("lagrangian", lagrangian)?;

    let named = |s: &mut ToSympy<'py>, items: &[(cas::SymId, ExprId)]| -> PyResult<_> {
        let dict = PyDict::new(py);
        for (sym, e) in items {
            dict.set_item(&pool.symbol(*sym).name, s.expr(pool, *e)?)?;
        }
        Ok(dict)
    };
    out.set_item("reactions", named(&mut s, &derived.reactions)?)?;
    out.set_item("reactions_of_state", named(&mut s, &derived.reactions_of_state)?)?;
    out.set_item("start", named(&mut s, &derived.start_state)?)?;

    let shown = PyDict::new(py);
    for (show, value) in &derived.shown {
        shown.set_item(&show.label, s.value(pool, value)?)?;
    }
    out.set_item("shown", shown)?;

    let (at_start, at_start_note) = at_start(py, &mut s, pool, &derived.at_start)?;
    out.set_item("at_start", at_start)?;
    out.set_item("at_start_note", at_start_note)?;

    let constraints = constraints(py, &mut s, d)?;
    out.set_item("constraints", constraints)?;

    let independent =
        derived.independent.as_ref().map(|form| independent(py, &mut s, pool, form)).transpose()?;
    out.set_item("independent", independent)?;
    out.set_item("latex", latex(d, &derived))?;
    Ok(out)
}

/// `show at start:` items: exact, or numbers with a note of how they were found, or only the
/// note of why there are none.
fn at_start<'py>(
    py: Python<'py>,
    s: &mut ToSympy<'py>,
    pool: &Pool,
    shown: &ShownAtStart,
) -> PyResult<(Bound<'py, PyDict>, Option<String>)> {
    let at_start = PyDict::new(py);
    let mut at_start_note: Option<String> = None;
    match shown {
        ShownAtStart::Exact(items) => {
            for (show, value) in items {
                at_start.set_item(&show.label, s.value(pool, value)?)?;
            }
        }
        ShownAtStart::Numeric { items, unknowns, digits, .. } => {
            for (show, value) in items {
                let v = match value {
                    NumericValue::Scalar(x) => s.float(*x)?,
                    NumericValue::Vector(xs) => {
                        let entries: Vec<_> =
                            xs.iter().map(|x| s.float(*x)).collect::<PyResult<_>>()?;
                        let rows: Vec<_> = entries
                            .into_iter()
                            .map(|e| PyList::new(py, [e]))
                            .collect::<PyResult<_>>()?;
                        py.import("sympy")?.getattr("Matrix")?.call1((PyList::new(py, rows)?,))?
                    }
                    NumericValue::Matrix(m) => {
                        let rows: Vec<_> = m
                            .iter()
                            .map(|r| {
                                let entries: Vec<_> =
                                    r.iter().map(|x| s.float(*x)).collect::<PyResult<_>>()?;
                                PyList::new(py, entries)
                            })
                            .collect::<PyResult<_>>()?;
                        py.import("sympy")?.getattr("Matrix")?.call1((PyList::new(py, rows)?,))?
                    }
                };
                at_start.set_item(&show.label, v)?;
            }
            at_start_note = Some(format!(
                "solved numerically at the parameters' values: {unknowns} unknowns, to about \
                 {digits} significant digits"
            ));
        }
        ShownAtStart::Unvalued { missing, .. } => {
            at_start_note = Some(format!(
                "the start needs numbers, and these parameters have no value: {}",
                missing.join(", ")
            ));
        }
        ShownAtStart::Singular => {
            at_start_note = Some("the mass matrix is singular at the start".to_string());
        }
    }
    Ok((at_start, at_start_note))
}

/// Each constraint: its equation, Φ, reaction, and how the derivation handled it.
fn constraints<'py>(
    py: Python<'py>,
    s: &mut ToSympy<'py>,
    d: &Derivation,
) -> PyResult<Bound<'py, PyList>> {
    let pool = &d.model.pool;
    let constraints = PyList::empty(py);
    for (k, c) in d.model.constraints.iter().enumerate() {
        let item = PyDict::new(py);
        item.set_item("name", &c.name)?;
        item.set_item("kind", c.kind.name())?;
        item.set_item("equation", s.equation(pool, c.lhs, c.rhs)?)?;
        item.set_item("phi", s.expr(pool, c.phi)?)?;
        item.set_item("reaction", s.symbol(pool, c.force_symbol)?)?;
        if let Some(e) = d.eliminated.iter().find(|e| e.constraint == k) {
            item.set_item("handling", "eliminated")?;
            item.set_item("solved_for", s.symbol(pool, e.coord)?)?;
            item.set_item("solution", s.expr(pool, e.solution)?)?;
        } else if d.multipliers.iter().any(|m| m.constraint == k) {
            item.set_item("handling", "kept")?;
        } else {
            // A component that always holds, dropped.
            item.set_item("handling", "dropped")?;
        }
        constraints.append(item)?;
    }
    Ok(constraints)
}

/// The equations in the independent rates, with the dependent rates solved.
fn independent<'py>(
    py: Python<'py>,
    s: &mut ToSympy<'py>,
    pool: &Pool,
    form: &engine::derived::IndependentForm,
) -> PyResult<Bound<'py, PyDict>> {
    let list = |s: &mut ToSympy<'py>, syms: &[cas::SymId]| -> PyResult<Bound<'py, PyList>> {
        let items: Vec<_> = syms.iter().map(|q| s.symbol(pool, *q)).collect::<PyResult<_>>()?;
        PyList::new(py, items)
    };
    let item = PyDict::new(py);
    let dependent = PyDict::new(py);
    for (rate, e) in &form.dependent {
        dependent.set_item(&pool.symbol(*rate).name, s.expr(pool, *e)?)?;
    }
    item.set_item("dependent", dependent)?;
    item.set_item("independent", list(s, &form.independent)?)?;
    let zero = pool.zero();
    let equations: Vec<_> =
        form.equations.iter().map(|e| s.equation(pool, *e, zero)).collect::<PyResult<_>>()?;
    item.set_item("equations", PyList::new(py, equations)?)?;
    Ok(item)
}

/// The equations of motion and the mass-matrix form in LaTeX, as a notebook shows them:
/// one `aligned` block inside `$$ … $$`.
pub fn latex(d: &Derivation, derived: &Derived) -> String {
    let pool = &d.model.pool;
    let l = Style::Latex;
    let mut lines = Vec::new();
    if let Some(title) = &d.model.title {
        lines.push(format!("&\\text{{{}}}", escape(title)));
    }
    for eq in &derived.equations {
        lines.push(format!("{} &= {}", pool.print(eq.lhs, l), pool.print(eq.rhs, l)));
    }
    if !derived.mass_matrix.is_empty() {
        let q: Vec<String> = d.accels.iter().map(|s| pool.symbol_text(*s, l)).collect();
        let forcing: Vec<Vec<ExprId>> = derived.forcing.iter().map(|e| vec![*e]).collect();
        lines.push(format!(
            "{} \\begin{{bmatrix}} {} \\end{{bmatrix}} &= {}",
            bmatrix(pool, &derived.mass_matrix),
            q.join(" \\\\ "),
            bmatrix(pool, &forcing)
        ));
    }
    for (sym, e) in &derived.reactions {
        lines.push(format!("{} &= {}", pool.symbol_text(*sym, l), pool.print(*e, l)));
    }
    if let ShownAtStart::Exact(items) = &derived.at_start {
        for (show, value) in items {
            let label = d.show_label(show, l);
            let value = match value {
                Value::Scalar(e) => pool.print(*e, l),
                Value::Vector(xs) => {
                    let rows: Vec<Vec<ExprId>> = xs.iter().map(|e| vec![*e]).collect();
                    bmatrix(pool, &rows)
                }
                Value::Matrix(m) => bmatrix(pool, m),
            };
            lines.push(format!("\\left.{label}\\right|_{{t=0}} &= {value}"));
        }
    }
    format!("$$\\begin{{aligned}}\n{}\n\\end{{aligned}}$$", lines.join(" \\\\\n"))
}

fn bmatrix(pool: &Pool, rows: &[Vec<ExprId>]) -> String {
    let body: Vec<String> = rows
        .iter()
        .map(|r| r.iter().map(|e| pool.print(*e, Style::Latex)).collect::<Vec<_>>().join(" & "))
        .collect();
    format!("\\begin{{bmatrix}} {} \\end{{bmatrix}}", body.join(" \\\\ "))
}

/// A title as LaTeX text: the characters LaTeX reads as commands escaped.
fn escape(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '{' | '}' | '$' | '&' | '#' | '%' | '_' => {
                out.push('\\');
                out.push(c);
            }
            '^' => out.push_str("\\^{}"),
            '~' => out.push_str("\\~{}"),
            _ => out.push(c),
        }
    }
    out
}
