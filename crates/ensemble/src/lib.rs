//! This crate owns the ensemble: one scene run many times, its parameters varied over a
//! grid (axes crossed) or drawn at random, a row of recorded values per run. It sits above
//! `engine`, whose loaded and lowered scene and whose model's names it takes: the scene is
//! derived and lowered once; each thread clones the lowered problem and runs one start after
//! another, taking the next run's index as it is free, and the rows are put back in run
//! order, so the table is the same whatever the number of threads. A run that faults, or
//! whose start cannot be made, is a row with its reason rather than the end of the ensemble.
//!
//! The runs go in chunks: a chunk's starts are drawn and made (`draws`: each run's draws
//! from its own stream of the seed), its runs run, its rows handed to a [`Sink`] in run order
//! and dropped, and the next chunk comes; so memory stays the same whatever the number of
//! runs, and the rows are those of the whole ensemble run at once.
//!
//! [`Ensemble`] is built once and can run any range of its runs from any thread, which is
//! what a front end that spreads the work itself (in chunks, over processes) needs. It reads
//! no files and prints nothing.

use std::ops::{ControlFlow, Range};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

use sim::Event;

mod draws;
mod record;

pub use record::{ContactRecord, Extreme, Recorded, Source};

use engine::input::Vary;
use engine::numbers::Prepared;
use engine::{Error, Piece, Setting};
use simulation::{Columns, FaultNames, Integrand, Overrides, Progress};

/// The most runs an ensemble may have. Its memory does not grow with them (the runs go in
/// chunks); a table kept whole ([`Ensemble::run`], Python's columns) does, by its rows.
pub const MAX_RUNS: usize = 1_000_000_000;

/// The fewest runs per thread that go side by side in lockstep.
const SIDE_BY_SIDE_FROM: usize = 4;

/// The runs each thread is given in a chunk: enough that the threads seldom wait for each
/// other at a chunk's end, few enough that a chunk's starts and rows take a megabyte or so.
const CHUNK_PER_THREAD: usize = 2048;

/// Where a front end takes an ensemble's rows as they are made, in run order: a CSV writer,
/// the summary's count, the picture's values, or a whole [`Table`].
pub trait Sink {
    /// Run `run`'s row: the varied values, then the recorded ones (NaN where the run failed),
    /// and why it failed.
    fn row(&mut self, run: usize, row: &[f64], failure: Option<&str>);
}

/// A table kept whole takes each row.
impl Sink for Table {
    fn row(&mut self, _run: usize, row: &[f64], failure: Option<&str>) {
        self.rows.push(row.to_vec());
        self.failures.push(failure.map(str::to_string));
    }
}

/// What a front end asks for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The settings of each run, as `simulate` takes them (its outputs and samples unused).
    pub simulate: simulation::Options,
    /// The parameters varied, in order: grid axes are crossed, the first varying slowest;
    /// random ones are drawn [`Options::runs`] times at each grid point.
    pub vary: Vec<Vary>,
    /// The number of random draws (at each grid point); only with a random [`Spread`].
    pub runs: Option<usize>,
    /// The seed of the random draws.
    pub seed: u64,
    /// What to record per run, comma-separated lists: scene expressions at the end (or the
    /// stop), `max(EXPR)` and `min(EXPR)` over the run. None: the scene's `output`
    /// quantities, else the coordinates, at the end.
    pub record: Vec<String>,
}

/// The rows of an ensemble, in run order.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The varied parameters' names, then the recorded quantities as written.
    pub columns: Vec<String>,
    /// How many of the columns are the varied parameters.
    pub varied: usize,
    /// A row per run: the varied values, then the recorded ones (NaN where the run failed).
    pub rows: Vec<Vec<f64>>,
    /// Why each run failed, or `None` where it ran.
    pub failures: Vec<Option<String>>,
    /// The grid's axes, each a parameter and its values, in the order of the columns.
    pub axes: Vec<(String, Vec<f64>)>,
    /// Whether some values were drawn at random.
    pub random: bool,
}

/// A scene lowered once: ready to run any of its runs, each run's start made as its chunk
/// comes.
pub struct Ensemble {
    integrand: Integrand,
    run_settings: sim::Settings,
    watched: Vec<Event>,
    recorded: Vec<Recorded>,
    /// The grid and the draws, from which any run's varied values come.
    design: draws::Design,
    seed: u64,
    /// What a run's start is made from: the scene (whose pool making one may grow), the
    /// `--set` values, and the varied parameters' indices.
    maker: Mutex<Maker>,
    /// The runs each thread is given in a chunk.
    chunk: usize,
    columns: Vec<String>,
    axes: Vec<(String, Vec<f64>)>,
    random: bool,
    state_names: Vec<String>,
    constraint_names: Vec<String>,
    /// The contacts, in the order written (a fault names them by their index).
    contact_names: Vec<String>,
    parameter_names: Vec<String>,
    angle_oriented_bodies: Vec<String>,
    /// Whether runs go side by side in lockstep ([`sim::Lockstep`]) where it serves them.
    lockstep: bool,
}

