//! The native half of the `lagrange` Python package (`lagrange._native`): a loaded scene
//! and what it gives Python: its derivation as SymPy objects ([`derive`]), fast callables of
//! its equations for NumPy and SciPy ([`numbers`]), simulations as NumPy arrays, and its
//! `expect` lines checked. The Python half (`python/lagrange`) wraps these in documented
//! classes.
//!
//! Everything goes through `engine`, as in the `lagrange` command; every error comes back as
//! a Python exception ([`errors`]), never as a panic across the boundary.

mod data;
mod derive;
mod ensemble;
mod errors;
mod inputs;
mod numbers;
mod runs;
mod sympy;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard};

use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use errors::engine_error;

/// A loaded scene: its text, the name it goes by in diagnostics, and its derivation. Usable
/// from any thread: the derivation is behind a lock (the forms of `derive` and `check` are
/// computed on demand into its pool), and runs take compiled scenes of their own from `runs`.
#[pyclass(frozen, module = "lagrange._native")]
struct NativeScene {
    source: String,
    path: String,
    units: bool,
    /// The scene's `simulate` block, read into each run's settings.
    simulation: model::Simulation,
    title: Option<String>,
    /// The scene's warnings, rendered as the `lagrange` command prints them.
    warnings: String,
    /// The derivation, or why there is none: a scene whose input stands in a constraint is
    /// derived only in a run, with the input's law in its place, so `derive` and `check`
    /// raise what the engine says while `simulate` runs it.
    scene: Mutex<Result<engine::Scene, engine::Error>>,
    /// Whether `derive` or `check` has added its forms to the derivation's pool. Numbers laid
    /// out from a copy of it would then number their expressions after those forms, and a
    /// sum's order (so its rounding) could follow: they derive the text afresh instead, so that
    /// `rhs()` gives the same bits whatever was asked of the scene before.
    forms_added: AtomicBool,
    runs: runs::Store,
}

/// Parses, resolves and derives a scene's text; `path` names it in diagnostics. The GIL is
/// released meanwhile.
#[pyfunction]
#[pyo3(signature = (text, path = "<string>".to_string(), units = true))]
fn loads(py: Python<'_>, text: String, path: String, units: bool) -> PyResult<NativeScene> {
    let options = engine::Options { units };
    let loaded = py.detach(|| match engine::load_with(&text, options) {
        Ok(scene) => {
            let model = &scene.derivation.model;
            let (simulation, title) = (model.simulation.clone(), model.title.clone());
            let warnings = lang::render::render(&path, &text, &scene.warnings);
            Ok((Ok(scene), simulation, title, warnings))
        }
        // Only runs can take it: each puts its input's law in place first.
        Err(refused) => match engine::resolve_for_runs(&text, options) {
            Ok((model, warnings)) => {
                let warnings = lang::render::render(&path, &text, &warnings);
                Ok((Err(refused), model.simulation, model.title, warnings))
            }
            Err(_) => Err(refused),
        },
    });
    let (scene, simulation, title, warnings) = loaded.map_err(|e| engine_error(&e, &path))?;
    Ok(NativeScene {
        simulation,
        title,
        warnings,
        source: text,
        path,
        units,
        scene: Mutex::new(scene),
        forms_added: AtomicBool::new(false),
        runs: runs::Store::default(),
    })
}

impl NativeScene {
    /// The loaded scene, for one thread at a time. A thread that panicked while holding it
    /// cannot have left it half changed in a way that matters: what `derive` and `check` add
    /// to the pool are memoised forms, each complete or absent.
    fn scene(&self) -> MutexGuard<'_, Result<engine::Scene, engine::Error>> {
        self.scene.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// A copy of the loaded scene's derivation, for numbers to be laid out from without
    /// deriving the text again; `None` where there is none (the callers then derive the text
    /// and say why it fails).
    fn derived(&self) -> Option<engine::Derivation> {
        let scene = self.scene();
        if self.forms_added.load(Ordering::SeqCst) {
            return None;
        }
        scene.as_ref().ok().map(|scene| scene.derivation.clone())
    }

