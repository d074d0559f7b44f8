//! A scene derived and lowered once for many runs: what a run costs before its first step
//! (parsing, resolving, deriving, lowering; milliseconds, most of a short run) is paid by
//! [`Compiled::new`], and each [`Compiled::run`] only resolves its `--set` values, settles its
//! start and integrates. A front end that runs one scene again and again (the Python
//! package's `simulate` and `batch`) keeps one and reuses it while the settings that shape
//! its programs stay the same ([`Compiled::fits`]).

use numeric::{Program, Tape};
use sim::Mechanical;

use super::rows::{Sink, Tee, Totals, Watched};
use super::{
    angle_oriented_bodies, conserves_energy, drive, integrate_scene, load, overrides,
    set_expressions, start, Columns, Loaded, Outcome, Progress, Resolved, Settings,
};
use crate::animate::{Animation, ContactTrack, Plan};
use engine::numbers::Prepared;
use engine::Error;

/// A scene loaded with a run's expressions (outputs, stops, events, driven inputs) and its
/// dynamics and observation programs lowered.
pub struct Compiled {
    /// The settings it was made for, with what only a run reads left at their defaults.
    shape: Settings,
    prepared: Prepared,
    outputs: Vec<String>,
    columns: Columns,
    dynamics: Program,
    /// The programs of q̈ by the recursive form, where q̈ is solved by it.
    recursive: Option<sim::Recursive>,
    /// The observations, lowered once; `None` with an animation, whose figures' expressions
    /// take the run's parameter values and are lowered with each run.
    observation: Option<Program>,
    conservative: bool,
    /// The laws of the inputs held between samples, each with its input.
    held: Vec<(cas::SymId, cas::ExprId)>,
    /// An input driven continuously is in the Lagrangian.
    lagrangian_driven: bool,
}

impl Compiled {
    /// Loads and derives `source` with the settings' expressions and lowers its programs.
    pub fn new(source: &str, settings: &Settings) -> Result<Compiled, Error> {
        Compiled::from_loaded(load(source, settings)?, settings)
    }

    /// [`Compiled::new`] of a scene whose settings were read from it already resolved.
    pub(crate) fn from_resolved(
        resolved: Resolved<'_>,
        settings: &Settings,
    ) -> Result<Compiled, Error> {
        Compiled::from_loaded(resolved.load(settings)?, settings)
    }

