//! `constraint` statements: the equation resolved and classified as holonomic or a velocity
//! constraint.

use cas::{ExprId, SymId, SymbolKind};
use lang::{Diagnostic, Expr, Ident, Span};

use super::{checks, normalize, space, Binding, Resolver};
use crate::{Constraint, ConstraintKind, Placeholder, Value};

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
            let index = self.model.constraints.len();
            let force_symbol = self.model.pool.param(&format!("{cname}.force"));
            let lhs_free = self.model.pool.free_symbols(l);
            let lhs_coords = lhs_free
                .iter()
                .copied()
                .filter(|s| {
                    matches!(
                        self.model.pool.symbol(*s).kind,
                        SymbolKind::Coordinate { order: 0, .. }
                    )
                })
                .collect();
            self.model.placeholders.push((force_symbol, Placeholder::Reaction(index)));
            self.model.constraints.push(Constraint {
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
