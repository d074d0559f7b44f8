//! States the system can reach: random states projected onto the constraints kept with
//! multipliers (positions onto Φ = 0 by Gauss–Newton, rates onto Φ̇ = 0), so that numeric
//! checks sample only where a hand derivation that uses the constraints is entitled to hold,
//! and the rank of the constraint Jacobian there, which tells a repeated constraint.

use cas::{SymId, SymbolKind};
use lang::Diagnostic;
use mechanics::Derivation;
use nalgebra::{DMatrix, DVector};
use numeric::{Evaluator, ScaledEvaluator};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Gauss–Newton iterations before a start is given up.
const NEWTON_ITERATIONS: usize = 60;
/// |Φ| relative to the size of its terms below which a position is on the constraint.
const ON_CONSTRAINT: f64 = 1e-11;
/// A singular value this small relative to the largest is a lost rank.
const RANK_TOLERANCE: f64 = 1e-8;

/// The symbols a random state gives values to: parameters and inputs, time, coordinates and
/// rates.
pub(crate) fn state_symbols(d: &Derivation) -> Vec<SymId> {
    let pool = &d.model.pool;
    let mut syms: Vec<SymId> = d.model.constants().iter().map(|(s, _)| *s).collect();
    syms.push(d.model.time);
    syms.extend(d.coords.iter().copied());
    syms.extend(d.rates.iter().copied());
    syms.retain(|s| !matches!(pool.symbol(*s).kind, SymbolKind::Coordinate { order: 2.., .. }));
    syms
}

/// A state drawn at random, ignoring the constraints: parameters in [0.5, 2), t in [0, 1),
/// coordinates in [−1.2, 1.2), rates in [−1, 1), derived parameters then following the ones
/// they name ([`tie_derived`]). Everything else is NaN.
pub(crate) fn random_state(d: &Derivation, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let pool = &d.model.pool;
    let mut values = vec![f64::NAN; pool.symbol_count()];
    for s in state_symbols(d) {
        values[s.index()] = match pool.symbol(s).kind {
            SymbolKind::Param => rng.gen_range(0.5..2.0),
            SymbolKind::Time => rng.gen_range(0.0..1.0),
            SymbolKind::Coordinate { order: 0, .. } => rng.gen_range(-1.2..1.2),
            SymbolKind::Coordinate { .. } => rng.gen_range(-1.0..1.0),
        };
    }
    tie_derived(d, &mut values);
    values
}

/// Each derived parameter (`param w0 = sqrt(k/m)`) set from the values `values` (indexed by
/// symbol) gives the parameters it names, in declaration order, as every run sets it: drawn
/// apart from them, `expect x'' = -w0^2*x` would be judged where `w0` is not what the scene
/// says it is, and fail though it holds. A derived value that is not a real number there is
/// NaN, which the sample's test turns down.
pub(crate) fn tie_derived(d: &Derivation, values: &mut [f64]) {
    let params = &d.model.params;
    let mut plan = model::ParameterValues::new(&d.model);
    let derived = plan.derived();
    if derived.is_empty() {
        return;
    }
    let given: Vec<(usize, model::Given)> = plan
        .free()
        .into_iter()
        .map(|i| (i, model::Given::Number(values[params[i].sym.index()])))
        .collect();
    let all = plan.values(given).ok();
    for i in derived {
        values[params[i].sym.index()] = all.as_ref().map_or(f64::NAN, |v| v[i]);
    }
}

/// Up to `count` random admissible states, each a value per symbol of the derivation's pool
/// (parameters, time, coordinates and rates drawn as `check` draws them, then projected onto
/// the kept constraints; NaN elsewhere), from `4·count` draws at most. Seeded by `seed`, so a
/// caller gets the same states on every run.
pub fn admissible_states(d: &mut Derivation, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut constraints = ConstraintSet::first(d, d.multipliers.len());
    let mut states = Vec::with_capacity(count);
    for _ in 0..4 * count {
        if states.len() == count {
            break;
        }
        let mut values = random_state(d, &mut rng);
        if constraints.project(&mut values).is_ok() {
            states.push(values);
        }
    }
    states
}

/// Why a start could not be brought onto the constraints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Projection {
    /// The iteration settled where Φ is not zero: a least-squares minimum, where the
    /// constraints' gradients are dependent. No state nearby satisfies them all.
    Stalled,
    /// The iteration diverged or met a point where the expressions are undefined.
    Lost,
}

/// What the constraint machinery needs, per kept constraint, lowered once: Φ, its gradient
/// in the remaining coordinates, and ∂Φ/∂t (for the rate projection J·q̇ = −∂Φ/∂t).
pub(crate) struct ConstraintSet {
    count: usize,
    /// Φ of each constraint, with the size of its terms.
    phi: ScaledEvaluator,
    /// The Jacobian row after row, each entry with the size of its terms.
    jacobian: ScaledEvaluator,
    /// What J·q̇ leaves out of the rate-level residual: ∂Φ/∂t for a position constraint, b of
    /// A·q̇ + b for a velocity constraint.
    phi_t: Evaluator,
    /// The rows that restrain positions; the others restrain only rates.
    positional: Vec<usize>,
    /// Where the coordinates and the rates sit in a state.
    coords: Vec<usize>,
    rates: Vec<usize>,
}

