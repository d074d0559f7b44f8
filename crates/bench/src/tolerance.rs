//! What `--tolerance` buys under each adaptive method: the final error of dopri5, dop853,
//! radau and auto at tolerances 1e-6 … 1e-12 on scenes with trustworthy references, and the
//! spread of those errors across the methods at each tolerance. The tolerance should mean the
//! same accuracy whichever method runs (docs/simulating.md): the spread is how far it does not.
//!
//! The error is the largest component error of the final (q, q̇), each relative to that
//! component's size where it exceeds 1 (|Δᵢ| / max(1, |refᵢ|)): the weight atol + rtol·|y|
//! with atol = rtol = tol that every method holds its local error to.

use engine::input::Assignment;
use sim::Method;
use simulation::{simulate_with, Options, Outcome};

use crate::precision::read;
use crate::progress::Bar;

/// The adaptive methods, in the order of the table.
const METHODS: [Method; 4] = [Method::Dopri5, Method::Dop853, Method::Radau, Method::Auto];

/// The tolerances of the table: 1e-6 … 1e-12.
fn tolerances() -> Vec<f64> {
    (6..=12).map(|k| numeric::pow_int(10.0, -k)).collect()
}

/// The harmonic oscillator x'' = −x from x = 1 at rest: x = cos t, x' = −sin t.
pub const OSCILLATOR: &str = "scene \"Oscillator\"\nparam m = 1, k = 1\ncoord x = 1\n\
                              particle p { mass m; position (x, 0) }\npotential k/2*x^2\n";

/// A scene of the table: where it comes from, how long it runs, and its reference.
struct Case {
    name: &'static str,
    source: String,
    base: Options,
    /// The methods whose tolerance, not stability, decides their steps here.
    methods: &'static [Method],
    reference: Reference,
}

enum Reference {
    /// The exact final state.
    Exact(Vec<f64>),
    /// A run of this method at this tolerance.
    Run(Method, f64),
}

fn cases() -> Vec<Case> {
    let oscillator_end = 20.0;
    let stiff = Options {
        set: vec!["k=1e8".parse::<Assignment>().expect("k=… is an assignment")],
        ..Options::default()
    };
    vec![
        Case {
            name: "harmonic oscillator, t = 20 (exact: cos t)",
            source: OSCILLATOR.to_string(),
            base: Options { until: Some(oscillator_end), ..Options::default() },
            methods: &METHODS,
            reference: Reference::Exact(vec![
                exact_cos(oscillator_end),
                -exact_sin(oscillator_end),
            ]),
        },
        Case {
            name: "double pendulum from π/2, t = 5 (dop853 at 1e-14)",
            source: read("classics/double_pendulum.lag"),
            base: Options { until: Some(5.0), ..Options::default() },
            methods: &METHODS,
            reference: Reference::Run(Method::Dop853, 1e-14),
        },
        Case {
            name: "Andrews' mechanism, t = 0.03 (dop853 at 1e-14)",
            source: read("classics/andrews_squeezer.lag"),
            base: Options::default(),
            methods: &METHODS,
            reference: Reference::Run(Method::Dop853, 1e-14),
        },
        Case {
            name: "car axis, t = 3 (dop853 at 1e-14)",
            source: read("classics/car_axis.lag"),
            base: Options::default(),
            methods: &METHODS,
            reference: Reference::Run(Method::Dop853, 1e-14),
        },
        Case {
            name: "stiffness ladder at k = 1e8, t = 10 (radau at 1e-14; the explicit methods \
                   are held by stability there, not by the tolerance)",
            source: read("classics/stiff_spring_pendulum.lag"),
            base: stiff,
            methods: &[Method::Radau, Method::Auto],
            reference: Reference::Run(Method::Radau, 1e-14),
        },
    ]
}

// The references are exact: their last bit shows nowhere in the errors measured.
#[allow(clippy::disallowed_methods)]
fn exact_cos(t: f64) -> f64 {
    t.cos()
}

#[allow(clippy::disallowed_methods)]
fn exact_sin(t: f64) -> f64 {
    t.sin()
}

fn run_with(case: &Case, method: Method, tolerance: f64, bar: &mut Bar) -> Option<Outcome> {
    let options = Options {
        method: Some(method.name().into()),
        tolerance: Some(tolerance),
        samples: 2,
        ..case.base.clone()
    };
    let outcome = simulate_with(&case.source, &options, bar).ok()?;
    outcome.run.fault.is_none().then_some(outcome)
}

/// The final error of `state` against `reference`, as the module's doc defines it.
pub fn final_error(state: &[f64], reference: &[f64]) -> f64 {
    if state.len() != reference.len() {
        return f64::INFINITY;
    }
    state.iter().zip(reference).map(|(s, r)| (s - r).abs() / r.abs().max(1.0)).fold(0.0, f64::max)
}

/// The table of every case, and each tolerance's spread; returns the largest spread of each
/// case, for the summary line.
pub fn run() {
    let tolerances = tolerances();
    outln!("## One tolerance, one accuracy: the final error of each adaptive method\n");
    outln!(
        "Error: max |Δᵢ| / max(1, |refᵢ|) over the final (q, q̇). Spread: the largest error over \
         the smallest across the methods at a tolerance.\n"
    );
    for case in cases() {
        let mut bar = Bar::new(format!("tolerance: {}", case.name));
        let reference = match &case.reference {
            Reference::Exact(state) => Some(state.clone()),
            Reference::Run(method, tolerance) => {
                run_with(&case, *method, *tolerance, &mut bar).map(|o| o.run.final_state)
            }
        };
        let Some(reference) = reference else {
            drop(bar);
            outln!("{}: the reference run failed\n", case.name);
            continue;
        };
        let errors: Vec<Vec<f64>> = tolerances
            .iter()
            .map(|&tol| {
                case.methods
                    .iter()
                    .map(|&m| {
                        run_with(&case, m, tol, &mut bar)
                            .map_or(f64::NAN, |o| final_error(&o.run.final_state, &reference))
                    })
                    .collect()
            })
            .collect();
        drop(bar);
        outln!("{}\n", case.name);
        let names: Vec<&str> = case.methods.iter().map(|m| m.name()).collect();
        outln!("| tolerance | {} | spread |", names.join(" | "));
        outln!("|---|{}---:|", "---:|".repeat(names.len()));
        for (tol, row) in tolerances.iter().zip(&errors) {
            let cells: Vec<String> = row
                .iter()
                .map(|e| if e.is_nan() { "fault".into() } else { format!("{e:.1e}") })
                .collect();
            outln!("| {tol:.0e} | {} | {} |", cells.join(" | "), spread_text(row));
        }
        outln!();
    }
}

/// max/min of the errors at one tolerance; a fault shows as such.
fn spread_text(errors: &[f64]) -> String {
    if errors.iter().any(|e| e.is_nan()) {
        return "–".into();
    }
    let most = errors.iter().copied().fold(0.0, f64::max);
    let least = errors.iter().copied().fold(f64::INFINITY, f64::min);
    if least > 0.0 {
        format!("{:.1}", most / least)
    } else {
        "∞".into()
    }
}
