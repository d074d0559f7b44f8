//! Inputs driven in a run (`--input F=-20*x - 5*x'`): each law resolved against the scene,
//! then put in place of the input's symbol in the equations before they are lowered, so that
//! the run is an ordinary one. The equations are derived with the input held as a symbol and
//! only then driven: a law of the state is not differentiated with the Lagrangian.

use std::collections::HashMap;

use cas::{ExprId, SymId};
use sim::Method;

use engine::input::Assignment;
use engine::numbers::Prepared;
use engine::{Error, Setting};

/// The inputs `drives` names, each with its law resolved in the scene's scope; an input not
/// driven keeps the value it is declared with.
pub(super) fn laws(
    model: &mut model::Model,
    drives: &[Assignment],
) -> Result<Vec<(SymId, ExprId)>, Error> {
    let mut laws: Vec<(SymId, ExprId)> = Vec::new();
    for drive in drives {
        let Some(index) = model.inputs.iter().position(|u| u.name == drive.name) else {
            return Err(Error::given(
                Setting::Input,
                &drive.name,
                unknown_input(model, &drive.name),
            ));
        };
        let sym = model.inputs[index].sym;
        if laws.iter().any(|(s, _)| *s == sym) {
            return Err(Error::given(Setting::Input, &drive.name, ": driven twice"));
        }
        let law = model
            .resolve_drive(index, &drive.value)
            .map_err(|diagnostics| Error::Expression { diagnostics, text: drive.value.clone() })?;
        laws.push((sym, law));
    }
    Ok(laws)
}

/// Puts each input that stands in a constraint out of it: its law. The constraint's rates and
/// second derivative are then derived with the law in place, exactly. Refused where they
/// cannot be: no law (the scene's error where the input stands, as every other command
/// gives it), a law of the rates (the constraint would restrain velocities), a time series (it
/// has no rates), a hold (the constraint would jump at each sample).
pub(super) fn into_constraints(
    source: &str,
    model: &mut model::Model,
    laws: &[(SymId, ExprId)],
    settings: &super::Settings,
) -> Result<(), Error> {
    let mut values: HashMap<SymId, ExprId> = HashMap::new();
    for input in &model.inputs {
        let Some(constraint) = model.constraints.iter().find(|c| {
            model.pool.free_symbols(c.lhs).contains(&input.sym)
                || model.pool.free_symbols(c.rhs).contains(&input.sym)
        }) else {
            continue;
        };
        let refuse = |why: &str| {
            let text = format!(": drives the constraint `{}`, {why}", constraint.name);
            Err(Error::given(Setting::Input, &input.name, text))
        };
        if settings.series.iter().any(|(name, _)| *name == input.name) {
            return refuse(
                "whose second derivative needs the input's first and second rates, and a time \
                 series has none; give a law of t and the coordinates",
            );
        }
        let Some(value) = laws.iter().find(|(s, _)| *s == input.sym).map(|(_, law)| *law) else {
            let refused = model.inputs_in_constraints.iter().filter(|(s, _)| *s == input.sym);
            let diagnostics = refused.map(|(_, d)| d.clone()).collect();
            return Err(Error::Scene { diagnostics, source: source.to_string() });
        };
        if settings.hold.is_some() {
            return refuse("which a held value would make jump at every sample; drop the hold");
        }
        let free = model.pool.free_symbols(value);
        if free.iter().any(|s| model.pool.symbol(*s).order() > 0) {
            return refuse(
                "so its law may name t, the coordinates and the parameters, not rates (the \
                 constraint would then restrain velocities)",
            );
        }
        values.insert(input.sym, value);
    }
    if values.is_empty() {
        return Ok(());
    }
    let pool = &mut model.pool;
    for c in &mut model.constraints {
        c.lhs = pool.subst(c.lhs, &values);
        c.rhs = pool.subst(c.rhs, &values);
        c.phi = pool.subst(c.phi, &values);
    }
    Ok(())
}