    /// The loaded scene, for `derive` and `check` to add their forms to.
    fn scene_for_forms(&self) -> MutexGuard<'_, Result<engine::Scene, engine::Error>> {
        let scene = self.scene();
        self.forms_added.store(true, Ordering::SeqCst);
        scene
    }

    /// `body` on the derived scene, or the engine's reason there is none, raised.
    fn with_scene<T>(&self, body: impl FnOnce(&mut engine::Scene) -> PyResult<T>) -> PyResult<T> {
        match &mut *self.scene_for_forms() {
            Ok(scene) => body(scene),
            Err(refused) => Err(engine_error(refused, &self.path)),
        }
    }

    /// The settings of a run: the scene's `simulate` block, then `options`.
    fn settings(&self, options: &simulation::Options) -> PyResult<simulation::Settings> {
        simulation::settings_of(self.simulation.clone(), options)
            .map_err(|e| engine_error(&e, &self.path))
    }
}

#[pymethods]
impl NativeScene {
    /// The forms a `derive` report shows, as a dict of SymPy objects.
    fn derive<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        self.with_scene(|scene| derive::derive(py, &mut scene.derivation))
    }

    /// y' = F(t, y) for `solve_ivp`.
    fn rhs(&self, py: Python<'_>) -> PyResult<numbers::Rhs> {
        py.detach(|| numbers::Rhs::new(&self.source, &self.path, self.units, self.derived()))
    }

    /// Pickles as what it is made from, the scene's text and settings: unpickling loads it
    /// again.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rebuild = py.import("lagrange._native")?.getattr("loads")?;
        let arguments = (self.source.clone(), self.path.clone(), self.units);
        (rebuild, arguments).into_pyobject(py).map(|t| t.into_any())
    }

    /// τ = M·q̈ − f over many motions.
    fn inverse_dynamics(&self) -> PyResult<numbers::InverseDynamics> {
        numbers::InverseDynamics::new(&self.source, &self.path, self.units)
    }

    /// M(t, q) at the parameters' values.
    fn mass_matrix_function(&self) -> PyResult<numbers::MassMatrix> {
        numbers::MassMatrix::new(&self.source, &self.path, self.units, self.derived())
    }

    /// Runs the scene as `lagrange simulate` does, with `options` (see [`RunOptions`]). The
    /// GIL is released while it runs (other Python threads go on), signals are handled every
    /// few milliseconds (Ctrl-C stops it), and the scene compiled for these settings is kept
    /// for the next call.
    fn simulate<'py>(&self, py: Python<'py>, options: RunOptions) -> PyResult<Bound<'py, PyDict>> {
        let settings = self.settings(&options.engine(self)?)?;
        let mut check = runs::SignalCheck::new();
        // The arrays are filled as the rows are made: no row is kept besides them.
        let mut arrays = Arrays::default();
        let outcome =
            py.detach(|| self.runs.run_into(&self.source, &settings, &mut check, &mut arrays));
        if let Some(raised) = check.raised {
            return Err(raised);
        }
        let outcome = outcome.map_err(|e| engine_error(&e, &self.path))?;
        outcome_dict(py, &outcome, arrays)
    }

    /// Runs the scene once per row of `values`, the values of `names` (parameters,
    /// coordinates, rates) in that run, on `threads` threads with the GIL released; `options`
    /// as for `simulate`, the same for every run. Returns the batch's arrays (see
    /// `runs::batch_dict`).
    fn batch<'py>(
        &self,
        py: Python<'py>,
        names: Vec<String>,
        values: numpy::PyReadonlyArray2<'py, f64>,
        threads: usize,
        options: RunOptions,
    ) -> PyResult<Bound<'py, PyDict>> {
        let options = options.engine(self)?;
        let values = values.as_array();
        if values.ncols() != names.len() {
            return Err(PyValueError::new_err(format!(
                "each row holds a value of each of the {} names ({}), not {}",
                names.len(),
                names.join(", "),
                values.ncols()
            )));
        }
        let mut each = Vec::with_capacity(values.nrows());
        for row in values.rows() {
            let mut options = options.clone();
            for (name, value) in names.iter().zip(row) {
                options.set.push(runs::exact_assignment(name, *value)?);
            }
            each.push(self.settings(&options)?);
        }
        let outcomes = runs::batch(py, &self.runs, &self.source, &each, threads)?
            .map_err(|e| engine_error(&e, &self.path))?;
        let sampling = each.first().map_or((0.0, 0), |s| (s.until, s.samples));
        runs::batch_dict(py, &outcomes, &self.path, sampling)
    }

    /// `lagrange ensemble`: the scene run over the grid axes and random draws of `vary`
    /// (`NAME=A:B:N`, `NAME=normal(MU, SIGMA)`, `NAME=uniform(A, B)`; `runs` draws from
    /// `seed`), recording `record` per run, on `threads` threads (`None`: one per core), the
    /// runs `start` to `stop` of it (`None`: to the last); `options` as for `simulate` (its
    /// outputs and samples unused). Returns the table's columns (see `ensemble::ensemble`).
    #[pyo3(signature = (vary, runs, seed, record, threads, start, stop, options))]
    #[allow(clippy::too_many_arguments)]
    fn ensemble<'py>(
        &self,
        py: Python<'py>,
        vary: Vec<String>,
        runs: Option<usize>,
        seed: u64,
        record: Vec<String>,
        threads: Option<usize>,
        start: usize,
        stop: Option<usize>,
        options: RunOptions,
    ) -> PyResult<Bound<'py, PyDict>> {
        let simulate = options.engine(self)?;
        let vary = engine::input::varies(&vary).map_err(|e| engine_error(&e, &self.path))?;
        let options = ::ensemble::Options { simulate, vary, runs, seed, record };
        let request = ensemble::Request { options, threads, from: start, to: stop };
        ensemble::ensemble(py, &self.source, &self.path, request)
    }

    /// Small motions about an equilibrium or a steady motion, as `lagrange linearize` finds
    /// them: exact M, C, K (SymPy matrices), the first-order A, B, C, D (NumPy; exactly too
    /// where the algebra gives them) and the eigenvalues, the verdict, the ranks of
    /// controllability and observability, and with `sweep` the eigenvalues against one
    /// parameter and where the verdict changes.
    #[pyo3(signature = (about = None, set = Vec::new(), sweep = None, keep_cyclic = true))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        about: Option<String>,
        set: Vec<String>,
        sweep: Option<String>,
        keep_cyclic: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = engine::linearize::Options {
            about,
            set,
            sweep,
            no_units: !self.units,
            drop_cyclic: !keep_cyclic,
        };
        let l = py
            .detach(|| {
                engine::linearize::linearize(&self.source, &options)
                    .map(|l| results::linearize::python(&l))
            })
            .map_err(|e| engine_error(&e, &self.path))?;
        data::to_python(py, &l)
    }

    /// Linearization along a motion, as `lagrange linearize --along` finds it: the scene run
    /// with `options` (as for `simulate`) when `times` is `None`, else the motion given by its
    /// `times`, `states` (q then q̇ per sample) and `inputs` (each input's value per sample).
    /// Returns `results::along`'s dict: the names, `t`, A, B, C and D stacked over the
    /// samples, and the state-transition matrix over the motion.
    #[pyo3(signature = (options, times = None, states = None, inputs = None))]
    fn linearize_along<'py>(
        &self,
        py: Python<'py>,
        options: RunOptions,
        times: Option<Vec<f64>>,
        states: Option<Vec<Vec<f64>>>,
        inputs: Option<Vec<Vec<f64>>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = options.engine(self)?;
        let linearized = py.detach(|| match times {
            None => simulation::along::linearize_run(&self.source, &options),
            Some(times) => {
                let along_options = engine::along::Options {
                    set: options.set.clone(),
                    no_units: options.no_units,
                    starts_allowed: false,
                };
                let mut along = engine::along::along(&self.source, &along_options)?;
                let count = times.len();
                let inputs = inputs.unwrap_or_else(|| vec![along.resting_inputs(); count]);
                let motion =
                    engine::along::Motion { times, states: states.unwrap_or_default(), inputs };
                engine::along::linearize_along(&mut along, &motion)
            }
        });
        let linearized = linearized.map_err(|e| engine_error(&e, &self.path))?;
        data::to_python(py, &results::along::report(&linearized))
    }

    /// A periodic orbit as `lagrange orbit` finds it: over a fixed `period` (an expression of
    /// the parameters) or to a `section` (an expression crossing zero in `direction`,
    /// `impact` or `impact:NAME`), each return mapped by `swap` (`a=b`) and `shift`
    /// (`name=value`) and compared without the coordinates `ignore` names. Returns a dict: the
    /// state's names, the fixed point, the period, the multipliers (complex), the map's
    /// Jacobian on the whole state (`monodromy`), how many trivial multipliers were left out,
    /// the jumps on the way, the verdict and the Newton residuals.
    #[pyo3(signature = (
        period = None, section = None, direction = "rising".to_string(), shift = Vec::new(),
        swap = Vec::new(), ignore = Vec::new(), set = Vec::new(), until = None, method = None,
        tolerance = None, iterations = 30
    ))]
    #[allow(clippy::too_many_arguments)]
    fn orbit<'py>(
        &self,
        py: Python<'py>,
        period: Option<String>,
        section: Option<String>,
        direction: String,
        shift: Vec<String>,
        swap: Vec<String>,
        ignore: Vec<String>,
        set: Vec<String>,
        until: Option<f64>,
        method: Option<String>,
        tolerance: Option<f64>,
        iterations: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let rising = match direction.as_str() {
            "rising" => true,
            "falling" => false,
            other => {
                return Err(PyValueError::new_err(format!(
                    "direction is \"rising\" or \"falling\", not {other:?}"
                )))
            }
        };
        let section = match (period, section) {
            (Some(period), None) => orbit::Section::Period(period),
            (None, Some(text)) => orbit::Section::parse(&text, rising),
            _ => {
                return Err(PyValueError::new_err(
                    "give one of period (a driven scene's) and section",
                ))
            }
        };
        let read = |texts: &[String]| {
            engine::input::assignments(texts).map_err(|e| engine_error(&e, &self.path))
        };
        let options = orbit::Options {
            run: simulation::Options {
                until,
                method,
                tolerance,
                set: read(&set)?,
                no_units: !self.units,
                ..Default::default()
            },
            section,
            swaps: read(&swap)?,
            shifts: read(&shift)?,
            ignore,
            iterations,
        };
        let found = py
            .detach(|| orbit::orbit(&self.source, &options))
            .map_err(|e| engine_error(&e, &self.path))?;
        orbit_dict(py, &found)
    }

    /// A fit as `lagrange fit` makes it: the scene's `free` unknowns (`"c, L=1.2, theta(0)"`)
    /// estimated from `data` (CSV text with a column `t`), its runs as `options` set them,
    /// each column's residuals divided by its `noise`, within `bounds` (`"c=0:"`), over
    /// `shots` shots. Returns a dict: the unknowns' names and kinds, the estimates, their
    /// standard errors, the covariance and correlation, the columns' RMS, the cost, the
    /// residuals' variance, the iterations, whether it converged, the combination the data
    /// cannot tell apart, the data's times and the model's values there, and the scene with
    /// the fitted values written in.
    #[pyo3(signature = (data, free, options, noise = Vec::new(), bounds = Vec::new(), shots = 1, iterations = 100))]
    #[allow(clippy::too_many_arguments)]
    fn fit<'py>(
        &self,
        py: Python<'py>,
        data: String,
        free: String,
        options: RunOptions,
        noise: Vec<(String, f64)>,
        bounds: Vec<String>,
        shots: usize,
        iterations: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let run = options.engine(self)?;
        let shown = |e: &fit::Error| -> PyErr {
            match e {
                fit::Error::Engine(e) => engine_error(e, &self.path),
                fit::Error::Data(diagnostics) => {
                    PyValueError::new_err(lang::render::render("data", &data, diagnostics))
                }
                fit::Error::Argument { text, diagnostics, .. } => {
                    PyValueError::new_err(lang::render::render("free", text, diagnostics))
                }
            }
        };
        let mut fit_options = fit::Options { run, noise, shots, iterations, ..Default::default() };
        fit_options.free = fit::parse_free(&free).map_err(|e| shown(&e))?;
        for b in &bounds {
            fit_options.bounds.push(fit::parse_bound(b).map_err(|e| shown(&e))?);
        }
        let table = fit::data::read(&data).map_err(|d| shown(&fit::Error::Data(d)))?;
        let found =
            py.detach(|| fit::fit(&self.source, &fit_options, table)).map_err(|e| shown(&e))?;
        let scene =
            fit::scene::written(&self.source, &found).map_err(|e| engine_error(&e, &self.path))?;
        let out = PyDict::new(py);
        let names: Vec<&str> = found.unknowns.iter().map(|u| u.name.as_str()).collect();
        let kinds: Vec<&str> = found
            .unknowns
            .iter()
            .map(|u| match u.kind {
                fit::Kind::Parameter(_) => "parameter",
                fit::Kind::Start { .. } => "start",
            })
            .collect();
        out.set_item("names", names)?;
        out.set_item("kinds", kinds)?;
        out.set_item("estimates", PyArray1::from_vec(py, found.estimates.clone()))?;
        out.set_item("standard_errors", PyArray1::from_vec(py, found.standard_errors.clone()))?;
        out.set_item("initial", PyArray1::from_vec(py, found.initial.clone()))?;
        out.set_item("covariance", found.covariance.clone())?;
        out.set_item("correlation", found.correlation.clone())?;
        let columns = PyDict::new(py);
        let model = PyDict::new(py);
        for (c, column) in found.columns.iter().enumerate() {
            columns.set_item(&column.name, (column.rms, column.count))?;
            model.set_item(&column.name, PyArray1::from_vec(py, found.model[c].clone()))?;
        }
        out.set_item("rms", columns)?;
        out.set_item("t", PyArray1::from_vec(py, found.times.clone()))?;
        out.set_item("model", model)?;
        out.set_item("cost", found.cost)?;
        out.set_item("initial_cost", found.initial_cost)?;
        out.set_item("variance", found.variance)?;
        out.set_item("measurements", found.measurements)?;
        out.set_item("degrees_of_freedom", found.degrees_of_freedom)?;
        out.set_item("iterations", found.iterations)?;
        out.set_item("evaluations", found.evaluations)?;
        out.set_item("shots", found.shots)?;
        out.set_item("converged", found.ending.converged())?;
        out.set_item("ending", found.ending.words())?;
        let unidentifiable = found.unidentifiable.as_ref().map(|c| c.terms.clone());
        out.set_item("unidentifiable", unidentifiable)?;
        out.set_item("scene", scene)?;
        Ok(out)
    }

    /// Every `expect` line with its verdict: dicts of line, text, held, how (and for one that
    /// fails, the residual and a state where it is not zero).
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut scene = self.scene_for_forms();
        let d = match &mut *scene {
            Ok(scene) => &mut scene.derivation,
            Err(refused) => return Err(engine_error(refused, &self.path)),
        };
        let checked = py.detach(|| results::check::expectations(&self.source, d));
        data::to_python(py, &results::check::python(&checked))
    }

    /// The scene's warnings, rendered as the `lagrange` command prints them ("" if none).
    #[getter]
    fn warnings(&self) -> String {
        self.warnings.clone()
    }

    #[getter]
    fn title(&self) -> Option<String> {
        self.title.clone()
    }

    #[getter]
    fn units(&self) -> bool {
        self.units
    }

    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }

    #[getter]
    fn path(&self) -> String {
        self.path.clone()
    }
}

