//! Inverse dynamics: the generalized forces τ = M(q, t)·q̈ − f(q, q̇, t) that make the scene
//! move with given positions, rates and accelerations, from the same lowered M and f that
//! `simulate` integrates. Applied as extra generalized forces (M·q̈ = f + τ), they reproduce
//! the motion: computed-torque control and actuator sizing.
//!
//! With constraints kept with multipliers, M·q̈ = f + Jᵀλ + τ, and any τ + Jᵀμ gives the same
//! motion: τ is fixed only up to what the constraints can carry. The τ given here is the least
//! in the norm τᵀ·M⁻¹·τ, the one with J·M⁻¹·τ = 0 (where M is singular, the same choice made
//! through the augmented system a run solves): the constraints carry the load they would
//! carry without it, so a motion the scene makes on its own needs τ = 0 (a pendulum written
//! with a kept rod needs no force to hang), and the choice does not depend on the units of the
//! coordinates, as a plain least norm would. It presumes accelerations the constraints allow
//! (J·q̈ = γ), which a trajectory of a run of the scene has.

use numeric::Tape;

use crate::input::Assignment;
use crate::{Error, Setting};

/// What a front end asks for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Parameter values (scene expressions) in place of the scene's.
    pub set: Vec<Assignment>,
    /// Skip the dimension check.
    pub no_units: bool,
}

/// The inverse dynamics of a loaded scene, at its parameters' values unless told others.
pub struct InverseDynamics {
    coordinates: Vec<String>,
    /// The one way to the parameters' values: the free ones set, the derived ones following.
    plan: model::ParameterValues,
    /// The free parameters' names, in declaration order: the ones a caller sets.
    parameter_names: Vec<String>,
    /// The derived parameters' names, in declaration order.
    derived_names: Vec<String>,
    input_names: Vec<String>,
    /// The program's parameter slots: every parameter, then the inputs.
    slots: Vec<f64>,
    /// Names of the constraints kept with multipliers: τ is the least in τᵀ·M⁻¹·τ.
    kept: Vec<String>,
    /// `[t, q, q̇, parameters]` → M (column-major), f, then per kept constraint J, γ, Φ, Φ̇.
    tape: Tape,
    input: Vec<f64>,
    output: Vec<f64>,
}

/// That `values` has one value for each of `names` (`what`s), or the error saying how many.
fn one_each(values: &[f64], names: &[String], what: &str) -> Result<(), Error> {
    if values.len() == names.len() {
        return Ok(());
    }
    Err(Error::Input(format!(
        "{} {what} values given for the {} {what}s ({})",
        values.len(),
        names.len(),
        names.join(", ")
    )))
}

/// Loads `source` and lowers what its inverse dynamics needs, at the parameters' values with
/// the `set` ones in place of the scene's.
pub fn inverse_dynamics(source: &str, options: &Options) -> Result<InverseDynamics, Error> {
    let values: Vec<(Option<&str>, String)> =
        options.set.iter().map(|a| (Some(a.name.as_str()), a.value.clone())).collect();
    let (model, warnings) =
        crate::resolve_with(source, crate::Options { units: !options.no_units })?;
    let mut prepared = crate::numbers::prepare_resolved_for(source, model, warnings, &values)?;
    prepared.refuse_contacts("inverse dynamics")?;
    let params = &prepared.derivation.model.params;
    let mut overrides = Vec::new();
    for (Assignment { name, .. }, expr) in options.set.iter().zip(&prepared.extra) {
        let Some(k) = params.iter().position(|p| p.name == *name) else {
            let known: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
            let rest = format!(": no parameter of that name; one of {}", known.join(", "));
            return Err(Error::given(Setting::Set, name, rest));
        };
        overrides.push((k, *expr));
    }
    let parameters = prepared.parameter_values(&overrides)?;
    let dynamics = prepared.dynamics_exprs();
    let inputs = prepared.dynamics_inputs();
    let program = prepared.lower(&inputs, &dynamics)?;
    let d = &prepared.derivation;
    let kept = d.multipliers.iter().map(|m| d.model.constraints[m.constraint].name.clone());
    let plan = prepared.parameter_plan.clone();
    let name = |i: usize| d.model.params[i].name.clone();
    Ok(InverseDynamics {
        coordinates: prepared.coordinate_names(),
        parameter_names: plan.free().into_iter().map(name).collect(),
        derived_names: plan.derived().into_iter().map(name).collect(),
        input_names: d.model.inputs.iter().map(|u| u.name.clone()).collect(),
        plan,
        slots: parameters,
        kept: kept.collect(),
        tape: Tape::new(program),
        input: vec![0.0; inputs.len()],
        output: vec![0.0; dynamics.len()],
    })
}

