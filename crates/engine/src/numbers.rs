//! From a derivation to numbers: parameter values, the initial state, and the lowered
//! programs that `simulate` runs and `export` prints. This is the glue between symbols
//! (`mechanics`) and slots (`numeric`, `sim`); it gathers exactly the expressions a command
//! needs and nothing more.

use cas::{ExprId, SymId};
use mechanics::Derivation;
use numeric::{lower, Program};
use sim::Layout;

use crate::{Error, Options, Piece, Setting};

mod partials;
mod sensitivity;

/// The error for a value `setting` gives the derived parameter `i`.
pub fn derived_error(plan: &model::ParameterValues, setting: Setting, i: usize) -> Error {
    let name = plan.names().nth(i).unwrap_or_default().to_string();
    Error::given(setting, name, format!(": {}", plan.derived_error(i)))
}

/// The fewest coordinates at which a scene with a recursive form is solved by it
/// ([`Prepared::recursive`]): about where its sweep overtakes factoring M.
pub const RECURSIVE_FROM: usize = 8;

/// A scene loaded for numbers, with extra expressions (outputs, events, `--set` values)
/// resolved against it.
pub struct Prepared {
    pub derivation: Derivation,
    /// The extra expressions, in the order asked for, expanded into the remaining
    /// coordinates (they may still mention accelerations and multipliers).
    pub extra: Vec<ExprId>,
    pub parameters: Vec<SymId>,
    pub layout: Layout,
    /// The inputs a run drives by laws, each with its law (empty unless `simulate --input`).
    pub driven: std::collections::HashMap<SymId, ExprId>,
    /// The partials program of the equations in (q, q̇), once a run has lowered it: a scene
    /// compiled for many runs lowers it once (`simulate::Compiled`).
    pub partials_program: Option<Program>,
    /// Where each contact's rows are among the multipliers, in the order written.
    pub contacts: Vec<mechanics::ContactSlots>,
    /// Each contact's arming condition in the state (`armed A`), in the order written.
    pub arming: Vec<Option<ExprId>>,
    /// The one way to the parameters' values: free ones set, derived ones following.
    pub parameter_plan: model::ParameterValues,
    /// Parameters a run gives other values than the scene's (`--set b=2*a`), each an
    /// expression of the parameters: their sensitivities follow those expressions, as a derived
    /// parameter's follow its own ([`Prepared::set_parameter_overrides`]).
    pub parameter_overrides: Vec<(usize, ExprId)>,
}

/// Loads `source` with `extra` expressions resolved against it as the scene's `show` items
/// are (reactions they name are derived too), before it is derived. A mistake in one of them
/// is an [`Error::Expression`], its diagnostics pointing into the expression.
pub fn prepare(source: &str, extra: &[String], options: Options) -> Result<Prepared, Error> {
    let (model, warnings) = crate::resolve_with(source, options)?;
    prepare_resolved(source, model, warnings, extra)
}

/// [`prepare`] of a model already resolved from `source` (and extended through its scope, as
/// `linearize --about` extends it), with its warnings.
pub fn prepare_resolved(
    source: &str,
    model: model::Model,
    warnings: Vec<lang::Diagnostic>,
    extra: &[String],
) -> Result<Prepared, Error> {
    let unnamed: Vec<(Option<&str>, String)> = extra.iter().map(|t| (None, t.clone())).collect();
    prepare_resolved_for(source, model, warnings, &unnamed)
}

