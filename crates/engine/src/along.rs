//! Linearization along a motion: A(t), B(t), C(t), D(t) of the small motions about a given
//! motion (a run of the scene, or a trajectory from a file), at each of its samples, and the
//! state-transition matrix Φ(t_end, t_0) over it.
//!
//! A motion is not an equilibrium, so the analysis about a reference (`linear`'s cases, which
//! substitute the reference into the equations exactly) does not apply. What does is the
//! first-order problem a run integrates, `sim::Mechanical`: A is its exact Jacobian
//! ∂(q̇, q̈)/∂(q, q̇), made of the residual's partials with q̈ and λ held at the sample's
//! (through the augmented system [M −Jᵀ; J 0] where constraints are kept, their Baumgarte
//! terms included, since those are part of the right-hand side the motion follows). It is the
//! very matrix `sim::variational` integrates Φ with beside a run, so that A at the samples and
//! Φ over a run come from one lowering. B takes each input's generalized force −∂r/∂u through
//! the same augmented system, and C and D read each output's gradient, its accelerations
//! through A's and B's lower rows.
//!
//! Along a run, Φ is the variational run's (`simulation::along`); along a motion known only at
//! its samples, [`transition`] integrates Φ̇ = A(t)·Φ with A linear between them.
//!
//! Scenes with contacts are refused: a motion through an impact has no linearization at the
//! jump. With kept constraints the state is every remaining coordinate and rate, as a run's
//! is: A holds the directions across the constraints too, where Baumgarte's terms pull the
//! state back.

pub mod transition;

pub use nalgebra::DMatrix;
use numeric::Tape;
use sim::{FaultKind, Mechanical, Problem};

use crate::input::Assignment;
use crate::numbers::Prepared;
use crate::{Error, Setting};

pub use transition::{state_transition, Between};

/// What a front end asks for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Parameter values (scene expressions) in place of the scene's.
    pub set: Vec<Assignment>,
    /// Skip the dimension check.
    pub no_units: bool,
    /// Whether `set` may name coordinates and rates: a run's start, which the motion already
    /// holds (else naming one is an error: a trajectory gives the state).
    pub starts_allowed: bool,
}

/// A motion: its times (strictly increasing), and at each the state (q, then q̇, of the
/// remaining coordinates) and the inputs' values.
#[derive(Clone, Debug, Default)]
pub struct Motion {
    pub times: Vec<f64>,
    pub states: Vec<Vec<f64>>,
    pub inputs: Vec<Vec<f64>>,
}

/// The first-order form ẋ = A·x + B·u, y = C·x + D·u of the small motions about one sample.
#[derive(Clone, Debug, PartialEq)]
pub struct Linear {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub c: DMatrix<f64>,
    pub d: DMatrix<f64>,
}

/// A scene ready to be linearized at any state: its equations and their partials lowered.
pub struct Along {
    coordinates: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    /// Every parameter's value, then the inputs' (the programs' parameter slots).
    slots: Vec<f64>,
    /// Where the inputs' slots begin.
    first_input: usize,
    /// The equations as a run integrates them, with their exact Jacobian; its observations,
    /// taken at the q̈ and λ it solves, are M (row-major), J of each kept constraint (a row
    /// each), −∂r/∂u (row-major), then per output ∂y/∂q, ∂y/∂q̇, ∂y/∂q̈ and ∂y/∂u.
    mechanical: Mechanical,
    multipliers: usize,
    observed: Vec<f64>,
    jacobian: Vec<f64>,
}

/// Loads `source` and lowers what a linearization along a motion needs.
pub fn along(source: &str, options: &Options) -> Result<Along, Error> {
    let values: Vec<(Option<&str>, String)> =
        options.set.iter().map(|a| (Some(a.name.as_str()), a.value.clone())).collect();
    let (model, warnings) =
        crate::resolve_with(source, crate::Options { units: !options.no_units })?;
    let mut prepared = crate::numbers::prepare_resolved_for(source, model, warnings, &values)?;
    refuse(&prepared)?;
    let overrides = overrides(&prepared, options)?;
    let slots = prepared.parameter_values(&overrides)?;
    from_prepared(&mut prepared, slots)
}

