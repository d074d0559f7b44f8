//! The instant t = 0: accelerations and multipliers exactly where the algebra stays small,
//! numerically otherwise, saying so and with how many digits the solve leaves.

use std::collections::HashMap;

use cas::linear_system::{self, Solution};
use cas::{ExprId, SymId};
use nalgebra::{DMatrix, DVector};

use crate::derive::Derivation;

/// New expression nodes the exact solve at the start may build before it gives up. A dense
/// system of a dozen unknowns needs millions and minutes; the 4-link pendulum at distinct
/// angles needs about 1,800, and problem set 5 a few dozen.
const START_BUDGET: usize = 25_000;

/// The unknowns of the start, solved exactly if the algebra allows.
#[derive(Clone, Debug)]
pub enum StartSolution {
    /// Accelerations and multipliers (and the initial state) as expressions of the parameters.
    Exact(HashMap<SymId, ExprId>),
    /// The mass matrix (with the constraints' rows) is singular at the start.
    Singular,
    /// The exact solution outgrew its budget; the unknowns are found numerically instead.
    TooLarge { unknowns: usize },
}

/// The start solved in floating point at given parameter values.
#[derive(Clone, Debug)]
pub struct NumericStart {
    /// A value per symbol: parameters, t = 0, coordinates, rates, accelerations, multipliers.
    pub values: Vec<f64>,
    /// Significant digits the solve leaves: 15 less the decimal exponent of the condition
    /// number of the system.
    pub digits: u32,
}

impl Derivation {
    /// Accelerations and multipliers at the initial state, exactly when the algebra stays
    /// within its budget. Computed once.
    pub fn unknowns_at_start(&mut self) -> StartSolution {
        if let Some(s) = &self.start {
            return s.clone();
        }
        let state = self.initial_state();
        let (rows, rhs) = self.system();
        let unknowns = self.unknowns();
        let pool = &mut self.model.pool;
        let mut memo = HashMap::new();
        let a: Vec<Vec<ExprId>> = rows
            .iter()
            .map(|r| r.iter().map(|e| pool.subst_memo(*e, &state, &mut memo)).collect())
            .collect();
        let b: Vec<ExprId> = rhs.iter().map(|e| pool.subst_memo(*e, &state, &mut memo)).collect();
        let solution = match linear_system::solve_within(pool, &a, &b, START_BUDGET) {
            Solution::Solved(x) => {
                let mut out: HashMap<SymId, ExprId> = unknowns.into_iter().zip(x).collect();
                out.extend(state);
                StartSolution::Exact(out)
            }
            Solution::Singular => StartSolution::Singular,
            Solution::TooLarge => StartSolution::TooLarge { unknowns: unknowns.len() },
        };
        self.start = Some(solution.clone());
        solution
    }

    /// The scene's parameter values, as numbers; `Err` names the parameters without one.
    pub fn parameter_values(&self) -> Result<Vec<(SymId, f64)>, Vec<String>> {
        let pool = &self.model.pool;
        let mut values = vec![f64::NAN; pool.symbol_count()];
        let mut out = Vec::new();
        let mut missing = Vec::new();
        for p in &self.model.params {
            match p.value {
                Some(v) => {
                    let x = pool.eval(v, &values);
                    values[p.sym.index()] = x;
                    out.push((p.sym, x));
                }
                None => missing.push(p.name.clone()),
            }
        }
        if missing.is_empty() {
            Ok(out)
        } else {
            Err(missing)
        }
    }

    /// The start in floating point at the given parameter values: the initial state, then the
    /// unknowns from the full system. `None` where the system is singular or undefined.
    pub fn start_numeric(&mut self, params: &[(SymId, f64)]) -> Option<NumericStart> {
        let (rows, rhs) = self.system();
        let unknowns = self.unknowns();
        let pool = &self.model.pool;
        let mut values = vec![f64::NAN; pool.symbol_count()];
        for (s, v) in params {
            values[s.index()] = *v;
        }
        values[self.model.time.index()] = 0.0;
        for c in &self.model.coords {
            let Some(k) = self.coords.iter().position(|q| *q == c.sym) else { continue };
            values[c.sym.index()] = pool.eval(c.initial, &values);
            values[self.rates[k].index()] = pool.eval(c.initial_rate, &values);
        }
        if unknowns.is_empty() {
            return Some(NumericStart { values, digits: 15 });
        }
        let n = unknowns.len();
        let mut memo = HashMap::new();
        let a = DMatrix::from_fn(n, n, |i, j| pool.eval_memo(rows[i][j], &values, &mut memo));
        let b = DVector::from_fn(n, |i, _| pool.eval_memo(rhs[i], &values, &mut memo));
        if !a.iter().chain(b.iter()).all(|x| x.is_finite()) {
            return None;
        }
        let svd = a.svd(true, true);
        let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
        if smallest <= largest * 1e-15 || smallest == 0.0 {
            return None;
        }
        let x = svd.solve(&b, 0.0).ok()?;
        for (u, v) in unknowns.iter().zip(x.iter()) {
            values[u.index()] = *v;
        }
        let lost = (largest / smallest).log10().max(0.0);
        let digits = (15.0 - lost).floor().clamp(0.0, 15.0) as u32;
        Some(NumericStart { values, digits })
    }
}
