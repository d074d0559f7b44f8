//! A run of a scene as the motion `linearize --along run` linearizes along: the scene run with
//! its `simulate` settings (and a front end's), its state recorded at the samples, the
//! linearization at each, and Φ over the run by the variational equations integrated beside
//! it (`sim::variational`, as `orbit` integrates them): with the run's method, tolerance and
//! step, from the exact Jacobian A is, so that Φ is the derivative of the run's own steps
//! ([`engine::along::Between::Model`]). The scene is resolved and derived once, for the run
//! and the linearization alike.

use engine::along::{Linearized, Motion};
use engine::Error;
use sim::variational::{self, End, Refusal};

use crate::{overrides, run_settings, set_expressions, start, Compiled, Options, Resolved};

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
    let method = settings.method;
    if method.form() != sim::Form::Physical || !method.is_explicit() {
        return Err(Error::Input(format!(
            "linearization along a run integrates Φ beside the run on an explicit method's \
             steps, and {} is not one: use dop853, the default, or another explicit method \
             (--method), or record the run (`lagrange simulate --out FILE.csv`) and give the \
             file to --along",
            method.name()
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
    let (slots, y0) = start(prepared, &values, &[])?;
    let mut along = engine::along::from_prepared(prepared, slots.clone())?;
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
    // Checked before Φ's run, which a motion of one sample would not need.
    engine::along::check_motion(&along, &motion)?;
    // The variational run records nothing (its value is its end): samples would only cut its
    // steps. It ends where the recorded run did, a stop's time included. Its step control
    // weighs Φ beside the state, so its steps are its own (115 against the recorded run's 93
    // on a pendulum's large swing at a tolerance of 1e-13, its end 2.5e-13 from the run's).
    let mut run = run_settings(&settings, 0);
    run.until = outcome.run.final_time;
    let mut mechanical = along.mechanical().clone();
    // The inputs at their declared values, as the recorded run held them.
    mechanical.set_parameters(&slots);
    let transition = variational::transition(&mut mechanical, &y0, &run, End::Time)
        .map_err(|refusal| refused(refusal, &outcome))?;
    let size = y0.len();
    let matrix = engine::along::DMatrix::from_row_slice(size, size, &transition.matrix);
    engine::along::linearize_run(&mut along, &motion, matrix)
}

/// Why the variational run gave no Φ, in words. Without contacts or a section, a fault is
/// the one refusal it can meet; the others are named for completeness.
fn refused(refusal: Refusal, outcome: &crate::Outcome) -> Error {
    match refusal {
        Refusal::Fault(fault) => Error::Numeric(format!(
            "integrating Φ beside the run: {}",
            outcome.describe_fault(&fault)
        )),
        other => Error::Numeric(format!("integrating Φ beside the run: {other:?}")),
    }
}
