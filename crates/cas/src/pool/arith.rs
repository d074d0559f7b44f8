//! The constructors of sums, products and powers, each returning the canonical form.

use num_traits::{One, Signed, Zero};

use super::collect::{ProductBuilder, SumBuilder};
use super::{ExprId, Node, Pool};
use crate::number::{self, Rational};

impl Pool {
    // ----- sums ----------------------------------------------------------------------------

    pub fn add(&mut self, terms: &[ExprId]) -> ExprId {
        let mut sum = SumBuilder::default();
        for &t in terms {
            sum.push(self, t, &Rational::one());
        }
        sum.finish(self)
    }

    /// `constant + Σ k·t` from terms and their coefficients, without building each `k·t` as
    /// a node first: the same sum as `add` of the scaled terms.
    pub(crate) fn sum_of(
        &mut self,
        constant: Rational,
        terms: impl IntoIterator<Item = (ExprId, Rational)>,
    ) -> ExprId {
        let mut sum = SumBuilder { constant, terms: Vec::new() };
        for (t, k) in terms {
            if !k.is_zero() {
                sum.push(self, t, &k);
            }
        }
        sum.finish(self)
    }

    /// `Σ k·t` over `terms`, each a term and its coefficient: the node `add` gives for the
    /// scaled terms (or for each term written out k times), and no other node made.
    pub fn add_scaled(&mut self, terms: &[(ExprId, Rational)]) -> ExprId {
        self.sum_of(Rational::zero(), terms.iter().cloned())
    }

    pub fn add2(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.add(&[a, b])
    }

    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let mut sum = SumBuilder::default();
        sum.push(self, a, &Rational::one());
        sum.push(self, b, &-Rational::one());
        sum.finish(self)
    }

    pub fn neg(&mut self, a: ExprId) -> ExprId {
        self.scale(a, &-Rational::one())
    }

    /// `q · a`, distributing over sums so that `2(x + y)` is `2x + 2y`.
    pub fn scale(&mut self, a: ExprId, q: &Rational) -> ExprId {
        if q.is_one() {
            return a;
        }
        if q.is_zero() {
            return self.zero;
        }
        if let Node::Num(p) = self.node(a) {
            let value = number::times(p, q);
            return self.num(value);
        }
        match self.node(a) {
            Node::Add(..) => {
                let mut sum = SumBuilder::default();
                sum.push(self, a, q);
                sum.finish(self)
            }
            _ => {
                let mut prod = ProductBuilder::new();
                prod.coef = q.clone();
                prod.push(self, a);
                prod.finish(self)
            }
        }
    }

    // ----- products and powers -------------------------------------------------------------

    pub fn mul(&mut self, factors: &[ExprId]) -> ExprId {
        let mut prod = ProductBuilder::new();
        for &f in factors {
            prod.push(self, f);
            if prod.coef.is_zero() {
                return self.zero;
            }
        }
        prod.finish(self)
    }

    pub fn mul2(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.mul(&[a, b])
    }

    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let inv = self.powq(b, &-Rational::one());
        self.mul(&[a, inv])
    }

    pub fn pow(&mut self, base: ExprId, exponent: ExprId) -> ExprId {
        if let Node::Num(q) = self.node(exponent) {
            let q = q.clone();
            return self.powq(base, &q);
        }
        if base == self.one {
            return self.one;
        }
        self.intern(Node::Pow(base, exponent))
    }

    pub fn powi(&mut self, base: ExprId, n: i64) -> ExprId {
        self.powq(base, &number::int(n))
    }

    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        self.powq(a, &number::ratio(1, 2))
    }

    /// `base^q` for a rational exponent.
    pub fn powq(&mut self, base: ExprId, q: &Rational) -> ExprId {
        if q.is_zero() {
            return self.one;
        }
        if q.is_one() {
            return base;
        }
        match self.node(base).clone() {
            Node::Mul(c, factors) if q.is_integer() || factors.len() == 1 => {
                // (c Π b^e)^n = c^n Π b^(e n) for integer n; for a single factor with a fractional
                // exponent only when that cannot change the sign (sqrt(x^2) stays, x^(1/2)^(1/2)
                // becomes x^(1/4)).
                if !q.is_integer() {
                    let (b, e) = &factors[0];
                    let safe = !e.is_integer() && c.is_positive();
                    if !safe {
                        return self.raw_power(base, q);
                    }
                    let mut prod = ProductBuilder::new();
                    let cn = self.num_node(&c);
                    prod.push_factor(self, cn, q);
                    prod.push_factor(self, *b, &(e * q));
                    return prod.finish(self);
                }
                let mut prod = ProductBuilder::new();
                let cn = self.num_node(&c);
                prod.push_factor(self, cn, q);
                for (b, e) in factors.iter() {
                    prod.push_factor(self, *b, &(e * q));
                }
                prod.finish(self)
            }
            Node::Mul(c, factors) if c.is_positive() && !c.is_one() => {
                // sqrt(3 x y) = sqrt(3) sqrt(x y): a positive number may always come out.
                let rest = self.intern(Node::Mul(Rational::one(), factors.clone()));
                let mut prod = ProductBuilder::new();
                let cn = self.num_node(&c);
                prod.push_factor(self, cn, q);
                prod.push_factor(self, rest, q);
                prod.finish(self)
            }
            Node::Pow(b, s) if q.is_integer() => {
                let qs = self.num(q.clone());
                let exponent = self.mul2(s, qs);
                self.pow(b, exponent)
            }
            _ => self.raw_power(base, q),
        }
    }

    fn raw_power(&mut self, base: ExprId, q: &Rational) -> ExprId {
        let mut prod = ProductBuilder::new();
        prod.push_factor(self, base, q);
        prod.finish(self)
    }

    fn num_node(&mut self, q: &Rational) -> ExprId {
        self.num(q.clone())
    }
}
