//! The expression arena: interned nodes, symbols, and the simplifying constructors.
//!
//! Every expression lives in a [`Pool`] and is named by a small [`ExprId`]. Nodes are
//! hash-consed, so two structurally equal expressions are the same id, and every constructor
//! returns the canonical form: sums and products flattened, like terms and like powers
//! collected, numbers folded, exact values of functions at special points taken.

use std::collections::HashMap;
use std::sync::Arc;

use hashbrown::HashTable;
use rustc_hash::{FxBuildHasher, FxHashMap};
use std::hash::BuildHasher;

use num_traits::{One, Zero};

use crate::number::{self, Rational};

mod arith;
mod collect;
mod functions;
mod node;
mod query;

pub use collect::Collected;
pub use node::{ExprId, Func, Node, SymId, Symbol, SymbolKind};

/// The numeric side of the zero test, handed in by a crate above this one ([`Pool::set_zero_test`]):
/// this crate evaluates no floats, and the one evaluator of expressions lives in `numeric`
/// (`numeric::GenericPoints`), which answers these questions at fixed generic points.
/// `Send + Sync` as the pool is: a loaded scene may move to another thread or be read from
/// several (the Python package's objects are used from any thread).
pub trait ZeroTest: Send + Sync {
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

    /// The sign (−1 or 1) of `e`, an expression without free symbols, where its value is
    /// clearly away from zero relative to its terms; `None` otherwise.
    fn sign_of_constant(&self, _pool: &Pool, _e: ExprId) -> Option<i8> {
        None
    }
}

/// The arena that owns every expression and symbol of one derivation.
#[derive(Clone)]
pub struct Pool {
    nodes: Vec<Node>,
    /// Each node's id under its hash (Fx rather than SipHash: the keys are our own ids, and
    /// interning is the hot path). The node itself is only in `nodes`: a map keyed by the
    /// node held a second copy of each and hashed every node again each time it grew, a
    /// tenth of a 64-link chain's load, and its copies were another part of the drop.
    interned: HashTable<(u64, ExprId)>,
    symbols: Vec<Symbol>,
    symbol_ids: HashMap<String, SymId>,
    pub(crate) diff_memo: FxHashMap<(ExprId, SymId), ExprId>,
    pub(crate) time_memo: FxHashMap<ExprId, ExprId>,
    pub(crate) expand_memo: FxHashMap<ExprId, ExprId>,
    pub(crate) simplify_memo: FxHashMap<ExprId, ExprId>,
    // `Arc`, not `Rc`, here and in the sum and product nodes: a pool is `Send + Sync`.
    free_memo: Vec<Option<Arc<[SymId]>>>,
    zero: ExprId,
    one: ExprId,
    /// The numbers of the zero test, if a crate above handed them in.
    zero_test: Option<Arc<dyn ZeroTest>>,
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
            interned: HashTable::new(),
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
        self.zero_test = Some(Arc::from(test));
    }

    /// The sign (−1 or 1) of `e`: exact for a rational, else from the zero test's numbers
    /// ([`ZeroTest::sign_of_constant`]) for an expression without free symbols that is
    /// clearly not zero; `None` where neither decides (a symbol left, or no zero test).
    pub fn sign_of_constant(&mut self, e: ExprId) -> Option<i8> {
        if let Some(q) = self.as_num(e) {
            use num_traits::Signed;
            return (!q.is_zero()).then_some(if q.is_negative() { -1 } else { 1 });
        }
        if !self.free_symbols(e).is_empty() {
            return None;
        }
        self.zero_test()?.sign_of_constant(self, e)
    }

    /// The numbers of the zero test, if handed in ([`Pool::set_zero_test`]).
    pub(crate) fn zero_test(&self) -> Option<&dyn ZeroTest> {
        self.zero_test.as_deref()
    }

    fn intern(&mut self, node: Node) -> ExprId {
        // One lookup, hashing the node once, whether it is new or not.
        let hash = FxBuildHasher.hash_one(&node);
        let nodes = &self.nodes;
        let same = |&(h, id): &(u64, ExprId)| h == hash && nodes[id.index()] == node;
        match self.interned.entry(hash, same, |&(h, _)| h) {
            hashbrown::hash_table::Entry::Occupied(known) => known.get().1,
            hashbrown::hash_table::Entry::Vacant(slot) => {
                let id =
                    ExprId(u32::try_from(self.nodes.len()).expect("more than 2^32 expressions"));
                slot.insert((hash, id));
                self.nodes.push(node);
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

    /// A sum collected from other sums' collections, or in one pass, is the node `add` gives,
    /// and collecting makes no node; a product with a coefficient other than 1 is not
    /// collected (`add` would intern its rest).
    #[test]
    fn collected_sums_are_the_sums_add_gives() {
        let mut p = Pool::new();
        let [x, y, z] = ["x", "y", "z"].map(|n| {
            let s = p.param(n);
            p.sym(s)
        });
        let sx = p.sin(x);
        let xy = p.mul2(x, y);
        let half = p.num(number::ratio(1, 2));
        let a = p.add(&[x, sx, half]);
        let neg = p.neg(sx);
        let b = p.add(&[a, xy, neg]);
        let c = p.add(&[b, z]);
        let list = [c, b, a, z, half];
        let before = p.nodes.len();
        let suffix = p.collected_all(&list[1..]).expect("collects");
        let whole = p.collected(list[0]).expect("collects").plus(&suffix);
        assert_eq!(p.collected_all(&list), Some(whole.clone()));
        assert_eq!(p.nodes.len(), before, "collecting made a node");
        let expected = p.add(&list);
        assert_eq!(p.add_collected(&whole), expected);
        let minus_x = p.scale(x, &number::int(-1));
        assert!(p.collected(minus_x).is_none());
        // Terms that cancel leave the sum: −sin x in b against sin x.
        let opposite = p.collected_all(&[b, sx]).expect("collects");
        let with_x = p.collected(x).expect("collects").plus(&opposite);
        let expected = p.add(&[x, b, sx]);
        assert_eq!(p.add_collected(&with_x), expected);
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