/// A run's parameter values, initial state (q, q̇) and its contacts' restitutions at those
/// values.
struct Start {
    parameters: Vec<f64>,
    state: Vec<f64>,
    restitutions: Vec<f64>,
    /// And their coefficients of friction (`None` for a smooth contact).
    frictions: Vec<Option<f64>>,
}

/// A run's start, or why it could not be made.
type Made = Result<Start, String>;

/// What every run's start is made from.
struct Maker {
    prepared: Prepared,
    sets: Overrides,
    /// The index of each varied parameter among the model's.
    given: Vec<usize>,
}

impl Maker {
    /// The start of a run with these varied values, or why it cannot be made.
    fn start(&mut self, values: &[f64]) -> Result<Start, String> {
        let numbers: Vec<(usize, f64)> =
            self.given.iter().copied().zip(values.iter().copied()).collect();
        let (parameters, state) = simulation::start(&mut self.prepared, &self.sets, &numbers)
            .map_err(|e| e.worded(run_words))?;
        // Each run's own: a varied parameter may be a restitution, or one it names.
        let restitutions = simulation::restitutions(&self.prepared, &parameters)
            .map_err(|e| e.worded(run_words))?;
        let frictions =
            simulation::frictions(&self.prepared, &parameters).map_err(|e| e.worded(run_words))?;
        Ok(Start { parameters, state, restitutions, frictions })
    }
}

/// What a run gives: its recorded values (NaN where it failed), and why it failed.
type Outcome = (Vec<f64>, Option<String>);

/// Runs the ensemble on `threads` threads (`None`: one per core), showing nothing.
pub fn ensemble(source: &str, options: &Options, threads: Option<usize>) -> Result<Table, Error> {
    ensemble_with(source, options, threads, &mut ())
}

/// [`ensemble`], telling `progress` how many runs are done (as its `t`, out of the runs).
pub fn ensemble_with(
    source: &str,
    options: &Options,
    threads: Option<usize>,
    progress: &mut dyn Progress,
) -> Result<Table, Error> {
    let ensemble = Ensemble::new(source, options)?;
    let threads = threads.unwrap_or_else(cores);
    Ok(ensemble.run(0..ensemble.runs(), threads, progress))
}

/// The number of threads the machine runs at once.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

impl Ensemble {
    /// Loads, derives and lowers `source` once; each run's start is made when its chunk runs.
    pub fn new(source: &str, options: &Options) -> Result<Ensemble, Error> {
        let design = draws::Design::new(&options.vary, options.runs)?;
        let recorded = record::parse(&options.record);
        let resolved = simulation::Resolved::new(source, &options.simulate);
        let mut settings = resolved.settings(&options.simulate)?;
        // Nothing asked for: the scene's `output` quantities, else the coordinates, at the end.
        if !recorded.is_empty() {
            settings.outputs = record::expressions(&recorded);
        }
        let simulation::Loaded { mut prepared, outputs, held, .. } = resolved.load(&settings)?;
        let set_exprs = simulation::set_expressions(&mut prepared, &settings.sets)?;
        let mut recorded = if recorded.is_empty() { record::finals(&outputs) } else { recorded };
        record::resolve_contacts(&mut recorded, &prepared.contact_names())?;
        let given = varied_parameters(&mut prepared, &options.vary)?;
        let sets = simulation::overrides(&prepared, &settings.sets, &set_exprs)?;
        let columns = Columns {
            outputs: outputs.len(),
            stops: settings.stops.len(),
            events: settings.events.len(),
        };
        // The scene's own values fill the parameters' slots until each run sets its own.
        let (parameters, _) = simulation::start(&mut prepared, &sets, &[])?;
        let dynamics_exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs)?;
        let observed = prepared.extra[..columns.figures()].to_vec();
        let observation = prepared.lower(&prepared.observation_inputs(), &observed)?;
        let signals = simulation::drive_signals(&prepared, &settings)?;
        let hold = simulation::drive_hold(&mut prepared, &held, settings.hold)?;
        let mut mechanical = sim::Mechanical::new(
            prepared.layout,
            numeric::Tape::new(dynamics),
            numeric::Tape::new(observation),
            parameters,
        )
        .with_kinds(prepared.stabilisation())
        .with_signals(signals);
        if let Some(recursive) = prepared.recursive()? {
            mechanical = mechanical.with_chain(recursive);
        }
        if let Some(hold) = hold {
            mechanical = mechanical.with_hold(hold);
        }
        let integrand = Integrand::new(&mut prepared, mechanical, settings.method)?;

