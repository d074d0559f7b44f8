//! The first phase of a derivation: each constraint solved for one coordinate where it can
//! be, which then leaves the equations; the rest are kept for multipliers.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId, SymbolKind};
use lang::Diagnostic;
use model::Model;

use super::rows::eliminable;
use super::{Derivation, Elimination};

/// How the constraints were used.
#[derive(Debug)]
pub(super) struct Eliminated {
    /// In the order they were solved, each solution in the coordinates that remain.
    pub eliminated: Vec<Elimination>,
    /// The constraints no coordinate could be solved for, by index.
    pub kept: Vec<usize>,
    /// Constraints that the earlier ones imply.
    pub errors: Vec<Diagnostic>,
}

/// The coordinates left once the eliminated ones are gone, and what those are in terms of them.
#[derive(Debug)]
pub(super) struct Coordinates {
    /// In declaration order.
    pub coords: Vec<SymId>,
    pub rates: Vec<SymId>,
    pub accels: Vec<SymId>,
    /// q, q̇ and q̈ of each eliminated coordinate in terms of the rest.
    pub elimination_map: HashMap<SymId, ExprId>,
}

/// Solves each constraint, in order, for one coordinate it is linear in with a coefficient
/// that never vanishes as the system moves; one that has none is kept.
pub(super) fn eliminate_constraints(pool: &mut Pool, model: &Model) -> Eliminated {
    let declared: Vec<SymId> = model.coords.iter().map(|c| c.sym).collect();
    let mut solved: HashMap<SymId, ExprId> = HashMap::new();
    let mut eliminated: Vec<Elimination> = Vec::new();
    let mut kept: Vec<usize> = Vec::new();
    let mut errors = Vec::new();
    for (ci, c) in model.constraints.iter().enumerate() {
        let Some((written, integrated)) = eliminable(pool, model, c) else {
            kept.push(ci);
            continue;
        };
        let integrated = integrated.then_some(written);
        let phi = pool.subst(written, &solved);
        let phi = pool.expand(phi);
        if pool.is_identically_zero(phi) {
            errors.push(
                Diagnostic::error(
                    c.span,
                    format!("constraint `{}` is implied by the ones before it", c.name),
                )
                .with_label("redundant")
                .with_hint("remove it: it adds no condition"),
            );
            continue;
        }
        let free = pool.free_symbols(phi);
        // Prefer a coordinate written alone on the left (`y = …`), then the latest declared.
        let mut candidates: Vec<SymId> = c
            .lhs_coords
            .iter()
            .copied()
            .filter(|q| free.contains(q) && !solved.contains_key(q))
            .collect();
        for q in declared.iter().rev() {
            if free.contains(q) && !candidates.contains(q) && !solved.contains_key(q) {
                candidates.push(*q);
            }
        }
        let Some((q, sol)) = solve_for_one_of(pool, phi, &candidates) else {
            kept.push(ci);
            continue;
        };
        // Earlier solutions that mention q now use the new one.
        let single: HashMap<SymId, ExprId> = [(q, sol)].into_iter().collect();
        for v in solved.values_mut() {
            let s = pool.subst(*v, &single);
            *v = pool.simplify(s);
        }
        for e in eliminated.iter_mut() {
            e.solution = solved[&e.coord];
        }
        solved.insert(q, sol);
        eliminated.push(Elimination { constraint: ci, coord: q, solution: sol, integrated });
    }
    for e in eliminated.iter_mut() {
        e.solution = solved[&e.coord];
    }
    Eliminated { eliminated, kept, errors }
}

/// The first candidate that Φ = 0 can be solved for, with its solution: Φ must be linear in
/// it, with a coefficient that never vanishes as the system moves (parameters alone).
fn solve_for_one_of(pool: &mut Pool, phi: ExprId, candidates: &[SymId]) -> Option<(SymId, ExprId)> {
    for &q in candidates {
        let a = pool.diff(phi, q);
        let a = pool.simplify(a);
        let a_free = pool.free_symbols(a);
        let depends_on_motion =
            a_free.iter().any(|s| !matches!(pool.symbol(*s).kind, SymbolKind::Param));
        if depends_on_motion || pool.is_identically_zero(a) {
            continue;
        }
        // Φ = a·q + rest with a free of q, so q = −rest/a. Taking the rest by substitution,
        // not q − Φ/a, keeps q out of the solution even where a·q/a would not cancel
        // (a sum over a symbolic denominator such as a/(a − 1) − 1/(a − 1)).
        let zero = pool.zero();
        let rest = pool.subst(phi, &[(q, zero)].into_iter().collect());
        let step = pool.div(rest, a);
        let sol = pool.neg(step);
        return Some((q, pool.simplify(sol)));
    }
    None
}

