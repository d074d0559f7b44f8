//! The scene's equations as fast callables for NumPy and SciPy: `Scene.rhs()` gives
//! y' = F(t, y) for `scipy.integrate.solve_ivp` (y = coordinates, then rates), evaluated by the
//! lowered programs through `sim::Mechanical` exactly as `simulate` runs them, with
//! `.batch(Y)` for many states in one call, `.jac(t, y)`, the exact ∂F/∂y for `solve_ivp`'s
//! `jac` (its partials lowered on first use), parameter values per call or from then on, and
//! the inputs' values per call (numbers, arrays per row or callables of (t, y): `inputs`);
//! `Scene.mass_matrix_function()` gives M(t, q); the inverse dynamics τ = M·q̈ − f of
//! `engine::inverse` over many states is [`InverseDynamics`].

use engine::numbers::{prepare, Prepared};
use engine::Derivation;
use numeric::Tape;
use numpy::ndarray::ArrayView2;
use numpy::{
    AllowTypeChange, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2, PyArrayLikeDyn, PyArrayMethods,
};
use pyo3::exceptions::PyKeyError;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::MutexExt;
use pyo3::types::{PyDict, PyMapping};
use sim::{FaultKind, Mechanical, Problem};
use std::cell::RefCell;
use std::sync::{Mutex, MutexGuard};

use crate::errors::{engine_error, numeric_error};
use crate::inputs::{self, Source};

/// Loads `source` for numbers, with its parameter values and initial state. `refused`, where
/// given, names what cannot take a scene with contacts (it would hold every contact closed,
/// as a two-sided constraint), which then raises naming them.
fn prepared(
    source: &str,
    units: bool,
    derived: Option<Derivation>,
    refused: Option<&str>,
) -> Result<(Prepared, Vec<f64>, Vec<f64>), engine::Error> {
    let prepared = match derived {
        Some(derivation) => engine::numbers::prepare_derived(derivation),
        None => prepare(source, &[], engine::Options { units })?,
    };
    if let Some(what) = refused {
        prepared.refuse_contacts(what)?;
    }
    let parameters = prepared.parameter_values(&[])?;
    let y0 = prepared.initial_state(&parameters, &[])?;
    Ok((prepared, parameters, y0))
}

