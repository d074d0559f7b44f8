//! The problem a method integrates, built once from the lowered programs: the equations in
//! (q, q̇), in canonical variables for the symplectic methods, or with the kept constraints as
//! they are for radau. `simulate` runs it once; an ensemble clones it per thread and runs it
//! at one set of parameters after another.

use std::ops::ControlFlow;

use numeric::Tape;
use sim::{Canonical, Constrained, Event, Form, Mechanical, Method, Problem, Rows, Run};

use super::{with_partials, Columns, Settings, NO_MULTIPLIERS};
use engine::numbers::Prepared;
use engine::Error;

/// The equations of a run in the form its method integrates.
#[derive(Clone)]
pub enum Integrand {
    /// y = (q, q̇), with the partials of the exact Jacobian for the methods that use one.
    Mechanical(Mechanical),
    /// y = (q, p), for the symplectic methods (boxed: it holds the problem in (q, q̇) too).
    Canonical(Box<Canonical>),
    /// y = (q, q̇, q̈, λ), the differential–algebraic system radau takes constraints as.
    Constrained(Constrained),
}

impl Integrand {
    /// The form `method` integrates, with what it needs lowered now (`auto`'s partials
    /// included, which a single run lowers at its first switch instead).
    pub fn new(
        prepared: &mut Prepared,
        mechanical: Mechanical,
        method: Method,
    ) -> Result<Integrand, Error> {
        // The contacts first: their rows are multipliers too, and a refusal should name them.
        let mechanical = with_contacts(prepared, mechanical, method)?;
        if prepared.layout.multipliers > 0 && !method.handles_multipliers() {
            return Err(Error::Input(format!(
                "{} {NO_MULTIPLIERS}; use dop853 or radau",
                method.name()
            )));
        }
        let form = method.form();
        if form == Form::Canonical {
            let momentum_exprs = prepared.momentum_exprs();
            let momentum = prepared.lower(&prepared.dynamics_inputs(), &momentum_exprs)?;
            let mut canonical = Canonical::new(mechanical, Tape::new(momentum));
            if method.uses_jacobian() {
                let exprs = prepared.canonical_partials_exprs();
                let partials = prepared.lower(&prepared.dynamics_inputs(), &exprs)?;
                canonical = canonical.with_partials(Tape::new(partials));
            }
            return Ok(Integrand::Canonical(Box::new(canonical)));
        }
        let mechanical = with_partials(prepared, method, mechanical)?;
        if form == Form::Algebraic && prepared.layout.multipliers > 0 {
            return Ok(Integrand::Constrained(Constrained::new(mechanical)));
        }
        Ok(Integrand::Mechanical(mechanical))
    }

    /// The equations in (q, q̇) underneath, whose parameters a run sets.
    pub fn mechanical(&mut self) -> &mut Mechanical {
        match self {
            Integrand::Mechanical(m) => m,
            Integrand::Canonical(c) => &mut c.inner,
            Integrand::Constrained(c) => c.inner_mut(),
        }
    }

    /// Integrates from the physical state `y0` = (q, q̇) at t = 0.
    pub fn integrate(
        &mut self,
        y0: &[f64],
        settings: &sim::Settings,
        watched: &[Event],
        progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
    ) -> Run {
        self.integrate_to(y0, settings, watched, progress, None)
    }

    /// [`Integrand::integrate`], its rows handed to `rows` (where given) rather than kept
    /// ([`sim::integrate_into`]).
    pub fn integrate_to(
        &mut self,
        y0: &[f64],
        settings: &sim::Settings,
        watched: &[Event],
        progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
        rows: Option<&mut dyn Rows>,
    ) -> Run {
        let integrate = |problem: &mut dyn Problem,
                         y0: &[f64],
                         progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
                         rows: Option<&mut dyn Rows>| match rows {
            Some(rows) => sim::integrate_into(problem, y0, settings, watched, progress, rows),
            None => sim::integrate(problem, y0, settings, watched, progress),
        };
        match self {
            Integrand::Mechanical(m) => integrate(m, y0, progress, rows),
            Integrand::Canonical(c) => {
                let z0 = c.from_physical(0.0, y0);
                integrate(&mut **c, &z0, progress, rows)
            }
            Integrand::Constrained(c) => match c.consistent_state(0.0, y0) {
                Ok(z0) => integrate(c, &z0, progress, rows),
                // No consistent accelerations at the start: the stabilised form reports why
                // (which of the mass matrix and the constraints lost rank) as its first fault.
                Err(_) => integrate(c.inner_mut() as &mut dyn Problem, y0, progress, rows),
            },
        }
    }
}

