//! Units and dimensions: the SI units a scene may write after a value, and a check that every
//! sum, equation and energy term in the scene has one dimension.
//!
//! Dimensions are exponents of the SI base quantities. Names without a unit get an unknown
//! dimension that the check infers from how they are used (a linear system over the
//! exponents, solved as it grows), so a scene needs units on only a few parameters for
//! every term to be checked.

use std::collections::{BTreeMap, HashMap};

use cas::number::{One, Signed, Zero};
use cas::{ExprId, Func, Pool, Rational};
use lang::{BinOp, Diagnostic, Expr, ExprKind, Property, SceneFile, Span, StmtKind, Unit};

/// Past this a power of a number is not physics; [`Checker::number_value`] leaves it unvalued
/// rather than build it (the resolver refuses it anyway).
const MAX_EXPONENT: i64 = 64;

/// The SI base quantities tracked: mass, length, time, current, temperature.
const BASES: [&str; 5] = ["kg", "m", "s", "A", "K"];

/// A dimension: the exponent of each base quantity.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Dim([Rational; 5]);

impl Dim {
    fn base(i: usize) -> Dim {
        let mut d = Dim::default();
        d.0[i] = Rational::one();
        d
    }

    fn of(exps: [i64; 5]) -> Dim {
        Dim(exps.map(|e| Rational::from_integer(e.into())))
    }

    fn is_dimensionless(&self) -> bool {
        self.0.iter().all(|e| e.is_zero())
    }

    fn add(&self, other: &Dim) -> Dim {
        Dim(std::array::from_fn(|i| &self.0[i] + &other.0[i]))
    }

    fn scale(&self, k: &Rational) -> Dim {
        Dim(std::array::from_fn(|i| &self.0[i] * k))
    }

    /// `kg·m²/s²`, or `1` for a dimensionless quantity.
    pub fn text(&self) -> String {
        let power = |e: &Rational| -> String {
            if e.is_one() {
                String::new()
            } else if e.is_integer() {
                cas::print::superscript(&e.to_string())
            } else {
                format!("^({e})")
            }
        };
        let up: Vec<String> = (0..5)
            .filter(|&i| self.0[i].is_positive())
            .map(|i| format!("{}{}", BASES[i], power(&self.0[i])))
            .collect();
        let down: Vec<String> = (0..5)
            .filter(|&i| self.0[i].is_negative())
            .map(|i| format!("{}{}", BASES[i], power(&-self.0[i].clone())))
            .collect();
        match (up.is_empty(), down.is_empty()) {
            (true, true) => "1 (dimensionless)".to_string(),
            (false, true) => up.join("·"),
            (true, false) => format!("1/{}", down.join("·")),
            (false, false) => format!("{}/{}", up.join("·"), down.join("·")),
        }
    }
}

/// The factor that turns a value in a unit into SI: `rational · π^pi_power`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scale {
    pub rational: Rational,
    pub pi_power: i32,
}

impl Scale {
    pub fn is_one(&self) -> bool {
        self.rational.is_one() && self.pi_power == 0
    }
}

/// A named unit: its dimension and its size in SI.
fn unit(name: &str) -> Option<(Dim, Rational, i32)> {
    let r = |n: i64, d: i64| Rational::new(n.into(), d.into());
    let one = r(1, 1);
    Some(match name {
        "kg" => (Dim::of([1, 0, 0, 0, 0]), one, 0),
        "g" => (Dim::of([1, 0, 0, 0, 0]), r(1, 1000), 0),
        "m" => (Dim::of([0, 1, 0, 0, 0]), one, 0),
        "km" => (Dim::of([0, 1, 0, 0, 0]), r(1000, 1), 0),
        "cm" => (Dim::of([0, 1, 0, 0, 0]), r(1, 100), 0),
        "mm" => (Dim::of([0, 1, 0, 0, 0]), r(1, 1000), 0),
        "s" => (Dim::of([0, 0, 1, 0, 0]), one, 0),
        "ms" => (Dim::of([0, 0, 1, 0, 0]), r(1, 1000), 0),
        "min" => (Dim::of([0, 0, 1, 0, 0]), r(60, 1), 0),
        "h" => (Dim::of([0, 0, 1, 0, 0]), r(3600, 1), 0),
        "Hz" => (Dim::of([0, 0, -1, 0, 0]), one, 0),
        "N" => (Dim::of([1, 1, -2, 0, 0]), one, 0),
        "J" => (Dim::of([1, 2, -2, 0, 0]), one, 0),
        "W" => (Dim::of([1, 2, -3, 0, 0]), one, 0),
        "Pa" => (Dim::of([1, -1, -2, 0, 0]), one, 0),
        "A" => (Dim::of([0, 0, 0, 1, 0]), one, 0),
        "C" => (Dim::of([0, 0, 1, 1, 0]), one, 0),
        "V" => (Dim::of([1, 2, -3, -1, 0]), one, 0),
        "T" => (Dim::of([1, 0, -2, -1, 0]), one, 0),
        "K" => (Dim::of([0, 0, 0, 0, 1]), one, 0),
        "rad" => (Dim::default(), one, 0),
        "deg" => (Dim::default(), r(1, 180), 1),
        "rev" => (Dim::default(), r(2, 1), 1),
        "rpm" => (Dim::of([0, 0, -1, 0, 0]), r(1, 30), 1),
        _ => return None,
    })
}

