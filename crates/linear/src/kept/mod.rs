//! Position and velocity constraints kept together (or more velocity constraints than the
//! independent rates' exact form takes). Exactly: M, C, K of all the coordinates, K with the
//! multipliers' symbols as in the holonomic case, the dependent rates left as symbols in every
//! matrix, and each constraint's row at the velocity level. In numbers (`reduce`): the
//! dependent rates solved from those rows, the multipliers and the accelerations at the
//! reference, and the reduction to the independent coordinates and rates.

mod reduce;

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;

use crate::reference::{self, Items, Placed};
use crate::signals;
use crate::{Case, LinearConstraint, Linearization, Signals};

pub(crate) use reduce::{at, Blocks};

/// What the kept case adds to a [`Linearization`]; the dependent rates stay symbols in its
/// matrices, for numbers to solve from the constraints' rows.
#[derive(Clone, Debug)]
pub struct Kept {
    /// The coordinates (indices into `coords`) whose rates the constraints fix at the
    /// reference: one per kept constraint, chosen as the independent rates' form chooses.
    pub dependent: Vec<usize>,
    pub constraints: Vec<LinearConstraint>,
    /// Each constraint's row at the velocity level, in the constraints' order.
    pub rows: Vec<VelocityRow>,
}

/// A kept constraint at the velocity level, with the dependent rates at 0 (so that it is J·q̇
/// of the given rates, and the rest).
#[derive(Clone, Debug)]
pub struct VelocityRow {
    /// Φ for a velocity constraint, Φ̇ for a position one.
    pub rate: ExprId,
    /// For a velocity constraint, ∂Φ/∂q: B of A·δq̇ + B·δq = 0. Empty for a position
    /// constraint, whose J·δq = 0 holds the positions instead.
    pub positions: Vec<ExprId>,
}

/// The reduction at one set of parameter values.
#[derive(Clone, Debug)]
pub struct Reduced {
    /// The dependent rates at the reference ([`Kept::dependent`], in its order).
    pub dependent_rates: Vec<f64>,
    /// G of δṗ = G·(δp, δu), one row per position kept.
    pub kinematics: Vec<Vec<f64>>,
    /// The coordinates (indices into `coords`) whose positions stay in the state, as the
    /// numbers chose them at these values.
    pub positions: Vec<usize>,
    /// The coordinates whose rates are the independent rates.
    pub rates: Vec<usize>,
}

/// Linearizes with position and velocity constraints kept together.
pub(crate) fn linearize(
    d: &mut Derivation,
    span: Span,
    items: &Items,
) -> Result<Linearization, Vec<Diagnostic>> {
    let n = d.coords.len();
    let rows = d.velocity_rows();
    let Some(dependent_rates) = d.dependent_rates(&rows) else {
        return Err(vec![Diagnostic::error(
            span,
            "the kept constraints' rows do not each restrain a rate of their own here",
        )
        .with_label("no dependent rate for every constraint")
        .with_hint("leave one rate per kept constraint without a value at the start")]);
    };
    let dependent: Vec<usize> =
        dependent_rates.iter().filter_map(|r| d.rates.iter().position(|x| x == r)).collect();
    let cyclic = reference::cyclic_flags(d);
    let pool = &mut d.model.pool;
    let (positions, mut map, mut errors) =
        substitution(pool, (&d.coords, &d.rates), items, &dependent, &cyclic);
    map.extend(signals::reference_inputs(&d.model.inputs));
    let missing: Vec<SymId> =
        (0..n).filter(|&i| !cyclic[i] && positions[i].is_none()).map(|i| d.coords[i]).collect();
    errors.extend(reference::missing_positions(pool, &missing, span, "a cyclic"));
    if !errors.is_empty() {
        return Err(errors);
    }

    // One memo for every substitution: the derivatives share most of their parts.
    let mut memo = HashMap::new();
    let mut at = |pool: &mut Pool, e: ExprId| {
        let e = pool.subst_memo(e, &map, &mut memo);
        pool.simplify(e)
    };
    let exact = reference::at_reference(d, &cyclic, &mut at);
    let pool = &mut d.model.pool;
    // The dependent rates at 0 in the rows that solve for them.
    let zero_dependent: HashMap<SymId, ExprId> =
        dependent.iter().map(|&i| (d.rates[i], pool.zero())).collect();
    let mut constraints = Vec::new();
    let mut velocity_rows = Vec::new();
    for (m, row) in d.multipliers.iter().zip(&rows) {
        let rate = at(pool, *row);
        let rate = pool.subst(rate, &zero_dependent);
        // A row of rates alone restrains the positions through its coefficients (B); a
        // position constraint's J·δq = 0 holds them instead.
        let positions = match m.rows.position {
            None => (0..n)
                .map(|i| match cyclic[i] {
                    true => pool.zero(),
                    false => {
                        let d = pool.diff(m.rows.velocity, d.coords[i]);
                        at(pool, d)
                    }
                })
                .collect(),
            Some(_) => Vec::new(),
        };
        let phi = at(pool, m.rows.phi());
        let phi = match m.rows.position {
            None => pool.subst(phi, &zero_dependent),
            Some(_) => phi,
        };
        constraints.push(LinearConstraint {
            constraint: m.constraint,
            positional: m.rows.position.is_some(),
            lambda: m.lambda,
            jacobian: m.rows.jacobian.iter().map(|e| at(pool, *e)).collect(),
            phi,
            bias: at(pool, m.rows.bias),
        });
        velocity_rows.push(VelocityRow { rate, positions });
    }
    let rates: Vec<ExprId> = (0..n)
        .map(|i| map.get(&d.rates[i]).copied().unwrap_or_else(|| pool.sym(d.rates[i])))
        .collect();

    let matrices = [&exact.mass[..], &exact.damping, &exact.stiffness];
    let more: Vec<ExprId> = velocity_rows.iter().flat_map(|r| r.positions.clone()).collect();
    let all = reference::all_of(matrices, &exact.residual, &constraints, &more);
    reference::refuse_time_dependence(pool, &all, d.model.time, span)?;

    let inputs: Vec<SymId> = d.model.inputs.iter().map(|u| u.sym).collect();
    let input_forces = signals::input_columns(pool, &d.forcing, &inputs, &mut at);
    let outputs = signals::output_rows(d, &mut at, None)?;
    let signals = Signals { inputs, input_forces, outputs };

    let placed = Placed { cyclic, positions, rates };
    let case = Case::Kept(Kept { dependent, constraints, rows: velocity_rows });
    // The multipliers' values, and so the residual's, are for numbers to find.
    Ok(Linearization::new(d.coords.clone(), placed, exact, false, (case, signals), span))
}

