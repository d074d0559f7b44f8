//! Checks of meaning made while resolving: derivatives past the second, rates where only the
//! configuration may appear, constants outside a function's domain, masses and inertias of the
//! wrong sign, and a scene with nothing to move. Each names the culprit's span.

use std::collections::HashMap;

use cas::number::{Signed, Zero};
use cas::{ExprId, Func, Rational, SymId, SymbolKind};
use lang::{Diagnostic, Expr, ExprKind, Ident, SceneFile, Span, StmtKind};

use super::{normalize, Binding, Resolver};
use crate::{Placeholder, Value};

/// How far from a function's domain an inexact value must fall before it counts as outside:
/// rounding can take an exact boundary value (`1 - sin(pi/2)`) a hair across it.
pub(super) const ROUNDING_MARGIN: f64 = 1e-9;

/// Where an expression stands, and how many time derivatives of the coordinates it may hold.
pub(super) struct Role {
    /// "a position", "a potential", …
    pub what: &'static str,
    /// Derivatives of coordinates allowed: 0 for the configuration only, 1 for rates too.
    pub max_order: u8,
    pub hint: &'static str,
    /// Whether deriving the equations of motion differentiates it (by the coordinates or
    /// the rates), so that a kink in it becomes a jump in a force.
    pub differentiated: bool,
    /// Whether an input may appear in it: only where no time derivative of it is taken.
    pub inputs: bool,
    /// Where an input may not appear and there is more to say than where inputs may stand:
    /// the hint, `{name}` standing for the input.
    pub instead_of_input: &'static str,
}

pub(super) const POSITION: Role = Role {
    what: "a position",
    max_order: 0,
    hint: "write where the body is as a function of the coordinates (and `t`); its velocity \
           follows by differentiation",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};
pub(super) const ANGLE: Role = Role {
    what: "an angle",
    max_order: 0,
    hint: "write the body's orientation as a function of the coordinates (and `t`); its angular \
           velocity follows by differentiation",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};
pub(super) const MASS: Role = Role {
    what: "a mass",
    max_order: 0,
    hint: "a mass is a constant, or a function of the coordinates and `t`",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};
pub(super) const INERTIA: Role = Role {
    what: "an inertia",
    max_order: 0,
    hint: "an inertia is a constant, or a function of the coordinates and `t`",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};
pub(super) const POTENTIAL: Role = Role {
    what: "a potential",
    max_order: 0,
    hint: "a potential depends on the configuration only; put terms with rates in `lagrangian` \
           (added to T − V) or, for friction, in `dissipation`",
    differentiated: true,
    inputs: true,
    instead_of_input: "",
};
pub(super) const GRAVITY: Role = Role {
    what: "gravity",
    max_order: 0,
    hint: "gravity's strength and direction may depend on the coordinates and `t` only",
    differentiated: true,
    inputs: true,
    instead_of_input: "",
};
pub(super) const SPRING: Role = Role {
    what: "a spring",
    max_order: 0,
    hint: "a spring's ends, stiffness and rest length may depend on the coordinates and `t` \
           only; for a force that grows with speed, use a `damper`",
    differentiated: true,
    inputs: true,
    instead_of_input: "",
};
pub(super) const ATTACHMENT: Role = Role {
    what: "an attachment point",
    max_order: 0,
    hint: "attach to a body by name, or to a point given as a function of the coordinates",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};
pub(super) const DAMPER: Role = Role {
    what: "a damper",
    max_order: 1,
    hint: "the equations of motion are solved for the accelerations, so a damping coefficient \
           may depend on the coordinates and rates, not on accelerations",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};
pub(super) const FORCE: Role = Role {
    what: "a force",
    max_order: 1,
    hint: "the equations of motion are solved for the accelerations, so a force may depend on \
           the coordinates, rates and `t`, not on accelerations",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};
pub(super) const TORQUE: Role = Role {
    what: "a torque",
    max_order: 1,
    hint: "the equations of motion are solved for the accelerations, so a torque may depend on \
           the coordinates, rates and `t`, not on accelerations",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};
pub(super) const DISSIPATION: Role = Role {
    what: "a dissipation function",
    max_order: 1,
    hint: "Rayleigh's dissipation function depends on the coordinates and rates",
    differentiated: true,
    inputs: true,
    instead_of_input: "",
};
pub(super) const LAGRANGIAN: Role = Role {
    what: "a Lagrangian",
    max_order: 1,
    hint: "lagrange derives second-order equations from L(q, q', t); a Lagrangian with \
           accelerations would give higher-order ones",
    differentiated: true,
    inputs: false,
    instead_of_input: "",
};