/// The dimension and SI scale of a written unit, or an error naming the unknown part.
pub fn parse_unit(u: &Unit) -> Result<(Dim, Scale), Diagnostic> {
    let mut dim = Dim::default();
    let mut scale = Scale { rational: Rational::one(), pi_power: 0 };
    for (name, power) in &u.factors {
        let Some((d, r, p)) = unit(&name.name) else {
            let mut diag = Diagnostic::error(name.span, format!("unknown unit `{}`", name.name))
                .with_label("not a unit lagrange knows");
            let near = lang::UNIT_NAMES.iter().find(|n| n.eq_ignore_ascii_case(&name.name));
            diag = match near {
                Some(n) => diag.with_hint(format!("did you mean `{n}`?")),
                None => diag.with_hint(format!("the units are {}", lang::UNIT_NAMES.join(", "))),
            };
            return Err(diag);
        };
        let k = Rational::from_integer((*power).into());
        dim = dim.add(&d.scale(&k));
        scale.rational *= cas::number::pow_int(&r, k.numer()).unwrap_or_else(Rational::one);
        scale.pi_power += p * power;
    }
    Ok((dim, scale))
}

/// A dimension that may still depend on unknowns: `known + Σ coefficient · unknown`.
#[derive(Clone, Debug, Default)]
struct Form {
    known: Dim,
    unknowns: BTreeMap<usize, Rational>,
}

impl Form {
    fn known(d: Dim) -> Form {
        Form { known: d, unknowns: BTreeMap::new() }
    }

    fn unknown(i: usize) -> Form {
        Form { known: Dim::default(), unknowns: [(i, Rational::one())].into_iter().collect() }
    }

    fn plus(&self, other: &Form, k: &Rational) -> Form {
        let mut out = self.clone();
        out.known = out.known.add(&other.known.scale(k));
        for (u, c) in &other.unknowns {
            let slot = out.unknowns.entry(*u).or_insert_with(Rational::zero);
            *slot += c * k;
        }
        out.unknowns.retain(|_, c| !c.is_zero());
        out
    }

    fn times(&self, k: &Rational) -> Form {
        Form::default().plus(self, k)
    }
}

/// The dimensions of a scene's values: scalars, vectors, matrices.
// Shapes live only while one expression is checked; boxing the scalar would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Shape {
    Scalar(Form),
    Many(Vec<Form>),
}

impl Shape {
    fn forms(&self) -> Vec<Form> {
        match self {
            Shape::Scalar(f) => vec![f.clone()],
            Shape::Many(v) => v.clone(),
        }
    }
}

struct BodyDims {
    mass: Form,
    position: Vec<Form>,
    angle: Option<Form>,
}

/// Checks that every term of the scene has one dimension. Returns the mismatches found.
pub fn check(file: &SceneFile) -> Vec<Diagnostic> {
    let mut c = Checker::default();
    let energy = c.fresh("the energy");
    c.energy = Some(energy);
    let time = Form::known(Dim::base(2));
    c.names.insert("t".into(), time);
    c.names.insert("pi".into(), Form::default());
    for name in ["KE", "PE"] {
        c.names.insert(name.into(), c.energy_form());
    }
    for stmt in &file.stmts {
        c.statement(&stmt.kind);
    }
    c.errors
}

#[derive(Default)]
struct Checker {
    /// What each unknown stands for, for messages.
    unknown_names: Vec<String>,
    /// Solved unknowns, in terms of the others.
    solved: HashMap<usize, Form>,
    names: HashMap<String, Form>,
    bodies: HashMap<String, BodyDims>,
    energy: Option<usize>,
    /// The first energy term, to point at when another disagrees with it.
    energy_span: Option<Span>,
    errors: Vec<Diagnostic>,
    /// Exact values of expressions made of numbers alone, to tell which of them are zero.
    numbers: Pool,
}

impl Checker {
    fn fresh(&mut self, what: &str) -> usize {
        self.unknown_names.push(what.to_string());
        self.unknown_names.len() - 1
    }

    fn energy_form(&self) -> Form {
        Form::unknown(self.energy.unwrap_or(0))
    }