    fn from_loaded(loaded: Loaded, settings: &Settings) -> Result<Compiled, Error> {
        let Loaded { mut prepared, outputs, held, lagrangian_driven } = loaded;
        let columns = Columns {
            outputs: outputs.len(),
            stops: settings.stops.len(),
            events: settings.events.len(),
        };
        let dynamics_exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs)?;
        let recursive = prepared.recursive()?;
        let observation = if settings.animate {
            None
        } else {
            let observed = &prepared.extra[..columns.figures()];
            Some(prepared.lower(&prepared.observation_inputs(), observed)?)
        };
        let conservative = conserves_energy(&mut prepared.derivation, &dynamics_exprs);
        Ok(Compiled {
            shape: shape(settings),
            prepared,
            outputs,
            columns,
            dynamics,
            recursive,
            observation,
            conservative,
            held,
            lagrangian_driven,
        })
    }

    /// The loaded scene, for what a front end lowers of it besides the run's programs
    /// (after them, so that the run's are the ones `simulate` lowers).
    pub(crate) fn prepared_mut(&mut self) -> &mut Prepared {
        &mut self.prepared
    }

    /// Whether a run with these settings can reuse the programs: they differ at most in what
    /// a run reads alone (the end time, tolerance, step, samples, `--set` values and input
    /// series).
    pub fn fits(&self, settings: &Settings) -> bool {
        self.shape == shape(settings)
    }

    /// Runs the scene with `settings`, which must [`fit`](Compiled::fits) it (a front end
    /// asks); the `--set` values are resolved against the derived scene here. A run that
    /// faults is an [`Outcome`] with its fault, and what was computed before it.
    pub fn run(
        &mut self,
        settings: &Settings,
        progress: &mut dyn Progress,
    ) -> Result<Outcome, Error> {
        self.run_to(settings, progress, None)
    }

    /// [`Compiled::run`], handing the rows to `sink` as they are made rather than keeping
    /// them (the outcome's trajectory left empty); with an animation, whose figures need
    /// every row, they are kept and handed to `sink` after the run.
    pub fn run_into(
        &mut self,
        settings: &Settings,
        progress: &mut dyn Progress,
        sink: &mut dyn Sink,
    ) -> Result<Outcome, Error> {
        self.run_to(settings, progress, Some(sink))
    }

    fn run_to(
        &mut self,
        settings: &Settings,
        progress: &mut dyn Progress,
        sink: Option<&mut dyn Sink>,
    ) -> Result<Outcome, Error> {
        let prepared = &mut self.prepared;
        let columns = &self.columns;
        let set_exprs = set_expressions(prepared, &settings.sets)?;
        let values = overrides(prepared, &settings.sets, &set_exprs)?;
        let (parameters, y0) = start(prepared, &values, &[])?;
        // The figures' numbers follow the energies, before the constraints' residuals that
        // the integrator appends.
        let mut plan = settings.animate.then(|| Plan::new(prepared, &parameters));
        // A `draw` line may show an input: what drives it, in a driven run.
        for e in plan.iter_mut().flat_map(|p| p.exprs.iter_mut()) {
            *e = prepared.with_laws(*e);
        }
        let n_drawn = plan.as_ref().map_or(0, |p| p.exprs.len());
        let observation = match (&self.observation, &plan) {
            (Some(program), None) => program.clone(),
            _ => {
                let mut observed: Vec<cas::ExprId> = prepared.extra[..columns.figures()].to_vec();
                observed.extend(plan.iter().flat_map(|p| p.exprs.iter().copied()));
                prepared.lower(&prepared.observation_inputs(), &observed)?
            }
        };
        let signals = drive::signals(prepared, settings)?;
        let hold = drive::hold(prepared, &self.held, settings.hold)?;
        let mut mechanical = Mechanical::new(
            prepared.layout,
            Tape::new(self.dynamics.clone()),
            Tape::new(observation),
            parameters,
        )
        .with_kinds(prepared.stabilisation())
        .with_signals(signals);
        if let Some(recursive) = &self.recursive {
            mechanical = mechanical.with_chain(recursive.clone());
        }
        if let Some(hold) = hold {
            mechanical = mechanical.with_hold(hold);
        }
        let constraint_columns: Vec<usize> =
            (0..prepared.layout.multipliers).map(|c| columns.figures() + n_drawn + c).collect();
        let watched = Watched::new(columns, constraint_columns.clone());
        let (streamed, after) = if plan.is_none() { (sink, None) } else { (None, sink) };
        let mut tee = streamed.map(|sink| Tee {
            sink,
            names: Some(&self.outputs),
            watched: &watched,
            totals: Totals::default(),
        });
        let rows = tee.as_mut().map(|tee| tee as &mut dyn sim::Rows);
        let (run, wall_seconds, fastest_mode) =
            integrate_scene(prepared, mechanical, &y0, settings, columns, progress, rows)?;
        let totals = match tee {
            Some(mut tee) => {
                // A run that ended at its start recorded no row: its table is the names.
                tee.begin();
                tee.totals
            }
            None => Totals::of(&watched, &run.trajectory.times, &run.trajectory.rows),
        };
        if let Some(sink) = after {
            sink.columns(&self.outputs);
            for (t, row) in run.trajectory.times.iter().zip(&run.trajectory.rows) {
                sink.row(*t, &row[..columns.outputs], watched.energy(row));
            }
        }

        let conservative = self.conservative;
        let figures = plan.map(|p| p.figures(&run.trajectory.rows, columns.figures()));
        let model = &prepared.derivation.model;
        let mut outcome = Outcome {
            columns: [
                &self.outputs[..],
                &settings.stops,
                &settings.events,
                &["KE".into(), "PE".into()],
            ]
            .concat(),
            run,
            totals,
            shown: columns.outputs,
            energy_columns: (columns.energies(), columns.energies() + 1),
            constraint_columns,
            event_names: [&settings.stops[..], &settings.events].concat(),
            stop_names: columns.stops,
            method: settings.method,
            wall_seconds,
            state_names: prepared.state_names(),
            constraint_names: prepared.kept_constraint_names(),
            contact_names: prepared.contact_names(),
            contacts_in_space: prepared.contacts.iter().map(|c| c.cross.is_some()).collect(),
            parameter_names: prepared.parameter_slot_names(),
            angle_oriented_bodies: angle_oriented_bodies(model),
            conservative,
            animation: None,
            fastest_mode,
            lagrangian_driven: self.lagrangian_driven,
        };
        if let Some(figures) = figures {
            let energy = outcome.energy();
            let times = &outcome.run.trajectory.times;
            outcome.animation = Some(Animation {
                title: model.title.clone(),
                dimension: model.dimension(),
                times: times.clone(),
                energy_error: energy_error(times, &energy),
                conservative,
                figures,
                contacts: ContactTrack::of(&outcome.contact_names, times, &outcome.run.modes),
                contact_events: outcome.run.modes.clone(),
            });
        }
        Ok(outcome)
    }
}