pub(super) const DRAWING: Role = Role {
    what: "a drawing",
    max_order: 1,
    hint: "a drawing shows the state: its points may use the coordinates, their rates and `t`, \
           not accelerations",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};

/// What drives an input in a run (`simulate --input F=-20*x`): evaluated before the
/// accelerations are solved for, so it cannot need them.
pub(super) const DRIVE: Role = Role {
    what: "what drives an input",
    max_order: 1,
    hint: "an input is driven by an expression of `t`, the coordinates, their rates and the \
           parameters (a state-feedback law such as `-k*x - c*x'`), not accelerations or \
           reactions, which are solved for with the input's value",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};
pub(super) const OUTPUT: Role = Role {
    what: "an output",
    max_order: 1,
    hint: "an output is a quantity measured from the state: it may use the coordinates, their \
           rates, the inputs and `t`, not accelerations or reactions",
    differentiated: false,
    inputs: true,
    instead_of_input: "",
};

/// A contact's gap: a position, whose sign says open or penetrating.
pub(super) const GAP: Role = Role {
    what: "a contact's gap",
    max_order: 0,
    hint: "a contact restrains positions, `contact floor: y >= 0`; a tangential rate held at \
           zero while it is closed goes in its block, `{ grip x' }`",
    differentiated: true,
    inputs: false,
    instead_of_input: "a contact's gap is differentiated in time, which only a run could do for \
                       an input: write the moving surface as an expression of `t`",
};

/// A contact's arming condition: an expression of the state, the contact watched while it is
/// positive.
pub(super) const ARMING: Role = Role {
    what: "a contact's arming condition",
    max_order: 1,
    hint: "a contact is armed while an expression of the coordinates, their rates and `t` is \
           positive, `{ armed -theta }`",
    differentiated: false,
    inputs: false,
    instead_of_input: "a contact's arming is watched by a run between evaluations of the \
                       dynamics: write it with the coordinates and their rates",
};

/// A gripping contact's tangential rate: linear in the rates, held at zero while closed.
pub(super) const GRIP: Role = Role {
    what: "a grip",
    max_order: 1,
    hint: "a grip is a tangential velocity, linear in the rates (`x'`, `x' + r*theta'`), held \
           at zero while the contact is closed",
    differentiated: true,
    inputs: false,
    instead_of_input: "a grip is differentiated in time, which only a run could do for an \
                       input: write it with the coordinates' rates",
};

/// A value of the state before an impact (`expect impact … where x' = -h*theta'`).
pub(super) const BEFORE_IMPACT: Role = Role {
    what: "the state before an impact",
    max_order: 1,
    hint: "the state before an impact gives positions and rates, as constants or in terms of \
           the others (`theta = 0, x' = -h*theta'`)",
    differentiated: false,
    inputs: false,
    instead_of_input: "",
};

/// Not a role an expression is refused in, but one whose kinks matter: a constraint's
/// gradient is its derivative.
pub(super) const CONSTRAINT: Role = Role {
    what: "a constraint",
    max_order: 1,
    hint: "",
    differentiated: true,
    inputs: false,
    instead_of_input: "deriving the equations would differentiate `{name}` in time, which only \
                       a run can: `simulate --input {name}=…` puts a law of `t` and the \
                       coordinates in its place first; to derive them here, write the driver as an expression of `t` \
                       (`y = A*sin(w*t)`)",
};

/// The functions whose derivative jumps (`abs`, `min`, `max`) or is a spike (`sign`).
const NOT_SMOOTH: [&str; 4] = ["abs", "sign", "min", "max"];

/// Whether `e` has `abs` or `sign` of something that moves with the coordinates or rates.
fn kinked(pool: &mut cas::Pool, e: ExprId, seen: &mut std::collections::HashSet<ExprId>) -> bool {
    if !seen.insert(e) {
        return false;
    }
    if let cas::Node::Func(f, a) = *pool.node(e) {
        if !f.is_smooth() {
            let moving = pool
                .free_symbols(a)
                .iter()
                .any(|s| matches!(pool.symbol(*s).kind, SymbolKind::Coordinate { .. }));
            if moving {
                return true;
            }
        }
    }
    pool.children(e).into_iter().any(|c| kinked(pool, c, seen))
}

