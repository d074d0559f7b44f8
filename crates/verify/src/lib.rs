//! The numeric side of checking a derivation.
//!
//! This crate owns everything about a derivation that takes numbers rather than algebra:
//! random states the system can reach (projected onto the constraints kept with multipliers),
//! the rank of the constraints' Jacobian there (which tells a repeated or contradicting
//! constraint), `expect` lines that the algebra of `mechanics` cannot decide, sampled at such
//! states, the start solved in floating point when the exact solve outgrows its budget, and
//! the warnings about `expect` lines no state can decide. Every float it computes from an
//! expression comes from `numeric`'s evaluator; it adds the linear algebra and the seeded
//! random states.

mod admissible;
mod check;
mod present;
mod start;
mod start_positions;
mod system;
mod undecidable;

pub use admissible::admissible_states;
pub use check::{check, check_all, Failure, Sampling, Verdict, SAMPLES};
pub use present::{shown_at_start, NumericValue, ShownAtStart};
pub use start::{parameter_values, start_numeric, NumericStart};
pub use start_positions::{settle_start_positions, solve_positions, within_rounding};

use lang::Diagnostic;
use mechanics::Derivation;

/// The numeric diagnostics that follow a derivation: an error for a kept constraint that
/// repeats or contradicts the ones before it, the start's positions settled against the kept
/// constraints (an error where they break one), and warnings about `expect` lines `check` will
/// not be able to decide (added to the derivation's warnings).
pub fn diagnose(d: &mut Derivation) -> Result<(), Vec<Diagnostic>> {
    let dependent = admissible::dependent_constraints(d);
    if !dependent.is_empty() {
        return Err(dependent);
    }
    if let Some(e) = d.start_rates_error.take() {
        return Err(vec![e]);
    }
    settle_start_positions(d)?;
    undecidable::warn_about_undecidable_expects(d);
    Ok(())
}
