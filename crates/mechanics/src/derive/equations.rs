//! The third phase of a derivation: the Euler–Lagrange equation of each remaining coordinate
//! as a row of M(q, t)·q̈ = f(q, q̇, t), and the generalized forces of the loads.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::Diagnostic;
use model::{Model, Rotation, Value};

use super::eliminate::Coordinates;
use super::energies::Energies;
use super::structural::{inertial_terms, kinetic_expansion, structural_rows, InertialTerm};

/// The equations of motion in the remaining coordinates, one row per coordinate.
#[derive(Debug)]
pub(super) struct Rows {
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub forcing: Vec<ExprId>,
    /// Q of the applied forces, torques and dissipation, already part of `forcing`.
    pub generalized_forces: Vec<ExprId>,
    /// What the recursive form is built from ([`super::chain`]).
    pub structure: Structure,
}

/// The rows taken apart as the recursive form needs them: the kinetic-energy terms on the
/// structural route, and per row the parts of f they did not give. Only ids already built are
/// kept, so that holding them adds no expression to the pool (whose numbering some printing
/// ties go by).
#[derive(Clone)]
pub(super) struct Structure {
    pub terms: Vec<InertialTerm>,
    pub rest_forcing: Vec<Vec<ExprId>>,
    /// Whether the rest of L has a term with the accelerations (a body off the structural route).
    pub rest_has_mass: bool,
}

impl std::fmt::Debug for Structure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Structure")
            .field("terms", &self.terms.len())
            .field("rest_forcing", &self.rest_forcing)
            .field("rest_has_mass", &self.rest_has_mass)
            .finish()
    }
}

/// The generalized force along `q` in any set of coordinates, by virtual work: Σ F·∂r/∂q over
/// forces (r the point they act at), Σ τ·∂ω/∂q̇ over torques (in the plane ∂ω/∂q̇ = ∂angle/∂q),
/// and −∂D/∂q̇, with positions, loads and D first put through `map`.
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
        let point = f.at.as_ref().unwrap_or(&body.position);
        for (fc, x) in comps.iter().zip(point.iter()) {
            let x = pool.subst(*x, map);
            let fc = pool.subst(*fc, map);
            let dx = pool.diff(x, q);
            parts.push(pool.mul2(fc, dx));
        }
    }
    let rate = pool.rate(q).expect("coordinate");
    for t in &model.torques {
        if let (Value::Vector(tau), Some(rotation @ Rotation::Spatial { .. })) =
            (&t.value, &model.bodies[t.body].rotation)
        {
            // The partial angular velocity ∂ω/∂q̇ in world axes, where τ is given.
            let omega = rotation.spatial_angular_velocity(pool, true).expect("in space");
            for (tc, w) in tau.iter().zip(omega) {
                let w = pool.subst(w, map);
                let tc = pool.subst(*tc, map);
                let dw = pool.diff(w, rate);
                parts.push(pool.mul2(tc, dw));
            }
            continue;
        }
        let (Value::Scalar(tau), Some(angle)) = (&t.value, model.bodies[t.body].angle()) else {
            continue;
        };
        let angle = pool.subst(angle, map);
        let tau = pool.subst(*tau, map);
        let da = pool.diff(angle, q);
        parts.push(pool.mul2(tau, da));
    }
    let d = pool.subst(dissipation, map);
    let dd = pool.diff(d, rate);
    parts.push(pool.neg(dd));
    pool.add(&parts)
}