/// The most steps a run takes: a run that cannot end (`until 1e300`) ends in a fault.
pub(crate) const MAX_STEPS: usize = 20_000_000;

/// The integrator's settings of a run recording `samples` evenly spaced times.
pub fn run_settings(settings: &Settings, samples: usize) -> sim::Settings {
    sim::Settings {
        method: settings.method,
        start: 0.0,
        until: settings.until,
        tolerance: settings.tolerance,
        step: settings.step,
        max_steps: MAX_STEPS,
        samples,
    }
}

/// The stops and events watched, by their observation columns.
pub fn watched(columns: &Columns) -> Vec<Event> {
    let Columns { outputs, stops, events } = *columns;
    (0..stops)
        .map(|k| Event { column: outputs + k, stop: true })
        .chain((0..events).map(|k| Event { column: outputs + stops + k, stop: false }))
        .collect()
}

/// The scene's contacts given to the problem, each with its restitution at the run's
/// parameter values; a method that cannot take them refuses the run, naming them.
pub(crate) fn with_contacts(
    prepared: &Prepared,
    mechanical: Mechanical,
    method: Method,
) -> Result<Mechanical, Error> {
    if prepared.contacts.is_empty() {
        return Ok(mechanical);
    }
    if !method.handles_contacts() {
        let d = &prepared.derivation;
        let names: Vec<String> =
            d.contacts.iter().map(|c| format!("`{}`", d.model.contacts[c.contact].name)).collect();
        return Err(Error::Input(format!(
            "{} does not take contacts, and this scene has {}: use dop853, radau or auto",
            method.name(),
            names.join(", ")
        )));
    }
    if prepared.has_friction() && method.form() == sim::Form::Algebraic {
        // The differential–algebraic form assembles its residual from the rows as they are:
        // a slipping contact's bent column is the stabilised form's alone for now.
        return Err(Error::Input(format!(
            "{} integrates the constraints as they are and does not take Coulomb friction yet: \
             use dop853 or auto",
            method.name()
        )));
    }
    let restitutions = restitutions(prepared, mechanical.parameters())?;
    let frictions = frictions(prepared, mechanical.parameters())?;
    let contacts = prepared
        .contacts
        .iter()
        .zip(restitutions)
        .zip(frictions)
        .map(|((slots, restitution), friction)| sim::Contact {
            normal: slots.normal,
            grip: slots.grip,
            cross: slots.cross,
            restitution,
            friction,
        })
        .collect();
    let mechanical = mechanical.with_contacts(contacts);
    if prepared.arming.iter().all(Option::is_none) {
        return Ok(mechanical);
    }
    // A contact without a condition is always armed: its condition is 1.
    let one = prepared.derivation.model.pool.one();
    let conditions: Vec<cas::ExprId> = prepared.arming.iter().map(|a| a.unwrap_or(one)).collect();
    let program = prepared.lower(&prepared.dynamics_inputs(), &conditions)?;
    let conditioned = prepared.arming.iter().map(Option::is_some).collect();
    Ok(mechanical.with_arming(Tape::new(program), conditioned))
}

/// Each rough contact's coefficient of friction at the parameter values `parameters` (in slot
/// order), checked not to be negative (a run's `--set` or an ensemble's draw may make it so);
/// `None` for the others.
pub fn frictions(prepared: &Prepared, parameters: &[f64]) -> Result<Vec<Option<f64>>, Error> {
    if !prepared.has_friction() {
        return Ok(vec![None; prepared.contacts.len()]);
    }
    let values = prepared.frictions(parameters);
    for (name, mu) in prepared.contact_names().iter().zip(&values) {
        if let Some(mu) = mu.filter(|mu| mu.is_nan() || *mu < 0.0) {
            return Err(Error::Input(format!(
                "the coefficient of friction of contact `{name}` is {mu} at this run's values: \
                 Coulomb's coefficient is not negative"
            )));
        }
    }
    Ok(values)
}

/// Each contact's restitution at the parameter values `parameters` (in slot order), checked
/// to lie in [0, 1]: a run's `--set` or an ensemble's draw may take it out, which the scene's
/// own values could not.
pub fn restitutions(prepared: &Prepared, parameters: &[f64]) -> Result<Vec<f64>, Error> {
    if prepared.contacts.is_empty() {
        // Nothing to evaluate, and nothing allocated: an ensemble asks once a run.
        return Ok(Vec::new());
    }
    let values = prepared.restitutions(parameters);
    for (name, e) in prepared.contact_names().iter().zip(&values) {
        if !(0.0..=1.0).contains(e) {
            return Err(Error::Input(format!(
                "the restitution of contact `{name}` is {e} at this run's values: Newton's \
                 coefficient lies between 0 and 1"
            )));
        }
    }
    Ok(values)
}
