//! The expression arena: interned nodes, symbols, and the simplifying constructors.
//!
//! Every expression lives in a [`Pool`] and is named by a small [`ExprId`]. Nodes are
//! hash-consed, so two structurally equal expressions are the same id, and every constructor
//! returns the canonical form: sums and products flattened, like terms and like powers
//! collected, numbers folded, exact values of functions at special points taken.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::rc::Rc;

use rustc_hash::FxHashMap;

use num_bigint::BigInt;
use num_traits::{One, Signed, Zero};

use crate::number::{self, Rational};

/// An expression in a [`Pool`]. Equal ids are equal expressions, and the converse holds for
/// the canonical forms the constructors produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(u32);

impl ExprId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A symbol in a [`Pool`]: a parameter, time, or a coordinate or one of its time derivatives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SymId(u32);

impl SymId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The elementary functions of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    /// |u|: continuous, with a kink at 0 (its derivative is `Sign`).
    Abs,
    /// −1, 0 or 1: a jump at 0, and a derivative of 0 everywhere else.
    Sign,
}

impl Func {
    pub const ALL: [Func; 13] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
        Func::Exp,
        Func::Ln,
        Func::Abs,
        Func::Sign,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
            Func::Sign => "sign",
        }
    }

    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    fn is_odd(self) -> bool {
        matches!(
            self,
            Func::Sin | Func::Tan | Func::Asin | Func::Atan | Func::Sinh | Func::Tanh | Func::Sign
        )
    }

    fn is_even(self) -> bool {
        matches!(self, Func::Cos | Func::Cosh | Func::Abs)
    }

    /// Whether it is smooth everywhere it is defined: derivatives through `abs` and `sign`
    /// are those of almost every point, and wrong at the kink or the jump.
    pub fn is_smooth(self) -> bool {
        !matches!(self, Func::Abs | Func::Sign)
    }
}

/// One interned node. Children are ids of nodes created before it.
#[derive(Clone, Debug, Eq)]
pub enum Node {
    Num(Rational),
    Sym(SymId),
    Pi,
    /// `constant + Σ coefficient·term`, terms sorted by id; no term is a number, a sum, or a
    /// product with a coefficient other than 1; at least two parts.
    Add(Rational, Rc<[(ExprId, Rational)]>),
    /// `coefficient · Π base^exponent`, bases sorted by id; no base is a product raised to an
    /// integer power or a rational raised to an integer power.
    Mul(Rational, Rc<[(ExprId, Rational)]>),
    /// A power whose exponent is not a number (numeric powers are one-factor products).
    Pow(ExprId, ExprId),
    Func(Func, ExprId),
    Atan2(ExprId, ExprId),
}

// Interning compares every node it finds in the table with the one it is handed. A rational's
// own equality goes through its ordering (cross-multiplying when denominators differ); ours are
// reduced, so equal values have equal numerators and denominators.
impl PartialEq for Node {
    fn eq(&self, other: &Node) -> bool {
        fn same(a: &Rational, b: &Rational) -> bool {
            a.numer() == b.numer() && a.denom() == b.denom()
        }
        fn same_parts(a: &[(ExprId, Rational)], b: &[(ExprId, Rational)]) -> bool {
            a.len() == b.len() && a.iter().zip(b).all(|((x, p), (y, q))| x == y && same(p, q))
        }
        match (self, other) {
            (Node::Num(a), Node::Num(b)) => same(a, b),
            (Node::Sym(a), Node::Sym(b)) => a == b,
            (Node::Pi, Node::Pi) => true,
            (Node::Add(c, a), Node::Add(d, b)) | (Node::Mul(c, a), Node::Mul(d, b)) => {
                same(c, d) && same_parts(a, b)
            }
            (Node::Pow(a, x), Node::Pow(b, y)) | (Node::Atan2(a, x), Node::Atan2(b, y)) => {
                a == b && x == y
            }
            (Node::Func(f, a), Node::Func(g, b)) => f == g && a == b,
            _ => false,
        }
    }
}

