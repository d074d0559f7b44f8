//! The collectors of sums and products: like terms and like powers gathered before a sum or
//! product is interned.

use std::sync::Arc;

use num_bigint::BigInt;
use num_traits::{One, Signed, Zero};

use super::{ExprId, Node, Pool};
use crate::number::{self, Rational};

/// Adds `value` to the entry of `key`. Entries are collected as they come and merged once,
/// by [`merged`]: most sums and products are short, and a map per builder cost more in
/// allocation than the merging does.
fn accumulate(entries: &mut Vec<(ExprId, Rational)>, key: ExprId, value: Rational) {
    entries.push((key, value));
}

/// The entries sorted by key, with the values of equal keys added: what a map from key to
/// value would hold.
fn merged(mut entries: Vec<(ExprId, Rational)>) -> Vec<(ExprId, Rational)> {
    if entries.windows(2).all(|w| w[0].0 < w[1].0) {
        return entries;
    }
    entries.sort_unstable_by_key(|(key, _)| *key);
    let mut out: Vec<(ExprId, Rational)> = Vec::with_capacity(entries.len());
    for (key, value) in entries {
        match out.last_mut() {
            Some((last, sum)) if *last == key => number::add_to(sum, &value),
            _ => out.push((key, value)),
        }
    }
    out
}

/// Collects a sum: a constant and a coefficient per distinct term.
#[derive(Default)]
pub(super) struct SumBuilder {
    pub(super) constant: Rational,
    pub(super) terms: Vec<(ExprId, Rational)>,
}

impl SumBuilder {
    pub(super) fn push(&mut self, pool: &mut Pool, e: ExprId, scale: &Rational) {
        // Read the node in place: cloning it would copy its coefficients.
        match pool.node(e) {
            Node::Num(q) => number::add_to(&mut self.constant, &number::times(q, scale)),
            Node::Add(c, terms) => {
                number::add_to(&mut self.constant, &number::times(c, scale));
                for (t, k) in terms.iter() {
                    accumulate(&mut self.terms, *t, number::times(k, scale));
                }
            }
            Node::Mul(c, _) if !c.is_one() => {
                let (c, rest) = pool.split_coefficient(e);
                accumulate(&mut self.terms, rest, number::times(&c, scale));
            }
            _ => accumulate(&mut self.terms, e, scale.clone()),
        }
    }

    pub(super) fn finish(self, pool: &mut Pool) -> ExprId {
        let terms: Vec<(ExprId, Rational)> =
            merged(self.terms).into_iter().filter(|(_, k)| !k.is_zero()).collect();
        match terms.len() {
            0 => pool.num(self.constant),
            1 if self.constant.is_zero() => {
                let (t, k) = &terms[0];
                pool.scale(*t, k)
            }
            _ => pool.intern(Node::Add(self.constant, Arc::from(terms))),
        }
    }
}

/// A sum collected outside the pool: its constant, and its terms sorted by term with their
/// coefficients, like terms added. Sums of many long sums that share most of their terms (a
/// chain's accelerations, Σₖ≥ᵢ a₀ₖ for every i) are collected from each other's collections
/// rather than term by term, and interned only when complete ([`Pool::add_collected`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Collected {
    constant: Rational,
    terms: Vec<(ExprId, Rational)>,
}

impl Collected {
    /// The collection of both sums.
    pub fn plus(&self, other: &Collected) -> Collected {
        let mut terms = Vec::with_capacity(self.terms.len() + other.terms.len());
        let (mut a, mut b) = (self.terms.iter().peekable(), other.terms.iter().peekable());
        loop {
            let next = match (a.peek(), b.peek()) {
                (Some(x), Some(y)) if x.0 == y.0 => {
                    let sum = number::plus(&x.1, &y.1);
                    let key = x.0;
                    a.next();
                    b.next();
                    (key, sum)
                }
                (Some(x), Some(y)) if x.0 < y.0 => a.next().cloned().expect("peeked"),
                (Some(_), Some(_)) | (None, Some(_)) => b.next().cloned().expect("peeked"),
                (Some(_), None) => a.next().cloned().expect("peeked"),
                (None, None) => break,
            };
            terms.push(next);
        }
        Collected { constant: number::plus(&self.constant, &other.constant), terms }
    }
}