/// What a linearization along a motion does not take: contacts, named (see the module's doc).
pub fn refuse(prepared: &Prepared) -> Result<(), Error> {
    prepared.refuse_contacts("linearization along a motion")
}

/// [`along`] of a scene already loaded (a run's, whose programs are lowered first so that the
/// run is the one `simulate` makes), at the parameter slots' values `slots` (every parameter,
/// then the inputs).
pub fn from_prepared(prepared: &mut Prepared, slots: Vec<f64>) -> Result<Along, Error> {
    refuse(prepared)?;
    let d = &mut prepared.derivation;
    let n = d.coords.len();
    if n == 0 {
        return Err(Error::Input(
            "the constraints fix every coordinate: nothing is left to linearize".into(),
        ));
    }
    let inputs: Vec<cas::SymId> = d.model.inputs.iter().map(|u| u.sym).collect();
    let mut observed: Vec<cas::ExprId> = d.mass_matrix.iter().flatten().copied().collect();
    for m in &d.multipliers {
        observed.extend(&m.rows.jacobian);
    }
    // −∂r/∂u = ∂f/∂u − (∂M/∂u)·q̈: the generalized force of each input. J does not depend on
    // an input (one in a constraint is refused, or a run puts its value in place before
    // deriving), so neither Jᵀλ nor the constraints' rows add to it.
    let accels: Vec<cas::ExprId> = d.accels.iter().map(|a| d.model.pool.sym(*a)).collect();
    for i in 0..n {
        for u in &inputs {
            let pool = &mut d.model.pool;
            let mut terms = vec![pool.diff(d.forcing[i], *u)];
            for (entry, accel) in d.mass_matrix[i].iter().zip(&accels) {
                let dm = pool.diff(*entry, *u);
                let inertial = pool.mul2(dm, *accel);
                terms.push(pool.neg(inertial));
            }
            observed.push(pool.add(&terms));
        }
    }
    // An output names no reaction (the model refuses one), so no multiplier stands in its
    // gradient: ∂λ/∂x, which the Jacobian of (q̇, q̈) does not give, is never needed.
    for output in d.model.outputs.clone() {
        let y = d.expand_quantities(output.value, false);
        let pool = &mut d.model.pool;
        for of in [&d.coords, &d.rates, &d.accels, &inputs] {
            observed.extend(of.iter().map(|s| pool.diff(y, *s)).collect::<Vec<_>>());
        }
    }
    let dynamics_exprs = prepared.dynamics_exprs();
    let dynamics = Tape::new(prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs)?);
    let observation = Tape::new(prepared.lower(&prepared.observation_inputs(), &observed)?);
    let partials = Tape::new(prepared.partials_program()?);
    let mechanical = Mechanical::new(prepared.layout, dynamics, observation, slots.clone())
        .with_kinds(prepared.stabilisation())
        .with_partials(partials);
    // A long chain's q̈, A and B by the recursive form's sweep, as its runs solve them.
    let mechanical = match prepared.recursive()? {
        Some(recursive) => mechanical.with_chain(recursive),
        None => mechanical,
    };
    let d = &prepared.derivation;
    Ok(Along {
        coordinates: prepared.coordinate_names(),
        inputs: d.model.inputs.iter().map(|u| u.name.clone()).collect(),
        outputs: d.model.outputs.iter().map(|o| o.name.clone()).collect(),
        first_input: prepared.parameter_plan.len(),
        slots,
        observed: vec![0.0; mechanical.observations()],
        jacobian: vec![0.0; 4 * n * n],
        multipliers: prepared.layout.multipliers,
        mechanical,
    })
}

