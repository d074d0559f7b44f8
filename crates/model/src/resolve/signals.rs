//! `input` and `output` lines: the signals that enter the dynamics from outside, and the named
//! quantities measured from it. An input is refused wherever the derivation would need its
//! rate, which nothing knows.

use cas::{ExprId, SymId};
use lang::{Diagnostic, Expr, Span};

use super::checks::{Role, DRIVE, OUTPUT};
use super::dims::NameDims;
use super::{normalize, Binding, Resolver};
use crate::{Input, Output, Placeholder, Value};

impl Resolver<'_> {
    /// An `input` line: each name a symbol of its own, with its unit and the value it takes
    /// when nothing drives it (0 when none is written).
    pub(super) fn input_statement(&mut self, decls: &[lang::ParamDecl]) {
        for decl in decls {
            let form = self.scope.units.declared(&decl.name.name, decl.name.span, None);
            let value = decl.value.as_ref().map(|v| self.constant(v));
            if let Some(Some((_, dims))) = &value {
                let v = self.with_unit(Some(dims.clone()), decl.unit.as_ref());
                let span = decl.value.as_ref().map_or(decl.name.span, |v| v.span);
                self.scope.units.same(&form, &v, decl.name.span, span, "in this input");
            }
            let value = match value {
                Some(v) => v.and_then(|(v, _)| self.in_si(v, decl.unit.as_ref())),
                None => Some(self.model.pool.zero()),
            };
            let name = normalize(&decl.name.name);
            if self.scope.names.get(&name).is_some_and(|b| !matches!(b, Binding::Quantity(_))) {
                self.bind(&decl.name, Binding::Input(self.model.time));
                continue;
            }
            let sym = self.model.pool.param(&name);
            if !self.bind(&decl.name, Binding::Input(sym)) {
                continue;
            }
            let dims = NameDims { at: self.stmt, form: Some(form), entries: None };
            self.scope.name_dims.insert(name.clone(), dims);
            if let Some(value) = value {
                let unit = decl.unit.clone();
                self.model.inputs.push(Input { name, sym, value, unit, span: decl.name.span });
            }
        }
    }

    /// An `output` line: a scalar of the state, the inputs and time, with no acceleration and
    /// no reaction (its gradient is a row of C and D).
    pub(super) fn output_statement(&mut self, name: &lang::Ident, e: &Expr) {
        let Some((value, _)) = self.scalar_in_role(e, &OUTPUT) else { return };
        if self.names_reaction(value) {
            self.error(
                Diagnostic::error(e.span, "an output cannot name a reaction")
                    .with_label("a reaction is found with the accelerations")
                    .with_hint(OUTPUT.hint),
            );
            return;
        }
        let key = normalize(&name.name);
        if self.model.outputs.iter().any(|o| o.name == key) {
            self.error(
                Diagnostic::error(name.span, format!("output `{}` is given twice", name.name))
                    .with_label("second output of this name"),
            );
            return;
        }
        self.model.outputs.push(Output { name: key, value, span: name.span });
    }

    /// Whether `value` names a reaction, which is found only with the accelerations.
    fn names_reaction(&mut self, value: ExprId) -> bool {
        self.model.pool.free_symbols(value).iter().any(|s| {
            self.model
                .placeholders
                .iter()
                .any(|(p, k)| p == s && matches!(k, Placeholder::Reaction(_)))
        })
    }

    /// What drives the input `input` (its index) in a run: a scalar of `t`, the state and the
    /// parameters, of the input's dimension, naming no acceleration, reaction or input.
    pub(super) fn drive(&mut self, input: usize, e: &Expr) -> Option<ExprId> {
        let (value, dims) = self.scalar_in_role(e, &DRIVE)?;
        let name = self.model.inputs[input].name.clone();
        let refusal = if self.names_reaction(value) {
            Some(("cannot name a reaction", "a reaction is found with the accelerations"))
        } else if self.input_in(&Value::Scalar(value)).is_some() {
            Some(("cannot name an input", "an input, driven or held at its value"))
        } else {
            None
        };
        if let Some((message, label)) = refusal {
            self.error(
                Diagnostic::error(e.span, format!("what drives `{name}` {message}"))
                    .with_label(label)
                    .with_hint(DRIVE.hint),
            );
            return None;
        }
        // A number alone takes the input's dimension, as a force written `(1, 0)` does.
        let form = self.operand_form(dims);
        if let Some(declared) = self.scope.name_dims.get(&name).and_then(|d| d.form.clone()) {
            let what = format!("between the input `{name}` and what drives it");
            self.scope.units.same(&declared, &form, e.span, e.span, &what);
        }
        Some(value)
    }

    /// The first input in `value`, if any.
    pub(super) fn input_in(&mut self, value: &Value) -> Option<SymId> {
        let inputs: Vec<SymId> = self.model.inputs.iter().map(|u| u.sym).collect();
        value.entries().into_iter().find_map(|e| self.input_in_expr(e, &inputs))
    }

    fn input_in_expr(&mut self, e: ExprId, inputs: &[SymId]) -> Option<SymId> {
        self.model.pool.free_symbols(e).iter().copied().find(|s| inputs.contains(s))
    }

    /// Whether `value` (of `e`) is free of inputs where its role needs it so; reports the
    /// smallest part of `e` that names one.
    pub(super) fn without_inputs(&mut self, e: &Expr, value: &Value, role: &Role) -> bool {
        let Some((_, d)) = self.input_diagnostic(e, value, role) else { return true };
        self.error(d);
        false
    }

    /// The input `value` (of `e`) holds where its role may not, and why, at the smallest part
    /// of `e` that names it; `None` where it holds none or may.
    pub(super) fn input_diagnostic(
        &mut self,
        e: &Expr,
        value: &Value,
        role: &Role,
    ) -> Option<(SymId, Diagnostic)> {
        if role.inputs {
            return None;
        }
        let input = self.input_in(value)?;
        let name = self.model.pool.symbol(input).name.clone();
        let part = self.input_part(e);
        let hint = if role.instead_of_input.is_empty() {
            format!(
                "an input stands where no rate of it is needed: in a force, a torque, a \
                 potential, a dissipation function or a spring; {} cannot hold one, since \
                 deriving the equations would differentiate `{name}` in time",
                role.what
            )
        } else {
            role.instead_of_input.replace("{name}", &name)
        };
        let d = Diagnostic::error(
            part.span,
            format!("{} cannot depend on the input `{name}`", role.what),
        )
        .with_label(format!("depends on `{name}`"))
        .with_hint(hint);
        Some((input, d))
    }

    /// The smallest part of `e` whose value names an input.
    fn input_part<'e>(&mut self, e: &'e Expr) -> &'e Expr {
        for child in super::checks::children(e) {
            let Some(v) = self.value_quietly(child) else { continue };
            if self.input_in(&v).is_some() {
                return self.input_part(child);
            }
        }
        e
    }

    /// Refuses the rate of PE or of a reaction in a scene with inputs: what they stand for may
    /// hold an input (a potential's, a force's), and its rate is not known. KE cannot hold one.
    pub(super) fn refuse_placeholder_rate_with_inputs(&mut self, p: SymId, span: Span) {
        let Some(input) = self.model.inputs.first() else { return };
        let kind = self.model.placeholders.iter().find(|(s, _)| *s == p).map(|(_, k)| *k);
        if matches!(kind, Some(Placeholder::KineticEnergy)) {
            return;
        }
        let name = input.name.clone();
        let what = self.model.pool.symbol(p).name.clone();
        self.error(
            Diagnostic::error(
                span,
                format!("the rate of `{what}` is not known in a scene with inputs"),
            )
            .with_label(format!("may depend on the rate of `{name}`"))
            .with_hint(
                "write the rate out from the terms it stands for, without the inputs' rates",
            ),
        );
    }

    /// Refuses the rate of an expression that holds an input, at `span`: the input's rate is
    /// not known. Whether it was refused.
    pub(super) fn refuse_input_rate(&mut self, e: ExprId, span: Span) -> bool {
        let inputs: Vec<SymId> = self.model.inputs.iter().map(|u| u.sym).collect();
        let Some(input) = self.input_in_expr(e, &inputs) else { return false };
        let name = self.model.pool.symbol(input).name.clone();
        self.error(
            Diagnostic::error(span, format!("this rate needs the rate of the input `{name}`"))
                .with_label(format!("depends on `{name}`"))
                .with_hint("an input's rate is not known: differentiate what drives it instead"),
        );
        true
    }
}

