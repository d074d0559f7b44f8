//! The results front ends show, as plain data: each result is built here once, from the
//! engine's types, into a [`Data`] tree of plain values, and a front end only renders the
//! tree (the `lagrange` command as JSON, the Python package as Python objects). Owns the
//! shapes of `linearize`'s report ([`linearize`]), of `linearize --along`'s ([`along`]) and of `check`'s verdicts ([`check`]), and
//! exact expressions without their pool ([`Exact`]).
//!
//! Nothing here prints for people: the text reports stay with the command, which reads the
//! same data.

pub mod along;
pub mod check;
mod exact;
pub mod linearize;

pub use cas::{Func, Rational};
pub use exact::{Exact, Term};

/// A result as plain values. Besides what JSON has, the few kinds a front end renders its
/// own way: a complex number, a numeric array, a matrix of numbers with its shape, exact
/// expressions.
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    Null,
    Bool(bool),
    Int(i64),
    Float(f64),
    Text(String),
    List(Vec<Data>),
    /// Keys in the order they are shown.
    Map(Vec<(String, Data)>),
    Complex(f64, f64),
    /// A list that Python receives as a NumPy array (JSON as a list).
    Array(Vec<Data>),
    /// Rows of numbers; `columns` gives an empty matrix its shape.
    Matrix {
        rows: Vec<Vec<f64>>,
        columns: usize,
    },
    Exact(Exact),
    ExactMatrix(Vec<Vec<Exact>>),
}

impl Data {
    /// A count, which fits an `i64` on every machine we build for.
    pub fn count(n: usize) -> Data {
        Data::Int(i64::try_from(n).unwrap_or(i64::MAX))
    }

    pub fn text(s: impl Into<String>) -> Data {
        Data::Text(s.into())
    }

    pub fn texts<S: AsRef<str>>(items: &[S]) -> Data {
        Data::List(items.iter().map(|s| Data::text(s.as_ref())).collect())
    }

    pub fn floats(values: &[f64]) -> Data {
        Data::List(values.iter().map(|v| Data::Float(*v)).collect())
    }

    /// Rows of numbers, as many columns as the first row has.
    pub fn matrix(rows: &[Vec<f64>]) -> Data {
        let columns = rows.first().map_or(0, Vec::len);
        Data::Matrix { rows: rows.to_vec(), columns }
    }

    /// `None` as null.
    pub fn or_null(value: Option<Data>) -> Data {
        value.unwrap_or(Data::Null)
    }
}

/// A map built key by key, in order.
#[derive(Default)]
pub(crate) struct MapBuilder(Vec<(String, Data)>);

impl MapBuilder {
    pub(crate) fn put(&mut self, key: &str, value: Data) {
        self.0.push((key.to_string(), value));
    }

    pub(crate) fn done(self) -> Data {
        Data::Map(self.0)
    }
}
