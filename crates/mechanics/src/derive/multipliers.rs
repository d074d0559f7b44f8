//! The fourth phase of a derivation: each constraint that could not be eliminated is kept,
//! with a multiplier λ whose generalized force is λ·∂Φ/∂q and a row J·q̈ = γ of its own.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::Diagnostic;
use model::Model;

use super::eliminate::Coordinates;
use super::rows::{may_be_implied, restrains_positions, ConstraintRows};
use super::Multiplier;

/// The rows of each kept constraint in the remaining coordinates ([`ConstraintRows`], by
/// kind), with its multiplier.
/// Velocity constraints that restrain nothing the position constraints do not: each with a
/// warning that says so (the vertical component of a wheel's rolling, the time derivative of
/// its touching the ground). They are left out of the equations, whose rows they would make
/// dependent.
pub(super) fn kept_constraints(
    pool: &mut Pool,
    model: &Model,
    kept: &[usize],
    coordinates: &Coordinates,
) -> (Vec<Multiplier>, Vec<Diagnostic>) {
    let mut multipliers = Vec::new();
    let mut warnings = Vec::new();
    let position_rows: Vec<(usize, ExprId)> = kept
        .iter()
        .filter(|&&ci| restrains_positions(model.constraints[ci].kind))
        .map(|&ci| {
            let phi = pool.subst(model.constraints[ci].phi, &coordinates.elimination_map);
            (ci, pool.time_derivative(phi))
        })
        .collect();
    for &ci in kept {
        let c = &model.constraints[ci];
        let phi = pool.subst(c.phi, &coordinates.elimination_map);
        if may_be_implied(c.kind) && !c.force_requested {
            let rows: Vec<ExprId> = position_rows.iter().map(|(_, r)| *r).collect();
            if let Some(by) = implied_by(pool, phi, &rows, &coordinates.rates) {
                let names: Vec<String> = by
                    .iter()
                    .map(|&k| format!("`{}`", model.constraints[position_rows[k].0].name))
                    .collect();
                let what = if names.is_empty() {
                    "it holds whatever the motion, in the coordinates left".to_string()
                } else {
                    format!("the time derivative of {} says as much", names.join(" and "))
                };
                warnings.push(
                    Diagnostic::warning(
                        c.span,
                        format!("`{}` restrains nothing more: left out", c.name),
                    )
                    .with_label(what)
                    .with_hint("constrain only what restrains velocities (of a vector, the components that do)"),
                );
                continue;
            }
        }
        let Coordinates { coords, rates, accels, .. } = coordinates;
        let rows = ConstraintRows::of(pool, c.kind, phi, (coords, rates, accels));
        multipliers.push(Multiplier { constraint: ci, lambda: c.force_symbol, rows, force: None });
    }
    (multipliers, warnings)
}

/// Whether the velocity row Φ (linear in the rates) is, at each generic point, a combination
/// of `rows` (the position constraints' Φ̇), coefficients of the rates and the rest alike; the
/// rows it needs, by index, if so. Decided by the pool's numeric identity test: the rows are as
/// large as a bicycle's.
fn implied_by(
    pool: &mut Pool,
    phi: ExprId,
    rows: &[ExprId],
    rates: &[SymId],
) -> Option<Vec<usize>> {
    // Each row as its coefficients of the rates, then what is left with them at 0.
    let zeros: HashMap<SymId, ExprId> = rates.iter().map(|r| (*r, pool.zero())).collect();
    let parts = |pool: &mut Pool, row: ExprId| -> Vec<ExprId> {
        let mut out: Vec<ExprId> = rates.iter().map(|r| pool.diff(row, *r)).collect();
        out.push(pool.subst(row, &zeros));
        out
    };
    let target = parts(pool, phi);
    let basis: Vec<Vec<ExprId>> = rows.iter().map(|r| parts(pool, *r)).collect();
    pool.combination_at_generic_points(&target, &basis)
}

#[cfg(test)]
mod tests {
    use super::super::eliminate::{eliminate_constraints, remaining_coordinates};
    use super::super::rows::reaction_direction;
    use super::super::testing::{ascii, derived, scene, CARTESIAN_PENDULUM};
    use super::*;
    use model::ConstraintKind;

    fn multipliers_of(source: &str) -> (Pool, Model, Vec<Multiplier>) {
        let (mut pool, model) = scene(source);
        let out = eliminate_constraints(&mut pool, &model);
        let coordinates = remaining_coordinates(&mut pool, &model, &out.eliminated);
        let (multipliers, _) = kept_constraints(&mut pool, &model, &out.kept, &coordinates);
        (pool, model, multipliers)
    }

    #[test]
    fn a_circle_gets_its_row() {
        let (pool, model, multipliers) = multipliers_of(CARTESIAN_PENDULUM);
        let [m] = &multipliers[..] else { panic!("{multipliers:?}") };
        assert_eq!(m.constraint, 0);
        assert_eq!(m.lambda, model.constraints[0].force_symbol);
        assert_eq!(ascii(&pool, m.rows.phi()), "-L^2 + x^2 + y^2");
        let jacobian: Vec<String> = m.rows.jacobian.iter().map(|e| ascii(&pool, *e)).collect();
        assert_eq!(jacobian, ["2*x", "2*y"]);
        assert_eq!(ascii(&pool, m.rows.bias), "-2*x'^2 - 2*y'^2");
    }