impl Resolver<'_> {
    /// An `expect linearized:` line: a verdict, an eigenvalue of constants, or a parameter
    /// with the constant where the verdict changes.
    pub(super) fn expect_linearized(&mut self, expectation: &lang::LinearExpectation, span: Span) {
        use crate::{ExpectedStability, LinearExpectation};
        let resolved = match expectation {
            lang::LinearExpectation::Verdict { word, .. } => {
                let stability = match word.as_str() {
                    "stable" => ExpectedStability::Stable,
                    "unstable" => ExpectedStability::Unstable,
                    _ => ExpectedStability::MarginallyStable,
                };
                Some(LinearExpectation::Stability(stability))
            }
            lang::LinearExpectation::Eigenvalue(e) => self.eigenvalue(e),
            lang::LinearExpectation::Critical { parameter, value } => {
                let index = match self.scope.names.get(&normalize(&parameter.name)) {
                    Some(Binding::Param(s)) => self.model.params.iter().position(|p| p.sym == *s),
                    _ => None,
                };
                self.scope.used.insert(normalize(&parameter.name));
                if index.is_none() {
                    let params: Vec<&str> =
                        self.model.params.iter().map(|p| p.name.as_str()).collect();
                    let name = normalize(&parameter.name);
                    let why = "a critical value is one of a parameter, where the verdict changes";
                    // Among a scene's few parameters, a short name one edit from exactly one
                    // of them is a slip of that one (`kk` for `k`), which `closest` leaves out
                    // among all names.
                    let one_edit: Vec<&str> = params
                        .iter()
                        .copied()
                        .filter(|p| strsim::levenshtein(&name, p) == 1)
                        .collect();
                    let near = super::closest(&name, params.iter().copied())
                        .or(if let [only] = one_edit[..] { Some(only) } else { None });
                    let hint = match (near, &params[..]) {
                        (_, []) => format!("{why}; the scene declares no parameter"),
                        (Some(near), _) => format!("did you mean `{near}`?"),
                        (None, _) => format!("{why}; the parameters are {}", params.join(", ")),
                    };
                    self.error(
                        Diagnostic::error(
                            parameter.span,
                            format!("`{}` is not a parameter", parameter.name),
                        )
                        .with_label("not a parameter")
                        .with_hint(hint),
                    );
                }
                let value = self.constant(value).map(|(v, _)| v);
                match (index, value) {
                    (Some(parameter), Some(value)) => {
                        Some(LinearExpectation::Critical { parameter, value })
                    }
                    _ => None,
                }
            }
        };
        if let Some(expectation) = resolved {
            let text = self.text(span);
            self.model.linear_expects.push(crate::LinearExpect { expectation, text, span });
        }
    }

    /// An expected eigenvalue: a real constant, or `(re, im)`.
    fn eigenvalue(&mut self, e: &Expr) -> Option<crate::LinearExpectation> {
        if let lang::ExprKind::Tuple(parts) = &e.kind {
            let [re, im] = &parts[..] else {
                self.error(
                    Diagnostic::error(e.span, "an eigenvalue is a number or a pair (re, im)")
                        .with_label(format!("{} entries", parts.len())),
                );
                return None;
            };
            let (re, im) = (self.constant(re), self.constant(im));
            return Some(crate::LinearExpectation::Eigenvalue { re: re?.0, im: im?.0 });
        }
        let (re, _) = self.constant(e)?;
        Some(crate::LinearExpectation::Eigenvalue { re, im: self.model.pool.zero() })
    }
}