        let mut names: Vec<String> = options.vary.iter().map(|v| v.parameter.clone()).collect();
        names.extend(recorded.iter().map(|r| r.name.clone()));
        let model = &prepared.derivation.model;
        Ok(Ensemble {
            integrand,
            // One sample: the start; the end (or the stop) is recorded anyway.
            run_settings: simulation::run_settings(&settings, 1),
            watched: simulation::watched(&columns),
            recorded,
            axes: design.axes(),
            random: design.is_random(),
            design,
            seed: options.seed,
            columns: names,
            state_names: prepared.state_names(),
            constraint_names: prepared.kept_constraint_names(),
            contact_names: prepared.contact_names(),
            parameter_names: prepared.parameter_slot_names(),
            angle_oriented_bodies: simulation::angle_oriented_bodies(model),
            lockstep: true,
            chunk: CHUNK_PER_THREAD,
            maker: Mutex::new(Maker { prepared, sets, given }),
        })
    }

    /// Gives each thread `runs` runs (at least one) in a chunk, rather than the default: the
    /// rows are the same whatever the chunks, which a test shows.
    pub fn set_chunk(&mut self, runs: usize) {
        self.chunk = runs.max(1);
    }

    /// The table's columns, axes and kind, with no rows yet: what a front end writes before
    /// the rows it is handed ([`Ensemble::stream`]).
    pub fn table(&self) -> Table {
        Table {
            columns: self.columns.clone(),
            varied: if self.runs() == 0 { 0 } else { self.design.parameters() },
            rows: Vec::new(),
            failures: Vec::new(),
            axes: self.axes.clone(),
            random: self.random,
        }
    }

    /// Whether runs go side by side in lockstep where the method and the problem allow it
    /// (the default), or one at a time. Either gives the same bits; one at a time is there to
    /// show it and to measure what the lockstep buys.
    pub fn set_lockstep(&mut self, on: bool) {
        self.lockstep = on;
    }

    /// How many runs the ensemble has.
    pub fn runs(&self) -> usize {
        self.design.runs()
    }

    /// The runs in `runs` (clipped to the ensemble's) on `threads` threads, the calling one
    /// among them; `progress` hears from the calling thread how many are done, and stops the
    /// ensemble when it says it is interrupted (asked between the calling thread's runs):
    /// every thread's run ends then, and the runs not finished are left out of the table.
    pub fn run(&self, runs: Range<usize>, threads: usize, progress: &mut dyn Progress) -> Table {
        let mut table = self.table();
        self.stream(runs, threads, progress, &mut table);
        table
    }

    /// [`Ensemble::run`], each row handed to `sink` in run order as its chunk is done rather
    /// than kept.
    pub fn stream(
        &self,
        runs: Range<usize>,
        threads: usize,
        progress: &mut dyn Progress,
        sink: &mut dyn Sink,
    ) {
        let runs = runs.start.min(self.runs())..runs.end.min(self.runs());
        self.run_where(&Runs::Range(runs), threads, progress, sink);
    }

    /// [`Ensemble::run`] on the runs numbered in `picked` (those past the ensemble's left
    /// out), their rows in the order of their numbers: a sample of the ensemble.
    pub fn run_picked(
        &self,
        picked: &[usize],
        threads: usize,
        progress: &mut dyn Progress,
    ) -> Table {
        let mut picked: Vec<usize> = picked.iter().copied().filter(|k| *k < self.runs()).collect();
        picked.sort_unstable();
        picked.dedup();
        let mut table = self.table();
        self.run_where(&Runs::Picked(picked), threads, progress, &mut table);
        table
    }

    /// Runs `runs` chunk by chunk, handing each chunk's rows to `sink` in run order.
    fn run_where(
        &self,
        runs: &Runs,
        threads: usize,
        progress: &mut dyn Progress,
        sink: &mut dyn Sink,
    ) {
        let done = AtomicUsize::new(0);
        let stop = AtomicBool::new(false);
        let helpers = threads.clamp(1, runs.len().max(1)) - 1;
        // A lane alone still pays for all of them on the batch tape: side by side only where
        // each thread has a few runs to fill its lanes with.
        let side_by_side = self.lockstep && runs.len() >= SIDE_BY_SIDE_FROM * (helpers + 1);
        let chunk = self.chunk * (helpers + 1);
        progress.start(runs.len() as f64);
        let mut first = 0;
        let mut row = Vec::new();
        while first < runs.len() && !stop.load(Ordering::Relaxed) {
            let part: Vec<usize> =
                (first..runs.len().min(first + chunk)).filter_map(|i| runs.get(i)).collect();
            first += chunk;
            let (values, starts) = self.starts(&part);
            let next = AtomicUsize::new(0);
            let jobs = Jobs { starts: &starts, next: &next };
            let mut results = std::thread::scope(|scope| {
                let workers: Vec<_> = (0..helpers)
                    .map(|_| {
                        let shared = (&done, &stop);
                        scope.spawn(move || self.work(&jobs, side_by_side, shared, &mut |_| {}))
                    })
                    .collect();
                let mut mine = self.work(&jobs, side_by_side, (&done, &stop), &mut |n| {
                    progress.update(n as f64);
                    if progress.interrupted() {
                        stop.store(true, Ordering::Relaxed);
                    }
                });
                for worker in workers {
                    // A worker's panic is a bug of ours; it is not input's to cause.
                    mine.extend(worker.join().expect("an ensemble's worker panicked"));
                }
                mine
            });
            results.sort_by_key(|(i, _)| *i);
            for (i, (recorded, failure)) in results {
                row.clear();
                row.extend_from_slice(&values[i]);
                row.extend(recorded);
                sink.row(part[i], &row, failure.as_deref());
            }
        }
        progress.finish();
    }

    /// The varied values and the start of each run numbered in `part`.
    fn starts(&self, part: &[usize]) -> (Vec<Vec<f64>>, Vec<Made>) {
        // A poisoned lock is a panic of ours while making a start; the maker is whole even so.
        let mut maker = self.maker.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let values: Vec<Vec<f64>> = part.iter().map(|k| self.design.run(self.seed, *k)).collect();
        let starts = values.iter().map(|v| maker.start(v)).collect();
        (values, starts)
    }

    /// Takes run after run of a chunk until none is left: each run's place in the chunk, its
    /// recorded values and why it failed, if it did, until `stop` is set. `report` hears how
    /// many runs are done in all.
    fn work(
        &self,
        jobs: &Jobs,
        side_by_side: bool,
        (done, stop): (&AtomicUsize, &AtomicBool),
        report: &mut dyn FnMut(usize),
    ) -> Vec<(usize, Outcome)> {
        let mut integrand = self.integrand.clone();
        let mut results = Vec::new();
        let lockstep = match &mut integrand {
            Integrand::Mechanical(problem) if side_by_side => {
                sim::Lockstep::new(problem, &self.run_settings)
            }
            _ => None,
        };
        if let Some(mut lockstep) = lockstep {
            // Runs end both where a start cannot be made and where a lane finishes one.
            let report = std::cell::RefCell::new(report);
            let mut next = || loop {
                let k = jobs.take().filter(|_| !stop.load(Ordering::Relaxed))?;
                match &jobs.starts[k] {
                    Ok(start) => {
                        let (parameters, state) = (start.parameters.clone(), start.state.clone());
                        return Some(sim::Job { id: k, parameters, state });
                    }
                    Err(why) => {
                        results.push((k, (vec![f64::NAN; self.recorded.len()], Some(why.clone()))));
                        (report.borrow_mut())(done.fetch_add(1, Ordering::Relaxed) + 1);
                    }
                }
            };
            let mut ran = Vec::new();
            let mut finished = |k: usize, run: sim::Run| {
                ran.push((k, self.outcome(&run)));
                (report.borrow_mut())(done.fetch_add(1, Ordering::Relaxed) + 1);
            };
            lockstep.run(&mut next, &self.watched, &mut finished, &mut || unless_stopped(stop));
            results.extend(ran);
            return results;
        }
        loop {
            let Some(k) = jobs.take().filter(|_| !stop.load(Ordering::Relaxed)) else {
                return results;
            };
            let outcome = self.run_one(&mut integrand, &jobs.starts[k], stop);
            if stop.load(Ordering::Relaxed) {
                return results;
            }
            results.push((k, outcome));
            report(done.fetch_add(1, Ordering::Relaxed) + 1);
        }
    }

    /// A run from `start` on `integrand`: its recorded values, and why it failed.
    fn run_one(&self, integrand: &mut Integrand, start: &Made, stop: &AtomicBool) -> Outcome {
        let failed = |why: String| (vec![f64::NAN; self.recorded.len()], Some(why));
        let start = match start {
            Ok(start) => start,
            Err(why) => return failed(why.clone()),
        };
        integrand.mechanical().set_parameters(&start.parameters);
        integrand.mechanical().set_restitutions(&start.restitutions);
        integrand.mechanical().set_frictions(&start.frictions);
        let mut go_on = |_| unless_stopped(stop);
        let run = integrand.integrate(&start.state, &self.run_settings, &self.watched, &mut go_on);
        self.outcome(&run)
    }

    /// What a run gives: its recorded values, or NaN and why it failed.
    fn outcome(&self, run: &sim::Run) -> Outcome {
        match &run.fault {
            Some(fault) => (vec![f64::NAN; self.recorded.len()], Some(self.describe(fault))),
            None => (self.recorded.iter().map(|r| r.value(run)).collect(), None),
        }
    }

    /// A fault in one line: when, and what went wrong.
    fn describe(&self, fault: &sim::Fault) -> String {
        let names = FaultNames {
            method: self.run_settings.method,
            state: &self.state_names,
            constraints: &self.constraint_names,
            parameters: &self.parameter_names,
            angle_oriented_bodies: &self.angle_oriented_bodies,
            contacts: &self.contact_names,
        };
        let (what, _) = names.words(&fault.kind);
        format!("numeric fault at t = {}: {what}", fault.time)
    }
}

