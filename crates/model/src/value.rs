//! Values of scene expressions: scalars, vectors (tuples) and matrices.

use cas::{ExprId, Pool};

#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Scalar(ExprId),
    /// `(x, y)` or `(x, y, z)`.
    Vector(Vec<ExprId>),
    /// `[a, b; c, d]`, rows of equal length; a column `[x''; s'']` is n×1.
    Matrix(Vec<Vec<ExprId>>),
}

impl Value {
    pub fn kind_name(&self) -> String {
        match self {
            Value::Scalar(_) => "a scalar".to_string(),
            Value::Vector(v) => format!("a {}-vector", v.len()),
            Value::Matrix(m) => {
                format!("a {}×{} matrix", m.len(), m.first().map_or(0, |r| r.len()))
            }
        }
    }

    /// The entries, row by row.
    pub fn entries(&self) -> Vec<ExprId> {
        match self {
            Value::Scalar(e) => vec![*e],
            Value::Vector(v) => v.clone(),
            Value::Matrix(m) => m.iter().flatten().copied().collect(),
        }
    }

    pub fn map(&self, mut f: impl FnMut(ExprId) -> ExprId) -> Value {
        match self {
            Value::Scalar(e) => Value::Scalar(f(*e)),
            Value::Vector(v) => Value::Vector(v.iter().map(|e| f(*e)).collect()),
            Value::Matrix(m) => {
                Value::Matrix(m.iter().map(|r| r.iter().map(|e| f(*e)).collect()).collect())
            }
        }
    }

    /// Prints the value with the given style: `(x, y)`, `[a, b; c, d]`.
    pub fn print(&self, pool: &Pool, style: cas::Style) -> String {
        match self {
            Value::Scalar(e) => pool.print(*e, style),
            Value::Vector(v) => {
                let parts: Vec<String> = v.iter().map(|e| pool.print(*e, style)).collect();
                format!("({})", parts.join(", "))
            }
            Value::Matrix(m) => {
                let rows: Vec<String> = m
                    .iter()
                    .map(|r| r.iter().map(|e| pool.print(*e, style)).collect::<Vec<_>>().join(", "))
                    .collect();
                format!("[{}]", rows.join("; "))
            }
        }
    }
}