/// The settings of a run as Python hands them over: the dict `lagrange._run_options` makes of
/// `simulate`'s keyword arguments, every key there, `None` or empty for the scene's setting.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct RunOptions {
    until: Option<f64>,
    method: Option<String>,
    tolerance: Option<f64>,
    step: Option<f64>,
    output: Vec<String>,
    set: Vec<String>,
    input: Vec<String>,
    /// Inputs given as time series: name, times, values.
    input_series: Vec<(String, Vec<f64>, Vec<f64>)>,
    hold: Option<f64>,
    stop_when: Vec<String>,
    events: Vec<String>,
    samples: usize,
}

impl RunOptions {
    /// The engine's options: the texts read into values, the time series checked.
    fn engine(self, scene: &NativeScene) -> PyResult<simulation::Options> {
        let path = &scene.path;
        let set = engine::input::assignments(&self.set).map_err(|e| engine_error(&e, path))?;
        let input = engine::input::assignments_of(engine::Setting::Input, &self.input)
            .map_err(|e| engine_error(&e, path))?;
        let mut series = Vec::new();
        for (name, times, values) in self.input_series {
            let samples = sim::Series::new(times, values)
                .map_err(|e| PyValueError::new_err(format!("input `{name}`: {e}")))?;
            series.push((name, samples));
        }
        Ok(simulation::Options {
            until: self.until,
            method: self.method,
            tolerance: self.tolerance,
            step: self.step,
            set,
            input,
            input_series: series,
            hold: self.hold,
            output: self.output,
            stop_when: self.stop_when,
            events: self.events,
            no_units: !scene.units,
            samples: self.samples,
            animate: false,
        })
    }
}

