//! The last phase of a derivation: the reactions the scene asks for. An eliminated
//! constraint's comes from the Euler–Lagrange equation of the coordinate it removed; a kept
//! one's is its multiplier, solved for once the whole system is known.

use std::collections::HashMap;

use cas::{linear_system, ExprId, Pool, SymId};
use lang::Diagnostic;
use model::Model;

use super::eliminate::Coordinates;
use super::energies::Energies;
use super::equations::generalized_force;
use super::rows::reaction_direction;
use super::{Derivation, Elimination, Multiplier, Reaction, SYMBOLIC_SOLVE_LIMIT};

/// The reactions of the eliminated constraints that the scene asks for, from energies in all
/// declared coordinates; none when it asks for none. `Err` is the warning that they cannot be
/// separated (the constraints' gradients along the eliminated coordinates are dependent).
pub(super) fn eliminated_reactions(
    pool: &mut Pool,
    model: &Model,
    full: &Energies,
    coordinates: &Coordinates,
    eliminated: &[Elimination],
    multipliers: &[Multiplier],
) -> Result<Vec<Reaction>, Diagnostic> {
    let mut reactions = Vec::new();
    let requested = eliminated.iter().any(|e| model.constraints[e.constraint].force_requested);
    if !requested {
        return Ok(reactions);
    }
    let elimination_map = &coordinates.elimination_map;
    // For each eliminated coordinate e: d/dt ∂L/∂ė − ∂L/∂e − Q_e = Σ_c λ_c ∂Φ_c/∂e, all
    // in the full coordinates, then expressed in the remaining ones.
    let k = eliminated.len();
    let mut a = vec![vec![pool.zero(); k]; k];
    let mut b = Vec::with_capacity(k);
    let identity: HashMap<SymId, ExprId> = HashMap::new();
    for (row, e) in eliminated.iter().enumerate() {
        let rate = pool.rate(e.coord).expect("coordinate");
        let p = pool.diff(full.lagrangian, rate);
        let dp = pool.time_derivative(p);
        let dl = pool.diff(full.lagrangian, e.coord);
        let q_force = generalized_force(pool, model, full.dissipation, e.coord, &identity);
        let lhs = pool.sub(dp, dl);
        let mut lhs = pool.sub(lhs, q_force);
        for m in multipliers {
            let c = &model.constraints[m.constraint];
            let dphi = reaction_direction(pool, c, e.coord);
            let lam = pool.sym(m.lambda);
            let t = pool.mul2(dphi, lam);
            lhs = pool.sub(lhs, t);
        }
        let lhs = pool.subst(lhs, elimination_map);
        b.push(pool.simplify(lhs));
        for (col, f) in eliminated.iter().enumerate() {
            let dphi = reaction_direction(pool, &model.constraints[f.constraint], e.coord);
            a[row][col] = pool.subst(dphi, elimination_map);
        }
    }
    let Some(lambdas) = linear_system::solve(pool, &a, &b) else {
        let c = &model.constraints[eliminated[0].constraint];
        return Err(Diagnostic::warning(
            c.span,
            "the reactions of these constraints cannot be separated",
        )
        .with_label("reaction not derived"));
    };
    for (e, expr) in eliminated.iter().zip(lambdas) {
        let c = &model.constraints[e.constraint];
        if c.force_requested {
            reactions.push(Reaction { constraint: e.constraint, symbol: c.force_symbol, expr });
        }
    }
    Ok(reactions)
}