// Interning hashes every node it is handed, coefficients and exponents included. A rational's
// own hash walks its continued fraction (so that unreduced equal values hash alike), with a
// big-integer division per step; ours are always reduced, with a positive denominator, so
// hashing the numerator and denominator is consistent with equality and far cheaper.
impl Hash for Node {
    fn hash<H: Hasher>(&self, state: &mut H) {
        fn rational<H: Hasher>(q: &Rational, state: &mut H) {
            // The sign and lowest digits: equal reduced values agree on them, and the few
            // rationals that differ only above 2^64 may share a bucket.
            let (numer, denom) = (q.numer(), q.denom());
            state.write_u8(numer.sign() as u8);
            state.write_u64(numer.iter_u64_digits().next().unwrap_or(0));
            state.write_u64(denom.iter_u64_digits().next().unwrap_or(0));
        }
        std::mem::discriminant(self).hash(state);
        match self {
            Node::Num(q) => rational(q, state),
            Node::Sym(s) => s.hash(state),
            Node::Pi => {}
            Node::Add(c, parts) | Node::Mul(c, parts) => {
                rational(c, state);
                parts.len().hash(state);
                for (e, k) in parts.iter() {
                    e.hash(state);
                    rational(k, state);
                }
            }
            Node::Pow(a, b) | Node::Atan2(a, b) => {
                a.hash(state);
                b.hash(state);
            }
            Node::Func(f, a) => {
                f.hash(state);
                a.hash(state);
            }
        }
    }
}

/// What a symbol stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SymbolKind {
    /// A parameter or any other symbol constant in time.
    Param,
    /// Time, `t`.
    Time,
    /// A generalized coordinate (`order` 0) or its `order`-th time derivative.
    Coordinate { base: SymId, order: u8 },
}

#[derive(Clone, Debug)]
pub struct Symbol {
    /// The name as the scene spells it (`theta`, `x'`).
    pub name: String,
    pub kind: SymbolKind,
    rate: Option<SymId>,
}

impl Symbol {
    /// The name without primes (`theta` for `theta''`).
    pub fn base_name(&self) -> &str {
        self.name.trim_end_matches('\'')
    }

    /// How many time derivatives this symbol is of a coordinate (0 for anything else).
    pub fn order(&self) -> u8 {
        match self.kind {
            SymbolKind::Coordinate { order, .. } => order,
            _ => 0,
        }
    }
}

/// The numeric side of the zero test, handed in by a crate above this one ([`Pool::set_zero_test`]):
/// this crate evaluates no floats, and the one evaluator of expressions lives in `numeric`
/// (`numeric::GenericPoints`), which answers these questions at fixed generic points.
pub trait ZeroTest {
    /// Whether `e` is clearly not zero at a generic point, relative to the size of the terms
    /// that make it up: one such point proves that `e` is not identically zero.
    fn clearly_nonzero_somewhere(&self, pool: &Pool, e: ExprId) -> bool;

    /// Whether the vector `target` is, at every generic point, a combination of the vectors
    /// `rows` (each as long as it), the coefficients free to change from point to point; the
    /// rows the combination needs, by index, if so. See [`Pool::combination_at_generic_points`].
    fn combination_at_generic_points(
        &self,
        pool: &Pool,
        target: &[ExprId],
        rows: &[Vec<ExprId>],
    ) -> Option<Vec<usize>>;
}

/// The arena that owns every expression and symbol of one derivation.
pub struct Pool {
    nodes: Vec<Node>,
    // Fx rather than SipHash: the keys are our own ids, and interning is the hot path.
    interned: FxHashMap<Node, ExprId>,
    symbols: Vec<Symbol>,
    symbol_ids: HashMap<String, SymId>,
    pub(crate) diff_memo: FxHashMap<(ExprId, SymId), ExprId>,
    pub(crate) time_memo: FxHashMap<ExprId, ExprId>,
    pub(crate) expand_memo: FxHashMap<ExprId, ExprId>,
    pub(crate) simplify_memo: FxHashMap<ExprId, ExprId>,
    free_memo: Vec<Option<Rc<[SymId]>>>,
    zero: ExprId,
    one: ExprId,
    /// The numbers of the zero test, if a crate above handed them in.
    zero_test: Option<Box<dyn ZeroTest>>,
}