fn fault_text(kind: &FaultKind, names: &[String]) -> String {
    let coordinates = |idx: &[usize]| -> String {
        idx.iter()
            .filter_map(|i| names.get(*i))
            .map(|s| format!("`{s}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match kind {
        FaultKind::SingularMass { coordinates: c, condition } => format!(
            "the mass matrix is singular or ill-conditioned here (condition ≈ {condition:.1e}; \
             along {})",
            if c.is_empty() { "some coordinate".to_string() } else { coordinates(c) }
        ),
        FaultKind::SingularConstraints { .. } => {
            "the constraints' Jacobian lost rank here".to_string()
        }
        FaultKind::NonFinite { at } => format!("a value became NaN or infinite ({at:?})"),
        other => format!("{other:?}"),
    }
}

/// y' = F(t, y) of a scene, y = (q, q̇) of its remaining coordinates: what
/// `scipy.integrate.solve_ivp` takes. Evaluated by the scene's lowered programs; constraints
/// kept with multipliers are solved with them (and Baumgarte-stabilised) as in `simulate`.
/// Usable from any thread: a call has the programs to itself.
#[pyclass(frozen, module = "lagrange")]
pub struct Rhs {
    /// Names of the state's slots: coordinates, then rates (`x`, `theta`, `x'`, `theta'`).
    #[pyo3(get)]
    names: Vec<String>,
    /// The free parameters' names in declaration order, the order of their values: the ones
    /// `p=` sets. The derived ones and the inputs are not among them.
    #[pyo3(get)]
    parameter_names: Vec<String>,
    /// The derived parameters' names in declaration order: each follows the free ones its
    /// value names, and none can be set.
    #[pyo3(get)]
    derived_parameter_names: Vec<String>,
    /// The inputs' names in declaration order, the order of `u=` as an array.
    #[pyo3(get)]
    input_names: Vec<String>,
    /// The scene's initial state.
    y0: Vec<f64>,
    /// What it is made from, to be made again when unpickled.
    source: String,
    units: bool,
    path: String,
    /// The programs, one call at a time; a thread waiting for them lets go of the GIL, so a
    /// call whose input callables run Python never blocks another thread's.
    inner: Mutex<RhsInner>,
}

impl Rhs {
    /// The right-hand side of the scene `source`, from `derived` (the loaded scene's
    /// derivation, derived from `source` with these `units`) where there is one.
    pub fn new(
        source: &str,
        path: &str,
        units: bool,
        derived: Option<Derivation>,
    ) -> PyResult<Self> {
        let inner = RhsInner::new(source, path, units, derived)?;
        Ok(Rhs {
            names: inner.names.clone(),
            parameter_names: inner.tunable.names.clone(),
            derived_parameter_names: inner.tunable.derived_names.clone(),
            input_names: inner.input_names.clone(),
            y0: inner.y0.clone(),
            source: source.to_string(),
            units,
            path: path.to_string(),
            inner: Mutex::new(inner),
        })
    }

    /// An [`Rhs`] made again from what it pickles as: the scene's text and settings, and the
    /// values of its parameters.
    pub fn from_pickle(
        source: &str,
        path: &str,
        units: bool,
        parameters: &[f64],
    ) -> PyResult<Self> {
        let rhs = Rhs::new(source, path, units, None)?;
        let mut inner = rhs.inner.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let mut all = inner.mechanical.parameters().to_vec();
        if parameters.len() != rhs.parameter_names.len() {
            return Err(PyValueError::new_err(format!(
                "{} parameter values for the {} parameters ({})",
                parameters.len(),
                rhs.parameter_names.len(),
                rhs.parameter_names.join(", ")
            )));
        }
        let values = inner.tunable.values_of_free(parameters)?;
        all[..values.len()].copy_from_slice(&values);
        inner.mechanical.set_parameters(&all);
        drop(inner);
        Ok(rhs)
    }

    /// The programs, for this thread alone until the guard is dropped; the GIL is let go while
    /// waiting for them. A call that panicked holding them left at worst its own parameter
    /// values in place, which the next call that gives its own replaces. A call from inside a
    /// call of the same `Rhs` on the same thread (an input callable that calls the `Rhs` it
    /// drives) would wait for itself: it raises instead.
    fn inner(&self, py: Python<'_>) -> PyResult<Held<'_>> {
        let key = self as *const Rhs as usize;
        if HELD.with(|held| held.borrow().contains(&key)) {
            return Err(PyRuntimeError::new_err(
                "this rhs is already in a call on this thread: an input callable (u=) may not \
                 call the rhs it drives",
            ));
        }
        let guard =
            self.inner.lock_py_attached(py).unwrap_or_else(|poisoned| poisoned.into_inner());
        HELD.with(|held| held.borrow_mut().push(key));
        Ok(Held { guard, key })
    }
}

thread_local! {
    /// The `Rhs` objects whose programs this thread holds, by address.
    static HELD: RefCell<Vec<usize>> = const { RefCell::new(Vec::new()) };
}

/// An [`Rhs`]'s programs, held by this thread until dropped.
struct Held<'a> {
    guard: MutexGuard<'a, RhsInner>,
    key: usize,
}

impl std::ops::Deref for Held<'_> {
    type Target = RhsInner;
    fn deref(&self) -> &RhsInner {
        &self.guard
    }
}

impl std::ops::DerefMut for Held<'_> {
    fn deref_mut(&mut self) -> &mut RhsInner {
        &mut self.guard
    }
}

impl Drop for Held<'_> {
    fn drop(&mut self) {
        HELD.with(|held| held.borrow_mut().retain(|k| *k != self.key));
    }
}

/// A state given to a call of one state, as its values: a 2-D array is refused with a
/// pointer to `batch` rather than NumPy's words about dimensions.
fn one_state(y: &PyArrayLikeDyn<'_, f64, AllowTypeChange>, names: &[String]) -> PyResult<Vec<f64>> {
    let y = y.as_array();
    if y.ndim() != 1 {
        return Err(PyValueError::new_err(format!(
            "y is one state, a 1-D array of {} entries ({}), not an array of shape {:?}; \
             f.batch(Y) takes many states, a row each",
            names.len(),
            names.join(", "),
            y.shape()
        )));
    }
    // A contiguous array is copied as one slice: the iterator of an array of any dimension
    // steps a multi-index per element, which cost more than the copy itself at 64 entries.
    Ok(match y.as_slice() {
        Some(values) => values.to_vec(),
        None => y.iter().copied().collect(),
    })
}

/// The programs of an [`Rhs`], their buffers and what a call reads: what one call at a
/// time uses.
struct RhsInner {
    mechanical: Mechanical,
    /// Names of the state's slots: coordinates, then rates (`x`, `theta`, `x'`, `theta'`).
    names: Vec<String>,
    y0: Vec<f64>,
    /// The parameters a call sets, and the derived ones that follow them.
    tunable: Tunable,
    /// The inputs' names in declaration order, the order of `u=` as an array.
    input_names: Vec<String>,
    /// The inputs' declared values, which they take where `u=` does not name them.
    declared_inputs: Vec<f64>,
    dy: Vec<f64>,
    /// The scene for numbers, kept to lower the partials when `jac` is first called (only
    /// implicit methods want them); `None` once they are.
    prepared: Option<Prepared>,
    path: String,
    jacobian: Vec<f64>,
}