/// Whether a run goes on: not once the ensemble was told to stop.
fn unless_stopped(stop: &AtomicBool) -> ControlFlow<()> {
    if stop.load(Ordering::Relaxed) {
        ControlFlow::Break(())
    } else {
        ControlFlow::Continue(())
    }
}

/// A chunk's runs, taken one after another by the threads: each by its place in the chunk.
#[derive(Clone, Copy)]
struct Jobs<'a> {
    starts: &'a [Made],
    next: &'a AtomicUsize,
}

impl Jobs<'_> {
    /// The place of the next run not yet taken, if one is left.
    fn take(&self) -> Option<usize> {
        Some(self.next.fetch_add(1, Ordering::Relaxed)).filter(|i| *i < self.starts.len())
    }
}

/// The runs a call runs: a range of their numbers, or numbers picked.
enum Runs {
    Range(Range<usize>),
    Picked(Vec<usize>),
}

impl Runs {
    fn len(&self) -> usize {
        match self {
            Runs::Range(range) => range.len(),
            Runs::Picked(picked) => picked.len(),
        }
    }

    /// The number of the `i`th run, if there are that many.
    fn get(&self, i: usize) -> Option<usize> {
        match self {
            Runs::Range(range) => Some(range.start + i).filter(|k| *k < range.end),
            Runs::Picked(picked) => picked.get(i).copied(),
        }
    }
}