/// The `--set` values by parameter index; a coordinate or rate is a run's start, skipped
/// where the options allow it.
fn overrides(prepared: &Prepared, options: &Options) -> Result<Vec<(usize, cas::ExprId)>, Error> {
    let model = &prepared.derivation.model;
    let mut overrides = Vec::new();
    for (Assignment { name, .. }, expr) in options.set.iter().zip(&prepared.extra) {
        if let Some(k) = model.params.iter().position(|p| p.name == *name) {
            if prepared.parameter_plan.is_derived(k) {
                let plan = &prepared.parameter_plan;
                return Err(crate::numbers::derived_error(plan, Setting::Set, k));
            }
            overrides.push((k, *expr));
            continue;
        }
        let base = name.trim_end_matches('\'');
        let state = model.coords.iter().any(|c| c.name == base);
        if state && options.starts_allowed {
            continue;
        }
        let known: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
        let rest = if state {
            ": a trajectory gives the state at every sample; --set takes parameters".to_string()
        } else {
            format!(": no parameter of that name; one of {}", known.join(", "))
        };
        return Err(Error::given(Setting::Set, name, rest));
    }
    Ok(overrides)
}

impl Along {
    /// The remaining coordinates, in the order of q.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The state's names: the coordinates, then their rates (`theta'`).
    pub fn state_names(&self) -> Vec<String> {
        let rates = self.coordinates.iter().map(|c| format!("{c}'"));
        self.coordinates.iter().cloned().chain(rates).collect()
    }

    /// The inputs' names: the columns of B and D.
    pub fn input_names(&self) -> &[String] {
        &self.inputs
    }

    /// The outputs' names: the rows of C and D.
    pub fn output_names(&self) -> &[String] {
        &self.outputs
    }

    /// The inputs' values when nothing drives them, in the order of [`Self::input_names`].
    pub fn resting_inputs(&self) -> Vec<f64> {
        self.slots[self.first_input..].to_vec()
    }

    /// The first-order problem A is the Jacobian of, at the parameters' values and the
    /// inputs of the last sample asked for: what a variational run integrates Φ on.
    pub fn mechanical(&self) -> &Mechanical {
        &self.mechanical
    }

    fn check(&self, t: f64, state: &[f64], inputs: &[f64]) -> Result<(), Error> {
        let n = self.coordinates.len();
        if state.len() != 2 * n {
            return Err(Error::Input(format!(
                "{} state values for the {} of the state ({})",
                state.len(),
                2 * n,
                self.state_names().join(", ")
            )));
        }
        if inputs.len() != self.inputs.len() {
            return Err(Error::Input(format!(
                "{} input values for the {} inputs ({})",
                inputs.len(),
                self.inputs.len(),
                self.inputs.join(", ")
            )));
        }
        if !t.is_finite() || state.iter().chain(inputs).any(|v| !v.is_finite()) {
            return Err(Error::Input(format!("at t = {t}, a value of the motion is not finite")));
        }
        Ok(())
    }

    /// The inputs' values put in their slots, checked with the sample first.
    fn set_inputs(&mut self, t: f64, state: &[f64], inputs: &[f64]) -> Result<(), Error> {
        self.check(t, state, inputs)?;
        let first = self.first_input;
        self.slots[first..].copy_from_slice(inputs);
        self.mechanical.set_parameters(&self.slots);
        Ok(())
    }

    /// (q̇, q̈) at the sample: the right-hand side the motion of the scene follows (with kept
    /// constraints, as a run integrates it, Baumgarte's terms included).
    pub fn rate(&mut self, t: f64, state: &[f64], inputs: &[f64]) -> Result<Vec<f64>, Error> {
        self.set_inputs(t, state, inputs)?;
        let mut rate = vec![0.0; state.len()];
        self.mechanical.rhs(t, state, &mut rate).map_err(|kind| fault(t, &kind))?;
        Ok(rate)
    }

