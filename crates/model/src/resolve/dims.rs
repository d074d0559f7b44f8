//! The dimension of each expression, worked out as the resolver resolves it, and the facts
//! about dimensions each statement states (see [`crate::units`], which solves them).

use cas::number::{One, Zero};
use cas::{ExprId, Rational};
use lang::{BinOp, Expr, ExprKind, Ident, Span, Unit};

use super::Resolver;
use crate::units::{self, Form, Shape, Unknown};
use crate::Value;

/// What is known of an expression's dimension before its place is known.
// These live only while one expression is resolved; boxing the scalar would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub(super) enum Dims {
    /// Made of numbers alone (`0`, `-1/2`, `sqrt(3)/2`, `2*pi`): it takes the dimension its
    /// place needs. `decided` is false where its value is a power to an exponent that is not a
    /// rational number, which is not tested for zero.
    Number {
        id: Unknown,
        value: ExprId,
        decided: bool,
    },
    Scalar(Form),
    Many(Vec<Form>),
    /// A matrix as written, entry by entry: in a product of two, each entry is a factor.
    Grid(Vec<Vec<Dims>>),
}

impl From<Shape> for Dims {
    fn from(s: Shape) -> Dims {
        match s {
            Shape::Scalar(f) => Dims::Scalar(f),
            Shape::Many(v) => Dims::Many(v),
        }
    }
}

/// The dimension of a name, beside its binding.
#[derive(Clone)]
pub(super) struct NameDims {
    /// The statement that declares it, by its place in the file.
    pub at: usize,
    /// `None` for a vector or matrix `let`, whose dimensions are in `entries`.
    pub form: Option<Form>,
    /// The dimensions of a vector or matrix `let`, entry by entry.
    pub entries: Option<Dims>,
}

#[derive(Clone)]
/// The dimensions of a body, beside it in the resolver's table.
pub(super) struct BodyDims {
    pub at: usize,
    pub mass: Form,
    pub position: Vec<Form>,
    pub angle: Option<Form>,
    /// Whether it turns in space (its `omega` is a vector).
    pub spatial: bool,
}

fn two() -> Rational {
    Rational::from_integer(2.into())
}

/// A numeric exponent as written: `2`, `-1`, `1/2`, `(3/2)`.
fn exponent_value(e: &Expr) -> Option<Rational> {
    match &e.kind {
        ExprKind::Number(t) => cas::number::parse_decimal(t),
        ExprKind::Neg(inner) => exponent_value(inner).map(|q| -q),
        ExprKind::Binary { op: BinOp::Div, lhs, rhs } => {
            let (a, b) = (exponent_value(lhs)?, exponent_value(rhs)?);
            (!b.is_zero()).then(|| a / b)
        }
        _ => None,
    }
}