impl Default for Pool {
    fn default() -> Self {
        Self::new()
    }
}

impl Pool {
    pub fn new() -> Self {
        let mut pool = Pool {
            nodes: Vec::new(),
            interned: FxHashMap::default(),
            symbols: Vec::new(),
            symbol_ids: HashMap::new(),
            diff_memo: FxHashMap::default(),
            time_memo: FxHashMap::default(),
            expand_memo: FxHashMap::default(),
            simplify_memo: FxHashMap::default(),
            free_memo: Vec::new(),
            zero: ExprId(0),
            one: ExprId(0),
            zero_test: None,
        };
        pool.zero = pool.intern(Node::Num(Rational::zero()));
        pool.one = pool.intern(Node::Num(Rational::one()));
        pool
    }

    /// Hands in the numbers of the zero test: [`Pool::is_identically_zero`] tries a numeric
    /// point before the algebra (one point where the value is clearly not zero settles most
    /// questions at a fraction of the algebra's cost; without it the answers are the same, only
    /// slower to reach), and [`Pool::vanishes_at_generic_points`] and
    /// [`Pool::combination_at_generic_points`] decide with it what is too large for the
    /// algebra.
    pub fn set_zero_test(&mut self, test: Box<dyn ZeroTest>) {
        self.zero_test = Some(test);
    }

    /// The numbers of the zero test, if handed in ([`Pool::set_zero_test`]).
    pub(crate) fn zero_test(&self) -> Option<&dyn ZeroTest> {
        self.zero_test.as_deref()
    }

    fn intern(&mut self, node: Node) -> ExprId {
        // One lookup, hashing the node once, whether it is new or not.
        match self.interned.entry(node) {
            std::collections::hash_map::Entry::Occupied(known) => *known.get(),
            std::collections::hash_map::Entry::Vacant(slot) => {
                let id =
                    ExprId(u32::try_from(self.nodes.len()).expect("more than 2^32 expressions"));
                self.nodes.push(slot.key().clone());
                slot.insert(id);
                id
            }
        }
    }

