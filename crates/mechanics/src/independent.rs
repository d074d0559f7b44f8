//! The equations of a system with velocity constraints in its independent rates only: the
//! dependent rates solved from the constraints (at the velocity level, every kept constraint
//! alike), and the equations of motion combined along the independent directions, where the
//! multipliers cancel (Maggi's form). This is what a scene that asks for no contact force is
//! printed as; the multiplier form stays what the numbers integrate.

use std::collections::HashMap;

use cas::{linear_system, ExprId, SymId};

use crate::derive::Derivation;
use crate::present::collect_by_motion;

/// Past this many kept constraints the dependent rates' exact solution is not worth printing.
pub const DEPENDENT_LIMIT: usize = 4;

/// The dependent rates as functions of the independent ones, and one equation per independent
/// rate, `lhs = 0`.
#[derive(Clone, Debug)]
pub struct IndependentForm {
    /// Each dependent rate with its expression in the positions, the independent rates and t.
    pub dependent: Vec<(SymId, ExprId)>,
    /// The independent rates, in the coordinates' order.
    pub independent: Vec<SymId>,
    /// One equation per independent rate: Σ M̃ᵢⱼ·u̇ⱼ + the rest = 0.
    pub equations: Vec<ExprId>,
}

impl Derivation {
    /// The equations in the independent rates, when a velocity constraint is kept, no kept
    /// constraint's reaction is asked for, and the dependent rates solve exactly within a
    /// small system; `None` otherwise.
    pub fn independent_form(&mut self) -> Option<IndependentForm> {
        if self.multipliers.iter().all(|m| m.rows.position.is_some())
            || self.multipliers.len() > DEPENDENT_LIMIT
            || self.multipliers.iter().any(|m| self.model.constraints[m.constraint].force_requested)
        {
            return None;
        }
        let rows = self.velocity_rows();
        let dependent = self.dependent_rates(&rows)?;
        let pool = &mut self.model.pool;
        // A·q̇ + b = 0 solved for the dependent rates: the rest of each row, with them at 0.
        let zeros: HashMap<SymId, ExprId> = dependent.iter().map(|d| (*d, pool.zero())).collect();
        let mut a = Vec::new();
        let mut rhs = Vec::new();
        for row in &rows {
            a.push(
                dependent
                    .iter()
                    .map(|d| {
                        let c = pool.diff(*row, *d);
                        pool.simplify(c)
                    })
                    .collect::<Vec<_>>(),
            );
            let rest = pool.subst(*row, &zeros);
            rhs.push(pool.neg(rest));
        }
        let solution = linear_system::solve(pool, &a, &rhs)?;
        let solution: Vec<ExprId> = solution.into_iter().map(|e| pool.simplify(e)).collect();
        let rates_map: HashMap<SymId, ExprId> =
            dependent.iter().copied().zip(solution.iter().copied()).collect();
        // Their accelerations: the time derivative of each solution, with the dependent rates
        // it brings in replaced again.
        let mut accel_map = HashMap::new();
        for (d, s) in dependent.iter().zip(&solution) {
            let rate = pool.time_derivative(*s);
            let rate = pool.subst(rate, &rates_map);
            let accel = pool.rate(*d).expect("a rate has an acceleration");
            accel_map.insert(accel, rate);
        }
        let mut map = rates_map.clone();
        map.extend(accel_map);
        let independent: Vec<SymId> =
            self.rates.iter().copied().filter(|r| !dependent.contains(r)).collect();
        let n = self.coords.len();
        // The residual of each row of M·q̈ = f, the multipliers left out: they cancel below.
        let mut residual = Vec::with_capacity(n);
        for i in 0..n {
            let mut terms = Vec::new();
            for j in 0..n {
                let a = pool.sym(self.accels[j]);
                terms.push(pool.mul2(self.mass_matrix[i][j], a));
            }
            terms.push(pool.neg(self.forcing[i]));
            residual.push(pool.add(&terms));
        }
        let mut equations = Vec::new();
        for u in &independent {
            // Along the direction that moves u alone: its own row, and each dependent rate's
            // row weighted by how that rate moves with u.
            let i = self.rates.iter().position(|r| r == u).expect("a rate of the system");
            let mut terms = vec![residual[i]];
            for (d, s) in dependent.iter().zip(&solution) {
                let k = self.rates.iter().position(|r| r == d).expect("a rate of the system");
                let weight = pool.diff(*s, *u);
                terms.push(pool.mul2(weight, residual[k]));
            }
            let combined = pool.add(&terms);
            let combined = pool.subst(combined, &map);
            let combined = pool.simplify(combined);
            // Divided, as a hand derivation would, by what the accelerations' coefficients
            // share, their first one kept positive.
            let mut coefficients = Vec::new();
            for r in &independent {
                let accel = pool.rate(*r).expect("a rate has an acceleration");
                let c = pool.diff(combined, accel);
                let c = pool.simplify(c);
                if !pool.is_zero(c) {
                    coefficients.push(c);
                }
            }
            let combined = if coefficients.is_empty() {
                combined
            } else {
                let (content, _) = pool.common_content(&coefficients);
                let content =
                    if pool.looks_negative(coefficients[0]) { pool.neg(content) } else { content };
                let inverse = pool.powi(content, -1);
                let scaled = pool.mul2(combined, inverse);
                pool.simplify(scaled)
            };
            let parts = pool.terms(combined);
            equations.push(collect_by_motion(pool, &parts));
        }
        Some(IndependentForm {
            dependent: dependent.into_iter().zip(solution).collect(),
            independent,
            equations,
        })
    }

    /// One dependent rate per row: those the scene left for the constraints at the start when
    /// they are as many as the rows, else, row by row, the last declared rate the row moves.
    pub fn dependent_rates(&mut self, rows: &[ExprId]) -> Option<Vec<SymId>> {
        let pool = &mut self.model.pool;
        let mut not_given = Vec::new();
        for c in &self.model.coords {
            if c.initial_rate_given || !self.coords.contains(&c.sym) {
                continue;
            }
            let r = pool.rate(c.sym).expect("coordinate");
            if rows.iter().any(|row| pool.depends_on(*row, r)) {
                not_given.push(r);
            }
        }
        if not_given.len() == rows.len() {
            return Some(not_given);
        }
        let mut chosen = Vec::new();
        for row in rows {
            let pick = self
                .rates
                .iter()
                .rev()
                .find(|r| !chosen.contains(*r) && pool.depends_on(*row, **r))
                .copied()?;
            chosen.push(pick);
        }
        Some(chosen)
    }
}
