//! From a model to equations of motion: constraints eliminated or kept as multipliers, the
//! energies, the Euler–Lagrange equations in mass-matrix form, and reactions where asked for.

mod chain;
mod eliminate;
mod energies;
mod equations;
mod multipliers;
mod reactions;
mod rows;
mod start_positions;
mod start_rates;
mod structural;

use std::collections::HashMap;

use cas::{linear_system, ExprId, Pool, SymId};
use lang::Diagnostic;
use model::{Model, Placeholder, Value};

use crate::start_solution::StartSolution;

use eliminate::{eliminate_constraints, remaining_coordinates, Coordinates, Eliminated};
use energies::energies;
use equations::{coordinates_without_inertia, euler_lagrange_rows};
use multipliers::kept_constraints;
use reactions::eliminated_reactions;

pub use chain::{ChainForm, ChainNode};
pub use rows::{ConstraintRows, Stabilisation};

/// A constraint solved for one coordinate, which then leaves the equations.
#[derive(Clone, Debug)]
pub struct Elimination {
    pub constraint: usize,
    pub coord: SymId,
    /// The coordinate as a function of the remaining ones (and time).
    pub solution: ExprId,
    /// For a velocity constraint that integrates (constant coefficients), the position
    /// constraint Φ = 0 it integrates to, from the start.
    pub integrated: Option<ExprId>,
}

/// A constraint kept in the equations through its multiplier λ (its reaction), with
/// generalized force λ·Jᵀ, and its rows at every level.
#[derive(Clone, Debug)]
pub struct Multiplier {
    pub constraint: usize,
    pub lambda: SymId,
    /// Φ, the velocity row, J and γ, as the constraint's kind builds them.
    pub rows: ConstraintRows,
    /// The direction of its generalized force where that is not its row J: a slipping rough
    /// contact's, J_N − μ·s·J_T (Coulomb's force rides on the normal one).
    pub force: Option<Vec<ExprId>>,
}

impl Multiplier {
    /// The direction of its generalized force λ·(this): its row, unless friction bends it.
    pub fn force_direction(&self) -> &[ExprId] {
        self.force.as_deref().unwrap_or(&self.rows.jacobian)
    }
}

/// The reaction of an eliminated constraint, from the Euler–Lagrange equation of the
/// coordinate it removed. In terms of coordinates, rates, accelerations (and multipliers).
#[derive(Clone, Debug)]
pub struct Reaction {
    pub constraint: usize,
    pub symbol: SymId,
    pub expr: ExprId,
}

/// Everything derived from a model. Owns the model (and with it the expression pool).
#[derive(Clone)]
pub struct Derivation {
    pub model: Model,
    /// The coordinates left after elimination, in declaration order.
    pub coords: Vec<SymId>,
    pub rates: Vec<SymId>,
    pub accels: Vec<SymId>,
    pub eliminated: Vec<Elimination>,
    pub multipliers: Vec<Multiplier>,
    /// Every contact's rows, open or closed at the start (those closed are among the
    /// multipliers too).
    pub contacts: Vec<crate::ContactRows>,
    /// q, q̇ and q̈ of each eliminated coordinate, as expressions of the remaining ones.
    pub elimination_map: HashMap<SymId, ExprId>,
    pub kinetic: ExprId,
    pub potential: ExprId,
    pub lagrangian: ExprId,
    /// Generalized forces of the applied forces, torques and dissipation.
    pub generalized_forces: Vec<ExprId>,
    /// M(q, t), with M·q̈ = f (+ Jᵀλ when there are multipliers).
    pub mass_matrix: Vec<Vec<ExprId>>,
    pub forcing: Vec<ExprId>,
    pub reactions: Vec<Reaction>,
    pub warnings: Vec<Diagnostic>,
    /// q̈ and λ solved symbolically, for small systems; computed on first use.
    pub(crate) solved: Option<Option<HashMap<SymId, ExprId>>>,
    /// The unknowns at the start; computed on first use.
    pub(crate) start: Option<StartSolution>,
    /// The start breaks a kept position constraint exactly: the `verify` crate decides in
    /// numbers whether that is the rounding of values given to some digits, or solves the free
    /// positions, before the start's rates are settled.
    pub start_positions_pending: bool,
    /// Coordinates whose start positions were solved in numbers from the kept constraints.
    pub solved_start_positions: Vec<SymId>,
    /// The start's rates break a kept constraint: the error, held for `verify` to report
    /// unless a contradiction between the constraints explains it.
    pub start_rates_error: Option<Diagnostic>,
    /// The start satisfies the kept constraints only at the parameters' values, or was solved
    /// there in numbers: what is decided at the start is decided at those values, not at
    /// random ones.
    pub start_at_values_only: bool,
    /// What the recursive form is built from, kept from the rows ([`Derivation::chain_form`]).
    structure: Option<equations::Structure>,
}