/// [`prepare_resolved`] with some extra expressions given as values for a name (`--set
/// L=20 cm`): those take a unit, checked against the name's dimension
/// ([`model::Model::resolve_value_for`]).
pub fn prepare_resolved_for(
    source: &str,
    mut model: model::Model,
    warnings: Vec<lang::Diagnostic>,
    extra: &[(Option<&str>, String)],
) -> Result<Prepared, Error> {
    let mut values = Vec::new();
    for (name, text) in extra {
        let value = match name {
            Some(name) => model.resolve_value_for(name, text),
            None => model.resolve_expression(text),
        };
        let value =
            value.map_err(|diagnostics| Error::Expression { diagnostics, text: text.clone() })?;
        values.push(value);
    }
    let extra: Vec<String> = extra.iter().map(|(_, text)| text.clone()).collect();
    let extra = &extra;
    let mut derivation = for_numbers(crate::derive_resolved(source, model, warnings)?.derivation);
    let mut exprs = Vec::new();
    for (value, text) in values.iter().zip(extra) {
        let model::Value::Scalar(e) = value else {
            return Err(Error::Input(format!(
                "`{text}` is {}, and only scalars can be recorded",
                value.kind_name()
            )));
        };
        exprs.push(derivation.expand_quantities(*e, false));
    }
    Ok(Prepared::from_derivation(derivation, exprs))
}

/// A scene derived already (by [`crate::load_with`], with the same options) laid out for
/// numbers, as [`prepare`] would lay it out: a front end that holds a loaded scene takes its
/// numbers from a copy of the derivation rather than deriving the text again.
pub fn prepare_derived(derivation: Derivation) -> Prepared {
    Prepared::from_derivation(for_numbers(derivation), Vec::new())
}

/// A run gives every contact a multiplier of its own, open or closed, and records it (0 while
/// open): the reaction the derivation solved for in the mode at the start holds only while
/// that mode does (a bead's push off a sphere would be recorded pulling once it flew).
fn for_numbers(mut derivation: Derivation) -> Derivation {
    let constraints = &derivation.model.constraints;
    derivation.reactions.retain(|r| !constraints[r.constraint].kind.is_unilateral());
    derivation
}

impl Prepared {
    /// A derived scene laid out for numbers, with `extra` expressions of it to observe.
    pub fn from_derivation(mut derivation: Derivation, extra: Vec<ExprId>) -> Prepared {
        let exprs = extra;
        // A run integrates every contact, open or closed, among its multipliers.
        let contacts = derivation.with_every_contact();
        let arming = derivation
            .contacts
            .clone()
            .iter()
            .map(|c| {
                let armed = derivation.model.contacts[c.contact].armed?;
                Some(derivation.expand_quantities(armed, false))
            })
            .collect();
        // The inputs' slots follow the parameters', filled with their values when nothing
        // drives them.
        let parameters: Vec<SymId> = derivation.model.constants().iter().map(|(s, _)| *s).collect();
        let layout = Layout {
            coordinates: derivation.coords.len(),
            multipliers: derivation.multipliers.len(),
            parameters: parameters.len(),
        };
        let parameter_plan = model::ParameterValues::new(&derivation.model);
        Prepared {
            parameter_plan,
            derivation,
            extra: exprs,
            parameters,
            layout,
            driven: Default::default(),
            partials_program: None,
            contacts,
            arming,
            parameter_overrides: Vec::new(),
        }
    }
}

impl Prepared {
    pub fn coordinate_names(&self) -> Vec<String> {
        let pool = &self.derivation.model.pool;
        self.derivation.coords.iter().map(|s| pool.symbol(*s).name.clone()).collect()
    }

    /// Names of the state slots: coordinates, then rates.
    pub fn state_names(&self) -> Vec<String> {
        let pool = &self.derivation.model.pool;
        let d = &self.derivation;
        d.coords.iter().chain(&d.rates).map(|s| pool.symbol(*s).name.clone()).collect()
    }

    /// Names of the parameter slots, the inputs' after the parameters', in slot order.
    pub fn parameter_slot_names(&self) -> Vec<String> {
        let pool = &self.derivation.model.pool;
        self.parameters.iter().map(|s| pool.symbol(*s).name.clone()).collect()
    }

