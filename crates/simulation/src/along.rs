//! A run of a scene as the motion `linearize --along run` linearizes along: the scene run with
//! its `simulate` settings (and a front end's), its state recorded at the samples, and the
//! linearization at each with Φ integrated by the scene's own equations between them
//! ([`engine::along::Between::Model`]). The scene is resolved and derived once, for the run and
//! the linearization alike.

use engine::along::{Between, Linearized, Motion};
use engine::Error;

use crate::{overrides, set_expressions, Compiled, Options, Resolved};

/// The linearization along a run of `source` with `options` (its `--set` values the run's
/// parameters and start alike). A run whose inputs are driven (by the options or the scene's
/// `simulate` block) is refused: what drives them would be part of the linearization too.
pub fn linearize_run(source: &str, options: &Options) -> Result<Linearized, Error> {
    let resolved = Resolved::new(source, options);
    // Every declared coordinate and rate is recorded, the remaining ones picked after the
    // derivation has said which they are.
    let declared = resolved.declared_states();
    let options = Options { output: declared.clone(), animate: false, ..options.clone() };
    let settings = resolved.settings(&options)?;
    let mut driven: Vec<String> = settings.drives.iter().map(|d| format!("`{}`", d.name)).collect();
    driven.extend(settings.series.iter().map(|(name, _)| format!("`{name}`")));
    if !driven.is_empty() {
        return Err(Error::Input(format!(
            "a run to linearize along keeps its inputs at their declared values, and this one \
             drives {} (by the scene's `simulate` block or the options): to linearize along a \
             driven motion, record it with the inputs among the outputs (`lagrange simulate \
             SCENE --output` the coordinates, their rates and the inputs, `--out FILE.csv`) \
             and give that file to --along",
            driven.join(", ")
        )));
    }
    let mut compiled = Compiled::from_resolved(resolved, &settings)?;
    engine::along::refuse(compiled.prepared_mut())?;
    let outcome = compiled.run(&settings, &mut ())?;
    if let Some(fault) = &outcome.run.fault {
        return Err(Error::Numeric(outcome.describe_fault(fault)));
    }
    let prepared = compiled.prepared_mut();
    let sets = set_expressions(prepared, &settings.sets)?;
    let values = overrides(prepared, &settings.sets, &sets)?;
    let slots = prepared.parameter_values(&values.params)?;
    let mut along = engine::along::from_prepared(prepared, slots)?;
    let mut columns = Vec::new();
    for name in along.state_names() {
        let Some(k) = declared.iter().position(|d| *d == name) else {
            return Err(Error::Input(format!("the run recorded no column of `{name}`")));
        };
        columns.push(k);
    }
    let resting = along.resting_inputs();
    let trajectory = &outcome.run.trajectory;
    let mut motion = Motion::default();
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        // A stop or the end may be recorded at a sample's time too: one row a time.
        if motion.times.last().is_some_and(|last| *t <= *last) {
            continue;
        }
        motion.times.push(*t);
        motion.states.push(columns.iter().map(|&k| row[k]).collect());
        motion.inputs.push(resting.clone());
    }
    engine::along::linearize_along(&mut along, &motion, Between::Model)
}
