//! Runs of a scene from Python, with the interpreter free while they integrate: the scene
//! compiled for a run's settings is kept and reused ([`Compiled`], the fixed cost of a call
//! paid once), runs release the GIL so that other Python threads go on, and they check for
//! signals as they go so that Ctrl-C stops them ([`SignalCheck`]). `batch` runs many value
//! sets of one scene on threads of its own.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use engine::input::Assignment;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use simulation::{Compiled, Outcome, Progress, Settings};

use crate::errors::engine_error;

/// How many compiled scenes a loaded scene keeps: one per thread that runs it at once, for a
/// few differently shaped runs.
const KEPT: usize = 8;

/// How often a run looks for a signal: after this long since it last looked.
const SIGNAL_PERIOD: Duration = Duration::from_millis(20);

/// Compiled scenes ready for runs. A run takes one that fits its settings out of the store (so
/// that threads never share one while it runs), or compiles its own, and gives it back after.
#[derive(Default)]
pub struct Store {
    kept: Mutex<Vec<Compiled>>,
}

impl Store {
    /// Runs `source` with `settings` on a compiled scene that fits them, from the store or new,
    /// its rows handed to `sink` as they are made rather than kept.
    pub fn run_into(
        &self,
        source: &str,
        settings: &Settings,
        progress: &mut dyn Progress,
        sink: &mut dyn simulation::Sink,
    ) -> Result<Outcome, engine::Error> {
        let mut compiled = self.take(source, settings)?;
        let outcome = compiled.run_into(settings, progress, sink);
        self.give_back(compiled);
        outcome
    }

    /// A compiled scene that fits `settings`: one from the store, or one compiled now.
    pub fn take(&self, source: &str, settings: &Settings) -> Result<Compiled, engine::Error> {
        let found = {
            let mut kept = self.kept.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            kept.iter().position(|c| c.fits(settings)).map(|k| kept.swap_remove(k))
        };
        match found {
            Some(compiled) => Ok(compiled),
            None => Compiled::new(source, settings),
        }
    }

    /// Keeps `compiled` for later runs, dropping the oldest beyond [`KEPT`].
    pub fn give_back(&self, compiled: Compiled) {
        let mut kept = self.kept.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if kept.len() >= KEPT {
            kept.remove(0);
        }
        kept.push(compiled);
    }
}

/// A run's [`Progress`] that, every [`SIGNAL_PERIOD`], takes the GIL for a moment to let
/// Python handle its signals: a handler that raises (`KeyboardInterrupt` on Ctrl-C) stops the
/// run, and the exception is kept to be raised once the run has ended. Reading the clock costs
/// far less than a step, so it is read every step.
pub struct SignalCheck {
    last: Instant,
    pub raised: Option<PyErr>,
}

impl SignalCheck {
    pub fn new() -> Self {
        SignalCheck { last: Instant::now(), raised: None }
    }

    /// Whether a signal handler raised, looking now if the period has passed.
    fn look(&mut self) -> bool {
        if self.raised.is_none() && self.last.elapsed() >= SIGNAL_PERIOD {
            self.last = Instant::now();
            self.raised = Python::attach(|py| py.check_signals()).err();
        }
        self.raised.is_some()
    }
}

impl Progress for SignalCheck {
    fn interrupted(&mut self) -> bool {
        self.look()
    }
}

/// A run's [`Progress`] on a worker thread of [`batch`]: it stops when the thread that
/// watches for signals says so.
struct Stopped<'a>(&'a AtomicBool);

impl Progress for Stopped<'_> {
    fn interrupted(&mut self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// What one run of a batch gives: its outcome, or why it could not run.
pub type BatchRun = Result<Outcome, engine::Error>;

/// Runs `source` once per settings of `each` (which differ only in what a run reads alone,
/// so one compiled scene fits them all), on `threads` threads of their own, each with a
/// compiled scene of its own (from `store`, or compiled here); the calling thread watches for
/// signals meanwhile, without the GIL between looks. The outcomes come back in the order of
/// `each`, the same whatever the thread count; a signal handler's exception ends the batch.
pub fn batch(
    py: Python<'_>,
    store: &Store,
    source: &str,
    each: &[Settings],
    threads: usize,
) -> PyResult<Result<Vec<BatchRun>, engine::Error>> {
    let Some(first) = each.first() else { return Ok(Ok(Vec::new())) };
    let threads = threads.clamp(1, each.len());
    let stop = AtomicBool::new(false);
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<BatchRun>>> = each.iter().map(|_| Mutex::new(None)).collect();
    let outcome = py.detach(|| {
        let (finished, done) = std::sync::mpsc::channel::<()>();
        let compiled: Vec<Compiled> =
            (0..threads).map(|_| store.take(source, first)).collect::<Result<_, _>>()?;
        let raised = std::thread::scope(|scope| {
            for mut compiled in compiled {
                let (stop, next, slots, finished) = (&stop, &next, &slots, finished.clone());
                scope.spawn(move || {
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(settings) = each.get(k) else { break };
                        if stop.load(Ordering::Relaxed) {
                            break;
                        }
                        let outcome = compiled.run(settings, &mut Stopped(stop));
                        *slots[k].lock().unwrap_or_else(|p| p.into_inner()) = Some(outcome);
                    }
                    store.give_back(compiled);
                    // The receiver outlives the workers (the scope ends after its loop).
                    let _ = finished.send(());
                });
            }
            // Only the workers' senders are left: should one end without sending (a panic),
            // the channel closes rather than leaving this loop waiting.
            drop(finished);
            let mut check = SignalCheck::new();
            let mut running = threads;
            while running > 0 {
                match done.recv_timeout(SIGNAL_PERIOD) {
                    Ok(()) => running -= 1,
                    Err(RecvTimeoutError::Timeout) => {
                        if check.look() {
                            stop.store(true, Ordering::Relaxed);
                        }
                    }
                    Err(RecvTimeoutError::Disconnected) => break,
                }
            }
            check.raised
        });
        Ok(raised)
    });
    let raised = match outcome {
        Ok(raised) => raised,
        Err(e) => return Ok(Err(e)),
    };
    if let Some(e) = raised {
        return Err(e);
    }
    let runs = slots.into_iter().map(|slot| {
        let run = slot.into_inner().unwrap_or_else(|p| p.into_inner());
        run.unwrap_or_else(|| Err(engine::Error::Input("not run: the batch was stopped".into())))
    });
    Ok(Ok(runs.collect()))
}