/// The reference's positions, the substitution its items make (the rates not given at 0 but
/// the dependent ones, a cyclic coordinate's position at 0 where none is given), and what is
/// wrong with the items.
fn substitution(
    pool: &mut Pool,
    (coords, rates): (&[SymId], &[SymId]),
    items: &Items,
    dependent: &[usize],
    cyclic: &[bool],
) -> (Vec<Option<ExprId>>, HashMap<SymId, ExprId>, Vec<Diagnostic>) {
    let mut errors = Vec::new();
    let mut positions = vec![None; coords.len()];
    let mut map: HashMap<SymId, ExprId> = HashMap::new();
    for ((coord, rate), (value, item_span)) in items {
        let Some(i) = coords.iter().position(|q| q == coord) else { continue };
        let name = pool.symbol_text(*coord, cas::Style::Unicode);
        if !*rate {
            positions[i] = Some(*value);
            map.insert(*coord, *value);
        } else if dependent.contains(&i) {
            errors.push(reference::dependent_given(*item_span, &name, "kept"));
        } else {
            map.insert(rates[i], *value);
            if !cyclic[i] && !pool.is_zero(*value) {
                let why = "cyclic: M, f or a constraint depends on it";
                errors.push(reference::moves(*item_span, &name, why, "cyclic coordinates"));
            }
        }
    }
    for (i, is_cyclic) in cyclic.iter().enumerate() {
        if !dependent.contains(&i) {
            map.entry(rates[i]).or_insert(pool.zero());
        }
        // A cyclic coordinate left in an expression too large to simplify does not change
        // its value (`is_cyclic`): any position stands for all.
        if *is_cyclic {
            map.entry(coords[i]).or_insert(pool.zero());
        }
    }
    (positions, map, errors)
}

#[cfg(test)]
mod tests {
    use crate::testing::derived;
    use crate::{Analysis, Component};

    /// A sleigh on its blade and, apart from it, a pendulum on its rod: a velocity and a
    /// position constraint kept together.
    const TWO: &str = "
param m = 1 kg, I = 1/10 kg*m^2, a = 1/5 m, v = 1 m/s, mb = 2 kg, L = 3/2 m, g = 9.81 m/s^2
coord x = 0, x' = v
coord y = 0
coord theta = 0, theta' = 0
coord u = 0, w = -L
body sleigh { mass m; inertia I; position (x + a*cos(theta), y + a*sin(theta)); angle theta }
particle bob { mass mb; position (u, w) }
constraint blade: y'*cos(theta) = x'*sin(theta)
constraint rod: u^2 + w^2 = L^2
potential mb*g*w
linearize about theta = 0, x' = v, u = 0, w = -L
";

    #[test]
    fn each_kept_constraint_brings_its_row_at_the_velocity_level() {
        let mut d = derived(TWO);
        let lin = crate::linearize(&mut d, true).expect("linearizes");
        let kept = lin.kept().expect("kept together");
        let positional: Vec<bool> = kept.constraints.iter().map(|c| c.positional).collect();
        assert_eq!(positional, [false, true]);
        // B of the blade's A·δq̇ + B·δq = 0 over the five coordinates; none for the rod.
        let widths: Vec<usize> = kept.rows.iter().map(|r| r.positions.len()).collect();
        assert_eq!(widths, [5, 0]);
        let pool = &d.model.pool;
        let dependent: Vec<&str> =
            kept.dependent.iter().map(|&i| pool.symbol(d.coords[i]).name.as_str()).collect();
        assert_eq!(dependent, ["y", "w"]);

        let parameters: Vec<cas::SymId> = d.model.params.iter().map(|p| p.sym).collect();
        let mut analysis = Analysis::new(&d, &parameters, lin).expect("lowers");
        let at = analysis.at(&[1.0, 0.1, 0.2, 1.0, 2.0, 1.5, 9.81]).expect("an equilibrium");
        let (positions, rates) = at.reduced().expect("reduced in numbers");
        assert_eq!((positions, rates), (vec![3], vec![0, 2, 3]));
        // δu, then the rates of x, θ and u.
        let expected =
            [Component::Position(3), Component::Rate(0), Component::Rate(2), Component::Rate(3)];
        assert_eq!(at.first_order.state, expected);
    }
}