impl Derivation {
    /// The reactions of constraints kept with multipliers, as expressions of the state: the
    /// multipliers of the solved system M q̈ − Jᵀλ = f, J q̈ = γ.
    pub(super) fn solve_multiplier_reactions(&mut self) {
        let wanted: Vec<usize> = (0..self.multipliers.len())
            .filter(|&i| self.model.constraints[self.multipliers[i].constraint].force_requested)
            .collect();
        let n = self.coords.len();
        if wanted.is_empty() || n + self.multipliers.len() > SYMBOLIC_SOLVE_LIMIT {
            return;
        }
        let Some(solved) = self.solved_unknowns() else { return };
        for i in wanted {
            let m = &self.multipliers[i];
            let expr = self.model.pool.factor_content(solved[&m.lambda]);
            self.reactions.push(Reaction { constraint: m.constraint, symbol: m.lambda, expr });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::eliminate::{eliminate_constraints, remaining_coordinates};
    use super::super::energies::energies;
    use super::super::multipliers::kept_constraints;
    use super::super::testing::{ascii, derived, scene, CARTESIAN_PENDULUM, FALLING_ROD};
    use super::*;

    /// The reactions of the eliminated constraints, with the phases before them run as
    /// `derive` runs them.
    fn reactions_of(source: &str) -> (Pool, Result<Vec<Reaction>, Diagnostic>) {
        let (mut pool, model) = scene(source);
        let out = eliminate_constraints(&mut pool, &model);
        let coordinates = remaining_coordinates(&mut pool, &model, &out.eliminated);
        let full = energies(&mut pool, &model);
        let (multipliers, _) = kept_constraints(&mut pool, &model, &out.kept, &coordinates);
        let reactions = eliminated_reactions(
            &mut pool,
            &model,
            &full,
            &coordinates,
            &out.eliminated,
            &multipliers,
        );
        (pool, reactions)
    }

    fn printed(pool: &Pool, reactions: &[Reaction]) -> Vec<String> {
        reactions
            .iter()
            .map(|r| format!("{} = {}", pool.symbol(r.symbol).name, ascii(pool, r.expr)))
            .collect()
    }

    #[test]
    fn the_floor_pushes_the_rod_up() {
        let (pool, reactions) = reactions_of(&format!("{FALLING_ROD}show floor.force"));
        assert_eq!(
            printed(&pool, &reactions.unwrap()),
            ["floor.force = -1/2*m*(L*sin(theta)*theta'' + L*cos(theta)*theta'^2 - 2*g)"]
        );
    }

    #[test]
    fn only_where_asked_for() {
        let (_, reactions) = reactions_of(FALLING_ROD);
        assert!(reactions.unwrap().is_empty());
    }

    #[test]
    fn two_eliminated_constraints_share_a_coordinate() {
        // x follows the cart s, y follows x: b's reaction pulls x too, so a's carries both.
        let (pool, reactions) = reactions_of(
            "param m, M, g\ncoord s\ncoord x\ncoord y\nparticle cart { mass M; position (s, 0) }\nparticle p { mass m; position (x, y) }\nconstraint a: x = s\nconstraint b: y = x\ngravity g\nshow a.force, b.force",
        );
        assert_eq!(
            printed(&pool, &reactions.unwrap()),
            ["a.force = m*(2*s'' + g)", "b.force = m*(s'' + g)"]
        );
    }

    #[test]
    fn a_kept_constraint_takes_its_share() {
        // The plane z = h holds the bob up against gravity, less the rod's pull along z.
        let (pool, reactions) = reactions_of(
            "param m, L, h, g\ncoord x\ncoord y\ncoord z\nparticle bob { mass m; position (x, y, z) }\nconstraint plane: z = h\nconstraint rod: x^2 + y^2 + z^2 = L^2\ngravity g\nshow plane.force",
        );
        assert_eq!(printed(&pool, &reactions.unwrap()), ["plane.force = m*g - 2*h*rod.force"]);
    }

    #[test]
    fn a_multiplier_is_solved_for_when_asked_for() {
        let mut d = derived(&format!("{CARTESIAN_PENDULUM}show rod.force"));
        let reactions = d.reactions.clone();
        assert_eq!(
            printed(d.pool(), &reactions),
            ["rod.force = -m*(x'^2 + y'^2 - g*y)/(2*x^2 + 2*y^2)"]
        );
    }
}
