//! Name resolution and the meaning of each statement: AST in, [`Model`] out.

mod bodies;
mod calls;
mod checks;
mod constraints;
mod dims;
mod draw;
mod expressions;
mod inertia;
mod loads;
mod names;
mod session;
mod signals;
mod simulation;
mod space;
mod statements;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Ident, SceneFile, Span, StmtKind};

pub use self::session::Scope;
pub use self::simulation::{constant_value, time_setting};
use crate::units::Form;
use crate::{
    Body, Checks, Constraint, Contact, Coord, Drawing, Expect, Gravity, Input, LinearExpect,
    Linearize, Link, Load, Model, Output, Param, Placeholder, Show, Simulation, Term, Value,
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
    Input(SymId),
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
    RESOLUTIONS.with(|n| n.set(n.get() + 1));
    walk(file, source).finish(checks)
}

thread_local! {
    static RESOLUTIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// How many scenes this thread has resolved so far. A command should resolve its scene once
/// (a second resolution costs a short run's set-up again, and may read the text differently
/// from the first); the workspace's tests count each command's resolutions with it. Per
/// thread, so that tests running side by side do not count each other's.
pub fn resolutions_on_this_thread() -> usize {
    RESOLUTIONS.with(|n| n.get())
}

/// Checks that every term of the scene has one dimension. Returns the mismatches found, from
/// as much of the scene as resolves.
pub fn dimension_errors(file: &SceneFile) -> Vec<Diagnostic> {
    walk(file, "").scope.units.solve()
}

fn walk<'a>(file: &SceneFile, source: &'a str) -> Resolver<'a> {
    let mut r = Resolver::new(source);
    r.declare_all(file);
    let numbered = file.stmts.iter().enumerate();
    let (outputs, statements): (Vec<_>, Vec<_>) = numbered.partition(|(_, s)| {
        matches!(
            s.kind,
            StmtKind::Show { .. }
                | StmtKind::Output { .. }
                | StmtKind::Expect { .. }
                | StmtKind::ExpectLinearized(_)
                | StmtKind::Linearize(_)
                | StmtKind::Draw(_)
        )
    });
    for (i, stmt) in statements {
        r.enter(i);
        r.statement(stmt);
    }
    // Show, output, expect, linearize and draw lines may name anything in the file, wherever they stand.
    r.in_outputs = true;
    for (i, stmt) in outputs {
        r.enter(i);
        r.statement(stmt);
    }
    r.require_a_coordinate(file);
    r.hold_needs_a_law();
    r
}

/// The Greek letters of a name spelled out, so `θ` and `theta` are the same name.
fn normalize(name: &str) -> String {
    name.chars()
        .map(|c| cas::greek_word(c).map(str::to_string).unwrap_or_else(|| c.to_string()))
        .collect()
}

/// The closest candidate within a small edit distance: the "did you mean" of a misspelt name,
/// for every stage that suggests one.
pub fn closest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
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

/// The walk over a scene: where it is, and its state in three parts, so that a method's
/// signature of use shows what it reads and writes: the [`Scope`] (what names mean, the
/// dimension facts, the parameters' values), the [`Draft`] of the model, and the
/// [`Diagnostics`] found.
struct Resolver<'a> {
    /// The text the spans point into.
    source: &'a str,
    scope: Scope,
    model: Draft,
    diagnostics: Diagnostics,
    /// The statement being resolved, by its place in the file.
    stmt: usize,
    /// Resolving `show`, `expect`, `linearize` and `draw` lines, which may name anything in
    /// the file wherever they stand.
    in_outputs: bool,
    /// Resolving a `draw` line, where a reaction may not be named: asking for one would change
    /// the derivation, and a drawing must leave the equations as they are.
    in_drawing: bool,
}

/// The errors and warnings found so far.
#[derive(Default)]
struct Diagnostics {
    errors: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    /// Inputs in constraints: errors unless the checks let them stand ([`Checks`]).
    inputs_in_constraints: Vec<(SymId, Diagnostic)>,
}

