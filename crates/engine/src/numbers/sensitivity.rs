//! The expressions of the parameter sensitivity program, from which a run integrates
//! S = ∂x(t)/∂p beside its state: the partials of the equations in residual form by the free
//! parameters a user sets, through the derived parameters that follow them by the chain rule,
//! and the derivative of the start the scene writes.
//!
//! A derived parameter (`param I = m*L^2/3`) and an input's declared value (`input F = L/4`)
//! are slots of their own in numbers, filled from the free parameters in declaration order
//! (`model::ParameterValues`). Their derivatives by a free parameter are taken symbolically
//! from the expressions the scene gives them, d slot/d p = Σ ∂value/∂s · d s/d p over the
//! earlier slots s, and lowered in the same program as the partials, so that a sensitivity by
//! `L` carries `I`'s share exactly.

use cas::{ExprId, SymId};
use numeric::Program;

use super::Prepared;
use crate::Error;

impl Prepared {
    /// Refuses a parameter index that is not one of the scene's free parameters: a derived
    /// parameter follows others and is not set, so no sensitivity is taken by it.
    fn check_free(&self, free: &[usize]) -> Result<(), Error> {
        let plan = &self.parameter_plan;
        for &i in free {
            if i >= plan.len() {
                return Err(Error::Input(format!(
                    "no parameter number {i} in the scene, which has {}",
                    plan.len()
                )));
            }
            if plan.is_derived(i) {
                return Err(Error::Input(format!(
                    "no sensitivity is taken by a derived parameter: {}",
                    plan.derived_error(i)
                )));
            }
        }
        Ok(())
    }

    /// d slot/d p for each parameter slot ([`Prepared::parameters`], the inputs' after the
    /// parameters') and each free parameter of `free`, as expressions of the parameters: 1 or 0
    /// for a free parameter, the chain rule through the scene's expression for a derived one,
    /// an input's declared value or a value a run sets in the scene's place
    /// ([`Prepared::set_parameter_overrides`]), 0 for an input a law drives (its symbol is gone
    /// from the equations).
    fn slot_derivatives(&mut self, free: &[usize]) -> Vec<Vec<ExprId>> {
        let model = &mut self.derivation.model;
        let mut values: Vec<Option<ExprId>> = model.constants().iter().map(|(_, v)| *v).collect();
        // A value a run gives in the scene's place follows its expression, unless the slot is
        // free: then the value is only where it starts.
        let mut overridden = vec![false; values.len()];
        for (slot, e) in self.parameter_overrides.iter().filter(|(slot, _)| !free.contains(slot)) {
            values[*slot] = Some(*e);
            overridden[*slot] = true;
        }
        let params = model.params.len();
        let mut out: Vec<Vec<ExprId>> = Vec::with_capacity(self.parameters.len());
        for (slot, &s) in self.parameters.iter().enumerate() {
            let pool = &mut model.pool;
            let set = slot < params && !self.parameter_plan.is_derived(slot) && !overridden[slot];
            let row: Vec<ExprId> = if set {
                free.iter().map(|&i| if i == slot { pool.one() } else { pool.zero() }).collect()
            } else if self.driven.contains_key(&s) {
                vec![pool.zero(); free.len()]
            } else {
                let value = values[slot].unwrap_or_else(|| pool.zero());
                // A value names parameters declared before it: their rows are made.
                let by: Vec<ExprId> = self.parameters[..slot.min(params)]
                    .iter()
                    .map(|&earlier| pool.diff(value, earlier))
                    .collect();
                (0..free.len())
                    .map(|j| products(pool, by.iter().zip(&out).map(|(d, row)| (*d, row[j]))))
                    .collect()
            };
            out.push(row);
        }
        out
    }

    /// Σ over the slots of ∂e/∂slot · d slot/d p, for each free parameter: the total
    /// derivative of each of `partials` (one row of partials by every slot) by the free ones.
    fn through_slots(&mut self, partials: &[Vec<ExprId>], slots: &[Vec<ExprId>]) -> Vec<ExprId> {
        let pool = &mut self.derivation.model.pool;
        let columns = slots.first().map_or(0, Vec::len);
        let mut out = Vec::with_capacity(partials.len() * columns);
        for row in partials {
            for j in 0..columns {
                out.push(products(pool, row.iter().zip(slots).map(|(d, by)| (*d, by[j]))));
            }
        }
        out
    }