impl Pool {
    /// What [`Pool::add`] collects from `e`, where collecting it makes no node: every
    /// expression but a product with a coefficient other than 1 (whose rest `add` interns).
    pub fn collected(&self, e: ExprId) -> Option<Collected> {
        self.collected_all(&[e])
    }

    /// [`Pool::collected`] of the sum of `exprs`, in one pass as `add` collects it.
    pub fn collected_all(&self, exprs: &[ExprId]) -> Option<Collected> {
        let mut sum = SumBuilder::default();
        for &e in exprs {
            match self.node(e) {
                Node::Mul(c, _) if !c.is_one() => return None,
                Node::Num(q) => number::add_to(&mut sum.constant, q),
                Node::Add(c, terms) => {
                    number::add_to(&mut sum.constant, c);
                    sum.terms.extend(terms.iter().cloned());
                }
                _ => sum.terms.push((e, Rational::one())),
            }
        }
        Some(Collected { constant: sum.constant, terms: merged(sum.terms) })
    }

    /// The sum collected: the node [`Pool::add`] of the expressions it was collected from
    /// gives.
    pub fn add_collected(&mut self, sum: &Collected) -> ExprId {
        let builder = SumBuilder { constant: sum.constant.clone(), terms: sum.terms.clone() };
        builder.finish(self)
    }
}

/// Collects a product: a coefficient and an exponent per distinct base.
pub(super) struct ProductBuilder {
    pub(super) coef: Rational,
    factors: Vec<(ExprId, Rational)>,
}

impl ProductBuilder {
    pub(super) fn new() -> Self {
        ProductBuilder { coef: Rational::one(), factors: Vec::new() }
    }

    pub(super) fn push(&mut self, pool: &mut Pool, e: ExprId) {
        match pool.node(e) {
            Node::Num(q) => number::scale_by(&mut self.coef, q),
            Node::Mul(c, f) => {
                number::scale_by(&mut self.coef, c);
                for (b, x) in f.iter() {
                    accumulate(&mut self.factors, *b, x.clone());
                }
            }
            _ => accumulate(&mut self.factors, e, Rational::one()),
        }
    }

    pub(super) fn push_factor(&mut self, pool: &mut Pool, base: ExprId, exponent: &Rational) {
        let unpowered = match pool.node(base) {
            Node::Num(q) if exponent.is_integer() => match number::pow_int(q, exponent.numer()) {
                Some(v) => {
                    number::scale_by(&mut self.coef, &v);
                    None
                }
                None => Some(base),
            },
            Node::Mul(c, f) if exponent.is_integer() => {
                for (b, x) in f.iter() {
                    accumulate(&mut self.factors, *b, number::times(x, exponent));
                }
                match number::pow_int(c, exponent.numer()) {
                    Some(v) => {
                        number::scale_by(&mut self.coef, &v);
                        None
                    }
                    None => {
                        let c = c.clone();
                        Some(pool.num(c))
                    }
                }
            }
            _ => Some(base),
        };
        if let Some(b) = unpowered {
            accumulate(&mut self.factors, b, exponent.clone());
        }
    }

