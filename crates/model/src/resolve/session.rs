//! Resolving more against a scene already resolved: the [`Scope`] a [`Model`] keeps, and
//! expressions and `linearize about` items resolved against it.

use std::collections::HashMap;

use cas::{ExprId, SymId};
use lang::{Diagnostic, Span};

use super::dims::{BodyDims, NameDims};
use super::{Binding, Resolver};
use crate::units::{Form, Inference};
use crate::{Checks, Model, Value};

/// What resolving a scene leaves behind for resolving more expressions against it later: its
/// names and what they are bound to, the dimension facts and the values of its parameters.
/// A [`Model`] keeps it, for [`Model::resolve_expression`] and [`Model::resolve_about`].
#[derive(Clone, Default)]
pub struct Scope {
    pub(super) names: HashMap<String, Binding>,
    pub(super) declared: HashMap<String, (Span, &'static str)>,
    pub(super) used: std::collections::HashSet<String>,
    pub(super) param_values: HashMap<SymId, ExprId>,
    /// The statements resolved so far, the scene's and the expressions' since.
    pub(super) statements: usize,
    pub(super) units: Inference,
    pub(super) name_dims: HashMap<String, NameDims>,
    pub(super) body_dims: Vec<BodyDims>,
    pub(super) loose: HashMap<String, Form>,
    pub(super) quaternions: Vec<(Vec<Vec<ExprId>>, [ExprId; 4], Span)>,
    pub(super) checks: Checks,
}

impl Model {
    /// Resolves `text`, one expression, against the scene as a `show` item would be (it may
    /// name anything the scene declares, reactions included, which marks them requested for
    /// the derivation). On failure, the diagnostics, with spans into `text`.
    pub fn resolve_expression(&mut self, text: &str) -> Result<Value, Vec<Diagnostic>> {
        let expr = lang::parse_expression(text)?;
        self.resolving(text, |r| r.value(&expr).map(|(v, _)| v))
    }

    /// Resolves `text`, a value given for `name` in place of the scene's (`--set L=20 cm`,
    /// `--set theta=30 deg`), as the scene writes a value: an expression with an optional
    /// unit, converted to SI. With a unit, the value must have the dimension of the parameter
    /// or coordinate (or rate, `theta'`) it replaces; without one it is read as
    /// [`Model::resolve_expression`] reads it. On failure, the diagnostics, with spans into
    /// `text`.
    pub fn resolve_value_for(&mut self, name: &str, text: &str) -> Result<Value, Vec<Diagnostic>> {
        let (expr, unit) = lang::parse_quantity(text)?;
        let Some(unit) = unit else {
            return self.resolving(text, |r| r.value(&expr).map(|(v, _)| v));
        };
        let base = name.trim_end_matches('\'');
        let primes = (name.len() - base.len()) as u8;
        let target = super::normalize(base);
        self.resolving(text, |r| {
            let (value, dims) = r.value(&expr)?;
            let Value::Scalar(e) = value else { return Some(value) };
            // A name the scene does not have is the caller's to report, naming its options.
            if matches!(r.scope.names.get(&target), Some(Binding::Param(_) | Binding::Coord(_))) {
                let whole = Span::new(0, text.len());
                if let Some((_, expected)) = r.name(base, primes, whole) {
                    let written = r.with_unit(Some(dims), Some(&unit));
                    let expected = r.form(expected);
                    let what = format!("in this value of `{name}`");
                    r.scope.units.same(&expected, &written, unit.span, expr.span, &what);
                }
            }
            r.in_si(e, Some(&unit)).map(Value::Scalar)
        })
    }

    /// Resolves `text`, what drives the input of index `input` in a run (a feedback law such
    /// as `-20*x - 5*x'`), against the scene as an expression after it: of `t`, the state and
    /// the parameters, with the input's dimension. On failure, the diagnostics, with spans
    /// into `text`.
    pub fn resolve_drive(&mut self, input: usize, text: &str) -> Result<ExprId, Vec<Diagnostic>> {
        let expr = lang::parse_expression(text)?;
        self.resolving(text, |r| r.drive(input, &expr))
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

    /// [`Model::resolve_about`] with the values of the `varying` parameters unknown to its
    /// checks: a front end that changes them (`--set`, a sweep) has the reference checked in
    /// numbers at the values in force, where the scene's values would judge a domain wrongly
    /// (`acos(g*b/(w^2*a^2))` beyond 1 at the scene's w, inside at the one set).
    pub fn resolve_about_varying(
        &mut self,
        text: &str,
        varying: &[SymId],
    ) -> Result<(), Vec<Diagnostic>> {
        let values = &mut self.scope.param_values;
        let held: Vec<(SymId, ExprId)> =
            varying.iter().filter_map(|s| values.remove(s).map(|v| (*s, v))).collect();
        let resolved = self.resolve_about(text);
        self.scope.param_values.extend(held);
        resolved
    }

    /// Runs `resolve` on a resolver with the model's state and its scope, `text` the source
    /// its spans point into; the model takes back what it added, or the errors if any.
    fn resolving<T>(
        &mut self,
        text: &str,
        resolve: impl FnOnce(&mut Resolver<'_>) -> Option<T>,
    ) -> Result<T, Vec<Diagnostic>> {
        let mut r = Resolver::resume(self, text);
        let mark = r.scope.units.mark();
        let index = r.stmt + 1;
        r.enter(index);
        let value = resolve(&mut r);
        let mut errors = std::mem::take(&mut r.diagnostics.errors);
        if errors.is_empty() && r.scope.checks.units {
            errors = r.scope.units.solve();
        }
        if !errors.is_empty() {
            r.scope.units.rollback(mark);
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
        r.model = super::Draft::take(model);
        r.scope = std::mem::take(&mut model.scope);
        r.stmt = r.scope.statements;
        r.in_outputs = true;
        r
    }

    /// Gives `model` back what [`Resolver::resume`] took, with what was added since.
    fn suspend(self, model: &mut Model) {
        *model = self.into_model();
    }
}
