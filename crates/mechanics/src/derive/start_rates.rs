//! The last phase of a derivation: rates at the start that velocity constraints fix. Given
//! rates must satisfy them; the rates the scene did not give are solved for, exactly, when
//! there are as many of them as constraint rows; otherwise the residual is an error.

use std::collections::HashMap;

use cas::{linear_system, ExprId, SymId};
use lang::Diagnostic;

use super::Derivation;

impl Derivation {
    /// Whether a kept velocity constraint A·q̇ + b = 0 has b ≠ 0: a moving surface (a turntable)
    /// that does work on the system, so that its energy is not conserved.
    pub fn drives_through_velocity_constraints(&mut self) -> bool {
        let (rates, time) = (self.rates.clone(), self.model.time);
        for m in self.multipliers.clone() {
            if m.rows.position.is_some() {
                continue;
            }
            let pool = &mut self.model.pool;
            let b = m.rows.rate_free(pool, time, &rates);
            if !pool.is_identically_zero(b) {
                return true;
            }
        }
        false
    }

    /// Settles the start's rates against the kept constraints, each at the velocity level: Φ
    /// for a velocity constraint, Φ̇ for a position one (a crank turning moves its rod, and a
    /// rod whose length is driven moves its bob).
    pub fn settle_start_rates(&mut self) -> Result<(), Diagnostic> {
        if self.multipliers.is_empty() {
            return Ok(());
        }
        let state = self.initial_state();
        let constraints: Vec<usize> = self.multipliers.iter().map(|m| m.constraint).collect();
        let rows: Vec<(usize, ExprId)> =
            constraints.into_iter().zip(self.velocity_rows()).collect();
        let mut violated = Vec::new();
        for (c, row) in &rows {
            let at_start = self.model.pool.subst(*row, &state);
            // At the values the run uses: a start may hold only there (a turntable's speed
            // matched to a ball's spin by the parameters' values).
            if !self.zero_at_parameter_values(at_start) {
                violated.push((*c, self.model.pool.simplify(at_start)));
            }
        }
        if violated.is_empty() {
            return Ok(());
        }
        let pool = &mut self.model.pool;
        // The rates left to the constraints: not given, and restrained by some row.
        let mut unknowns: Vec<(usize, SymId)> = Vec::new();
        for (i, c) in self.model.coords.iter().enumerate() {
            if c.initial_rate_given || !self.coords.contains(&c.sym) {
                continue;
            }
            let rate = pool.rate(c.sym).expect("coordinate");
            if rows.iter().any(|(_, r)| pool.depends_on(*r, rate)) {
                unknowns.push((i, rate));
            }
        }
        let (first, residual) = violated[0];
        let constraint = self.model.constraints[first].clone();
        let names = |pool: &cas::Pool, u: &[(usize, SymId)]| {
            u.iter().map(|(_, s)| format!("`{}`", pool.symbol(*s).name)).collect::<Vec<_>>()
        };
        let refuse = |pool: &cas::Pool, hint: String| {
            let residual = pool.print(residual, cas::Style::Ascii);
            Diagnostic::error(
                constraint.span,
                format!("the rates at the start do not satisfy `{}`", constraint.name),
            )
            .with_label(format!("at the start this side minus that is {residual}, not 0"))
            .with_hint(hint)
        };
        if unknowns.len() != rows.len() {
            let k = rows.len();
            let (rows_text, them, restrain) = if k == 1 {
                ("1 constraint row".to_string(), "it", "it restrains")
            } else {
                (format!("{k} constraint rows"), "them", "they restrain")
            };
            let hint = if unknowns.len() > k {
                format!(
                    "{rows_text} fix{} {k} of the rates {} at the start: give the others",
                    if k == 1 { "es" } else { "" },
                    names(pool, &unknowns).join(", ")
                )
            } else if unknowns.is_empty() {
                format!(
                    "{rows_text} fix{} {k} rate{} at the start: leave {k} of the rates {restrain} without a value",
                    if k == 1 { "es" } else { "" },
                    if k == 1 { "" } else { "s" },
                )
            } else {
                format!(
                    "{rows_text} fix {k} rates at the start, and only {} {} left to {them}: leave more without a value",
                    names(pool, &unknowns).join(", "),
                    if unknowns.len() == 1 { "is" } else { "are" },
                )
            };
            return Err(refuse(pool, hint));
        }
        // Each row is linear in the rates: A·u + b = 0 at the start positions.
        let mut zeroed: HashMap<SymId, ExprId> = state.clone();
        for (_, u) in &unknowns {
            zeroed.insert(*u, pool.zero());
        }
        let mut a = Vec::new();
        let mut b = Vec::new();
        for (_, row) in &rows {
            let coefficients: Vec<ExprId> = unknowns
                .iter()
                .map(|(_, u)| {
                    let d = pool.diff(*row, *u);
                    let d = pool.subst(d, &zeroed);
                    pool.simplify(d)
                })
                .collect();
            a.push(coefficients);
            let rest = pool.subst(*row, &zeroed);
            b.push(pool.neg(rest));
        }
        let Some(solution) = linear_system::solve(pool, &a, &b) else {
            let hint = format!(
                "the constraints do not fix {} at the start: give some of them",
                names(pool, &unknowns).join(", ")
            );
            return Err(refuse(pool, hint));
        };
        for ((i, _), value) in unknowns.iter().zip(solution) {
            let value = pool.simplify(value);
            self.model.coords[*i].initial_rate = value;
        }
        self.start = None;
        Ok(())
    }
}
