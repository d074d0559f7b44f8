//! Substitution of expressions for symbols, and numeric evaluation.

use std::collections::HashMap;

use crate::number;
use crate::pool::{ExprId, Func, Node, Pool, SymId};

impl Pool {
    /// Replaces every symbol in `map` by its expression, re-canonicalising on the way up.
    /// Sub-expressions that mention none of the symbols are shared, not rebuilt.
    pub fn subst(&mut self, e: ExprId, map: &HashMap<SymId, ExprId>) -> ExprId {
        let mut memo = HashMap::new();
        self.subst_memo(e, map, &mut memo)
    }

    /// Like [`Pool::subst`], reusing `memo` across calls with the same map.
    pub fn subst_memo(
        &mut self,
        e: ExprId,
        map: &HashMap<SymId, ExprId>,
        memo: &mut HashMap<ExprId, ExprId>,
    ) -> ExprId {
        if let Some(&r) = memo.get(&e) {
            return r;
        }
        let touches = self.free_symbols(e).iter().any(|s| map.contains_key(s));
        let r = if !touches {
            e
        } else {
            match self.node(e).clone() {
                Node::Sym(s) => map[&s],
                Node::Num(_) | Node::Pi => e,
                Node::Add(c, terms) => {
                    let mut parts = vec![self.num(c)];
                    for (t, k) in terms.iter() {
                        let t = self.subst_memo(*t, map, memo);
                        parts.push(self.scale(t, k));
                    }
                    self.add(&parts)
                }
                Node::Mul(c, factors) => {
                    let mut parts = vec![self.num(c)];
                    for (b, x) in factors.iter() {
                        let b = self.subst_memo(*b, map, memo);
                        parts.push(self.powq(b, x));
                    }
                    self.mul(&parts)
                }
                Node::Pow(b, x) => {
                    let b = self.subst_memo(b, map, memo);
                    let x = self.subst_memo(x, map, memo);
                    self.pow(b, x)
                }
                Node::Func(f, a) => {
                    let a = self.subst_memo(a, map, memo);
                    self.func(f, a)
                }
                Node::Atan2(y, x) => {
                    let y = self.subst_memo(y, map, memo);
                    let x = self.subst_memo(x, map, memo);
                    self.atan2(y, x)
                }
            }
        };
        memo.insert(e, r);
        r
    }

    /// Evaluates `e` in floating point, with `values[s.index()]` the value of symbol `s`.
    /// Symbols without a value (past the end of `values`) are NaN, which propagates.
    pub fn eval(&self, e: ExprId, values: &[f64]) -> f64 {
        let mut memo = HashMap::new();
        self.eval_memo(e, values, &mut memo)
    }

    pub fn eval_memo(&self, e: ExprId, values: &[f64], memo: &mut HashMap<ExprId, f64>) -> f64 {
        if let Some(&v) = memo.get(&e) {
            return v;
        }
        let v = match self.node(e) {
            Node::Num(q) => number::to_f64(q),
            Node::Sym(s) => values.get(s.index()).copied().unwrap_or(f64::NAN),
            Node::Pi => std::f64::consts::PI,
            Node::Add(c, terms) => {
                let mut acc = number::to_f64(c);
                for (t, k) in terms.iter() {
                    acc += number::to_f64(k) * self.eval_memo(*t, values, memo);
                }
                acc
            }
            Node::Mul(c, factors) => {
                let mut acc = number::to_f64(c);
                for (b, x) in factors.iter() {
                    let base = self.eval_memo(*b, values, memo);
                    acc *= power(base, x);
                }
                acc
            }
            Node::Pow(b, x) => {
                self.eval_memo(*b, values, memo).powf(self.eval_memo(*x, values, memo))
            }
            Node::Func(f, a) => apply(*f, self.eval_memo(*a, values, memo)),
            Node::Atan2(y, x) => {
                self.eval_memo(*y, values, memo).atan2(self.eval_memo(*x, values, memo))
            }
        };
        memo.insert(e, v);
        v
    }
}

/// `base^x` for a rational exponent, with integer powers by repeated multiplication (exact
/// sign for negative bases) and square roots by `sqrt`.
pub fn power(base: f64, x: &number::Rational) -> f64 {
    use num_traits::ToPrimitive;
    if x.is_integer() {
        if let Some(n) = x.numer().to_i32() {
            return base.powi(n);
        }
    }
    if *x.denom() == 2.into() {
        if let Some(n) = x.numer().to_i32() {
            return base.sqrt().powi(n);
        }
    }
    base.powf(number::to_f64(x))
}

pub fn apply(f: Func, a: f64) -> f64 {
    match f {
        Func::Sin => a.sin(),
        Func::Cos => a.cos(),
        Func::Tan => a.tan(),
        Func::Asin => a.asin(),
        Func::Acos => a.acos(),
        Func::Atan => a.atan(),
        Func::Sinh => a.sinh(),
        Func::Cosh => a.cosh(),
        Func::Tanh => a.tanh(),
        Func::Exp => a.exp(),
        Func::Ln => a.ln(),
    }
}