    /// Substitutes every solved unknown.
    fn reduce(&self, f: &Form) -> Form {
        let mut out = Form::known(f.known.clone());
        for (u, k) in &f.unknowns {
            match self.solved.get(u) {
                Some(s) => out = out.plus(s, k),
                None => out = out.plus(&Form::unknown(*u), k),
            }
        }
        out
    }

    fn describe(&self, f: &Form) -> String {
        let f = self.reduce(f);
        if f.unknowns.is_empty() {
            return f.known.text();
        }
        let mut parts: Vec<String> = Vec::new();
        if !f.known.is_dimensionless() {
            parts.push(f.known.text());
        }
        for (u, k) in &f.unknowns {
            let name = &self.unknown_names[*u];
            parts.push(if k.is_one() { format!("[{name}]") } else { format!("[{name}]^({k})") });
        }
        parts.join("·")
    }

    /// Records that `a` and `b` have one dimension; on a contradiction, reports both spans.
    /// Returns whether they can be one; a mismatch is reported once, and callers replace the
    /// mismatched value by a fresh unknown so that one mistake does not cascade.
    fn same(&mut self, a: &Form, b: &Form, span_a: Span, span_b: Span, what: &str) -> bool {
        let diff = self.reduce(&a.plus(b, &-Rational::one()));
        if let Some((&u, k)) = diff.unknowns.iter().next() {
            // Solve diff = 0 for u, and fold it into every earlier solution.
            let mut rest = diff.clone();
            rest.unknowns.remove(&u);
            let value = rest.times(&-(Rational::one() / k));
            for s in self.solved.values_mut() {
                if let Some(c) = s.unknowns.remove(&u) {
                    *s = s.plus(&value, &c);
                }
            }
            self.solved.insert(u, value);
            return true;
        }
        if diff.known.is_dimensionless() {
            return true;
        }
        let (da, db) = (self.describe(a), self.describe(b));
        let mut d = Diagnostic::error(
            span_a,
            format!("dimensions do not match {what}: {da} here, {db} there"),
        )
        .with_label(da.clone());
        if span_b != span_a {
            d = d.with_related(span_b, db);
        }
        self.errors.push(d.with_hint("every term added or equated must have one dimension; `--no-units` turns this check off"));
        false
    }

    fn dimensionless(&mut self, f: &Form, span: Span, what: &str) {
        let diff = self.reduce(f);
        if diff.unknowns.is_empty() && !diff.known.is_dimensionless() {
            let d = Diagnostic::error(span, format!("{what} must be dimensionless, but this is {}", diff.known.text()))
                .with_label(diff.known.text())
                .with_hint("divide by a quantity of the same dimension, e.g. sin(x/L); a name without a unit takes its dimension from its uses, its initial value and rate among them (write `phi' = 1 rad/s`, not `phi' = 1`)");
            self.errors.push(d);
        } else {
            self.same(f, &Form::default(), span, span, what);
        }
    }

    fn energy_term(&mut self, f: &Form, span: Span) {
        let e = self.energy_form();
        let first = *self.energy_span.get_or_insert(span);
        self.same(f, &e, span, first, "between energy terms");
    }

    fn with_unit(&mut self, value: Option<&Expr>, unit: Option<&Unit>) -> Form {
        let mut f = match value {
            // A number with a unit has the unit's dimension (even `0 m`); one without is a
            // wildcard.
            Some(v) if unit.is_some() && self.is_number(v) => Form::default(),
            Some(v) if unit.is_some() => self.scalar(v),
            Some(v) => self.operand_scalar(v),
            None => Form::unknown(self.fresh("a value")),
        };
        if let Some(u) = unit {
            match parse_unit(u) {
                Ok((d, _)) => f = f.plus(&Form::known(d), &Rational::one()),
                Err(e) => self.errors.push(e),
            }
        }
        f
    }

