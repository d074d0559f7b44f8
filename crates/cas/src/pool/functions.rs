//! The constructors of function applications, with the exact values of functions at special
//! points.

use num_bigint::BigInt;
use num_traits::{One, Signed, Zero};

use super::{ExprId, Func, Node, Pool};
use crate::number::{self, Rational};

impl Pool {
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
}
