//! The instant t = 0 in floating point, for starts whose unknowns are too many for the exact
//! solve: the parameters' values, the initial state, and the unknowns with how many digits
//! the solve leaves.

use cas::SymId;
use mechanics::Derivation;
use numeric::Evaluator;

use crate::system::System;

/// The start solved in floating point at given parameter values.
#[derive(Clone, Debug)]
pub struct NumericStart {
    /// A value per symbol: parameters, t = 0, coordinates, rates, accelerations, multipliers.
    pub values: Vec<f64>,
    /// Significant digits the solve leaves: 15 less the decimal exponent of the condition
    /// number of the system.
    pub digits: u32,
}

/// The scene's parameter values (then its inputs' when undriven), as numbers (NaN where one is
/// not a finite number); `Err` names the parameters without one.
pub fn parameter_values(d: &Derivation) -> Result<Vec<(SymId, f64)>, Vec<String>> {
    let model = &d.model;
    let missing: Vec<String> =
        model.params.iter().filter(|p| p.value.is_none()).map(|p| p.name.clone()).collect();
    if !missing.is_empty() {
        return Err(missing);
    }
    let values = model::ParameterValues::new(model).scene_values();
    let symbols = model.params.iter().map(|p| p.sym).chain(model.inputs.iter().map(|u| u.sym));
    Ok(symbols.zip(values).map(|(s, v)| (s, v.unwrap_or(f64::NAN))).collect())
}

/// The start in floating point at the given parameter values: the initial state, then the
/// unknowns from the full system. `None` where the system is singular or undefined.
pub fn start_numeric(d: &mut Derivation, params: &[(SymId, f64)]) -> Option<NumericStart> {
    StartSolver::new(d).solve(d, params)
}

/// The start's expressions lowered once, for solving it at many parameter values.
pub(crate) struct StartSolver {
    system: System,
    /// Per remaining coordinate: its symbol and initial value, its rate and initial rate.
    initial: Vec<(SymId, Evaluator, SymId, Evaluator)>,
}

impl StartSolver {
    pub(crate) fn new(d: &mut Derivation) -> StartSolver {
        let system = System::new(d);
        let pool = &d.model.pool;
        let mut initial = Vec::new();
        for c in &d.model.coords {
            let Some(k) = d.coords.iter().position(|q| *q == c.sym) else { continue };
            initial.push((
                c.sym,
                Evaluator::new(pool, &[c.initial]),
                d.rates[k],
                Evaluator::new(pool, &[c.initial_rate]),
            ));
        }
        StartSolver { system, initial }
    }

    pub(crate) fn solve(
        &mut self,
        d: &Derivation,
        params: &[(SymId, f64)],
    ) -> Option<NumericStart> {
        let mut values = vec![f64::NAN; d.model.pool.symbol_count()];
        for (s, v) in params {
            values[s.index()] = *v;
        }
        values[d.model.time.index()] = 0.0;
        // One after the other: a rate's initial value may read its coordinate's.
        for (q, value, rate, rate_value) in &mut self.initial {
            values[q.index()] = value.eval(&values)[0];
            values[rate.index()] = rate_value.eval(&values)[0];
        }
        if self.system.unknowns().is_empty() {
            return Some(NumericStart { values, digits: 15 });
        }
        let (a, b) = self.system.at(&values)?;
        let svd = a.clone().svd(false, false);
        let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
        if smallest <= largest * 1e-15 || smallest == 0.0 {
            return None;
        }
        // The singular values tell the digits; Gaussian elimination with full pivoting keeps
        // more of them than the SVD's own solve (a few ulps against 1e-12 in Andrews'
        // mechanism).
        let x = a.full_piv_lu().solve(&b)?;
        for (u, v) in self.system.unknowns().iter().zip(x.iter()) {
            values[u.index()] = *v;
        }
        let lost = numeric::elementary::log10(largest / smallest).max(0.0);
        let digits = (15.0 - lost).floor().clamp(0.0, 15.0) as u32;
        Some(NumericStart { values, digits })
    }
}