/// "third", "fourth", … for a derivative's order.
fn ordinal(n: u8) -> String {
    match n {
        1 => "first".into(),
        2 => "second".into(),
        3 => "third".into(),
        4 => "fourth".into(),
        5 => "fifth".into(),
        _ => format!("{n}th"),
    }
}

/// A value for a label: exact when it is a rational, else to six significant digits.
pub(super) fn number_text(pool: &cas::Pool, e: ExprId) -> String {
    match pool.as_num(e) {
        Some(_) => pool.print(e, cas::Style::Ascii),
        None => approx(numeric::eval(pool, e, &[])),
    }
}

/// `≈ 0.333333`, `≈ 1.23e-7`.
fn approx(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-4..1e6).contains(&a) {
        return format!("≈ {v:.3e}");
    }
    let text = format!("{v:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    format!("≈ {text}")
}

/// The sub-expressions an expression is built from.
pub(super) fn children(e: &Expr) -> Vec<&Expr> {
    match &e.kind {
        ExprKind::Number(_) | ExprKind::Name { .. } | ExprKind::Member { .. } => Vec::new(),
        ExprKind::Neg(inner) => vec![inner],
        ExprKind::Binary { lhs, rhs, .. } => vec![lhs, rhs],
        ExprKind::Call { args, .. } | ExprKind::Tuple(args) => args.iter().collect(),
        ExprKind::Matrix(rows) => rows.iter().flatten().collect(),
    }
}