/// `name = value` as a `--set` value of exactly `value`: its shortest decimal that reads back
/// as the same float, which the scene's numbers take exactly.
pub fn exact_assignment(name: &str, value: f64) -> PyResult<Assignment> {
    if !value.is_finite() {
        return Err(PyValueError::new_err(format!("`{name}` must be finite, not {value}")));
    }
    format!("{name}={value:?}").parse().map_err(|e| PyValueError::new_err(format!("`{name}`: {e}")))
}

/// The outcomes of a batch as arrays, one entry a run: `t` (where each ended), `columns`
/// (each output's value there), `stopped_by` and `fault` (lists), `steps`, `wall_seconds`;
/// with samples, `samples_t` (the sampled times) and `samples` (each output at them, a row a
/// run, NaN past a run's stop). A run that could not start raises its error.
pub fn batch_dict<'py>(
    py: Python<'py>,
    runs: &[BatchRun],
    path: &str,
    (until, samples): (f64, usize),
) -> PyResult<Bound<'py, PyDict>> {
    let mut outcomes = Vec::with_capacity(runs.len());
    for (k, run) in runs.iter().enumerate() {
        match run {
            Ok(outcome) => outcomes.push(outcome),
            Err(e) => {
                let err = engine_error(e, path);
                // A note says which run (Python 3.11 on; older ones go without).
                let _ =
                    err.value(py).call_method1("add_note", (format!("in run {k} of the batch"),));
                return Err(err);
            }
        }
    }
    let out = PyDict::new(py);
    let names: &[String] = outcomes.first().map_or(&[], |o| &o.columns[..o.shown]);
    let last = |o: &Outcome, k: usize| o.run.trajectory.rows.last().map_or(f64::NAN, |r| r[k]);
    let columns = PyDict::new(py);
    for (k, name) in names.iter().enumerate() {
        let values: Vec<f64> = outcomes.iter().map(|o| last(o, k)).collect();
        columns.set_item(name, PyArray1::from_vec(py, values))?;
    }
    out.set_item("columns", columns)?;
    out.set_item("t", PyArray1::from_iter(py, outcomes.iter().map(|o| o.run.final_time)))?;
    let stopped_by =
        outcomes.iter().map(|o| o.run.stopped_by.and_then(|k| o.event_names.get(k).cloned()));
    out.set_item("stopped_by", PyList::new(py, stopped_by)?)?;
    let faults = outcomes.iter().map(|o| o.run.fault.as_ref().map(|f| o.describe_fault(f)));
    out.set_item("fault", PyList::new(py, faults)?)?;
    out.set_item("steps", PyArray1::from_iter(py, outcomes.iter().map(|o| o.run.steps)))?;
    let wall = outcomes.iter().map(|o| o.wall_seconds);
    out.set_item("wall_seconds", PyArray1::from_iter(py, wall))?;
    if samples > 0 {
        out.set_item("samples", sampled(py, &outcomes, until, samples)?)?;
    }
    Ok(out)
}

/// Each output at the `count` evenly spaced times a run with `samples` recorded, a row a
/// run: the recorded rows at those times, NaN where a run stopped before one.
fn sampled<'py>(
    py: Python<'py>,
    outcomes: &[&Outcome],
    until: f64,
    count: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let times: Vec<f64> = (0..count)
        .map(|i| if count == 1 { 0.0 } else { until * i as f64 / (count - 1) as f64 })
        .collect();
    let names: &[String] = outcomes.first().map_or(&[], |o| &o.columns[..o.shown]);
    let out = PyDict::new(py);
    for (k, name) in names.iter().enumerate() {
        let mut values = vec![f64::NAN; outcomes.len() * count];
        for (r, o) in outcomes.iter().enumerate() {
            let trajectory = &o.run.trajectory;
            let mut i = 0;
            for (time, row) in trajectory.times.iter().zip(&trajectory.rows) {
                // Samples land on their times up to the rounding of the time grid; an event
                // or a stop between two of them is another row, left out.
                while i < count && times[i] < time - 1e-9 * until.max(1.0) {
                    i += 1;
                }
                if i < count && (times[i] - time).abs() <= 1e-9 * until.max(1.0) {
                    values[r * count + i] = row[k];
                    i += 1;
                }
            }
        }
        let array = PyArray1::from_vec(py, values).reshape([outcomes.len(), count])?;
        let array: Bound<'py, PyArray2<f64>> = array;
        out.set_item(name, array)?;
    }
    out.set_item("t", PyArray1::from_vec(py, times))?;
    Ok(out)
}