impl RhsInner {
    pub fn new(
        source: &str,
        path: &str,
        units: bool,
        derived: Option<Derivation>,
    ) -> PyResult<Self> {
        // Its evaluations would hold every contact closed: a two-sided constraint it is not.
        let refused = "`Scene.rhs()` (f, f.batch and f.jac, which would hold every contact closed)";
        let (mut prepared, parameters, y0) =
            prepared(source, units, derived, Some(refused)).map_err(|e| engine_error(&e, path))?;
        let dynamics_exprs = prepared.dynamics_exprs();
        let inputs = prepared.dynamics_inputs();
        let dynamics =
            prepared.lower(&inputs, &dynamics_exprs).map_err(|e| engine_error(&e, path))?;
        let observation = prepared
            .lower(&prepared.observation_inputs(), &[])
            .map_err(|e| engine_error(&e, path))?;
        let names = prepared.state_names();
        // The slots of `parameters`: the parameters, then the inputs at their values.
        let model = &prepared.derivation.model;
        let tunable = Tunable::new(prepared.parameter_plan.clone());
        let input_names: Vec<String> = model.inputs.iter().map(|u| u.name.clone()).collect();
        let declared_inputs = parameters[tunable.slots()..].to_vec();
        let mut mechanical = Mechanical::new(
            prepared.layout,
            Tape::new(dynamics),
            Tape::new(observation),
            parameters,
        )
        .with_kinds(prepared.stabilisation());
        if let Some(recursive) = prepared.recursive().map_err(|e| engine_error(&e, path))? {
            mechanical = mechanical.with_chain(recursive);
        }
        let dim = mechanical.dim();
        Ok(RhsInner {
            mechanical,
            names,
            y0,
            tunable,
            input_names,
            declared_inputs,
            dy: vec![0.0; dim],
            prepared: Some(prepared),
            path: path.to_string(),
            jacobian: Vec::new(),
        })
    }

    /// Runs `body` with the parameter values `p` gives (none: those in use), and puts back
    /// those in use afterwards, whatever `body` returns.
    fn with_parameters<T>(
        &mut self,
        p: Option<&Bound<'_, PyAny>>,
        body: impl FnOnce(&mut Self) -> PyResult<T>,
    ) -> PyResult<T> {
        let Some(p) = p else { return body(self) };
        let kept = self.mechanical.parameters().to_vec();
        let mut given = kept.clone();
        let values = self.tunable.given(&kept, p)?;
        given[..values.len()].copy_from_slice(&values);
        self.mechanical.set_parameters(&given);
        let result = body(self);
        self.mechanical.set_parameters(&kept);
        result
    }

    fn check_length(&self, y: &[f64]) -> PyResult<()> {
        if y.len() == self.dy.len() {
            return Ok(());
        }
        Err(PyValueError::new_err(format!(
            "the state has {} entries ({}), not {}",
            self.dy.len(),
            self.names.join(", "),
            y.len()
        )))
    }

    /// What drives each input in a call: `u` read against the inputs (see
    /// [`inputs::sources`]); `rows` for a batch.
    fn sources(&self, u: Option<&Bound<'_, PyAny>>, rows: Option<usize>) -> PyResult<Vec<Source>> {
        let (names, parameters) = (&self.input_names, &self.tunable.all_names);
        inputs::sources(names, &self.declared_inputs, parameters, u, rows)
    }

    /// Puts the inputs' values at (t, y) into their slots (row `row` of a batch).
    fn set_inputs(
        &mut self,
        py: Python<'_>,
        sources: &[Source],
        t: f64,
        y: &[f64],
        row: usize,
    ) -> PyResult<()> {
        if sources.is_empty() {
            return Ok(());
        }
        let values = inputs::values(py, &self.input_names, sources, t, y, row)?;
        let mut all = self.mechanical.parameters().to_vec();
        all[self.tunable.slots()..].copy_from_slice(&values);
        self.mechanical.set_parameters(&all);
        Ok(())
    }

    fn eval(
        &mut self,
        py: Python<'_>,
        t: f64,
        y: &[f64],
        sources: &[Source],
        row: usize,
    ) -> PyResult<()> {
        self.check_length(y)?;
        self.set_inputs(py, sources, t, y, row)?;
        self.rhs_here(t, y)
    }

