//! The `show at start` items in numbers, for starts whose unknowns are too many for the
//! exact solve of `mechanics`.

use cas::SymId;
use mechanics::{Derivation, NumericStart, StartShows};
use model::Value;

use crate::start::{parameter_values, start_numeric};

/// A `show at start` value in floating point.
#[derive(Clone, Debug, PartialEq)]
pub enum NumericValue {
    Scalar(f64),
    Vector(Vec<f64>),
    Matrix(Vec<Vec<f64>>),
}

/// The `show at start` items, as [`shown_at_start`] could find them.
#[derive(Clone, Debug)]
pub enum ShownAtStart {
    /// Exactly, in the parameters.
    Exact(Vec<(model::Show, Value)>),
    /// Numerically at the scene's parameter values (`params`), for the reason `because`;
    /// `digits` significant digits are trustworthy.
    Numeric {
        items: Vec<(model::Show, NumericValue)>,
        unknowns: usize,
        digits: u32,
        params: Vec<(SymId, f64)>,
        because: NumericStart,
    },
    /// Numbers were needed, but these parameters have no value.
    Unvalued { unknowns: usize, missing: Vec<String> },
    /// The mass matrix (with the constraints' rows) is singular at the start.
    Singular,
}

/// The `show at start` items at the initial state: exactly where the algebra stays within
/// its budget, numerically at the parameters' values otherwise.
pub fn shown_at_start(d: &mut Derivation) -> ShownAtStart {
    let (unknowns, shows, because) = match d.shows_at_start() {
        StartShows::Exact(items) => return ShownAtStart::Exact(items),
        StartShows::Numeric { unknowns, shows, because } => (unknowns, shows, because),
    };
    let params = match parameter_values(d) {
        Ok(p) => p,
        Err(missing) => return ShownAtStart::Unvalued { unknowns, missing },
    };
    let Some(start) = start_numeric(d, &params) else {
        return ShownAtStart::Singular;
    };
    let items = shows
        .into_iter()
        .map(|s| {
            let v = d.expand_value(&s.value, true);
            let pool = &d.model.pool;
            // + 0.0 turns −0 (a value solved to exactly zero) into 0.
            let at = |e: &cas::ExprId| numeric::eval(pool, *e, &start.values) + 0.0;
            let numbers = match &v {
                Value::Scalar(e) => NumericValue::Scalar(at(e)),
                Value::Vector(xs) => NumericValue::Vector(xs.iter().map(at).collect()),
                Value::Matrix(m) => {
                    NumericValue::Matrix(m.iter().map(|r| r.iter().map(at).collect()).collect())
                }
            };
            (s, numbers)
        })
        .collect();
    ShownAtStart::Numeric { items, unknowns, digits: start.digits, params, because }
}