    /// A, B, C and D of the small motions about the sample (time `t`, state (q, q̇), inputs'
    /// values), moving or at rest.
    pub fn at(&mut self, t: f64, state: &[f64], inputs: &[f64]) -> Result<Linear, Error> {
        let (n, m) = (self.coordinates.len(), self.multipliers);
        let (ni, no) = (self.inputs.len(), self.outputs.len());
        self.set_inputs(t, state, inputs)?;
        let fail = |kind: FaultKind| fault(t, &kind);
        self.mechanical.jacobian(t, state, &mut self.jacobian).map_err(fail)?;
        self.mechanical.observe(t, state, &mut self.observed).map_err(fail)?;
        let a = DMatrix::from_row_slice(2 * n, 2 * n, &self.jacobian);
        let out = &self.observed[..self.observed.len() - m];
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            return Err(Error::Numeric(format!(
                "at t = {t}, a partial derivative of the equations is not finite ({})",
                out[k]
            )));
        }
        let (mass, rest) = out.split_at(n * n);
        let (rows, rest) = rest.split_at(m * n);
        let (forces, gradients) = rest.split_at(n * ni);
        let mut b = DMatrix::zeros(2 * n, ni);
        if ni > 0 {
            // [M −Jᵀ; J 0]·(∂q̈, ∂λ)/∂u = (−∂r/∂u, 0): the system the accelerations solve.
            let rows = DMatrix::from_row_slice(m, n, rows);
            let mut system = DMatrix::zeros(n + m, n + m);
            system.view_mut((0, 0), (n, n)).copy_from(&DMatrix::from_row_slice(n, n, mass));
            system.view_mut((0, n), (n, m)).copy_from(&-rows.transpose());
            system.view_mut((n, 0), (m, n)).copy_from(&rows);
            let mut by_inputs = DMatrix::zeros(n + m, ni);
            by_inputs.view_mut((0, 0), (n, ni)).copy_from(&DMatrix::from_row_slice(n, ni, forces));
            let solved = system.lu().solve(&by_inputs).filter(|s| s.iter().all(|v| v.is_finite()));
            let Some(solved) = solved else {
                return Err(Error::Numeric(format!(
                    "at t = {t}, the inputs' effect on the accelerations is not finite (the \
                     mass matrix{} is singular there)",
                    if m > 0 { " with the kept constraints' rows" } else { "" }
                )));
            };
            b.view_mut((n, 0), (n, ni)).copy_from(&solved.rows(0, n));
        }
        let width = 3 * n + ni;
        let mut c = DMatrix::zeros(no, 2 * n);
        let mut d = DMatrix::zeros(no, ni);
        for (row, g) in gradients.chunks(width).enumerate().take(no) {
            let (positions, rest) = g.split_at(n);
            let (rates, rest) = rest.split_at(n);
            let (accels, by_inputs) = rest.split_at(n);
            // An output that reads accelerations reads them through q̈ = A's and B's lower rows.
            for j in 0..2 * n {
                let direct = if j < n { positions[j] } else { rates[j - n] };
                let through: f64 = (0..n).map(|i| accels[i] * a[(n + i, j)]).sum();
                c[(row, j)] = direct + through;
            }
            for k in 0..ni {
                let through: f64 = (0..n).map(|i| accels[i] * b[(n + i, k)]).sum();
                d[(row, k)] = by_inputs[k] + through;
            }
        }
        Ok(Linear { a, b, c, d })
    }
}

/// A fault of the equations at a sample, in words.
fn fault(t: f64, kind: &FaultKind) -> Error {
    let words = match kind {
        FaultKind::SingularMass { condition, .. } => {
            format!("the mass matrix is singular there (condition {condition:.1e})")
        }
        FaultKind::SingularConstraints { .. } => {
            "the kept constraints' gradients are dependent there (a dead point, or constraints \
             that coincide)"
                .to_string()
        }
        FaultKind::NonFinite { .. } => {
            "a value of the equations or of their partials is not finite there".to_string()
        }
        other => format!("{other:?}"),
    };
    Error::Numeric(format!("at t = {t}, no first-order form: {words}"))
}

