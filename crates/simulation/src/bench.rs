//! What each method and tolerance buys on one scene, measured. Every integrator runs over a
//! ladder of tolerances (adaptive methods) or step counts (fixed-step methods); each run's
//! final state is compared with a tight-tolerance reference, and each [`Trial`] holds the
//! error, the wall time (median of a few repeats) and the right-hand-side evaluations. A method
//! that cannot run the scene at all (a symplectic one, when a constraint keeps a multiplier) is
//! listed as not applicable rather than failing the whole comparison. Tables and diagrams are
//! the front end's.

use std::fmt::Write;

use sim::Method;

use crate::{simulate_with, Options, Outcome, Progress, DRIVEN_IN_LAGRANGIAN, NO_MULTIPLIERS};
use engine::Error;

/// What one rung of a ladder sets: a tolerance, or a number of fixed steps over the span.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    Tolerance(f64),
    Steps(usize),
}

impl Setting {
    /// The rung as a table names it: `tol 1e-6`, `800 steps`.
    pub fn label(&self) -> String {
        match self {
            Setting::Tolerance(t) => format!("tol {t:.0e}"),
            Setting::Steps(n) => format!("{n} steps"),
        }
    }
}

/// The ladder of a method: tolerances 1e-3 … 1e-12 for the adaptive methods, 100 … 12,800
/// steps over the span for the fixed-step ones.
pub fn ladder(method: Method) -> Vec<Setting> {
    if method.is_adaptive() {
        (3..=12).map(|k| Setting::Tolerance(numeric::pow_int(10.0, -k))).collect()
    } else {
        (0..8).map(|k| Setting::Steps(100 << k)).collect()
    }
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Trial {
    pub method: Method,
    pub setting: Setting,
    /// The error against the reference, as the caller measures it; NaN when the run faulted.
    pub error: f64,
    /// Median wall time of the integration alone (no derivation or lowering), in seconds.
    pub seconds: f64,
    pub evaluations: usize,
    pub steps: usize,
    pub fault: Option<String>,
}

/// A method left out of a comparison, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Inapplicable {
    pub method: Method,
    pub reason: &'static str,
}

/// `base` with the method and the rung's tolerance or step set.
pub fn options_for(base: &Options, method: Method, setting: Setting, span: f64) -> Options {
    let mut o = base.clone();
    o.method = Some(method.name().to_string());
    match setting {
        Setting::Tolerance(t) => o.tolerance = Some(t),
        Setting::Steps(n) => o.step = Some(span / n as f64),
    }
    o
}

/// Runs `options` `repeats` times; the last outcome, and the median integration time.
pub fn timed(
    source: &str,
    options: &Options,
    repeats: usize,
    progress: &mut dyn Progress,
) -> Result<(Outcome, f64), Error> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let outcome = simulate_with(source, options, progress)?;
        times.push(outcome.wall_seconds);
        // A slow run is measured once: its timing noise is small against its length.
        let slow = outcome.wall_seconds > 1.0;
        last = Some(outcome);
        if slow {
            break;
        }
    }
    Ok((last.expect("at least one run"), median(&mut times)))
}

/// The median of `v` (which it sorts); NaN when it is empty.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Every method over its ladder; `error` measures a finished run against the caller's
/// reference.
pub fn work_precision(
    source: &str,
    base: &Options,
    span: f64,
    methods: &[Method],
    repeats: usize,
    error: &mut dyn FnMut(&Outcome) -> f64,
    progress: &mut dyn Progress,
) -> Result<Vec<Trial>, Error> {
    let mut trials = Vec::new();
    for &method in methods {
        for setting in ladder(method) {
            let options = options_for(base, method, setting, span);
            let (outcome, seconds) = timed(source, &options, repeats, progress)?;
            let fault = outcome.run.fault.as_ref().map(|f| outcome.describe_fault(f));
            let e = if fault.is_some() { f64::NAN } else { error(&outcome) };
            trials.push(Trial {
                method,
                setting,
                error: e,
                seconds,
                evaluations: outcome.run.evaluations,
                steps: outcome.run.steps,
                fault,
            });
        }
    }
    Ok(trials)
}