/// The parameter slots of the inputs the settings give as time series, each with its series;
/// refused where a series does not cover the run, or its input is also driven by a law.
pub fn signals(
    prepared: &Prepared,
    settings: &super::Settings,
) -> Result<Vec<(usize, sim::Series)>, Error> {
    let model = &prepared.derivation.model;
    let mut signals = Vec::new();
    for (name, series) in &settings.series {
        let Some(input) = model.inputs.iter().find(|u| u.name == *name) else {
            return Err(Error::given(Setting::Input, name, unknown_input(model, name)));
        };
        let Some(slot) = prepared.parameters.iter().position(|s| *s == input.sym) else {
            return Err(Error::given(Setting::Input, name, ": has no slot in this run"));
        };
        if settings.drives.iter().any(|d| d.name == *name)
            || signals.iter().any(|(s, _)| *s == slot)
        {
            return Err(Error::given(Setting::Input, name, ": driven twice"));
        }
        let (first, last) = series.span();
        if first > 0.0 || last < settings.until {
            return Err(Error::given(
                Setting::Input,
                name,
                format!(
                    ": the series spans t = {first} to {last} s, and the run needs it from 0 to \
                     {} s; extend it, or shorten the run",
                    settings.until
                ),
            ));
        }
        signals.push((slot, series.clone()));
    }
    Ok(signals)
}

/// Refuses a hold that is not a positive time, or that would hold nothing: it samples the laws
/// of driven inputs, and a run with none is surely not what was meant.
pub(super) fn check_hold(hold: Option<f64>, drives: &[Assignment]) -> Result<(), Error> {
    let Some(period) = hold else { return Ok(()) };
    if !(period.is_finite() && period > 0.0) {
        return Err(Error::setting(
            Setting::Hold,
            format!(" must be a positive time, not {period}"),
        ));
    }
    if drives.is_empty() {
        return Err(Error::setting(
            Setting::Hold,
            " samples the laws that drive inputs, and no input is driven by one; give a law \
             with `input NAME=EXPR`",
        ));
    }
    Ok(())
}

/// The zero-order hold of the laws `held`, sampled every `period`: each law lowered from the
/// dynamics program's inputs into its input's parameter slot.
pub fn hold(
    prepared: &mut Prepared,
    held: &[(SymId, ExprId)],
    period: Option<f64>,
) -> Result<Option<sim::Hold>, Error> {
    let Some(period) = period else { return Ok(None) };
    let mut slots = Vec::new();
    let mut exprs = Vec::new();
    for (sym, law) in held {
        let Some(slot) = prepared.parameters.iter().position(|s| s == sym) else {
            let name = prepared.derivation.model.pool.symbol(*sym).name.clone();
            return Err(Error::given(Setting::Input, &name, ": has no slot in this run"));
        };
        slots.push(slot);
        exprs.push(prepared.derivation.expand_quantities(*law, false));
    }
    let laws = prepared.lower(&prepared.dynamics_inputs(), &exprs)?;
    Ok(Some(sim::Hold::new(period, slots, numeric::Tape::new(laws))))
}

/// Why no input has the name given, with the nearest name and the inputs there are.
fn unknown_input(model: &model::Model, given: &str) -> String {
    let names: Vec<&str> = model.inputs.iter().map(|u| u.name.as_str()).collect();
    if names.is_empty() {
        return ": the scene has no input; declare one with `input NAME = VALUE UNIT`".into();
    }
    let known = names.join(", ");
    match model::closest(given, names.iter().copied()) {
        Some(near) => format!(": no input of that name; did you mean `{near}`? (inputs: {known})"),
        None => format!(": no input of that name; the inputs are {known}"),
    }
}

/// The first input driven by a law that is in the Lagrangian (through a potential), if any.
pub(super) fn in_lagrangian(prepared: &mut Prepared, laws: &[(SymId, ExprId)]) -> Option<SymId> {
    let d = &mut prepared.derivation;
    let in_lagrangian = d.model.pool.free_symbols(d.lagrangian);
    laws.iter().map(|(s, _)| *s).find(|s| in_lagrangian.contains(s))
}

/// Refuses a symplectic method where a driven input enters the Lagrangian (through a
/// potential): those methods differentiate L, and the law must not be differentiated with it.
pub(super) fn check_method(
    prepared: &mut Prepared,
    laws: &[(SymId, ExprId)],
    method: Method,
) -> Result<(), Error> {
    let Some(sym) = in_lagrangian(prepared, laws).filter(|_| method.is_symplectic()) else {
        return Ok(());
    };
    Err(Error::Input(format!(
        "{} {}: `{}` is; use dop853 or radau",
        method.name(),
        super::DRIVEN_IN_LAGRANGIAN,
        prepared.derivation.model.pool.symbol(sym).name
    )))
}