impl InverseDynamics {
    /// The remaining coordinates, in the order of q and of τ.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The free parameters' names, in declaration order: the ones [`Self::set_parameters`]
    /// takes. The derived ones follow them, and the inputs are set apart.
    pub fn parameter_names(&self) -> &[String] {
        &self.parameter_names
    }

    /// The derived parameters' names, in declaration order: each follows the free ones its
    /// value names.
    pub fn derived_parameter_names(&self) -> &[String] {
        &self.derived_names
    }

    /// The scene's one way to its parameters' values, which this one follows.
    pub fn parameter_plan(&self) -> &model::ParameterValues {
        &self.plan
    }

    /// The inputs' names, in declaration order.
    pub fn input_names(&self) -> &[String] {
        &self.input_names
    }

    /// The free parameters' values in use, in the order of [`Self::parameter_names`].
    pub fn parameters(&self) -> Vec<f64> {
        self.plan.free().into_iter().map(|i| self.slots[i]).collect()
    }

    /// The derived parameters' values in use, in the order of
    /// [`Self::derived_parameter_names`].
    pub fn derived_parameters(&self) -> Vec<f64> {
        self.plan.derived().into_iter().map(|i| self.slots[i]).collect()
    }

    /// Every parameter's value in use in declaration order, then the inputs': the slots the
    /// lowered programs read.
    pub fn slots(&self) -> &[f64] {
        &self.slots
    }

    /// Uses these values of the free parameters (in the order of [`Self::parameter_names`])
    /// from now on; the derived ones follow them.
    pub fn set_parameters(&mut self, values: &[f64]) -> Result<(), Error> {
        one_each(values, &self.parameter_names, "parameter")?;
        let all = self.plan.values_of_free(values).map_err(|e| Error::Input(e.to_string()))?;
        let k = self.plan.len();
        self.slots[..k].copy_from_slice(&all[..k]);
        Ok(())
    }

    /// Holds the inputs at these values (in the order of [`Self::input_names`]) from now on.
    pub fn set_inputs(&mut self, values: &[f64]) -> Result<(), Error> {
        one_each(values, &self.input_names, "input")?;
        let k = self.plan.len();
        self.slots[k..].copy_from_slice(values);
        Ok(())
    }

    /// The constraints kept with multipliers; with any, τ is the least in τᵀ·M⁻¹·τ.
    pub fn kept_constraints(&self) -> &[String] {
        &self.kept
    }

    /// τ = M·q̈ − f at time `t` with positions `q`, rates `rates` and accelerations
    /// `accelerations` (each one value per coordinate), written into `tau`.
    pub fn torques(
        &mut self,
        t: f64,
        q: &[f64],
        rates: &[f64],
        accelerations: &[f64],
        tau: &mut [f64],
    ) -> Result<(), Error> {
        let n = self.coordinates.len();
        for (what, values) in
            [("positions", q), ("rates", rates), ("accelerations", accelerations), ("τ", tau)]
        {
            if values.len() != n {
                return Err(Error::Input(format!(
                    "{} {what} for the {n} coordinates ({})",
                    values.len(),
                    self.coordinates.join(", ")
                )));
            }
        }
        self.input[0] = t;
        self.input[1..1 + n].copy_from_slice(q);
        self.input[1 + n..1 + 2 * n].copy_from_slice(rates);
        self.input[1 + 2 * n..].copy_from_slice(&self.slots);
        self.tape.eval(&self.input, &mut self.output);
        let (mass, forcing) = self.output.split_at(n * n);
        for (i, out) in tau.iter_mut().enumerate() {
            let inertial: f64 = (0..n).map(|j| mass[j * n + i] * accelerations[j]).sum();
            *out = inertial - forcing[i];
        }
        if !self.kept.is_empty() {
            self.take_out_what_the_constraints_carry(t, tau)?;
        }
        if let Some(i) = tau.iter().position(|v| !v.is_finite()) {
            return Err(Error::Numeric(format!(
                "at t = {t}, the generalized force on `{}` is {} (M or f is not finite there)",
                self.coordinates[i], tau[i]
            )));
        }
        Ok(())
    }
}

