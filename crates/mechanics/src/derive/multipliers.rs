//! The fourth phase of a derivation: each constraint that could not be eliminated is kept,
//! with a multiplier λ whose generalized force is λ·∂Φ/∂q and a row J·q̈ = γ of its own.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use model::Model;

use super::eliminate::Coordinates;
use super::Multiplier;

/// Φ of each kept constraint in the remaining coordinates, its Jacobian, and γ: Φ̈ = J·q̈ − γ,
/// so that Φ̈ = 0 is J·q̈ = γ.
pub(super) fn kept_constraints(
    pool: &mut Pool,
    model: &Model,
    kept: &[usize],
    coordinates: &Coordinates,
) -> Vec<Multiplier> {
    let mut multipliers = Vec::new();
    for &ci in kept {
        let c = &model.constraints[ci];
        let phi = pool.subst(c.phi, &coordinates.elimination_map);
        let phi = pool.expand(phi);
        let jacobian: Vec<ExprId> = coordinates.coords.iter().map(|q| pool.diff(phi, *q)).collect();
        let velocity = pool.time_derivative(phi);
        let acceleration = pool.time_derivative(velocity);
        let zeros: HashMap<SymId, ExprId> =
            coordinates.accels.iter().map(|a| (*a, pool.zero())).collect();
        let rest = pool.subst(acceleration, &zeros);
        let bias = pool.neg(rest);
        multipliers.push(Multiplier {
            constraint: ci,
            lambda: c.force_symbol,
            phi,
            jacobian,
            bias,
        });
    }
    multipliers
}
