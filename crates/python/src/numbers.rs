//! The scene's equations as fast callables for NumPy and SciPy: `Scene.rhs()` gives
//! y' = F(t, y) for `scipy.integrate.solve_ivp` (y = coordinates, then rates), evaluated by the
//! lowered programs through `sim::Mechanical` exactly as `simulate` runs them, with
//! `.batch(Y)` for many states in one call, `.jac(t, y)`, the exact ∂F/∂y for `solve_ivp`'s
//! `jac` (its partials lowered on first use), and parameter values per call or from then on;
//! `Scene.mass_matrix_function()` gives M(t, q); the inverse dynamics τ = M·q̈ − f of
//! `engine::inverse` over many states is [`InverseDynamics`].

use engine::numbers::{prepare, Prepared};
use numeric::Tape;
use numpy::ndarray::ArrayView2;
use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2, PyArrayMethods};
use pyo3::exceptions::PyKeyError;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyMapping};
use sim::{FaultKind, Mechanical, Problem};
use std::sync::{Mutex, MutexGuard};

use crate::errors::{engine_error, numeric_error};

/// Loads `source` for numbers, with its parameter values and initial state.
fn prepared(source: &str, units: bool) -> Result<(Prepared, Vec<f64>, Vec<f64>), engine::Error> {
    let prepared = prepare(source, &[], engine::Options { units })?;
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
        FaultKind::NonFinite { component } => {
            format!("a value became NaN or infinite (component {component})")
        }
        other => format!("{other:?}"),
    }
}

/// y' = F(t, y) of a scene, y = (q, q̇) of its remaining coordinates: what
/// `scipy.integrate.solve_ivp` takes. Evaluated by the scene's lowered programs; constraints
/// kept with multipliers are solved with them (and Baumgarte-stabilised) as in `simulate`.
/// Usable from any thread: the programs and their buffers are behind a lock, held for one
/// call at a time.
#[pyclass(frozen, module = "lagrange")]
pub struct Rhs {
    /// Names of the state's slots: coordinates, then rates (`x`, `theta`, `x'`, `theta'`).
    #[pyo3(get)]
    names: Vec<String>,
    y0: Vec<f64>,
    /// The parameters' names in declaration order, the order of their values.
    #[pyo3(get)]
    parameter_names: Vec<String>,
    /// What it is made from, to be made again when unpickled.
    source: String,
    units: bool,
    path: String,
    state: Mutex<RhsState>,
}

/// The programs of an [`Rhs`] and their buffers: what a call changes.
struct RhsState {
    mechanical: Mechanical,
    names: Vec<String>,
    dy: Vec<f64>,
    /// The scene for numbers, kept to lower the partials when `jac` is first called (only
    /// implicit methods want them); `None` once they are.
    prepared: Option<Prepared>,
    path: String,
    jacobian: Vec<f64>,
}

impl Rhs {
    /// An [`Rhs`] made again from what it pickles as: the scene's text and settings, and the
    /// parameter values it had.
    pub fn from_pickle(
        source: &str,
        path: &str,
        units: bool,
        parameters: &[f64],
    ) -> PyResult<Self> {
        let rhs = Rhs::new(source, path, units)?;
        if parameters.len() != rhs.parameter_names.len() {
            return Err(PyValueError::new_err(format!(
                "{} parameter values for the {} parameters ({})",
                parameters.len(),
                rhs.parameter_names.len(),
                rhs.parameter_names.join(", ")
            )));
        }
        rhs.state().mechanical.set_parameters(parameters);
        Ok(rhs)
    }

    pub fn new(source: &str, path: &str, units: bool) -> PyResult<Self> {
        let (mut prepared, parameters, y0) =
            prepared(source, units).map_err(|e| engine_error(&e, path))?;
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
        let parameter_names = model.params.iter().map(|p| p.name.clone());
        let parameter_names: Vec<String> =
            parameter_names.chain(model.inputs.iter().map(|u| u.name.clone())).collect();
        let mechanical = Mechanical::new(
            prepared.layout,
            Tape::new(dynamics),
            Tape::new(observation),
            parameters,
        )
        .with_kinds(prepared.stabilisation());
        let dim = mechanical.dim();
        let state = RhsState {
            mechanical,
            names: names.clone(),
            dy: vec![0.0; dim],
            prepared: Some(prepared),
            path: path.to_string(),
            jacobian: Vec::new(),
        };
        Ok(Rhs {
            names,
            y0,
            parameter_names,
            source: source.to_string(),
            units,
            path: path.to_string(),
            state: Mutex::new(state),
        })
    }