    /// F at (t, y) into `self.dy`, with the slots as they are.
    fn rhs_here(&mut self, t: f64, y: &[f64]) -> PyResult<()> {
        self.mechanical.rhs(t, y, &mut self.dy).map_err(|kind| {
            numeric_error(format!("at t = {t}: {}", fault_text(&kind, &self.names)))
        })
    }

    /// ∂F/∂y at (t, y) into `self.jacobian` with the inputs `sources` give: exact where they are
    /// numbers; an input given by a callable adds ∂F/∂u·∂u/∂y, both by central differences
    /// (the callable has no exact derivative, and ∂F/∂u is not lowered).
    fn eval_jacobian(
        &mut self,
        py: Python<'_>,
        t: f64,
        y: &[f64],
        sources: &[Source],
    ) -> PyResult<()> {
        self.check_length(y)?;
        self.set_inputs(py, sources, t, y, 0)?;
        self.exact_jacobian(t, y)?;
        let d = self.dy.len();
        let k = self.tunable.slots();
        for (j, source) in sources.iter().enumerate() {
            let Source::Law(law) = source else { continue };
            let gradient = inputs::law_gradient(py, law, t, y)?;
            let mut slots = self.mechanical.parameters().to_vec();
            let u = slots[k + j];
            let h = inputs::central_step(u);
            let mut sensitivity = vec![0.0; d];
            for (sign, weight) in [(1.0, 1.0), (-1.0, -1.0)] {
                slots[k + j] = u + sign * h;
                self.mechanical.set_parameters(&slots);
                self.rhs_here(t, y)?;
                for (s, f) in sensitivity.iter_mut().zip(&self.dy) {
                    *s += weight * f / (2.0 * h);
                }
            }
            slots[k + j] = u;
            self.mechanical.set_parameters(&slots);
            for (r, s) in sensitivity.iter().enumerate() {
                for (c, g) in gradient.iter().enumerate() {
                    self.jacobian[r * d + c] += s * g;
                }
            }
        }
        Ok(())
    }

    /// The exact ∂F/∂y at (t, y) with the slots as they are, lowering the partials the first
    /// time.
    fn exact_jacobian(&mut self, t: f64, y: &[f64]) -> PyResult<()> {
        if let Some(mut prepared) = self.prepared.take() {
            let exprs = prepared.partials_exprs();
            let program = prepared
                .lower(&prepared.observation_inputs(), &exprs)
                .map_err(|e| engine_error(&e, &self.path))?;
            self.mechanical.set_partials(Tape::new(program));
            self.jacobian = vec![0.0; self.dy.len() * self.dy.len()];
        }
        match self.mechanical.jacobian(t, y, &mut self.jacobian) {
            Ok(true) => Ok(()),
            Ok(false) => Err(numeric_error("the Jacobian's partials are missing".to_string())),
            Err(kind) => {
                Err(numeric_error(format!("at t = {t}: {}", fault_text(&kind, &self.names))))
            }
        }
    }
}

