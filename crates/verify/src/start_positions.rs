//! The start's positions against the kept position constraints, in numbers: where the exact
//! test of `mechanics` found a constraint broken at the start, either the positions were given
//! to some digits and break it only by their rounding, or the scene left positions free (no
//! value, or a guess with `~`) for the constraints to fix, which Newton's method solves; or
//! the start is impossible, and that is an error at the constraint with its residual.

use cas::{ExprId, SymId};
use lang::Diagnostic;
use mechanics::Derivation;
use nalgebra::{DMatrix, DVector};
use numeric::Evaluator;

use crate::start::parameter_values;

/// A residual this small beside the magnitude of its terms is the rounding of start values
/// given to some digits (a position solved elsewhere and pasted in), not a different start.
const ROUNDING: f64 = 1e-9;

/// Where Newton's iteration stops: every residual within this share of its magnitude.
const CONVERGED: f64 = 1e-14;

/// Whether a constraint's residual at the start, beside the magnitude of its terms, is only
/// the rounding of values given to some digits. A residual that is not a number is not.
pub fn within_rounding(residual: f64, magnitude: f64) -> bool {
    residual.abs() <= ROUNDING * magnitude.max(f64::MIN_POSITIVE)
}

const ITERATIONS: usize = 60;

/// Settles a start that breaks a kept position constraint exactly (see the module's doc);
/// afterwards the start's rates are settled as the derivation settles them.
pub fn settle_start_positions(d: &mut Derivation) -> Result<(), Vec<Diagnostic>> {
    if !d.start_positions_pending {
        return Ok(());
    }
    let broken = d.start_position_residuals();
    let params = match parameter_values(d) {
        Ok(p) => p,
        Err(_) => {
            // Without values there is nothing to solve with. A scene that leaves the positions
            // a broken constraint restrains free and asks nothing at the start is after its
            // equations, not its start; otherwise the algebra's residual is the answer.
            let free = d.free_start_positions();
            let asks = d.model.shows.iter().any(|s| s.at_start)
                || d.model.expects.iter().any(|e| e.at_start);
            let all_free = broken.iter().all(|(c, _)| {
                let phi =
                    d.multipliers.iter().find(|m| m.constraint == *c).and_then(|m| m.rows.position);
                free.iter().any(|q| phi.is_some_and(|phi| d.model.pool.depends_on(phi, *q)))
            });
            if all_free && !asks {
                return Ok(());
            }
            return Err(broken.iter().map(|b| off_the_constraint(d, *b, None)).collect());
        }
    };
    let mut values = vec![f64::NAN; d.model.pool.symbol_count()];
    for (s, v) in &params {
        values[s.index()] = *v;
    }
    values[d.model.time.index()] = 0.0;
    let off: Vec<(usize, ExprId, f64)> = broken
        .iter()
        .filter_map(|(c, r)| {
            let (value, magnitude) = numeric::value_and_magnitude(&d.model.pool, *r, &values);
            (!within_rounding(value, magnitude)).then_some((*c, *r, value))
        })
        .collect();
    if off.is_empty() {
        // Rounded values are a start only at these parameter values.
        d.start_positions_pending = false;
        d.start_at_values_only = true;
        return d.settle_start_rates().map_err(|e| vec![e]);
    }
    let free = d.free_start_positions();
    if free.is_empty() {
        return Err(off
            .iter()
            .map(|(c, r, v)| off_the_constraint(d, (*c, *r), Some(*v)))
            .collect());
    }
    match solve_positions(d, &free, values, false) {
        Some(solved) => {
            let exact: Vec<(SymId, cas::Rational)> =
                solved.iter().filter_map(|(s, x)| Some((*s, shortest_decimal(*x)?))).collect();
            d.set_start_positions(&exact).map_err(|e| vec![e])
        }
        None => {
            let names: Vec<String> =
                free.iter().map(|s| format!("`{}`", d.model.pool.symbol(*s).name)).collect();
            let (c, _, value) = off[0];
            let constraint = &d.model.constraints[c];
            Err(vec![Diagnostic::error(
                constraint.span,
                format!("the start positions could not be solved from `{}`", constraint.name),
            )
            .with_label(format!(
                "at the start this side minus that is {value:.6e}, and Newton's method from there \
                 did not bring it to 0"
            ))
            .with_hint(format!(
                "give a guess near the start you mean for {}: `coord {} ~ …`",
                names.join(", "),
                d.model.pool.symbol(free[0]).name
            ))])
        }
    }
}

