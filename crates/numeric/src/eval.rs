//! Expressions evaluated at a point, for every number that is not a simulation's: parameter
//! values, initial states, `expect` checks and the zero test's numbers. They go through the
//! same lowering and tape as the integrators, so a value is the same wherever it is computed.

use cas::{ExprId, Node, Pool, SymId};

use crate::elementary::{pow_int, to_f64};
use crate::lower::lower_free;
use crate::tape::Tape;

/// Expressions lowered once, to be evaluated at many points. The inputs are every symbol the
/// expressions mention, read from a vector indexed by symbol ([`SymId::index`]).
#[derive(Clone, Debug)]
pub struct Evaluator {
    tape: Tape,
    symbols: Vec<SymId>,
    input: Vec<f64>,
    out: Vec<f64>,
}

impl Evaluator {
    pub fn new(pool: &Pool, exprs: &[ExprId]) -> Evaluator {
        let (program, symbols) = lower_free(pool, exprs);
        Evaluator {
            tape: Tape::new(program),
            input: vec![0.0; symbols.len()],
            symbols,
            out: vec![0.0; exprs.len()],
        }
    }

    /// The symbols the expressions read.
    pub fn symbols(&self) -> &[SymId] {
        &self.symbols
    }

    /// The value of each expression, in order, with `values[s.index()]` the value of symbol
    /// `s`. A symbol past the end of `values` is NaN, which propagates.
    pub fn eval(&mut self, values: &[f64]) -> &[f64] {
        for (slot, s) in self.input.iter_mut().zip(&self.symbols) {
            *slot = values.get(s.index()).copied().unwrap_or(f64::NAN);
        }
        self.tape.eval(&self.input, &mut self.out);
        &self.out
    }
}

/// The value of one expression at one point: see [`Evaluator::eval`].
pub fn eval(pool: &Pool, e: ExprId, values: &[f64]) -> f64 {
    Evaluator::new(pool, &[e]).eval(values)[0]
}

/// Expressions evaluated with the size of the terms each is a sum of, for tests relative to
/// that size: a cancellation of large terms is not a large value, and a small value among
/// small terms is not a zero.
#[derive(Clone, Debug)]
pub struct ScaledEvaluator {
    evaluator: Evaluator,
    /// Per expression, `None` for one that is not a sum (its size is its magnitude).
    sums: Vec<Option<Sum>>,
}

/// A sum's parts: |its constant| and, per term, the term's output and its coefficient.
#[derive(Clone, Debug)]
struct Sum {
    constant: f64,
    terms: Vec<(usize, f64)>,
}

impl ScaledEvaluator {
    pub fn new(pool: &Pool, exprs: &[ExprId]) -> ScaledEvaluator {
        let mut outputs = exprs.to_vec();
        let mut sums = Vec::with_capacity(exprs.len());
        for e in exprs {
            sums.push(match pool.node(*e) {
                Node::Add(c, terms) => {
                    let mut parts = Vec::with_capacity(terms.len());
                    for (t, k) in terms.iter() {
                        parts.push((outputs.len(), to_f64(k)));
                        outputs.push(*t);
                    }
                    Some(Sum { constant: to_f64(c).abs(), terms: parts })
                }
                _ => None,
            });
        }
        ScaledEvaluator { evaluator: Evaluator::new(pool, &outputs), sums }
    }

    /// `(value, size)` of each expression, in order; see [`Evaluator::eval`] for `values`.
    pub fn eval(&mut self, values: &[f64]) -> Vec<(f64, f64)> {
        let out = self.evaluator.eval(values);
        self.sums
            .iter()
            .enumerate()
            .map(|(i, sum)| {
                let value = out[i];
                let size = match sum {
                    Some(Sum { constant, terms }) => {
                        constant + terms.iter().map(|(j, k)| (k * out[*j]).abs()).sum::<f64>()
                    }
                    None => value.abs(),
                };
                (value, size)
            })
            .collect()
    }
}

/// The value of one expression at one point and the size of the terms it is a sum of: see
/// [`ScaledEvaluator`]: the zero test's quick probe ([`crate::GenericPoints`]).
pub fn value_and_scale(pool: &Pool, e: ExprId, values: &[f64]) -> (f64, f64) {
    ScaledEvaluator::new(pool, &[e]).eval(values)[0]
}

/// The value of one expression at one point and its magnitude: the same expression evaluated
/// with every coefficient, term and factor by its absolute value, so that the rounding of the
/// value is within a few ulps of the magnitude wherever cancellations hide, in a sum nested
/// however deep: for the zero test of expressions too large for the algebra
/// ([`Pool::vanishes_at_generic_points`], through [`crate::GenericPoints`]).
pub fn value_and_magnitude(pool: &Pool, e: ExprId, values: &[f64]) -> (f64, f64) {
    let mut memo = std::collections::HashMap::new();
    magnitude(pool, e, values, &mut memo)
}

fn magnitude(
    pool: &Pool,
    e: ExprId,
    values: &[f64],
    memo: &mut std::collections::HashMap<ExprId, (f64, f64)>,
) -> (f64, f64) {
    if let Some(&r) = memo.get(&e) {
        return r;
    }
    let r = match pool.node(e) {
        Node::Num(q) => (to_f64(q), to_f64(q).abs()),
        Node::Sym(s) => {
            let v = values.get(s.index()).copied().unwrap_or(f64::NAN);
            (v, v.abs())
        }
        Node::Pi => (std::f64::consts::PI, std::f64::consts::PI),
        Node::Add(c, terms) => {
            let (mut value, mut size) = (to_f64(c), to_f64(c).abs());
            for (t, k) in terms.iter() {
                let (v, m) = magnitude(pool, *t, values, memo);
                let k = to_f64(k);
                value += k * v;
                size += k.abs() * m;
            }
            (value, size)
        }
        Node::Mul(c, factors) => {
            let (mut value, mut size) = (to_f64(c), to_f64(c).abs());
            for (b, x) in factors.iter() {
                let (v, m) = magnitude(pool, *b, values, memo);
                match x.is_integer().then(|| x.to_integer()).and_then(|n| i32::try_from(n).ok()) {
                    Some(n) if n > 0 => {
                        value *= pow_int(v, n);
                        size *= pow_int(m, n);
                    }
                    // A quotient or a root: its rounding is relative to its value.
                    Some(n) => {
                        let p = pow_int(v, n);
                        value *= p;
                        size *= p.abs();
                    }
                    None => {
                        let p = crate::elementary::pow(v, to_f64(x));
                        value *= p;
                        size *= p.abs();
                    }
                }
            }
            (value, size)
        }
        Node::Pow(b, x) => {
            let (v, m) = magnitude(pool, *b, values, memo);
            let (xv, _) = magnitude(pool, *x, values, memo);
            let p = crate::elementary::pow(v, xv);
            let size =
                if xv > 0.0 && xv.fract() == 0.0 { crate::elementary::pow(m, xv) } else { p.abs() };
            (p, size)
        }
        Node::Func(f, a) => {
            let (v, _) = magnitude(pool, *a, values, memo);
            let value = crate::elementary::apply(*f, v);
            (value, value.abs())
        }
        Node::Atan2(y, x) => {
            let (yv, _) = magnitude(pool, *y, values, memo);
            let (xv, _) = magnitude(pool, *x, values, memo);
            let value = crate::elementary::atan2(yv, xv);
            (value, value.abs())
        }
    };
    memo.insert(e, r);
    r
}