    /// A velocity constraint, set in the model directly: a knife edge at angle theta that
    /// cannot slide sideways, sin(theta)·ẋ − cos(theta)·ẏ = 0. It is kept, never eliminated,
    /// its row is Φ̇ with the rates' coefficients as Jacobian, and its force on theta is nil.
    #[test]
    fn a_velocity_constraint_gets_its_row_from_one_derivative() {
        let (mut pool, mut model) = scene(
            "param m, I\ncoord x\ncoord y\ncoord theta\nbody blade { mass m; inertia I; position (x, y); angle theta }\nconstraint edge: x = y",
        );
        let rate = |pool: &mut Pool, name: &str| {
            let s = pool.lookup_symbol(name).expect("declared");
            let r = pool.rate(s).expect("a coordinate");
            pool.sym(r)
        };
        let (xd, yd) = (rate(&mut pool, "x"), rate(&mut pool, "y"));
        let theta = pool.lookup_symbol("theta").expect("declared");
        let theta = pool.sym(theta);
        let (s, c) = (pool.sin(theta), pool.cos(theta));
        let (a, b) = (pool.mul2(s, xd), pool.mul2(c, yd));
        model.constraints[0].kind = ConstraintKind::Velocity;
        model.constraints[0].phi = pool.sub(a, b);
        let out = eliminate_constraints(&mut pool, &model);
        assert!(out.eliminated.is_empty());
        assert_eq!(out.kept, [0]);
        let coordinates = remaining_coordinates(&mut pool, &model, &out.eliminated);
        let (multipliers, _) = kept_constraints(&mut pool, &model, &out.kept, &coordinates);
        let [m] = &multipliers[..] else { panic!("{multipliers:?}") };
        assert_eq!((m.rows.position, m.rows.velocity), (None, m.rows.phi()));
        assert_eq!(m.rows.stabilisation, super::super::Stabilisation::Velocity);
        let jacobian: Vec<String> = m.rows.jacobian.iter().map(|e| ascii(&pool, *e)).collect();
        assert_eq!(jacobian, ["sin(theta)", "-cos(theta)", "0"]);
        assert_eq!(ascii(&pool, m.rows.bias), "-(cos(theta)*x' + sin(theta)*y')*theta'");
        let along_theta = coordinates.coords[2];
        let gradient = reaction_direction(&mut pool, &model.constraints[0], along_theta);
        assert!(pool.is_zero(gradient));
    }

    #[test]
    fn a_kept_constraint_sees_the_eliminations() {
        // The floor removes y; the circle is then one in x and theta alone.
        let (pool, _, multipliers) = multipliers_of(
            "param m, L\ncoord x\ncoord y\ncoord theta\nbody rod { mass m; inertia m*L^2; position (x, y); angle theta }\nconstraint floor: y = L*cos(theta)\nconstraint ring: x^2 + y^2 = L^2",
        );
        let [m] = &multipliers[..] else { panic!("{multipliers:?}") };
        assert_eq!(m.constraint, 1);
        assert_eq!(ascii(&pool, m.rows.phi()), "-L^2*sin(theta)^2 + x^2");
        let jacobian: Vec<String> = m.rows.jacobian.iter().map(|e| ascii(&pool, *e)).collect();
        assert_eq!(jacobian, ["2*x", "-2*L^2*sin(theta)*cos(theta)"]);
        assert_eq!(
            ascii(&pool, m.rows.bias),
            "-2*x'^2 - (2*L^2*sin(theta)^2*theta' - 2*L^2*cos(theta)^2*theta')*theta'"
        );
    }

    #[test]
    fn a_moving_constraint_has_a_bias_in_time() {
        let (pool, _, multipliers) = multipliers_of(
            "param m, w\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\nconstraint spin: x*sin(w*t) = y*cos(w*t)",
        );
        let [m] = &multipliers[..] else { panic!("{multipliers:?}") };
        assert_eq!(
            ascii(&pool, m.rows.bias),
            "-2*w*cos(w*t)*x' - 2*w*sin(w*t)*y' + w^2*sin(w*t)*x - w^2*cos(w*t)*y"
        );
    }

    #[test]
    fn a_velocity_row_that_a_position_constraint_implies_is_left_out_with_a_warning() {
        // The bead's speed along the radius is zero because its distance is fixed: the second
        // constraint says again, at the velocity level, what the first says.
        let source = "
param m, L, g
coord x = 1, y = 0
particle bead { mass m; position (x, y) }
gravity g
constraint ring: x^2 + y^2 = L^2
constraint radial: x*x' + y*y' = 0
constraint skewed: x*y' - y*x' = 0
";
        let d = derived(source);
        let kept: Vec<&str> =
            d.multipliers.iter().map(|m| d.model.constraints[m.constraint].name.as_str()).collect();
        assert_eq!(kept, ["ring", "skewed"]);
        assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
        assert!(d.warnings[0].message.contains("`radial` restrains nothing more"));
        assert!(d.warnings[0].label.contains("time derivative of `ring`"));
    }
}
