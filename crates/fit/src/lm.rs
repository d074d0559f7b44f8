//! Levenberg–Marquardt on the problem's residuals, with Marquardt's scaling by the diagonal
//! of JᵀJ (kept at its largest, as Moré advises, so that a column that once mattered keeps its
//! scale), Nielsen's update of the damping, bounds by projection, and multiple shooting's
//! continuity kept exactly at each step: the damped step solves the linearized residuals in
//! least squares subject to the linearized gaps being zero (a KKT system), and steps are
//! judged by a merit of the cost and the gaps' ℓ₁ norm.

use nalgebra::{DMatrix, DVector};

use crate::problem::{Evaluation, Problem};
use crate::Error;

/// Why the iteration ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// The step fell below the tolerance relative to the unknowns.
    Step,
    /// The cost stopped falling, to rounding.
    Cost,
    /// The gradient vanished.
    Gradient,
    /// The iterations allowed were spent.
    Iterations,
    /// No step within the damping's range lowered the cost.
    Stalled,
}

impl Ending {
    pub fn words(self) -> &'static str {
        match self {
            Ending::Step => "converged: the step is below 1e-10 of the unknowns",
            Ending::Cost => "converged: the cost no longer falls",
            Ending::Gradient => "converged: the gradient vanishes",
            Ending::Iterations => "stopped: the iterations allowed were spent",
            Ending::Stalled => "stopped: no step lowers the cost any more",
        }
    }

    pub fn converged(self) -> bool {
        matches!(self, Ending::Step | Ending::Cost | Ending::Gradient)
    }
}

pub struct Solution {
    pub unknowns: Vec<f64>,
    pub evaluation: Evaluation,
    pub initial_cost: f64,
    /// Jacobians taken: one per accepted step, and the first.
    pub iterations: usize,
    /// Runs, each with its residuals and Jacobian.
    pub evaluations: usize,
    pub ending: Ending,
    pub steps: usize,
}

const STEP_TOLERANCE: f64 = 1e-10;
const COST_TOLERANCE: f64 = 1e-15;
/// The gaps count as closed below this, relative to the state's scale.
const GAP_TOLERANCE: f64 = 1e-9;

/// ½‖r‖².
fn cost(e: &Evaluation) -> f64 {
    0.5 * e.residuals.iter().map(|r| r * r).sum::<f64>()
}

fn gap_norm(e: &Evaluation) -> f64 {
    e.gaps.iter().map(|g| g.abs()).sum()
}

/// The gaps' weight as residuals while the shots are joined by penalty, relative to the
/// largest column weight: strong enough that the penalized optimum lies within the linear
/// reach of the exact joins, mild enough that Levenberg–Marquardt's damping governs the
/// shots' first moves, far from joined.
const GAP_WEIGHT: f64 = 1e3;
/// Newton steps on the exact joins after the penalized fit.
const JOINING_STEPS: usize = 10;

/// Minimizes the problem's cost from `start` within `bounds` (per unknown, lower and upper).
/// With several shots, first with the gaps as heavily weighted residuals (a penalty, which
/// Levenberg–Marquardt's damping carries through the nonlinear start), then by constrained
/// Gauss–Newton steps that close the gaps exactly.
pub fn solve(
    problem: &mut Problem,
    start: Vec<f64>,
    bounds: &[(f64, f64)],
    iterations_allowed: usize,
) -> Result<Solution, Error> {
    if problem.width() == problem.free() {
        return levenberg(problem, start, bounds, iterations_allowed, None);
    }
    let weight = GAP_WEIGHT * problem.weights.iter().copied().fold(0.0, f64::max);
    let penalized = levenberg(problem, start, bounds, iterations_allowed, Some(weight))?;
    join(problem, penalized, bounds)
}

/// The evaluation with its gaps moved among the residuals, weighted by `weight`.
fn penalized(mut e: Evaluation, weight: Option<f64>) -> Evaluation {
    if let Some(w) = weight {
        e.residuals.extend(e.gaps.drain(..).map(|g| w * g));
        e.jacobian.extend(e.gap_jacobian.drain(..).map(|g| w * g));
    }
    e
}