impl Derivation {
    pub fn pool(&mut self) -> &mut Pool {
        &mut self.model.pool
    }

    /// The unknowns of one instant: accelerations, then multipliers.
    pub fn unknowns(&self) -> Vec<SymId> {
        let mut u = self.accels.clone();
        u.extend(self.multipliers.iter().map(|m| m.lambda));
        u
    }

    /// The rows of the full linear system in the unknowns: `rows · u = rhs`.
    /// First the equations of motion (M q̈ − Jᵀλ = f), then the constraints (J q̈ = γ).
    pub fn system(&mut self) -> (Vec<Vec<ExprId>>, Vec<ExprId>) {
        let n = self.coords.len();
        let mut rows = Vec::new();
        let mut rhs = Vec::new();
        for i in 0..n {
            let mut row = self.mass_matrix[i].clone();
            for m in &self.multipliers {
                let j = m.force_direction()[i];
                row.push(self.model.pool.neg(j));
            }
            rows.push(row);
            rhs.push(self.forcing[i]);
        }
        for m in &self.multipliers {
            let mut row = m.rows.jacobian.clone();
            row.extend(std::iter::repeat_n(self.model.pool.zero(), self.multipliers.len()));
            rows.push(row);
            rhs.push(m.rows.bias);
        }
        (rows, rhs)
    }

    /// Each kept constraint at the velocity level, in the multipliers' order: Φ̇ of a position
    /// constraint, Φ of a velocity one (linear in the rates either way).
    pub fn velocity_rows(&self) -> Vec<ExprId> {
        self.multipliers.iter().map(|m| m.rows.velocity).collect()
    }

    /// Replaces KE, PE and reactions by what they are, and eliminated coordinates by their
    /// solutions. With `keep_multipliers`, the reactions of constraints kept with multipliers
    /// stay the unknowns λ of the equations of motion (as checks want them), rather than their
    /// solved forms (as `show` wants them).
    pub fn expand_quantities(&mut self, e: ExprId, keep_multipliers: bool) -> ExprId {
        let kept: Vec<usize> = if keep_multipliers {
            self.multipliers.iter().map(|m| m.constraint).collect()
        } else {
            Vec::new()
        };
        let mut map: HashMap<SymId, ExprId> = HashMap::new();
        // What each placeholder a rate is taken of stands for, in the state: its rate is the
        // time derivative of that. A rate is always made after what it differentiates.
        let mut in_state: HashMap<SymId, ExprId> = HashMap::new();
        let differentiated: Vec<SymId> = self
            .model
            .placeholders
            .iter()
            .filter_map(|(_, k)| match k {
                Placeholder::Rate { of, .. } => Some(*of),
                _ => None,
            })
            .collect();
        for (s, kind) in self.model.placeholders.clone() {
            let value = match kind {
                Placeholder::KineticEnergy => Some(self.kinetic),
                Placeholder::PotentialEnergy => Some(self.potential),
                Placeholder::Reaction(c) if kept.contains(&c) => None,
                Placeholder::Reaction(c) => {
                    self.reactions.iter().find(|r| r.constraint == c).map(|r| r.expr)
                }
                Placeholder::Rate { of, .. } => in_state.get(&of).map(|base| {
                    let d = self.model.pool.time_derivative(*base);
                    self.model.pool.subst(d, &self.elimination_map)
                }),
            };
            if differentiated.contains(&s) {
                let form = match kind {
                    Placeholder::Reaction(c) => self.reaction_in_state(c),
                    _ => value,
                };
                if let Some(f) = form {
                    in_state.insert(s, f);
                }
            }
            if let Some(v) = value {
                map.insert(s, v);
            }
        }
        let e = self.model.pool.subst(e, &map);
        self.model.pool.subst(e, &self.elimination_map)
    }

    /// A reaction as an expression of the state (positions, rates, time), with the
    /// accelerations and multipliers solved for: what its time derivative is taken of.
    /// `None` where the system is too large for the symbolic solve.
    pub fn reaction_in_state(&mut self, constraint: usize) -> Option<ExprId> {
        let solved = self.solved_unknowns()?;
        let m = self.multipliers.iter().find(|m| m.constraint == constraint);
        let e = match m {
            Some(m) => return solved.get(&m.lambda).copied(),
            None => self.reactions.iter().find(|r| r.constraint == constraint)?.expr,
        };
        let x = self.model.pool.subst(e, &solved);
        let x = self.model.pool.subst(x, &self.elimination_map);
        Some(self.model.pool.together(x))
    }