impl Resolver<'_> {
    /// The coordinate symbol of highest order in `v` (a coordinate, a rate, …), if any.
    fn highest_coordinate(&mut self, v: &Value) -> Option<(u8, SymId)> {
        let mut best: Option<(u8, SymId)> = None;
        for e in v.entries() {
            for s in self.model.pool.free_symbols(e).iter() {
                if !matches!(self.model.pool.symbol(*s).kind, SymbolKind::Coordinate { .. }) {
                    continue;
                }
                let order = self.model.pool.symbol(*s).order();
                let higher = match best {
                    Some((b, _)) => order > b,
                    None => true,
                };
                if higher {
                    best = Some((order, *s));
                }
            }
        }
        best
    }

    /// The highest derivative of a coordinate in `v`, with its order (none for 0).
    fn highest_derivative(&mut self, v: &Value) -> Option<(u8, SymId)> {
        self.highest_coordinate(v).filter(|(order, _)| *order > 0)
    }

    /// Resolves `e` again without reporting anything, to look inside an expression that
    /// resolved once already.
    pub(super) fn value_quietly(&mut self, e: &Expr) -> Option<Value> {
        let (errors, facts) = (self.diagnostics.errors.len(), self.scope.units.mark());
        let v = self.value(e);
        self.diagnostics.errors.truncate(errors);
        self.scope.units.rollback(facts);
        v.map(|(v, _)| v)
    }

    /// The smallest part of `e` that has a derivative past `max_order`: the name itself
    /// (`x'`), a `let` name, or a member such as `p.velocity`.
    fn fastest_part<'e>(&mut self, e: &'e Expr, max_order: u8) -> &'e Expr {
        for child in children(e) {
            let Some(v) = self.value_quietly(child) else { continue };
            if self.highest_derivative(&v).is_some_and(|(order, _)| order > max_order) {
                return self.fastest_part(child, max_order);
            }
        }
        e
    }

    /// Whether `value` (of the expression `e`) stays within the derivatives its role allows;
    /// reports the part that does not.
    pub(super) fn within_role(&mut self, e: &Expr, value: &Value, role: &Role) -> bool {
        if !self.without_inputs(e, value, role) {
            return false;
        }
        let Some((order, _)) = self.highest_derivative(value) else { return true };
        if order <= role.max_order {
            return true;
        }
        let part = self.fastest_part(e, role.max_order);
        let (order, base) = match self.value_quietly(part) {
            Some(v) => match self.highest_derivative(&v) {
                Some((o, s)) => (o, self.model.pool.symbol(s).base_name().to_string()),
                None => (order, String::new()),
            },
            None => (order, String::new()),
        };
        let (noun, article) = match order {
            1 => ("rate", "a"),
            2 => ("acceleration", "an"),
            _ => ("derivative", "a"),
        };
        let plain = matches!(&part.kind, ExprKind::Name { primes, .. } if *primes == order);
        let label = match (base.is_empty(), plain) {
            (true, _) => format!("{article} {noun}"),
            (false, true) => format!("the {noun} of `{base}`"),
            (false, false) => format!("depends on the {noun} of `{base}`"),
        };
        self.error(
            Diagnostic::error(
                part.span,
                format!("{} cannot depend on {article} {noun}", role.what),
            )
            .with_label(label)
            .with_hint(role.hint),
        );
        false
    }

    /// A warning where the equations of motion will differentiate `abs`, `sign`, `min` or
    /// `max` of the state: at the call when it is written in `e`, else at `e` (through a
    /// `let`). The derivation goes on; the equations are those of either side of the kink.
    pub(super) fn warn_kinks(&mut self, e: &Expr, value: &Value, role: &Role) {
        if !role.differentiated {
            return;
        }
        let mut seen = std::collections::HashSet::new();
        if !value.entries().into_iter().any(|x| kinked(&mut self.model.pool, x, &mut seen)) {
            return;
        }
        let (span, name) = self.kinked_call(e).unwrap_or((e.span, String::new()));
        let what = if name.is_empty() {
            "through a `let`, `abs`, `sign`, `min` or `max`".to_string()
        } else {
            format!("`{name}`")
        };
        let label = match name.as_str() {
            "sign" => "jumps where its argument is 0; its derivative (0 elsewhere) misses that",
            "min" | "max" => "has a kink where its arguments are equal",
            "abs" => "has a kink where its argument is 0",
            _ => "has a kink or a jump",
        };
        self.diagnostics.warnings.push(
            Diagnostic::warning(
                span,
                format!(
                    "{what} in {} is not smooth, and the equations of motion differentiate it",
                    role.what
                ),
            )
            .with_label(label)
            .with_hint(
                "the equations hold on either side, but a force derived from it jumps there; \
                 an integrator with error control crosses the jump with many tiny steps or \
                 loses accuracy, and a fixed step steps over it; a smooth stand-in such as \
                 sqrt(x^2 + eps^2) for abs(x) avoids it",
            ),
        );
    }

    /// The first call of `abs`, `sign`, `min` or `max` in `e` whose value moves with the state.
    fn kinked_call(&mut self, e: &Expr) -> Option<(Span, String)> {
        if let ExprKind::Call { func, .. } = &e.kind {
            if NOT_SMOOTH.contains(&func.name.as_str()) {
                let v = self.value_quietly(e)?;
                let mut seen = std::collections::HashSet::new();
                if v.entries().into_iter().any(|x| kinked(&mut self.model.pool, x, &mut seen)) {
                    return Some((e.span, func.name.clone()));
                }
            }
        }
        children(e).into_iter().find_map(|c| self.kinked_call(c))
    }

    /// `theta'''`: only rates and accelerations exist. `span` covers the name as written,
    /// with its primes; `direct` says whether it is the derivative of coordinate `base` itself
    /// (`x'''`) or needs it (a `let` name with primes).
    pub(super) fn past_acceleration(&mut self, span: Span, order: u8, base: &str, direct: bool) {
        let written = self.text(span);
        let message = if direct {
            format!(
                "`{written}` is a {} derivative; only rates and accelerations exist",
                ordinal(order)
            )
        } else {
            format!(
                "`{written}` needs the {} derivative of `{base}`; only rates and accelerations \
                 exist",
                ordinal(order)
            )
        };
        self.error(
            Diagnostic::error(span, message)
                .with_label(format!("{} time derivative of `{base}`", ordinal(order)))
                .with_hint(format!(
                    "the equations of motion are of second order: a scene can use `{base}`, \
                     its rate `{base}'` and its acceleration `{base}''`"
                )),
        );
    }

    /// Whether `primes` derivatives of a `let` name or a quantity stay within accelerations.
    /// Decided before differentiating: each derivative of an expression that depends on a
    /// coordinate's k-th derivative brings in the (k+1)-th, so the order is known, and a long
    /// row of primes is refused without building its growing derivatives.
    pub(super) fn derivative_exists(&mut self, v: &Value, primes: u8, span: Span) -> bool {
        if primes == 0 {
            return true;
        }
        match self.highest_coordinate(v) {
            Some((order, sym)) if usize::from(order) + usize::from(primes) > 2 => {
                let base = self.model.pool.symbol(sym).base_name().to_string();
                let order = order.saturating_add(primes);
                self.past_acceleration(span, order, &base, false);
                return false;
            }
            _ => {}
        }
        match self.highest_placeholder(v) {
            Some((order, root, root_order)) if usize::from(order) + usize::from(primes) > 2 => {
                let name = self.model.pool.symbol(root).name.clone();
                let written = self.text(span);
                let (has, times) = match root_order {
                    0 => ("positions", "twice"),
                    _ => ("rates", "once"),
                };
                self.error(
                    Diagnostic::error(
                        span,
                        format!(
                            "`{written}` needs a {} derivative of the coordinates; only rates and \
                             accelerations exist",
                            ordinal(order.saturating_add(primes))
                        ),
                    )
                    .with_label(format!("`{name}` has {has} in it"))
                    .with_hint(format!(
                        "the equations of motion are of second order: `{name}` can be \
                         differentiated {times}"
                    )),
                );
                false
            }
            _ => true,
        }
    }

    /// The placeholder (KE, PE, a reaction or a rate of one) in `v` whose expression holds the
    /// highest derivative of the coordinates: that order, and the quantity it is a rate of
    /// (itself if none) with that quantity's order. T has rates, V positions, and a reaction
    /// is differentiated in its form in the state (positions and rates).
    fn highest_placeholder(&mut self, v: &Value) -> Option<(u8, SymId, u8)> {
        let mut best: Option<(u8, SymId, u8)> = None;
        for e in v.entries() {
            for s in self.model.pool.free_symbols(e).iter() {
                let Some((order, root, root_order)) = self.placeholder_order(*s) else {
                    continue;
                };
                if best.is_none_or(|(b, _, _)| order > b) {
                    best = Some((order, root, root_order));
                }
            }
        }
        best
    }

    /// A placeholder's order (see [`Self::highest_placeholder`]), with the quantity it is a
    /// rate of and that quantity's order.
    fn placeholder_order(&self, s: SymId) -> Option<(u8, SymId, u8)> {
        let kind = self.model.placeholders.iter().find(|(p, _)| *p == s).map(|(_, k)| *k)?;
        Some(match kind {
            Placeholder::PotentialEnergy => (0, s, 0),
            Placeholder::KineticEnergy | Placeholder::Reaction(_) => (1, s, 1),
            Placeholder::Rate { of, .. } => {
                let (order, root, root_order) = self.placeholder_order(of)?;
                (order + 1, root, root_order)
            }
        })
    }

    /// The total time derivative of `e`, placeholders included. KE, PE and reactions stand
    /// for expressions derived only later, and their stand-in symbols are constants to the
    /// algebra; so each contributes ∂e/∂p times a symbol for its rate, which the derivation
    /// replaces by the derivative of what p turns out to be.
    pub(super) fn total_rate(&mut self, e: ExprId, span: Span) -> ExprId {
        self.refuse_input_rate(e, span);
        let mut parts = vec![self.model.pool.time_derivative(e)];
        let free = self.model.pool.free_symbols(e);
        for p in free.iter() {
            if self.placeholder_order(*p).is_none() {
                continue;
            }
            self.refuse_placeholder_rate_with_inputs(*p, span);
            let rate = self.placeholder_rate(*p, span);
            let partial = self.model.pool.diff(e, *p);
            let rate = self.model.pool.sym(rate);
            parts.push(self.model.pool.mul2(partial, rate));
        }
        self.model.pool.add(&parts)
    }

    /// The symbol for the rate of placeholder `p`, made on first use.
    fn placeholder_rate(&mut self, p: SymId, span: Span) -> SymId {
        let made = self.model.placeholders.iter().find_map(|(r, k)| match k {
            Placeholder::Rate { of, .. } if *of == p => Some(*r),
            _ => None,
        });
        if let Some(r) = made {
            return r;
        }
        let name = format!("{}'", self.model.pool.symbol(p).name);
        let r = self.model.pool.param(&name);
        self.model.placeholders.push((r, Placeholder::Rate { of: p, span }));
        r
    }

    // --- constants ----------------------------------------------------------------------

    /// `e` as a number, exactly, when every symbol in it is a parameter with a value: what the
    /// scene means by it. `None` when a coordinate, time or a parameter without a value
    /// appears.
    pub(super) fn known(&mut self, e: ExprId) -> Option<ExprId> {
        let free = self.model.pool.free_symbols(e);
        if !free.iter().all(|s| self.scope.param_values.contains_key(s)) {
            return None;
        }
        if free.is_empty() {
            return Some(e);
        }
        let map: HashMap<SymId, ExprId> = self.scope.param_values.clone();
        Some(self.model.pool.subst(e, &map))
    }

    /// Whether a constant is a finite number where its value is known; reports it otherwise.
    /// Domain errors (`sqrt(-1)`) were reported where they happened; this catches the rest,
    /// such as `1e400`.
    pub(super) fn finite(&mut self, value: ExprId, written: &Expr) -> bool {
        let Some(v) = self.known(value) else { return true };
        let x = numeric::eval(&self.model.pool, v, &[]);
        if x.is_finite() {
            return true;
        }
        let label = if x.is_nan() {
            "not a number".to_string()
        } else {
            format!("too large for floating point ({x})")
        };
        self.error(
            Diagnostic::error(written.span, "this value is not a finite number")
                .with_label(label)
                .with_hint("values must be real numbers of magnitude below about 1.8e308"),
        );
        false
    }

    /// Records a parameter's value, in numbers, for the checks of later constants.
    pub(super) fn param_value(&mut self, sym: SymId, value: ExprId, written: &Expr) {
        if !self.finite(value, written) {
            return;
        }
        if let Some(v) = self.known(value) {
            self.scope.param_values.insert(sym, v);
        }
    }

    /// A function applied to a known constant outside its domain (`sqrt(-1)`, `ln(0)`,
    /// `asin(2)`), or overflowing: the error, at the call.
    pub(super) fn outside_domain(
        &mut self,
        name: &str,
        args: &[ExprId],
        written: &[Expr],
        span: Span,
    ) -> Option<Diagnostic> {
        let known: Vec<ExprId> = args.iter().map(|a| self.known(*a)).collect::<Option<Vec<_>>>()?;
        let values: Vec<f64> = numeric::Evaluator::new(&self.model.pool, &known).eval(&[]).to_vec();
        if !values.iter().all(|v| v.is_finite()) {
            return None;
        }
        let exact: Option<Rational> =
            known.first().and_then(|k| self.model.pool.as_num(*k)).cloned();
        let a = values[0];
        // Exact constants are judged exactly; others with a margin for rounding.
        let negative = exact.as_ref().map_or(a < -ROUNDING_MARGIN, |q| q.is_negative());
        let zero = exact.as_ref().is_some_and(|q| q.is_zero());
        let beyond_one = exact
            .as_ref()
            .map_or(a.abs() > 1.0 + ROUNDING_MARGIN, |q| q.abs() > cas::number::int(1));
        let func = Func::from_name(name);
        let problem = match (name, func) {
            ("sqrt", _) if negative => Some((
                "the square root of a negative number is not real".to_string(),
                "sqrt needs an argument of 0 or more",
            )),
            (_, Some(Func::Ln)) if negative || zero => Some((
                if zero {
                    "the logarithm of 0 is not a number (it is −∞)".to_string()
                } else {
                    "the logarithm of a negative number is not real".to_string()
                },
                "ln needs a positive argument",
            )),
            (_, Some(Func::Asin | Func::Acos)) if beyond_one => Some((
                format!("{name} of a number outside [-1, 1] is not real"),
                "asin and acos take a sine or a cosine, between -1 and 1",
            )),
            _ => None,
        };
        let written_arg = written.first();
        if let Some((message, hint)) = problem {
            let arg_text = written_arg.map(|w| self.text(w.span)).unwrap_or_default();
            let value = number_text(&self.model.pool, known[0]);
            let label = if arg_text == value {
                format!("the argument is {value}")
            } else {
                format!("the argument `{arg_text}` is {value}")
            };
            let hint = if self.model.pool.free_symbols(args[0]).is_empty() {
                hint.to_string()
            } else {
                format!("{hint} (parameters count at their given values)")
            };
            return Some(Diagnostic::error(span, message).with_label(label).with_hint(hint));
        }
        // In the domain, but too large for floating point (`exp(1000)`).
        let result = match name {
            "sqrt" => a.sqrt(),
            "atan2" => numeric::elementary::atan2(a, values.get(1).copied().unwrap_or(f64::NAN)),
            _ => func.map_or(0.0, |f| numeric::elementary::apply(f, a)),
        };
        if result.is_infinite() {
            return Some(
                Diagnostic::error(span, "this value is too large for floating point")
                    .with_label(format!(
                        "{name} of {} overflows",
                        number_text(&self.model.pool, known[0])
                    ))
                    .with_hint(
                        "values must be of magnitude below about 1.8e308; check the formula",
                    ),
            );
        }
        None
    }

    /// A known divisor that is 0 at the parameters' values: the error at the divisor.
    pub(super) fn zero_divisor(&mut self, divisor: ExprId, written: &Expr) -> Option<Diagnostic> {
        let k = self.known(divisor)?;
        let zero = match self.model.pool.as_num(k) {
            Some(q) => q.is_zero(),
            None => numeric::eval(&self.model.pool, k, &[]) == 0.0,
        };
        if !zero {
            return None;
        }
        let text = self.text(written.span);
        Some(
            Diagnostic::error(written.span, "division by zero")
                .with_label(format!("`{text}` is 0"))
                .with_hint("check the parameters' values, or the formula"),
        )
    }

    /// A power of known constants that is not a real number: 0 to a negative power, a
    /// negative number to a fractional one.
    pub(super) fn bad_power(
        &mut self,
        base: ExprId,
        exponent: ExprId,
        span: Span,
    ) -> Option<Diagnostic> {
        let (b, x) = (self.known(base)?, self.known(exponent)?);
        let (bv, xv) =
            (numeric::eval(&self.model.pool, b, &[]), numeric::eval(&self.model.pool, x, &[]));
        let exact_base = self.model.pool.as_num(b).cloned();
        let exact_exponent = self.model.pool.as_num(x).cloned();
        let base_zero = exact_base.as_ref().map_or(bv == 0.0, |q| q.is_zero());
        let negative_exponent = exact_exponent.as_ref().map_or(xv < 0.0, |q| q.is_negative());
        if base_zero && negative_exponent {
            return Some(
                Diagnostic::error(span, "division by zero")
                    .with_label("0 to a negative power, with the parameters' values")
                    .with_hint("check the parameters' values, or the formula"),
            );
        }
        let base_negative = exact_base.as_ref().map_or(bv < -ROUNDING_MARGIN, |q| q.is_negative());
        let fractional = exact_exponent.as_ref().map_or(xv.fract() != 0.0, |q| !q.is_integer());
        if base_negative && fractional {
            return Some(
                Diagnostic::error(span, "a negative number to a fractional power is not real")
                    .with_label(format!(
                        "{} to the power {}",
                        number_text(&self.model.pool, b),
                        number_text(&self.model.pool, x)
                    ))
                    .with_hint("a fractional power needs a base of 0 or more; check the sign"),
            );
        }
        None
    }

    /// A mass that is zero or negative, or an inertia that is negative, at the parameters'
    /// values: the error at the property. Left alone when the sign cannot be known (a
    /// coordinate, or a parameter without a value, appears).
    pub(super) fn check_sign(
        &mut self,
        body: &Ident,
        value: ExprId,
        written: &Expr,
        inertia: bool,
    ) {
        let Some(k) = self.known(value) else { return };
        let x = numeric::eval(&self.model.pool, k, &[]);
        if !x.is_finite() {
            return;
        }
        let (negative, zero) = match self.model.pool.as_num(k) {
            Some(q) => (q.is_negative(), q.is_zero()),
            // An inertia may be exactly 0, which rounding can take a hair below; a mass may
            // not be 0 either way, and tiny masses (1e-12 kg) are real.
            None => (x < 0.0 && !(inertia && x > -ROUNDING_MARGIN), x == 0.0),
        };
        let refused = negative || (zero && !inertia);
        if !refused {
            return;
        }
        let (what, unit) = if inertia { ("inertia", "kg·m²") } else { ("mass", "kg") };
        let sign = if negative { "negative" } else { "zero" };
        let shown = number_text(&self.model.pool, k);
        let text = self.text(written.span);
        let label = if text == shown {
            format!("this is {shown} {unit}")
        } else {
            format!("`{text}` is {shown} {unit}")
        };
        let hint = match (inertia, negative) {
            (true, _) => "a moment of inertia about the centre of mass is 0 or more, e.g. \
                          m*L^2/12 for a thin rod of length L"
                .to_string(),
            (false, true) => "a mass must be positive: check the sign".to_string(),
            (false, false) => "a body needs a positive mass; leave out a point that carries none \
                               (a spring can be anchored at a fixed point such as (0, 0))"
                .to_string(),
        };
        let mut d =
            Diagnostic::error(written.span, format!("the {what} of `{}` is {sign}", body.name))
                .with_label(label)
                .with_hint(hint);
        if let ExprKind::Name { name, primes: 0 } = &written.kind {
            let key = normalize(name);
            if let Some(Binding::Param(s)) = self.scope.names.get(&key) {
                let s = *s;
                if let Some(p) = self.model.params.iter().find(|p| p.sym == s) {
                    d = d.with_related(p.span, format!("`{}` is given its value here", p.name));
                }
            }
        }
        self.error(d);
    }

    // --- the scene as a whole -------------------------------------------------------------

    /// A scene needs a coordinate: without one there is nothing to derive or integrate.
    pub(super) fn require_a_coordinate(&mut self, file: &SceneFile) {
        if file.stmts.iter().any(|s| matches!(s.kind, StmtKind::Coord(_))) {
            return;
        }
        let example = "declare a coordinate and a body that moves with it: `param m = 1 kg`, \
                       `coord x`, `particle p { mass m; position (x, 0) }`";
        let d = if file.stmts.is_empty() {
            let message = if self.source.trim().is_empty() {
                "the scene is empty"
            } else {
                "the scene is empty: the file has only comments"
            };
            Diagnostic::error(Span::new(0, 0), message)
                .with_label("expected a `coord` line and a body")
                .with_hint(example)
        } else {
            let body = file.stmts.iter().find_map(|s| match &s.kind {
                StmtKind::Particle { name, .. } | StmtKind::Body { name, .. } => Some(name),
                _ => None,
            });
            let (span, label) = match body {
                Some(name) => (name.span, format!("no coordinate moves `{}`", name.name)),
                None => (file.stmts[0].span, "this scene has no `coord` line".to_string()),
            };
            Diagnostic::error(span, "the scene declares no coordinate").with_label(label).with_hint(
                "declare the generalized coordinates with `coord` (e.g. `coord x`) and \
                     write the positions in terms of them",
            )
        };
        self.error(d);
    }
}

