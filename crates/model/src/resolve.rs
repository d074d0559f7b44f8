//! Name resolution and the meaning of each statement: AST in, [`Model`] out.

mod checks;
mod dims;
mod draw;
mod space;

use std::collections::HashMap;

use cas::number::{One, Signed};
use cas::{ExprId, Func, Pool, Rational, SymId, SymbolKind};
use lang::{BinOp, Diagnostic, Expr, ExprKind, Ident, Property, SceneFile, Span, Stmt, StmtKind};

use self::checks::{
    Role, ANGLE, ATTACHMENT, DAMPER, DISSIPATION, FORCE, GRAVITY, INERTIA, LAGRANGIAN, MASS,
    POSITION, POTENTIAL, SPRING, TORQUE,
};
use self::dims::{BodyDims, Dims, NameDims};
use crate::units::{Form, Inference, Shape};
use crate::{
    About, Body, BodyKind, Checks, Constraint, ConstraintKind, Coord, Drawing, Expect, Gravity,
    Linearize, Link, LinkKind, Load, Model, Param, Placeholder, Rotation, Show, Term, Value,
};

/// Two attachment points of a spring or damper, and what lies between them.
struct Separation {
    /// B − A, padded to the longer of the two.
    difference: Vec<ExprId>,
    /// The dimension of its length.
    length: Form,
    /// A and B as written.
    ends: [Vec<ExprId>; 2],
}

/// Past this the power is not physics and expanding it would exhaust memory.
const MAX_EXPONENT: i64 = 64;

/// What a name refers to at a point of the file.
#[derive(Clone, Debug)]
enum Binding {
    Param(SymId),
    Coord(SymId),
    Let(Value),
    Body(usize),
    /// The constraint's scalar components, one for a scalar constraint; `None` for a
    /// component of a vector constraint that always holds.
    Constraint(Vec<Option<usize>>),
    Quantity(SymId),
}

/// Resolves a parsed scene. On success, the model and any warnings; otherwise every error found.
pub fn resolve(
    file: &SceneFile,
    source: &str,
) -> Result<(Model, Vec<Diagnostic>), Vec<Diagnostic>> {
    resolve_with(file, source, Checks::default())
}

/// [`resolve`], with the checks asked for. The dimension check is made only on a scene that
/// resolves, and its mismatches are then the errors.
pub fn resolve_with(
    file: &SceneFile,
    source: &str,
    checks: Checks,
) -> Result<(Model, Vec<Diagnostic>), Vec<Diagnostic>> {
    walk(file, source).finish(checks)
}

/// Checks that every term of the scene has one dimension. Returns the mismatches found, from
/// as much of the scene as resolves.
pub fn dimension_errors(file: &SceneFile) -> Vec<Diagnostic> {
    walk(file, "").units.solve()
}

fn walk<'a>(file: &SceneFile, source: &'a str) -> Resolver<'a> {
    let mut r = Resolver::new(source);
    r.declare_all(file);
    let numbered = file.stmts.iter().enumerate();
    let (outputs, statements): (Vec<_>, Vec<_>) = numbered.partition(|(_, s)| {
        matches!(
            s.kind,
            StmtKind::Show { .. }
                | StmtKind::Expect { .. }
                | StmtKind::Linearize(_)
                | StmtKind::Draw(_)
        )
    });
    for (i, stmt) in statements {
        r.enter(i);
        r.statement(stmt);
    }
    // Show, expect, linearize and draw lines may name anything in the file, wherever they stand.
    r.in_outputs = true;
    for (i, stmt) in outputs {
        r.enter(i);
        r.statement(stmt);
    }
    r.require_a_coordinate(file);
    r
}

/// The Greek letters of a name spelled out, so `θ` and `theta` are the same name.
fn normalize(name: &str) -> String {
    name.chars()
        .map(|c| cas::greek_word(c).map(str::to_string).unwrap_or_else(|| c.to_string()))
        .collect()
}

/// The closest candidate within a small edit distance.
fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    // One letter away from a one- or two-letter name is any other name: only a change of
    // case counts there.
    if name.chars().count() <= 2 {
        return candidates.into_iter().find(|c| c.eq_ignore_ascii_case(name) && *c != name);
    }
    let limit = (name.chars().count() / 3).clamp(1, 2);
    candidates
        .into_iter()
        .map(|c| (strsim::levenshtein(name, c), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, c)| (*d, c.to_string()))
        .map(|(_, c)| c)
}

struct Resolver<'a> {
    source: &'a str,
    pool: Pool,
    time: SymId,
    names: HashMap<String, Binding>,
    /// Every name the file declares anywhere, for "used before it is declared".
    declared: HashMap<String, (Span, &'static str)>,
    errors: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    in_outputs: bool,
    /// Resolving a `draw` line, where a reaction may not be named: asking for one would change
    /// the derivation, and a drawing must leave the equations as they are.
    in_drawing: bool,
    /// Names looked up so far, for the warning about parameters nothing uses.
    used: std::collections::HashSet<String>,
    title: Option<String>,
    params: Vec<Param>,
    coords: Vec<Coord>,
    bodies: Vec<Body>,
    constraints: Vec<Constraint>,
    gravity: Option<Gravity>,
    potentials: Vec<Term>,
    forces: Vec<Load>,
    torques: Vec<Load>,
    dissipation: Vec<Term>,
    lagrangians: Vec<Term>,
    shows: Vec<Show>,
    expects: Vec<Expect>,
    drawings: Vec<Drawing>,
    links: Vec<Link>,
    simulate: Vec<lang::Setting>,
    linearize: Vec<Linearize>,
    placeholders: Vec<(SymId, Placeholder)>,
    lets: Vec<(String, cas::ExprId)>,
    /// Each parameter's value as a number (no symbols left), for the checks of constants.
    param_values: HashMap<SymId, ExprId>,
    /// The statement being resolved, by its place in the file.
    stmt: usize,
    /// What every expression resolved says about dimensions.
    units: Inference,
    /// The dimension of each name in `names`.
    name_dims: HashMap<String, NameDims>,
    /// The dimensions of each body in `bodies`, by the same index.
    body_dims: Vec<BodyDims>,
    /// Names whose dimension is not known where they are used (see [`Self::name_dims`]).
    loose: HashMap<String, Form>,
    /// Each `quaternion(…)` resolved: its matrix, its Euler parameters and where it is written.
    quaternions: Vec<(Vec<Vec<ExprId>>, [ExprId; 4], Span)>,
    /// What is checked besides names and meaning.
    checks: Checks,
}

impl<'a> Resolver<'a> {
    fn new(source: &'a str) -> Self {
        let mut pool = Pool::new();
        pool.set_zero_test(Box::new(numeric::GenericPoints));
        let time = pool.time();
        let mut names = HashMap::new();
        let mut placeholders = Vec::new();
        for (name, kind) in
            [("KE", Placeholder::KineticEnergy), ("PE", Placeholder::PotentialEnergy)]
        {
            let s = pool.param(name);
            names.insert(name.to_string(), Binding::Quantity(s));
            placeholders.push((s, kind));
        }
        Resolver {
            source,
            pool,
            time,
            names,
            declared: HashMap::new(),
            errors: Vec::new(),
            warnings: Vec::new(),
            in_outputs: false,
            in_drawing: false,
            used: std::collections::HashSet::new(),
            title: None,
            params: Vec::new(),
            coords: Vec::new(),
            bodies: Vec::new(),
            constraints: Vec::new(),
            gravity: None,
            potentials: Vec::new(),
            forces: Vec::new(),
            torques: Vec::new(),
            dissipation: Vec::new(),
            lagrangians: Vec::new(),
            shows: Vec::new(),
            expects: Vec::new(),
            drawings: Vec::new(),
            links: Vec::new(),
            simulate: Vec::new(),
            linearize: Vec::new(),
            placeholders,
            lets: Vec::new(),
            param_values: HashMap::new(),
            stmt: 0,
            units: Inference::default(),
            name_dims: HashMap::new(),
            body_dims: Vec::new(),
            loose: HashMap::new(),
            quaternions: Vec::new(),
            checks: Checks::default(),
        }
    }

    fn enter(&mut self, index: usize) {
        self.stmt = index;
        self.units.enter(index);
    }

    fn error(&mut self, d: Diagnostic) {
        self.errors.push(d);
    }

    fn text(&self, span: Span) -> String {
        self.source.get(span.start..span.end).unwrap_or("").trim().to_string()
    }