    /// d(r, c, Φ, Φ̇)/dp with q, q̇, q̈ and λ held, for the free parameters `free` (indices
    /// in declaration order, as [`model::ParameterValues::free`] gives them), row-major with
    /// the rows of [`sim::Layout`]'s partials program and a column per free parameter, for the
    /// observation inputs `[t, q, q̇, q̈, λ, parameters]`: the sensitivity program of
    /// [`sim::Mechanical::set_sensitivities`]. An input's slot counts as following its
    /// declared value: a run that fills it from a series or a held law instead must not
    /// count on its share.
    pub fn sensitivity_exprs(&mut self, free: &[usize]) -> Result<Vec<ExprId>, Error> {
        self.check_free(free)?;
        let slots = self.slot_derivatives(free);
        let constants = self.parameters.clone();
        let p = self.derivation.parameter_partials(&constants);
        let mut v = Vec::with_capacity((p.residual.len() + 3 * p.phi.len()) * free.len());
        for rows in [&p.residual, &p.constraint, &p.phi, &p.drift_rate] {
            v.extend(self.through_slots(rows, &slots));
        }
        Ok(v)
    }

    /// [`Prepared::sensitivity_exprs`] lowered for the observation inputs.
    pub fn sensitivity_program(&mut self, free: &[usize]) -> Result<Program, Error> {
        let exprs = self.sensitivity_exprs(free)?;
        self.lower(&self.observation_inputs(), &exprs)
    }

    /// ∂x(0)/∂p, row-major 2n × k for the free parameters `free`, at the parameters' values
    /// `parameters` (in slot order): the derivative of the start as the scene writes it (each
    /// coordinate's value and rate, expressions of the parameters), with `overrides` in place
    /// of the scene's values as [`Prepared::initial_state`] takes them, the chain rule through
    /// derived parameters included. A start the scene leaves to its kept constraints (a
    /// position or rate solved at the start, which moves with the parameters through the
    /// solve) is refused by name: the caller gives S(0) itself there.
    pub fn start_sensitivity(
        &mut self,
        parameters: &[f64],
        overrides: &[(usize, bool, ExprId)],
        free: &[usize],
    ) -> Result<Vec<f64>, Error> {
        self.check_free(free)?;
        let solved = self.start_left_to_constraints(overrides);
        if let Some(name) = solved.first() {
            return Err(Error::Input(format!(
                "the start of `{name}` is left to the kept constraints, solved at the start, \
                 and its derivative by the parameters is not the scene's expression's: give \
                 the start's sensitivities yourself"
            )));
        }
        let slots = self.slot_derivatives(free);
        let n = self.layout.coordinates;
        let model = &self.derivation.model;
        let mut starts = vec![model.pool.zero(); 2 * n];
        for (k, q) in self.derivation.coords.iter().enumerate() {
            let Some(i) = model.coords.iter().position(|c| c.sym == *q) else { continue };
            let find = |rate: bool| {
                overrides.iter().rev().find(|(j, r, _)| *j == i && *r == rate).map(|x| x.2)
            };
            starts[k] = find(false).unwrap_or(model.coords[i].initial);
            starts[n + k] = find(true).unwrap_or(model.coords[i].initial_rate);
        }
        let constants = self.parameters.clone();
        let partials: Vec<Vec<ExprId>> = starts
            .iter()
            .map(|e| constants.iter().map(|s| self.derivation.model.pool.diff(*e, *s)).collect())
            .collect();
        let exprs = self.through_slots(&partials, &slots);
        let out: Vec<f64> = exprs.iter().map(|e| self.constant(*e, parameters)).collect();
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Error::Numeric(
                "the start's derivative by the parameters is not a finite number at these values"
                    .into(),
            ));
        }
        Ok(out)
    }

    /// d e/dp of a constant expression `e` of the parameters (a period, a shift), for the
    /// free parameters `free`, at the parameters' values `parameters` (in slot order), the
    /// chain rule through derived parameters included.
    pub fn constant_sensitivity(
        &mut self,
        e: ExprId,
        parameters: &[f64],
        free: &[usize],
    ) -> Result<Vec<f64>, Error> {
        self.check_free(free)?;
        let slots = self.slot_derivatives(free);
        let constants = self.parameters.clone();
        let partials: Vec<ExprId> =
            constants.iter().map(|s| self.derivation.model.pool.diff(e, *s)).collect();
        let exprs = self.through_slots(&[partials], &slots);
        Ok(exprs.iter().map(|e| self.constant(*e, parameters)).collect())
    }

    /// The remaining coordinates whose start position or rate the kept constraints solve for
    /// at the start, by name: those the scene leaves to them and `overrides` do not give.
    fn start_left_to_constraints(&mut self, overrides: &[(usize, bool, ExprId)]) -> Vec<String> {
        let coords = &self.derivation.model.coords;
        let overridden: Vec<(SymId, bool)> =
            overrides.iter().filter_map(|(j, r, _)| coords.get(*j).map(|c| (c.sym, *r))).collect();
        let given = |sym: SymId, rate: bool| overridden.contains(&(sym, rate));
        let mut positions: Vec<SymId> = self.derivation.free_start_positions();
        positions.retain(|q| !given(*q, false));
        let d = &mut self.derivation;
        let velocity_rows: Vec<ExprId> = d
            .multipliers
            .iter()
            .filter(|m| !d.model.constraints[m.constraint].kind.is_unilateral())
            .map(|m| m.rows.velocity)
            .collect();
        let mut unset = Vec::new();
        for k in 0..d.coords.len() {
            let written = d.model.coords.iter().find(|c| c.sym == d.coords[k]);
            if written.is_none_or(|c| c.initial_rate_given) || given(d.coords[k], true) {
                continue;
            }
            let rate = d.rates[k];
            if velocity_rows.iter().any(|r| d.model.pool.depends_on(*r, rate)) {
                unset.push(k);
            }
        }
        let d = &self.derivation;
        // The rates are solved only where the rows fix them ([`Prepared::settle_rates`]):
        // otherwise they must hold as written.
        let rates_solved = !unset.is_empty() && unset.len() == velocity_rows.len();
        let name = |q: &SymId| d.model.coords.iter().find(|c| c.sym == *q).map(|c| c.name.clone());
        let mut out: Vec<String> = positions.iter().filter_map(name).collect();
        if rates_solved {
            out.extend(unset.iter().filter_map(|&k| name(&d.coords[k])).map(|n| n + "'"));
        }
        out
    }
}

