//! Structure queries: free symbols, children, terms and factors of an expression.

use std::sync::Arc;

use num_traits::{One, Zero};

use super::collect::ProductBuilder;
use super::{ExprId, Node, Pool, SymId};
use crate::number::Rational;

impl Pool {
    // ----- structure queries ---------------------------------------------------------------

    /// The symbols `e` depends on, sorted by id. Memoised.
    pub fn free_symbols(&mut self, e: ExprId) -> Arc<[SymId]> {
        if let Some(Some(s)) = self.free_memo.get(e.index()) {
            return s.clone();
        }
        let children = self.children(e);
        let set: Arc<[SymId]> = match self.node(e) {
            Node::Sym(s) => Arc::from(vec![*s]),
            _ => {
                let mut all: Vec<SymId> = Vec::new();
                for c in children {
                    all.extend(self.free_symbols(c).iter().copied());
                }
                all.sort_unstable();
                all.dedup();
                Arc::from(all)
            }
        };
        if self.free_memo.len() <= e.index() {
            self.free_memo.resize(e.index() + 1, None);
        }
        self.free_memo[e.index()] = Some(set.clone());
        set
    }

    pub fn depends_on(&mut self, e: ExprId, s: SymId) -> bool {
        self.free_symbols(e).binary_search(&s).is_ok()
    }

    /// The direct sub-expressions of `e`.
    pub fn children(&self, e: ExprId) -> Vec<ExprId> {
        match self.node(e) {
            Node::Num(_) | Node::Sym(_) | Node::Pi => Vec::new(),
            Node::Add(_, t) | Node::Mul(_, t) => t.iter().map(|(x, _)| *x).collect(),
            Node::Pow(a, b) | Node::Atan2(a, b) => vec![*a, *b],
            Node::Func(_, a) => vec![*a],
        }
    }

    /// `body` on each of [`Pool::children`] in its order, without a vector to hold them: for
    /// walks over large expressions, which visit many nodes once each.
    pub fn for_each_child(&self, e: ExprId, mut body: impl FnMut(ExprId)) {
        match self.node(e) {
            Node::Num(_) | Node::Sym(_) | Node::Pi => {}
            Node::Add(_, t) | Node::Mul(_, t) => t.iter().for_each(|(x, _)| body(*x)),
            Node::Pow(a, b) | Node::Atan2(a, b) => {
                body(*a);
                body(*b);
            }
            Node::Func(_, a) => body(*a),
        }
    }

    /// Splits `e` into a rational coefficient and the rest: `3xy` → (3, xy), `x` → (1, x).
    pub fn split_coefficient(&mut self, e: ExprId) -> (Rational, ExprId) {
        match self.node(e).clone() {
            Node::Num(q) => (q, self.one),
            Node::Mul(c, f) if !c.is_one() => {
                // The factors are already canonical: the rest is the same product with
                // coefficient 1, or its one factor.
                if f.len() == 1 && f[0].1.is_one() {
                    (c, f[0].0)
                } else {
                    (c, self.intern(Node::Mul(Rational::one(), f)))
                }
            }
            _ => (Rational::one(), e),
        }
    }

    /// The terms of a sum (with their coefficients folded in), or `[e]` for anything else.
    pub fn terms(&mut self, e: ExprId) -> Vec<ExprId> {
        match self.node(e).clone() {
            Node::Add(c, terms) => {
                let mut out: Vec<ExprId> = terms.iter().map(|(t, k)| self.scale(*t, k)).collect();
                if !c.is_zero() {
                    out.push(self.num(c));
                }
                out
            }
            _ => vec![e],
        }
    }

    /// The factors of a product as (base, exponent) with its coefficient, or `(1, [(e, 1)])`.
    pub fn factors(&self, e: ExprId) -> (Rational, Vec<(ExprId, Rational)>) {
        match self.node(e) {
            Node::Num(q) => (q.clone(), Vec::new()),
            Node::Mul(c, f) => (c.clone(), f.to_vec()),
            _ => (Rational::one(), vec![(e, Rational::one())]),
        }
    }

    /// Rebuilds a product from a coefficient and (base, exponent) factors.
    pub fn product(&mut self, coef: &Rational, factors: &[(ExprId, Rational)]) -> ExprId {
        let mut prod = ProductBuilder::new();
        prod.coef = coef.clone();
        for (b, x) in factors {
            prod.push_factor(self, *b, x);
        }
        prod.finish(self)
    }
}
