//! The meaning of each statement: declarations, terms of the Lagrangian, outputs and
//! `linearize about` lines, each resolved into the model or reported.

use cas::number::One;
use cas::Rational;
use lang::{Diagnostic, Span, Stmt, StmtKind};

use super::checks::{
    ATTACHMENT, BEFORE_IMPACT, DAMPER, DISSIPATION, GRAVITY, LAGRANGIAN, POTENTIAL, SPRING,
};
use super::dims::{Dims, NameDims};
use super::{normalize, Binding, Resolver, Separation};
use crate::units::Shape;
use crate::{
    About, BodyKind, Coord, Expect, Gravity, Linearize, Link, LinkKind, Param, Show, Term, Value,
};

impl Resolver<'_> {
    pub(super) fn statement(&mut self, stmt: &Stmt) {
        match &stmt.kind {
            StmtKind::Scene { title } => self.model.title = Some(title.clone()),
            StmtKind::Param(decls) => self.param_statement(decls),
            StmtKind::Input(decls) => self.input_statement(decls),
            StmtKind::Output { name, value } => self.output_statement(name, value),
            StmtKind::Let { name, value } => self.let_statement(name, value),
            StmtKind::Coord(decls) => self.coord_statement(decls),
            StmtKind::Particle { name, props } => {
                self.body(name, props, BodyKind::Particle, stmt.span)
            }
            StmtKind::Body { name, props } => self.body(name, props, BodyKind::Planar, stmt.span),
            StmtKind::Constraint { name, lhs, rhs } => {
                self.constraint(name.as_ref(), lhs, rhs, stmt.span)
            }
            StmtKind::Contact { name, lhs, rhs, at_least, laws } => {
                self.contact(name, (lhs, rhs), *at_least, laws, stmt.span)
            }
            StmtKind::Gravity { strength: written, direction } => {
                self.gravity_statement(written, direction.as_ref(), stmt.span)
            }
            StmtKind::Potential(e) => self.potential_statement(e),
            StmtKind::Dissipation(e) => self.dissipation_statement(e),
            StmtKind::Lagrangian(e) => self.lagrangian_statement(e),
            StmtKind::Spring { name, a, b, stiffness, rest } => {
                self.spring_statement(name, (a, b), stiffness, rest.as_ref(), stmt.span)
            }
            StmtKind::Damper { name, a, b, coefficient } => {
                self.damper_statement(name, (a, b), coefficient, stmt.span)
            }
            StmtKind::Force { name, body, at, value } => {
                self.load(name, body, at.as_ref(), value, stmt.span, false)
            }
            StmtKind::Torque { name, body, value } => {
                self.load(name, body, None, value, stmt.span, true)
            }
            StmtKind::Show { at_start, items } => self.show_statement(*at_start, items),
            StmtKind::Expect { at_start, impact, lhs, rhs, before } => {
                self.expect_statement((*at_start, impact.as_ref(), before), lhs, rhs, stmt.span)
            }
            StmtKind::ExpectLinearized(expectation) => {
                self.expect_linearized(expectation, stmt.span)
            }
            StmtKind::Simulate(settings) => self.simulate_statement(settings),
            StmtKind::Linearize(items) => self.linearize(items, stmt.span),
            StmtKind::Draw(shape) => self.draw(shape, stmt.span),
        }
    }

    /// A `param` line: each name is a symbol, with its unit and its value if given.
    fn param_statement(&mut self, decls: &[lang::ParamDecl]) {
        for decl in decls {
            // Its unknown comes before any in its value: unknowns follow the file.
            let example = match (&decl.value, &decl.unit) {
                (Some(v), None) => {
                    let value = self.text(v.span);
                    let value = if value.is_empty() { "…" } else { value.as_str() };
                    Some(format!("param {} = {value} rad", decl.name.name))
                }
                _ => None,
            };
            let form = self.scope.units.declared(&decl.name.name, decl.name.span, example);
            let value = decl.value.as_ref().map(|v| self.constant(v));
            if !matches!(value, Some(None)) && (value.is_some() || decl.unit.is_some()) {
                let dims = value.as_ref().and_then(|v| v.as_ref()).map(|(_, d)| d.clone());
                let v = self.with_unit(dims, decl.unit.as_ref());
                let span = decl.value.as_ref().map_or(decl.name.span, |v| v.span);
                self.scope.units.same(&form, &v, decl.name.span, span, "in this parameter");
            }
            let value = value.flatten().and_then(|(v, _)| self.in_si(v, decl.unit.as_ref()));
            let name = normalize(&decl.name.name);
            if self.scope.names.get(&name).is_some_and(|b| !matches!(b, Binding::Quantity(_))) {
                self.bind(&decl.name, Binding::Param(self.model.time));
                continue;
            }
            let sym = self.model.pool.param(&name);
            if self.bind(&decl.name, Binding::Param(sym)) {
                let dims = NameDims { at: self.stmt, form: Some(form), entries: None };
                self.scope.name_dims.insert(name.clone(), dims);
                if let (Some(v), Some(written)) = (value, &decl.value) {
                    self.param_value(sym, v, written);
                }
                self.model.params.push(Param {
                    name,
                    sym,
                    value,
                    unit: decl.unit.clone(),
                    span: decl.name.span,
                });
            }
        }
    }

    /// A `let` line: the name stands for its value, with the value's dimensions.
    fn let_statement(&mut self, name: &lang::Ident, value: &lang::Expr) {
        if let Some((v, dims)) = self.value(value) {
            if let Value::Scalar(e) = v {
                self.model.lets.push((normalize(&name.name), e));
            }
            // A vector or matrix keeps the dimension of each entry.
            let (form, entries) = match dims {
                Dims::Grid(g) => {
                    let g = g
                        .into_iter()
                        .map(|row| row.into_iter().map(|d| Dims::Scalar(self.form(d))).collect())
                        .collect();
                    (None, Some(Dims::Grid(g)))
                }
                Dims::Many(v) => (None, Some(Dims::Many(v))),
                d => match self.shape(d) {
                    Shape::Scalar(f) => (Some(f), None),
                    Shape::Many(v) => (None, Some(Dims::Many(v))),
                },
            };
            if self.bind(name, Binding::Let(v)) {
                let dims = NameDims { at: self.stmt, form, entries };
                self.scope.name_dims.insert(normalize(&name.name), dims);
            }
        }
    }

    /// A `coord` line: each name is a coordinate, with its initial value and rate.
    fn coord_statement(&mut self, decls: &[lang::CoordDecl]) {
        for decl in decls {
            let form = self.scope.units.fresh(&decl.name.name);
            let initial = decl.value.as_ref().and_then(|v| self.constant(v));
            if let (Some((_, dims)), Some(written)) = (&initial, &decl.value) {
                let v = self.with_unit(Some(dims.clone()), decl.value_unit.as_ref());
                let what = "in this initial value";
                self.scope.units.same(&form, &v, decl.name.span, written.span, what);
            }
            let initial = initial.and_then(|(v, _)| self.in_si(v, decl.value_unit.as_ref()));
            let rate = decl.rate.as_ref().and_then(|v| self.constant(v));
            if let (Some((_, dims)), Some(written)) = (&rate, &decl.rate) {
                let v = self.with_unit(Some(dims.clone()), decl.rate_unit.as_ref());
                let what = "in this initial rate";
                self.scope.units.same(&form.rate(1), &v, written.span, written.span, what);
            }
            let rate = rate.and_then(|(v, _)| self.in_si(v, decl.rate_unit.as_ref()));
            let name = normalize(&decl.name.name);
            if self.scope.names.get(&name).is_some_and(|b| !matches!(b, Binding::Quantity(_))) {
                self.bind(&decl.name, Binding::Param(self.model.time));
                continue;
            }
            let sym = self.model.pool.coordinate(&name);
            let zero = self.model.pool.zero();
            if self.bind(&decl.name, Binding::Coord(sym)) {
                let dims = NameDims { at: self.stmt, form: Some(form), entries: None };
                self.scope.name_dims.insert(name.clone(), dims);
                self.model.coords.push(Coord {
                    name,
                    sym,
                    initial: initial.unwrap_or(zero),
                    initial_rate: rate.unwrap_or(zero),
                    initial_given: decl.value.is_some() || decl.rate.is_some(),
                    initial_rate_given: decl.rate.is_some(),
                    position_free: decl.value.is_none() || decl.guess,
                    span: decl.name.span,
                });
            }
        }
    }

    /// A `gravity` line: its strength and direction, given once.
    fn gravity_statement(
        &mut self,
        written: &lang::Expr,
        direction: Option<&lang::Expr>,
        span: Span,
    ) {
        let strength = self.scalar_in_role(written, &GRAVITY).map(|(g, dims)| {
            let form = self.form(dims);
            (g, form)
        });
        let direction = direction.and_then(|d| {
            let (value, dims) = self.value_in_role(d, &GRAVITY)?;
            for f in self.shape(dims).forms() {
                self.scope.units.dimensionless(&f, d.span, "a direction");
            }
            match value {
                Value::Vector(v) => Some(v),
                other => {
                    self.error(
                        Diagnostic::error(
                            d.span,
                            format!("a direction must be a vector, not {}", other.kind_name()),
                        )
                        .with_label("expected `(x, y)` or `(x, y, z)`")
                        .with_hint("write `gravity g along (0, -1)`"),
                    );
                    None
                }
            }
        });
        if let Some((_, g)) = &strength {
            self.gravity_energy(g, written.span);
        }
        let strength = strength.map(|(g, _)| g);
        if let Some(previous) = &self.model.gravity {
            let first = previous.span;
            self.error(
                Diagnostic::error(span, "gravity is given twice")
                    .with_label("second `gravity`")
                    .with_related(first, "first given here"),
            );
        } else if let Some(strength) = strength {
            self.model.gravity = Some(Gravity { strength, direction, span });
        }
    }

    /// A `potential` line: an energy term of the potential.
    fn potential_statement(&mut self, e: &lang::Expr) {
        if let Some((expr, dims)) = self.scalar_in_role(e, &POTENTIAL) {
            let f = self.form(dims);
            self.scope.units.energy_term(&f, e.span);
            self.model.potentials.push(Term { expr, span: e.span });
        }
    }

    /// A `dissipation` line: a term of the Rayleigh function, a power.
    fn dissipation_statement(&mut self, e: &lang::Expr) {
        if let Some((expr, dims)) = self.scalar_in_role(e, &DISSIPATION) {
            // A Rayleigh function is a power: energy per time.
            let f = self.form(dims).plus(&crate::units::time(), &Rational::one());
            self.scope.units.energy_term(&f, e.span);
            self.model.dissipation.push(Term { expr, span: e.span });
        }
    }

    /// A `lagrangian` line: an energy term added to the Lagrangian.
    fn lagrangian_statement(&mut self, e: &lang::Expr) {
        if let Some((expr, dims)) = self.scalar_in_role(e, &LAGRANGIAN) {
            let f = self.form(dims);
            self.scope.units.energy_term(&f, e.span);
            self.model.lagrangians.push(Term { expr, span: e.span });
        }
    }

    /// A `spring` line: its energy k/2 (|AB| − l0)², and the link for drawing.
    fn spring_statement(
        &mut self,
        name: &lang::Ident,
        ends: (&lang::Expr, &lang::Expr),
        stiffness: &lang::Expr,
        rest: Option<&lang::Expr>,
        span: Span,
    ) {
        let (a, b) = ends;
        let (Some((len2, separation)), Some((k, k_dims))) =
            (self.separation_squared(a, b, &SPRING), self.scalar_in_role(stiffness, &SPRING))
        else {
            return;
        };
        let rest = match rest {
            Some(r) => match self.scalar_in_role(r, &SPRING) {
                Some((l0, dims)) => Some((l0, (dims, r.span))),
                None => return,
            },
            None => None,
        };
        let (rest, rest_dims) = rest.unzip();
        let len = separation.length;
        self.spring_energy(&len, (k_dims, stiffness.span), rest_dims, a.span.join(b.span));
        // k/2 (|AB| − l0)²; with no rest length, k/2 |AB|², which needs no square root.
        let stretch2 = match rest {
            Some(l0) => {
                let len = self.model.pool.sqrt(len2);
                let s = self.model.pool.sub(len, l0);
                self.model.pool.powi(s, 2)
            }
            None => len2,
        };
        let e = self.model.pool.mul2(k, stretch2);
        let expr = self.model.pool.scale(e, &Rational::new(1.into(), 2.into()));
        self.model.potentials.push(Term { expr, span });
        self.model.links.push(Link {
            name: name.name.clone(),
            kind: LinkKind::Spring,
            ends: separation.ends,
            span,
        });
    }

    /// A `damper` line: its Rayleigh term c/2 (d|AB|/dt)², and the link for drawing.
    fn damper_statement(
        &mut self,
        name: &lang::Ident,
        ends: (&lang::Expr, &lang::Expr),
        coefficient: &lang::Expr,
        span: Span,
    ) {
        let (a, b) = ends;
        let (Some(separation), Some((c, c_dims))) =
            (self.separation(a, b, &ATTACHMENT), self.scalar_in_role(coefficient, &DAMPER))
        else {
            return;
        };
        let Separation { difference: d, length: len, ends } = separation;
        self.model.links.push(Link { name: name.name.clone(), kind: LinkKind::Damper, ends, span });
        self.damper_energy(&len, c_dims, coefficient.span);
        // c/2 (d|AB|/dt)², with d|AB|/dt = (AB·AB')/|AB|: squared, no root is left, and
        // on a line (AB = u) it is exactly u'².
        let mut dots = Vec::new();
        let mut squares = Vec::new();
        for x in &d {
            let v = self.model.pool.time_derivative(*x);
            dots.push(self.model.pool.mul2(*x, v));
            squares.push(self.model.pool.powi(*x, 2));
        }
        let dot = self.model.pool.add(&dots);
        let len2 = self.model.pool.add(&squares);
        let dot2 = self.model.pool.powi(dot, 2);
        let inv = self.model.pool.powi(len2, -1);
        let rate2 = self.model.pool.mul2(dot2, inv);
        let d = self.model.pool.mul2(c, rate2);
        let expr = self.model.pool.scale(d, &Rational::new(1.into(), 2.into()));
        self.model.dissipation.push(Term { expr, span });
    }

    /// A `show` line: each item's value, labelled by its text.
    fn show_statement(&mut self, at_start: bool, items: &[lang::Expr]) {
        for item in items {
            if let Some((value, _)) = self.value(item) {
                let label = self.text(item.span);
                self.model.shows.push(Show { at_start, label, value, span: item.span });
            }
        }
    }

    /// An `expect` line: two values of the same shape and dimensions, to compare.
    fn expect_statement(
        &mut self,
        (at_start, impact, before): (bool, Option<&lang::Ident>, &[lang::AboutItem]),
        lhs: &lang::Expr,
        rhs: &lang::Expr,
        span: Span,
    ) {
        let impact = match impact {
            None => None,
            Some(name) => {
                let found =
                    self.model.contacts.iter().position(|c| c.name == normalize(&name.name));
                if found.is_none() {
                    let mut d =
                        Diagnostic::error(name.span, format!("no contact named `{}`", name.name))
                            .with_label("not a contact");
                    let names: Vec<&str> =
                        self.model.contacts.iter().map(|c| c.name.as_str()).collect();
                    d = d.with_hint(if names.is_empty() {
                        "`expect impact NAME:` names a contact declared above with `contact NAME: gap >= 0`".to_string()
                    } else {
                        format!("the contacts are {}", names.join(", "))
                    });
                    self.error(d);
                    return;
                }
                found
            }
        };
        let before = self.about_items(
            before,
            "the state before an impact gives coordinates and their rates: `where theta = 0, theta' = w`",
            false,
        );
        let (l, r) = (self.value(lhs), self.value(rhs));
        let (Some((l, l_dims)), Some((r, r_dims))) = (l, r) else { return };
        let (lf, rf) = (self.operand(l_dims).forms(), self.operand(r_dims).forms());
        for (a, b) in lf.iter().zip(&rf) {
            let what = "between the sides of this expectation";
            self.scope.units.same(a, b, lhs.span, rhs.span, what);
        }
        let (ln, rn) = (l.entries().len(), r.entries().len());
        if ln != rn {
            self.error(
                Diagnostic::error(rhs.span, "the two sides of this `expect` have different shapes")
                    .with_label(r.kind_name())
                    .with_related(lhs.span, l.kind_name()),
            );
            return;
        }
        let text = self.text(span);
        self.model.expects.push(Expect {
            at_start,
            impact,
            before,
            text,
            lhs: l,
            rhs: r,
            span,
            lhs_span: lhs.span,
            rhs_span: rhs.span,
        });
    }

    /// A `linearize about` line: each item names a coordinate (or its rate) and gives it a
    /// constant of the coordinate's dimension (or its rate's).
    pub(super) fn linearize(&mut self, items: &[lang::AboutItem], span: Span) {
        let hint = "a reference gives coordinates and their rates: `linearize about theta = 0, theta' = 0`";
        let out = self.about_items(items, hint, true);
        self.model.linearize.push(Linearize { items: out, span });
    }

    /// Items `q = value` and `q' = value`, each a coordinate or its rate given a value of its
    /// dimension: a reference (`constant`), or the state before an impact, whose values may
    /// be in terms of the state's other positions and rates. `hint` says what they are for
    /// where one names something else.
    fn about_items(&mut self, items: &[lang::AboutItem], hint: &str, constant: bool) -> Vec<About> {
        let mut out: Vec<About> = Vec::new();
        for item in items {
            let raw = &item.name.name;
            let name = normalize(raw);
            let coord = match self.scope.names.get(&name).cloned() {
                Some(Binding::Coord(s)) => s,
                None => {
                    self.unknown_name(raw, &name, item.name.span);
                    continue;
                }
                Some(other) => {
                    let what = match other {
                        Binding::Param(_) => "a parameter",
                        Binding::Input(_) => "an input",
                        Binding::Let(_) => "a `let` name",
                        Binding::Body(_) => "a body",
                        Binding::Constraint(_) => "a constraint",
                        Binding::Quantity(_) | Binding::Coord(_) => "a derived quantity",
                    };
                    self.error(
                        Diagnostic::error(item.name.span, format!("`{raw}` is not a coordinate"))
                            .with_label(what)
                            .with_hint(hint),
                    );
                    continue;
                }
            };
            // The primes follow the name with nothing between them.
            let primed = Span::new(item.name.span.start, item.name.span.end + item.primes as usize);
            let Some((_, coord_dims)) = self.name(raw, item.primes, primed) else { continue };
            let resolved = match constant {
                true => self.constant(&item.value),
                false => self.scalar_in_role(&item.value, &BEFORE_IMPACT),
            };
            let Some((value, dims)) = resolved else { continue };
            let written = self.with_unit(Some(dims), item.unit.as_ref());
            let expected = self.form(coord_dims);
            let what = "in this reference value";
            self.scope.units.same(&expected, &written, primed, item.value.span, what);
            let Some(value) = self.in_si(value, item.unit.as_ref()) else { continue };
            let rate = item.primes == 1;
            if let Some(first) = out.iter().find(|a| a.coord == coord && a.rate == rate) {
                let written = format!("{raw}{}", if rate { "'" } else { "" });
                self.error(
                    Diagnostic::error(item.span, format!("`{written}` is given twice"))
                        .with_label("given again here")
                        .with_related(first.span, "first given here")
                        .with_hint("give each coordinate and rate one reference value"),
                );
                continue;
            }
            out.push(About { coord, rate, value, span: item.span });
        }
        out
    }
}
