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
        r.inputs = std::mem::take(&mut model.inputs);
        r.outputs = std::mem::take(&mut model.outputs);
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
        r.linear_expects = std::mem::take(&mut model.linear_expects);
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
        *model = self.into_model();
    }
}