    fn statement(&mut self, stmt: &StmtKind) {
        match stmt {
            StmtKind::Param(decls) => {
                for p in decls {
                    let u = self.fresh(&p.name.name);
                    let f = Form::unknown(u);
                    if p.value.is_some() || p.unit.is_some() {
                        let v = self.with_unit(p.value.as_ref(), p.unit.as_ref());
                        let span = p.value.as_ref().map_or(p.name.span, |v| v.span);
                        self.same(&f, &v, p.name.span, span, "in this parameter");
                    }
                    self.names.insert(normalize(&p.name.name), f);
                }
            }
            StmtKind::Coord(decls) => {
                for c in decls {
                    let u = self.fresh(&c.name.name);
                    let f = Form::unknown(u);
                    if c.value.is_some() {
                        let v = self.with_unit(c.value.as_ref(), c.value_unit.as_ref());
                        let span = c.value.as_ref().map_or(c.name.span, |v| v.span);
                        self.same(&f, &v, c.name.span, span, "in this initial value");
                    }
                    if c.rate.is_some() {
                        let v = self.with_unit(c.rate.as_ref(), c.rate_unit.as_ref());
                        let rate = f.plus(&Form::known(Dim::base(2)), &-Rational::one());
                        let span = c.rate.as_ref().map_or(c.name.span, |v| v.span);
                        self.same(&rate, &v, span, span, "in this initial rate");
                    }
                    self.names.insert(normalize(&c.name.name), f);
                }
            }
            StmtKind::Let { name, value } => {
                let s = self.value(value);
                let f = match s {
                    Shape::Scalar(f) => f,
                    Shape::Many(_) => return,
                };
                self.names.insert(normalize(&name.name), f);
            }
            StmtKind::Particle { name, props } | StmtKind::Body { name, props } => {
                self.body(&name.name, props)
            }
            StmtKind::Constraint { lhs, rhs, .. } => {
                let (l, r) = (self.operand_scalar(lhs), self.operand_scalar(rhs));
                self.same(&l, &r, lhs.span, rhs.span, "between the sides of this constraint");
            }
            StmtKind::Gravity { strength, direction } => {
                let g = self.scalar(strength);
                if let Some(d) = direction {
                    for f in self.value(d).forms() {
                        self.dimensionless(&f, d.span, "a direction");
                    }
                }
                let bodies: Vec<(Form, Vec<Form>)> =
                    self.bodies.values().map(|b| (b.mass.clone(), b.position.clone())).collect();
                for (m, pos) in bodies {
                    for x in pos {
                        let e = m.plus(&g, &Rational::one()).plus(&x, &Rational::one());
                        self.energy_term(&e, strength.span);
                    }
                }
            }
            StmtKind::Potential(e) | StmtKind::Lagrangian(e) => {
                let f = self.scalar(e);
                self.energy_term(&f, e.span);
            }
            StmtKind::Dissipation(e) => {
                // A Rayleigh function is a power: energy per time.
                let f = self.scalar(e).plus(&Form::known(Dim::base(2)), &Rational::one());
                self.energy_term(&f, e.span);
            }
            StmtKind::Force { body, value, .. } => {
                let v = self.value(value).forms();
                let pos = self
                    .bodies
                    .get(&normalize(&body.name))
                    .map(|b| b.position.clone())
                    .unwrap_or_default();
                for (f, x) in v.iter().zip(pos) {
                    let work = f.plus(&x, &Rational::one());
                    self.energy_term(&work, value.span);
                }
            }
            StmtKind::Spring { a, b, stiffness, rest, .. } => {
                let len = self.separation(a, b);
                let k = self.scalar(stiffness);
                if let Some(r) = rest {
                    let l0 = self.operand_scalar(r);
                    self.same(
                        &l0,
                        &len,
                        r.span,
                        a.span.join(b.span),
                        "between a rest length and the distance it rests at",
                    );
                }
                let e = k.plus(&len, &Rational::from_integer(2.into()));
                self.energy_term(&e, stiffness.span);
            }
            StmtKind::Damper { a, b, coefficient, .. } => {
                let len = self.separation(a, b);
                let c = self.scalar(coefficient);
                // c (d|AB|/dt)² is a power: c·len²/T² = energy/T.
                let time = Form::known(Dim::base(2));
                let e =
                    c.plus(&len, &Rational::from_integer(2.into())).plus(&time, &-Rational::one());
                self.energy_term(&e, coefficient.span);
            }
            StmtKind::Torque { body, value, .. } => {
                let f = self.scalar(value);
                if let Some(a) =
                    self.bodies.get(&normalize(&body.name)).and_then(|b| b.angle.clone())
                {
                    let work = f.plus(&a, &Rational::one());
                    self.energy_term(&work, value.span);
                }
            }
            StmtKind::Show { items, .. } => {
                for item in items {
                    self.value(item);
                }
            }
            StmtKind::Expect { lhs, rhs, .. } => {
                let (l, r) = (self.operand(lhs).forms(), self.operand(rhs).forms());
                for (a, b) in l.iter().zip(r.iter()) {
                    self.same(a, b, lhs.span, rhs.span, "between the sides of this expectation");
                }
            }
            StmtKind::Scene { .. } | StmtKind::Simulate(_) => {}
        }
    }

    /// The dimension of the distance between two attachments (bodies or points), after
    /// checking that their coordinates share one.
    fn separation(&mut self, a: &Expr, b: &Expr) -> Form {
        let mut forms = Vec::new();
        for e in [a, b] {
            let body = match &e.kind {
                ExprKind::Name { name, primes: 0 } => {
                    self.bodies.get(&normalize(name)).map(|b| b.position.clone())
                }
                _ => None,
            };
            match body {
                Some(p) => forms.extend(p),
                None => forms.extend(self.value(e).forms()),
            }
        }
        let Some(first) = forms.first().cloned() else { return Form::default() };
        for f in &forms[1..] {
            self.same(&first, f, a.span, b.span, "between the coordinates of a spring's ends");
        }
        first
    }