impl Resolver<'_> {
    pub(super) fn number_dims(&mut self, value: ExprId, decided: bool) -> Dims {
        Dims::Number { id: self.scope.units.reserve(), value, decided }
    }

    /// The dimension of a value wherever it stands. A number is dimensionless there, except
    /// zero: 0·x is zero whatever x is, so a zero has every dimension (`[m, 0; 0, m]*[x''; y'']`).
    pub(super) fn shape(&mut self, d: Dims) -> Shape {
        match d {
            Dims::Number { id, value, decided } => {
                Shape::Scalar(if decided && self.model.pool.is_identically_zero(value) {
                    self.scope.units.named(id, "zero")
                } else {
                    Form::default()
                })
            }
            Dims::Scalar(f) => Shape::Scalar(f),
            Dims::Many(v) => Shape::Many(v),
            Dims::Grid(rows) => {
                Shape::Many(rows.into_iter().flatten().map(|d| self.operand_form(d)).collect())
            }
        }
    }

    /// A value that stands alone: a side of an equation, a term of a sum, an initial value, a
    /// vector component. A number there takes whatever dimension its place needs, so scenes
    /// written without units still pass; a number that multiplies something (`k/10`, `2*x`) is
    /// dimensionless, so coefficients are checked, unless it is zero (see [`Self::shape`]).
    pub(super) fn operand(&mut self, d: Dims) -> Shape {
        match d {
            Dims::Number { id, .. } => Shape::Scalar(self.scope.units.named(id, "a number")),
            other => self.shape(other),
        }
    }

    pub(super) fn form(&mut self, d: Dims) -> Form {
        self.shape(d).first()
    }

    pub(super) fn operand_form(&mut self, d: Dims) -> Form {
        self.operand(d).first()
    }

    /// Whether a declaration at statement `at` comes after the statement being resolved: only
    /// `show` and `expect` lines see such names, and their dimensions are not known there yet.
    fn ahead(&self, at: usize) -> bool {
        self.in_outputs && at > self.stmt
    }

    /// One unknown for a name wherever its dimension is not known: before its declaration,
    /// or for a vector or matrix `let`.
    fn loose(&mut self, raw: &str, name: &str) -> Form {
        if let Some(f) = self.scope.loose.get(name) {
            return f.clone();
        }
        let f = self.scope.units.fresh(raw);
        self.scope.loose.insert(name.to_string(), f.clone());
        f
    }

    /// The dimension of a declared name with `primes` rates.
    pub(super) fn name_dims(&mut self, raw: &str, name: &str, primes: u8) -> Dims {
        let declared = self.scope.name_dims.get(name).filter(|d| !self.ahead(d.at));
        if let Some(entries) = declared.and_then(|d| d.entries.clone()) {
            return self.rate_dims(entries, primes);
        }
        let form = match declared.and_then(|d| d.form.clone()) {
            Some(f) => f,
            None if matches!(name, "KE" | "PE") => self.scope.units.energy(),
            None => self.loose(raw, name),
        };
        Dims::Scalar(form.rate(primes))
    }

    /// The dimension of the `primes`-th rate of a value of dimension `d`.
    pub(super) fn rate_dims(&mut self, d: Dims, primes: u8) -> Dims {
        if primes == 0 {
            return d;
        }
        match d {
            Dims::Number { .. } => Dims::Scalar(Form::default().rate(primes)),
            Dims::Scalar(f) => Dims::Scalar(f.rate(primes)),
            Dims::Many(v) => Dims::Many(v.iter().map(|f| f.rate(primes)).collect()),
            Dims::Grid(g) => Dims::Grid(
                g.into_iter()
                    .map(|row| {
                        row.into_iter().map(|d| Dims::Scalar(self.form(d).rate(primes))).collect()
                    })
                    .collect(),
            ),
        }
    }

    /// The dimension of `object.field`, where `body` is the index of the body it names.
    pub(super) fn member_dims(
        &mut self,
        object: &Ident,
        field: &Ident,
        body: Option<usize>,
    ) -> Dims {
        let body = body.filter(|i| !self.ahead(self.scope.body_dims[*i].at));
        let Some(b) = body.map(|i| &self.scope.body_dims[i]) else {
            // A reaction, or a body not declared yet: its dimension is its own unknown.
            return Dims::Scalar(
                self.scope.units.fresh(&format!("{}.{}", object.name, field.name)),
            );
        };
        match field.name.as_str() {
            "position" => Dims::Many(b.position.clone()),
            "velocity" => Dims::Many(b.position.iter().map(|x| x.rate(1)).collect()),
            "mass" => Dims::Scalar(b.mass.clone()),
            "angle" => Dims::Scalar(b.angle.clone().unwrap_or_default()),
            "omega" | "omega_body" if b.spatial => Dims::Many(vec![Form::default().rate(1); 3]),
            "axes" => Dims::Grid(vec![vec![Dims::Scalar(Form::default()); 3]; 3]),
            "omega" => Dims::Scalar(b.angle.clone().unwrap_or_default().rate(1)),
            "x" | "y" | "z" => {
                let i = match field.name.as_str() {
                    "x" => 0,
                    "y" => 1,
                    _ => 2,
                };
                Dims::Scalar(b.position.get(i).cloned().unwrap_or_default())
            }
            _ => Dims::Scalar(self.scope.units.fresh(&field.name)),
        }
    }

    /// The dimension of a call of `name` on `args`, whose value is `value`.
    pub(super) fn call_dims(
        &mut self,
        name: &str,
        args: Vec<Dims>,
        written: &[Expr],
        value: ExprId,
    ) -> Dims {
        if args.iter().all(|d| matches!(d, Dims::Number { .. })) {
            let decided = args.iter().all(|d| matches!(d, Dims::Number { decided: true, .. }));
            return self.number_dims(value, decided);
        }
        if matches!(name, "min" | "max") && args.len() == 2 {
            // Like the terms of a sum: a number alone takes the other side's dimension.
            let forms: Vec<Form> = args.into_iter().map(|d| self.operand_form(d)).collect();
            let what = format!("between the arguments of {name}");
            self.scope.units.same(&forms[0], &forms[1], written[0].span, written[1].span, &what);
            return Dims::Scalar(forms[0].clone());
        }
        let forms: Vec<Form> = args.into_iter().map(|d| self.form(d)).collect();
        match name {
            "sqrt" => Dims::Scalar(
                forms
                    .first()
                    .cloned()
                    .unwrap_or_default()
                    .times(&Rational::new(1.into(), 2.into())),
            ),
            // |u| keeps the dimension; the sign has none.
            "abs" => Dims::Scalar(forms.first().cloned().unwrap_or_default()),
            "sign" => Dims::Scalar(Form::default()),
            "atan2" if forms.len() == 2 => {
                self.scope.units.same(
                    &forms[0],
                    &forms[1],
                    written[0].span,
                    written[1].span,
                    "between the arguments of atan2",
                );
                Dims::Scalar(Form::default())
            }
            _ => {
                for (f, a) in forms.iter().zip(written) {
                    self.scope.units.dimensionless(f, a.span, &format!("the argument of {name}"));
                }
                Dims::Scalar(Form::default())
            }
        }
    }

    /// The dimension of `l op r`, whose value is `value`.
    pub(super) fn binary_dims(
        &mut self,
        op: BinOp,
        (l, r): (Dims, Dims),
        le: &Expr,
        re: &Expr,
        value: &Value,
    ) -> Dims {
        if let (Dims::Number { decided: a, .. }, Dims::Number { decided: b, value: rv, .. }) =
            (&l, &r)
        {
            let decided = *a && *b && (op != BinOp::Pow || self.model.pool.as_num(*rv).is_some());
            if let Value::Scalar(v) = value {
                return self.number_dims(*v, decided);
            }
        }
        // R*v: a matrix times a vector, each entry of the result a sum like those below.
        let (l, r) = match (op, l, r) {
            (BinOp::Mul, Dims::Grid(a), Dims::Many(v))
                if a.first().map_or(0, Vec::len) == v.len() =>
            {
                (Dims::Grid(a), Dims::Grid(v.into_iter().map(|f| vec![Dims::Scalar(f)]).collect()))
            }
            (_, l, r) => (l, r),
        };
        let fits =
            |a: &Vec<Vec<Dims>>, b: &Vec<Vec<Dims>>| a.first().map_or(0, Vec::len) == b.len();
        match (op, l, r) {
            // The entries of `[a, b; c, d] * [x; y]` are sums a·x + b·y.
            (BinOp::Mul, Dims::Grid(a), Dims::Grid(b)) if fits(&a, &b) => {
                let mut grid = |g: Vec<Vec<Dims>>| -> Vec<Vec<Form>> {
                    g.into_iter()
                        .map(|row| row.into_iter().map(|d| self.form(d)).collect())
                        .collect()
                };
                let (a, b) = (grid(a), grid(b));
                let mut out = Vec::new();
                for row in &a {
                    for j in 0..b.first().map_or(0, |r| r.len()) {
                        let terms: Vec<Form> = row
                            .iter()
                            .zip(&b)
                            .map(|(x, brow)| x.plus(&brow[j], &Rational::one()))
                            .collect();
                        for t in terms.iter().skip(1) {
                            self.scope.units.same(
                                &terms[0],
                                t,
                                le.span,
                                re.span,
                                "between the terms of this matrix product",
                            );
                        }
                        out.push(terms.into_iter().next().unwrap_or_default());
                    }
                }
                // A column stays a list of components; a product of matrices keeps its rows,
                // so that it can multiply again (`rotz(phi)*rotx(theta)*v`).
                let columns = b.first().map_or(0, |r| r.len());
                if columns > 1 {
                    let rows = out
                        .chunks(columns)
                        .map(|row| row.iter().cloned().map(Dims::Scalar).collect())
                        .collect();
                    return Dims::Grid(rows);
                }
                Dims::Many(out)
            }
            (BinOp::Add | BinOp::Sub, l, r) => {
                let (l, r) = (self.operand(l), self.operand(r));
                self.scope.units.sum(l, r, le.span, re.span).into()
            }
            (BinOp::Mul | BinOp::Div, l, r) => {
                let k = if op == BinOp::Mul { Rational::one() } else { -Rational::one() };
                match (self.shape(l), self.shape(r)) {
                    (Shape::Scalar(a), Shape::Scalar(b)) => Dims::Scalar(a.plus(&b, &k)),
                    (Shape::Scalar(a), Shape::Many(v)) => {
                        Dims::Many(v.iter().map(|b| a.plus(b, &k)).collect())
                    }
                    (Shape::Many(v), Shape::Scalar(b)) => {
                        Dims::Many(v.iter().map(|a| a.plus(&b, &k)).collect())
                    }
                    (Shape::Many(v), Shape::Many(_)) => Dims::Many(v),
                }
            }
            (BinOp::Pow, l, r) => {
                let base = match self.shape(l) {
                    Shape::Scalar(f) => f,
                    many => return many.into(),
                };
                match exponent_value(re) {
                    Some(q) => Dims::Scalar(base.times(&q)),
                    None => {
                        let exponent = match self.shape(r) {
                            Shape::Scalar(f) => f,
                            Shape::Many(_) => Form::default(),
                        };
                        let what = "a base raised to a symbolic power";
                        self.scope.units.dimensionless(&base, le.span, what);
                        self.scope.units.dimensionless(&exponent, re.span, "an exponent");
                        Dims::Scalar(Form::default())
                    }
                }
            }
        }
    }

    /// The dimension of a declared value with its unit. A number with a unit has the unit's
    /// dimension (even `0 m`); one without takes its place's.
    pub(super) fn with_unit(&mut self, value: Option<Dims>, unit: Option<&Unit>) -> Form {
        let f = match value {
            Some(Dims::Number { .. }) if unit.is_some() => Form::default(),
            Some(d) if unit.is_some() => self.form(d),
            Some(d) => self.operand_form(d),
            None => self.scope.units.fresh("a value"),
        };
        match unit.map(units::parse_unit) {
            Some(Ok((d, _))) => f.plus(&Form::known(d), &Rational::one()),
            _ => f,
        }
    }

    /// ½ m v² and ½ I ω² are energies.
    pub(super) fn body_energy(
        &mut self,
        mass: Option<Form>,
        position: &[(Form, Span)],
        inertia: Option<(Form, Span)>,
        angle: Option<&Form>,
    ) {
        let m = mass.unwrap_or_default();
        for (x, span) in position {
            self.scope.units.energy_term(&m.plus(&x.rate(1), &two()), *span);
        }
        if let (Some((i, span)), Some(a)) = (inertia, angle) {
            self.scope.units.energy_term(&i.plus(&a.rate(1), &two()), span);
        }
    }

    /// The potential of gravity on each body so far is an energy: m·g·x.
    pub(super) fn gravity_energy(&mut self, g: &Form, span: Span) {
        let terms: Vec<Form> = self
            .scope
            .body_dims
            .iter()
            .flat_map(|b| {
                b.position
                    .iter()
                    .map(|x| b.mass.plus(g, &Rational::one()).plus(x, &Rational::one()))
            })
            .collect();
        for e in terms {
            self.scope.units.energy_term(&e, span);
        }
    }

    /// A spring's potential k/2·(|AB| − l0)² is an energy, and l0 is a length like |AB|.
    pub(super) fn spring_energy(
        &mut self,
        len: &Form,
        k: (Dims, Span),
        rest: Option<(Dims, Span)>,
        ends: Span,
    ) {
        let stiffness = self.form(k.0);
        if let Some((rest, span)) = rest {
            let l0 = self.operand_form(rest);
            let what = "between a rest length and the distance it rests at";
            self.scope.units.same(&l0, len, span, ends, what);
        }
        self.scope.units.energy_term(&stiffness.plus(len, &two()), k.1);
    }

    /// A damper's c/2·(d|AB|/dt)² is a power: c·len²/T² = energy/T.
    pub(super) fn damper_energy(&mut self, len: &Form, c: Dims, span: Span) {
        let c = self.form(c);
        let e = c.plus(len, &two()).plus(&units::time(), &-Rational::one());
        self.scope.units.energy_term(&e, span);
    }

    /// The work of a force along its body's position, or of a torque through its angle, is an
    /// energy.
    pub(super) fn load_energy(
        &mut self,
        body: usize,
        value: Dims,
        span: Span,
        torque: bool,
        point: Option<Vec<Form>>,
    ) {
        if torque && self.scope.body_dims[body].spatial {
            // τ·ω dt: the rotation's entries are dimensionless, so each component is an energy.
            for f in self.shape(value).forms() {
                self.scope.units.energy_term(&f, span);
            }
            return;
        }
        if torque {
            let f = self.form(value);
            if let Some(a) = self.scope.body_dims[body].angle.clone() {
                self.scope.units.energy_term(&f.plus(&a, &Rational::one()), span);
            }
            return;
        }
        let forms = self.shape(value).forms();
        let position = point.unwrap_or_else(|| self.scope.body_dims[body].position.clone());
        for (f, x) in forms.iter().zip(position) {
            self.scope.units.energy_term(&f.plus(&x, &Rational::one()), span);
        }
    }

    /// The coordinates of both ends of a spring or damper share one dimension, that of their
    /// distance, which is returned.
    pub(super) fn separation_dims(&mut self, ends: Vec<Form>, a: Span, b: Span) -> Form {
        let Some(first) = ends.first().cloned() else { return Form::default() };
        for f in &ends[1..] {
            self.scope.units.same(&first, f, a, b, "between the coordinates of a spring's ends");
        }
        first
    }
}
