//! The third phase of a derivation: the Euler–Lagrange equation of each remaining coordinate
//! as a row of M(q, t)·q̈ = f(q, q̇, t), and the generalized forces of the loads.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::Diagnostic;
use model::{Model, Value};

use super::eliminate::Coordinates;
use super::energies::Energies;

/// The equations of motion in the remaining coordinates, one row per coordinate.
#[derive(Debug)]
pub(super) struct Rows {
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub forcing: Vec<ExprId>,
    /// Q of the applied forces, torques and dissipation, already part of `forcing`.
    pub generalized_forces: Vec<ExprId>,
}

/// The generalized force along `q` in any set of coordinates: Σ F·∂r/∂q + τ·∂angle/∂q −
/// ∂D/∂q̇, with positions, loads and D first put through `map`.
pub(super) fn generalized_force(
    pool: &mut Pool,
    model: &Model,
    dissipation: ExprId,
    q: SymId,
    map: &HashMap<SymId, ExprId>,
) -> ExprId {
    let mut parts = Vec::new();
    for f in &model.forces {
        let body = &model.bodies[f.body];
        let comps = match &f.value {
            Value::Vector(v) => v.clone(),
            Value::Scalar(s) => vec![*s],
            Value::Matrix(_) => Vec::new(),
        };
        for (fc, x) in comps.iter().zip(body.position.iter()) {
            let x = pool.subst(*x, map);
            let fc = pool.subst(*fc, map);
            let dx = pool.diff(x, q);
            parts.push(pool.mul2(fc, dx));
        }
    }
    for t in &model.torques {
        let (Value::Scalar(tau), Some(angle)) = (&t.value, model.bodies[t.body].angle) else {
            continue;
        };
        let angle = pool.subst(angle, map);
        let tau = pool.subst(*tau, map);
        let da = pool.diff(angle, q);
        parts.push(pool.mul2(tau, da));
    }
    let d = pool.subst(dissipation, map);
    let rate = pool.rate(q).expect("coordinate");
    let dd = pool.diff(d, rate);
    parts.push(pool.neg(dd));
    pool.add(&parts)
}

/// d/dt ∂L/∂q̇ᵢ − ∂L/∂qᵢ = Qᵢ for each remaining coordinate, split into the accelerations'
/// coefficients (M) and everything else (f), from energies in the remaining coordinates.
pub(super) fn euler_lagrange_rows(
    pool: &mut Pool,
    model: &Model,
    reduced: &Energies,
    coordinates: &Coordinates,
) -> Rows {
    let Coordinates { coords, rates, elimination_map, .. } = coordinates;
    let lagrangian = reduced.lagrangian;
    let n = coords.len();
    let mut mass_matrix = vec![vec![pool.zero(); n]; n];
    let mut forcing = Vec::with_capacity(n);
    let mut generalized_forces = Vec::with_capacity(n);
    for i in 0..n {
        // p_i = ∂L/∂q̇_i; d/dt p_i = Σ_j M_ij q̈_j + Σ_j ∂p_i/∂q_j q̇_j + ∂p_i/∂t.
        let p = pool.diff(lagrangian, rates[i]);
        for j in 0..n {
            mass_matrix[i][j] = pool.diff(p, rates[j]);
        }
        let mut parts = Vec::new();
        let q_force =
            generalized_force(pool, model, reduced.dissipation, coords[i], elimination_map);
        generalized_forces.push(q_force);
        parts.push(q_force);
        parts.push(pool.diff(lagrangian, coords[i]));
        for j in 0..n {
            let dp = pool.diff(p, coords[j]);
            let qd = pool.sym(rates[j]);
            let t = pool.mul2(dp, qd);
            parts.push(pool.neg(t));
        }
        let dpt = pool.diff(p, model.time);
        parts.push(pool.neg(dpt));
        forcing.push(pool.add(&parts));
    }
    // Folding sin² + cos² and angle sums (cos θ₁ cos θ₂ + sin θ₁ sin θ₂ = cos(θ₁ − θ₂)) leaves
    // fewer operations for the numbers to do, and is what every report prints anyway.
    for row in mass_matrix.iter_mut() {
        for e in row.iter_mut() {
            *e = pool.simplify(*e);
        }
    }
    for e in forcing.iter_mut() {
        *e = pool.simplify(*e);
    }
    Rows { mass_matrix, forcing, generalized_forces }
}

/// A coordinate whose row of M is zero has no acceleration the equations could determine.
pub(super) fn coordinates_without_inertia(
    pool: &mut Pool,
    model: &Model,
    coords: &[SymId],
    rows: &Rows,
) -> Vec<Diagnostic> {
    let mut errors = Vec::new();
    for (i, q) in coords.iter().enumerate() {
        if rows.mass_matrix[i].iter().all(|e| pool.is_identically_zero(*e)) {
            let span =
                model.coords.iter().find(|c| c.sym == *q).map(|c| c.span).unwrap_or_default();
            errors.push(
                Diagnostic::error(span, format!("no kinetic energy depends on the rate of `{}`", pool.symbol(*q).name))
                    .with_label("this coordinate has no inertia")
                    .with_hint("the mass matrix would be singular: place a body that moves with this coordinate, or remove it"),
            );
        }
    }
    errors
}