    /// An error naming the scene's contacts, for a stage that does not take them yet
    /// (`what` says which); `Ok` for a scene without any.
    pub fn refuse_contacts(&self, what: &str) -> Result<(), Error> {
        let d = &self.derivation;
        if d.contacts.is_empty() {
            return Ok(());
        }
        let names: Vec<String> =
            d.contacts.iter().map(|c| format!("`{}`", d.model.contacts[c.contact].name)).collect();
        Err(Error::Input(format!(
            "{what} does not take contacts yet, and this scene has {}: runs take them \
             (`lagrange simulate`, `Scene.simulate` in Python), or make the contact a \
             `constraint` if it never opens",
            names.join(", ")
        )))
    }

    /// An error naming the scene's rough contacts, for a stage that does not take Coulomb
    /// friction yet (`what` says which); `Ok` for a scene without any.
    pub fn refuse_friction(&self, what: &str) -> Result<(), Error> {
        let d = &self.derivation;
        let names: Vec<String> = d
            .contacts
            .iter()
            .map(|c| &d.model.contacts[c.contact])
            .filter(|c| c.friction.is_some())
            .map(|c| format!("`{}`", c.name))
            .collect();
        if names.is_empty() {
            return Ok(());
        }
        Err(Error::Input(format!(
            "{what} does not take Coulomb friction yet, and this scene's {} has it: runs take \
             it (`lagrange simulate`), or make the contact grip (`grip V`) or smooth",
            names.join(", ")
        )))
    }