impl InverseDynamics {
    /// τ + Jᵀ·μ where [M −Jᵀ; J 0]·(x, μ) = (τ, 0), the system a run solves: with M regular,
    /// μ = −(J·M⁻¹·Jᵀ)⁻¹·J·M⁻¹·τ, which leaves J·M⁻¹·τ = 0. It needs only the augmented system
    /// regular, not M (Euler parameters make M singular along e, their constraint not). M and J
    /// are those of the last evaluation.
    fn take_out_what_the_constraints_carry(&self, t: f64, tau: &mut [f64]) -> Result<(), Error> {
        let n = tau.len();
        let m = self.kept.len();
        let jacobian = |c: usize, j: usize| self.output[n * n + n + c * (n + 3) + j];
        let system = nalgebra::DMatrix::from_fn(n + m, n + m, |i, j| match (i < n, j < n) {
            (true, true) => self.output[j * n + i],
            (true, false) => -jacobian(j - n, i),
            (false, true) => jacobian(i - n, j),
            (false, false) => 0.0,
        });
        let mut rhs = nalgebra::DVector::zeros(n + m);
        rhs.as_mut_slice()[..n].copy_from_slice(tau);
        let solution = system.lu().solve(&rhs).ok_or_else(|| {
            Error::Numeric(format!(
                "at t = {t}, the mass matrix with the kept constraints ({}) is singular, so the \
                 generalized forces are not determined",
                self.kept.join(", ")
            ))
        })?;
        for (j, out) in tau.iter_mut().enumerate() {
            *out += (0..m).map(|c| jacobian(c, j) * solution[n + c]).sum::<f64>();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assignments(texts: &[&str]) -> Vec<Assignment> {
        crate::input::assignments(texts).unwrap()
    }

    const FLYWHEEL: &str = "param I = 1/2, tau = 2, b = 1/10\ncoord theta\n\
        body wheel { mass 1; inertia I; position (0, 0); angle theta }\n\
        torque motor on wheel: tau\ndissipation b/2*theta'^2\n";

    #[test]
    fn a_flywheel_needs_its_inertia_times_the_acceleration_less_the_forces() {
        let mut inverse = inverse_dynamics(FLYWHEEL, &Options::default()).unwrap();
        let mut tau = [0.0];
        inverse.torques(0.0, &[1.0], &[3.0], &[5.0], &mut tau).unwrap();
        // I·θ̈ − (τ − b·θ̇) = 2.5 − 2 + 0.3.
        assert!((tau[0] - 0.8).abs() < 1e-15, "{tau:?}");
        inverse.set_parameters(&[1.0, 0.0, 0.0]).unwrap();
        inverse.torques(0.0, &[1.0], &[3.0], &[5.0], &mut tau).unwrap();
        assert_eq!(tau[0], 5.0);
        let set = Options { set: assignments(&["tau = 0", "b=I"]), no_units: false };
        let mut inverse = inverse_dynamics(FLYWHEEL, &set).unwrap();
        inverse.torques(0.0, &[1.0], &[3.0], &[5.0], &mut tau).unwrap();
        // I·θ̈ + b·θ̇ with b = I: 2.5 + 1.5.
        assert!((tau[0] - 4.0).abs() < 1e-15, "{tau:?}");
    }

    #[test]
    fn wrong_lengths_and_names_are_errors() {
        let set = Options { set: assignments(&["J=1"]), no_units: false };
        let e = inverse_dynamics(FLYWHEEL, &set).err().unwrap();
        assert_eq!(e.to_string(), "error: `set` J: no parameter of that name; one of I, tau, b");
        let mut inverse = inverse_dynamics(FLYWHEEL, &Options::default()).unwrap();
        let mut tau = [0.0];
        let e = inverse.torques(0.0, &[1.0, 2.0], &[3.0], &[5.0], &mut tau).unwrap_err();
        assert_eq!(e.to_string(), "error: 2 positions for the 1 coordinates (theta)");
        let e = inverse.set_parameters(&[1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "error: 1 parameter values given for the 3 parameters (I, tau, b)"
        );
    }
}
