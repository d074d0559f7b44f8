//! Work–precision of every integrator on three scenes with trustworthy references: the double
//! pendulum (DOP853 at 1e-14, checked against 1e-13), the falling rod (landing time from the
//! energy integral) and the simple pendulum (its exact period from the arithmetic–geometric
//! mean: after one period the state is the initial one again).

use simulation::bench::{final_state_error, options_for, work_precision, Setting, Trial};
use simulation::{simulate_with, Options, Outcome};

use crate::progress::Bar;
use bench::reference::{elliptic_k, gauss_legendre};
use sim::Method;

pub const METHODS: [Method; 6] =
    [Method::Rk4, Method::Dopri5, Method::Dop853, Method::Midpoint, Method::Gauss, Method::Radau];

pub fn examples() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

pub fn read(rel: &str) -> String {
    std::fs::read_to_string(examples().join(rel)).expect("example")
}

/// The rod's landing time from the energy integral (m = L = 1, g = 9.81, from θ0 at rest).
// A reference that errors of 1e-13 are measured against: its last bit shows nowhere.
#[allow(clippy::disallowed_methods)]
pub fn rod_landing_time(theta0: f64) -> f64 {
    let (l, g) = (1.0f64, 9.81f64);
    let span = std::f64::consts::FRAC_PI_2 - theta0;
    // θ = θ0 + span·u² turns the 1/√(θ − θ0) singularity at the start into a smooth integrand.
    // cos θ0 − cos θ = 2 sin((θ + θ0)/2) sin((θ − θ0)/2) keeps its digits next to θ0, where
    // the plain difference cancels (it left a 2.5e-12 floor on every method's error).
    let integrand = |u: f64| {
        let gap = span * u * u;
        let theta = theta0 + gap;
        let drop = 2.0 * ((theta + theta0) / 2.0).sin() * (gap / 2.0).sin();
        let rate2 = 12.0 * g * drop / (l * (1.0 + 3.0 * theta.sin().powi(2)));
        2.0 * span * u / rate2.sqrt()
    };
    gauss_legendre(integrand, 0.0, 1.0, 4000)
}

fn section(title: &str, note: &str, trials: &[Trial]) {
    outln!("{title}\n{note}");
    out!("{}", simulation::bench::table(trials, &[]));
    outln!();
}

/// The three work–precision tables, and the trials of the double pendulum for the plot.
// The pendulum's exact period is a reference too (see `rod_landing_time`).
#[allow(clippy::disallowed_methods)]
pub fn run() -> Vec<Trial> {
    outln!("## Work–precision (integration wall time, median of 3 runs)\n");

    // Double pendulum to t = 10.
    let rel = "classics/double_pendulum.lag";
    let source = read(rel);
    let base = Options { until: Some(10.0), ..Options::default() };
    let mut bar = Bar::new("work–precision: double pendulum");
    let reference_options = options_for(&base, Method::Dop853, Setting::Tolerance(1e-14), 10.0);
    let reference = simulate_with(&source, &reference_options, &mut bar).expect("reference");
    let check_options = options_for(&base, Method::Dop853, Setting::Tolerance(1e-13), 10.0);
    let check = simulate_with(&source, &check_options, &mut bar).expect("check");
    let reference_error = final_state_error(&reference, &check);
    let mut error = |o: &Outcome| final_state_error(&reference, o);
    let double =
        work_precision(&source, &base, 10.0, &METHODS, 3, &mut error, &mut bar).expect("runs");
    drop(bar);
    section(
        "double pendulum (θ1 = θ2 = π/2 from rest), t = 10 s",
        &format!(
            "error: max |Δ(q, q̇)| at t = 10 against DOP853 at 1e-14 (which differs from 1e-13 by \
             {reference_error:.1e})"
        ),
        &double,
    );

    // Falling rod until it lands.
    let rel = "ps5/falling_rod.lag";
    let source = read(rel);
    let landing = rod_landing_time(std::f64::consts::FRAC_PI_6);
    let base = Options::default();
    let mut error = |o: &Outcome| (o.run.final_time - landing).abs();
    let mut bar = Bar::new("work–precision: falling rod");
    let rod =
        work_precision(&source, &base, landing, &METHODS, 3, &mut error, &mut bar).expect("runs");
    drop(bar);
    section(
        "falling rod from θ = π/6 until it lies flat",
        &format!("error: |landing time − {landing:.15}| (energy integral by quadrature)"),
        &rod,
    );

    // Simple pendulum over one exact period.
    let rel = "classics/simple_pendulum.lag";
    let source = read(rel);
    let (l, g, theta0) = (1.0f64, 9.81f64, 0.5f64);
    let period = 4.0 * (l / g).sqrt() * elliptic_k((theta0 / 2.0).sin());
    let base = Options { until: Some(period), ..Options::default() };
    let mut bar = Bar::new("work–precision: simple pendulum");
    let mut error = |o: &Outcome| {
        let s = &o.run.final_state;
        (s[0] - theta0).abs().max(s[1].abs())
    };
    let simple =
        work_precision(&source, &base, period, &METHODS, 3, &mut error, &mut bar).expect("runs");
    drop(bar);
    section(
        "simple pendulum (θ0 = 0.5), one period",
        &format!("error: max |Δ(θ, θ̇)| after the exact period T = {period:.15} s (AGM)"),
        &simple,
    );
    double
}
