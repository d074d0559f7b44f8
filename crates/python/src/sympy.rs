//! Our exact expressions as SymPy objects, built node by node through SymPy's constructors
//! (never by parsing printed text): parameters become `Symbol`s, coordinates functions of `t`
//! and their rates and accelerations `Derivative`s of them, numbers exact `Rational`s.

use std::collections::HashMap;

use cas::{ExprId, Func, Node, Pool, SymId, SymbolKind};
use model::Value;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use results::{Exact, Term};

/// Builds SymPy expressions from one pool's expressions, each node once.
pub struct ToSympy<'py> {
    py: Python<'py>,
    sympy: Bound<'py, PyModule>,
    t: Bound<'py, PyAny>,
    symbols: HashMap<SymId, Bound<'py, PyAny>>,
    memo: HashMap<ExprId, Bound<'py, PyAny>>,
}

impl<'py> ToSympy<'py> {
    pub fn new(py: Python<'py>) -> PyResult<Self> {
        let sympy = py.import("sympy")?;
        let t = sympy.getattr("Symbol")?.call1(("t",))?;
        Ok(ToSympy { py, sympy, t, symbols: HashMap::new(), memo: HashMap::new() })
    }

    /// Time, `t`.
    pub fn time(&self) -> Bound<'py, PyAny> {
        self.t.clone()
    }

    fn call(&self, name: &str, args: Vec<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyAny>> {
        let args = PyTuple::new(self.py, args)?;
        self.sympy.getattr(name)?.call1(args)
    }

    /// An exact rational as `sympy.Rational` (an `Integer` when it is whole).
    pub fn rational(&self, q: &cas::Rational) -> PyResult<Bound<'py, PyAny>> {
        let p = q.numer().clone().into_pyobject(self.py)?.into_any();
        let d = q.denom().clone().into_pyobject(self.py)?.into_any();
        self.call("Rational", vec![p, d])
    }

    /// A symbol: a parameter (or reaction) as `Symbol(name)`, time as `t`, a coordinate as
    /// `Function(name)(t)` and its k-th rate as `Derivative(q(t), (t, k))`.
    pub fn symbol(&mut self, pool: &Pool, s: SymId) -> PyResult<Bound<'py, PyAny>> {
        if let Some(done) = self.symbols.get(&s) {
            return Ok(done.clone());
        }
        let symbol = pool.symbol(s);
        let value = match symbol.kind {
            SymbolKind::Param => {
                self.call("Symbol", vec![symbol.name.clone().into_pyobject(self.py)?.into_any()])?
            }
            SymbolKind::Time => self.t.clone(),
            SymbolKind::Coordinate { base, order } => {
                self.coordinate(pool.symbol(base).base_name(), order)?
            }
        };
        self.symbols.insert(s, value.clone());
        Ok(value)
    }

    /// `Function(name)(t)`, or its `order`-th `Derivative`.
    fn coordinate(&self, name: &str, order: u8) -> PyResult<Bound<'py, PyAny>> {
        let function = self.call("Function", vec![name.into_pyobject(self.py)?.into_any()])?;
        let q = function.call1((self.t.clone(),))?;
        if order == 0 {
            return Ok(q);
        }
        let order = (order as i64).into_pyobject(self.py)?.into_any();
        let wrt = PyTuple::new(self.py, [self.t.clone(), order])?.into_any();
        self.call("Derivative", vec![q, wrt])
    }

    /// An exact expression handed over as data, built as [`ToSympy::expr`] builds a pool's.
    pub fn term(&mut self, term: &Term) -> PyResult<Bound<'py, PyAny>> {
        let mut parts = |constant: &cas::Rational, parts: &[(Term, cas::Rational)], add: bool| {
            let mut args = vec![self.rational(constant)?];
            for (t, k) in parts {
                let t = self.term(t)?;
                args.push(match add {
                    true => self.call("Mul", vec![self.rational(k)?, t])?,
                    false => self.call("Pow", vec![t, self.rational(k)?])?,
                });
            }
            self.call(if add { "Add" } else { "Mul" }, args)
        };
        match term {
            Term::Add(c, terms) => parts(c, terms, true),
            Term::Mul(c, factors) => parts(c, factors, false),
            Term::Number(q) => self.rational(q),
            Term::Constant(name) => {
                self.call("Symbol", vec![name.clone().into_pyobject(self.py)?.into_any()])
            }
            Term::Time => Ok(self.t.clone()),
            Term::Coordinate { name, order } => self.coordinate(name, *order),
            Term::Pi => self.sympy.getattr("pi"),
            Term::Pow(base, exponent) => {
                let (base, exponent) = (self.term(base)?, self.term(exponent)?);
                self.call("Pow", vec![base, exponent])
            }
            Term::Func(f, argument) => {
                let argument = self.term(argument)?;
                self.call(function_name(*f), vec![argument])
            }
            Term::Atan2(y, x) => {
                let (y, x) = (self.term(y)?, self.term(x)?);
                self.call("atan2", vec![y, x])
            }
        }
    }

    /// A `sympy.Matrix` of rows of exact expressions handed over as data.
    pub fn terms(&mut self, rows: &[Vec<Exact>]) -> PyResult<Bound<'py, PyAny>> {
        let mut out = Vec::new();
        for row in rows {
            let entries: Vec<Bound<'py, PyAny>> =
                row.iter().map(|e| self.term(&e.term)).collect::<PyResult<_>>()?;
            out.push(PyList::new(self.py, entries)?.into_any());
        }
        let rows = PyList::new(self.py, out)?.into_any();
        self.call("Matrix", vec![rows])
    }

    /// An expression, walked node by node.
    pub fn expr(&mut self, pool: &Pool, e: ExprId) -> PyResult<Bound<'py, PyAny>> {
        if let Some(done) = self.memo.get(&e) {
            return Ok(done.clone());
        }
        let value = match pool.node(e) {
            Node::Num(q) => self.rational(q)?,
            Node::Sym(s) => self.symbol(pool, *s)?,
            Node::Pi => self.sympy.getattr("pi")?,
            Node::Add(constant, terms) => {
                let mut args = vec![self.rational(constant)?];
                for (term, coefficient) in terms.iter() {
                    let term = self.expr(pool, *term)?;
                    args.push(self.call("Mul", vec![self.rational(coefficient)?, term])?);
                }
                self.call("Add", args)?
            }
            Node::Mul(coefficient, factors) => {
                let mut args = vec![self.rational(coefficient)?];
                for (base, exponent) in factors.iter() {
                    let base = self.expr(pool, *base)?;
                    args.push(self.call("Pow", vec![base, self.rational(exponent)?])?);
                }
                self.call("Mul", args)?
            }
            Node::Pow(base, exponent) => {
                let (base, exponent) = (self.expr(pool, *base)?, self.expr(pool, *exponent)?);
                self.call("Pow", vec![base, exponent])?
            }
            Node::Func(f, argument) => {
                let argument = self.expr(pool, *argument)?;
                self.call(function_name(*f), vec![argument])?
            }
            Node::Atan2(y, x) => {
                let (y, x) = (self.expr(pool, *y)?, self.expr(pool, *x)?);
                self.call("atan2", vec![y, x])?
            }
        };
        self.memo.insert(e, value.clone());
        Ok(value)
    }

    /// `sympy.Eq(lhs, rhs)`, left unevaluated.
    pub fn equation(
        &mut self,
        pool: &Pool,
        lhs: ExprId,
        rhs: ExprId,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (l, r) = (self.expr(pool, lhs)?, self.expr(pool, rhs)?);
        let kwargs = pyo3::types::PyDict::new(self.py);
        kwargs.set_item("evaluate", false)?;
        self.sympy.getattr("Eq")?.call((l, r), Some(&kwargs))
    }

    /// A `sympy.Matrix` of rows of expressions.
    pub fn matrix(&mut self, pool: &Pool, rows: &[Vec<ExprId>]) -> PyResult<Bound<'py, PyAny>> {
        let mut out = Vec::new();
        for row in rows {
            let entries: Vec<Bound<'py, PyAny>> =
                row.iter().map(|e| self.expr(pool, *e)).collect::<PyResult<_>>()?;
            out.push(PyList::new(self.py, entries)?.into_any());
        }
        let rows = PyList::new(self.py, out)?.into_any();
        self.call("Matrix", vec![rows])
    }

    /// A column vector as a `sympy.Matrix`.
    pub fn column(&mut self, pool: &Pool, entries: &[ExprId]) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<Vec<ExprId>> = entries.iter().map(|e| vec![*e]).collect();
        self.matrix(pool, &rows)
    }

    /// A scene value: a scalar as an expression, a vector as a column, a matrix as a matrix.
    pub fn value(&mut self, pool: &Pool, v: &Value) -> PyResult<Bound<'py, PyAny>> {
        match v {
            Value::Scalar(e) => self.expr(pool, *e),
            Value::Vector(xs) => self.column(pool, xs),
            Value::Matrix(rows) => self.matrix(pool, rows),
        }
    }

    /// A float as `sympy.Float`, for values known only numerically.
    pub fn float(&self, x: f64) -> PyResult<Bound<'py, PyAny>> {
        self.call("Float", vec![x.into_pyobject(self.py)?.into_any()])
    }
}

/// SymPy's name of a function: ours, except the natural logarithm, which SymPy calls `log`,
/// and `Abs`. (`min` and `max` reach SymPy as the `Abs` they are written with.)
fn function_name(f: Func) -> &'static str {
    match f {
        Func::Ln => "log",
        Func::Abs => "Abs",
        other => other.name(),
    }
}