#[pymethods]
impl Rhs {
    /// F(t, y): the rates of the state y = (q, q̇) at time t, as a 1-D array (q̇, q̈); `p`
    /// gives parameter values for this call only (see [`parameter_values`]), `u` the inputs'
    /// values (see [`inputs::sources`]).
    #[pyo3(signature = (t, y, p = None, u = None))]
    fn __call__<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let y = one_state(&y, &self.names)?;
        let mut this = self.inner(py)?;
        let sources = this.sources(u, None)?;
        this.with_parameters(p, |rhs| rhs.eval(py, t, &y, &sources, 0))?;
        Ok(PyArray1::from_slice(py, &this.dy))
    }

    /// F at many states in one call: `Y` is a 2-D array with one state a row; `t` one time
    /// for all rows or one time per row; `p` parameter values for this call only; `u` the
    /// inputs' values, a dict's value also an array of one value per row. Returns an array of
    /// the same shape as `Y`.
    #[pyo3(signature = (y, t = None, p = None, u = None))]
    fn batch<'py>(
        &self,
        py: Python<'py>,
        y: PyArrayLike2<'py, f64, AllowTypeChange>,
        t: Option<&Bound<'py, PyAny>>,
        p: Option<&Bound<'py, PyAny>>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let y = y.as_array();
        let rows = y.nrows();
        let times: Vec<f64> = match t {
            None => vec![0.0; rows],
            Some(t) => match t.extract::<f64>() {
                Ok(t) => vec![t; rows],
                Err(_) => {
                    let t: PyArrayLike1<'py, f64, AllowTypeChange> = t.extract()?;
                    let t: Vec<f64> = t.as_array().iter().copied().collect();
                    if t.len() != rows {
                        return Err(PyValueError::new_err(format!(
                            "{} times for {rows} states",
                            t.len()
                        )));
                    }
                    t
                }
            },
        };
        let mut this = self.inner(py)?;
        let width = this.dy.len();
        if y.ncols() != width {
            return Err(PyValueError::new_err(format!(
                "each row is a state of {width} entries ({}), not {}",
                this.names.join(", "),
                y.ncols()
            )));
        }
        let mut out = Vec::with_capacity(rows * width);
        let mut state = vec![0.0; width];
        let sources = this.sources(u, Some(rows))?;
        // Inputs that are the same at every row leave every row's numbers to one batch.
        let same_inputs = sources.iter().all(|s| matches!(s, Source::Value(_)));
        this.with_parameters(p, |rhs| {
            if same_inputs {
                rhs.set_inputs(py, &sources, 0.0, &state, 0)?;
                let states: Vec<f64> = y.iter().copied().collect();
                out.resize(states.len(), 0.0);
                return rhs.mechanical.rhs_many(&times, &states, &mut out).map_err(
                    |(row, kind)| {
                        let at = times[row];
                        numeric_error(format!("at t = {at}: {}", fault_text(&kind, &rhs.names)))
                    },
                );
            }
            for (k, (row, t)) in y.rows().into_iter().zip(times.iter().copied()).enumerate() {
                for (slot, v) in state.iter_mut().zip(row.iter()) {
                    *slot = *v;
                }
                rhs.eval(py, t, &state, &sources, k)?;
                out.extend_from_slice(&rhs.dy);
            }
            Ok(())
        })?;
        let flat = PyArray1::from_vec(py, out);
        flat.reshape([rows, width])
    }

    /// ∂F/∂y at (t, y), exactly, as the 2-D array `solve_ivp(..., jac=f.jac)` takes: row i,
    /// column j is ∂F_i/∂y_j. From the equations' partials (lowered on the first call) and
    /// the matrix the accelerations are solved with, stabilisation of kept constraints
    /// included, so it is the Jacobian of `f` itself. `p` gives parameter values for this
    /// call only, as `solve_ivp`'s `args` hands them to `jac` as well as to `f`; `u` the
    /// inputs' values, as for `f`: an input a callable gives (a feedback law) adds its
    /// ∂F/∂u·∂u/∂y, by central differences.
    #[pyo3(signature = (t, y, p = None, u = None))]
    fn jac<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let y = one_state(&y, &self.names)?;
        let mut this = self.inner(py)?;
        let sources = this.sources(u, None)?;
        this.with_parameters(p, |rhs| rhs.eval_jacobian(py, t, &y, &sources))?;
        let d = this.dy.len();
        PyArray1::from_slice(py, &this.jacobian).reshape([d, d])
    }

    /// The scene's initial state (q, q̇), as `solve_ivp`'s `y0`.
    #[getter]
    fn y0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.y0)
    }

    /// The parameters' values the programs use, name to value, read-only: a change is made by
    /// assigning to `parameters`, never lost in a copy.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let this = self.inner(py)?;
        let values = this.tunable.free_values(this.mechanical.parameters());
        read_only(py, &self.parameter_names, &values)
    }

    /// Uses these values of the free parameters from now on: a dict replaces the values it
    /// names, an array gives them all (see [`Tunable::given`]); the derived ones follow.
    #[setter]
    fn set_parameters(&self, p: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut this = self.inner(p.py())?;
        let mut all = this.mechanical.parameters().to_vec();
        let values = this.tunable.given(&all, p)?;
        all[..values.len()].copy_from_slice(&values);
        this.mechanical.set_parameters(&all);
        Ok(())
    }

    /// The derived parameters' values in use, name to value, read-only: each follows the
    /// free parameters its value names.
    #[getter]
    fn derived_parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let this = self.inner(py)?;
        let values = this.tunable.derived_values(this.mechanical.parameters());
        read_only(py, &self.derived_parameter_names, &values)
    }

    /// Pickles as what it is made from: the scene's text and settings, and the parameter
    /// values in use; unpickling derives and lowers the scene again.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rebuild = py.import("lagrange._native")?.getattr("_rhs_from")?;
        let this = self.inner(py)?;
        let parameters = this.tunable.free_values(this.mechanical.parameters());
        drop(this);
        let arguments = (self.source.clone(), self.path.clone(), self.units, parameters);
        (rebuild, arguments).into_pyobject(py).map(|t| t.into_any())
    }

    /// The inputs' declared values, name to value, read-only: what each takes in a call whose
    /// `u` does not name it.
    #[getter]
    fn inputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let declared = self.inner(py)?.declared_inputs.clone();
        read_only(py, &self.input_names, &declared)
    }

    fn __repr__(&self) -> String {
        format!("<lagrange rhs of ({})>", self.names.join(", "))
    }
}

