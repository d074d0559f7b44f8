//! A run of a scene as the motion `linearize --along run` linearizes along: the scene run with
//! its `simulate` settings (and a front end's), its state recorded at the samples, and the
//! linearization at each with Φ integrated by the scene's own equations between them
//! ([`engine::along::Between::Model`]).

use engine::along::{Along, Between, Linearized, Motion};
use engine::Error;

use crate::Options;

/// The linearization along a run of `source` with `options` (its `--set` values the run's
/// parameters and start alike).
pub fn linearize_run(source: &str, options: &Options) -> Result<Linearized, Error> {
    let along_options = engine::along::Options {
        set: options.set.clone(),
        no_units: options.no_units,
        starts_allowed: true,
    };
    let mut along = engine::along::along(source, &along_options)?;
    let motion = run_motion(source, options, &along)?;
    engine::along::linearize_along(&mut along, &motion, Between::Model)
}

/// The run's samples as a motion: its state at each recorded time, the inputs at their
/// declared values. A run whose inputs are driven is refused: what drives them would have to
/// be part of the linearization too.
pub fn run_motion(source: &str, options: &Options, along: &Along) -> Result<Motion, Error> {
    if !options.input.is_empty() || !options.input_series.is_empty() || options.hold.is_some() {
        return Err(Error::Input(
            "a run to linearize along keeps its inputs at their declared values: to linearize \
             along a driven motion, record it with the inputs among the outputs (`lagrange \
             simulate SCENE --input … --output …` to a CSV file) and give that file to --along"
                .into(),
        ));
    }
    let options = Options { output: along.state_names(), animate: false, ..options.clone() };
    let outcome = crate::simulate(source, &options)?;
    if let Some(fault) = &outcome.run.fault {
        return Err(Error::Numeric(outcome.describe_fault(fault)));
    }
    let size = 2 * along.coordinates().len();
    let trajectory = &outcome.run.trajectory;
    let resting = along.resting_inputs();
    let mut motion = Motion::default();
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        // A stop or the end may be recorded at a sample's time too: one row a time.
        if motion.times.last().is_some_and(|last| *t <= *last) {
            continue;
        }
        motion.times.push(*t);
        motion.states.push(row[..size].to_vec());
        motion.inputs.push(resting.clone());
    }
    Ok(motion)
}