/// A run's arrays, filled as its rows are made: the times, each output, and the energy.
#[derive(Default)]
struct Arrays {
    times: Vec<f64>,
    outputs: Vec<Vec<f64>>,
    energy: Vec<f64>,
}

impl simulation::Sink for Arrays {
    fn columns(&mut self, names: &[String]) {
        self.outputs = vec![Vec::new(); names.len()];
    }

    fn row(&mut self, t: f64, outputs: &[f64], energy: f64) {
        self.times.push(t);
        for (column, value) in self.outputs.iter_mut().zip(outputs) {
            column.push(*value);
        }
        self.energy.push(energy);
    }
}

/// A run's outcome as the dict the Python `Results` wraps, with its arrays.
/// An orbit as the dict `Scene.orbit` reads.
fn orbit_dict<'py>(py: Python<'py>, found: &orbit::Orbit) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let size = found.fixed_point.len();
    out.set_item("state", PyList::new(py, &found.state_names)?)?;
    out.set_item("fixed_point", PyArray1::from_vec(py, found.fixed_point.clone()))?;
    out.set_item("period", found.period)?;
    let multipliers: Vec<(f64, f64)> = found.multipliers.iter().map(|m| (m.re, m.im)).collect();
    out.set_item("multipliers", multipliers)?;
    let rows: Vec<Vec<f64>> =
        (0..size).map(|i| found.monodromy[i * size..(i + 1) * size].to_vec()).collect();
    out.set_item("monodromy", rows)?;
    out.set_item("trivial", found.trivial)?;
    out.set_item("jumps", found.jumps)?;
    out.set_item("stable", found.stable)?;
    out.set_item("verdict", found.verdict.word())?;
    let residuals: Vec<f64> = found.iterations.iter().map(|i| i.residual).collect();
    out.set_item("residuals", residuals)?;
    let tolerances: Vec<f64> = found.iterations.iter().map(|i| i.tolerance).collect();
    out.set_item("tolerances", tolerances)?;
    out.set_item("last_step", found.last_step)?;
    Ok(out)
}

