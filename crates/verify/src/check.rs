//! Checking `expect` lines: by the algebra of `mechanics` where it decides, otherwise at many
//! random states the system can reach (on its constraints), always saying which.

use cas::{ExprId, SymId};
use mechanics::{Decision, Derivation};
use numeric::ScaledEvaluator;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::admissible::{random_state, state_symbols, ConstraintSet};
use crate::start::StartSolver;
use crate::system::{solve_unknowns, System};

/// How many random states a numeric check uses.
pub const SAMPLES: usize = 24;
const RELATIVE_TOLERANCE: f64 = 1e-9;

/// The outcome of one `expect` line.
#[derive(Clone, Debug)]
pub enum Verdict {
    /// The residual simplifies to zero.
    Exact,
    /// The residual simplifies to zero once the kept constraints are used (x² = L² − y²).
    ExactOnConstraints,
    /// The algebra could not decide; the residual vanished at this many random states.
    Numeric { samples: usize, sampling: Sampling },
    /// The residual is not zero.
    Fails(Failure),
    /// Neither algebra nor numbers could decide (e.g. no state where everything is defined).
    Undecided { reason: String },
}

/// Where the random states of a numeric verdict came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Sampling {
    /// Anywhere: the system has no constraint kept with a multiplier.
    Anywhere,
    /// On the constraint surface: positions on Φ = 0, rates on Φ̇ = 0.
    OnConstraints,
    /// At the start, at random parameter values, with the unknowns of the start solved
    /// numerically (there were too many for the algebra).
    AtStart { unknowns: usize },
    /// At the start, at the parameters' values only (the start holds only there, or was
    /// solved there), with its unknowns solved numerically.
    AtStartValues { unknowns: usize },
}

#[derive(Clone, Debug)]
pub struct Failure {
    /// Which entry of a vector or matrix equation, if it has several.
    pub component: Option<usize>,
    /// lhs − rhs, simplified (with accelerations, where the equation has them).
    pub residual: ExprId,
    /// A state where the residual is not zero, and its value there.
    pub state: Vec<(SymId, f64)>,
    pub value: f64,
}

impl Verdict {
    pub fn holds(&self) -> bool {
        matches!(self, Verdict::Exact | Verdict::ExactOnConstraints | Verdict::Numeric { .. })
    }

    /// How it was decided, in the words of a `check` report ("holds exactly", "DOES NOT
    /// HOLD"); every front end says it alike.
    pub fn how(&self) -> String {
        match self {
            Verdict::Exact => "holds exactly".to_string(),
            Verdict::ExactOnConstraints => "holds exactly on the constraint surface".to_string(),
            Verdict::Numeric { samples, sampling: Sampling::Anywhere } => {
                format!("holds at {samples} random states (the algebra could not decide)")
            }
            Verdict::Numeric { samples, sampling: Sampling::OnConstraints } => format!(
                "holds at {samples} random states on the constraint surface (the algebra could not decide)"
            ),
            Verdict::Numeric { samples, sampling: Sampling::AtStart { unknowns } } => format!(
                "holds at {samples} random parameter values, the start's {unknowns} unknowns solved numerically (too many for the algebra)"
            ),
            Verdict::Numeric { sampling: Sampling::AtStartValues { unknowns }, .. } => format!(
                "holds at the parameters' values, where the start is, with its {unknowns} unknowns solved numerically"
            ),
            Verdict::Fails(_) => "DOES NOT HOLD".to_string(),
            Verdict::Undecided { reason } => format!("UNDECIDED: {reason}"),
        }
    }
}

/// Checks every `expect` line, in order.
pub fn check_all(d: &mut Derivation) -> Vec<Verdict> {
    (0..d.model.expects.len()).map(|i| check(d, i)).collect()
}

/// Checks one `expect` line.
pub fn check(d: &mut Derivation, index: usize) -> Verdict {
    if let Some(contact) = d.model.expects[index].impact {
        return check_impact(d, index, contact);
    }
    let at_start = d.model.expects[index].at_start;
    let (lhs, rhs) = d.expect_sides(index);
    each_component(d, lhs, rhs, |d, residual| {
        let decision =
            if at_start { d.decide_at_start(residual) } else { d.decide_everywhere(residual) };
        match decision {
            Decision::Exact => Verdict::Exact,
            Decision::ExactOnConstraints => Verdict::ExactOnConstraints,
            Decision::Sample { residual, solve } => sample(d, residual, solve),
            Decision::SampleAtStart { residual, unknowns } => {
                sample_at_start(d, residual, unknowns)
            }
            // The exact solve's zero test decides large entries at generic points: numbers at
            // the start have the last word.
            Decision::SingularAtStart => {
                let unknowns = d.unknowns().len();
                match sample_at_start(d, residual, unknowns) {
                    Verdict::Undecided { .. } => Verdict::Undecided {
                        reason: "the mass matrix is singular at the start".into(),
                    },
                    verdict => verdict,
                }
            }
        }
    })
}