    /// The parameters' values `parameters` (in slot order) indexed by symbol, as
    /// `numeric::eval` takes them.
    fn by_symbol(&self, parameters: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.derivation.model.pool.symbol_count()];
        for (s, v) in self.parameters.iter().zip(parameters) {
            values[s.index()] = *v;
        }
        values
    }

    /// Newton's coefficient of each contact at the parameters' values `parameters` (in slot
    /// order), in the order written.
    pub fn restitutions(&self, parameters: &[f64]) -> Vec<f64> {
        let (d, values) = (&self.derivation, self.by_symbol(parameters));
        d.contacts.iter().map(|c| numeric::eval(&d.model.pool, c.restitution, &values)).collect()
    }

    /// Coulomb's coefficient of each rough contact at the parameters' values `parameters`
    /// (in slot order), `None` for the others, in the order written.
    pub fn frictions(&self, parameters: &[f64]) -> Vec<Option<f64>> {
        let (d, values) = (&self.derivation, self.by_symbol(parameters));
        d.contacts
            .iter()
            .map(|c| {
                let mu = d.model.contacts[c.contact].friction?;
                Some(numeric::eval(&d.model.pool, mu, &values))
            })
            .collect()
    }

    /// Whether any contact has Coulomb friction.
    pub fn has_friction(&self) -> bool {
        let d = &self.derivation;
        d.contacts.iter().any(|c| d.model.contacts[c.contact].friction.is_some())
    }

    /// The constraints kept with multipliers, by name, in the order of their slots.
    /// The contacts' names, in the order written (a run's mode events index them).
    pub fn contact_names(&self) -> Vec<String> {
        let d = &self.derivation;
        d.contacts.iter().map(|c| d.model.contacts[c.contact].name.clone()).collect()
    }

    pub fn kept_constraint_names(&self) -> Vec<String> {
        let d = &self.derivation;
        d.multipliers.iter().map(|m| d.model.constraints[m.constraint].name.clone()).collect()
    }

    /// `[t, q, q̇, parameters]`.
    pub fn dynamics_inputs(&self) -> Vec<SymId> {
        let d = &self.derivation;
        let mut v = vec![d.model.time];
        v.extend(&d.coords);
        v.extend(&d.rates);
        v.extend(&self.parameters);
        v
    }

    /// `[t, q, q̇, q̈, λ, parameters]`.
    pub fn observation_inputs(&self) -> Vec<SymId> {
        let d = &self.derivation;
        let mut v = vec![d.model.time];
        v.extend(&d.coords);
        v.extend(&d.rates);
        v.extend(&d.accels);
        v.extend(d.multipliers.iter().map(|m| m.lambda));
        v.extend(&self.parameters);
        v
    }

    /// M (column-major), f, and per kept constraint J, γ, Φ, Φ̇: the layout of
    /// [`sim::Mechanical`].
    pub fn dynamics_exprs(&mut self) -> Vec<ExprId> {
        let d = &mut self.derivation;
        let mut v = mass_matrix_by_columns(d);
        v.extend(&d.forcing);
        for m in &d.multipliers {
            v.extend(&m.rows.jacobian);
            v.push(m.rows.bias);
            v.push(m.rows.phi());
            // A velocity constraint is stabilised on its residual alone.
            v.push(m.rows.drift_rate(&d.model.pool));
        }
        v
    }

    /// The programs of q̈ by the recursive form's sweep (inputs those of the dynamics
    /// program), where the scene has the form and at least [`RECURSIVE_FROM`] coordinates:
    /// below that the dense route is as fast, and keeps the bits small scenes have always had.
    pub fn recursive(&mut self) -> Result<Option<sim::Recursive>, Error> {
        self.recursive_from(RECURSIVE_FROM)
    }

    /// [`Prepared::recursive`] from `fewest` coordinates on (tests hold small scenes to it).
    pub fn recursive_from(&mut self, fewest: usize) -> Result<Option<sim::Recursive>, Error> {
        // A law driving an input may move a position in time, which the form was judged
        // without.
        if self.derivation.coords.len() < fewest || !self.driven.is_empty() {
            return Ok(None);
        }
        let Some(form) = self.derivation.chain_form() else { return Ok(None) };
        let nodes: Vec<(Option<usize>, Vec<usize>)> =
            form.nodes.iter().map(|node| (node.parent, node.coordinates.clone())).collect();
        let chain = sim::Chain::new(form.dimension, &nodes);
        let terms = self.lower(&self.dynamics_inputs(), &form.outputs())?;
        Ok(Some(chain.lower(terms)))
    }

    /// How the integrator stabilises each kept constraint, in slot order.
    pub fn stabilisation(&self) -> Vec<sim::Stabilisation> {
        let of = |m: &mechanics::Multiplier| match m.rows.stabilisation {
            mechanics::Stabilisation::Position => sim::Stabilisation::Position,
            mechanics::Stabilisation::Velocity => sim::Stabilisation::Velocity,
        };
        self.derivation.multipliers.iter().map(of).collect()
    }

    /// M, p = ∂L/∂q̇ and ∂L/∂q + Q: the layout of [`sim::Canonical`].
    pub fn momentum_exprs(&mut self) -> Vec<ExprId> {
        let d = &mut self.derivation;
        let n = d.coords.len();
        let mut v = mass_matrix_by_columns(d);
        for i in 0..n {
            v.push(d.model.pool.diff(d.lagrangian, d.rates[i]));
        }
        for i in 0..n {
            let dl = d.model.pool.diff(d.lagrangian, d.coords[i]);
            v.push(d.model.pool.add2(dl, d.generalized_forces[i]));
        }
        v
    }

    pub fn lower(&self, inputs: &[SymId], outputs: &[ExprId]) -> Result<Program, Error> {
        lower(&self.derivation.model.pool, inputs, outputs).map_err(|e| self.lower_error(e))
    }

    /// Why an expression could not be lowered, as an error.
    pub fn lower_error(&self, e: numeric::LowerError) -> Error {
        match e {
            numeric::LowerError::UnboundSymbol(s) => {
                let name = &self.derivation.model.pool.symbol(s).name;
                Error::Input(format!(
                    "`{name}` has no numeric value here (it is not part of the state)"
                ))
            }
        }
    }

    /// Parameter values in declaration order, with `overrides` (parameter index → expression
    /// of earlier parameters) taking the place of the scene's values; then the inputs' values
    /// when nothing drives them (the slots of [`Prepared::parameters`]).
    pub fn parameter_values(&self, overrides: &[(usize, ExprId)]) -> Result<Vec<f64>, Error> {
        self.parameter_values_given(overrides, &[])
    }

    /// [`Prepared::parameter_values`] with numbers `given` to some parameters (by index), in
    /// place of their expressions: an ensemble's run. Later parameters defined through them
    /// follow. A derived parameter cannot be given a value (`--set` names it; `--vary` a
    /// given number's).
    pub fn parameter_values_given(
        &self,
        overrides: &[(usize, ExprId)],
        given: &[(usize, f64)],
    ) -> Result<Vec<f64>, Error> {
        let model = &self.derivation.model;
        let plan = &self.parameter_plan;
        for (settings, i) in overrides
            .iter()
            .map(|(i, _)| (Setting::Set, *i))
            .chain(given.iter().map(|(i, _)| (Setting::Vary, *i)))
        {
            if plan.is_derived(i) {
                return Err(derived_error(plan, settings, i));
            }
        }
        let mut values: Vec<(usize, model::Given)> =
            overrides.iter().map(|(i, e)| (*i, model::Given::expression(model, *e))).collect();
        values.extend(given.iter().map(|(i, v)| (*i, model::Given::Number(*v))));
        self.parameter_plan.clone().values(values).map_err(|e| match e {
            model::ParameterError::Missing { name } => Error::Setting(vec![
                Piece::Text(format!(
                    "parameter `{name}` has no value; give one in the scene or with "
                )),
                Piece::Given(Setting::Set, name),
            ]),
            other => Error::Input(other.to_string()),
        })
    }

    /// The initial state (q, then q̇, of the remaining coordinates) at the given parameter
    /// values; `overrides` (the coordinate's index in the model, whether it is the rate, an
    /// expression of the parameters) take the place of the scene's values, the last one of a
    /// slot winning.
    pub fn initial_state(
        &self,
        parameters: &[f64],
        overrides: &[(usize, bool, ExprId)],
    ) -> Result<Vec<f64>, Error> {
        let model = &self.derivation.model;
        let n = self.layout.coordinates;
        let mut y0 = vec![0.0; 2 * n];
        for (k, q) in self.derivation.coords.iter().enumerate() {
            let Some(i) = model.coords.iter().position(|c| c.sym == *q) else { continue };
            let c = &model.coords[i];
            let find = |rate: bool| {
                overrides.iter().rev().find(|(j, r, _)| *j == i && *r == rate).map(|x| x.2)
            };
            y0[k] = self.constant(find(false).unwrap_or(c.initial), parameters);
            y0[n + k] = self.constant(find(true).unwrap_or(c.initial_rate), parameters);
        }
        if let Some(slot) = y0.iter().position(|v| !v.is_finite()) {
            return Err(Error::Input(format!(
                "the initial value of `{}` is not a finite number",
                self.state_names()[slot]
            )));
        }
        Ok(y0)
    }

    /// Refuses a mass that is not positive, or an inertia that is negative, at the given
    /// parameter values; those that depend on the motion are left alone.
    pub fn masses_at(&mut self, parameters: &[f64]) -> Result<(), Error> {
        for body in self.derivation.model.bodies.clone() {
            for (value, inertia) in [(Some(body.mass), false), (body.planar_inertia(), true)] {
                let Some(value) = value else { continue };
                let pool = &mut self.derivation.model.pool;
                let constant = pool
                    .free_symbols(value)
                    .iter()
                    .all(|s| matches!(pool.symbol(*s).kind, cas::SymbolKind::Param));
                if !constant {
                    continue;
                }
                let v = self.constant(value, parameters);
                let (what, unit) =
                    if inertia { ("an inertia", "kg·m²") } else { ("a mass", "kg") };
                if (inertia && v < 0.0) || (!inertia && v <= 0.0) {
                    let rule = if inertia { "cannot be negative" } else { "must be positive" };
                    return Err(Error::Setting(vec![
                        Piece::Text("with the values of ".into()),
                        Piece::Setting(Setting::Set),
                        Piece::Text(format!(
                            ", `{}` has {what} of {v} {unit}; {what} {rule}",
                            body.name
                        )),
                    ]));
                }
            }
        }
        Ok(())
    }

    /// The value of a constant expression (of parameters) at the given parameter values.
    pub fn constant(&self, e: ExprId, parameters: &[f64]) -> f64 {
        let pool = &self.derivation.model.pool;
        let mut values = vec![f64::NAN; pool.symbol_count()];
        for (s, v) in self.parameters.iter().zip(parameters) {
            values[s.index()] = *v;
        }
        values[self.derivation.model.time.index()] = 0.0;
        numeric::eval(pool, e, &values)
    }
}