fn outcome_dict<'py>(
    py: Python<'py>,
    outcome: &simulation::Outcome,
    arrays: Arrays,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("t", PyArray1::from_vec(py, arrays.times))?;
    let columns = PyDict::new(py);
    for (name, values) in outcome.columns.iter().zip(arrays.outputs) {
        columns.set_item(name, PyArray1::from_vec(py, values))?;
    }
    out.set_item("columns", columns)?;
    out.set_item("energy", PyArray1::from_vec(py, arrays.energy))?;
    let hits = PyList::empty(py);
    for hit in &outcome.run.events {
        hits.append((outcome.event_names.get(hit.event).cloned(), hit.time))?;
    }
    out.set_item("events", hits)?;
    let stopped_by = outcome.run.stopped_by.and_then(|k| outcome.event_names.get(k).cloned());
    out.set_item("stopped_by", stopped_by)?;
    out.set_item("fault", outcome.run.fault.as_ref().map(|f| outcome.describe_fault(f)))?;
    out.set_item("method", outcome.method.name())?;
    let segments = PyList::empty(py);
    for segment in &outcome.run.segments {
        segments.append((segment.method.name(), segment.start, segment.end))?;
    }
    out.set_item("segments", segments)?;
    out.set_item("steps", outcome.run.steps)?;
    out.set_item("rejected", outcome.run.rejected)?;
    out.set_item("evaluations", outcome.run.evaluations)?;
    out.set_item("jacobians", outcome.run.jacobians)?;
    out.set_item("factorizations", outcome.run.factorizations)?;
    out.set_item("energy_drift", outcome.energy_drift())?;
    out.set_item("conservative", outcome.conservative)?;
    out.set_item("constraint_drift", outcome.constraint_drift())?;
    out.set_item("constraint_drift_at_steps", outcome.constraint_drift_at_steps())?;
    out.set_item("wall_seconds", outcome.wall_seconds)?;
    out.set_item("contacts", PyList::new(py, &outcome.contact_names)?)?;
    out.set_item("contact_events", contact_events(py, outcome)?)?;
    out.set_item("energy_changed_by_impacts", outcome.totals.energy_jumps())?;
    Ok(out)
}

