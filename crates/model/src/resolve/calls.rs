//! Function calls and binary operators on resolved values, with their dimensions.

use cas::number::Signed;
use cas::{Func, Rational};
use lang::{BinOp, Diagnostic, Expr, Ident, Span};

use super::dims::Dims;
use super::{closest, space, Resolver, MAX_EXPONENT};
use crate::Value;

impl Resolver<'_> {
    pub(super) fn call(
        &mut self,
        func: &Ident,
        args: &[Expr],
        span: Span,
    ) -> Option<(Value, Dims)> {
        let name = func.name.as_str();
        if space::is_space_function(name) {
            return self.space_call(name, args, span);
        }
        let arity = match name {
            "atan2" | "min" | "max" => 2,
            "sqrt" => 1,
            _ if Func::from_name(name).is_some() => 1,
            _ => {
                let mut known: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
                known.extend(["sqrt", "atan2", "min", "max"]);
                known.extend(space::SPACE_FUNCTIONS.iter().map(|(n, _)| *n));
                let mut d = Diagnostic::error(func.span, format!("unknown function `{name}`"))
                    .with_label("not a function lagrange knows");
                d = match closest(name, known.iter().copied()) {
                    Some(near) => d.with_hint(format!("did you mean `{near}`?")),
                    None => d.with_hint(format!("the functions are {}", known.join(", "))),
                };
                self.error(d);
                return None;
            }
        };
        if args.len() != arity {
            self.error(
                Diagnostic::error(
                    span,
                    format!("`{name}` takes {arity} argument{}", if arity == 1 { "" } else { "s" }),
                )
                .with_label(format!("given {}", args.len())),
            );
            return None;
        }
        let mut xs = Vec::new();
        for a in args {
            xs.push(self.scalar(a));
        }
        let (xs, arg_dims): (Vec<_>, Vec<_>) =
            xs.into_iter().collect::<Option<Vec<_>>>()?.into_iter().unzip();
        if let Some(d) = self.outside_domain(name, &xs, args, span) {
            self.error(d);
            return None;
        }
        let v = match name {
            "atan2" => self.model.pool.atan2(xs[0], xs[1]),
            "sqrt" => self.model.pool.sqrt(xs[0]),
            // (a + b ∓ |a − b|)/2: no node of their own, so everything that knows `abs`
            // (derivatives, numbers, printing, SymPy) knows them.
            "min" | "max" => {
                let sum = self.model.pool.add2(xs[0], xs[1]);
                let gap = self.model.pool.sub(xs[0], xs[1]);
                let mut gap = self.model.pool.func(Func::Abs, gap);
                if name == "min" {
                    gap = self.model.pool.neg(gap);
                }
                let twice = self.model.pool.add2(sum, gap);
                let half = self.model.pool.num(cas::Rational::new(1.into(), 2.into()));
                self.model.pool.mul2(half, twice)
            }
            _ => self.model.pool.func(Func::from_name(name).expect("checked above"), xs[0]),
        };
        let dims = self.call_dims(name, arg_dims, args, v);
        Some((Value::Scalar(v), dims))
    }

    pub(super) fn binary(
        &mut self,
        op: BinOp,
        l: Value,
        r: Value,
        le: &Expr,
        re: &Expr,
    ) -> Option<Value> {
        use Value::*;
        let span = le.span.join(re.span);
        let mismatch = |this: &mut Self, what: &str| {
            this.error(
                Diagnostic::error(
                    span,
                    format!("cannot {what} {} and {}", l.kind_name(), r.kind_name()),
                )
                .with_label("shapes do not fit")
                .with_related(le.span, l.kind_name())
                .with_related(re.span, r.kind_name()),
            );
            None
        };
        match op {
            BinOp::Add | BinOp::Sub => {
                let mut combine = |a: cas::ExprId, b: cas::ExprId| {
                    if op == BinOp::Add {
                        self.model.pool.add2(a, b)
                    } else {
                        self.model.pool.sub(a, b)
                    }
                };
                match (&l, &r) {
                    (Scalar(a), Scalar(b)) => Some(Scalar(combine(*a, *b))),
                    (Vector(a), Vector(b)) if a.len() == b.len() => {
                        Some(Vector(a.iter().zip(b).map(|(x, y)| combine(*x, *y)).collect()))
                    }
                    (Matrix(a), Matrix(b)) if a.len() == b.len() && a[0].len() == b[0].len() => {
                        Some(Matrix(
                            a.iter()
                                .zip(b)
                                .map(|(ra, rb)| {
                                    ra.iter().zip(rb).map(|(x, y)| combine(*x, *y)).collect()
                                })
                                .collect(),
                        ))
                    }
                    _ => mismatch(self, if op == BinOp::Add { "add" } else { "subtract" }),
                }
            }
            BinOp::Mul => match (&l, &r) {
                (Scalar(a), Scalar(b)) => Some(Scalar(self.model.pool.mul2(*a, *b))),
                (Scalar(s), other) | (other, Scalar(s)) => {
                    let s = *s;
                    Some(other.map(|x| self.model.pool.mul2(s, x)))
                }
                (Matrix(a), Matrix(b)) if a[0].len() == b.len() => {
                    Some(Matrix(crate::kinematics::product(&mut self.model.pool, a, b)))
                }
                // R*v: a vector in the rotated axes carried into the fixed ones.
                (Matrix(a), Vector(v)) if a[0].len() == v.len() => {
                    Some(Vector(crate::kinematics::apply(&mut self.model.pool, a, v)))
                }
                _ => mismatch(self, "multiply"),
            },
            BinOp::Div => match (&l, &r) {
                (_, Scalar(b)) => {
                    if self.model.pool.is_zero(*b) {
                        self.error(
                            Diagnostic::error(re.span, "division by zero").with_label("this is 0"),
                        );
                        return None;
                    }
                    if let Some(d) = self.zero_divisor(*b, re) {
                        self.error(d);
                        return None;
                    }
                    let b = *b;
                    Some(l.map(|x| self.model.pool.div(x, b)))
                }
                _ => mismatch(self, "divide"),
            },
            BinOp::Pow => match (&l, &r) {
                (Scalar(a), Scalar(b)) => {
                    if let Some(q) = self.model.pool.as_num(*b) {
                        if q.numer().bits() > 32
                            || q.denom().bits() > 32
                            || q.abs() > Rational::from_integer(MAX_EXPONENT.into())
                        {
                            self.error(
                                Diagnostic::error(re.span, "this exponent is too large")
                                    .with_label(format!("exponents are limited to ±{MAX_EXPONENT}"))
                                    .with_hint(
                                        "a power this high is not physics; check the formula",
                                    ),
                            );
                            return None;
                        }
                        if self.model.pool.is_zero(*a) && q < &Rational::from_integer(0.into()) {
                            self.error(
                                Diagnostic::error(span, "division by zero")
                                    .with_label("0 to a negative power"),
                            );
                            return None;
                        }
                    }
                    if let Some(d) = self.bad_power(*a, *b, span) {
                        self.error(d);
                        return None;
                    }
                    Some(Scalar(self.model.pool.pow(*a, *b)))
                }
                _ => mismatch(self, "raise to a power"),
            },
        }
    }
}