/// The model under construction: a [`Model`] but for its scope, field by field.
struct Draft {
    pool: Pool,
    time: SymId,
    title: Option<String>,
    params: Vec<Param>,
    inputs: Vec<Input>,
    outputs: Vec<Output>,
    coords: Vec<Coord>,
    bodies: Vec<Body>,
    constraints: Vec<Constraint>,
    contacts: Vec<Contact>,
    gravity: Option<Gravity>,
    potentials: Vec<Term>,
    forces: Vec<Load>,
    torques: Vec<Load>,
    dissipation: Vec<Term>,
    lagrangians: Vec<Term>,
    shows: Vec<Show>,
    expects: Vec<Expect>,
    linear_expects: Vec<LinearExpect>,
    drawings: Vec<Drawing>,
    links: Vec<Link>,
    simulation: Simulation,
    linearize: Vec<Linearize>,
    placeholders: Vec<(SymId, Placeholder)>,
    lets: Vec<(String, cas::ExprId)>,
}

impl Draft {
    /// An empty model with its pool, time, and the placeholders `KE` and `PE`.
    fn new() -> Draft {
        let mut pool = Pool::new();
        pool.set_zero_test(Box::new(numeric::GenericPoints));
        let time = pool.time();
        let placeholders =
            [("KE", Placeholder::KineticEnergy), ("PE", Placeholder::PotentialEnergy)]
                .map(|(name, kind)| (pool.param(name), kind))
                .to_vec();
        Draft {
            pool,
            time,
            title: None,
            params: Vec::new(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            coords: Vec::new(),
            bodies: Vec::new(),
            constraints: Vec::new(),
            contacts: Vec::new(),
            gravity: None,
            potentials: Vec::new(),
            forces: Vec::new(),
            torques: Vec::new(),
            dissipation: Vec::new(),
            lagrangians: Vec::new(),
            shows: Vec::new(),
            expects: Vec::new(),
            linear_expects: Vec::new(),
            drawings: Vec::new(),
            links: Vec::new(),
            simulation: Simulation::default(),
            linearize: Vec::new(),
            placeholders,
            lets: Vec::new(),
        }
    }

    /// The draft of a resolved model, taken out of it to be added to; `model` keeps its scope.
    fn take(model: &mut Model) -> Draft {
        let mut pool = Pool::new();
        std::mem::swap(&mut pool, &mut model.pool);
        Draft {
            pool,
            time: model.time,
            title: model.title.take(),
            params: std::mem::take(&mut model.params),
            inputs: std::mem::take(&mut model.inputs),
            outputs: std::mem::take(&mut model.outputs),
            coords: std::mem::take(&mut model.coords),
            bodies: std::mem::take(&mut model.bodies),
            constraints: std::mem::take(&mut model.constraints),
            contacts: std::mem::take(&mut model.contacts),
            gravity: model.gravity.take(),
            potentials: std::mem::take(&mut model.potentials),
            forces: std::mem::take(&mut model.forces),
            torques: std::mem::take(&mut model.torques),
            dissipation: std::mem::take(&mut model.dissipation),
            lagrangians: std::mem::take(&mut model.lagrangians),
            shows: std::mem::take(&mut model.shows),
            expects: std::mem::take(&mut model.expects),
            linear_expects: std::mem::take(&mut model.linear_expects),
            drawings: std::mem::take(&mut model.drawings),
            links: std::mem::take(&mut model.links),
            simulation: std::mem::take(&mut model.simulation),
            linearize: std::mem::take(&mut model.linearize),
            placeholders: std::mem::take(&mut model.placeholders),
            lets: std::mem::take(&mut model.lets),
        }
    }

    fn into_model(self, scope: Scope) -> Model {
        Model {
            scope,
            pool: self.pool,
            title: self.title,
            time: self.time,
            params: self.params,
            inputs: self.inputs,
            outputs: self.outputs,
            coords: self.coords,
            bodies: self.bodies,
            constraints: self.constraints,
            contacts: self.contacts,
            gravity: self.gravity,
            potentials: self.potentials,
            forces: self.forces,
            torques: self.torques,
            dissipation: self.dissipation,
            lagrangians: self.lagrangians,
            shows: self.shows,
            expects: self.expects,
            linear_expects: self.linear_expects,
            drawings: self.drawings,
            links: self.links,
            simulation: self.simulation,
            inputs_in_constraints: Vec::new(),
            linearize: self.linearize,
            placeholders: self.placeholders,
            lets: self.lets,
        }
    }
}

impl<'a> Resolver<'a> {
    fn new(source: &'a str) -> Self {
        let model = Draft::new();
        let mut scope = Scope::default();
        for &(s, _) in &model.placeholders {
            scope.names.insert(model.pool.symbol(s).name.clone(), Binding::Quantity(s));
        }
        Resolver {
            source,
            scope,
            model,
            diagnostics: Diagnostics::default(),
            stmt: 0,
            in_outputs: false,
            in_drawing: false,
        }
    }