    /// The programs, for this thread alone until the guard is dropped. A call that panicked
    /// holding them left at worst parameters of its own in place; the next call sets its own.
    fn state(&self) -> MutexGuard<'_, RhsState> {
        self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Runs `body` on the programs with the parameter values `p` gives (none: those in use),
    /// and puts back those in use afterwards, whatever `body` returns. `p` is read before the
    /// programs are locked: reading it may run Python code.
    fn with_parameters<T>(
        &self,
        p: Option<&Bound<'_, PyAny>>,
        body: impl FnOnce(&mut RhsState) -> PyResult<T>,
    ) -> PyResult<T> {
        let Some(p) = p else { return body(&mut self.state()) };
        let kept = self.state().mechanical.parameters().to_vec();
        let given = parameter_values(&self.parameter_names, &kept, p)?;
        let mut state = self.state();
        let kept = state.mechanical.parameters().to_vec();
        state.mechanical.set_parameters(&given);
        let result = body(&mut state);
        state.mechanical.set_parameters(&kept);
        result
    }
}

impl RhsState {
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

    fn eval(&mut self, t: f64, y: &[f64]) -> PyResult<()> {
        self.check_length(y)?;
        self.mechanical.rhs(t, y, &mut self.dy).map_err(|kind| {
            numeric_error(format!("at t = {t}: {}", fault_text(&kind, &self.names)))
        })
    }

    /// The exact ∂F/∂y at (t, y) into `self.jacobian`, lowering the partials the first time.
    fn eval_jacobian(&mut self, t: f64, y: &[f64]) -> PyResult<()> {
        self.check_length(y)?;
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
    /// gives parameter values for this call only (see [`parameter_values`]).
    #[pyo3(signature = (t, y, p = None))]
    fn __call__<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyArrayLike1<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let y = y.as_array();
        let y: Vec<f64> = y.iter().copied().collect();
        let dy = self.with_parameters(p, |rhs| rhs.eval(t, &y).map(|()| rhs.dy.clone()))?;
        Ok(PyArray1::from_vec(py, dy))
    }