impl ConstraintSet {
    /// The first `count` kept constraints of a derivation.
    pub(crate) fn first(d: &mut Derivation, count: usize) -> ConstraintSet {
        let time = d.model.time;
        let (mut phi, mut jacobian, mut phi_t) = (Vec::new(), Vec::new(), Vec::new());
        let mut positional = Vec::new();
        for (i, m) in d.multipliers.iter().take(count).enumerate() {
            phi.push(m.rows.phi());
            jacobian.extend(m.rows.jacobian.iter().copied());
            if m.rows.position.is_some() {
                positional.push(i);
            }
            phi_t.push(m.rows.rate_free(&mut d.model.pool, time, &d.rates));
        }
        let pool = &d.model.pool;
        ConstraintSet {
            count: phi.len(),
            phi: ScaledEvaluator::new(pool, &phi),
            jacobian: ScaledEvaluator::new(pool, &jacobian),
            phi_t: Evaluator::new(pool, &phi_t),
            positional,
            coords: d.coords.iter().map(|q| q.index()).collect(),
            rates: d.rates.iter().map(|q| q.index()).collect(),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.count == 0
    }

    fn jacobian_at(&mut self, values: &[f64]) -> DMatrix<f64> {
        let entries = self.jacobian.eval(values);
        DMatrix::from_fn(self.count, self.coords.len(), |i, j| entries[i * self.coords.len() + j].0)
    }

    /// Moves the coordinates of `values` onto Φ = 0 (the smallest step each time, so the state
    /// stays near its random start), then the rates onto Φ̇ = J·q̇ + ∂Φ/∂t = 0.
    pub(crate) fn project(&mut self, values: &mut [f64]) -> Result<(), Projection> {
        if self.is_empty() {
            return Ok(());
        }
        let mut converged = self.positional.is_empty();
        for _ in 0..if converged { 0 } else { NEWTON_ITERATIONS } {
            let mut worst = 0.0f64;
            let mut phi = DVector::zeros(self.positional.len());
            let all = self.phi.eval(values);
            for (row, &i) in self.positional.iter().enumerate() {
                let (v, scale) = all[i];
                if !v.is_finite() || !scale.is_finite() {
                    return Err(Projection::Lost);
                }
                phi[row] = v;
                worst = worst.max(v.abs() / (1.0 + scale));
            }
            if worst < ON_CONSTRAINT {
                converged = true;
                break;
            }
            let j = self.jacobian_at(values).select_rows(self.positional.iter());
            let step = min_norm_solve(j, &phi).ok_or(Projection::Lost)?;
            let size = step.amax();
            for (k, &slot) in self.coords.iter().enumerate() {
                values[slot] -= step[k];
            }
            // No progress while Φ stays away from zero: a least-squares minimum.
            let magnitude = self.coords.iter().fold(1.0f64, |m, &s| m.max(values[s].abs()));
            if size < 1e-12 * magnitude {
                return Err(Projection::Stalled);
            }
        }
        if !converged {
            return Err(Projection::Lost);
        }
        // Φ̇ (Φ itself for a velocity constraint) is linear in the rates: one minimum-norm
        // correction lands on it, a second cleans up rounding.
        for _ in 0..2 {
            let j = self.jacobian_at(values);
            let phi_t = self.phi_t.eval(values);
            let rates = &self.rates;
            let rhs = DVector::from_fn(self.count, |i, _| {
                let rate: f64 = (0..rates.len()).map(|k| j[(i, k)] * values[rates[k]]).sum();
                rate + phi_t[i]
            });
            if !rhs.iter().all(|x| x.is_finite()) {
                return Err(Projection::Lost);
            }
            let step = min_norm_solve(j, &rhs).ok_or(Projection::Lost)?;
            for (k, &slot) in self.rates.iter().enumerate() {
                values[slot] -= step[k];
            }
        }
        Ok(())
    }

    /// How far the rates of a projected state stay from the rate-level rows, relative to the
    /// size of their terms: 0 but for rounding, unless the rows contradict one another (the
    /// same combination of rates asked to take two values), where the projection can only
    /// come as close as least squares allow.
    pub(crate) fn rate_residual(&mut self, values: &[f64]) -> f64 {
        let j = self.jacobian_at(values);
        let phi_t = self.phi_t.eval(values).to_vec();
        let mut worst = 0.0f64;
        for (i, bias) in phi_t.iter().enumerate() {
            let terms: Vec<f64> =
                (0..self.rates.len()).map(|k| j[(i, k)] * values[self.rates[k]]).collect();
            let residual: f64 = terms.iter().sum::<f64>() + bias;
            let size = terms.iter().map(|t| t.abs()).sum::<f64>() + bias.abs();
            worst = worst.max(residual.abs() / (1.0 + size));
        }
        worst
    }

    /// The rank of the constraints' Jacobian at a state. Each row is measured against the size
    /// of the terms its entries are sums of, so a gradient that vanishes by cancellation
    /// (2·x − 2·L near x = L) counts as lost even though nothing else is larger.
    pub(crate) fn rank_at(&mut self, values: &[f64]) -> Option<usize> {
        let n = self.coords.len();
        let entries = self.jacobian.eval(values);
        let mut j = DMatrix::zeros(self.count, n);
        for i in 0..self.count {
            let mut size = 0.0f64;
            for k in 0..n {
                let (v, scale) = entries[i * n + k];
                if !v.is_finite() || !scale.is_finite() {
                    return None;
                }
                j[(i, k)] = v;
                size += scale * scale;
            }
            if size > 0.0 {
                j.row_mut(i).scale_mut(1.0 / size.sqrt());
            }
        }
        Some(j.singular_values().iter().filter(|s| **s > NORMALISED_RANK_TOLERANCE).count())
    }
}

/// A singular value of the row-normalised Jacobian below this is a lost rank. Loose, because
/// a position projected onto a double root (a squared constraint) is only accurate to the
/// square root of the projection's tolerance.
const NORMALISED_RANK_TOLERANCE: f64 = 1e-5;

/// The smallest x with j·x = b in the least-squares sense (the pseudo-inverse), which also
/// serves when the rows of j are dependent.
fn min_norm_solve(j: DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    if !j.iter().all(|x| x.is_finite()) {
        return None;
    }
    let svd = j.svd(true, true);
    let eps = RANK_TOLERANCE * svd.singular_values.amax();
    let x = svd.solve(b, eps).ok()?;
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Errors for a kept constraint that repeats the ones before it (its gradient is a
/// combination of theirs at every state that satisfies them all, so its multiplier cannot
/// be found) or contradicts them (no state satisfies them all). Tested one constraint at a
/// time, in order, so the first culprit is the one named.
/// A constraint that no start reaches gets a warning instead: Newton's method can miss a
/// constraint that does hold somewhere.
pub(crate) fn dependent_constraints(d: &mut Derivation) -> Vec<Diagnostic> {
    let mut rng = ChaCha8Rng::seed_from_u64(0xdebe_4d00);
    for k in 0..d.multipliers.len() {
        let mut set = ConstraintSet::first(d, k + 1);
        let (mut reached, mut stalled, mut full_rank) = (0, 0, false);
        let mut rates_off = false;
        for _ in 0..INDEPENDENCE_TRIES {
            let mut values = random_state(d, &mut rng);
            match set.project(&mut values) {
                Ok(()) => {
                    reached += 1;
                    rates_off |= set.rate_residual(&values) > 1e-8;
                    if set.rank_at(&values) == Some(k + 1) {
                        full_rank = true;
                        break;
                    }
                    if reached == 3 {
                        break;
                    }
                }
                Err(Projection::Stalled) => stalled += 1,
                Err(Projection::Lost) => {}
            }
        }
        if full_rank {
            continue;
        }
        if reached == 0 && stalled == 0 {
            let c = &d.model.constraints[d.multipliers[k].constraint];
            d.warnings.push(
                Diagnostic::warning(
                    c.span,
                    format!("no random start reached a state where `{}` holds", c.name),
                )
                .with_label(format!("tried from {INDEPENDENCE_TRIES} starts"))
                .with_hint("if no state satisfies it, the motion is undefined: check its signs and parameters"),
            );
            return Vec::new();
        }
        let c = &d.model.constraints[d.multipliers[k].constraint];
        let diagnostic = if reached > 0 && k == 0 {
            Diagnostic::error(
                c.span,
                format!("constraint `{}` has no gradient where it holds", c.name),
            )
            .with_label("∂Φ/∂q vanishes on Φ = 0")
            .with_hint("its force cannot be found; write it without the square, e.g. `x = L` rather than `(x - L)^2 = 0`")
        } else if reached > 0 && rates_off {
            Diagnostic::error(
                c.span,
                format!("constraint `{}` contradicts the ones before it", c.name),
            )
            .with_label("no motion satisfies it together with them")
            .with_hint(
                "at the velocity level it restrains the same combination of rates as they do \
                 (a position constraint restrains its time derivative), but asks another value \
                 of it: check its signs and parameters, or remove it",
            )
        } else if reached > 0 {
            Diagnostic::error(
                c.span,
                format!("constraint `{}` repeats the ones before it", c.name),
            )
            .with_label("its gradient is a combination of theirs")
            .with_hint(format!(
                "at every state tried that satisfies them, the constraints' Jacobian has rank {k}, not {}: remove `{}` or one it depends on",
                k + 1,
                c.name
            ))
        } else if k == 0 {
            Diagnostic::error(c.span, format!("constraint `{}` can never hold", c.name))
                .with_label("no state satisfies it")
                .with_hint("check its signs and parameters")
        } else {
            Diagnostic::error(
                c.span,
                format!("constraint `{}` contradicts the ones before it", c.name),
            )
            .with_label("no state satisfies it together with them")
            .with_hint("from every start tried, the closest the constraints come to holding leaves this one unmet: check its signs and parameters")
        };
        return vec![diagnostic];
    }
    Vec::new()
}

/// Random starts tried per constraint when testing their independence.
const INDEPENDENCE_TRIES: usize = 16;