/// M entry by entry, column after column: the order the solvers read it in.
fn mass_matrix_by_columns(d: &Derivation) -> Vec<ExprId> {
    let n = d.coords.len();
    (0..n).flat_map(|j| (0..n).map(move |i| d.mass_matrix[i][j])).collect()
}

impl Prepared {
    /// A value per symbol at the start `y0` (`[q, q̇]` in slot order): the parameters, t = 0,
    /// the coordinates and their rates.
    fn start_values(&self, y0: &[f64], parameters: &[f64]) -> Vec<f64> {
        let d = &self.derivation;
        let n = d.coords.len();
        let mut values = vec![f64::NAN; d.model.pool.symbol_count()];
        for (s, v) in self.parameters.iter().zip(parameters) {
            values[s.index()] = *v;
        }
        values[d.model.time.index()] = 0.0;
        for k in 0..n {
            values[d.coords[k].index()] = y0[k];
            values[d.rates[k].index()] = y0[n + k];
        }
        values
    }

    /// Checks the start's positions against the kept position constraints at the values a
    /// run uses (the scene's, with `--set`): positions the scene left free are solved again
    /// there, and a start that breaks a constraint all the same is an error, rather than a run
    /// that Baumgarte drags back onto it.
    pub fn settle_positions(
        &mut self,
        y0: &mut [f64],
        parameters: &[f64],
        set_positions: &[bool],
    ) -> Result<(), Error> {
        let values = self.start_values(y0, parameters);
        let d = &mut self.derivation;
        let broken = |d: &mechanics::Derivation, values: &[f64]| {
            // A contact may start open: only the two-sided constraints hold the start.
            d.multipliers
                .iter()
                .filter(|m| !d.model.constraints[m.constraint].kind.is_unilateral())
                .filter_map(|m| m.rows.position.map(|phi| (m.constraint, phi)))
                .map(|(constraint, phi)| {
                    let (v, size) = numeric::value_and_magnitude(&d.model.pool, phi, values);
                    (constraint, v, size)
                })
                .find(|(_, v, size)| !verify::within_rounding(*v, *size))
        };
        let Some((first, ..)) = broken(d, &values) else { return Ok(()) };
        let free: Vec<SymId> = d
            .free_start_positions()
            .into_iter()
            .filter(|q| !d.coords.iter().position(|c| c == q).is_some_and(|k| set_positions[k]))
            .collect();
        let solved = if free.is_empty() {
            None
        } else {
            verify::solve_positions(d, &free, values.clone(), true)
        };
        let Some(solved) = solved else {
            let name = &d.model.constraints[first].name;
            let (.., v, _) = broken(d, &values).expect("broken");
            return Err(Error::Input(format!(
                "with these values the start breaks the constraint `{name}` (this side \
                 minus that is {v:.6e} at the start); set start positions that satisfy it, or \
                 leave one it restrains without a value in the scene for lagrange to solve"
            )));
        };
        for (q, v) in solved {
            let k = d.coords.iter().position(|c| *c == q).expect("remaining");
            y0[k] = v;
        }
        Ok(())
    }