/// A run's contact events as columns, an entry an event in the order they happened (as
/// `lagrange simulate --events` writes them): `t`, `contact` (its name), `kind`
/// (`simulation::mode_word`), `closed` (after it), `impulse`, `tangential_impulse` (NaN for a
/// contact without grip), `energy_change` and `slip` (a rough contact's: ±1 the way it slips
/// after the event, 0 sticking).
fn contact_events<'py>(
    py: Python<'py>,
    outcome: &simulation::Outcome,
) -> PyResult<Bound<'py, PyDict>> {
    let modes = &outcome.run.modes;
    let out = PyDict::new(py);
    out.set_item("t", PyArray1::from_iter(py, modes.iter().map(|m| m.time)))?;
    let names = modes.iter().map(|m| outcome.contact_name(m.contact));
    out.set_item("contact", PyList::new(py, names)?)?;
    let kinds = modes.iter().map(|m| simulation::mode_word(m.kind));
    out.set_item("kind", PyList::new(py, kinds)?)?;
    out.set_item("closed", PyArray1::from_iter(py, modes.iter().map(|m| m.closed)))?;
    out.set_item("impulse", PyArray1::from_iter(py, modes.iter().map(|m| m.impulse)))?;
    let tangential = modes.iter().map(|m| m.tangential.unwrap_or(f64::NAN));
    out.set_item("tangential_impulse", PyArray1::from_iter(py, tangential))?;
    let energy = modes.iter().map(|m| m.energy_change);
    out.set_item("energy_change", PyArray1::from_iter(py, energy))?;
    out.set_item("slip", PyArray1::from_iter(py, modes.iter().map(|m| m.slip)))?;
    Ok(out)
}

/// An `Rhs` made again from its pickle: the scene's text and settings, and the parameter
/// values it had.
#[pyfunction]
fn _rhs_from(
    py: Python<'_>,
    source: String,
    path: String,
    units: bool,
    parameters: Vec<f64>,
) -> PyResult<numbers::Rhs> {
    py.detach(|| numbers::Rhs::from_pickle(&source, &path, units, &parameters))
}

/// The native half of the `lagrange` package.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(loads, m)?)?;
    m.add_function(wrap_pyfunction!(_rhs_from, m)?)?;
    m.add_class::<NativeScene>()?;
    m.add_class::<numbers::Rhs>()?;
    m.add_class::<numbers::MassMatrix>()?;
    m.add_class::<numbers::InverseDynamics>()?;
    Ok(())
}
