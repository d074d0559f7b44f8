//! The node types of the arena: expression and symbol ids, functions, nodes (with the
//! equality and hashing interning relies on) and symbols.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use crate::number::Rational;

/// An expression in a [`Pool`](super::Pool). Equal ids are equal expressions, and the converse
/// holds for the canonical forms the constructors produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(pub(super) u32);

impl ExprId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A symbol in a [`Pool`](super::Pool): a parameter, time, or a coordinate or one of its time
/// derivatives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SymId(pub(super) u32);

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

    pub(super) fn is_odd(self) -> bool {
        matches!(
            self,
            Func::Sin | Func::Tan | Func::Asin | Func::Atan | Func::Sinh | Func::Tanh | Func::Sign
        )
    }

    pub(super) fn is_even(self) -> bool {
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
    Add(Rational, Arc<[(ExprId, Rational)]>),
    /// `coefficient · Π base^exponent`, bases sorted by id; no base is a product raised to an
    /// integer power or a rational raised to an integer power.
    Mul(Rational, Arc<[(ExprId, Rational)]>),
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
    pub(super) rate: Option<SymId>,
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