    /// F at many states in one call: `Y` is a 2-D array with one state a row; `t` one time
    /// for all rows or one time per row; `p` parameter values for this call only. Returns an
    /// array of the same shape as `Y`.
    #[pyo3(signature = (y, t = None, p = None))]
    fn batch<'py>(
        &self,
        py: Python<'py>,
        y: PyArrayLike2<'py, f64, AllowTypeChange>,
        t: Option<&Bound<'py, PyAny>>,
        p: Option<&Bound<'py, PyAny>>,
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
        let width = self.y0.len();
        if y.ncols() != width {
            return Err(PyValueError::new_err(format!(
                "each row is a state of {width} entries ({}), not {}",
                self.names.join(", "),
                y.ncols()
            )));
        }
        let mut out = Vec::with_capacity(rows * width);
        let mut state = vec![0.0; width];
        self.with_parameters(p, |rhs| {
            for (row, t) in y.rows().into_iter().zip(times) {
                for (slot, v) in state.iter_mut().zip(row.iter()) {
                    *slot = *v;
                }
                rhs.eval(t, &state)?;
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
    /// call only, as `solve_ivp`'s `args` hands them to `jac` as well as to `f`.
    #[pyo3(signature = (t, y, p = None))]
    fn jac<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyArrayLike1<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let y: Vec<f64> = y.as_array().iter().copied().collect();
        let jacobian =
            self.with_parameters(p, |rhs| rhs.eval_jacobian(t, &y).map(|()| rhs.jacobian.clone()))?;
        let d = self.y0.len();
        PyArray1::from_vec(py, jacobian).reshape([d, d])
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
        let values = self.state().mechanical.parameters().to_vec();
        read_only(py, &self.parameter_names, &values)
    }

    /// Uses these parameter values from now on: a dict replaces the values it names, an
    /// array gives them all (see [`parameter_values`]).
    #[setter]
    fn set_parameters(&self, p: &Bound<'_, PyAny>) -> PyResult<()> {
        let current = self.state().mechanical.parameters().to_vec();
        let values = parameter_values(&self.parameter_names, &current, p)?;
        self.state().mechanical.set_parameters(&values);
        Ok(())
    }

    /// Pickles as what it is made from: the scene's text and settings, and the parameter
    /// values in use; unpickling derives and lowers the scene again.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let rebuild = py.import("lagrange._native")?.getattr("_rhs_from")?;
        let parameters = self.state().mechanical.parameters().to_vec();
        let arguments = (self.source.clone(), self.path.clone(), self.units, parameters);
        (rebuild, arguments).into_pyobject(py).map(|t| t.into_any())
    }

    fn __repr__(&self) -> String {
        format!("<lagrange rhs of ({})>", self.names.join(", "))
    }
}

/// Parameter values from `given`: a mapping of name to value replaces the values it names in
/// `current`; anything else is read as an array of every value in the order of `names`. Each
/// value is finite. A parameter the scene defines from others is a value like any other here:
/// it is not recomputed when they change.
pub fn parameter_values(
    names: &[String],
    current: &[f64],
    given: &Bound<'_, PyAny>,
) -> PyResult<Vec<f64>> {
    let finite = |name: &str, v: f64| {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(PyValueError::new_err(format!("parameter `{name}` must be finite, not {v}")))
        }
    };
    if let Ok(mapping) = given.cast::<PyMapping>() {
        let mut values = current.to_vec();
        for item in mapping.items()?.iter() {
            let (name, value): (String, f64) = item.extract()?;
            let Some(k) = names.iter().position(|n| *n == name) else {
                return Err(PyKeyError::new_err(format!(
                    "no parameter `{name}`; the parameters are {}",
                    names.join(", ")
                )));
            };
            values[k] = finite(&name, value)?;
        }
        return Ok(values);
    }
    let array: PyArrayLike1<'_, f64, AllowTypeChange> = given.extract().map_err(|_| {
        PyValueError::new_err(format!(
            "parameter values are a dict of name to value or an array of {} values ({})",
            names.len(),
            names.join(", ")
        ))
    })?;
    let values: Vec<f64> = array.as_array().iter().copied().collect();
    if values.len() != names.len() {
        return Err(PyValueError::new_err(format!(
            "{} parameter values for the {} parameters ({})",
            values.len(),
            names.len(),
            names.join(", ")
        )));
    }
    names.iter().zip(values).map(|(name, v)| finite(name, v)).collect()
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
    /// The parameters' names, in the order of their values.
    #[pyo3(get)]
    parameter_names: Vec<String>,
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
            kept_constraints: inner.kept_constraints().to_vec(),
            inner,
        })
    }

    /// τ of each row of the motion, one after another in a flat vector.
    fn rows(&mut self, t: &[f64], motion: [&ArrayView2<'_, f64>; 3]) -> PyResult<Vec<f64>> {
        let n = self.names.len();
        let mut out = Vec::with_capacity(t.len() * n);
        let mut tau = vec![0.0; n];
        let row = |m: &ArrayView2<'_, f64>, k: usize| -> Vec<f64> { m.row(k).to_vec() };
        for (k, t) in t.iter().enumerate() {
            let [q, rates, accelerations] = motion.map(|m| row(m, k));
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
    /// parameter values for this call only. Returns an N×n array.
    #[pyo3(signature = (t, q, qd, qdd, p = None))]
    fn batch<'py>(
        &mut self,
        py: Python<'py>,
        t: PyArrayLike1<'py, f64, AllowTypeChange>,
        q: PyArrayLike2<'py, f64, AllowTypeChange>,
        qd: PyArrayLike2<'py, f64, AllowTypeChange>,
        qdd: PyArrayLike2<'py, f64, AllowTypeChange>,
        p: Option<&Bound<'py, PyAny>>,
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
        let kept = self.inner.parameters().to_vec();
        if let Some(p) = p {
            let given = parameter_values(&self.parameter_names, &kept, p)?;
            self.inner.set_parameters(&given).map_err(|e| engine_error(&e, "<parameters>"))?;
        }
        let result = self.rows(&t, [&q, &qd, &qdd]);
        self.inner.set_parameters(&kept).map_err(|e| engine_error(&e, "<parameters>"))?;
        let flat = PyArray1::from_vec(py, result?);
        flat.reshape([t.len(), n])
    }

    /// The parameters' values in use, name to value, read-only: assign to `parameters` to
    /// change them.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        read_only(py, &self.parameter_names, self.inner.parameters())
    }

    /// Uses these parameter values from now on: a dict replaces those it names, an array gives
    /// them all.
    #[setter]
    fn set_parameters(&mut self, p: &Bound<'_, PyAny>) -> PyResult<()> {
        let values = parameter_values(&self.parameter_names, self.inner.parameters(), p)?;
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
    pub fn new(source: &str, path: &str, units: bool) -> PyResult<Self> {
        let (prepared, parameters, _) =
            prepared(source, units).map_err(|e| engine_error(&e, path))?;
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
        let flat = PyArray1::from_slice(py, &self.output);
        flat.reshape([n, n])
    }

    fn __repr__(&self) -> String {
        format!("<lagrange mass matrix of ({})>", self.names.join(", "))
    }
}