/// d/dt ∂L/∂q̇ᵢ − ∂L/∂qᵢ = Qᵢ for each remaining coordinate, split into the accelerations'
/// coefficients (M) and everything else (f), from energies in the remaining coordinates
/// (`reduced`) and in all declared ones (`full`). The kinetic energy of translation, planar
/// rotation and rotation in space takes the structural route (`structural`: m·Jᵀ·J and m·a₀·J,
/// Wᵀ·I·W and Euler's gyroscopic terms); the rest of L is differentiated.
pub(super) fn euler_lagrange_rows(
    pool: &mut Pool,
    model: &Model,
    full: &Energies,
    reduced: &Energies,
    coordinates: &Coordinates,
) -> Rows {
    let Coordinates { coords, rates, elimination_map, .. } = coordinates;
    let (inertial, inertial_kinetic) = inertial_terms(pool, model, elimination_map, coords);
    // L without the terms the structural route covers, in the remaining coordinates.
    let rest = pool.sub(full.lagrangian, inertial_kinetic);
    let lagrangian = pool.subst(rest, elimination_map);
    let (structural_mass, structural_forcing) = structural_rows(pool, &inertial, coords);
    let n = coords.len();
    let mut mass_matrix = vec![vec![pool.zero(); n]; n];
    let mut forcing = Vec::with_capacity(n);
    let mut generalized_forces = Vec::with_capacity(n);
    let mut rest_forcing = Vec::with_capacity(n);
    let mut rest_has_mass = false;
    for i in 0..n {
        // p_i = ∂L/∂q̇_i; d/dt p_i = Σ_j M_ij q̈_j + Σ_j ∂p_i/∂q_j q̇_j + ∂p_i/∂t.
        let p = pool.diff(lagrangian, rates[i]);
        for j in 0..n {
            let m = pool.diff(p, rates[j]);
            // The structural part is symmetric and kept in its upper triangle.
            rest_has_mass |= !pool.is_zero(m);
            let structural = structural_mass[i.min(j)][i.max(j)];
            mass_matrix[i][j] = pool.add2(structural, m);
        }
        let mut parts = Vec::new();
        let q_force =
            generalized_force(pool, model, reduced.dissipation, coords[i], elimination_map);
        generalized_forces.push(q_force);
        parts.push(q_force);
        parts.push(structural_forcing[i]);
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
        parts.remove(1);
        rest_forcing.push(parts);
    }
    // Folding sin² + cos² and angle sums (cos θ₁ cos θ₂ + sin θ₁ sin θ₂ = cos(θ₁ − θ₂)) leaves
    // fewer operations for the numbers to do, and is what every report prints anyway.
    for row in mass_matrix.iter_mut() {
        for e in row.iter_mut() {
            *e = simplified_unless_larger(pool, *e);
        }
    }
    for e in forcing.iter_mut() {
        *e = simplified_unless_larger(pool, *e);
    }
    // Reports show T simplified; its squares of long sums multiplied out would cost more than
    // the rows did.
    let structural_kinetic = pool.subst(inertial_kinetic, elimination_map);
    if let Some(expanded) = kinetic_expansion(
        pool,
        &inertial,
        &structural_mass,
        rates,
        reduced.kinetic,
        structural_kinetic,
    ) {
        pool.remember_expansion(reduced.kinetic, expanded);
    }
    let structure = Structure { terms: inertial, rest_forcing, rest_has_mass };
    Rows { mass_matrix, forcing, generalized_forces, structure }
}