/// Constrained Gauss–Newton steps from the penalized optimum until the gaps are closed: each
/// taken whole where it lowers the gaps (it is near the joined optimum, in the linear reach).
fn join(problem: &mut Problem, mut s: Solution, bounds: &[(f64, f64)]) -> Result<Solution, Error> {
    let width = problem.width();
    let mut e = problem.evaluate(&s.unknowns)?;
    s.evaluations += 1;
    let scale_of_state = 1.0 + s.unknowns.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for _ in 0..JOINING_STEPS {
        if gap_norm(&e) <= 1e-3 * GAP_TOLERANCE * scale_of_state {
            break;
        }
        let rows = e.residuals.len();
        let j = DMatrix::from_row_slice(rows, width, &e.jacobian);
        let r = DVector::from_column_slice(&e.residuals);
        let normal = j.transpose() * &j;
        let gradient = j.transpose() * &r;
        let scale: Vec<f64> = (0..width).map(|k| normal[(k, k)].max(f64::MIN_POSITIVE)).collect();
        let Some((delta, _)) = damped_step(&normal, &gradient, &e, width, &scale, 0.0) else {
            break;
        };
        let mut trial: Vec<f64> = s.unknowns.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
        for (v, (lo, hi)) in trial.iter_mut().zip(bounds) {
            *v = v.clamp(*lo, *hi);
        }
        let Ok(next) = problem.evaluate(&trial) else { break };
        s.evaluations += 1;
        s.steps += next.steps;
        if gap_norm(&next) >= gap_norm(&e) {
            break;
        }
        s.unknowns = trial;
        s.iterations += 1;
        e = next;
    }
    if gap_norm(&e) > GAP_TOLERANCE * scale_of_state {
        s.ending = Ending::Stalled;
    }
    s.evaluation = e;
    Ok(s)
}