    fn enter(&mut self, index: usize) {
        self.stmt = index;
        self.scope.units.enter(index);
    }

    fn error(&mut self, d: Diagnostic) {
        self.diagnostics.errors.push(d);
    }

    fn text(&self, span: Span) -> String {
        self.source.get(span.start..span.end).unwrap_or("").trim().to_string()
    }

    fn declare_all(&mut self, file: &SceneFile) {
        for stmt in &file.stmts {
            let mut add = |id: &Ident, what: &'static str| {
                self.scope.declared.entry(normalize(&id.name)).or_insert((id.span, what));
            };
            match &stmt.kind {
                StmtKind::Param(ps) => ps.iter().for_each(|p| add(&p.name, "parameter")),
                StmtKind::Input(us) => us.iter().for_each(|u| add(&u.name, "input")),
                StmtKind::Coord(cs) => cs.iter().for_each(|c| add(&c.name, "coordinate")),
                StmtKind::Let { name, .. } => add(name, "name"),
                StmtKind::Particle { name, .. } | StmtKind::Body { name, .. } => add(name, "body"),
                StmtKind::Constraint { name: Some(name), .. } => add(name, "constraint"),
                StmtKind::Contact { name, .. } => add(name, "contact"),
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
        if let Some(existing) = self.scope.names.get(&name) {
            if !matches!(existing, Binding::Quantity(_)) {
                let first = self.scope.declared.get(&name).map(|(s, _)| *s);
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
        self.scope.names.insert(name, binding);
        true
    }

    fn finish(mut self, checks: Checks) -> Result<(Model, Vec<Diagnostic>), Vec<Diagnostic>> {
        let unused_inputs = self.model.inputs.iter().filter(|u| !self.scope.used.contains(&u.name));
        let unused_inputs: Vec<_> = unused_inputs.map(|u| (u.span, u.name.clone())).collect();
        for (span, name) in unused_inputs {
            self.diagnostics.warnings.push(
                Diagnostic::warning(span, format!("input `{name}` is never used"))
                    .with_label("declared here")
                    .with_hint("use it in a force, torque, potential or dissipation, or remove it"),
            );
        }
        for p in &self.model.params {
            if !self.scope.used.contains(&p.name) {
                self.diagnostics.warnings.push(
                    Diagnostic::warning(p.span, format!("parameter `{}` is never used", p.name))
                        .with_label("declared here")
                        .with_hint(
                            "remove it, or check the spelling where it was meant to be used",
                        ),
                );
            }
        }
        if let (Some(first), true) =
            (self.model.linear_expects.first(), self.model.linearize.is_empty())
        {
            let d = Diagnostic::error(first.span, "nothing is linearized to expect this of")
                .with_label("the scene has no `linearize about` line")
                .with_hint("add `linearize about …` naming the reference");
            self.diagnostics.errors.push(d);
        }
        let mut inputs_in_constraints = std::mem::take(&mut self.diagnostics.inputs_in_constraints);
        if !checks.inputs_in_constraints {
            self.diagnostics.errors.extend(inputs_in_constraints.drain(..).map(|(_, d)| d));
        }
        if !self.diagnostics.errors.is_empty() {
            let mut errors = self.diagnostics.errors;
            errors.sort_by_key(|d| d.span.start);
            return Err(errors);
        }
        if checks.units {
            let mismatches = self.scope.units.solve();
            if !mismatches.is_empty() {
                return Err(mismatches);
            }
        }
        self.scope.checks = checks;
        let warnings = std::mem::take(&mut self.diagnostics.warnings);
        let mut model = self.into_model();
        model.inputs_in_constraints = inputs_in_constraints;
        Ok((model, warnings))
    }

    /// The model resolved so far, with the scope that resolves more expressions against it.
    fn into_model(mut self) -> Model {
        self.scope.statements = self.stmt + 1;
        self.model.into_model(self.scope)
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