/// The verdict of an expectation from each component's residual lhs − rhs, decided by
/// `decide`: the first failure (naming its component where there are several) or undecided
/// one, else the weakest of the others (numbers over exact, on the constraints over
/// everywhere).
fn each_component(
    d: &mut Derivation,
    lhs: Vec<ExprId>,
    rhs: Vec<ExprId>,
    mut decide: impl FnMut(&mut Derivation, ExprId) -> Verdict,
) -> Verdict {
    let many = lhs.len() > 1;
    let mut numeric: Option<(usize, Sampling)> = None;
    let mut on_constraints = false;
    for (k, (l, r)) in lhs.into_iter().zip(rhs).enumerate() {
        let residual = d.model.pool.sub(l, r);
        match decide(d, residual) {
            Verdict::Exact => {}
            Verdict::ExactOnConstraints => on_constraints = true,
            Verdict::Numeric { samples, sampling } => {
                numeric = Some(
                    numeric.map_or((samples, sampling), |(n, s)| (n.min(samples), s.max(sampling))),
                )
            }
            Verdict::Fails(mut f) => {
                f.component = many.then_some(k);
                return Verdict::Fails(f);
            }
            undecided => return undecided,
        }
    }
    match numeric {
        Some((samples, sampling)) => Verdict::Numeric { samples, sampling },
        None if on_constraints => Verdict::ExactOnConstraints,
        None => Verdict::Exact,
    }
}

/// `expect impact NAME: lhs = rhs`: the left side with the rates after an impact at the
/// contact alone (its exact impact law), the right side with those before, both at the state
/// before it that the line's `where` list gives; decided as an identity in the rest of the
/// state, exactly where the algebra can, else at random states.
fn check_impact(d: &mut Derivation, index: usize, contact: usize) -> Verdict {
    let Some(k) = d.contacts.iter().position(|c| c.contact == contact) else {
        return Verdict::Undecided { reason: "the contact keeps no rows in the equations".into() };
    };
    let Some(law) = d.impact_law(k) else {
        return Verdict::Undecided {
            reason: "the impact law is too large to derive exactly; a run solves it in numbers"
                .into(),
        };
    };
    let after: std::collections::HashMap<cas::SymId, ExprId> =
        d.rates.iter().copied().zip(law.rates_after.iter().copied()).collect();
    let mut before: std::collections::HashMap<cas::SymId, ExprId> = Default::default();
    for item in d.model.expects[index].before.clone() {
        let sym = if item.rate { d.model.pool.rate(item.coord) } else { Some(item.coord) };
        before.extend(sym.map(|s| (s, item.value)));
    }
    let (lhs, rhs) = d.expect_sides(index);
    let lhs: Vec<ExprId> = lhs.into_iter().map(|l| d.model.pool.subst(l, &after)).collect();
    each_component(d, lhs, rhs, |d, residual| {
        let residual = d.model.pool.subst(residual, &before);
        match d.decide_everywhere(residual) {
            Decision::Exact | Decision::ExactOnConstraints => Verdict::Exact,
            Decision::Sample { residual, .. } => sample(d, residual, false),
            _ => Verdict::Undecided { reason: "the impact law could not be decided".into() },
        }
    })
}

