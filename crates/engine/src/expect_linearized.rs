//! `expect linearized:` lines, decided: the scene linearized about its reference at the
//! parameters' values, and each expectation compared with what was found (a verdict, an
//! eigenvalue within the verdict's tolerance, or a change of verdict found by a sweep about
//! the expected critical value), so that a stability result is checked like an equation.

use model::{ExpectedStability, LinearExpectation};

use mechanics::Derivation;

use crate::linearize::{linearize_derived, Linearized, Stability, RELATIVE_TOLERANCE};
use crate::Error;

/// How far about an expected critical value the sweep looks, relatively.
const CRITICAL_WINDOW: f64 = 1e-3;

/// How close the change found must be to the expected critical value, relatively: the
/// bisection brackets it to 1e-10.
const CRITICAL_TOLERANCE: f64 = 1e-8;

/// What became of one `expect linearized:` line.
#[derive(Clone, Debug, PartialEq)]
pub enum LinearVerdict {
    /// It holds; how, in words.
    Holds(String),
    /// It does not; what was found instead.
    Fails(String),
    /// The linearization itself failed; why.
    Undecided(String),
}

impl LinearVerdict {
    pub fn holds(&self) -> bool {
        matches!(self, LinearVerdict::Holds(_))
    }
}

/// Each `expect linearized:` line of `source`, decided (none without such lines), from its
/// derivation, which comes back with the verdicts; or why the scene does not linearize about
/// its own reference at its own values, which is bad input as it is for `linearize` (a
/// reference that is not an equilibrium, say), not an expectation left undecided. A critical
/// value's sweep is made on the same linearization: the scene is not resolved again.
pub fn check_linearized(
    source: &str,
    derivation: Derivation,
) -> Result<(Vec<LinearVerdict>, Derivation), Error> {
    let expectations: Vec<LinearExpectation> =
        derivation.model.linear_expects.iter().map(|e| e.expectation.clone()).collect();
    // Each critical value's sweep, about the value at the scene's parameters.
    let mut sweeps = Vec::new();
    let mut windows = Vec::new();
    for e in &expectations {
        if let LinearExpectation::Critical { parameter, value } = e {
            let name = derivation.model.params[*parameter].name.clone();
            let value = value_of(&derivation, *value);
            let half = CRITICAL_WINDOW * value.abs().max(1.0);
            if value.is_finite() {
                sweeps.push((name.clone(), value - half, value + half, 3));
            }
            windows.push((name, value, half));
        }
    }
    let (l, swept) = linearize_derived(source, derivation, &sweeps)?;
    let mut swept = swept.into_iter();
    let mut windows = windows.into_iter();
    let verdicts = expectations
        .iter()
        .map(|e| match e {
            LinearExpectation::Critical { .. } => {
                let (name, value, half) = windows.next().expect("a window per critical line");
                if !value.is_finite() {
                    return LinearVerdict::Undecided(format!(
                        "the critical value of `{name}` is {value}"
                    ));
                }
                let sweep = swept.next().expect("a sweep per finite critical value");
                critical(&name, value, half, sweep)
            }
            _ => decide(&l, e),
        })
        .collect();
    Ok((verdicts, l.derivation))
}

/// `re ± |im|i` with true minus signs, as the text reports write numbers (`1.5 − 2.2i`, not
/// `1.5 + -2.2i`).
fn complex_text(re: f64, im: f64) -> String {
    let minus = |x: f64| format!("{x}").replace('-', "−");
    let sign = if im.is_sign_negative() { "−" } else { "+" };
    format!("{} {sign} {}i", minus(re), minus(im.abs()))
}

fn first_line(e: &Error) -> String {
    e.to_string().lines().next().unwrap_or("").to_string()
}

/// A constant of the parameters at the scene's values.
fn value_of(d: &Derivation, e: cas::ExprId) -> f64 {
    match model::ParameterValues::new(&d.model).values(Vec::new()) {
        Ok(parameters) => value_with(&d.model, &parameters, e),
        Err(_) => f64::NAN,
    }
}