    pub fn expand_value(&mut self, v: &Value, keep_multipliers: bool) -> Value {
        v.map(|e| self.expand_quantities(e, keep_multipliers))
    }

    /// The initial state: each remaining coordinate and rate at its `coord` value, t = 0.
    pub fn initial_state(&mut self) -> HashMap<SymId, ExprId> {
        let mut state = HashMap::new();
        let time = self.model.time;
        state.insert(time, self.model.pool.zero());
        for c in self.model.coords.clone() {
            if !self.coords.contains(&c.sym) {
                continue;
            }
            state.insert(c.sym, c.initial);
            let rate = self.model.pool.rate(c.sym).expect("coordinate");
            state.insert(rate, c.initial_rate);
        }
        state
    }

    /// Accelerations and multipliers as expressions of the state, for systems small enough
    /// (at most four unknowns) that the symbolic solution stays readable.
    pub fn solved_unknowns(&mut self) -> Option<HashMap<SymId, ExprId>> {
        if self.solved.is_none() {
            let unknowns = self.unknowns();
            let result = if unknowns.is_empty() || unknowns.len() > SYMBOLIC_SOLVE_LIMIT {
                None
            } else {
                let (rows, rhs) = self.system();
                linear_system::solve(&mut self.model.pool, &rows, &rhs)
                    .map(|x| unknowns.into_iter().zip(x).collect())
            };
            self.solved = Some(result);
        }
        self.solved.clone().flatten()
    }

    /// An expression with accelerations and multipliers replaced by their solved forms, where
    /// the system is small enough to have them; unchanged otherwise.
    pub fn of_state(&mut self, e: ExprId) -> ExprId {
        match self.solved_unknowns() {
            Some(map) => {
                let x = self.model.pool.subst(e, &map);
                self.model.pool.together(x)
            }
            None => e,
        }
    }
}

/// Derives the equations of motion of a model, phase by phase: constraints eliminated where
/// they can be solved for a coordinate, the energies, the Euler–Lagrange rows, the kept
/// constraints' multipliers, the reactions of the eliminated ones; then the checks that need
/// the whole derivation.
pub fn derive(mut model: Model) -> Result<Derivation, Vec<Diagnostic>> {
    // The phases build expressions while reading the rest of the model; holding the pool apart
    // meanwhile lets each borrow both. Their order matters beyond what each needs: the pool
    // numbers expressions as it builds them and some ties (in simplification, in printing) go
    // by those numbers, so building in another order could print the same equations otherwise.
    let mut pool = std::mem::take(&mut model.pool);
    let Eliminated { eliminated, kept, mut errors } = eliminate_constraints(&mut pool, &model);
    let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
    let full = energies(&mut pool, &model);
    let reduced = full.reduced(&mut pool, &coordinates.elimination_map);
    let rows = euler_lagrange_rows(&mut pool, &model, &full, &reduced, &coordinates);
    errors.extend(coordinates_without_inertia(&mut pool, &model, &coordinates.coords, &rows));
    let (multipliers, implied) = kept_constraints(&mut pool, &model, &kept, &coordinates);
    if !errors.is_empty() {
        return Err(errors);
    }
    let mut warnings = implied;
    let reactions = match eliminated_reactions(
        &mut pool,
        &model,
        &full,
        &coordinates,
        &eliminated,
        &multipliers,
    ) {
        Ok(reactions) => reactions,
        Err(warning) => {
            warnings.push(warning);
            Vec::new()
        }
    };
    model.pool = pool;

    let Coordinates { coords, rates, accels, elimination_map } = coordinates;
    let mut derivation = Derivation {
        model,
        coords,
        rates,
        accels,
        eliminated,
        multipliers,
        contacts: Vec::new(),
        elimination_map,
        kinetic: reduced.kinetic,
        potential: reduced.potential,
        lagrangian: reduced.lagrangian,
        generalized_forces: rows.generalized_forces,
        structure: Some(rows.structure),
        mass_matrix: rows.mass_matrix,
        forcing: rows.forcing,
        reactions,
        warnings,
        solved: None,
        start: None,
        start_positions_pending: false,
        solved_start_positions: Vec::new(),
        start_rates_error: None,
        start_at_values_only: false,
    };
    derivation.separate_contacts()?;
    derivation.solve_multiplier_reactions();
    derivation.warn_about_overridden_initial_values();
    derivation.reaction_rates_exist()?;
    if derivation.start_position_residuals().is_empty() {
        // Rates that break a kept constraint may be a constraint that contradicts another,
        // which `verify` tells in numbers: it reports this only if nothing explains it better.
        derivation.start_rates_error = derivation.settle_start_rates().err();
    } else {
        derivation.start_positions_pending = true;
    }
    Ok(derivation)
}

