//! Exact expressions out of their pool: a tree of plain values (names in place of symbol ids)
//! that a front end rebuilds in its own algebra, with the scene-syntax text beside it.

use cas::{ExprId, Func, Node, Pool, Rational, Style, SymbolKind};

/// An expression as the scene syntax prints it (`text`) and as a tree (`term`).
#[derive(Clone, Debug, PartialEq)]
pub struct Exact {
    pub text: String,
    pub term: Term,
}

/// One node of an exact expression; sums and products carry their rational coefficients and
/// exponents as the pool does.
#[derive(Clone, Debug, PartialEq)]
pub enum Term {
    Number(Rational),
    /// A parameter or any other symbol constant in time.
    Constant(String),
    Time,
    /// A coordinate (`order` 0) or its `order`-th rate; `name` is the coordinate's.
    Coordinate {
        name: String,
        order: u8,
    },
    Pi,
    /// constant + Σ coefficient·term
    Add(Rational, Vec<(Term, Rational)>),
    /// coefficient · Π base^exponent
    Mul(Rational, Vec<(Term, Rational)>),
    Pow(Box<Term>, Box<Term>),
    Func(Func, Box<Term>),
    Atan2(Box<Term>, Box<Term>),
}

impl Exact {
    pub fn of(pool: &Pool, e: ExprId) -> Exact {
        Exact { text: pool.print(e, Style::Ascii), term: Term::of(pool, e) }
    }

    pub fn rows(pool: &Pool, rows: &[Vec<ExprId>]) -> Vec<Vec<Exact>> {
        rows.iter().map(|r| r.iter().map(|e| Exact::of(pool, *e)).collect()).collect()
    }
}

impl Term {
    fn of(pool: &Pool, e: ExprId) -> Term {
        let parts = |parts: &[(ExprId, Rational)]| -> Vec<(Term, Rational)> {
            parts.iter().map(|(e, k)| (Term::of(pool, *e), k.clone())).collect()
        };
        match pool.node(e) {
            Node::Num(q) => Term::Number(q.clone()),
            Node::Sym(s) => {
                let symbol = pool.symbol(*s);
                match symbol.kind {
                    SymbolKind::Param => Term::Constant(symbol.name.clone()),
                    SymbolKind::Time => Term::Time,
                    SymbolKind::Coordinate { base, order } => {
                        Term::Coordinate { name: pool.symbol(base).base_name().to_string(), order }
                    }
                }
            }
            Node::Pi => Term::Pi,
            Node::Add(c, terms) => Term::Add(c.clone(), parts(terms)),
            Node::Mul(c, factors) => Term::Mul(c.clone(), parts(factors)),
            Node::Pow(b, x) => {
                Term::Pow(Box::new(Term::of(pool, *b)), Box::new(Term::of(pool, *x)))
            }
            Node::Func(f, a) => Term::Func(*f, Box::new(Term::of(pool, *a))),
            Node::Atan2(y, x) => {
                Term::Atan2(Box::new(Term::of(pool, *y)), Box::new(Term::of(pool, *x)))
            }
        }
    }
}