    fn body(&mut self, name: &str, props: &[Property]) {
        let mut mass = None;
        let mut inertia = None;
        let mut position = Vec::new();
        let mut angle = None;
        for p in props {
            match p.key.name.as_str() {
                "mass" => mass = Some((self.scalar(&p.value), p.value.span)),
                "inertia" => inertia = Some((self.scalar(&p.value), p.value.span)),
                "angle" => angle = Some((self.scalar(&p.value), p.value.span)),
                "position" => {
                    position = self
                        .value(&p.value)
                        .forms()
                        .into_iter()
                        .map(|f| (f, p.value.span))
                        .collect()
                }
                _ => {}
            }
        }
        let time = Form::known(Dim::base(2));
        let two = Rational::from_integer(2.into());
        let m = mass.clone().map(|(f, _)| f).unwrap_or_default();
        // ½ m v² and ½ I ω² are energies.
        for (x, span) in &position {
            let v = x.plus(&time, &-Rational::one());
            let e = m.plus(&v, &two);
            self.energy_term(&e, *span);
        }
        if let (Some((i, span)), Some((a, _))) = (&inertia, &angle) {
            let w = a.plus(&time, &-Rational::one());
            let e = i.plus(&w, &two);
            self.energy_term(&e, *span);
        }
        self.bodies.insert(
            normalize(name),
            BodyDims {
                mass: m,
                position: position.into_iter().map(|(f, _)| f).collect(),
                angle: angle.map(|(f, _)| f),
            },
        );
    }

    /// A value that stands alone: a side of an equation, a term of a sum, an initial value, a
    /// vector component. A number there, or an expression of numbers alone (`x'' = 0`,
    /// `coord s = 1, s' = -1`, `theta' = sqrt(3)/2`, `x + 1/3`), takes whatever dimension its
    /// place needs, so scenes written without units still pass; a number that multiplies
    /// something (`k/10`, `2*x`) is dimensionless, so coefficients are checked, unless it is
    /// zero (see [`Checker::value`]).
    fn operand(&mut self, e: &Expr) -> Shape {
        if self.is_number(e) {
            return Shape::Scalar(Form::unknown(self.fresh("a number")));
        }
        self.value(e)
    }

    fn operand_scalar(&mut self, e: &Expr) -> Form {
        match self.operand(e) {
            Shape::Scalar(f) => f,
            Shape::Many(v) => v.into_iter().next().unwrap_or_default(),
        }
    }

    fn scalar(&mut self, e: &Expr) -> Form {
        match self.value(e) {
            Shape::Scalar(f) => f,
            Shape::Many(v) => v.into_iter().next().unwrap_or_default(),
        }
    }

