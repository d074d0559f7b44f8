//! Differentiation: partial derivatives by a symbol (memoised per node and symbol) and the
//! total time derivative, which treats every coordinate as a function of time.

use num_traits::{One, Zero};

use crate::number::{self, Rational};
use crate::pool::{ExprId, Func, Node, Pool, SymId, SymbolKind};

impl Pool {
    /// ∂e/∂s. Memoised: each (node, symbol) pair is differentiated once per pool.
    pub fn diff(&mut self, e: ExprId, s: SymId) -> ExprId {
        if !self.depends_on(e, s) {
            return self.zero();
        }
        if let Some(&d) = self.diff_memo.get(&(e, s)) {
            return d;
        }
        let d = self.diff_uncached(e, s);
        self.diff_memo.insert((e, s), d);
        d
    }

    fn diff_uncached(&mut self, e: ExprId, s: SymId) -> ExprId {
        match self.node(e).clone() {
            Node::Num(_) | Node::Pi => self.zero(),
            Node::Sym(x) => {
                if x == s {
                    self.one()
                } else {
                    self.zero()
                }
            }
            Node::Add(_, terms) => {
                // Only the terms that depend on s: along a chain, most do not.
                let mut parts = Vec::new();
                for (t, k) in terms.iter() {
                    let dt = self.diff(*t, s);
                    if !self.is_zero(dt) {
                        parts.push((dt, k.clone()));
                    }
                }
                self.sum_of(Rational::zero(), parts)
            }
            Node::Mul(c, factors) => {
                // Product rule, one term per factor that depends on s:
                // ∂(c Π b_j^e_j) = Σ_i c e_i b_i^(e_i − 1) ∂b_i Π_{j≠i} b_j^e_j.
                let mut parts = Vec::new();
                for (i, (b, x)) in factors.iter().enumerate() {
                    let db = self.diff(*b, s);
                    if self.is_zero(db) {
                        continue;
                    }
                    let mut fs = factors.to_vec();
                    fs[i].1 = x - Rational::one();
                    let rest = self.product(&(&c * x), &fs);
                    parts.push(self.mul2(rest, db));
                }
                self.add(&parts)
            }
            Node::Pow(b, x) => {
                // d(b^x) = b^x (x' ln b + x b'/b)
                let db = self.diff(b, s);
                let dx = self.diff(x, s);
                let ln_b = self.func(Func::Ln, b);
                let t1 = self.mul2(dx, ln_b);
                let t2 = {
                    let q = self.div(db, b);
                    self.mul2(x, q)
                };
                let inner = self.add2(t1, t2);
                self.mul2(e, inner)
            }
            Node::Func(f, u) => {
                let du = self.diff(u, s);
                let outer = self.func_derivative(f, u);
                self.mul2(outer, du)
            }
            Node::Atan2(y, x) => {
                // d atan2(y, x) = (x dy − y dx)/(x² + y²)
                let dy = self.diff(y, s);
                let dx = self.diff(x, s);
                let a = self.mul2(x, dy);
                let b = self.mul2(y, dx);
                let num = self.sub(a, b);
                let x2 = self.powi(x, 2);
                let y2 = self.powi(y, 2);
                let den = self.add2(x2, y2);
                self.div(num, den)
            }
        }
    }

    /// f'(u) for an elementary function.
    fn func_derivative(&mut self, f: Func, u: ExprId) -> ExprId {
        let half = number::ratio(1, 2);
        match f {
            Func::Sin => self.cos(u),
            Func::Cos => {
                let s = self.sin(u);
                self.neg(s)
            }
            Func::Tan => {
                let c = self.cos(u);
                self.powi(c, -2)
            }
            Func::Asin | Func::Acos => {
                let u2 = self.powi(u, 2);
                let one = self.one();
                let d = self.sub(one, u2);
                let r = self.powq(d, &-half);
                if f == Func::Asin {
                    r
                } else {
                    self.neg(r)
                }
            }
            Func::Atan => {
                let u2 = self.powi(u, 2);
                let one = self.one();
                let d = self.add2(one, u2);
                self.powi(d, -1)
            }
            Func::Sinh => self.func(Func::Cosh, u),
            Func::Cosh => self.func(Func::Sinh, u),
            Func::Tanh => {
                let c = self.func(Func::Cosh, u);
                self.powi(c, -2)
            }
            Func::Exp => self.func(Func::Exp, u),
            Func::Ln => self.powi(u, -1),
            // Almost everywhere: at u = 0 neither has a derivative (see `Func::is_smooth`).
            Func::Abs => self.func(Func::Sign, u),
            Func::Sign => self.zero(),
        }
    }

    /// d/dt e, where every coordinate q depends on time through q → q' → q'' and `t` itself
    /// appears explicitly: de/dt = ∂e/∂t + Σ ∂e/∂q q'. Memoised.
    pub fn time_derivative(&mut self, e: ExprId) -> ExprId {
        if let Some(&d) = self.time_memo.get(&e) {
            return d;
        }
        let mut parts = Vec::new();
        for &s in self.free_symbols(e).iter() {
            let rate = match self.symbol(s).kind {
                SymbolKind::Time => self.one(),
                SymbolKind::Coordinate { .. } => {
                    let r = self.rate(s).expect("coordinates have rates");
                    self.sym(r)
                }
                SymbolKind::Param => continue,
            };
            let partial = self.diff(e, s);
            parts.push(self.mul2(partial, rate));
        }
        let d = self.add(&parts);
        self.time_memo.insert(e, d);
        d
    }
}