/// A residual the algebra left undecided, compared with zero at random states (on the
/// constraint surface, where there are kept constraints), solving for the accelerations and
/// multipliers at each state when `solve` says so.
fn sample(d: &mut Derivation, residual: ExprId, solve: bool) -> Verdict {
    // A fixed seed: the same scene is checked at the same states in every run.
    let mut rng = ChaCha8Rng::seed_from_u64(0x1a9_2a96e);
    let syms = state_symbols(d);
    let mut constraints = ConstraintSet::first(d, d.multipliers.len());
    let sampling =
        if constraints.is_empty() { Sampling::Anywhere } else { Sampling::OnConstraints };
    let mut measure = ScaledEvaluator::new(&d.model.pool, &[residual]);
    let mut system: Option<System> = None;
    let mut good = 0;
    let mut reached = 0;
    for _ in 0..SAMPLES * 4 {
        if good == SAMPLES {
            break;
        }
        let mut values = random_state(d, &mut rng);
        if constraints.project(&mut values).is_err() {
            continue;
        }
        reached += 1;
        if solve && solve_unknowns(d, &mut system, &mut values).is_none() {
            continue;
        }
        let (value, scale) = measure.eval(&values)[0];
        if let Some(f) = failure_at(d, residual, (value, scale), &values, &syms) {
            return Verdict::Fails(f);
        }
        if value.is_finite() && scale.is_finite() {
            good += 1;
        }
    }
    if good == 0 {
        let reason = if reached == 0 {
            "no random start reached a state that satisfies the constraints"
        } else {
            "no random state where the expressions are defined"
        };
        return Verdict::Undecided { reason: reason.into() };
    }
    Verdict::Numeric { samples: good, sampling }
}

/// `expect at start:` past the algebra's budget: at random parameter values, the start is
/// solved numerically and the residual evaluated there.
fn sample_at_start(d: &mut Derivation, residual: ExprId, unknowns: usize) -> Verdict {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5747_a247);
    let params: Vec<SymId> = d.model.constants().iter().map(|(s, _)| *s).collect();
    let mut solver = StartSolver::new(d);
    let mut measure = ScaledEvaluator::new(&d.model.pool, &[residual]);
    // A start that holds only at the scene's values is tried there alone: elsewhere it would
    // break its constraints.
    let at_values = if d.start_at_values_only {
        let Ok(values) = crate::start::parameter_values(d) else {
            return Verdict::Undecided {
                reason: "the start holds only at the parameters' values, and some have none".into(),
            };
        };
        Some(values)
    } else {
        None
    };
    let tries = if at_values.is_some() { 1 } else { SAMPLES * 4 };
    let mut good = 0;
    for _ in 0..tries {
        if good == SAMPLES {
            break;
        }
        let values: Vec<(SymId, f64)> = match &at_values {
            Some(values) => values.clone(),
            None => {
                let mut drawn = vec![f64::NAN; d.model.pool.symbol_count()];
                for p in &params {
                    drawn[p.index()] = rng.gen_range(0.5..2.0);
                }
                crate::admissible::tie_derived(d, &mut drawn);
                params.iter().map(|p| (*p, drawn[p.index()])).collect()
            }
        };
        let Some(start) = solver.solve(d, &values) else { continue };
        let (value, scale) = measure.eval(&start.values)[0];
        if let Some(mut f) = failure_at(d, residual, (value, scale), &start.values, &params) {
            f.state.retain(|(s, _)| params.contains(s));
            return Verdict::Fails(f);
        }
        if value.is_finite() && scale.is_finite() {
            good += 1;
        }
    }
    match (good, at_values) {
        (0, Some(_)) => Verdict::Undecided {
            reason: "the start could not be solved at the parameters' values, or the expression \
                     is undefined there"
                .into(),
        },
        (0, None) => Verdict::Undecided {
            reason: "the start could not be solved at any parameter values tried".into(),
        },
        (_, Some(_)) => {
            Verdict::Numeric { samples: good, sampling: Sampling::AtStartValues { unknowns } }
        }
        (_, None) => Verdict::Numeric { samples: good, sampling: Sampling::AtStart { unknowns } },
    }
}

/// A failure when the residual, whose value and size at this state are `measured`, is
/// defined and not zero there.
fn failure_at(
    d: &mut Derivation,
    residual: ExprId,
    (value, scale): (f64, f64),
    values: &[f64],
    syms: &[SymId],
) -> Option<Failure> {
    if !value.is_finite() || !scale.is_finite() {
        return None;
    }
    if value.abs() <= RELATIVE_TOLERANCE * (1.0 + scale) {
        return None;
    }
    let pool = &mut d.model.pool;
    let mut state: Vec<(SymId, f64)> = syms
        .iter()
        .filter(|s| pool.depends_on(residual, **s))
        .map(|s| (*s, values[s.index()]))
        .collect();
    state.extend(
        d.unknowns()
            .into_iter()
            .filter(|u| d.model.pool.depends_on(residual, *u))
            .map(|u| (u, values[u.index()])),
    );
    Some(Failure { component: None, residual, state, value })
}
