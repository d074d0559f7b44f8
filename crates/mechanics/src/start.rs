//! The instant t = 0: accelerations and multipliers exactly where the algebra stays small.
//! Past its budget the start is solved numerically, by the `verify` crate.

use std::collections::HashMap;

use cas::linear_system::{self, Solution};
use cas::{ExprId, SymId};

use crate::derive::Derivation;
use crate::start_solution::StartSolution;

/// New expression nodes the exact solve at the start may build before it gives up. A dense
/// system of a dozen unknowns needs millions and minutes; the 4-link pendulum at distinct
/// angles needs about 1,800, and problem set 5 a few dozen.
const START_BUDGET: usize = 25_000;

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
        if !self.solved_start_positions.is_empty() {
            // Positions solved in numbers are decimals close to irrational values: an exact
            // solve at them would only spell out their rounding.
            let solution = StartSolution::Numeric { unknowns: unknowns.len() };
            self.start = Some(solution.clone());
            return solution;
        }
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
}