/// Σ a·b over the pairs, leaving out those with a zero factor: most parameters appear in few
/// rows, and the program need not multiply by zero.
fn products(pool: &mut cas::Pool, pairs: impl Iterator<Item = (ExprId, ExprId)>) -> ExprId {
    let mut terms = Vec::new();
    for (a, b) in pairs {
        if !pool.is_zero(a) && !pool.is_zero(b) {
            terms.push(pool.mul2(a, b));
        }
    }
    pool.add(&terms)
}

impl Prepared {
    /// For each of `exprs` (expressions of the observation inputs), its value, its partials
    /// in q, q̇, q̈ and λ (2n, then n, then m), and its total derivative by each
    /// free parameter of `free` through the derived slots (k): row after row of
    /// 1 + 3n + m + k, lowered for the observation inputs. What a fit needs of a measured
    /// column to chain the run's Φ and S into the column's own derivative,
    /// dy/dθ = ∂y/∂x·dx/dθ + ∂y/∂(q̈, λ)·d(q̈, λ)/dθ + ∂y/∂p·dp/dθ.
    pub fn observation_partials(
        &mut self,
        exprs: &[ExprId],
        free: &[usize],
    ) -> Result<Program, Error> {
        self.check_free(free)?;
        let slots = self.slot_derivatives(free);
        let constants = self.parameters.clone();
        let d = &self.derivation;
        let multipliers = d.multipliers.iter().map(|m| m.lambda);
        let state: Vec<SymId> =
            d.coords.iter().chain(&d.rates).chain(&d.accels).copied().chain(multipliers).collect();
        let mut out = Vec::with_capacity(exprs.len() * (1 + state.len() + free.len()));
        for &e in exprs {
            out.push(e);
            let pool = &mut self.derivation.model.pool;
            out.extend(state.iter().map(|s| pool.diff(e, *s)));
            let by_slot: Vec<ExprId> = constants.iter().map(|s| pool.diff(e, *s)).collect();
            out.extend(self.through_slots(&[by_slot], &slots));
        }
        self.lower(&self.observation_inputs(), &out)
    }

    /// Whether `e` names an acceleration or a constraint's multiplier (a reaction), which a
    /// run's state alone does not give.
    pub fn names_unknowns(&mut self, e: ExprId) -> bool {
        let d = &self.derivation;
        let unknowns: Vec<SymId> =
            d.accels.iter().copied().chain(d.multipliers.iter().map(|m| m.lambda)).collect();
        let pool = &mut self.derivation.model.pool;
        unknowns.iter().any(|s| pool.depends_on(e, *s))
    }
}

impl Prepared {
    /// The values a run gives parameters in the scene's place (`--set b=2*a`, by slot): the
    /// sensitivities by a free parameter follow them through the chain rule, as they follow a
    /// derived parameter's expression. Without this, `b` would count as a parameter of its
    /// own, and its share in a sensitivity by `a` would be left out.
    pub fn set_parameter_overrides(&mut self, overrides: &[(usize, ExprId)]) {
        self.parameter_overrides = overrides.to_vec();
    }
}