    /// How many distinct expressions the pool holds.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn node(&self, e: ExprId) -> &Node {
        &self.nodes[e.index()]
    }

    // ----- symbols -------------------------------------------------------------------------

    fn new_symbol(&mut self, name: &str, kind: SymbolKind) -> SymId {
        let id = SymId(self.symbols.len() as u32);
        self.symbols.push(Symbol { name: name.to_string(), kind, rate: None });
        self.symbol_ids.insert(name.to_string(), id);
        id
    }

    /// The parameter (time-constant symbol) with this name, created on first use.
    pub fn param(&mut self, name: &str) -> SymId {
        match self.symbol_ids.get(name) {
            Some(&id) => id,
            None => self.new_symbol(name, SymbolKind::Param),
        }
    }

    /// Time, `t`.
    pub fn time(&mut self) -> SymId {
        match self.symbol_ids.get("t") {
            Some(&id) => id,
            None => self.new_symbol("t", SymbolKind::Time),
        }
    }

    /// Declares a generalized coordinate. An existing symbol of that name becomes one.
    pub fn coordinate(&mut self, name: &str) -> SymId {
        let id = self.param(name);
        self.symbols[id.index()].kind = SymbolKind::Coordinate { base: id, order: 0 };
        id
    }

    /// The time derivative of a coordinate symbol (`x` → `x'`), created on first use.
    /// `None` for symbols that are constant in time.
    pub fn rate(&mut self, s: SymId) -> Option<SymId> {
        let SymbolKind::Coordinate { base, order } = self.symbols[s.index()].kind else {
            return None;
        };
        if let Some(r) = self.symbols[s.index()].rate {
            return Some(r);
        }
        let name = format!("{}'", self.symbols[s.index()].name);
        let r = self.new_symbol(&name, SymbolKind::Coordinate { base, order: order + 1 });
        self.symbols[s.index()].rate = Some(r);
        Some(r)
    }

    /// The `order`-th time derivative symbol of a coordinate.
    pub fn derivative_symbol(&mut self, coordinate: SymId, order: u8) -> Option<SymId> {
        let mut s = coordinate;
        for _ in 0..order {
            s = self.rate(s)?;
        }
        Some(s)
    }

    pub fn symbol(&self, s: SymId) -> &Symbol {
        &self.symbols[s.index()]
    }

    pub fn lookup_symbol(&self, name: &str) -> Option<SymId> {
        self.symbol_ids.get(name).copied()
    }

    pub fn symbol_count(&self) -> usize {
        self.symbols.len()
    }

    // ----- leaves --------------------------------------------------------------------------

    pub fn zero(&self) -> ExprId {
        self.zero
    }

    pub fn one(&self) -> ExprId {
        self.one
    }

    pub fn num(&mut self, q: Rational) -> ExprId {
        self.intern(Node::Num(q))
    }

    pub fn int(&mut self, n: i64) -> ExprId {
        self.num(number::int(n))
    }

    pub fn ratio(&mut self, n: i64, d: i64) -> ExprId {
        self.num(number::ratio(n, d))
    }

    pub fn sym(&mut self, s: SymId) -> ExprId {
        self.intern(Node::Sym(s))
    }

    pub fn pi(&mut self) -> ExprId {
        self.intern(Node::Pi)
    }

    pub fn as_num(&self, e: ExprId) -> Option<&Rational> {
        match self.node(e) {
            Node::Num(q) => Some(q),
            _ => None,
        }
    }

    pub fn as_sym(&self, e: ExprId) -> Option<SymId> {
        match self.node(e) {
            Node::Sym(s) => Some(*s),
            _ => None,
        }
    }

    pub fn is_zero(&self, e: ExprId) -> bool {
        e == self.zero
    }

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

    // ----- functions -----------------------------------------------------------------------

    pub fn func(&mut self, f: Func, arg: ExprId) -> ExprId {
        if let Some(v) = self.exact_function_value(f, arg) {
            return v;
        }
        if let Some(v) = self.quarter_turn_shift(f, arg) {
            return v;
        }
        if f.is_odd() && self.looks_negative(arg) {
            let pos = self.neg(arg);
            let v = self.func(f, pos);
            return self.neg(v);
        }
        if f.is_even() && self.looks_negative(arg) {
            let pos = self.neg(arg);
            return self.func(f, pos);
        }
        self.intern(Node::Func(f, arg))
    }

    pub fn sin(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Sin, a)
    }

    pub fn cos(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Cos, a)
    }

    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        if let (Some(yq), Some(xq)) = (self.as_num(y), self.as_num(x)) {
            if yq.is_zero() && xq.is_positive() {
                return self.zero;
            }
        }
        self.intern(Node::Atan2(y, x))
    }

    /// Whether the canonical form reads with a leading minus sign. Used to pick one of `u` and
    /// `-u` as the argument of odd and even functions, so `cos(a - b)` and `cos(b - a)` meet.
    pub fn looks_negative(&self, e: ExprId) -> bool {
        match self.node(e) {
            Node::Num(q) => q.is_negative(),
            Node::Mul(c, _) => c.is_negative(),
            Node::Add(c, terms) => match terms.first() {
                Some((_, k)) => k.is_negative(),
                None => c.is_negative(),
            },
            _ => false,
        }
    }

    /// If `e` is `k·π` for a rational `k`, that `k`.
    pub fn pi_multiple(&self, e: ExprId) -> Option<Rational> {
        match self.node(e) {
            Node::Num(q) if q.is_zero() => Some(Rational::zero()),
            Node::Pi => Some(Rational::one()),
            Node::Mul(c, f)
                if f.len() == 1 && f[0].1.is_one() && *self.node(f[0].0) == Node::Pi =>
            {
                Some(c.clone())
            }
            _ => None,
        }
    }

    /// sin, cos or tan of `u + n·π/2` (n ≠ 0) in terms of `u`: cos(π/2 + u) is −sin(u), as a
    /// hand derivation reduces it (tan only for whole turns of π, where it stays a tan).
    fn quarter_turn_shift(&mut self, f: Func, arg: ExprId) -> Option<ExprId> {
        if !matches!(f, Func::Sin | Func::Cos | Func::Tan) {
            return None;
        }
        let Node::Add(_, terms) = self.node(arg) else { return None };
        let k = terms.iter().find(|(t, _)| *self.node(*t) == Node::Pi)?.1.clone();
        let halves = &k * number::int(2);
        if !halves.is_integer() {
            return None;
        }
        let n: i64 = num_traits::ToPrimitive::to_i64(&(halves.to_integer() % BigInt::from(4)))?;
        let n = n.rem_euclid(4);
        if f == Func::Tan && n % 2 == 1 {
            return None;
        }
        let pi = self.pi();
        let turn = self.scale(pi, &k);
        let u = self.sub(arg, turn);
        // sin(u + nπ/2) and cos(u + nπ/2) for n = 0, 1, 2, 3 go round sin, cos, −sin, −cos.
        let (g, negative) = match (f, n) {
            (Func::Tan, _) => (Func::Tan, false),
            (Func::Sin, 0) | (Func::Cos, 3) => (Func::Sin, false),
            (Func::Sin, 1) | (Func::Cos, 0) => (Func::Cos, false),
            (Func::Sin, 2) | (Func::Cos, 1) => (Func::Sin, true),
            _ => (Func::Cos, true),
        };
        let v = self.func(g, u);
        Some(if negative { self.neg(v) } else { v })
    }

    /// √(1 − x²), the cosine of asin(x) and the sine of acos(x) for real |x| ≤ 1 (their
    /// ranges, [−π/2, π/2] and [0, π], are where those are not negative).
    fn cofunction_of_inverse(&mut self, x: ExprId) -> ExprId {
        let square = self.powi(x, 2);
        let rest = self.sub(self.one, square);
        self.sqrt(rest)
    }

    fn exact_function_value(&mut self, f: Func, arg: ExprId) -> Option<ExprId> {
        match (f, self.node(arg).clone()) {
            (Func::Sin, Node::Func(Func::Asin, x)) => Some(x),
            (Func::Cos, Node::Func(Func::Acos, x)) => Some(x),
            (Func::Tan, Node::Func(Func::Atan, x)) => Some(x),
            (Func::Cos, Node::Func(Func::Asin, x)) | (Func::Sin, Node::Func(Func::Acos, x)) => {
                Some(self.cofunction_of_inverse(x))
            }
            (Func::Tan, Node::Func(Func::Asin, x)) => {
                let c = self.cofunction_of_inverse(x);
                Some(self.div(x, c))
            }
            (Func::Tan, Node::Func(Func::Acos, x)) => {
                let s = self.cofunction_of_inverse(x);
                Some(self.div(s, x))
            }
            // cos(atan x) = 1/√(1 + x²) > 0 on all of atan's range (−π/2, π/2).
            (Func::Sin | Func::Cos, Node::Func(Func::Atan, x)) => {
                let square = self.powi(x, 2);
                let hypotenuse = self.add2(self.one, square);
                let secant = self.sqrt(hypotenuse);
                let top = if f == Func::Sin { x } else { self.one };
                Some(self.div(top, secant))
            }
            (Func::Sin | Func::Cos | Func::Tan, _) => {
                let k = self.pi_multiple(arg)?;
                let sin = self.sin_of_pi_multiple(&k);
                let half = number::ratio(1, 2);
                let cos = self.sin_of_pi_multiple(&(k + half));
                match f {
                    Func::Sin => sin,
                    Func::Cos => cos,
                    _ => {
                        let (s, c) = (sin?, cos?);
                        (!self.is_zero(c)).then(|| self.div(s, c))
                    }
                }
            }
            (Func::Exp, Node::Num(q)) if q.is_zero() => Some(self.one),
            (Func::Exp, Node::Func(Func::Ln, x)) => Some(x),
            (Func::Ln, Node::Num(q)) if q.is_one() => Some(self.zero),
            (Func::Ln, Node::Func(Func::Exp, x)) => Some(x),
            (Func::Sinh | Func::Tanh | Func::Asin | Func::Atan, Node::Num(q)) if q.is_zero() => {
                Some(self.zero)
            }
            (Func::Cosh, Node::Num(q)) if q.is_zero() => Some(self.one),
            (Func::Abs, Node::Func(Func::Abs, _)) => Some(arg),
            (Func::Abs | Func::Sign, _) => {
                // A number, or a number times π, has a known sign.
                let (k, pi) = match self.node(arg) {
                    Node::Num(q) => (q.clone(), false),
                    _ => (self.pi_multiple(arg)?, true),
                };
                Some(match f {
                    Func::Sign if k.is_zero() => self.zero,
                    Func::Sign => self.num(number::int(if k.is_negative() { -1 } else { 1 })),
                    _ => {
                        let m = self.num(k.abs());
                        if pi {
                            let p = self.pi();
                            self.mul2(m, p)
                        } else {
                            m
                        }
                    }
                })
            }
            _ => None,
        }
    }

    /// sin(kπ) exactly, for k with denominator dividing 12.
    fn sin_of_pi_multiple(&mut self, k: &Rational) -> Option<ExprId> {
        let twelfths = k * number::int(12);
        if !twelfths.is_integer() {
            return None;
        }
        let n = twelfths.to_integer() % BigInt::from(24);
        let n: i64 = num_traits::ToPrimitive::to_i64(&n)?;
        let n = n.rem_euclid(24);
        let (index, negative) = match n {
            0..=6 => (n, false),
            7..=12 => (12 - n, false),
            13..=18 => (n - 12, true),
            _ => (24 - n, true),
        };
        let value = self.sin_twelfth(index);
        Some(if negative { self.neg(value) } else { value })
    }

    /// sin(nπ/12) for n = 0..=6.
    fn sin_twelfth(&mut self, n: i64) -> ExprId {
        let half = number::ratio(1, 2);
        let quarter = number::ratio(1, 4);
        match n {
            0 => self.zero,
            2 => self.num(half),
            3 | 4 => {
                let r = self.int(if n == 3 { 2 } else { 3 });
                let root = self.sqrt(r);
                self.scale(root, &half)
            }
            6 => self.one,
            _ => {
                // sin(π/12) = (√6 − √2)/4, sin(5π/12) = (√6 + √2)/4.
                let (six, two) = (self.int(6), self.int(2));
                let r6 = self.sqrt(six);
                let r2 = self.sqrt(two);
                let r2 = if n == 1 { self.neg(r2) } else { r2 };
                let s = self.add2(r6, r2);
                self.scale(s, &quarter)
            }
        }
    }

    // ----- structure queries ---------------------------------------------------------------

    /// The symbols `e` depends on, sorted by id. Memoised.
    pub fn free_symbols(&mut self, e: ExprId) -> Rc<[SymId]> {
        if let Some(Some(s)) = self.free_memo.get(e.index()) {
            return s.clone();
        }
        let children = self.children(e);
        let set: Rc<[SymId]> = match self.node(e) {
            Node::Sym(s) => Rc::from(vec![*s]),
            _ => {
                let mut all: Vec<SymId> = Vec::new();
                for c in children {
                    all.extend(self.free_symbols(c).iter().copied());
                }
                all.sort_unstable();
                all.dedup();
                Rc::from(all)
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
struct SumBuilder {
    constant: Rational,
    terms: Vec<(ExprId, Rational)>,
}

impl SumBuilder {
    fn push(&mut self, pool: &mut Pool, e: ExprId, scale: &Rational) {
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

    fn finish(self, pool: &mut Pool) -> ExprId {
        let terms: Vec<(ExprId, Rational)> =
            merged(self.terms).into_iter().filter(|(_, k)| !k.is_zero()).collect();
        match terms.len() {
            0 => pool.num(self.constant),
            1 if self.constant.is_zero() => {
                let (t, k) = &terms[0];
                pool.scale(*t, k)
            }
            _ => pool.intern(Node::Add(self.constant, Rc::from(terms))),
        }
    }
}

/// Collects a product: a coefficient and an exponent per distinct base.
struct ProductBuilder {
    coef: Rational,
    factors: Vec<(ExprId, Rational)>,
}

impl ProductBuilder {
    fn new() -> Self {
        ProductBuilder { coef: Rational::one(), factors: Vec::new() }
    }

    fn push(&mut self, pool: &mut Pool, e: ExprId) {
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

    fn push_factor(&mut self, pool: &mut Pool, base: ExprId, exponent: &Rational) {
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

    fn finish(mut self, pool: &mut Pool) -> ExprId {
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
        pool.intern(Node::Mul(self.coef, Rc::from(factors)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn like_terms_and_powers_collect() {
        let mut p = Pool::new();
        let x = p.param("x");
        let x = p.sym(x);
        let y = p.param("y");
        let y = p.sym(y);
        let xx = p.add2(x, x);
        let two_x = p.scale(x, &number::int(2));
        assert_eq!(xx, two_x);
        let x2 = p.mul2(x, x);
        assert_eq!(x2, p.powi(x, 2));
        let xy = p.mul2(x, y);
        let yx = p.mul2(y, x);
        assert_eq!(xy, yx);
        let d = p.sub(xy, yx);
        assert!(p.is_zero(d));
        let q = p.div(x2, x);
        assert_eq!(q, x);
    }

    #[test]
    fn exact_trig_at_special_angles() {
        let mut p = Pool::new();
        let pi = p.pi();
        let sixth = p.scale(pi, &number::ratio(1, 6));
        let s = p.sin(sixth);
        assert_eq!(p.as_num(s), Some(&number::ratio(1, 2)));
        let c = p.cos(sixth);
        let three = p.int(3);
        let r3 = p.sqrt(three);
        let expected = p.scale(r3, &number::ratio(1, 2));
        assert_eq!(c, expected);
        let c2 = p.mul2(c, c);
        assert_eq!(p.as_num(c2), Some(&number::ratio(3, 4)));
        let five_quarter = p.scale(pi, &number::ratio(5, 4));
        let s = p.sin(five_quarter);
        let two = p.int(2);
        let r2 = p.sqrt(two);
        let expected = p.scale(r2, &number::ratio(-1, 2));
        assert_eq!(s, expected);
    }

    /// Printed as a hand derivation writes them: the forms of the scene syntax.
    fn printed(p: &Pool, e: ExprId) -> String {
        p.print(e, crate::Style::Ascii)
    }

    #[test]
    fn powers_of_numbers_with_one_exponent_combine() {
        let mut p = Pool::new();
        let (two, three, six) = (p.int(2), p.int(3), p.int(6));
        let (r2, r3, r6) = (p.sqrt(two), p.sqrt(three), p.sqrt(six));
        let product = p.mul2(r2, r3);
        assert_eq!(printed(&p, product), "sqrt(6)");
        // √2·√6 = √12 = 2·√3: what is a perfect square comes out.
        let product = p.mul2(r2, r6);
        assert_eq!(printed(&p, product), "2*sqrt(3)");
        let x = p.param("x");
        let x = p.sym(x);
        let product = p.mul(&[r2, x, r3]);
        assert_eq!(printed(&p, product), "sqrt(6)*x");
        // √2/√2 is 1, and √3/√2 is √6/2 (1/√2 is √2/2 first).
        let inverse = p.powq(two, &number::ratio(-1, 2));
        let one = p.mul2(r2, inverse);
        assert_eq!(one, p.one());
        let quotient = p.mul2(r3, inverse);
        assert_eq!(printed(&p, quotient), "1/2*sqrt(6)");
    }

    #[test]
    fn trig_of_a_quarter_turn_and_more_is_trig_of_the_rest() {
        let mut p = Pool::new();
        let x = p.param("x");
        let x = p.sym(x);
        let pi = p.pi();
        let shifted = |p: &mut Pool, k: (i64, i64)| {
            let turn = p.scale(pi, &number::ratio(k.0, k.1));
            p.add2(turn, x)
        };
        let mut cases = Vec::new();
        for (k, f, expected) in [
            ((1, 2), Func::Cos, "-sin(x)"),
            ((1, 2), Func::Sin, "cos(x)"),
            ((1, 1), Func::Sin, "-sin(x)"),
            ((3, 2), Func::Cos, "sin(x)"),
            ((-1, 2), Func::Sin, "-cos(x)"),
            ((2, 1), Func::Cos, "cos(x)"),
            ((1, 1), Func::Tan, "tan(x)"),
        ] {
            let arg = shifted(&mut p, k);
            let v = p.func(f, arg);
            cases.push((printed(&p, v), expected));
        }
        for (got, expected) in cases {
            assert_eq!(got, expected);
        }
        // A quarter turn of tan is a cotangent: left as it is; so is a turn of π/4.
        let arg = shifted(&mut p, (1, 2));
        let v = p.func(Func::Tan, arg);
        assert!(printed(&p, v).starts_with("tan("), "{}", printed(&p, v));
        let arg = shifted(&mut p, (1, 4));
        let v = p.cos(arg);
        assert!(printed(&p, v).starts_with("cos("), "{}", printed(&p, v));
    }

    #[test]
    fn trig_of_inverse_trig_is_algebraic() {
        let mut p = Pool::new();
        let x = p.param("x");
        let x = p.sym(x);
        let mut got = Vec::new();
        for (outer, inner) in [
            (Func::Cos, Func::Asin),
            (Func::Sin, Func::Acos),
            (Func::Tan, Func::Asin),
            (Func::Tan, Func::Acos),
            (Func::Sin, Func::Atan),
            (Func::Cos, Func::Atan),
            (Func::Sin, Func::Asin),
        ] {
            let a = p.func(inner, x);
            let v = p.func(outer, a);
            got.push(printed(&p, v));
        }
        assert_eq!(
            got,
            [
                "sqrt(1 - x^2)",
                "sqrt(1 - x^2)",
                "x/sqrt(1 - x^2)",
                "sqrt(1 - x^2)/x",
                "x/sqrt(1 + x^2)",
                "1/sqrt(1 + x^2)",
                "x",
            ]
        );
        // sin²(acos x) is 1 − x², the square root squared away.
        let a = p.func(Func::Acos, x);
        let s = p.sin(a);
        let square = p.powi(s, 2);
        assert_eq!(printed(&p, square), "1 - x^2");
    }

    #[test]
    fn odd_and_even_functions_take_one_sign() {
        let mut p = Pool::new();
        let a = p.param("a");
        let a = p.sym(a);
        let b = p.param("b");
        let b = p.sym(b);
        let ab = p.sub(a, b);
        let ba = p.sub(b, a);
        let c1 = p.cos(ab);
        let c2 = p.cos(ba);
        assert_eq!(c1, c2);
        let s1 = p.sin(ab);
        let s2 = p.sin(ba);
        let s2n = p.neg(s2);
        assert_eq!(s1, s2n);
    }

    #[test]
    fn radicals_fold() {
        let mut p = Pool::new();
        let twelve = p.int(12);
        let r = p.sqrt(twelve);
        let three = p.int(3);
        let r3 = p.sqrt(three);
        let expected = p.scale(r3, &number::int(2));
        assert_eq!(r, expected);
        let inv = p.powq(three, &number::ratio(-1, 2));
        let expected = p.scale(r3, &number::ratio(1, 3));
        assert_eq!(inv, expected);
    }
}