    /// Makes the start's rates satisfy the kept constraints (at the velocity level) again
    /// after `--set` changed parameters, positions or rates: the rates the scene left to the
    /// constraints (and `--set` did not give) are solved for at the new state, numerically;
    /// with none to solve for, rates that break a row are an error. `y0` is `[q, q̇]` in slot
    /// order; `set_rates` marks the rates `--set` gave.
    pub fn settle_rates(
        &mut self,
        y0: &mut [f64],
        parameters: &[f64],
        set_rates: &[bool],
    ) -> Result<(), Error> {
        let start_values = self.start_values(y0, parameters);
        let d = &mut self.derivation;
        if d.multipliers.is_empty() {
            return Ok(());
        }
        let n = d.coords.len();
        let two_sided: Vec<mechanics::Multiplier> = d
            .multipliers
            .iter()
            .filter(|m| !d.model.constraints[m.constraint].kind.is_unilateral())
            .cloned()
            .collect();
        if two_sided.is_empty() {
            return Ok(());
        }
        let rows: Vec<ExprId> = two_sided.iter().map(|m| m.rows.velocity).collect();
        let pool = &mut d.model.pool;
        let free: Vec<usize> = (0..n)
            .filter(|k| {
                let c = d.model.coords.iter().find(|c| c.sym == d.coords[*k]).expect("declared");
                !c.initial_rate_given
                    && !set_rates[*k]
                    && rows.iter().any(|r| pool.depends_on(*r, d.rates[*k]))
            })
            .collect();
        let mut values = start_values;
        if free.len() != rows.len() {
            // Nothing to solve for: the rates must satisfy the rows as they are, or the run
            // would start off the constraints and be dragged back by the stabilisation.
            for (m, row) in two_sided.iter().zip(&rows) {
                let (v, size) = numeric::value_and_magnitude(pool, *row, &values);
                if !verify::within_rounding(v, size) {
                    let name = &d.model.constraints[m.constraint].name;
                    return Err(Error::Input(format!(
                        "with these values the start's rates break the constraint \
                         `{name}` (this side minus that is {v:.6e} at the start); set rates \
                         that satisfy it, or leave some it restrains without a value in the \
                         scene for lagrange to solve"
                    )));
                }
            }
            return Ok(());
        }
        for k in &free {
            values[d.rates[*k].index()] = 0.0;
        }
        let size = rows.len();
        let mut a = nalgebra::DMatrix::zeros(size, size);
        let mut b = vec![0.0; size];
        for (i, row) in rows.iter().enumerate() {
            b[i] = -numeric::eval(pool, *row, &values);
            for (j, k) in free.iter().enumerate() {
                let coefficient = pool.diff(*row, d.rates[*k]);
                a[(i, j)] = numeric::eval(pool, coefficient, &values);
            }
        }
        let mut pivots = vec![0; size];
        sim::linalg::solve_general(&mut a, &mut b, &mut pivots).map_err(|_| {
            Error::Input(
                "the rates left to the velocity constraints are not fixed by them at the \
                 state --set gives; give them with --set too"
                    .into(),
            )
        })?;
        for (j, k) in free.iter().enumerate() {
            y0[n + *k] = b[j];
        }
        Ok(())
    }
}

impl Prepared {
    /// Puts each law in place of its input in the equations (M, f, the generalized forces and
    /// each kept constraint's rows) and in the recorded expressions, whose partials then
    /// follow by the chain rule.
    pub fn drive(&mut self, laws: &[(SymId, ExprId)]) {
        if laws.is_empty() {
            return;
        }
        let d = &mut self.derivation;
        let map: std::collections::HashMap<SymId, ExprId> =
            laws.iter().map(|(s, law)| (*s, d.expand_quantities(*law, false))).collect();
        let pool = &mut d.model.pool;
        let mut driven = |e: &mut ExprId| *e = pool.subst(*e, &map);
        d.mass_matrix.iter_mut().flatten().for_each(&mut driven);
        d.forcing.iter_mut().for_each(&mut driven);
        d.generalized_forces.iter_mut().for_each(&mut driven);
        for m in &mut d.multipliers {
            m.rows.exprs_mut().for_each(&mut driven);
        }
        self.extra.iter_mut().for_each(&mut driven);
        self.driven = map;
    }

    /// `e` with the driven inputs' laws in place of their symbols.
    pub fn with_laws(&mut self, e: ExprId) -> ExprId {
        self.derivation.model.pool.subst(e, &self.driven)
    }
}