/// A constant of the parameters at the values the linearization used.
fn value_at(l: &Linearized, e: cas::ExprId) -> f64 {
    value_with(&l.derivation.model, &l.at.parameters, e)
}

/// A constant of the parameters at `parameters`, in the model's order.
fn value_with(model: &model::Model, parameters: &[f64], e: cas::ExprId) -> f64 {
    let pool = &model.pool;
    let mut values = vec![f64::NAN; pool.symbol_count()];
    for (p, v) in model.params.iter().zip(parameters) {
        values[p.sym.index()] = *v;
    }
    numeric::eval(pool, e, &values)
}

fn decide(l: &Linearized, e: &LinearExpectation) -> LinearVerdict {
    match e {
        LinearExpectation::Stability(expected) => {
            let expected = match expected {
                ExpectedStability::Stable => Stability::Stable,
                ExpectedStability::MarginallyStable => Stability::MarginallyStable,
                ExpectedStability::Unstable => Stability::Unstable,
            };
            let found = l.at.stability;
            match found == expected {
                true => LinearVerdict::Holds(format!("{} at the reference", found.name())),
                false => LinearVerdict::Fails(format!("{} at the reference", found.name())),
            }
        }
        LinearExpectation::Eigenvalue { re, im } => {
            let (re, im) = (value_at(l, *re), value_at(l, *im));
            let distance = |z: &(f64, f64)| {
                let (dr, di) = (z.0 - re, z.1 - im);
                (dr * dr + di * di).sqrt()
            };
            let nearest =
                l.at.eigenvalues.iter().min_by(|a, b| distance(a).total_cmp(&distance(b)));
            let Some(nearest) = nearest else {
                return LinearVerdict::Fails("A has no eigenvalues".into());
            };
            // The eigenvalue's own bound, or the relative tolerance of a value computed
            // through A's entries where that is larger, or rounding's where every eigenvalue
            // is zero.
            let index = l.at.eigenvalues.iter().position(|z| z == nearest).unwrap_or(0);
            let own = l.at.bounds.get(index).copied().unwrap_or(0.0);
            let modulus = |z: &(f64, f64)| (z.0 * z.0 + z.1 * z.1).sqrt();
            let largest = l.at.eigenvalues.iter().map(modulus).fold(0.0, f64::max);
            let tolerance = own.max(RELATIVE_TOLERANCE * largest).max(1e-12);
            let text = complex_text(nearest.0, nearest.1);
            match distance(nearest) <= tolerance {
                true => LinearVerdict::Holds(format!("an eigenvalue is {text}, within {tolerance:.1e}")),
                false => LinearVerdict::Fails(format!(
                    "the nearest eigenvalue is {text}, {:.3e} away (the tolerance is {tolerance:.1e})",
                    distance(nearest)
                )),
            }
        }
        LinearExpectation::Critical { .. } => {
            unreachable!("a critical value is decided by its sweep")
        }
    }
}

/// Whether the verdict changes within [`CRITICAL_TOLERANCE`] of `value`, by a sweep of the
/// parameter across a window about it, bisected where the verdict changes.
fn critical(
    name: &str,
    value: f64,
    half: f64,
    sweep: Result<linear::Sweep, Error>,
) -> LinearVerdict {
    let sweep = match sweep {
        Ok(sweep) => sweep,
        Err(e) => return LinearVerdict::Undecided(first_line(&e)),
    };
    let changes = sweep.changes;
    let scale = value.abs().max(f64::MIN_POSITIVE);
    let near = changes.iter().find(|c| (c.value - value).abs() <= CRITICAL_TOLERANCE * scale);
    match (near, changes.first()) {
        (Some(c), _) => LinearVerdict::Holds(format!(
            "{} → {} at {name} = {}",
            c.from.name(),
            c.to.name(),
            c.value
        )),
        (None, Some(c)) => LinearVerdict::Fails(format!(
            "the verdict changes at {name} = {}, {:.3e} away",
            c.value,
            (c.value - value).abs()
        )),
        (None, None) => LinearVerdict::Fails(format!(
            "the verdict does not change between {name} = {} and {}",
            value - half,
            value + half
        )),
    }
}