impl Resolver<'_> {
    /// A vector whose every component is 0 at the parameters' values (a rotation's axis,
    /// `(a, 0, 0)` with `a = 0`): the error at the vector, naming the parameters it has.
    pub(super) fn zero_at_values(&mut self, v: &[ExprId], written: &Expr) -> Option<Diagnostic> {
        let mut params = Vec::new();
        for x in v {
            let k = self.known(*x)?;
            let zero = match self.model.pool.as_num(k) {
                Some(q) => q.is_zero(),
                None => numeric::eval(&self.model.pool, k, &[]) == 0.0,
            };
            if !zero {
                return None;
            }
            params.extend(self.model.pool.free_symbols(*x).iter().copied());
        }
        let text = self.text(written.span);
        let mut d = Diagnostic::error(written.span, "a rotation's axis cannot be zero")
            .with_label(format!("`{text}` is (0, 0, 0) at the parameters' values"))
            .with_hint(
                "give the direction to turn about, such as (0, 0, 1), or check the parameters' \
                 values",
            );
        params.sort();
        params.dedup();
        for s in params {
            if let Some(p) = self.model.params.iter().find(|p| p.sym == s) {
                d = d.with_related(p.span, format!("`{}` is given its value here", p.name));
            }
        }
        Some(d)
    }
}