    fn declare_all(&mut self, file: &SceneFile) {
        for stmt in &file.stmts {
            let mut add = |id: &Ident, what: &'static str| {
                self.declared.entry(normalize(&id.name)).or_insert((id.span, what));
            };
            match &stmt.kind {
                StmtKind::Param(ps) => ps.iter().for_each(|p| add(&p.name, "parameter")),
                StmtKind::Coord(cs) => cs.iter().for_each(|c| add(&c.name, "coordinate")),
                StmtKind::Let { name, .. } => add(name, "name"),
                StmtKind::Particle { name, .. } | StmtKind::Body { name, .. } => add(name, "body"),
                StmtKind::Constraint { name: Some(name), .. } => add(name, "constraint"),
                _ => {}
            }
        }
    }

    /// Binds a new name, or reports that it is taken.
    fn bind(&mut self, id: &Ident, binding: Binding) -> bool {
        let name = normalize(&id.name);
        if name == "t" || name == "pi" {
            self.error(
                Diagnostic::error(
                    id.span,
                    format!("`{name}` is built in and cannot be redeclared"),
                )
                .with_label("built-in name")
                .with_hint(if name == "t" { "`t` is time" } else { "`pi` is π" }),
            );
            return false;
        }
        if let Some(existing) = self.names.get(&name) {
            if !matches!(existing, Binding::Quantity(_)) {
                let first = self.declared.get(&name).map(|(s, _)| *s);
                let mut d = Diagnostic::error(id.span, format!("`{}` is declared twice", id.name))
                    .with_label("declared again here");
                if let Some(first) = first.filter(|s| *s != id.span) {
                    d = d.with_related(first, "first declared here");
                }
                self.error(d.with_hint(
                    "give each parameter, coordinate, body and constraint its own name",
                ));
                return false;
            }
        }
        self.names.insert(name, binding);
        true
    }

    fn statement(&mut self, stmt: &Stmt) {
        match &stmt.kind {
            StmtKind::Scene { title } => self.title = Some(title.clone()),
            StmtKind::Param(decls) => {
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
                    let form = self.units.declared(&decl.name.name, decl.name.span, example);
                    let value = decl.value.as_ref().map(|v| self.constant(v));
                    if !matches!(value, Some(None)) && (value.is_some() || decl.unit.is_some()) {
                        let dims = value.as_ref().and_then(|v| v.as_ref()).map(|(_, d)| d.clone());
                        let v = self.with_unit(dims, decl.unit.as_ref());
                        let span = decl.value.as_ref().map_or(decl.name.span, |v| v.span);
                        self.units.same(&form, &v, decl.name.span, span, "in this parameter");
                    }
                    let value =
                        value.flatten().and_then(|(v, _)| self.in_si(v, decl.unit.as_ref()));
                    let name = normalize(&decl.name.name);
                    if self.names.get(&name).is_some_and(|b| !matches!(b, Binding::Quantity(_))) {
                        self.bind(&decl.name, Binding::Param(self.time));
                        continue;
                    }
                    let sym = self.pool.param(&name);
                    if self.bind(&decl.name, Binding::Param(sym)) {
                        let dims = NameDims { at: self.stmt, form: Some(form), entries: None };
                        self.name_dims.insert(name.clone(), dims);
                        if let (Some(v), Some(written)) = (value, &decl.value) {
                            self.param_value(sym, v, written);
                        }
                        self.params.push(Param {
                            name,
                            sym,
                            value,
                            unit: decl.unit.clone(),
                            span: decl.name.span,
                        });
                    }
                }
            }
            StmtKind::Let { name, value } => {
                if let Some((v, dims)) = self.value(value) {
                    if let Value::Scalar(e) = v {
                        self.lets.push((normalize(&name.name), e));
                    }
                    // A vector or matrix keeps the dimension of each entry.
                    let (form, entries) = match dims {
                        Dims::Grid(g) => {
                            let g = g
                                .into_iter()
                                .map(|row| {
                                    row.into_iter().map(|d| Dims::Scalar(self.form(d))).collect()
                                })
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
                        self.name_dims.insert(normalize(&name.name), dims);
                    }
                }
            }
            StmtKind::Coord(decls) => {
                for decl in decls {
                    let form = self.units.fresh(&decl.name.name);
                    let initial = decl.value.as_ref().and_then(|v| self.constant(v));
                    if let (Some((_, dims)), Some(written)) = (&initial, &decl.value) {
                        let v = self.with_unit(Some(dims.clone()), decl.value_unit.as_ref());
                        let what = "in this initial value";
                        self.units.same(&form, &v, decl.name.span, written.span, what);
                    }
                    let initial =
                        initial.and_then(|(v, _)| self.in_si(v, decl.value_unit.as_ref()));
                    let rate = decl.rate.as_ref().and_then(|v| self.constant(v));
                    if let (Some((_, dims)), Some(written)) = (&rate, &decl.rate) {
                        let v = self.with_unit(Some(dims.clone()), decl.rate_unit.as_ref());
                        let what = "in this initial rate";
                        self.units.same(&form.rate(1), &v, written.span, written.span, what);
                    }
                    let rate = rate.and_then(|(v, _)| self.in_si(v, decl.rate_unit.as_ref()));
                    let name = normalize(&decl.name.name);
                    if self.names.get(&name).is_some_and(|b| !matches!(b, Binding::Quantity(_))) {
                        self.bind(&decl.name, Binding::Param(self.time));
                        continue;
                    }
                    let sym = self.pool.coordinate(&name);
                    let zero = self.pool.zero();
                    if self.bind(&decl.name, Binding::Coord(sym)) {
                        let dims = NameDims { at: self.stmt, form: Some(form), entries: None };
                        self.name_dims.insert(name.clone(), dims);
                        self.coords.push(Coord {
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
            StmtKind::Particle { name, props } => {
                self.body(name, props, BodyKind::Particle, stmt.span)
            }
            StmtKind::Body { name, props } => self.body(name, props, BodyKind::Planar, stmt.span),
            StmtKind::Constraint { name, lhs, rhs } => {
                self.constraint(name.as_ref(), lhs, rhs, stmt.span)
            }
            StmtKind::Gravity { strength: written, direction } => {
                let strength = self.scalar_in_role(written, &GRAVITY).map(|(g, dims)| {
                    let form = self.form(dims);
                    (g, form)
                });
                let direction = direction.as_ref().and_then(|d| {
                    let (value, dims) = self.value_in_role(d, &GRAVITY)?;
                    for f in self.shape(dims).forms() {
                        self.units.dimensionless(&f, d.span, "a direction");
                    }
                    match value {
                        Value::Vector(v) => Some(v),
                        other => {
                            self.error(
                                Diagnostic::error(
                                    d.span,
                                    format!(
                                        "a direction must be a vector, not {}",
                                        other.kind_name()
                                    ),
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
                if let Some(previous) = &self.gravity {
                    let first = previous.span;
                    self.error(
                        Diagnostic::error(stmt.span, "gravity is given twice")
                            .with_label("second `gravity`")
                            .with_related(first, "first given here"),
                    );
                } else if let Some(strength) = strength {
                    self.gravity = Some(Gravity { strength, direction, span: stmt.span });
                }
            }
            StmtKind::Potential(e) => {
                if let Some((expr, dims)) = self.scalar_in_role(e, &POTENTIAL) {
                    let f = self.form(dims);
                    self.units.energy_term(&f, e.span);
                    self.potentials.push(Term { expr, span: e.span });
                }
            }
            StmtKind::Dissipation(e) => {
                if let Some((expr, dims)) = self.scalar_in_role(e, &DISSIPATION) {
                    // A Rayleigh function is a power: energy per time.
                    let f = self.form(dims).plus(&crate::units::time(), &Rational::one());
                    self.units.energy_term(&f, e.span);
                    self.dissipation.push(Term { expr, span: e.span });
                }
            }
            StmtKind::Lagrangian(e) => {
                if let Some((expr, dims)) = self.scalar_in_role(e, &LAGRANGIAN) {
                    let f = self.form(dims);
                    self.units.energy_term(&f, e.span);
                    self.lagrangians.push(Term { expr, span: e.span });
                }
            }
            StmtKind::Spring { name, a, b, stiffness, rest } => {
                let (Some((len2, separation)), Some((k, k_dims))) = (
                    self.separation_squared(a, b, &SPRING),
                    self.scalar_in_role(stiffness, &SPRING),
                ) else {
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
                        let len = self.pool.sqrt(len2);
                        let s = self.pool.sub(len, l0);
                        self.pool.powi(s, 2)
                    }
                    None => len2,
                };
                let e = self.pool.mul2(k, stretch2);
                let expr = self.pool.scale(e, &Rational::new(1.into(), 2.into()));
                self.potentials.push(Term { expr, span: stmt.span });
                self.links.push(Link {
                    name: name.name.clone(),
                    kind: LinkKind::Spring,
                    ends: separation.ends,
                    span: stmt.span,
                });
            }
            StmtKind::Damper { name, a, b, coefficient } => {
                let (Some(separation), Some((c, c_dims))) =
                    (self.separation(a, b, &ATTACHMENT), self.scalar_in_role(coefficient, &DAMPER))
                else {
                    return;
                };
                let Separation { difference: d, length: len, ends } = separation;
                self.links.push(Link {
                    name: name.name.clone(),
                    kind: LinkKind::Damper,
                    ends,
                    span: stmt.span,
                });
                self.damper_energy(&len, c_dims, coefficient.span);
                // c/2 (d|AB|/dt)², with d|AB|/dt = (AB·AB')/|AB|: squared, no root is left, and
                // on a line (AB = u) it is exactly u'².
                let mut dots = Vec::new();
                let mut squares = Vec::new();
                for x in &d {
                    let v = self.pool.time_derivative(*x);
                    dots.push(self.pool.mul2(*x, v));
                    squares.push(self.pool.powi(*x, 2));
                }
                let dot = self.pool.add(&dots);
                let len2 = self.pool.add(&squares);
                let dot2 = self.pool.powi(dot, 2);
                let inv = self.pool.powi(len2, -1);
                let rate2 = self.pool.mul2(dot2, inv);
                let d = self.pool.mul2(c, rate2);
                let expr = self.pool.scale(d, &Rational::new(1.into(), 2.into()));
                self.dissipation.push(Term { expr, span: stmt.span });
            }
            StmtKind::Force { name, body, at, value } => {
                self.load(name, body, at.as_ref(), value, stmt.span, false)
            }
            StmtKind::Torque { name, body, value } => {
                self.load(name, body, None, value, stmt.span, true)
            }
            StmtKind::Show { at_start, items } => {
                for item in items {
                    if let Some((value, _)) = self.value(item) {
                        let label = self.text(item.span);
                        self.shows.push(Show {
                            at_start: *at_start,
                            label,
                            value,
                            span: item.span,
                        });
                    }
                }
            }
            StmtKind::Expect { at_start, lhs, rhs } => {
                let (l, r) = (self.value(lhs), self.value(rhs));
                let (Some((l, l_dims)), Some((r, r_dims))) = (l, r) else { return };
                let (lf, rf) = (self.operand(l_dims).forms(), self.operand(r_dims).forms());
                for (a, b) in lf.iter().zip(&rf) {
                    let what = "between the sides of this expectation";
                    self.units.same(a, b, lhs.span, rhs.span, what);
                }
                let (ln, rn) = (l.entries().len(), r.entries().len());
                if ln != rn {
                    self.error(
                        Diagnostic::error(
                            rhs.span,
                            "the two sides of this `expect` have different shapes",
                        )
                        .with_label(r.kind_name())
                        .with_related(lhs.span, l.kind_name()),
                    );
                    return;
                }
                let text = self.text(stmt.span);
                self.expects.push(Expect {
                    at_start: *at_start,
                    text,
                    lhs: l,
                    rhs: r,
                    span: stmt.span,
                    lhs_span: lhs.span,
                    rhs_span: rhs.span,
                });
            }
            StmtKind::Simulate(settings) => self.simulate.extend(settings.iter().cloned()),
            StmtKind::Linearize(items) => self.linearize(items, stmt.span),
            StmtKind::Draw(shape) => self.draw(shape, stmt.span),
        }
    }

    /// A `linearize about` line: each item names a coordinate (or its rate) and gives it a
    /// constant of the coordinate's dimension (or its rate's).
    fn linearize(&mut self, items: &[lang::AboutItem], span: Span) {
        let mut out: Vec<About> = Vec::new();
        for item in items {
            let raw = &item.name.name;
            let name = normalize(raw);
            let coord = match self.names.get(&name).cloned() {
                Some(Binding::Coord(s)) => s,
                None => {
                    self.unknown_name(raw, &name, item.name.span);
                    continue;
                }
                Some(other) => {
                    let what = match other {
                        Binding::Param(_) => "a parameter",
                        Binding::Let(_) => "a `let` name",
                        Binding::Body(_) => "a body",
                        Binding::Constraint(_) => "a constraint",
                        Binding::Quantity(_) | Binding::Coord(_) => "a derived quantity",
                    };
                    self.error(
                        Diagnostic::error(item.name.span, format!("`{raw}` is not a coordinate"))
                            .with_label(what)
                            .with_hint(
                                "a reference gives coordinates and their rates: \
                                 `linearize about theta = 0, theta' = 0`",
                            ),
                    );
                    continue;
                }
            };
            // The primes follow the name with nothing between them.
            let primed = Span::new(item.name.span.start, item.name.span.end + item.primes as usize);
            let Some((_, coord_dims)) = self.name(raw, item.primes, primed) else { continue };
            let Some((value, dims)) = self.constant(&item.value) else { continue };
            let written = self.with_unit(Some(dims), item.unit.as_ref());
            let expected = self.form(coord_dims);
            let what = "in this reference value";
            self.units.same(&expected, &written, primed, item.value.span, what);
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
        self.linearize.push(Linearize { items: out, span });
    }

    fn body(&mut self, name: &Ident, props: &[Property], kind: BodyKind, span: Span) {
        let allowed: &[&str] = match kind {
            BodyKind::Particle => &["mass", "position"],
            BodyKind::Planar | BodyKind::Spatial => {
                &["mass", "inertia", "position", "angle", "orientation"]
            }
        };
        let mut seen: HashMap<&str, Span> = HashMap::new();
        // A misspelled property is reported once, not again as missing.
        let mut misspelled: Vec<&str> = Vec::new();
        let (mut mass, mut inertia, mut position, mut angle) = (None, None, None, None);
        let mut orientation: Option<(Vec<Vec<ExprId>>, Span)> = None;
        // The dimensions of each property, with where it is written.
        let (mut mass_dims, mut inertia_dims, mut angle_dims) = (None, None, None);
        let mut inertia_written: Option<(Value, &Expr)> = None;
        let mut position_dims: Vec<(Form, Span)> = Vec::new();
        for p in props {
            let key = p.key.name.as_str();
            if !allowed.contains(&key) {
                let mut d = Diagnostic::error(p.key.span, format!("unknown property `{key}`"))
                    .with_label(format!("expected one of {}", allowed.join(", ")));
                if kind == BodyKind::Particle && matches!(key, "inertia" | "angle") {
                    d = d.with_hint("a particle has no orientation; use `body` for a rigid body");
                } else if let Some(near) = closest(key, allowed.iter().copied()) {
                    d = d.with_hint(format!("did you mean `{near}`?"));
                    misspelled.push(near);
                }
                self.error(d);
                continue;
            }
            if let Some(first) = seen.insert(key, p.key.span) {
                self.error(
                    Diagnostic::error(p.key.span, format!("`{key}` is given twice"))
                        .with_label("again here")
                        .with_related(first, "first given here"),
                );
                continue;
            }
            match key {
                "mass" => {
                    let resolved = self.scalar_in_role(&p.value, &MASS);
                    mass = resolved.as_ref().map(|(m, _)| *m);
                    mass_dims = resolved.map(|(_, d)| self.form(d));
                    if let Some(m) = mass {
                        self.check_sign(name, m, &p.value, false);
                    }
                }
                "inertia" => {
                    // A scalar for a planar body; in space also principal moments or a tensor,
                    // decided once the orientation is known.
                    let resolved = self.value_in_role(&p.value, &INERTIA);
                    if let Some((v, d)) = resolved {
                        let forms = self.shape(d).forms();
                        inertia_dims = forms.first().cloned().map(|f| (f, p.value.span));
                        for f in &forms[1.min(forms.len())..] {
                            let what = "between the entries of an inertia";
                            self.units.same(&forms[0], f, p.value.span, p.value.span, what);
                        }
                        if let Value::Scalar(i) = v {
                            inertia = Some(i);
                            self.check_sign(name, i, &p.value, true);
                        }
                        inertia_written = Some((v, &p.value));
                    }
                }
                "orientation" => {
                    let resolved = self.value_in_role(&p.value, &ANGLE);
                    match resolved {
                        Some((Value::Matrix(m), d))
                            if m.len() == 3 && m.iter().all(|r| r.len() == 3) =>
                        {
                            for f in self.shape(d).forms() {
                                let what = "an entry of an orientation";
                                self.units.dimensionless(&f, p.value.span, what);
                            }
                            orientation = Some((m, p.value.span));
                        }
                        Some((other, _)) => self.error(
                            Diagnostic::error(
                                p.value.span,
                                format!(
                                    "an orientation is a 3×3 rotation matrix, not {}",
                                    other.kind_name()
                                ),
                            )
                            .with_label("expected a rotation")
                            .with_hint(
                                "compose rotations such as `rotz(phi)*rotx(theta)*rotz(psi)`; a \
                                 body turning in the plane takes `angle` instead",
                            ),
                        ),
                        None => {}
                    }
                }
                "angle" => {
                    let resolved = self.scalar_in_role(&p.value, &ANGLE);
                    angle = resolved.as_ref().map(|(a, _)| *a);
                    angle_dims = resolved.map(|(_, d)| self.form(d));
                }
                _ => {
                    let resolved = self.value_in_role(&p.value, &POSITION);
                    let resolved = resolved.map(|(v, d)| {
                        let forms = self.shape(d).forms();
                        position_dims = forms.into_iter().map(|f| (f, p.value.span)).collect();
                        v
                    });
                    position = match resolved {
                        Some(Value::Vector(v)) if v.len() <= 3 => Some(v),
                        Some(Value::Scalar(x)) => Some(vec![x]),
                        Some(other) => {
                            self.error(
                                Diagnostic::error(
                                    p.value.span,
                                    format!(
                                        "a position must be a vector, not {}",
                                        other.kind_name()
                                    ),
                                )
                                .with_label("expected `(x, y)` or `(x, y, z)`"),
                            );
                            None
                        }
                        None => None,
                    }
                }
            }
        }
        let what = if kind == BodyKind::Particle { "particle" } else { "body" };
        let missing = |field: &str, hint: &str| {
            Diagnostic::error(name.span, format!("{what} `{}` has no {field}", name.name))
                .with_label(format!("{field} missing"))
                .with_hint(hint.to_string())
        };
        let mut ok = true;
        if mass.is_none() && !seen.contains_key("mass") && !misspelled.contains(&"mass") {
            let d = missing("mass", "add `mass m` inside the braces");
            self.error(d);
            ok = false;
        }
        if position.is_none() && !seen.contains_key("position") && !misspelled.contains(&"position")
        {
            let d = missing("position", "add `position (x, y)`: where its centre of mass is, as a function of the coordinates");
            self.error(d);
            ok = false;
        }
        let spatial = orientation.is_some() || seen.contains_key("orientation");
        if spatial {
            if let Some(first) = seen.get("angle") {
                self.error(
                    Diagnostic::error(*first, "a body has either an `angle` or an `orientation`")
                        .with_label("angle given")
                        .with_related(seen["orientation"], "orientation given")
                        .with_hint(
                            "`angle` turns a body in the plane; `orientation` turns it in space",
                        ),
                );
                ok = false;
            }
            if !seen.contains_key("inertia") && !misspelled.contains(&"inertia") {
                let d = missing(
                    "inertia",
                    "add `inertia (A, B, C)`: the principal moments about the centre of mass in \
                     body axes, or the full tensor `[Ixx, Ixy, Ixz; Ixy, Iyy, Iyz; Ixz, Iyz, Izz]`",
                );
                self.error(d);
                ok = false;
            }
        }
        if kind == BodyKind::Planar && !spatial {
            if inertia.is_none()
                && !seen.contains_key("inertia")
                && !misspelled.contains(&"inertia")
            {
                let d = missing("inertia", "add `inertia m*L^2/12` (about the centre of mass), or use `particle` for a point mass");
                self.error(d);
                ok = false;
            }
            if angle.is_none() && !seen.contains_key("angle") && !misspelled.contains(&"angle") {
                let d = missing(
                    "angle",
                    "add `angle theta`: the body's orientation; its angular velocity is angle'",
                );
                self.error(d);
                ok = false;
            }
        }
        let rotation_rate = match spatial {
            // ω of a body in space is a rate of dimensionless rotation entries.
            true => Some(Form::default()),
            false => angle_dims.clone(),
        };
        self.body_energy(mass_dims.clone(), &position_dims, inertia_dims, rotation_rate.as_ref());
        if let (false, Some((written, expr))) = (spatial, &inertia_written) {
            if !matches!(written, Value::Scalar(_)) {
                self.error(
                    Diagnostic::error(expr.span, "a body turning in the plane has one inertia")
                        .with_label(format!("expected a scalar, found {}", written.kind_name()))
                        .with_hint(
                            "principal moments or a tensor need an `orientation` in space; in the \
                             plane give the inertia about the axis normal to it",
                        ),
                );
                ok = false;
            }
        }
        let spatial_rotation = match (orientation, inertia_written) {
            (Some((rows, span)), Some((written, expr))) => {
                self.spatial_rotation(name, rows, span, written, expr, position.as_deref())
            }
            _ => None,
        };
        if spatial && spatial_rotation.is_none() {
            ok = false;
        }
        let (Some(mass), Some(position), true) = (mass, position, ok) else { return };
        let index = self.bodies.len();
        if self.bind(name, Binding::Body(index)) {
            self.body_dims.push(BodyDims {
                at: self.stmt,
                mass: mass_dims.unwrap_or_default(),
                position: position_dims.into_iter().map(|(f, _)| f).collect(),
                angle: angle_dims,
                spatial,
            });
            let rotation = match (kind, inertia, angle) {
                _ if spatial => spatial_rotation,
                (BodyKind::Planar, Some(inertia), Some(angle)) => {
                    Some(Rotation::Planar { inertia, angle })
                }
                _ => None,
            };
            self.bodies.push(Body { name: normalize(&name.name), mass, position, rotation, span });
        }
    }

    fn constraint(&mut self, name: Option<&Ident>, lhs: &Expr, rhs: &Expr, span: Span) {
        let (l, r) = (self.value(lhs), self.value(rhs));
        let (Some((l, l_dims)), Some((r, r_dims))) = (l, r) else { return };
        self.warn_kinks(lhs, &l, &checks::CONSTRAINT);
        self.warn_kinks(rhs, &r, &checks::CONSTRAINT);
        // A vector constraint is one scalar constraint per component (`roll.x`, `roll.y`, …).
        let (ls, rs) = match (space::as_vector(&l), space::as_vector(&r), &l, &r) {
            (_, _, Value::Scalar(a), Value::Scalar(b)) => (vec![*a], vec![*b]),
            (Some(a), Some(b), _, _) if a.len() == b.len() => (a, b),
            _ => {
                self.error(
                    Diagnostic::error(
                        span,
                        format!(
                            "the sides of this constraint differ in shape: {} and {}",
                            l.kind_name(),
                            r.kind_name()
                        ),
                    )
                    .with_label("shapes do not fit")
                    .with_related(lhs.span, l.kind_name())
                    .with_related(rhs.span, r.kind_name()),
                );
                return;
            }
        };
        let vector = ls.len() > 1 || !matches!(l, Value::Scalar(_));
        let (lf, rf) = (self.operand(l_dims).forms(), self.operand(r_dims).forms());
        for (a, b) in lf.iter().zip(&rf) {
            self.units.same(a, b, lhs.span, rhs.span, "between the sides of this constraint");
        }
        let base = match name {
            Some(id) => normalize(&id.name),
            None => format!("constraint{}", self.constraints.len() + 1),
        };
        let mut indices = Vec::new();
        for (k, (l, r)) in ls.into_iter().zip(rs).enumerate() {
            let phi = self.pool.sub(l, r);
            if vector && self.pool.is_identically_zero(phi) {
                // A component that holds whatever the motion (the height of a ball's contact
                // with the floor it rolls on) restrains nothing.
                indices.push(None);
                continue;
            }
            let cname =
                if vector { format!("{base}.{}", ["x", "y", "z"][k.min(2)]) } else { base.clone() };
            let Some(kind) = self.constraint_kind(phi, span) else { return };
            let index = self.constraints.len();
            let force_symbol = self.pool.param(&format!("{cname}.force"));
            let lhs_free = self.pool.free_symbols(l);
            let lhs_coords = lhs_free
                .iter()
                .copied()
                .filter(|s| {
                    matches!(self.pool.symbol(*s).kind, SymbolKind::Coordinate { order: 0, .. })
                })
                .collect();
            self.placeholders.push((force_symbol, Placeholder::Reaction(index)));
            self.constraints.push(Constraint {
                name: cname,
                kind,
                lhs: l,
                rhs: r,
                phi,
                force_symbol,
                force_requested: false,
                lhs_coords,
                quaternion: None,
                span,
            });
            indices.push(Some(index));
        }
        if indices.iter().all(Option::is_none) {
            self.error(
                Diagnostic::error(span, "every component of this constraint always holds")
                    .with_label("nothing is restrained")
                    .with_hint("a constraint relates coordinates declared with `coord`"),
            );
            return;
        }
        if let Some(id) = name {
            self.bind(id, Binding::Constraint(indices));
        }
    }

    /// Whether Φ = 0 restrains positions or velocities; `None` (with the error reported) when
    /// it is neither: accelerations, rates not entering linearly, or no coordinate at all.
    fn constraint_kind(&mut self, phi: ExprId, span: Span) -> Option<ConstraintKind> {
        let free = self.pool.free_symbols(phi);
        if free.iter().any(|s| self.pool.symbol(*s).order() > 1) {
            self.error(
                Diagnostic::error(span, "this constraint involves accelerations")
                    .with_label("an acceleration appears here")
                    .with_hint("a constraint restrains positions, or velocities (rolling without slipping)"),
            );
            return None;
        }
        if !free.iter().any(|s| matches!(self.pool.symbol(*s).kind, SymbolKind::Coordinate { .. }))
        {
            self.error(
                Diagnostic::error(span, "this constraint involves no coordinate")
                    .with_label("nothing here can move")
                    .with_hint("a constraint relates coordinates declared with `coord`"),
            );
            return None;
        }
        let rates: Vec<SymId> =
            free.iter().copied().filter(|s| self.pool.symbol(*s).order() == 1).collect();
        if rates.is_empty() {
            return Some(ConstraintKind::Position);
        }
        // A(q, t)·q̇ + b(q, t): no rate may remain in a derivative by a rate.
        for v in &rates {
            let dv = self.pool.diff(phi, *v);
            let dv_free = self.pool.free_symbols(dv);
            if let Some(w) = dv_free.iter().find(|s| self.pool.symbol(**s).order() == 1) {
                let (v, w) = (self.pool.symbol(*v).name.clone(), self.pool.symbol(*w).name.clone());
                self.error(
                    Diagnostic::error(span, "this constraint is not linear in the rates")
                        .with_label(format!("the coefficient of {v} depends on {w}"))
                        .with_hint(
                            "a velocity constraint is A(q, t)·q' + b(q, t) = 0, as rolling without slipping is",
                        ),
                );
                return None;
            }
        }
        Some(ConstraintKind::Velocity)
    }

    fn load(
        &mut self,
        name: &Ident,
        body: &Ident,
        at: Option<&Expr>,
        value: &Expr,
        span: Span,
        torque: bool,
    ) {
        let key = normalize(&body.name);
        let index = match self.names.get(&key) {
            Some(Binding::Body(i)) => *i,
            _ => {
                let bodies: Vec<String> = self.bodies.iter().map(|b| b.name.clone()).collect();
                let mut d = Diagnostic::error(body.span, format!("no body named `{}`", body.name))
                    .with_label("not a particle or body");
                if let Some(near) = closest(&key, bodies.iter().map(String::as_str)) {
                    d = d.with_hint(format!("did you mean `{near}`?"));
                }
                self.error(d);
                return;
            }
        };
        let role = if torque { &TORQUE } else { &FORCE };
        let dim = self.bodies[index].position.len();
        let kind = self.bodies[index].kind();
        // The point a force acts at, when it is not the centre of mass.
        let mut point = None;
        if let Some(at) = at {
            if kind == BodyKind::Particle {
                self.error(
                    Diagnostic::error(at.span, "a particle is a point: a force on it acts there")
                        .with_label("a point of a particle")
                        .with_hint(format!(
                            "drop `at …`, or declare `{}` as a rigid `body`",
                            body.name
                        )),
                );
                return;
            }
            let Some((p, p_dims)) = self.value_in_role(at, &POSITION) else { return };
            match space::as_vector(&p).filter(|p| p.len() == dim) {
                Some(p) => point = Some((p, self.shape(p_dims).forms())),
                None => {
                    self.error(
                        Diagnostic::error(
                            at.span,
                            format!("expected a point, a {dim}-vector, found {}", p.kind_name()),
                        )
                        .with_label("not a point")
                        .with_hint("give the point in world axes, like the body's position"),
                    );
                    return;
                }
            }
        }
        let Some((v, dims)) = self.value_in_role(value, role) else { return };
        let v = match v {
            // `R*v` and written columns alike.
            Value::Matrix(_) => space::as_vector(&v).map(Value::Vector).unwrap_or(v),
            v => v,
        };
        self.load_energy(index, dims, value.span, torque, point.as_ref().map(|(_, f)| f.clone()));
        let ok = match (&v, torque) {
            (Value::Scalar(_), true) => kind == BodyKind::Planar,
            (Value::Vector(c), true) => kind == BodyKind::Spatial && c.len() == 3,
            (Value::Vector(c), false) => c.len() == dim,
            (Value::Scalar(_), false) => dim == 1,
            _ => false,
        };
        if torque && self.bodies[index].kind() == BodyKind::Particle {
            self.error(
                Diagnostic::error(
                    body.span,
                    format!("`{}` is a particle, and a torque needs a rigid body", body.name),
                )
                .with_label("a particle has no orientation")
                .with_hint("declare it with `body`, with an `inertia` and an `angle`"),
            );
            return;
        }
        if !ok {
            let expected = if torque && kind == BodyKind::Spatial {
                "a torque vector `(tx, ty, tz)` in world axes on a body in space".to_string()
            } else if torque {
                "a scalar torque on a rigid `body`".to_string()
            } else {
                format!("a {dim}-vector, like the body's position")
            };
            self.error(
                Diagnostic::error(
                    value.span,
                    format!("expected {expected}, found {}", v.kind_name()),
                )
                .with_label("here"),
            );
            return;
        }
        let at = point.map(|(p, _)| p);
        let load = Load { name: normalize(&name.name), body: index, value: v, at, span };
        if torque {
            self.torques.push(load);
        } else {
            self.forces.push(load);
        }
    }

    /// A value written with a unit, converted to SI (`30 deg` is π/6, `10 cm` is 1/10).
    fn in_si(&mut self, value: cas::ExprId, unit: Option<&lang::Unit>) -> Option<cas::ExprId> {
        let Some(unit) = unit else { return Some(value) };
        match crate::units::parse_unit(unit) {
            Ok((_, scale)) => {
                let k = self.pool.num(scale.rational);
                let pi = self.pool.pi();
                let pi = self.pool.powi(pi, i64::from(scale.pi_power));
                Some(self.pool.mul(&[value, k, pi]))
            }
            Err(d) => {
                self.error(d);
                None
            }
        }
    }

    /// Where a spring or damper is attached: a body (its centre of mass) or a fixed point;
    /// with the dimensions of its coordinates.
    fn anchor(&mut self, e: &Expr, role: &Role) -> Option<(Vec<cas::ExprId>, Vec<Form>)> {
        if let ExprKind::Name { name, primes: 0 } = &e.kind {
            if let Some(Binding::Body(i)) = self.names.get(&normalize(name)) {
                let i = *i;
                return Some((self.bodies[i].position.clone(), self.body_dims[i].position.clone()));
            }
        }
        let (value, dims) = self.value_in_role(e, role)?;
        let forms = self.shape(dims).forms();
        match value {
            Value::Vector(v) => Some((v, forms)),
            other => {
                self.error(
                    Diagnostic::error(e.span, format!("expected a body or a point, found {}", other.kind_name()))
                        .with_label("not an attachment")
                        .with_hint("attach to a `particle` or `body` by name, or to a fixed point such as (0, 0)"),
                );
                None
            }
        }
    }

    /// B − A for two attachments, padding the shorter with zeros (a 2D point in 3D), with the
    /// dimension of its length and the two ends as written (for drawing).
    fn separation(&mut self, a: &Expr, b: &Expr, role: &Role) -> Option<Separation> {
        let (pa, pb) = (self.anchor(a, role), self.anchor(b, role));
        let (Some((pa, mut ends)), Some((pb, b_ends))) = (pa, pb) else { return None };
        ends.extend(b_ends);
        let length = self.separation_dims(ends, a.span, b.span);
        let n = pa.len().max(pb.len());
        let zero = self.pool.zero();
        let difference = (0..n)
            .map(|i| self.pool.sub(*pb.get(i).unwrap_or(&zero), *pa.get(i).unwrap_or(&zero)))
            .collect();
        Some(Separation { difference, length, ends: [pa, pb] })
    }

    /// |B − A|², with the separation it is of.
    fn separation_squared(
        &mut self,
        a: &Expr,
        b: &Expr,
        role: &Role,
    ) -> Option<(cas::ExprId, Separation)> {
        let separation = self.separation(a, b, role)?;
        let squares: Vec<cas::ExprId> =
            separation.difference.iter().map(|x| self.pool.powi(*x, 2)).collect();
        Some((self.pool.add(&squares), separation))
    }

    /// A scalar that may not depend on coordinates or time (initial values, parameter values).
    fn constant(&mut self, e: &Expr) -> Option<(cas::ExprId, Dims)> {
        let (v, dims) = self.scalar(e)?;
        let moving = self
            .pool
            .free_symbols(v)
            .iter()
            .any(|s| !matches!(self.pool.symbol(*s).kind, SymbolKind::Param));
        if moving {
            self.error(
                Diagnostic::error(e.span, "this value must be a constant")
                    .with_label("depends on a coordinate or on time")
                    .with_hint(
                        "initial values and parameter values may use numbers and parameters only",
                    ),
            );
            return None;
        }
        self.finite(v, e).then_some((v, dims))
    }

    /// [`Self::value`], refused when it has derivatives its role does not allow.
    fn value_in_role(&mut self, e: &Expr, role: &Role) -> Option<(Value, Dims)> {
        let (v, dims) = self.value(e)?;
        let within = self.within_role(e, &v, role);
        if within {
            self.warn_kinks(e, &v, role);
        }
        within.then_some((v, dims))
    }

    /// [`Self::scalar`], refused when it has derivatives its role does not allow.
    fn scalar_in_role(&mut self, e: &Expr, role: &Role) -> Option<(cas::ExprId, Dims)> {
        let (v, dims) = self.scalar(e)?;
        let within = self.within_role(e, &Value::Scalar(v), role);
        if within {
            self.warn_kinks(e, &Value::Scalar(v), role);
        }
        within.then_some((v, dims))
    }

    fn scalar(&mut self, e: &Expr) -> Option<(cas::ExprId, Dims)> {
        match self.value(e)? {
            (Value::Scalar(x), dims) => Some((x, dims)),
            (other, _) => {
                self.error(
                    Diagnostic::error(
                        e.span,
                        format!("expected a scalar, found {}", other.kind_name()),
                    )
                    .with_label("not a scalar"),
                );
                None
            }
        }
    }

    /// The value of `e`, and what is known of its dimension.
    fn value(&mut self, e: &Expr) -> Option<(Value, Dims)> {
        match &e.kind {
            ExprKind::Number(text) => match cas::number::parse_decimal(text) {
                Some(q) => {
                    let v = self.pool.num(q);
                    Some((Value::Scalar(v), self.number_dims(v, true)))
                }
                None => {
                    self.error(
                        Diagnostic::error(
                            e.span,
                            format!("`{text}` is not a number lagrange can use"),
                        )
                        .with_label("out of range")
                        .with_hint("exponents beyond ±4000 are not supported"),
                    );
                    None
                }
            },
            ExprKind::Name { name, primes } => self.name(name, *primes, e.span),
            ExprKind::Member { object, field, component: None } => {
                self.member(object, field, e.span)
            }
            // `roll.x.force`, as reports name a component's reaction, is `roll.force.x`.
            ExprKind::Member { object, field, component: Some(c) }
                if c.name == "force"
                    && matches!(field.name.as_str(), "x" | "y" | "z")
                    && matches!(
                        self.names.get(&normalize(&object.name)),
                        Some(Binding::Constraint(_))
                    ) =>
            {
                let (v, dims) = self.member(object, c, e.span)?;
                self.component(v, dims, field, &format!("{}.force", object.name))
            }
            ExprKind::Member { object, field, component: Some(c) } => {
                let (v, dims) = self.member(object, field, e.span)?;
                self.component(v, dims, c, &format!("{}.{}", object.name, field.name))
            }
            ExprKind::Call { func, args } => self.call(func, args, e.span),
            ExprKind::Neg(inner) => {
                let (v, dims) = self.value(inner)?;
                let v = v.map(|x| self.pool.neg(x));
                let dims = match (dims, &v) {
                    (Dims::Number { decided, .. }, Value::Scalar(x)) => {
                        self.number_dims(*x, decided)
                    }
                    (dims, _) => dims,
                };
                Some((v, dims))
            }
            ExprKind::Binary { op, lhs, rhs } => {
                if let (BinOp::Mul | BinOp::Div, ExprKind::Neg(inner)) = (op, &lhs.kind) {
                    // `-a*b` is built as −(a·b), the product it prints back from: as (−a)·b a
                    // sum a would take the sign into its terms, `-(y + z)*x` would read back as
                    // `(-y - z)*x`, and print so.
                    let product = Expr {
                        kind: ExprKind::Binary { op: *op, lhs: inner.clone(), rhs: rhs.clone() },
                        span: Span { start: inner.span.start, end: rhs.span.end },
                    };
                    let negated = Expr { kind: ExprKind::Neg(Box::new(product)), span: e.span };
                    return self.value(&negated);
                }
                let (l, r) = (self.value(lhs), self.value(rhs));
                let ((l, l_dims), (r, r_dims)) = (l?, r?);
                let v = self.binary(*op, l, r, lhs, rhs)?;
                let dims = self.binary_dims(*op, (l_dims, r_dims), lhs, rhs, &v);
                Some((v, dims))
            }
            ExprKind::Tuple(items) => {
                let mut out = Vec::new();
                for item in items {
                    out.push(self.scalar(item));
                }
                let (out, dims): (Vec<_>, Vec<_>) =
                    out.into_iter().collect::<Option<Vec<_>>>()?.into_iter().unzip();
                let forms = dims.into_iter().map(|d| self.operand_form(d)).collect();
                Some((Value::Vector(out), Dims::Many(forms)))
            }
            ExprKind::Matrix(rows) => {
                let mut out = Vec::new();
                for row in rows {
                    let mut r = Vec::new();
                    for item in row {
                        r.push(self.scalar(item));
                    }
                    out.push(r.into_iter().collect::<Option<Vec<_>>>());
                }
                let out = out.into_iter().collect::<Option<Vec<_>>>()?;
                let (out, grid): (Vec<Vec<_>>, Vec<Vec<_>>) =
                    out.into_iter().map(|row| row.into_iter().unzip()).unzip();
                let width = out.first().map_or(0, |r| r.len());
                if out.iter().any(|r| r.len() != width) {
                    self.error(
                        Diagnostic::error(e.span, "the rows of this matrix have different lengths")
                            .with_label("ragged matrix")
                            .with_hint("separate entries with `,` and rows with `;`"),
                    );
                    return None;
                }
                Some((Value::Matrix(out), Dims::Grid(grid)))
            }
        }
    }

    fn name(&mut self, raw: &str, primes: u8, span: Span) -> Option<(Value, Dims)> {
        let value = self.name_value(raw, primes, span)?;
        let name = normalize(raw);
        let dims = match (name.as_str(), &value) {
            ("t", _) if !self.names.contains_key("t") => Dims::Scalar(crate::units::time()),
            ("pi", Value::Scalar(pi)) if !self.names.contains_key("pi") && primes == 0 => {
                self.number_dims(*pi, true)
            }
            ("pi", _) if !self.names.contains_key("pi") => {
                Dims::Scalar(Form::default().rate(primes))
            }
            _ => self.name_dims(raw, &name, primes),
        };
        if let Dims::Scalar(f) = &dims {
            self.units.used(f, span);
        }
        Some((value, dims))
    }

    fn name_value(&mut self, raw: &str, primes: u8, span: Span) -> Option<Value> {
        let name = normalize(raw);
        self.used.insert(name.clone());
        let base = match name.as_str() {
            "t" if !self.names.contains_key("t") => {
                if primes > 0 {
                    self.error(
                        Diagnostic::error(span, "`t` is time; it has no rate")
                            .with_label("t' is always 1")
                            .with_hint("write `1`"),
                    );
                    return None;
                }
                return Some(Value::Scalar(self.pool.sym(self.time)));
            }
            "pi" if !self.names.contains_key("pi") => Value::Scalar(self.pool.pi()),
            _ => match self.names.get(&name).cloned() {
                Some(Binding::Param(s)) => {
                    if primes > 0 {
                        self.error(
                            Diagnostic::error(
                                span,
                                format!("`{raw}` is a parameter, constant in time"),
                            )
                            .with_label("has no rate")
                            .with_hint(format!("declare it with `coord {raw}` if it moves")),
                        );
                        return None;
                    }
                    Value::Scalar(self.pool.sym(s))
                }
                // KE stands for an expression only derived later; its rates are symbols of
                // their own (see `total_rate`), taken below as a `let` name's are.
                Some(Binding::Quantity(s)) => Value::Scalar(self.pool.sym(s)),
                Some(Binding::Coord(s)) => {
                    if primes > 2 {
                        let base = self.pool.symbol(s).name.clone();
                        self.past_acceleration(span, primes, &base, true);
                        return None;
                    }
                    let d = self.pool.derivative_symbol(s, primes).expect("coordinates have rates");
                    return Some(Value::Scalar(self.pool.sym(d)));
                }
                Some(Binding::Let(v)) => v,
                Some(Binding::Body(_)) | Some(Binding::Constraint(_)) => {
                    let what = if matches!(self.names.get(&name), Some(Binding::Body(_))) {
                        "a body: write `NAME.position`, `NAME.velocity` or `NAME.omega`"
                    } else {
                        "a constraint: write `NAME.force` for its reaction"
                    };
                    self.error(
                        Diagnostic::error(span, format!("`{raw}` is not a value"))
                            .with_label("names a body or constraint")
                            .with_hint(format!("`{raw}` is {what}")),
                    );
                    return None;
                }
                None => {
                    self.unknown_name(raw, &name, span);
                    return None;
                }
            },
        };
        if primes == 0 {
            return Some(base);
        }
        if !self.derivative_exists(&base, primes, span) {
            return None;
        }
        // A rate of a `let` name or a quantity: the total time derivative.
        Some(base.map(|mut x| {
            for _ in 0..primes {
                x = self.total_rate(x, span);
            }
            x
        }))
    }

    fn unknown_name(&mut self, raw: &str, name: &str, span: Span) {
        if let Some((decl, what)) = self.declared.get(name).copied() {
            if decl.start > span.start && !self.in_outputs {
                self.error(
                    Diagnostic::error(
                        span,
                        format!("the {what} `{raw}` is used before it is declared"),
                    )
                    .with_label("used here")
                    .with_related(decl, "declared here")
                    .with_hint(format!("move the declaration of `{raw}` above its first use")),
                );
                return;
            }
            // Declared, but its declaration had an error of its own: already reported.
            return;
        }
        let mut candidates: Vec<&str> = self.names.keys().map(String::as_str).collect();
        candidates.extend(["t", "pi"]);
        candidates.sort_unstable();
        let mut d =
            Diagnostic::error(span, format!("unknown name `{raw}`")).with_label("not declared");
        d = match closest(name, candidates) {
            Some(near) => d.with_hint(format!("did you mean `{near}`?")),
            None => d.with_hint(format!(
                "declare it first: `coord {raw}` for a coordinate, `param {raw}` for a constant, `let {raw} = …` for a name"
            )),
        };
        self.error(d);
    }

    fn member(&mut self, object: &Ident, field: &Ident, span: Span) -> Option<(Value, Dims)> {
        if let Some(Binding::Let(v)) = self.names.get(&normalize(&object.name)) {
            if !matches!(v, Value::Scalar(_)) {
                // A component of a vector `let`.
                let (v, dims) = self.name(&object.name, 0, object.span)?;
                return self.component(v, dims, field, &object.name);
            }
        }
        let value = self.member_value(object, field, span)?;
        let body = match self.names.get(&normalize(&object.name)) {
            Some(Binding::Body(i)) => Some(*i),
            _ => None,
        };
        Some((value, self.member_dims(object, field, body)))
    }

    fn member_value(&mut self, object: &Ident, field: &Ident, span: Span) -> Option<Value> {
        let name = normalize(&object.name);
        match self.names.get(&name).cloned() {
            Some(Binding::Body(i)) => {
                let body = self.bodies[i].clone();
                let fields: &[&str] = match body.kind() {
                    BodyKind::Particle => &["position", "velocity", "mass", "x", "y", "z"],
                    BodyKind::Planar => {
                        &["position", "velocity", "mass", "angle", "omega", "x", "y", "z"]
                    }
                    BodyKind::Spatial => &[
                        "position",
                        "velocity",
                        "mass",
                        "omega",
                        "omega_body",
                        "axes",
                        "x",
                        "y",
                        "z",
                    ],
                };
                if let Some(rotation @ Rotation::Spatial { orientation, .. }) = &body.rotation {
                    let orientation = *orientation;
                    let pool = &mut self.pool;
                    let spatial = match field.name.as_str() {
                        "omega" | "omega_body" => {
                            let world = field.name == "omega";
                            rotation
                                .spatial_angular_velocity(pool, world)
                                .map(|w| Value::Vector(w.to_vec()))
                        }
                        "axes" => Some(Value::Matrix(crate::kinematics::rows(&orientation))),
                        _ => None,
                    };
                    if spatial.is_some() {
                        return spatial;
                    }
                }
                let value = match field.name.as_str() {
                    "position" => Some(Value::Vector(body.position.clone())),
                    "velocity" => Some(Value::Vector(
                        body.position.iter().map(|x| self.pool.time_derivative(*x)).collect(),
                    )),
                    "mass" => Some(Value::Scalar(body.mass)),
                    "angle" => body.angle().map(Value::Scalar),
                    "omega" => body.angle().map(|a| Value::Scalar(self.pool.time_derivative(a))),
                    "x" => body.position.first().map(|x| Value::Scalar(*x)),
                    "y" => body.position.get(1).map(|x| Value::Scalar(*x)),
                    "z" => body.position.get(2).map(|x| Value::Scalar(*x)),
                    _ => None,
                };
                let value = match field.name.as_str() {
                    "angle" if body.kind() == BodyKind::Spatial => None,
                    _ => value,
                };
                if value.is_none() {
                    let mut d = Diagnostic::error(
                        field.span,
                        format!("`{}` has no `{}`", object.name, field.name),
                    )
                    .with_label(format!("expected one of {}", fields.join(", ")));
                    if body.kind() == BodyKind::Spatial && field.name == "angle" {
                        d = d.with_hint(
                            "a body turning in space has no single angle: its orientation is \
                             `axes`, its angular velocity `omega` (world axes) or `omega_body`",
                        );
                    } else if body.kind() == BodyKind::Particle
                        && matches!(field.name.as_str(), "omega" | "angle")
                    {
                        d = d.with_hint(
                            "a particle has no orientation; declare a rigid `body` with an `angle`",
                        );
                    } else if let Some(near) = closest(&field.name, fields.iter().copied()) {
                        d = d.with_hint(format!("did you mean `{near}`?"));
                    }
                    self.error(d);
                }
                value
            }
            Some(Binding::Constraint(components)) => {
                if field.name != "force" {
                    self.error(
                        Diagnostic::error(
                            field.span,
                            format!("a constraint has no `{}`", field.name),
                        )
                        .with_label("expected `force`")
                        .with_hint(format!("`{}.force` is its reaction", object.name)),
                    );
                    return None;
                }
                if self.in_drawing {
                    self.error(
                        Diagnostic::error(span, "a reaction cannot be drawn")
                            .with_label("a force, not a point")
                            .with_hint(
                                "a `draw` line places shapes with positions, which may use the \
                                 coordinates, their rates and `t`",
                            ),
                    );
                    return None;
                }
                if !self.in_outputs {
                    self.error(
                        Diagnostic::error(span, "a reaction can only be shown or checked")
                            .with_label("used in the model itself")
                            .with_hint("use `.force` in `show` and `expect` lines"),
                    );
                    return None;
                }
                let mut forces = Vec::new();
                for component in &components {
                    forces.push(match component {
                        Some(i) => {
                            self.constraints[*i].force_requested = true;
                            self.pool.sym(self.constraints[*i].force_symbol)
                        }
                        // A component that always holds exerts nothing.
                        None => self.pool.zero(),
                    });
                }
                // A vector constraint's reaction is the vector of its components' reactions.
                let vector = components.len() > 1
                    || components.iter().flatten().any(|i| self.constraints[*i].name.contains('.'));
                match vector {
                    false => Some(Value::Scalar(forces[0])),
                    true => Some(Value::Vector(forces)),
                }
            }
            _ => {
                if self.declared.contains_key(&name) {
                    // Declared but failed to resolve: already reported.
                    return None;
                }
                let mut candidates: Vec<&str> = self
                    .names
                    .iter()
                    .filter(|(_, b)| matches!(b, Binding::Body(_) | Binding::Constraint(_)))
                    .map(|(k, _)| k.as_str())
                    .collect();
                candidates.sort_unstable();
                let mut d = Diagnostic::error(
                    object.span,
                    format!("no body or constraint named `{}`", object.name),
                )
                .with_label("unknown");
                if let Some(near) = closest(&name, candidates) {
                    d = d.with_hint(format!("did you mean `{near}`?"));
                }
                self.error(d);
                None
            }
        }
    }

    fn call(&mut self, func: &Ident, args: &[Expr], span: Span) -> Option<(Value, Dims)> {
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
            "atan2" => self.pool.atan2(xs[0], xs[1]),
            "sqrt" => self.pool.sqrt(xs[0]),
            // (a + b ∓ |a − b|)/2: no node of their own, so everything that knows `abs`
            // (derivatives, numbers, printing, SymPy) knows them.
            "min" | "max" => {
                let sum = self.pool.add2(xs[0], xs[1]);
                let gap = self.pool.sub(xs[0], xs[1]);
                let mut gap = self.pool.func(Func::Abs, gap);
                if name == "min" {
                    gap = self.pool.neg(gap);
                }
                let twice = self.pool.add2(sum, gap);
                let half = self.pool.num(cas::Rational::new(1.into(), 2.into()));
                self.pool.mul2(half, twice)
            }
            _ => self.pool.func(Func::from_name(name).expect("checked above"), xs[0]),
        };
        let dims = self.call_dims(name, arg_dims, args, v);
        Some((Value::Scalar(v), dims))
    }

    fn binary(&mut self, op: BinOp, l: Value, r: Value, le: &Expr, re: &Expr) -> Option<Value> {
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
                        self.pool.add2(a, b)
                    } else {
                        self.pool.sub(a, b)
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
                (Scalar(a), Scalar(b)) => Some(Scalar(self.pool.mul2(*a, *b))),
                (Scalar(s), other) | (other, Scalar(s)) => {
                    let s = *s;
                    Some(other.map(|x| self.pool.mul2(s, x)))
                }
                (Matrix(a), Matrix(b)) if a[0].len() == b.len() => {
                    Some(Matrix(crate::kinematics::product(&mut self.pool, a, b)))
                }
                // R*v: a vector in the rotated axes carried into the fixed ones.
                (Matrix(a), Vector(v)) if a[0].len() == v.len() => {
                    Some(Vector(crate::kinematics::apply(&mut self.pool, a, v)))
                }
                _ => mismatch(self, "multiply"),
            },
            BinOp::Div => match (&l, &r) {
                (_, Scalar(b)) => {
                    if self.pool.is_zero(*b) {
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
                    Some(l.map(|x| self.pool.div(x, b)))
                }
                _ => mismatch(self, "divide"),
            },
            BinOp::Pow => match (&l, &r) {
                (Scalar(a), Scalar(b)) => {
                    if let Some(q) = self.pool.as_num(*b) {
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
                        if self.pool.is_zero(*a) && q < &Rational::from_integer(0.into()) {
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
                    Some(Scalar(self.pool.pow(*a, *b)))
                }
                _ => mismatch(self, "raise to a power"),
            },
        }
    }

    fn finish(mut self, checks: Checks) -> Result<(Model, Vec<Diagnostic>), Vec<Diagnostic>> {
        for p in &self.params {
            if !self.used.contains(&p.name) {
                self.warnings.push(
                    Diagnostic::warning(p.span, format!("parameter `{}` is never used", p.name))
                        .with_label("declared here")
                        .with_hint(
                            "remove it, or check the spelling where it was meant to be used",
                        ),
                );
            }
        }
        if !self.errors.is_empty() {
            let mut errors = self.errors;
            errors.sort_by_key(|d| d.span.start);
            return Err(errors);
        }
        if checks.units {
            let mismatches = self.units.solve();
            if !mismatches.is_empty() {
                return Err(mismatches);
            }
        }
        let scope = Scope {
            names: self.names,
            declared: self.declared,
            used: self.used,
            param_values: self.param_values,
            statements: self.stmt + 1,
            units: self.units,
            name_dims: self.name_dims,
            body_dims: self.body_dims,
            loose: self.loose,
            quaternions: self.quaternions,
            checks,
        };
        Ok((
            Model {
                scope,
                pool: self.pool,
                title: self.title,
                time: self.time,
                params: self.params,
                coords: self.coords,
                bodies: self.bodies,
                constraints: self.constraints,
                gravity: self.gravity,
                potentials: self.potentials,
                forces: self.forces,
                torques: self.torques,
                dissipation: self.dissipation,
                lagrangians: self.lagrangians,
                shows: self.shows,
                expects: self.expects,
                drawings: self.drawings,
                links: self.links,
                simulate: self.simulate,
                linearize: self.linearize,
                placeholders: self.placeholders,
                lets: self.lets,
            },
            self.warnings,
        ))
    }
}

/// What resolving a scene leaves behind for resolving more expressions against it later: its
/// names and what they are bound to, the dimension facts and the values of its parameters.
/// A [`Model`] keeps it, for [`Model::resolve_expression`] and [`Model::resolve_about`].
pub struct Scope {
    names: HashMap<String, Binding>,
    declared: HashMap<String, (Span, &'static str)>,
    used: std::collections::HashSet<String>,
    param_values: HashMap<SymId, ExprId>,
    /// The statements resolved so far, the scene's and the expressions' since.
    statements: usize,
    units: Inference,
    name_dims: HashMap<String, NameDims>,
    body_dims: Vec<BodyDims>,
    loose: HashMap<String, Form>,
    quaternions: Vec<(Vec<Vec<ExprId>>, [ExprId; 4], Span)>,
    checks: Checks,
}

impl Model {
    /// Resolves `text`, one expression, against the scene as a `show` item would be (it may
    /// name anything the scene declares, reactions included, which marks them requested for
    /// the derivation). On failure, the diagnostics, with spans into `text`.
    pub fn resolve_expression(&mut self, text: &str) -> Result<Value, Vec<Diagnostic>> {
        let expr = lang::parse_expression(text)?;
        self.resolving(text, |r| r.value(&expr).map(|(v, _)| v))
    }

    /// Resolves `text`, the items of a reference (`theta = 0, phi' = 2`), against the scene as
    /// a `linearize about` line after the scene's own, which it overrides item by item. On
    /// failure, the diagnostics, with spans into `text`.
    pub fn resolve_about(&mut self, text: &str) -> Result<(), Vec<Diagnostic>> {
        let items = lang::parse_about(text)?;
        self.resolving(text, |r| {
            r.linearize(&items, Span::new(0, text.len()));
            Some(())
        })
    }

    /// Runs `resolve` on a resolver with the model's state and its scope, `text` the source
    /// its spans point into; the model takes back what it added, or the errors if any.
    fn resolving<T>(
        &mut self,
        text: &str,
        resolve: impl FnOnce(&mut Resolver<'_>) -> Option<T>,
    ) -> Result<T, Vec<Diagnostic>> {
        let mut r = Resolver::resume(self, text);
        let mark = r.units.mark();
        let index = r.stmt + 1;
        r.enter(index);
        let value = resolve(&mut r);
        let mut errors = std::mem::take(&mut r.errors);
        if errors.is_empty() && r.checks.units {
            errors = r.units.solve();
        }
        if !errors.is_empty() {
            r.units.rollback(mark);
        }
        r.suspend(self);
        match value {
            Some(value) if errors.is_empty() => Ok(value),
            _ => {
                errors.sort_by_key(|d| d.span.start);
                if errors.is_empty() {
                    errors.push(Diagnostic::error(Span::new(0, text.len()), "cannot be resolved"));
                }
                Err(errors)
            }
        }
    }
}

impl<'a> Resolver<'a> {
    /// A resolver that goes on from where `model` was left, reading `source`.
    fn resume(model: &mut Model, source: &'a str) -> Resolver<'a> {
        let mut r = Resolver::new(source);
        std::mem::swap(&mut r.pool, &mut model.pool);
        r.title = model.title.take();
        r.time = model.time;
        r.params = std::mem::take(&mut model.params);
        r.coords = std::mem::take(&mut model.coords);
        r.bodies = std::mem::take(&mut model.bodies);
        r.constraints = std::mem::take(&mut model.constraints);
        r.gravity = model.gravity.take();
        r.potentials = std::mem::take(&mut model.potentials);
        r.forces = std::mem::take(&mut model.forces);
        r.torques = std::mem::take(&mut model.torques);
        r.dissipation = std::mem::take(&mut model.dissipation);
        r.lagrangians = std::mem::take(&mut model.lagrangians);
        r.shows = std::mem::take(&mut model.shows);
        r.expects = std::mem::take(&mut model.expects);
        r.drawings = std::mem::take(&mut model.drawings);
        r.links = std::mem::take(&mut model.links);
        r.simulate = std::mem::take(&mut model.simulate);
        r.linearize = std::mem::take(&mut model.linearize);
        r.placeholders = std::mem::take(&mut model.placeholders);
        r.lets = std::mem::take(&mut model.lets);
        let scope = &mut model.scope;
        r.names = std::mem::take(&mut scope.names);
        r.declared = std::mem::take(&mut scope.declared);
        r.used = std::mem::take(&mut scope.used);
        r.param_values = std::mem::take(&mut scope.param_values);
        r.stmt = scope.statements;
        r.units = std::mem::take(&mut scope.units);
        r.name_dims = std::mem::take(&mut scope.name_dims);
        r.body_dims = std::mem::take(&mut scope.body_dims);
        r.loose = std::mem::take(&mut scope.loose);
        r.quaternions = std::mem::take(&mut scope.quaternions);
        r.checks = scope.checks;
        r.in_outputs = true;
        r
    }

    /// Gives `model` back what [`Resolver::resume`] took, with what was added since.
    fn suspend(self, model: &mut Model) {
        model.pool = self.pool;
        model.title = self.title;
        model.params = self.params;
        model.coords = self.coords;
        model.bodies = self.bodies;
        model.constraints = self.constraints;
        model.gravity = self.gravity;
        model.potentials = self.potentials;
        model.forces = self.forces;
        model.torques = self.torques;
        model.dissipation = self.dissipation;
        model.lagrangians = self.lagrangians;
        model.shows = self.shows;
        model.expects = self.expects;
        model.drawings = self.drawings;
        model.links = self.links;
        model.simulate = self.simulate;
        model.linearize = self.linearize;
        model.placeholders = self.placeholders;
        model.lets = self.lets;
        model.scope = Scope {
            names: self.names,
            declared: self.declared,
            used: self.used,
            param_values: self.param_values,
            statements: self.stmt + 1,
            units: self.units,
            name_dims: self.name_dims,
            body_dims: self.body_dims,
            loose: self.loose,
            quaternions: self.quaternions,
            checks: self.checks,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_are_close_names() {
        assert_eq!(closest("thta", ["theta", "phi", "x"]), Some("theta"));
        assert_eq!(closest("q", ["theta", "phi"]), None);
        assert_eq!(closest("y", ["L", "x"]), None);
        assert_eq!(closest("l", ["L", "x"]), Some("L"));
    }

    #[test]
    fn greek_letters_are_spelled_out() {
        assert_eq!(normalize("θ"), "theta");
        assert_eq!(normalize("φ1"), "phi1");
        assert_eq!(normalize("x"), "x");
    }
}