/// Levenberg–Marquardt from `start`; with `gap_weight`, the gaps are residuals so weighted.
fn levenberg(
    problem: &mut Problem,
    start: Vec<f64>,
    bounds: &[(f64, f64)],
    iterations_allowed: usize,
    gap_weight: Option<f64>,
) -> Result<Solution, Error> {
    let width = problem.width();
    let mut x = start;
    let first = problem.evaluate(&x)?;
    // The data's cost, not the penalty's.
    let initial_cost = cost(&first);
    let mut e = penalized(first, gap_weight);
    let mut evaluations = 1;
    let mut iterations = 1;
    let mut steps = e.steps;
    let mut scale = vec![0.0f64; width];
    let mut damping: Option<f64> = None;
    let mut growth = 2.0;
    let mut penalty = 0.0f64;
    let state_scale = 1.0 + x.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let ending = loop {
        let rows = e.residuals.len();
        let j = DMatrix::from_row_slice(rows, width, &e.jacobian);
        let r = DVector::from_column_slice(&e.residuals);
        let normal = j.transpose() * &j;
        let gradient = j.transpose() * &r;
        for (k, s) in scale.iter_mut().enumerate() {
            *s = s.max(normal[(k, k)]).max(f64::MIN_POSITIVE);
        }
        let gaps_closed = gap_norm(&e) <= GAP_TOLERANCE * state_scale;
        if gaps_closed && gradient.amax() <= 1e-15 * (1.0 + cost(&e)) {
            break Ending::Gradient;
        }
        // The damping multiplies `scale`, JᵀJ's diagonal, already: μ is relative to it, and
        // starts at 10⁻³ whatever the units. Scaled once more by the diagonal's largest (as
        // Nielsen starts an unscaled μ) it began at 5 (the pendulum) and 190 (the cart) and,
        // cut by at most 3 per accepted step, took some eight short steps to come down.
        let mu = *damping.get_or_insert(1e-3);
        let Some((delta, multipliers)) = damped_step(&normal, &gradient, &e, width, &scale, mu)
        else {
            damping = Some(mu * growth);
            growth *= 2.0;
            if mu > 1e20 {
                break Ending::Stalled;
            }
            continue;
        };
        penalty = penalty.max(2.0 * multipliers.iter().map(|v| v.abs()).fold(0.0, f64::max));
        let mut trial: Vec<f64> = x.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
        for (v, (lo, hi)) in trial.iter_mut().zip(bounds) {
            *v = v.clamp(*lo, *hi);
        }
        let taken = DVector::from_iterator(width, trial.iter().zip(&x).map(|(a, b)| a - b));
        let linear = &r + &j * &taken;
        let mut predicted = cost(&e) - 0.5 * linear.norm_squared();
        if !e.gaps.is_empty() {
            let c = DMatrix::from_row_slice(e.gaps.len(), width, &e.gap_jacobian);
            let after = DVector::from_column_slice(&e.gaps) + c * &taken;
            predicted += penalty * (gap_norm(&e) - after.iter().map(|g| g.abs()).sum::<f64>());
        }
        let merit = |e: &Evaluation| cost(e) + penalty * gap_norm(e);
        let step_small = taken
            .iter()
            .zip(&x)
            .all(|(d, v)| d.abs() <= STEP_TOLERANCE * (v.abs() + STEP_TOLERANCE));
        // A step this small cannot move the estimates past the tolerance: its run would
        // only confirm it (a full run with its sensitivities, a tenth of a small fit's time).
        if step_small && gap_norm(&e) <= GAP_TOLERANCE * state_scale {
            break Ending::Step;
        }
        let outcome = problem.evaluate(&trial).map(|e| penalized(e, gap_weight));
        evaluations += 1;
        let accepted = match outcome {
            Ok(next) if predicted > 0.0 || next.residuals.is_empty() => {
                let actual = merit(&e) - merit(&next);
                let ratio = actual / predicted;
                steps += next.steps;
                if ratio > 1e-4 {
                    let before = merit(&e);
                    x = trial;
                    e = next;
                    iterations += 1;
                    let lean = 2.0 * ratio - 1.0;
                    damping = Some(mu * (1.0 - lean * lean * lean).max(1.0 / 3.0));
                    growth = 2.0;
                    let closed = gap_norm(&e) <= GAP_TOLERANCE * state_scale;
                    if closed && step_small {
                        break Ending::Step;
                    }
                    if closed && actual <= COST_TOLERANCE * before {
                        break Ending::Cost;
                    }
                    true
                } else {
                    false
                }
            }
            Ok(next) => {
                steps += next.steps;
                false
            }
            // A step into values the scene refuses (a mass below zero) or a run that faults
            // is a step too long: the damping shortens it.
            Err(_) => false,
        };
        if !accepted {
            damping = Some(mu * growth);
            growth *= 2.0;
            if mu > 1e20 {
                break Ending::Stalled;
            }
        }
        if iterations >= iterations_allowed {
            break Ending::Iterations;
        }
    };
    Ok(Solution {
        unknowns: x,
        evaluation: e,
        initial_cost,
        iterations,
        evaluations,
        ending,
        steps,
    })
}

/// The damped Gauss–Newton step: min ‖r + J·δ‖² + μ·Σ scaleₖ·δₖ² subject to the gaps'
/// linearization c + C·δ = 0 where there are gaps; with the constraints' multipliers.
fn damped_step(
    normal: &DMatrix<f64>,
    gradient: &DVector<f64>,
    e: &Evaluation,
    width: usize,
    scale: &[f64],
    mu: f64,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let mut a = normal.clone();
    for (k, s) in scale.iter().enumerate() {
        a[(k, k)] += mu * s;
    }
    if e.gaps.is_empty() {
        let delta = a.cholesky()?.solve(&(-gradient));
        return delta.iter().all(|v| v.is_finite()).then_some((delta, DVector::zeros(0)));
    }
    let g = e.gaps.len();
    let c = DMatrix::from_row_slice(g, width, &e.gap_jacobian);
    let mut kkt = DMatrix::zeros(width + g, width + g);
    kkt.view_mut((0, 0), (width, width)).copy_from(&a);
    kkt.view_mut((0, width), (width, g)).copy_from(&c.transpose());
    kkt.view_mut((width, 0), (g, width)).copy_from(&c);
    let mut rhs = DVector::zeros(width + g);
    rhs.rows_mut(0, width).copy_from(&(-gradient));
    rhs.rows_mut(width, g).copy_from(&(-DVector::from_column_slice(&e.gaps)));
    let solution = kkt.full_piv_lu().solve(&rhs)?;
    if !solution.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some((solution.rows(0, width).into_owned(), solution.rows(width, g).into_owned()))
}