    /// The dimension of `e` wherever it stands. Numbers are dimensionless here, except zero:
    /// 0·x is zero whatever x is, so a zero has every dimension (`[m, 0; 0, m]*[x''; y'']`).
    fn value(&mut self, e: &Expr) -> Shape {
        if self.is_number(e) {
            return Shape::Scalar(if self.is_zero_number(e) {
                Form::unknown(self.fresh("zero"))
            } else {
                Form::default()
            });
        }
        match &e.kind {
            ExprKind::Number(_) => Shape::Scalar(Form::default()),
            ExprKind::Name { name, primes } => {
                let key = normalize(name);
                let f = match self.names.get(&key) {
                    Some(f) => f.clone(),
                    None => {
                        let u = self.fresh(name);
                        let f = Form::unknown(u);
                        self.names.insert(key, f.clone());
                        f
                    }
                };
                let k = Rational::from_integer((*primes).into());
                Shape::Scalar(f.plus(&Form::known(Dim::base(2)), &-k))
            }
            ExprKind::Member { object, field } => {
                let time = Form::known(Dim::base(2));
                match self.bodies.get(&normalize(&object.name)) {
                    Some(b) => match field.name.as_str() {
                        "position" => Shape::Many(b.position.clone()),
                        "velocity" => Shape::Many(
                            b.position.iter().map(|x| x.plus(&time, &-Rational::one())).collect(),
                        ),
                        "mass" => Shape::Scalar(b.mass.clone()),
                        "angle" => Shape::Scalar(b.angle.clone().unwrap_or_default()),
                        "omega" => Shape::Scalar(
                            b.angle.clone().unwrap_or_default().plus(&time, &-Rational::one()),
                        ),
                        "x" | "y" | "z" => {
                            let i = match field.name.as_str() {
                                "x" => 0,
                                "y" => 1,
                                _ => 2,
                            };
                            Shape::Scalar(b.position.get(i).cloned().unwrap_or_default())
                        }
                        _ => Shape::Scalar(Form::unknown(self.fresh(&field.name))),
                    },
                    // A reaction: its dimension depends on the constraint's coordinates.
                    None => Shape::Scalar(Form::unknown(
                        self.fresh(&format!("{}.{}", object.name, field.name)),
                    )),
                }
            }
            ExprKind::Call { func, args } => {
                let forms: Vec<Form> = args.iter().map(|a| self.scalar(a)).collect();
                match func.name.as_str() {
                    "sqrt" => Shape::Scalar(
                        forms
                            .first()
                            .cloned()
                            .unwrap_or_default()
                            .times(&Rational::new(1.into(), 2.into())),
                    ),
                    "atan2" if forms.len() == 2 => {
                        self.same(
                            &forms[0],
                            &forms[1],
                            args[0].span,
                            args[1].span,
                            "between the arguments of atan2",
                        );
                        Shape::Scalar(Form::default())
                    }
                    name => {
                        for (f, a) in forms.iter().zip(args) {
                            self.dimensionless(f, a.span, &format!("the argument of {name}"));
                        }
                        Shape::Scalar(Form::default())
                    }
                }
            }
            ExprKind::Neg(inner) => self.value(inner),
            ExprKind::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs),
            ExprKind::Tuple(items) => {
                Shape::Many(items.iter().map(|i| self.operand_scalar(i)).collect())
            }
            ExprKind::Matrix(rows) => {
                let forms: Vec<Vec<Form>> = rows
                    .iter()
                    .map(|r| r.iter().map(|i| self.operand_scalar(i)).collect())
                    .collect();
                Shape::Many(forms.into_iter().flatten().collect())
            }
        }
    }

    /// Whether `e` is made of numbers alone: literals, `pi`, and functions and operations of
    /// them (`0`, `-1/2`, `sqrt(3)/2`, `2*pi`).
    fn is_number(&self, e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Number(_) => true,
            // `pi` stays the number unless the scene declared a name `pi` of its own.
            ExprKind::Name { name, primes: 0 } => {
                normalize(name) == "pi"
                    && self
                        .names
                        .get("pi")
                        .is_some_and(|f| f.unknowns.is_empty() && f.known.is_dimensionless())
            }
            ExprKind::Neg(inner) => self.is_number(inner),
            ExprKind::Binary { lhs, rhs, .. } => self.is_number(lhs) && self.is_number(rhs),
            ExprKind::Call { func, args } => {
                let known = matches!(func.name.as_str(), "sqrt" | "atan2")
                    || Func::from_name(&func.name).is_some();
                known && args.iter().all(|a| self.is_number(a))
            }
            ExprKind::Member { .. } | ExprKind::Name { .. } => false,
            ExprKind::Tuple(_) | ExprKind::Matrix(_) => false,
        }
    }

    /// Whether a number-only expression is exactly zero (`0`, `-0.0`, `0*pi`, `sin(pi)`,
    /// `1/2 - 0.5`). `false` when its value could not be decided.
    fn is_zero_number(&mut self, e: &Expr) -> bool {
        match self.number_value(e) {
            Some(v) => self.numbers.is_identically_zero(v),
            None => false,
        }
    }

    /// The exact value of a number-only expression, or `None` where building it would divide
    /// by zero or raise to a power too large to be meant.
    fn number_value(&mut self, e: &Expr) -> Option<ExprId> {
        let pool = &mut self.numbers;
        Some(match &e.kind {
            ExprKind::Number(text) => {
                let q = cas::number::parse_decimal(text)?;
                pool.num(q)
            }
            ExprKind::Name { name, .. } if normalize(name) == "pi" => pool.pi(),
            ExprKind::Neg(inner) => {
                let v = self.number_value(inner)?;
                self.numbers.neg(v)
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let (a, b) = (self.number_value(lhs)?, self.number_value(rhs)?);
                let pool = &mut self.numbers;
                match op {
                    BinOp::Add => pool.add2(a, b),
                    BinOp::Sub => pool.sub(a, b),
                    BinOp::Mul => pool.mul2(a, b),
                    BinOp::Div if pool.is_zero(b) => return None,
                    BinOp::Div => pool.div(a, b),
                    BinOp::Pow => {
                        let q = pool.as_num(b)?.clone();
                        let limit = Rational::from_integer(MAX_EXPONENT.into());
                        let huge =
                            q.numer().bits() > 32 || q.denom().bits() > 32 || q.abs() > limit;
                        if huge || (pool.is_zero(a) && q.is_negative()) {
                            return None;
                        }
                        pool.powq(a, &q)
                    }
                }
            }
            ExprKind::Call { func, args } => {
                let mut xs = Vec::new();
                for a in args {
                    xs.push(self.number_value(a)?);
                }
                let pool = &mut self.numbers;
                match (func.name.as_str(), xs.as_slice()) {
                    ("sqrt", [x]) => pool.sqrt(*x),
                    ("atan2", [y, x]) => pool.atan2(*y, *x),
                    (name, [x]) => pool.func(Func::from_name(name)?, *x),
                    _ => return None,
                }
            }
            ExprKind::Name { .. }
            | ExprKind::Member { .. }
            | ExprKind::Tuple(_)
            | ExprKind::Matrix(_) => return None,
        })
    }

    fn binary(&mut self, op: BinOp, lhs: &Expr, rhs: &Expr) -> Shape {
        // Matrix products: the entries of `[a, b; c, d] * [x; y]` are sums a·x + b·y.
        if let (BinOp::Mul, ExprKind::Matrix(a), ExprKind::Matrix(b)) = (op, &lhs.kind, &rhs.kind) {
            let a: Vec<Vec<Form>> =
                a.iter().map(|r| r.iter().map(|i| self.scalar(i)).collect()).collect();
            let b: Vec<Vec<Form>> =
                b.iter().map(|r| r.iter().map(|i| self.scalar(i)).collect()).collect();
            let mut out = Vec::new();
            for row in &a {
                for j in 0..b.first().map_or(0, |r| r.len()) {
                    let terms: Vec<Form> = row
                        .iter()
                        .zip(&b)
                        .map(|(x, brow)| x.plus(&brow[j], &Rational::one()))
                        .collect();
                    for t in terms.iter().skip(1) {
                        self.same(
                            &terms[0],
                            t,
                            lhs.span,
                            rhs.span,
                            "between the terms of this matrix product",
                        );
                    }
                    out.push(terms.into_iter().next().unwrap_or_default());
                }
            }
            return Shape::Many(out);
        }
        let (l, r) = match op {
            BinOp::Add | BinOp::Sub => (self.operand(lhs), self.operand(rhs)),
            _ => (self.value(lhs), self.value(rhs)),
        };
        match op {
            BinOp::Add | BinOp::Sub => {
                let (lf, rf) = (l.forms(), r.forms());
                let mut ok = true;
                for (a, b) in lf.iter().zip(rf.iter()) {
                    ok &= self.same(a, b, lhs.span, rhs.span, "between the terms of this sum");
                }
                if ok {
                    l
                } else {
                    Shape::Scalar(Form::unknown(self.fresh("a mismatched sum")))
                }
            }
            BinOp::Mul | BinOp::Div => {
                let k = if op == BinOp::Mul { Rational::one() } else { -Rational::one() };
                match (l, r) {
                    (Shape::Scalar(a), Shape::Scalar(b)) => Shape::Scalar(a.plus(&b, &k)),
                    (Shape::Scalar(a), Shape::Many(v)) => Shape::Many(
                        v.iter().map(|b| a.times(&Rational::one()).plus(b, &k)).collect(),
                    ),
                    (Shape::Many(v), Shape::Scalar(b)) => {
                        Shape::Many(v.iter().map(|a| a.plus(&b, &k)).collect())
                    }
                    (Shape::Many(v), Shape::Many(_)) => Shape::Many(v),
                }
            }
            BinOp::Pow => {
                let base = match l {
                    Shape::Scalar(f) => f,
                    Shape::Many(_) => return l,
                };
                match exponent_value(rhs) {
                    Some(q) => Shape::Scalar(base.times(&q)),
                    None => {
                        let ef = match r {
                            Shape::Scalar(f) => f,
                            Shape::Many(_) => Form::default(),
                        };
                        self.dimensionless(&base, lhs.span, "a base raised to a symbolic power");
                        self.dimensionless(&ef, rhs.span, "an exponent");
                        Shape::Scalar(Form::default())
                    }
                }
            }
        }
    }
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

