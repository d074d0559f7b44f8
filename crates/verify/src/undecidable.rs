//! Foresight for `check`: warnings, with the derivation, about `expect` lines it will not be
//! able to decide, tried at the kind of random states it uses.

use cas::{ExprId, SymId};
use lang::Diagnostic;
use mechanics::Derivation;
use numeric::Evaluator;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::admissible::{random_state, ConstraintSet};
use crate::system::{solve_unknowns, System};

/// How many random states the foresight of undecidable `expect` lines tries: enough that an
/// expression defined on a good part of the states is found defined at one of them.
const FORESIGHT_STATES: usize = 8;

/// Warns, with the derivation, about `expect` lines that `check` will find undecidable:
/// a side undefined at every state tried (`sqrt(-1 - x^2)`), or accelerations that cannot
/// be solved for at the start. Tried at the kind of random states `check` uses.
pub(crate) fn warn_about_undecidable_expects(d: &mut Derivation) {
    let mut rng = ChaCha8Rng::seed_from_u64(0xf0_2e5e);
    let mut constraints = ConstraintSet::first(d, d.multipliers.len());
    let mut system: Option<System> = None;
    for index in 0..d.model.expects.len() {
        let expect = d.model.expects[index].clone();
        let lhs = d.expand_value(&expect.lhs, true).entries();
        let rhs = d.expand_value(&expect.rhs, true).entries();
        let residuals: Vec<ExprId> =
            lhs.iter().zip(&rhs).map(|(l, r)| d.model.pool.sub(*l, *r)).collect();
        let unknowns = d.unknowns();
        // `check` solves for the accelerations at the start whatever the line says, and
        // elsewhere only when the line has them.
        let solve = expect.at_start
            || residuals.iter().any(|r| unknowns.iter().any(|u| d.model.pool.depends_on(*r, *u)));
        let mut states = Vec::new();
        for _ in 0..FORESIGHT_STATES {
            let mut values = random_state(d, &mut rng);
            if expect.at_start {
                start_values(d, &mut values);
            } else if constraints.project(&mut values).is_err() {
                continue;
            }
            if solve && solve_unknowns(d, &mut system, &mut values).is_none() {
                continue;
            }
            states.push(values);
        }
        if states.is_empty() {
            if expect.at_start {
                d.warnings.push(
                    Diagnostic::warning(
                        expect.span,
                        "`check` cannot decide this expectation: the mass matrix is \
                         singular at the start",
                    )
                    .with_label("the accelerations at the start cannot be solved for")
                    .with_hint(
                        "start away from the singular configuration (an angle or a radius \
                         where some coordinate stops moving any mass)",
                    ),
                );
            }
            continue;
        }
        let pool = &d.model.pool;
        let undefined = |e: ExprId| {
            let mut evaluator = Evaluator::new(pool, &[e]);
            states.iter().all(|v| !evaluator.eval(v)[0].is_finite())
        };
        if !residuals.iter().any(|r| undefined(*r)) {
            continue;
        }
        // Point at the side that is undefined, and inside it at the smallest part that is.
        let side = match lhs.iter().find(|e| undefined(**e)) {
            Some(e) => Some((*e, expect.lhs_span)),
            None => rhs.iter().find(|e| undefined(**e)).map(|e| (*e, expect.rhs_span)),
        };
        let Some((side, span)) = side else {
            // Each side is defined somewhere, but never both at once.
            let label = format!("none of {} random states defines both sides", states.len());
            d.warnings.push(
                Diagnostic::warning(
                    expect.span,
                    "`check` cannot decide this expectation: its sides are never defined \
                     at the same state",
                )
                .with_label(label)
                .with_hint(UNDEFINED_HINT),
            );
            continue;
        };
        let mut part = side;
        for _ in 0..MAX_DESCENT {
            match pool.children(part).into_iter().find(|c| undefined(*c)) {
                Some(child) => part = child,
                None => break,
            }
        }
        let text = pool.print(part, cas::Style::Unicode);
        let label = if text.chars().count() <= 48 {
            format!("{text} is not a real number at any of {} random states", states.len())
        } else {
            format!("not a real number at any of {} random states", states.len())
        };
        d.warnings.push(
            Diagnostic::warning(
                span,
                "`check` cannot decide this expectation: it is undefined wherever it is tried",
            )
            .with_label(label)
            .with_hint(UNDEFINED_HINT),
        );
    }
}

/// Puts the initial state into `values`: coordinates and rates at their `coord` values
/// (at the parameters' values in `values`), time 0.
fn start_values(d: &mut Derivation, values: &mut [f64]) {
    let (symbols, exprs): (Vec<SymId>, Vec<ExprId>) = d.initial_state().into_iter().unzip();
    // Evaluated in full before any is written: the values depend on the parameters only.
    let evaluated = Evaluator::new(&d.model.pool, &exprs).eval(values).to_vec();
    for (s, v) in symbols.into_iter().zip(evaluated) {
        values[s.index()] = v;
    }
}

/// Why an expression is undefined at every state `check` tries, and what to look at.
const UNDEFINED_HINT: &str = "`check` compares the sides at random states (parameters in \
     [0.5, 2], coordinates in [-1.2, 1.2], rates in [-1, 1]); check the sign under a square root \
     or a logarithm, or the argument of asin or acos";

/// How deep the search for the smallest undefined part of an expression goes.
const MAX_DESCENT: usize = 64;