/// The parameters a caller of a compiled scene sets: the free ones, by name or in order; the
/// derived ones (`param L = 2*a`) follow them through the scene's one way to parameter values
/// (`model::ParameterValues`), as `simulate --set` has them follow.
#[derive(Clone, Debug)]
pub struct Tunable {
    plan: model::ParameterValues,
    /// The free parameters' names, in declaration order: what `p=` takes.
    names: Vec<String>,
    derived_names: Vec<String>,
    free: Vec<usize>,
    derived: Vec<usize>,
    /// Every parameter's name, for messages about a name that is not a free one.
    all_names: Vec<String>,
}

impl Tunable {
    pub fn new(plan: model::ParameterValues) -> Tunable {
        let all_names: Vec<String> = plan.names().map(str::to_string).collect();
        let (free, derived) = (plan.free(), plan.derived());
        Tunable {
            names: free.iter().map(|i| all_names[*i].clone()).collect(),
            derived_names: derived.iter().map(|i| all_names[*i].clone()).collect(),
            free,
            derived,
            all_names,
            plan,
        }
    }

    /// How many parameter slots the programs read before the inputs'.
    pub fn slots(&self) -> usize {
        self.plan.len()
    }

    /// The free parameters' values among the slots `values`.
    pub fn free_values(&self, values: &[f64]) -> Vec<f64> {
        self.free.iter().map(|i| values[*i]).collect()
    }

    /// The derived parameters' values among the slots `values`.
    pub fn derived_values(&self, values: &[f64]) -> Vec<f64> {
        self.derived.iter().map(|i| values[*i]).collect()
    }

    /// Every parameter's slot value from `given` (see [`free_given`]), the free ones in use
    /// read from `current`, every parameter's slot.
    pub fn given(&mut self, current: &[f64], given: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let free = free_given(&self.names, &self.free_values(current), &self.not_free(), given)?;
        self.values_of_free(&free)
    }

    /// Every parameter's slot value with these values of the free ones.
    pub fn values_of_free(&mut self, free: &[f64]) -> PyResult<Vec<f64>> {
        let mut all =
            self.plan.values_of_free(free).map_err(|e| PyValueError::new_err(e.to_string()))?;
        all.truncate(self.plan.len());
        Ok(all)
    }

    /// The error for a name that is not a free parameter: a derived one says what it
    /// follows, anything else lists the free ones.
    fn not_free(&self) -> NotFree {
        let derived = self.derived.iter().map(|i| {
            let message = self.plan.derived_error(*i).to_string();
            (self.all_names[*i].clone(), message)
        });
        NotFree { derived: derived.collect() }
    }
}

/// Why a name given to `p=` is refused: the derived parameters', with their messages.
pub struct NotFree {
    derived: Vec<(String, String)>,
}

/// The free parameters' values from `given`: a mapping of name to value replaces the values it
/// names in `current` (in the order of `names`); anything else is read as an array of every
/// free parameter's value in that order. Each value is finite; a derived parameter named
/// raises, naming what it is derived from.
pub fn free_given(
    names: &[String],
    current: &[f64],
    refused: &NotFree,
    given: &Bound<'_, PyAny>,
) -> PyResult<Vec<f64>> {
    if let Ok(mapping) = given.cast::<PyMapping>() {
        let mut values = current.to_vec();
        for item in mapping.items()?.iter() {
            let (name, value): (String, f64) = item.extract()?;
            let Some(k) = names.iter().position(|n| *n == name) else {
                if let Some((_, message)) = refused.derived.iter().find(|(n, _)| *n == name) {
                    return Err(PyValueError::new_err(message.clone()));
                }
                return Err(PyKeyError::new_err(format!(
                    "no parameter `{name}`; the parameters are {}",
                    names.join(", ")
                )));
            };
            values[k] = inputs::finite_value("parameter", &name, value)?;
        }
        return Ok(values);
    }
    let form = PyValueError::new_err(format!(
        "parameter values are a dict of name to value or an array of {} values ({})",
        names.len(),
        names.join(", ")
    ));
    inputs::in_order(names, given, "parameter", form)
}

/// A read-only mapping of `names` to `values` (`types.MappingProxyType` over a dict): an item
/// assigned to it raises rather than changing a copy that nothing reads.
fn read_only<'py>(
    py: Python<'py>,
    names: &[String],
    values: &[f64],
) -> PyResult<Bound<'py, PyAny>> {
    let dict = PyDict::new(py);
    for (name, value) in names.iter().zip(values) {
        dict.set_item(name, value)?;
    }
    py.import("types")?.getattr("MappingProxyType")?.call1((dict,))
}

