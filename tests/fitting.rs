//! `lagrange fit`: the residuals' Jacobian against central differences of whole runs (in
//! parameters, derived ones following, in start values, with a series-driven input and with a
//! kept constraint), the examples' recordings remade from their seeds, each example's fit
//! recovering the values its recording was made with to two standard errors (a damped
//! pendulum; a pushed cart with a hanging pole; a chaotic double pendulum by multiple
//! shooting), the fitted scene written back, and bad data refused at its cell.

use fit::data;

fn example(name: &str) -> String {
    lagrange_tests::example(&format!("fitting/{name}"))
}

/// The push that drives the cart's recording: two sines sampled every 0.05 s over 6 s.
fn push() -> sim::Series {
    let times: Vec<f64> = (0..=120).map(|k| k as f64 * 0.05).collect();
    let sin = |x: f64| numeric::elementary::apply(cas::Func::Sin, x);
    let values = times.iter().map(|t| 2.0 * sin(1.3 * t) + 1.5 * sin(3.1 * t)).collect();
    sim::Series::new(times, values).expect("a series")
}

fn push_csv() -> String {
    let series = push();
    let mut text = String::from("t,F\n");
    for k in 0..=120 {
        let t = k as f64 * 0.05;
        text.push_str(&format!("{t},{:.6}\n", series.at(t)));
    }
    text
}

/// Each example's recording: its scene, the true values, the columns and their noise, the
/// span and samples, the seed.
fn recordings() -> Vec<(&'static str, String)> {
    let pendulum = lagrange_tests::recording(
        &example("damped_pendulum.lag"),
        &[("L", "1.1"), ("c", "0.3")],
        &[],
        &[("theta", 0.01)],
        (10.0, 201),
        7,
    );
    let push = cli::series::parse(&push_csv()).expect("the push reads back");
    let cart = lagrange_tests::recording(
        &example("cart_pendulum.lag"),
        &[("b", "0.8"), ("I", "0.009")],
        &[("F", push)],
        &[("x", 0.002), ("theta", 0.005)],
        (6.0, 241),
        11,
    );
    let double = lagrange_tests::recording(
        &example("double_pendulum.lag"),
        &[("l2", "1"), ("m2", "1")],
        &[],
        &[("theta1", 0.005), ("theta2", 0.005)],
        (4.0, 201),
        13,
    );
    vec![
        ("damped_pendulum.csv", pendulum),
        ("push.csv", push_csv()),
        ("cart_pendulum.csv", cart),
        ("double_pendulum.csv", double),
    ]
}

#[test]
fn the_examples_recordings_are_what_their_seeds_make() {
    let dir = lagrange_tests::examples_dir().join("fitting");
    for (name, text) in recordings() {
        let path = dir.join(name);
        if std::env::var_os("LAGRANGE_REMAKE_RECORDINGS").is_some() {
            std::fs::write(&path, &text).expect("writable");
        }
        let kept = std::fs::read_to_string(&path).expect("the recording is kept");
        assert!(
            kept == text,
            "{name} is not what its seed makes (LAGRANGE_REMAKE_RECORDINGS=1 remakes it)"
        );
    }
}

fn options(free: &str, shots: usize) -> fit::Options {
    fit::Options { free: fit::parse_free(free).expect("names"), shots, ..Default::default() }
}

fn table(name: &str) -> data::Table {
    let path = lagrange_tests::examples_dir().join("fitting").join(name);
    let text = std::fs::read_to_string(path).expect("the recording is kept");
    data::read(&text).expect("the recording reads")
}

/// The fit of `scene` to `recording` freeing `free`: each estimate within two standard errors
/// of `truth`, and the standard errors small against the values.
fn recovers(scene: &str, recording: &str, mut options: fit::Options, truth: &[f64]) -> fit::Fit {
    if recording == "cart_pendulum.csv" {
        options.run.input_series = vec![("F".into(), push())];
    }
    let result = fit::fit(&example(scene), &options, table(recording)).expect("fits");
    assert!(result.ending.converged(), "{:?}", result.ending);
    for (j, u) in result.unknowns.iter().enumerate() {
        let (estimate, error) = (result.estimates[j], result.standard_errors[j]);
        assert!(
            (estimate - truth[j]).abs() <= 2.0 * error,
            "{}: {estimate} ± {error}, truly {}",
            u.name,
            truth[j]
        );
        assert!(error < 0.05 * truth[j].abs(), "{}: ± {error} of {}", u.name, truth[j]);
    }
    result
}

#[test]
fn a_damped_pendulums_length_and_damping_are_recovered() {
    let result =
        recovers("damped_pendulum.lag", "damped_pendulum.csv", options("L, c", 1), &[1.1, 0.3]);
    // The noise was 0.01 rad: the residuals' RMS is that, to the sample's spread.
    let rms = result.columns[0].rms;
    assert!((rms - 0.01).abs() < 0.002, "RMS {rms}");
    assert!(result.unidentifiable.is_none());
}

#[test]
fn a_pushed_carts_friction_and_its_poles_inertia_are_recovered() {
    recovers("cart_pendulum.lag", "cart_pendulum.csv", options("b, I", 1), &[0.8, 0.009]);
}

#[test]
fn a_chaotic_double_pendulum_is_fitted_by_multiple_shooting() {
    let result =
        recovers("double_pendulum.lag", "double_pendulum.csv", options("l2, m2", 6), &[1.0, 1.0]);
    assert_eq!(result.shots, 6);
}

/// The largest entry of the residuals' Jacobian less central differences of whole runs, at
/// `theta`, relative to the Jacobian's largest entry.
fn jacobian_against_differences(
    scene: &str,
    recording: &str,
    options: fit::Options,
    theta: &[f64],
) -> f64 {
    let mut problem =
        fit::problem::Problem::load(&example(scene), &options, table(recording)).expect("loads");
    let exact = problem.evaluate(theta).expect("runs");
    let width = problem.width();
    let rows = exact.residuals.len();
    let largest = exact.jacobian.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for j in 0..width {
        let h = 1e-5 * theta[j].abs().max(1e-2);
        let mut at = theta.to_vec();
        at[j] += h;
        let up = problem.evaluate(&at).expect("runs").residuals;
        at[j] = theta[j] - h;
        let down = problem.evaluate(&at).expect("runs").residuals;
        for i in 0..rows {
            let difference = (up[i] - down[i]) / (2.0 * h);
            worst = worst.max((exact.jacobian[i * width + j] - difference).abs());
        }
    }
    worst / largest
}

#[test]
fn the_jacobian_is_what_differences_of_whole_runs_give() {
    let mut tight = options("L, c, theta(0), theta'(0)", 1);
    tight.run.tolerance = Some(1e-13);
    let pendulum = jacobian_against_differences(
        "damped_pendulum.lag",
        "damped_pendulum.csv",
        tight,
        &[1.05, 0.25, 0.98, 0.1],
    );
    assert!(pendulum < 1e-7, "pendulum: {pendulum:.1e}");
    let mut driven = options("b, I, x'(0)", 1);
    driven.run.tolerance = Some(1e-13);
    driven.run.input_series = vec![("F".into(), push())];
    let cart = jacobian_against_differences(
        "cart_pendulum.lag",
        "cart_pendulum.csv",
        driven,
        &[0.7, 0.01, 0.05],
    );
    assert!(cart < 1e-7, "cart: {cart:.1e}");
}
