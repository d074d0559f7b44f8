//! What the start's unknowns turned out to be: the answer [`Derivation::unknowns_at_start`]
//! computes (in `start`) and a [`Derivation`] caches. A module of its own, below both, so that
//! the derivation holds the cache without knowing how the start is solved.
//!
//! [`Derivation`]: crate::Derivation
//! [`Derivation::unknowns_at_start`]: crate::Derivation::unknowns_at_start

use std::collections::HashMap;

use cas::{ExprId, SymId};

/// The unknowns of the start, solved exactly if the algebra allows.
#[derive(Clone, Debug)]
pub enum StartSolution {
    /// Accelerations and multipliers (and the initial state) as expressions of the parameters.
    Exact(HashMap<SymId, ExprId>),
    /// The mass matrix (with the constraints' rows) is singular at the start.
    Singular,
    /// The exact solution outgrew its budget; the unknowns are found numerically instead.
    TooLarge { unknowns: usize },
    /// The start's positions were solved in numbers, and so is the rest of the start.
    Numeric { unknowns: usize },
}