/// The motion checked against the scene: one state and one set of inputs per time, the
/// times finite and strictly increasing, at least two of them.
pub fn check_motion(along: &Along, motion: &Motion) -> Result<(), Error> {
    let k = motion.times.len();
    if k < 2 {
        return Err(Error::Input(format!(
            "a motion needs at least two samples to linearize along, and this one has {k}"
        )));
    }
    if motion.states.len() != k || motion.inputs.len() != k {
        return Err(Error::Input(format!(
            "{k} times, {} states and {} sets of inputs: one of each per sample",
            motion.states.len(),
            motion.inputs.len()
        )));
    }
    for (i, pair) in motion.times.windows(2).enumerate() {
        if pair[1].partial_cmp(&pair[0]) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Input(format!(
                "the times of a motion must increase, and sample {} (t = {}) does not come after \
                 sample {} (t = {})",
                i + 2,
                pair[1],
                i + 1,
                pair[0]
            )));
        }
    }
    for (i, (state, inputs)) in motion.states.iter().zip(&motion.inputs).enumerate() {
        along.check(motion.times[i], state, inputs)?;
    }
    Ok(())
}

/// The linearization along a motion: its first-order form at each sample, and Φ over it.
pub struct Linearized {
    pub state: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub times: Vec<f64>,
    pub samples: Vec<Linear>,
    /// Φ(t_end, t_0): δx(t_end) = Φ·δx(t_0) with the inputs held on the motion.
    pub transition: DMatrix<f64>,
    /// How Φ was integrated.
    pub between: Between,
}

/// A, B, C, D at every sample of `motion`, checked first.
pub fn samples(along: &mut Along, motion: &Motion) -> Result<Vec<Linear>, Error> {
    check_motion(along, motion)?;
    let mut samples = Vec::with_capacity(motion.times.len());
    for (k, t) in motion.times.iter().enumerate() {
        samples.push(along.at(*t, &motion.states[k], &motion.inputs[k])?);
    }
    Ok(samples)
}

/// The linearization along a motion known only at its samples (a file's): A, B, C, D at
/// each, and Φ over it with A(t) linear between them ([`Between::Interpolated`]).
pub fn linearize_along(along: &mut Along, motion: &Motion) -> Result<Linearized, Error> {
    let samples = samples(along, motion)?;
    let transition = state_transition(&motion.times, &samples)?;
    Ok(gathered(along, motion, samples, transition, Between::Interpolated))
}

/// The linearization along a run of the scene whose Φ was integrated beside it
/// ([`Between::Model`]): A, B, C, D at each of the run's samples `motion`, and `transition`.
pub fn linearize_run(
    along: &mut Along,
    motion: &Motion,
    transition: DMatrix<f64>,
) -> Result<Linearized, Error> {
    let size = 2 * along.coordinates.len();
    if transition.shape() != (size, size) {
        return Err(Error::Numeric(format!(
            "the state-transition matrix is {}×{}, not {size}×{size}",
            transition.nrows(),
            transition.ncols()
        )));
    }
    let samples = samples(along, motion)?;
    Ok(gathered(along, motion, samples, transition, Between::Model))
}

fn gathered(
    along: &Along,
    motion: &Motion,
    samples: Vec<Linear>,
    transition: DMatrix<f64>,
    between: Between,
) -> Linearized {
    Linearized {
        state: along.state_names(),
        inputs: along.inputs.clone(),
        outputs: along.outputs.clone(),
        times: motion.times.clone(),
        samples,
        transition,
        between,
    }
}

#[cfg(test)]
// The expected gradient is a closed form in the test, far from a last bit.
#[allow(clippy::disallowed_methods)]
mod tests {
    use super::*;

