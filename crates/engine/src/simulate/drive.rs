//! Inputs driven in a run (`--input F=-20*x - 5*x'`): each law resolved against the scene,
//! then put in place of the input's symbol in the equations before they are lowered, so that
//! the run is an ordinary one. The equations are derived with the input held as a symbol and
//! only then driven: a law of the state is not differentiated with the Lagrangian.

use std::collections::HashMap;

use cas::{ExprId, SymId};
use sim::Method;

use crate::input::Assignment;
use crate::numbers::Prepared;
use crate::{Error, Setting};

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

/// The parameter slots of the inputs the settings give as time series, each with its series;
/// refused where a series does not cover the run, or its input is also driven by a law.
pub(crate) fn signals(
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

impl Prepared {
    /// Puts each law in place of its input in the equations (M, f, the generalized forces and
    /// each kept constraint's J, γ and Φ) and in the recorded expressions, whose partials then
    /// follow by the chain rule.
    pub(super) fn drive(&mut self, laws: &[(SymId, ExprId)]) {
        if laws.is_empty() {
            return;
        }
        let d = &mut self.derivation;
        let map: HashMap<SymId, ExprId> =
            laws.iter().map(|(s, law)| (*s, d.expand_quantities(*law, false))).collect();
        let pool = &mut d.model.pool;
        let mut driven = |e: &mut ExprId| *e = pool.subst(*e, &map);
        d.mass_matrix.iter_mut().flatten().for_each(&mut driven);
        d.forcing.iter_mut().for_each(&mut driven);
        d.generalized_forces.iter_mut().for_each(&mut driven);
        for m in &mut d.multipliers {
            m.jacobian.iter_mut().for_each(&mut driven);
            driven(&mut m.bias);
            driven(&mut m.phi);
        }
        self.extra.iter_mut().for_each(&mut driven);
        self.driven = map;
    }

    /// `e` with the driven inputs' laws in place of their symbols.
    pub(super) fn with_laws(&mut self, e: ExprId) -> ExprId {
        self.derivation.model.pool.subst(e, &self.driven)
    }
}

/// Refuses a symplectic method where a driven input enters the Lagrangian (through a
/// potential): those methods differentiate L, and the law must not be differentiated with it.
pub(super) fn check_method(
    prepared: &mut Prepared,
    laws: &[(SymId, ExprId)],
    method: Method,
) -> Result<(), Error> {
    if !method.is_symplectic() {
        return Ok(());
    }
    let d = &mut prepared.derivation;
    let in_lagrangian = d.model.pool.free_symbols(d.lagrangian);
    let Some((sym, _)) = laws.iter().find(|(s, _)| in_lagrangian.contains(s)) else {
        return Ok(());
    };
    Err(Error::Input(format!(
        "{} works from the Lagrangian, and the driven input `{}` is in it (through a \
         potential); use dop853 or radau",
        method.name(),
        d.model.pool.symbol(*sym).name
    )))
}