    /// q₁^x·q₂^x = (q₁·q₂)^x for positive rationals and one fractional x, so that √2·√3 is √6
    /// as a hand derivation writes it (the loop in `finish` then takes out what is a perfect
    /// power: √2·√6 = √12 = 2·√3). Whether it combined any.
    fn combine_numeric_powers(&mut self, pool: &mut Pool) -> bool {
        let positive = |pool: &Pool, (b, x): &(ExprId, Rational)| {
            !x.is_integer() && matches!(pool.node(*b), Node::Num(q) if q.is_positive())
        };
        let mut combined = false;
        let mut k = 0;
        while k < self.factors.len() {
            if !positive(pool, &self.factors[k]) {
                k += 1;
                continue;
            }
            let x = self.factors[k].1.clone();
            let mut base = pool.as_num(self.factors[k].0).cloned().unwrap_or_else(Rational::one);
            let mut j = k + 1;
            let mut merged_any = false;
            while j < self.factors.len() {
                if self.factors[j].1 == x && positive(pool, &self.factors[j]) {
                    let (b, _) = self.factors.remove(j);
                    if let Some(q) = pool.as_num(b) {
                        base *= q.clone();
                    }
                    merged_any = true;
                } else {
                    j += 1;
                }
            }
            if merged_any {
                self.factors[k].0 = pool.num(base);
                combined = true;
            }
            k += 1;
        }
        if combined {
            self.factors = merged(std::mem::take(&mut self.factors));
        }
        combined
    }

    /// Whether no factor is one the folding in `finish` would touch: most products are of
    /// symbols and functions, and need no pass at all.
    fn settled(&self, pool: &Pool) -> bool {
        self.factors.iter().all(|(b, x)| match pool.node(*b) {
            Node::Num(_) => false,
            Node::Mul(..) => !x.is_integer(),
            _ => !x.is_zero(),
        })
    }

    pub(super) fn finish(mut self, pool: &mut Pool) -> ExprId {
        // Merging exponents can turn a fractional power of a number or product into an integer
        // one (√3·√3, √(xy)·√(xy)); fold those until nothing changes.
        self.factors = merged(std::mem::take(&mut self.factors));
        while !self.settled(pool) {
            let mut changed = self.combine_numeric_powers(pool);
            let entries = std::mem::take(&mut self.factors);
            for (b, x) in entries {
                if x.is_zero() {
                    changed = true;
                    continue;
                }
                match pool.node(b).clone() {
                    Node::Num(q) if q.is_zero() && x.is_positive() => {
                        self.coef = Rational::zero();
                        changed = true;
                    }
                    Node::Num(q) if x.is_integer() => match number::pow_int(&q, x.numer()) {
                        Some(v) => {
                            number::scale_by(&mut self.coef, &v);
                            changed = true;
                        }
                        None => accumulate(&mut self.factors, b, x),
                    },
                    Node::Num(q) if q.is_positive() => match number::rational_root(&q, &x) {
                        Some((c, r)) => {
                            self.coef *= c;
                            let root = Rational::new(BigInt::one(), x.denom().clone());
                            if !r.is_one() {
                                let rn = pool.num(r);
                                if (rn, root.clone()) != (b, x.clone()) {
                                    changed = true;
                                }
                                accumulate(&mut self.factors, rn, root);
                            } else {
                                changed = true;
                            }
                        }
                        None => accumulate(&mut self.factors, b, x),
                    },
                    Node::Mul(c, f) if x.is_integer() => {
                        changed = true;
                        self.coef *= number::pow_int(&c, x.numer()).unwrap_or_else(Rational::one);
                        for (fb, fx) in f.iter() {
                            accumulate(&mut self.factors, *fb, number::times(fx, &x));
                        }
                    }
                    _ => accumulate(&mut self.factors, b, x),
                }
            }
            self.factors = merged(std::mem::take(&mut self.factors));
            if !changed {
                break;
            }
        }
        if self.coef.is_zero() {
            return pool.zero;
        }
        let factors: Vec<(ExprId, Rational)> =
            self.factors.into_iter().filter(|(_, x)| !x.is_zero()).collect();
        if factors.is_empty() {
            return pool.num(self.coef);
        }
        if factors.len() == 1 && factors[0].1.is_one() {
            let b = factors[0].0;
            if self.coef.is_one() {
                return b;
            }
            if matches!(pool.node(b), Node::Add(..)) {
                return pool.scale(b, &self.coef);
            }
        }
        pool.intern(Node::Mul(self.coef, Arc::from(factors)))
    }
}