    const CART_POLE: &str = "
param M = 1, m = 1/4, L = 1, g = 9.81
input F = 0
coord x, theta
particle cart { mass M; position (x, 0) }
body pole { mass m; inertia m*L^2/12; position (x + L/2*sin(theta), L/2*cos(theta)); angle -theta }
gravity g
force push on cart: (F, 0)
output tip: x + L*sin(theta)
output speed: x'
linearize about theta = 0
";

    fn loaded(source: &str) -> Along {
        along(source, &Options::default()).expect("loads")
    }

    fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
        (0..m.nrows()).map(|i| m.row(i).iter().copied().collect()).collect()
    }

    #[test]
    fn at_an_equilibrium_it_is_the_linearization_about_it() {
        let about = crate::linearize::linearize(CART_POLE, &Default::default()).expect("about");
        let space = &about.at.first_order;
        let mut along = loaded(CART_POLE);
        let at = along.at(0.0, &[0.0; 4], &[0.0]).expect("at rest");
        // The same numbers, not merely close: the run's Jacobian and `linear`'s formula solve
        // the same partials with the same M.
        assert_eq!(rows(&at.a), space.a);
        assert_eq!(rows(&at.b), space.b);
        assert_eq!(rows(&at.c), space.c);
        assert_eq!(rows(&at.d), space.d);
    }

    #[test]
    fn a_moving_state_agrees_with_central_differences_of_the_right_hand_side() {
        let mut along = loaded(CART_POLE);
        let (t, x, u) = (0.3, [0.4, 2.1, -0.7, 1.9], [0.8]);
        let at = along.at(t, &x, &u).expect("moving");
        let h = 1e-5;
        for j in 0..4 {
            let (mut plus, mut minus) = (x, x);
            plus[j] += h;
            minus[j] -= h;
            let up = along.rate(t, &plus, &u).expect("rate");
            let down = along.rate(t, &minus, &u).expect("rate");
            for i in 0..4 {
                let difference = (up[i] - down[i]) / (2.0 * h);
                let scale = at.a[(i, j)].abs().max(1.0);
                assert!((difference - at.a[(i, j)]).abs() < 1e-7 * scale, "A[{i},{j}]");
            }
        }
        let up = along.rate(t, &x, &[u[0] + h]).expect("rate");
        let down = along.rate(t, &x, &[u[0] - h]).expect("rate");
        for i in 0..4 {
            let difference = (up[i] - down[i]) / (2.0 * h);
            assert!((difference - at.b[(i, 0)]).abs() < 1e-7, "B[{i}]");
        }
        // The tip at x + L·sin θ: C = [1, L·cos θ, 0, 0]; the speed reads x'.
        let expected = [1.0, 2.1f64.cos(), 0.0, 0.0];
        for (j, e) in expected.iter().enumerate() {
            assert!((at.c[(0, j)] - e).abs() < 1e-15, "C[0,{j}]");
        }
        assert_eq!(rows(&at.c)[1], [0.0, 0.0, 1.0, 0.0]);
    }

    #[test]
    fn bad_motions_are_refused() {
        let mut along = loaded(CART_POLE);
        let motion = |times: Vec<f64>| Motion {
            states: vec![vec![0.0; 4]; times.len()],
            inputs: vec![vec![0.0]; times.len()],
            times,
        };
        let e = linearize_along(&mut along, &motion(vec![0.0, 0.2, 0.1]))
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("sample 3 (t = 0.1) does not come after sample 2 (t = 0.2)"), "{e}");
        let e = linearize_along(&mut along, &motion(vec![0.0])).err().expect("refused").to_string();
        assert!(e.contains("at least two samples"), "{e}");
        let set =
            Options { set: vec!["theta=1".parse().expect("an assignment")], ..Default::default() };
        let e = super::along(CART_POLE, &set).err().expect("refused").to_string();
        assert!(e.contains("a trajectory gives the state"), "{e}");
    }
}