/// The largest difference of the final states (and of the final times, for runs that a stop
/// event ended) between a run and the reference.
pub fn final_state_error(reference: &Outcome, run: &Outcome) -> f64 {
    let state = reference
        .run
        .final_state
        .iter()
        .zip(&run.run.final_state)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    state.max((reference.run.final_time - run.run.final_time).abs())
}

/// The reference run of [`bench()`]: DOP853 at this tolerance.
pub const REFERENCE_TOLERANCE: f64 = 1e-14;

/// What `lagrange bench FILE` measures.
pub struct Report {
    pub trials: Vec<Trial>,
    /// Methods that cannot run this scene, in the order of [`Method::NAMES`].
    pub inapplicable: Vec<Inapplicable>,
    /// max |reference − the same at 10× the tolerance|: how far the reference itself can be
    /// trusted.
    pub reference_check: f64,
    pub span: f64,
}

/// The speed–accuracy trials of a scene: every method over its ladder against DOP853 at
/// [`REFERENCE_TOLERANCE`]. `base` carries the scene's options (`--until`, `--set`, stops).
pub fn bench(
    source: &str,
    base: &Options,
    repeats: usize,
    progress: &mut dyn Progress,
) -> Result<Report, Error> {
    let reference_options = options_for(
        base,
        Method::Dop853,
        Setting::Tolerance(REFERENCE_TOLERANCE),
        base.until.unwrap_or(1.0),
    );
    let reference = simulate_with(source, &reference_options, progress)?;
    if let Some(f) = &reference.run.fault {
        return Err(Error::Numeric(format!(
            "the reference run failed\n{}",
            reference.describe_fault(f)
        )));
    }
    let looser = options_for(
        base,
        Method::Dop853,
        Setting::Tolerance(10.0 * REFERENCE_TOLERANCE),
        base.until.unwrap_or(1.0),
    );
    let check = simulate_with(source, &looser, progress)?;
    let reference_check = final_state_error(&reference, &check);
    // The fixed-step ladders divide the span the reference actually covered (a stop event
    // may end it before --until).
    let span = reference.run.final_time;
    // One constraint column per multiplier.
    let multipliers = !reference.constraint_columns.is_empty();
    let mut methods = Vec::new();
    let mut inapplicable = Vec::new();
    for method in Method::all() {
        if multipliers && !method.handles_multipliers() {
            inapplicable.push(Inapplicable { method, reason: NO_MULTIPLIERS });
        } else if reference.lagrangian_driven && method.is_symplectic() {
            inapplicable.push(Inapplicable { method, reason: DRIVEN_IN_LAGRANGIAN });
        } else {
            methods.push(method);
        }
    }
    let mut error = |o: &Outcome| final_state_error(&reference, o);
    let trials = work_precision(source, base, span, &methods, repeats, &mut error, progress)?;
    Ok(Report { trials, inapplicable, reference_check, span })
}

/// The table of trials, one line each, then a line for each method left out: plain text that
/// `lagrange bench` and `lagrange-bench` print alike.
pub fn table(trials: &[Trial], inapplicable: &[Inapplicable]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<9} {:>12} {:>11} {:>12} {:>10} {:>9}",
        "method", "setting", "error", "time", "rhs evals", "steps"
    );
    for t in trials {
        let error = if t.error.is_nan() { "fault".to_string() } else { format!("{:.2e}", t.error) };
        let _ = writeln!(
            s,
            "{:<9} {:>12} {:>11} {:>12} {:>10} {:>9}",
            t.method.name(),
            t.setting.label(),
            error,
            seconds(t.seconds),
            t.evaluations,
            t.steps
        );
    }
    for m in inapplicable {
        let _ = writeln!(s, "{:<9} not applicable: {}", m.method.name(), m.reason);
    }
    s
}

/// A duration with a unit that keeps three significant digits readable.
pub fn seconds(s: f64) -> String {
    if s < 1e-6 {
        format!("{:.1} ns", s * 1e9)
    } else if s < 1e-3 {
        format!("{:.2} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladders_span_the_tolerances_and_steps() {
        assert_eq!(ladder(Method::Dop853).first(), Some(&Setting::Tolerance(1e-3)));
        assert_eq!(ladder(Method::Dop853).len(), 10);
        assert_eq!(ladder(Method::Gauss).last(), Some(&Setting::Steps(12_800)));
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