/// τ = M·q̈ − f of a scene over many motions at once (`engine::inverse`): with constraints
/// kept, the forces least in τᵀ·M⁻¹·τ.
#[pyclass(module = "lagrange")]
pub struct InverseDynamics {
    inner: engine::inverse::InverseDynamics,
    /// The coordinates, in the order of q and of τ.
    #[pyo3(get)]
    names: Vec<String>,
    /// The free parameters' names, in the order of their values: the ones `p=` sets. The
    /// derived ones and the inputs are not among them.
    #[pyo3(get)]
    parameter_names: Vec<String>,
    /// The derived parameters' names: each follows the free ones its value names.
    #[pyo3(get)]
    derived_parameter_names: Vec<String>,
    /// The inputs' names, in the order of `u=` as an array.
    #[pyo3(get)]
    input_names: Vec<String>,
    tunable: Tunable,
    /// The constraints kept with multipliers.
    #[pyo3(get)]
    kept_constraints: Vec<String>,
}

impl InverseDynamics {
    pub fn new(source: &str, path: &str, units: bool) -> PyResult<Self> {
        let options = engine::inverse::Options { set: Vec::new(), no_units: !units };
        let inner = engine::inverse::inverse_dynamics(source, &options)
            .map_err(|e| engine_error(&e, path))?;
        Ok(InverseDynamics {
            names: inner.coordinates().to_vec(),
            parameter_names: inner.parameter_names().to_vec(),
            derived_parameter_names: inner.derived_parameter_names().to_vec(),
            input_names: inner.input_names().to_vec(),
            tunable: Tunable::new(inner.parameter_plan().clone()),
            kept_constraints: inner.kept_constraints().to_vec(),
            inner,
        })
    }

    /// τ of each row of the motion, one after another in a flat vector, with the inputs
    /// `sources` give at each.
    fn rows(
        &mut self,
        py: Python<'_>,
        t: &[f64],
        motion: [&ArrayView2<'_, f64>; 3],
        sources: &[Source],
    ) -> PyResult<Vec<f64>> {
        let n = self.names.len();
        let mut out = Vec::with_capacity(t.len() * n);
        let mut tau = vec![0.0; n];
        let row = |m: &ArrayView2<'_, f64>, k: usize| -> Vec<f64> { m.row(k).to_vec() };
        for (r, t) in t.iter().enumerate() {
            let [q, rates, accelerations] = motion.map(|m| row(m, r));
            if !sources.is_empty() {
                let state = [&q[..], &rates[..]].concat();
                let values = inputs::values(py, &self.input_names, sources, *t, &state, r)?;
                self.inner.set_inputs(&values).map_err(|e| engine_error(&e, "<inputs>"))?;
            }
            self.inner
                .torques(*t, &q, &rates, &accelerations, &mut tau)
                .map_err(|e| numeric_error(e.worded(engine::Piece::plain)))?;
            out.extend_from_slice(&tau);
        }
        Ok(out)
    }
}

#[pymethods]
impl InverseDynamics {
    /// τ at N motions: `t` (N times), `q`, `qd`, `qdd` (N×n arrays, one motion a row); `p`
    /// parameter values for this call only, `u` the inputs' (as for `rhs.batch`, a callable
    /// taking t and the state (q, q̇)). Returns an N×n array.
    #[pyo3(signature = (t, q, qd, qdd, p = None, u = None))]
    #[allow(clippy::too_many_arguments)]
    fn batch<'py>(
        &mut self,
        py: Python<'py>,
        t: PyArrayLike1<'py, f64, AllowTypeChange>,
        q: PyArrayLike2<'py, f64, AllowTypeChange>,
        qd: PyArrayLike2<'py, f64, AllowTypeChange>,
        qdd: PyArrayLike2<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.names.len();
        let t: Vec<f64> = t.as_array().iter().copied().collect();
        let (q, qd, qdd) = (q.as_array(), qd.as_array(), qdd.as_array());
        for (what, m) in [("q", &q), ("qd", &qd), ("qdd", &qdd)] {
            if m.nrows() != t.len() || m.ncols() != n {
                return Err(PyValueError::new_err(format!(
                    "`{what}` has {}×{} values for {} times of the {n} coordinates ({})",
                    m.nrows(),
                    m.ncols(),
                    t.len(),
                    self.names.join(", ")
                )));
            }
        }
        let kept = self.inner.slots().to_vec();
        let k = self.tunable.slots();
        let declared = &kept[k..];
        let all_names = &self.tunable.all_names;
        let sources = inputs::sources(&self.input_names, declared, all_names, u, Some(t.len()))?;
        let free = self.inner.parameters();
        if let Some(p) = p {
            let given = free_given(&self.parameter_names, &free, &self.tunable.not_free(), p)?;
            self.inner.set_parameters(&given).map_err(|e| engine_error(&e, "<parameters>"))?;
        }
        let result = self.rows(py, &t, [&q, &qd, &qdd], &sources);
        self.inner.set_parameters(&free).map_err(|e| engine_error(&e, "<parameters>"))?;
        self.inner.set_inputs(declared).map_err(|e| engine_error(&e, "<inputs>"))?;
        let flat = PyArray1::from_vec(py, result?);
        flat.reshape([t.len(), n])
    }