#[cfg(test)]
mod tests {
    /// The warnings of a scene that resolves, as `label: message`, but for unused parameters.
    fn warnings(source: &str) -> Vec<String> {
        let file = lang::parse(source).expect("parses");
        let (_, w) = crate::resolve(&file, source).expect("resolves");
        w.into_iter()
            .filter(|d| !d.message.contains("never used"))
            .map(|d| format!("{}: {}", d.label, d.message))
            .collect()
    }

    #[test]
    fn a_kink_the_equations_differentiate_is_warned_of_and_one_they_do_not_is_not() {
        let scene = "param m = 1 kg, k = 2 N, c = 1 N*s/m\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\n";
        let w = warnings(&format!("{scene}potential k*abs(x)\n"));
        assert!(w.len() == 1 && w[0].contains("`abs` in a potential is not smooth"), "{w:?}");
        let w = warnings(&format!("{scene}let d = max(x, 0)\npotential k*d\n"));
        assert!(w.len() == 1 && w[0].contains("through a `let`"), "{w:?}");
        let w = warnings(&format!("{scene}dissipation c/2*x'^2*sign(x')\n"));
        assert!(w.len() == 1 && w[0].starts_with("jumps where its argument is 0"), "{w:?}");
        // A force is not differentiated (it is itself discontinuous, which the README says),
        // and a constant under `abs` has no kink.
        assert!(warnings(&format!("{scene}force f on p: (-k*sign(x'), 0)\n")).is_empty());
        assert!(warnings(&format!("{scene}potential abs(-k)*x\n")).is_empty());
    }
}