/// A start's error in words that fit a run: its values are the run's (and `--set`'s), where
/// `simulate`'s are `--set`'s alone.
fn run_words(piece: &Piece) -> String {
    match piece {
        Piece::Setting(Setting::Set) => "this run".to_string(),
        other => other.plain(),
    }
}

/// The index of each varied parameter among the model's, or why one is not a parameter.
fn varied_parameters(
    prepared: &mut engine::numbers::Prepared,
    vary: &[Vary],
) -> Result<Vec<usize>, Error> {
    let mut found = Vec::new();
    for (k, v) in vary.iter().enumerate() {
        let name = &v.parameter;
        if vary[..k].iter().any(|earlier| earlier.parameter == *name) {
            return Err(Error::given(Setting::Vary, name, ": varied twice; give it once"));
        }
        if let Some(i) = prepared.derivation.model.params.iter().position(|p| p.name == *name) {
            if prepared.parameter_plan.is_derived(i) {
                return Err(engine::numbers::derived_error(
                    &prepared.parameter_plan,
                    Setting::Vary,
                    i,
                ));
            }
            // A number written with a unit is the parameter's value: the unit must fit it.
            for text in &v.with_units {
                prepared
                    .derivation
                    .model
                    .resolve_value_for(name, text)
                    .map_err(|diagnostics| Error::Expression { diagnostics, text: text.clone() })?;
            }
            found.push(i);
            continue;
        }
        let model = &prepared.derivation.model;
        let params: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
        let mut rest = format!(": no parameter of that name; one of {}", params.join(", "));
        if let Some(c) = model.coords.iter().find(|c| c.name == *name) {
            rest = format!(
                ": `{}` is a coordinate; vary a parameter its start is given by (coord {} = a, \
                 with param a), one of {}",
                c.name,
                c.name,
                params.join(", ")
            );
        } else if let Some(near) = model::closest(name, params.iter().copied()) {
            rest = format!(": no parameter of that name; did you mean `{near}`?");
        }
        return Err(Error::given(Setting::Vary, name, rest));
    }
    Ok(found)
}
