//! The start's positions against the kept position constraints. A start that breaks one is
//! an impossible state: `show at start` and `expect at start` would be evaluated there, and a
//! run would drag the state back onto the constraint. Decided here exactly, at the values the
//! run uses; what only numbers can decide (a value given to some digits, a position to solve
//! for) is the `verify` crate's, which hands its solution back through
//! [`Derivation::set_start_positions`].

use std::collections::HashMap;

use cas::{ExprId, Rational, SymId};
use lang::Diagnostic;

use super::Derivation;

impl Derivation {
    /// Each parameter's value as numbers only (earlier parameters' values substituted),
    /// exactly, and each input's when nothing drives it; parameters without a value are left
    /// out.
    pub fn parameter_values(&mut self) -> HashMap<SymId, ExprId> {
        let mut values: HashMap<SymId, ExprId> = HashMap::new();
        for (sym, value) in self.model.constants() {
            let Some(v) = value else { continue };
            let v = self.model.pool.subst(v, &values);
            values.insert(sym, v);
        }
        values
    }

    /// Whether `e`, an expression of the parameters (and the start), is zero at the values
    /// the run uses: exactly, as an identity first, then at the parameters' values.
    /// A start that holds only at the values marks the derivation
    /// ([`Derivation::start_at_values_only`]).
    pub fn zero_at_parameter_values(&mut self, e: ExprId) -> bool {
        if self.model.pool.is_identically_zero(e) {
            return true;
        }
        let values = self.parameter_values();
        let at_values = self.model.pool.subst(e, &values);
        let free = self.model.pool.free_symbols(at_values);
        let zero = free.is_empty() && self.model.pool.is_identically_zero(at_values);
        self.start_at_values_only |= zero;
        zero
    }

    /// Each kept position constraint that the start does not satisfy exactly: the
    /// constraint's index and Φ at the start.
    pub fn start_position_residuals(&mut self) -> Vec<(usize, ExprId)> {
        let state = self.initial_state();
        let mut out = Vec::new();
        for m in self.multipliers.clone() {
            if self.model.constraints[m.constraint].kind.is_unilateral() {
                continue;
            }
            let Some(phi) = m.rows.position else { continue };
            let at_start = self.model.pool.subst(phi, &state);
            if !self.zero_at_parameter_values(at_start) {
                out.push((m.constraint, at_start));
            }
        }
        out
    }

    /// Φ of each two-sided position constraint kept with a multiplier, in the multipliers'
    /// order: what places the start (a contact does not: its gap is an inequality).
    pub fn kept_position_constraints(&self) -> Vec<ExprId> {
        self.multipliers
            .iter()
            .filter(|m| !self.model.constraints[m.constraint].kind.is_unilateral())
            .filter_map(|m| m.rows.position)
            .collect()
    }

    /// The coordinates whose start positions the kept position constraints may solve for:
    /// remaining, restrained by one of them, and given no value or only a guess (`~`).
    pub fn free_start_positions(&mut self) -> Vec<SymId> {
        let phis = self.kept_position_constraints();
        let mut out = Vec::new();
        for c in self.model.coords.clone() {
            if !c.position_free || !self.coords.contains(&c.sym) {
                continue;
            }
            if phis.iter().any(|phi| self.model.pool.depends_on(*phi, c.sym)) {
                out.push(c.sym);
            }
        }
        out
    }

    /// Takes start positions solved in numbers (each as the exact decimal the `verify` crate
    /// read its float as), marks them as solved, and settles the start's rates at the new
    /// positions.
    pub fn set_start_positions(&mut self, solved: &[(SymId, Rational)]) -> Result<(), Diagnostic> {
        for (s, q) in solved {
            let value = self.model.pool.num(q.clone());
            if let Some(c) = self.model.coords.iter_mut().find(|c| c.sym == *s) {
                c.initial = value;
            }
            if !self.solved_start_positions.contains(s) {
                self.solved_start_positions.push(*s);
            }
        }
        self.start = None;
        self.start_positions_pending = false;
        self.start_at_values_only = true;
        self.settle_start_rates()
    }
}
