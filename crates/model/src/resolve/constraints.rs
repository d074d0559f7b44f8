//! `constraint` statements: the equation resolved and classified as holonomic or a velocity
//! constraint; and `contact` statements: the gap, checked to be a position, with its laws
//! (a restitution in [0, 1], a grip that is a velocity), as rows among the constraints.

use cas::number::{One, Signed};
use cas::{ExprId, Rational, SymId, SymbolKind};
use lang::{Diagnostic, Expr, ExprKind, Ident, Property, Span};

use super::checks::{self, ARMING, GAP, GRIP};
use super::{normalize, space, Binding, Resolver};
use crate::{Constraint, ConstraintKind, Contact, Placeholder, Value};

/// The laws a `contact` block may give, as a hint names them.
const CONTACT_LAWS: &str = "a contact's laws are `restitution E` (Newton's coefficient, 0 to 1), \
                            `grip V` (a tangential rate held at zero while it is closed), \
                            `friction MU` with `slip V` (Coulomb's law along the tangential rate \
                            V; `slip (V1, V2)` in space, the exact cone), and `armed A` (watched \
                            only while A > 0)";

impl Resolver<'_> {
    pub(super) fn constraint(&mut self, name: Option<&Ident>, lhs: &Expr, rhs: &Expr, span: Span) {
        let (l, r) = (self.value(lhs), self.value(rhs));
        let (Some((l, l_dims)), Some((r, r_dims))) = (l, r) else { return };
        // Whether an input may stand here is the checks' to say, known when the walk is done.
        for (e, value) in [(lhs, &l), (rhs, &r)] {
            if let Some(refused) = self.input_diagnostic(e, value, &checks::CONSTRAINT) {
                self.diagnostics.inputs_in_constraints.push(refused);
            }
        }
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
            self.scope.units.same(a, b, lhs.span, rhs.span, "between the sides of this constraint");
        }
        let base = match name {
            Some(id) => normalize(&id.name),
            None => format!("constraint{}", self.model.constraints.len() + 1),
        };
        let mut indices = Vec::new();
        for (k, (l, r)) in ls.into_iter().zip(rs).enumerate() {
            let phi = self.model.pool.sub(l, r);
            if vector && self.model.pool.is_identically_zero(phi) {
                // A component that holds whatever the motion (the height of a ball's contact
                // with the floor it rolls on) restrains nothing.
                indices.push(None);
                continue;
            }
            let cname =
                if vector { format!("{base}.{}", ["x", "y", "z"][k.min(2)]) } else { base.clone() };
            let Some(kind) = self.constraint_kind(phi, span) else { return };
            indices.push(Some(self.push_constraint(cname, kind, (l, r), phi, span)));
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

    /// Adds a constraint row Φ = l − r of `kind` with its reaction's symbol `NAME.force`;
    /// returns its index.
    fn push_constraint(
        &mut self,
        name: String,
        kind: ConstraintKind,
        (l, r): (ExprId, ExprId),
        phi: ExprId,
        span: Span,
    ) -> usize {
        let index = self.model.constraints.len();
        let force_symbol = self.model.pool.param(&format!("{name}.force"));
        let lhs_free = self.model.pool.free_symbols(l);
        let lhs_coords = lhs_free
            .iter()
            .copied()
            .filter(|s| {
                matches!(self.model.pool.symbol(*s).kind, SymbolKind::Coordinate { order: 0, .. })
            })
            .collect();
        self.model.placeholders.push((force_symbol, Placeholder::Reaction(index)));
        self.model.constraints.push(Constraint {
            name,
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
        index
    }

    /// `contact NAME: lhs >= rhs { laws }`: the gap lhs − rhs (rhs − lhs for `<=`), a position,
    /// kept as a row of kind [`ConstraintKind::Contact`]; a grip as a row of kind
    /// [`ConstraintKind::Grip`] after it.
    pub(super) fn contact(
        &mut self,
        name: &Ident,
        (lhs, rhs): (&Expr, &Expr),
        at_least: bool,
        laws: &[Property],
        span: Span,
    ) {
        let l = self.scalar_in_role(lhs, &GAP);
        let r = self.scalar_in_role(rhs, &GAP);
        let (Some((l, l_dims)), Some((r, r_dims))) = (l, r) else { return };
        let (lf, rf) = (self.operand(l_dims).forms(), self.operand(r_dims).forms());
        for (a, b) in lf.iter().zip(&rf) {
            self.scope.units.same(a, b, lhs.span, rhs.span, "between the sides of this contact");
        }
        let gap = if at_least { self.model.pool.sub(l, r) } else { self.model.pool.sub(r, l) };
        let free = self.model.pool.free_symbols(gap);
        if !free
            .iter()
            .any(|s| matches!(self.model.pool.symbol(*s).kind, SymbolKind::Coordinate { .. }))
        {
            self.error(
                Diagnostic::error(span, "this contact's gap involves no coordinate")
                    .with_label("nothing here can move")
                    .with_hint("a contact's gap is a distance between moving things, `y >= 0`"),
            );
            return;
        }
        let mut restitution: Option<ExprId> = None;
        let mut grip: Option<(ExprId, Span)> = None;
        let mut slip: Option<(ExprId, Span)> = None;
        // In space, the second tangential rate a rough contact slips along.
        let mut cross: Option<ExprId> = None;
        let mut friction: Option<(ExprId, Span)> = None;
        let mut armed: Option<ExprId> = None;
        // A coefficient written but refused (reported already) still pairs with its slip.
        let mut friction_written = false;
        // And a slip written but refused with its coefficient.
        let mut slip_written = false;
        let mut seen: Vec<&Ident> = Vec::new();
        for law in laws {
            if let Some(first) = seen.iter().find(|k| k.name == law.key.name) {
                self.error(
                    Diagnostic::error(law.key.span, format!("`{}` is given twice", law.key.name))
                        .with_label("again here")
                        .with_related(first.span, "first given here"),
                );
                continue;
            }
            seen.push(&law.key);
            match law.key.name.as_str() {
                "restitution" => restitution = self.restitution(&law.value),
                "grip" => grip = self.grip(&law.value, "a grip").map(|g| (g, law.value.span)),
                "slip" => {
                    slip_written = true;
                    let (first, second) = self.slip(&law.value);
                    slip = first.map(|g| (g, law.value.span));
                    cross = second;
                }
                "armed" => armed = self.scalar_in_role(&law.value, &ARMING).map(|(a, _)| a),
                "friction" => {
                    friction_written = true;
                    friction = self.friction(&law.value).map(|mu| (mu, law.value.span));
                }
                other => self.error(
                    Diagnostic::error(law.key.span, format!("a contact has no law `{other}`"))
                        .with_label("unknown law")
                        .with_hint(CONTACT_LAWS),
                ),
            }
        }
        // Coulomb's law needs its direction, and a grip is friction without a bound: a contact
        // has one tangential law.
        match (grip, slip, friction) {
            (Some((_, g)), Some((_, s)), _) => {
                self.error(
                    Diagnostic::error(s, "a contact grips or slips, not both")
                        .with_label("a slip direction here")
                        .with_related(g, "a grip here")
                        .with_hint("`grip V` holds V at zero; `friction MU; slip V` bounds the force along V by MU times the normal force"),
                );
                return;
            }
            (Some((_, g)), None, Some((_, f))) => {
                self.error(
                    Diagnostic::error(f, "a gripping contact has no friction coefficient")
                        .with_label("friction here")
                        .with_related(g, "a grip here, which never slips")
                        .with_hint(
                            "for Coulomb's law, write `friction MU; slip V` instead of `grip V`",
                        ),
                );
                return;
            }
            (None, None, Some(_)) if slip_written => return,
            (None, None, Some((_, f))) => {
                self.error(
                    Diagnostic::error(f, "friction needs the tangential rate it acts along")
                        .with_label("no `slip` for it")
                        .with_hint("add `slip V`, the contact point's tangential rate (`x'`, `x' + r*theta'`)"),
                );
                return;
            }
            (None, Some(_), None) if friction_written => return,
            (None, Some((_, s)), None) => {
                self.error(
                    Diagnostic::error(s, "a slip direction without a friction coefficient")
                        .with_label("slip here")
                        .with_hint("add `friction MU`; a frictionless contact needs no `slip`"),
                );
                return;
            }
            _ => {}
        }
        let grip = grip.or(slip);
        let friction = friction.map(|(mu, _)| mu);
        let cross_span = slip.map(|(_, s)| s);
        let cname = normalize(&name.name);
        let zero = self.model.pool.zero();
        let normal =
            self.push_constraint(cname.clone(), ConstraintKind::Contact, (gap, zero), gap, span);
        let grip = grip.map(|(g, gspan)| {
            let name = format!("{cname}.grip");
            self.push_constraint(name, ConstraintKind::Grip, (g, zero), g, gspan)
        });
        let cross = cross.zip(cross_span).map(|(c, cspan)| {
            let name = format!("{cname}.cross");
            self.push_constraint(name, ConstraintKind::Grip, (c, zero), c, cspan)
        });
        let restitution = restitution.unwrap_or(zero);
        self.model.contacts.push(Contact {
            name: cname,
            normal,
            grip,
            cross,
            restitution,
            friction,
            armed,
            span,
        });
        self.bind(name, Binding::Constraint(vec![Some(normal)]));
    }

    /// A contact's coefficient (`what`, "restitution" or "friction"): a dimensionless
    /// constant of the parameters, with `example` its hint's; the expression, and its value
    /// at the parameters' (exact where it is a rational).
    fn coefficient(
        &mut self,
        written: &Expr,
        what: &str,
        example: &str,
    ) -> Option<(ExprId, Option<Rational>, f64)> {
        let (e, dims) = self.scalar(written)?;
        for f in self.operand(dims).forms() {
            self.scope.units.dimensionless(&f, written.span, &format!("a coefficient of {what}"));
        }
        let free = self.model.pool.free_symbols(e);
        if let Some(s) =
            free.iter().find(|s| !matches!(self.model.pool.symbol(**s).kind, SymbolKind::Param))
        {
            let name = self.model.pool.symbol(*s).name.clone();
            self.error(
                Diagnostic::error(written.span, format!("a coefficient of {what} is a constant"))
                    .with_label(format!("depends on `{name}`"))
                    .with_hint(format!("write a number or an expression of parameters, {example}")),
            );
            return None;
        }
        let known = self.known(e)?;
        let exact = self.model.pool.as_num(known).cloned();
        Some((e, exact, numeric::eval(&self.model.pool, known, &[])))
    }

    /// A contact's `restitution`: a dimensionless constant, in [0, 1] at the parameters' values.
    fn restitution(&mut self, written: &Expr) -> Option<ExprId> {
        let (e, exact, value) = self.coefficient(written, "restitution", "`4/5` or `e`")?;
        let outside = match exact {
            Some(q) => q.is_negative() || q > Rational::one(),
            None => !(-1e-12..=1.0 + 1e-12).contains(&value),
        };
        if outside {
            self.error(
                Diagnostic::error(
                    written.span,
                    "a coefficient of restitution lies between 0 and 1",
                )
                .with_label(format!("is {value} here"))
                .with_hint(
                    "0 is a plastic landing (the contact closes), 1 an elastic one (the \
                         normal rate reverses in full)",
                ),
            );
            return None;
        }
        Some(e)
    }

    /// A contact's `friction`: Coulomb's coefficient, a dimensionless constant, at least 0 at
    /// the parameters' values.
    fn friction(&mut self, written: &Expr) -> Option<ExprId> {
        let (e, exact, value) = self.coefficient(written, "friction", "`3/10` or `mu`")?;
        let negative = match exact {
            Some(q) => q.is_negative(),
            None => value < -1e-12,
        };
        if negative {
            self.error(
                Diagnostic::error(written.span, "a coefficient of friction is not negative")
                    .with_label(format!("is {value} here"))
                    .with_hint("0 is a smooth contact; Coulomb's μ is typically 0.1 to 1"),
            );
            return None;
        }
        Some(e)
    }

    /// A contact's `slip`: one tangential rate in the plane, or two, `(V1, V2)`, in space (the
    /// contact point's velocity along two directions of the tangent plane, along which the
    /// exact cone acts). The second is `None` in the plane; both `None` when refused.
    fn slip(&mut self, written: &Expr) -> (Option<ExprId>, Option<ExprId>) {
        let ExprKind::Tuple(items) = &written.kind else {
            return (self.grip(written, "a slip"), None);
        };
        if items.len() != 2 {
            self.error(
                Diagnostic::error(written.span, "a slip in space has two tangential rates")
                    .with_label(format!("{} rates here", items.len()))
                    .with_hint(
                        "write `slip V` in the plane, or `slip (V1, V2)` with the contact point's \
                         velocity along two directions of the tangent plane",
                    ),
            );
            return (None, None);
        }
        let (first, second) = (self.grip(&items[0], "a slip"), self.grip(&items[1], "a slip"));
        match (first, second) {
            (Some(a), Some(b)) => (Some(a), Some(b)),
            _ => (None, None),
        }
    }

    /// A contact's `grip`: a tangential velocity, linear in the rates.
    /// `what` names the law in its errors: `a grip`, or `a slip` (each of a slip's rates).
    fn grip(&mut self, written: &Expr, what: &str) -> Option<ExprId> {
        let (g, _) = self.scalar_in_role(written, &GRIP)?;
        match self.constraint_kind(g, written.span)? {
            ConstraintKind::Velocity => Some(g),
            _ => {
                let hint = if what == "a grip" {
                    "a grip holds a tangential rate at zero while the contact is closed: \
                     write the rate, `x'` or `x' + r*theta'`"
                } else {
                    "friction acts against the contact point's tangential rates: write each \
                     rate, `x'` or `x' - r*a'`"
                };
                self.error(
                    Diagnostic::error(written.span, format!("{what} is a velocity"))
                        .with_label("no rate here")
                        .with_hint(hint),
                );
                None
            }
        }
    }

    /// Whether Φ = 0 restrains positions or velocities; `None` (with the error reported) when
    /// it is neither: accelerations, rates not entering linearly, or no coordinate at all.
    fn constraint_kind(&mut self, phi: ExprId, span: Span) -> Option<ConstraintKind> {
        let free = self.model.pool.free_symbols(phi);
        if free.iter().any(|s| self.model.pool.symbol(*s).order() > 1) {
            self.error(
                Diagnostic::error(span, "this constraint involves accelerations")
                    .with_label("an acceleration appears here")
                    .with_hint("a constraint restrains positions, or velocities (rolling without slipping)"),
            );
            return None;
        }
        if !free
            .iter()
            .any(|s| matches!(self.model.pool.symbol(*s).kind, SymbolKind::Coordinate { .. }))
        {
            self.error(
                Diagnostic::error(span, "this constraint involves no coordinate")
                    .with_label("nothing here can move")
                    .with_hint("a constraint relates coordinates declared with `coord`"),
            );
            return None;
        }
        let rates: Vec<SymId> =
            free.iter().copied().filter(|s| self.model.pool.symbol(*s).order() == 1).collect();
        if rates.is_empty() {
            return Some(ConstraintKind::Position);
        }
        // A(q, t)·q̇ + b(q, t): no rate may remain in a derivative by a rate.
        for v in &rates {
            let dv = self.model.pool.diff(phi, *v);
            let dv_free = self.model.pool.free_symbols(dv);
            if let Some(w) = dv_free.iter().find(|s| self.model.pool.symbol(**s).order() == 1) {
                let (v, w) = (
                    self.model.pool.symbol(*v).name.clone(),
                    self.model.pool.symbol(*w).name.clone(),
                );
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
}