/// A row entry simplified; but one too large to print either way (a bicycle's) is kept in
/// whichever form has fewer operations. Multiplied out, the structural products of short
/// factors lose what they share: the bicycle's M took 18,078 lowered operations simplified.
fn simplified_unless_larger(pool: &mut Pool, e: ExprId) -> ExprId {
    let simplified = pool.simplify(e);
    if pool.prints_in_full(simplified)
        || pool.operation_count(simplified) <= pool.operation_count(e)
    {
        simplified
    } else {
        e
    }
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

#[cfg(test)]
mod tests {
    use super::super::eliminate::{eliminate_constraints, remaining_coordinates};
    use super::super::energies::energies;
    use super::super::testing::{ascii, coord, scene, FALLING_ROD};
    use super::*;

    /// The rows of a scene, with the phases before them run as `derive` runs them.
    fn rows_of(source: &str) -> (Pool, Model, Coordinates, Rows) {
        let (mut pool, model) = scene(source);
        let eliminated = eliminate_constraints(&mut pool, &model).eliminated;
        let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
        let full = energies(&mut pool, &model);
        let reduced = full.reduced(&mut pool, &coordinates.elimination_map);
        let rows = euler_lagrange_rows(&mut pool, &model, &full, &reduced, &coordinates);
        (pool, model, coordinates, rows)
    }

    fn matrix(pool: &Pool, m: &[Vec<ExprId>]) -> Vec<Vec<String>> {
        m.iter().map(|row| row.iter().map(|e| ascii(pool, *e)).collect()).collect()
    }

    #[test]
    fn two_particles_share_a_coordinate() {
        let (pool, _, _, rows) = rows_of(
            "param m1, m2, k\ncoord x\ncoord s\nparticle a { mass m1; position (x, 0) }\nparticle b { mass m2; position (x + s, 0) }\npotential k/2*s^2",
        );
        assert_eq!(matrix(&pool, &rows.mass_matrix), [["m1 + m2", "m2"], ["m2", "m2"]]);
        assert_eq!([ascii(&pool, rows.forcing[0]), ascii(&pool, rows.forcing[1])], ["0", "-k*s"]);
    }

    #[test]
    fn a_pendulum_row_is_simplified() {
        let (pool, _, _, rows) = rows_of(
            "param m, L, g\ncoord theta\nparticle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\ngravity g",
        );
        assert_eq!(matrix(&pool, &rows.mass_matrix), [["m*L^2"]]);
        assert_eq!(ascii(&pool, rows.forcing[0]), "-m*L*g*sin(theta)");
        assert_eq!(ascii(&pool, rows.generalized_forces[0]), "0");
    }

    #[test]
    fn the_falling_rod() {
        let (pool, _, _, rows) = rows_of(FALLING_ROD);
        assert_eq!(
            matrix(&pool, &rows.mass_matrix),
            [["m", "0"], ["0", "1/12*m*L^2 + 1/4*m*L^2*sin(theta)^2"]]
        );
        assert_eq!(
            [ascii(&pool, rows.forcing[0]), ascii(&pool, rows.forcing[1])],
            ["0", "-1/4*m*L^2*sin(theta)*cos(theta)*theta'^2 + 1/2*m*L*g*sin(theta)"]
        );
    }

    /// The rows of d/dt ∂L/∂q̇ − ∂L/∂q = 0 with L differentiated twice, the route the structural
    /// rows replace, for comparing with them: M and f.
    fn rows_by_differentiation(
        pool: &mut Pool,
        model: &Model,
        coordinates: &Coordinates,
    ) -> (Vec<Vec<ExprId>>, Vec<ExprId>) {
        let full = energies(pool, model);
        let l = pool.subst(full.lagrangian, &coordinates.elimination_map);
        let (coords, rates) = (&coordinates.coords, &coordinates.rates);
        let mut mass = Vec::new();
        let mut forcing = Vec::new();
        for (&coord, &rate) in coords.iter().zip(rates) {
            let p = pool.diff(l, rate);
            mass.push(rates.iter().map(|r| pool.diff(p, *r)).collect());
            let mut parts = vec![pool.diff(l, coord)];
            for (q, r) in coords.iter().zip(rates) {
                let dp = pool.diff(p, *q);
                let r = pool.sym(*r);
                let t = pool.mul2(dp, r);
                parts.push(pool.neg(t));
            }
            let dpt = pool.diff(p, model.time);
            parts.push(pool.neg(dpt));
            forcing.push(pool.add(&parts));
        }
        (mass, forcing)
    }

    /// A body turning in space takes the structural route (Wᵀ·I·W and Euler's gyroscopic
    /// terms), which agrees with differentiating ½·ωᵀ·I·ω twice only through sin² + cos² = 1:
    /// an inertia with products, three angles, a centre that moves with them, and a frame
    /// turned in time underneath.
    #[test]
    fn a_body_turning_in_space_has_the_rows_of_its_lagrangian() {
        for orientation in ["rotz(a)*rotx(b)*roty(c)", "rotz(w*t)*rotx(a)*rotz(b)*roty(c)"] {
            let source = format!(
                "param m, g, w, l, A, B, C, D\ncoord a\ncoord b\ncoord c\nbody top {{ mass m; inertia [A, 0, D; 0, B, 0; D, 0, C]; orientation {orientation}; position rotz(a)*rotx(b)*(0, 0, l) }}\ngravity g"
            );
            let (mut pool, model, coordinates, rows) = rows_of(&source);
            let (mass, forcing) = rows_by_differentiation(&mut pool, &model, &coordinates);
            for (i, row) in mass.iter().enumerate() {
                for (j, by_l) in row.iter().enumerate() {
                    let d = pool.sub(rows.mass_matrix[i][j], *by_l);
                    assert!(pool.is_identically_zero(d), "M[{i}][{j}] of {orientation}");
                }
                let d = pool.sub(rows.forcing[i], forcing[i]);
                assert!(pool.is_identically_zero(d), "f[{i}] of {orientation}");
            }
        }
    }

    #[test]
    fn loads_do_virtual_work() {
        let (mut pool, model) = scene(
            "param m, L, F, tau, c\ncoord x\ncoord theta\nbody arm { mass m; inertia m*L^2; position (x + L*sin(theta), -L*cos(theta)); angle theta }\nforce push on arm: (F, 0)\ntorque motor on arm: tau\ndissipation c/2*x'^2",
        );
        let full = energies(&mut pool, &model);
        let none = HashMap::new();
        let x = coord(&model, "x");
        let theta = coord(&model, "theta");
        let q_x = generalized_force(&mut pool, &model, full.dissipation, x, &none);
        let q_theta = generalized_force(&mut pool, &model, full.dissipation, theta, &none);
        assert_eq!(
            [ascii(&pool, q_x), ascii(&pool, q_theta)],
            ["-c*x' + F", "tau + L*F*cos(theta)"]
        );
    }

    #[test]
    fn loads_on_an_eliminated_coordinate_reach_the_rest() {
        let (mut pool, model) = scene(
            "param m, L, P\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\nconstraint track: y = L*x^2\nforce lift on p: (0, P)",
        );
        let eliminated = eliminate_constraints(&mut pool, &model).eliminated;
        let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
        let full = energies(&mut pool, &model);
        let x = coord(&model, "x");
        let q =
            generalized_force(&mut pool, &model, full.dissipation, x, &coordinates.elimination_map);
        assert_eq!(ascii(&pool, q), "2*L*P*x");
    }

    #[test]
    fn a_coordinate_nothing_moves_with_is_an_error() {
        let (mut pool, model) =
            scene("param m\ncoord x\ncoord z\nparticle p { mass m; position (x, 0) }");
        let eliminated = eliminate_constraints(&mut pool, &model).eliminated;
        let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
        let full = energies(&mut pool, &model);
        let reduced = full.reduced(&mut pool, &coordinates.elimination_map);
        let rows = euler_lagrange_rows(&mut pool, &model, &full, &reduced, &coordinates);
        let errors = coordinates_without_inertia(&mut pool, &model, &coordinates.coords, &rows);
        let [e] = &errors[..] else { panic!("{errors:?}") };
        assert_eq!(e.message, "no kinetic energy depends on the rate of `z`");
    }
}