/// The coordinates that remain, with their rates and accelerations, and the eliminated ones'
/// positions, rates and accelerations as expressions of them.
pub(super) fn remaining_coordinates(
    pool: &mut Pool,
    model: &Model,
    eliminated: &[Elimination],
) -> Coordinates {
    let coords: Vec<SymId> = model
        .coords
        .iter()
        .map(|c| c.sym)
        .filter(|q| !eliminated.iter().any(|e| e.coord == *q))
        .collect();
    let rates: Vec<SymId> = coords.iter().map(|q| pool.rate(*q).expect("coordinate")).collect();
    let accels: Vec<SymId> = rates.iter().map(|q| pool.rate(*q).expect("coordinate")).collect();
    let mut elimination_map: HashMap<SymId, ExprId> = HashMap::new();
    for e in eliminated {
        let v = pool.time_derivative(e.solution);
        let a = pool.time_derivative(v);
        let r = pool.rate(e.coord).expect("coordinate");
        let rr = pool.rate(r).expect("coordinate");
        elimination_map.insert(e.coord, e.solution);
        elimination_map.insert(r, v);
        elimination_map.insert(rr, a);
    }
    Coordinates { coords, rates, accels, elimination_map }
}

impl Derivation {
    /// An eliminated coordinate's initial value comes from its constraint; one written in the
    /// scene that disagrees with it would be silently ignored, so say so.
    pub(super) fn warn_about_overridden_initial_values(&mut self) {
        let mut state = self.initial_state();
        // Compare with the parameters' values, as the numbers will see them.
        for (sym, value) in self.model.constants() {
            if let Some(v) = value {
                state.insert(sym, v);
            }
        }
        for e in self.eliminated.clone() {
            let Some(c) = self.model.coords.iter().find(|c| c.sym == e.coord).cloned() else {
                continue;
            };
            if !c.initial_given {
                continue;
            }
            let pool = &mut self.model.pool;
            let implied = pool.subst(e.solution, &state);
            let implied = pool.simplify(implied);
            let given = pool.subst(c.initial, &state);
            let difference = pool.sub(given, implied);
            if pool.is_identically_zero(difference) {
                continue;
            }
            let constraint = self.model.constraints[e.constraint].name.clone();
            let text = pool.print(implied, cas::Style::Ascii);
            self.warnings.push(
                Diagnostic::warning(c.span, format!("the initial value of `{}` is ignored", c.name))
                    .with_label(format!("`{constraint}` fixes it at {text}"))
                    .with_hint(format!(
                        "the constraint `{constraint}` eliminates `{}`: drop its initial value, or make it {text}",
                        c.name
                    )),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{
        ascii, coord, derived, names, scene, CARTESIAN_PENDULUM, FALLING_ROD,
    };
    use super::*;

    #[test]
    fn the_floor_is_solved_for_y() {
        let (mut pool, model) = scene(FALLING_ROD);
        let out = eliminate_constraints(&mut pool, &model);
        assert!(out.errors.is_empty() && out.kept.is_empty());
        let [e] = &out.eliminated[..] else { panic!("{:?}", out.eliminated) };
        assert_eq!((e.constraint, e.coord), (0, coord(&model, "y")));
        assert_eq!(ascii(&pool, e.solution), "1/2*L*cos(theta)");
    }

    #[test]
    fn the_eliminated_coordinate_moves_with_the_rest() {
        let (mut pool, model) = scene(FALLING_ROD);
        let out = eliminate_constraints(&mut pool, &model);
        let c = remaining_coordinates(&mut pool, &model, &out.eliminated);
        assert_eq!(names(&pool, &c.coords), ["x", "theta"]);
        assert_eq!(names(&pool, &c.rates), ["x'", "theta'"]);
        assert_eq!(names(&pool, &c.accels), ["x''", "theta''"]);
        let y = coord(&model, "y");
        let y_rate = pool.rate(y).unwrap();
        let y_accel = pool.rate(y_rate).unwrap();
        let of = |s: SymId| ascii(&pool, c.elimination_map[&s]);
        assert_eq!(
            [of(y), of(y_rate), of(y_accel)],
            [
                "1/2*L*cos(theta)",
                "-1/2*L*sin(theta)*theta'",
                "-1/2*L*sin(theta)*theta'' - 1/2*L*cos(theta)*theta'^2"
            ]
        );
    }

    #[test]
    fn a_circle_is_kept() {
        let (mut pool, model) = scene(CARTESIAN_PENDULUM);
        let out = eliminate_constraints(&mut pool, &model);
        assert!(out.eliminated.is_empty() && out.errors.is_empty());
        assert_eq!(out.kept, [0]);
    }

    #[test]
    fn a_coordinate_alone_on_the_left_is_preferred() {
        let (mut pool, model) = scene("coord x\ncoord y\nconstraint c: x = 2*y");
        let out = eliminate_constraints(&mut pool, &model);
        assert_eq!(out.eliminated[0].coord, coord(&model, "x"));
        assert_eq!(ascii(&pool, out.eliminated[0].solution), "2*y");

        // Otherwise the latest declared.
        let (mut pool, model) = scene("coord x\ncoord y\nconstraint c: 2*y = x");
        let out = eliminate_constraints(&mut pool, &model);
        assert_eq!(out.eliminated[0].coord, coord(&model, "y"));
        assert_eq!(ascii(&pool, out.eliminated[0].solution), "x/2");
    }

    #[test]
    fn a_symbolic_coefficient_leaves_no_trace_of_the_coordinate() {
        // a·q = q − a gives q = −a/(a − 1); the solution must not mention q itself, which
        // q − Φ/a did when a/(a − 1) and 1/(a − 1) did not combine.
        let (mut pool, model) = scene("param a = 2\ncoord q\ncoord p\nconstraint c: q*a = q - a");
        let out = eliminate_constraints(&mut pool, &model);
        let [e] = &out.eliminated[..] else { panic!("{:?}", out.eliminated) };
        assert_eq!(e.coord, coord(&model, "q"));
        assert!(!pool.free_symbols(e.solution).contains(&e.coord), "{}", ascii(&pool, e.solution));
        let a = pool.free_symbols(e.solution);
        assert_eq!(a.len(), 1);
        let expected = {
            let a = pool.sym(a[0]);
            let one = pool.one();
            let a_minus_one = pool.sub(a, one);
            let quotient = pool.div(a, a_minus_one);
            pool.neg(quotient)
        };
        let difference = pool.sub(e.solution, expected);
        assert!(pool.is_identically_zero(difference), "{}", ascii(&pool, e.solution));
    }

    #[test]
    fn a_coefficient_that_moves_is_not_divided_by() {
        // Solving x*y = 1 for x would divide by y, which may pass through zero.
        let (mut pool, model) = scene("coord x\ncoord y\nconstraint c: x*y = 1");
        let out = eliminate_constraints(&mut pool, &model);
        assert!(out.eliminated.is_empty());
        assert_eq!(out.kept, [0]);
    }

    #[test]
    fn earlier_solutions_follow_later_ones() {
        let (mut pool, model) =
            scene("coord x\ncoord y\ncoord z\nconstraint a: x = y\nconstraint b: y = z + 1");
        let out = eliminate_constraints(&mut pool, &model);
        let solved: Vec<(String, String)> = out
            .eliminated
            .iter()
            .map(|e| (pool.symbol(e.coord).name.clone(), ascii(&pool, e.solution)))
            .collect();
        assert_eq!(solved, [("x".into(), "1 + z".into()), ("y".into(), "1 + z".into())]);
    }

    #[test]
    fn an_implied_constraint_is_an_error() {
        let (mut pool, model) =
            scene("param L\ncoord x\ncoord y\nconstraint a: y = L\nconstraint b: 2*y = 2*L");
        let out = eliminate_constraints(&mut pool, &model);
        assert_eq!(out.eliminated.len(), 1);
        assert!(out.kept.is_empty());
        let [e] = &out.errors[..] else { panic!("{:?}", out.errors) };
        assert_eq!(e.message, "constraint `b` is implied by the ones before it");
    }

    #[test]
    fn an_initial_value_the_constraint_overrides_is_warned_about() {
        let d = derived(
            "param m = 1 kg, L = 2 m\ncoord x = 0\ncoord y = 1 m\nparticle p { mass m; position (x, y) }\nconstraint floor: y = L",
        );
        let [w] = &d.warnings[..] else { panic!("{:?}", d.warnings) };
        assert_eq!(
            (w.message.as_str(), w.label.as_str()),
            ("the initial value of `y` is ignored", "`floor` fixes it at 2")
        );

        // One that agrees with it is not.
        let d = derived(
            "param m = 1 kg, L = 2 m\ncoord x = 0\ncoord y = 2 m\nparticle p { mass m; position (x, y) }\nconstraint floor: y = L",
        );
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    }
}