impl Derivation {
    /// A rate of a reaction is the derivative of the reaction as an expression of the state,
    /// which exists only where the full system is solved symbolically.
    fn reaction_rates_exist(&mut self) -> Result<(), Vec<Diagnostic>> {
        let mut errors = Vec::new();
        for (_, kind) in self.model.placeholders.clone() {
            let Placeholder::Rate { of, span } = kind else { continue };
            let Some(Placeholder::Reaction(c)) = self.model.placeholder(of) else { continue };
            if self.reaction_in_state(c).is_some() {
                continue;
            }
            let name = self.model.pool.symbol(of).name.clone();
            let unknowns = self.unknowns().len();
            errors.push(
                Diagnostic::error(span, format!("the rate of `{name}` is not available"))
                    .with_label("needs the reaction as an expression of the state")
                    .with_hint(format!(
                        "lagrange solves for the accelerations and reactions symbolically only up \
                         to {SYMBOLIC_SOLVE_LIMIT} unknowns, and this scene has {unknowns}"
                    )),
            );
        }
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }
}

/// Past this many unknowns the symbolic solution of the full system is too large to be worth
/// printing; the reactions of kept constraints then stay multipliers, found numerically.
const SYMBOLIC_SOLVE_LIMIT: usize = 4;

#[cfg(test)]
pub(crate) mod testing {
    //! Small scenes for the phases' tests, and their expressions as text.

    use cas::{ExprId, Pool, Style, SymId};
    use model::Model;

    /// Problem set 5's rod: its end on the floor is a constraint solved for y.
    pub const FALLING_ROD: &str = "
param m, L, g
coord x
coord y
coord theta
body rod { mass m; inertia m*L^2/12; position (x, y); angle theta }
constraint floor: y = L/2*cos(theta)
gravity g
";

    /// A pendulum in x and y: its rod is a constraint kept with a multiplier.
    pub const CARTESIAN_PENDULUM: &str = "
param m, L, g
coord x
coord y
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";

    /// The model of a scene, with its pool held apart as `derive` holds it during the phases.
    pub fn scene(source: &str) -> (Pool, Model) {
        let ast = lang::parse(source).expect("the scene parses");
        let (mut model, _warnings) = model::resolve(&ast, source).expect("the scene resolves");
        let pool = std::mem::take(&mut model.pool);
        (pool, model)
    }

    /// A scene derived whole.
    pub fn derived(source: &str) -> super::Derivation {
        let ast = lang::parse(source).expect("the scene parses");
        let (model, _warnings) = model::resolve(&ast, source).expect("the scene resolves");
        super::derive(model).expect("the scene derives")
    }

    pub fn ascii(pool: &Pool, e: ExprId) -> String {
        pool.print(e, Style::Ascii)
    }

    pub fn names(pool: &Pool, syms: &[SymId]) -> Vec<String> {
        syms.iter().map(|s| pool.symbol(*s).name.clone()).collect()
    }

    /// The coordinate declared with this name.
    pub fn coord(model: &Model, name: &str) -> SymId {
        let found = model.coords.iter().find(|c| c.name == name);
        found.unwrap_or_else(|| panic!("no coordinate `{name}`")).sym
    }
}

#[cfg(test)]
mod tests {
    use super::testing::{ascii, derived, CARTESIAN_PENDULUM};

    #[test]
    fn the_full_system_stacks_the_constraint_rows_under_the_equations() {
        let mut d = derived(CARTESIAN_PENDULUM);
        assert_eq!(d.unknowns().len(), 3);
        let (rows, rhs) = d.system();
        let pool = d.pool();
        let rows: Vec<Vec<String>> =
            rows.iter().map(|r| r.iter().map(|e| ascii(pool, *e)).collect()).collect();
        let rhs: Vec<String> = rhs.iter().map(|e| ascii(pool, *e)).collect();
        assert_eq!(rows, [["m", "0", "-2*x"], ["0", "m", "-2*y"], ["2*x", "2*y", "0"]]);
        assert_eq!(rhs, ["0", "-m*g", "-2*x'^2 - 2*y'^2"]);
    }
}