/// The shortest decimal that reads back as `x`, exactly: what a report prints of it.
fn shortest_decimal(x: f64) -> Option<cas::Rational> {
    let q = cas::number::parse_decimal(&format!("{:e}", x.abs()))?;
    Some(if x < 0.0 { -q } else { q })
}

/// The error for a start off a kept position constraint, with the residual in numbers where
/// there are numbers, and the coordinates that could be left for the constraint to fix.
fn off_the_constraint(
    d: &mut Derivation,
    (c, residual): (usize, ExprId),
    value: Option<f64>,
) -> Diagnostic {
    let constraint = d.model.constraints[c].clone();
    let shown = match value {
        Some(v) => format!("{v:.6e}"),
        None => {
            let r = d.model.pool.simplify(residual);
            d.model.pool.print(r, cas::Style::Ascii)
        }
    };
    let phi = d.multipliers.iter().find(|m| m.constraint == c).and_then(|m| m.rows.position);
    let pool = &mut d.model.pool;
    let restrained: Vec<SymId> = d
        .coords
        .iter()
        .copied()
        .filter(|q| phi.is_some_and(|phi| pool.depends_on(phi, *q)))
        .collect();
    let restrained: Vec<String> = restrained.iter().map(|q| pool.symbol(*q).name.clone()).collect();
    let hint = match restrained.last() {
        Some(q) => format!(
            "give start positions that satisfy it, or leave one that it restrains ({}) for \
             lagrange to solve: without a value (`coord {q}`) or with a guess (`coord {q} ~ …`)",
            restrained.iter().map(|r| format!("`{r}`")).collect::<Vec<_>>().join(", ")
        ),
        None => "give start positions that satisfy it".to_string(),
    };
    Diagnostic::error(
        constraint.span,
        format!("the start positions do not satisfy `{}`", constraint.name),
    )
    .with_label(format!("at the start this side minus that is {shown}, not 0"))
    .with_hint(hint)
}

/// Newton's method on all kept position constraints at t = 0 in the free positions, from the
/// start's values (guesses, or 0), with the least-squares step where there are more free
/// positions than constraints (the smallest step, so that guesses move as little as they
/// can). `None` if it does not converge.
///
/// `values` holds a value per symbol: the parameters' and t = 0 at least; the start's
/// positions are read from the scene unless `keep_positions` says they are set there already.
pub fn solve_positions(
    d: &mut Derivation,
    free: &[SymId],
    mut values: Vec<f64>,
    keep_positions: bool,
) -> Option<Vec<(SymId, f64)>> {
    let phis = d.kept_position_constraints();
    let mut jacobian = Vec::new();
    for phi in &phis {
        for q in free {
            jacobian.push(d.model.pool.diff(*phi, *q));
        }
    }
    let pool = &d.model.pool;
    let mut residuals = Evaluator::new(pool, &phis);
    let mut derivatives = Evaluator::new(pool, &jacobian);
    // The start's other positions, and the free ones' guesses (0 where none was given).
    for c in &d.model.coords {
        if d.coords.contains(&c.sym) && !keep_positions {
            values[c.sym.index()] = numeric::eval(pool, c.initial, &values);
        }
    }
    let magnitudes: Vec<f64> = phis
        .iter()
        .map(|phi| numeric::value_and_magnitude(pool, *phi, &values).1.max(1.0))
        .collect();
    let size = |r: &[f64]| -> f64 {
        r.iter().zip(&magnitudes).map(|(x, m)| (x / m).abs()).fold(0.0, f64::max)
    };
    let (rows, cols) = (phis.len(), free.len());
    for _ in 0..ITERATIONS {
        let r = residuals.eval(&values).to_vec();
        let now = size(&r);
        if !now.is_finite() {
            return None;
        }
        if now <= CONVERGED {
            return Some(free.iter().map(|q| (*q, values[q.index()])).collect());
        }
        let j = derivatives.eval(&values).to_vec();
        let j = DMatrix::from_row_slice(rows, cols, &j);
        let step = j.svd(true, true).solve(&-DVector::from_vec(r), 1e-12).ok()?;
        // Halve the step until the residual falls: Newton's full step may overshoot far from
        // the solution.
        let mut scale = 1.0;
        loop {
            let mut trial = values.clone();
            for (q, dq) in free.iter().zip(step.iter()) {
                trial[q.index()] += scale * dq;
            }
            let after = size(residuals.eval(&trial));
            if after < now || scale < 1e-6 {
                values = trial;
                break;
            }
            scale /= 2.0;
        }
    }
    None
}