/// E(t) − E(0) at each recorded time, less what the jumps before it changed E by: two rows at
/// one time are the states before and after an impact, whose change is the impact's, not the
/// integrator's error (as the summary measures the drift, [`Totals`]).
fn energy_error(times: &[f64], energy: &[f64]) -> Vec<f64> {
    let e0 = energy.first().copied().unwrap_or(0.0);
    let mut jumps = 0.0;
    let mut out = Vec::with_capacity(energy.len());
    for (k, (&t, &e)) in times.iter().zip(energy).enumerate() {
        if k > 0 && times[k - 1] == t {
            jumps += e - energy[k - 1];
        }
        out.push(e - e0 - jumps);
    }
    out
}

/// The settings that shape the programs: those a run reads alone put back to their
/// defaults.
fn shape(settings: &Settings) -> Settings {
    Settings {
        until: 1.0,
        tolerance: 1.0,
        step: 1.0,
        sets: Vec::new(),
        series: Vec::new(),
        samples: 0,
        ..settings.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{settings, Options};
    use engine::input::Assignment;

    const PENDULUM: &str = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\n\
        coord theta = 0.5\n\
        particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\n\
        gravity g\n";

    fn settings_with(set: &[(&str, &str)], until: f64) -> Settings {
        let options = Options {
            until: Some(until),
            set: set
                .iter()
                .map(|(name, value)| Assignment { name: (*name).into(), value: (*value).into() })
                .collect(),
            ..Options::default()
        };
        settings(PENDULUM, &options).expect("settings")
    }

    fn last(outcome: &Outcome) -> Vec<f64> {
        outcome.run.trajectory.rows.last().expect("a row").clone()
    }

    #[test]
    fn a_compiled_scene_runs_value_after_value_as_fresh_ones_do() {
        let first = settings_with(&[("g", "1.62")], 2.0);
        let mut compiled = Compiled::new(PENDULUM, &first).expect("compiled");
        for (set, until) in [
            (vec![("g", "1.62")], 2.0),
            (vec![("theta", "1.1"), ("L", "2")], 3.0),
            (vec![], 1.0),
            (vec![("g", "1.62")], 2.0),
        ] {
            let settings = settings_with(&set, until);
            assert!(compiled.fits(&settings));
            let reused = compiled.run(&settings, &mut ()).expect("run");
            let fresh = super::super::run(PENDULUM, &settings, &mut ()).expect("run");
            assert_eq!(last(&reused), last(&fresh), "{set:?}");
            assert_eq!(reused.run.trajectory.times, fresh.run.trajectory.times);
            assert_eq!(reused.run.final_time, until);
        }
        // Other outputs or another method need other programs.
        let mut other = settings_with(&[], 1.0);
        other.outputs = vec!["theta'".into()];
        assert!(!compiled.fits(&other));
        let mut other = settings_with(&[], 1.0);
        other.method = sim::Method::Rk4;
        assert!(!compiled.fits(&other));
        // A bad value is an error of its run, and the next run goes on.
        let bad = settings_with(&[("g", "nosuch")], 1.0);
        assert!(matches!(compiled.run(&bad, &mut ()), Err(Error::Expression { .. })));
        assert!(compiled.run(&settings_with(&[], 1.0), &mut ()).is_ok());
    }

    /// Stops the run once it has been asked this many times.
    struct StopAfter(usize);

    impl Progress for StopAfter {
        fn interrupted(&mut self) -> bool {
            self.0 = self.0.saturating_sub(1);
            self.0 == 0
        }
    }

    #[test]
    fn a_progress_that_interrupts_ends_the_run_early() {
        let settings = settings_with(&[], 1000.0);
        let outcome = super::super::run(PENDULUM, &settings, &mut StopAfter(50)).expect("run");
        assert!(outcome.run.interrupted);
        assert_eq!(outcome.run.steps, 50);
        assert!(outcome.run.final_time < 1000.0);
    }

    #[test]
    fn a_compiled_scene_moves_to_another_thread() {
        let settings = settings_with(&[], 1.0);
        let mut compiled = Compiled::new(PENDULUM, &settings).expect("compiled");
        let here = last(&compiled.run(&settings, &mut ()).expect("run"));
        let there = std::thread::spawn(move || {
            last(&compiled.run(&settings_with(&[], 1.0), &mut ()).expect("run"))
        });
        assert_eq!(there.join().expect("the thread"), here);
    }
}