    /// The parameters' values in use, name to value, read-only: assign to `parameters` to
    /// change them.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(py, &self.parameter_names, &self.inner.parameters())
    }

    /// The derived parameters' values in use, name to value, read-only.
    #[getter]
    fn derived_parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(py, &self.derived_parameter_names, &self.inner.derived_parameters())
    }

    /// Uses these values of the free parameters from now on: a dict replaces those it names,
    /// an array gives them all; the derived ones follow.
    #[setter]
    fn set_parameters(&mut self, p: &Bound<'_, PyAny>) -> PyResult<()> {
        let free = self.inner.parameters();
        let values = free_given(&self.parameter_names, &free, &self.tunable.not_free(), p)?;
        self.inner.set_parameters(&values).map_err(|e| engine_error(&e, "<parameters>"))
    }

    fn __repr__(&self) -> String {
        format!("<lagrange inverse dynamics of ({})>", self.names.join(", "))
    }
}

/// M(t, q) of a scene at its parameter values: its remaining coordinates' mass matrix.
#[pyclass(module = "lagrange")]
pub struct MassMatrix {
    tape: Tape,
    n: usize,
    parameters: Vec<f64>,
    /// Names of the coordinates, in the order of M's rows.
    #[pyo3(get)]
    names: Vec<String>,
    input: Vec<f64>,
    output: Vec<f64>,
}

impl MassMatrix {
    /// M of the scene `source`, from `derived` as [`Rhs::new`] takes it.
    pub fn new(
        source: &str,
        path: &str,
        units: bool,
        derived: Option<Derivation>,
    ) -> PyResult<Self> {
        // M(q) is the same whichever contacts are closed.
        let (prepared, parameters, _) =
            prepared(source, units, derived, None).map_err(|e| engine_error(&e, path))?;
        let d = &prepared.derivation;
        let n = d.coords.len();
        let entries: Vec<cas::ExprId> =
            (0..n).flat_map(|i| (0..n).map(move |j| d.mass_matrix[i][j])).collect();
        let inputs = prepared.dynamics_inputs();
        let program = prepared.lower(&inputs, &entries).map_err(|e| engine_error(&e, path))?;
        let inputs = inputs.len();
        Ok(MassMatrix {
            tape: Tape::new(program),
            n,
            parameters,
            names: prepared.coordinate_names(),
            input: vec![0.0; inputs],
            output: vec![0.0; n * n],
        })
    }
}

#[pymethods]
impl MassMatrix {
    /// M at time t and coordinates q (a state y = (q, q̇) is taken too; M does not depend on
    /// the rates), as an n×n array.
    fn __call__<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: PyArrayLike1<'py, f64, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.n;
        let q = q.as_array();
        if q.len() != n && q.len() != 2 * n {
            return Err(PyValueError::new_err(format!(
                "M takes the {n} coordinates ({}) or a whole state of {}, not {} values",
                self.names.join(", "),
                2 * n,
                q.len()
            )));
        }
        self.input.iter_mut().for_each(|v| *v = 0.0);
        self.input[0] = t;
        for (slot, v) in self.input[1..].iter_mut().zip(q.iter()) {
            *slot = *v;
        }
        self.input[1 + 2 * n..].copy_from_slice(&self.parameters);
        self.tape.eval(&self.input, &mut self.output);
        // As `rhs` raises where its numbers are not finite, so does M.
        if let Some(k) = self.output.iter().position(|v| !v.is_finite()) {
            return Err(numeric_error(format!(
                "at t = {t}, M[{}, {}] is {} (q = {:?})",
                k % n,
                k / n,
                self.output[k],
                q.iter().take(n).collect::<Vec<_>>()
            )));
        }
        let flat = PyArray1::from_slice(py, &self.output);
        flat.reshape([n, n])
    }

    fn __repr__(&self) -> String {
        format!("<lagrange mass matrix of ({})>", self.names.join(", "))
    }
}