fn normalize(name: &str) -> String {
    name.chars()
        .map(|c| cas::greek_word(c).map(str::to_string).unwrap_or_else(|| c.to_string()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(source: &str) -> Vec<String> {
        let file = lang::parse(source).expect("parses");
        check(&file).into_iter().map(|d| d.message).collect()
    }

    #[test]
    fn consistent_scenes_pass() {
        let rod = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord x = L/4, y, theta = pi/6\nbody rod { mass m; inertia m*L^2/12; position (x, y); angle theta }\nconstraint floor: y = L/2*cos(theta)\ngravity g\nexpect x'' = 0\nexpect at start: theta'' = 12/7*g/L\n";
        assert_eq!(errors(rod), Vec::<String>::new());
    }

    #[test]
    fn an_angle_where_a_length_is_needed_is_caught() {
        let bad = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord theta = pi/6\nparticle p { mass m; position (L*sin(theta), -L*cos(theta)) }\npotential m*g*theta\n";
        let e = errors(bad);
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].contains("kg·m/s²") && e[0].contains("kg·m²/s²"), "{e:?}");
    }

    #[test]
    fn function_arguments_must_be_dimensionless() {
        let bad = "param L = 2 m\ncoord x = 1 m\nparticle p { mass 1; position (sin(x), 0) }\n";
        let e = errors(bad);
        assert!(e.iter().any(|m| m.contains("argument of sin")), "{e:?}");
    }

    const CHARGE: &str = "param m = 1 kg, q = 1 C, B = 2 T\ncoord x = 1 m, x' = 0\ncoord y = 0, y' = 1 m/s\nlagrangian m/2*(x'^2 + y'^2) + q*B/2*(x*y' - y*x')\n";

    #[test]
    fn zero_has_every_dimension() {
        let matrix = format!("{CHARGE}expect [m, 0; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
        assert_eq!(errors(&matrix), Vec::<String>::new());
        for zero in ["0", "-0.0", "0*pi", "(1/2 - 0.5)", "sin(pi)", "(sqrt(4) - 2)"] {
            let m = format!("{CHARGE}expect [m, {zero}; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
            assert_eq!(errors(&m), Vec::<String>::new(), "{zero}");
            let product = format!("{CHARGE}expect m*x'' + {zero}*y'' = q*B*y'\n");
            assert_eq!(errors(&product), Vec::<String>::new(), "{zero}");
        }
        // A number that is not zero still makes a product keep the other factor's dimension.
        let wrong = format!("{CHARGE}expect [m, 1; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
        let e = errors(&wrong);
        assert!(e.len() == 1 && e[0].contains("matrix product"), "{e:?}");
    }

    #[test]
    fn number_only_expressions_take_the_dimension_their_place_needs() {
        let pendulum = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord theta = 0, theta' = RATE\nparticle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\ngravity g\n";
        for rate in ["0.866", "1/2*sqrt(3)", "sqrt(3)/2", "2*pi", "1/3", "-1/2", "-(1/2)"] {
            assert_eq!(errors(&pendulum.replace("RATE", rate)), Vec::<String>::new(), "{rate}");
        }
        let sum =
            "param L = 1 m\ncoord x = 1 m\nparticle p { mass 1; position (x + sqrt(2)/2, 2*pi) }\n";
        assert_eq!(errors(sum), Vec::<String>::new());
        // A name is not a number: `pi` declared as a parameter is checked like any other.
        let shadowed =
            "param pi = 2 s, L = 1 m\ncoord x = 1 m\nparticle p { mass 1; position (x + pi, 0) }\n";
        assert_eq!(errors(shadowed).len(), 1);
    }

    #[test]
    fn units_after_expressions_and_denominators_only() {
        let ok = "param m = 1 kg, L = 1 m, k = 1/2 1/m, c = sqrt(2) N/m\ncoord x = 0 m\nparticle p { mass m; position (x, 0) }\npotential c/2*x^2 + c*k*x^3\n";
        assert_eq!(errors(ok), Vec::<String>::new());
        // `0 m` keeps its unit: x is a length, and so x + t is refused.
        let zero_with_unit = "coord x = 0 m\nparticle p { mass 1; position (x + t, 0) }\n";
        assert_eq!(errors(zero_with_unit).len(), 1);
        let inverse_length = "param k = 1/2 1/m, L = 1 m\ncoord x = 1 m\nparticle p { mass 1; position (x + k, 0) }\n";
        let e = errors(inverse_length);
        assert!(e.len() == 1 && e[0].contains("1/m"), "{e:?}");
    }

    #[test]
    fn inconsistent_scenes_still_fail() {
        let sum = "param L = 1 m\ncoord x = 1 s\nparticle p { mass 1; position (x + L, 0) }\n";
        assert_eq!(errors(sum).len(), 1);
        let expect = "param m = 1 kg\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\nexpect m*x'' = x\n";
        let e = errors(expect);
        assert!(e.len() == 1 && e[0].contains("expectation"), "{e:?}");
    }

    #[test]
    fn the_parser_knows_every_unit() {
        for name in lang::UNIT_NAMES {
            assert!(unit(name).is_some(), "{name}");
        }
    }

    #[test]
    fn units_scale_to_si() {
        let file = lang::parse("param a = 30 deg, b = 10 cm\n").expect("parses");
        let lang::StmtKind::Param(ps) = &file.stmts[0].kind else { panic!() };
        let (_, s) = parse_unit(ps[0].unit.as_ref().expect("unit")).expect("known");
        assert_eq!((s.rational, s.pi_power), (Rational::new(1.into(), 180.into()), 1));
        let (d, s) = parse_unit(ps[1].unit.as_ref().expect("unit")).expect("known");
        assert_eq!(d, Dim::base(1));
        assert_eq!(s.rational, Rational::new(1.into(), 100.into()));
    }
}
