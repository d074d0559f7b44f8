//! The start against the kept constraints: a start that breaks one is refused with its
//! residual, positions the scene leaves free (`coord y ~ -1`) are solved, the rates follow
//! the constraints at the velocity level, a start that holds only at the parameters' values
//! is decided there, and `--set` values that break the start are caught before a run.

// The references are plain arithmetic (square roots of the closed forms).
#![allow(clippy::disallowed_methods)]

use simulation::{simulate, Options};

const PENDULUM: &str = "scene \"Cartesian pendulum\"
param m = 1 kg, L = 1 m, g = 9.81 m/s^2
COORDS
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";

fn pendulum(coords: &str) -> String {
    PENDULUM.replace("COORDS", coords)
}

fn refused(source: &str) -> String {
    let result = cli::check::check_file("scene.lag", source);
    assert_eq!(result.exit_code, 2, "accepted:\n{}", result.report);
    result.report
}

fn report(source: &str) -> String {
    cli::derive("scene.lag", source, cli::Format::Text).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_start_off_a_position_constraint_is_refused_with_its_residual() {
    let text = refused(&pendulum("coord x = 1 m, y = -1 m"));
    assert!(text.contains("the start positions do not satisfy `rod`"), "{text}");
    assert!(text.contains("this side minus that is 1"), "{text}");
    assert!(text.contains("`coord y ~ …`"), "{text}");

    // The unit constraint of Euler parameters, made by `quaternion(…)`: e·e = 1.25.
    let path = lagrange_tests::examples_dir().join("space/tennis_racket.lag");
    let racket = std::fs::read_to_string(path).expect("example");
    let off = racket.replace("coord e1 = 0,", "coord e1 = 1/2,");
    assert_ne!(off, racket);
    let text = refused(&off);
    assert!(text.contains("the start positions do not satisfy `racket_unit`"), "{text}");
    assert!(text.contains("2.5"), "{text}");
}

const SLIDER_CRANK: &str = "scene \"Slider-crank\"
param m = 1 kg, r = 1/10 m, l = 3/10 m, J = 1/100 kg*m^2
coord a = pi/6, a' = 1 rad/s
ROD
coord s
body crank { mass m; inertia J; position (r/2*cos(a), r/2*sin(a)); angle a }
particle slider { mass m; position (s, 0) }
constraint loop_y: r*sin(a) = l*sin(b)
constraint loop_x: s = r*cos(a) + l*cos(b)
show at start: b, b'
";

#[test]
fn a_slider_crank_with_a_wrong_rod_angle_is_refused_and_a_guess_is_solved() {
    let wrong = SLIDER_CRANK.replace("ROD", "coord b = 0.2");
    let text = refused(&wrong);
    assert!(text.contains("the start positions do not satisfy `loop_y`"), "{text}");

    let guessed = SLIDER_CRANK.replace("ROD", "coord b ~ 0.2");
    let text = report(&guessed);
    // r·sin a = l·sin b: sin b = 1/6; the rate from r·cos a·ȧ = l·cos b·ḃ.
    let b = (1.0f64 / 6.0).asin();
    let rate = 0.1 * (std::f64::consts::FRAC_PI_6).cos() / (0.3 * b.cos());
    assert!(text.contains("solved from the constraints"), "{text}");
    let shown = |label: &str| -> f64 {
        let line = text.lines().find(|l| l.trim_start().starts_with(label)).expect(label);
        line.split('≈').nth(1).expect("a value").trim().replace('−', "-").parse().expect("number")
    };
    assert!((shown("b ≈") - b).abs() < 1e-12, "{text}");
    assert!((shown("b\u{307} ≈") - rate).abs() < 1e-12, "{text}");
    assert!(text.contains("the start positions were solved numerically"), "{text}");

    // The run starts on both constraints and stays there.
    let outcome = simulate(
        &guessed,
        &Options { until: Some(1.0), tolerance: Some(1e-10), ..Options::default() },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (_, relative) = outcome.energy_drift();
    assert!(relative < 1e-8, "energy drift {relative:e}");
}

#[test]
fn free_positions_are_solved_near_their_guesses() {
    // Below the pivot, and above it: the guess picks the branch.
    for (guess, y) in [("-1", -0.8), ("1", 0.8)] {
        let text = report(&pendulum(&format!("coord x = 0.6 m, y ~ {guess} m")));
        assert!(
            text.contains(&format!("y   (from y ≈ {}", if y < 0.0 { "−0.8" } else { "0.8" })),
            "{text}"
        );
    }
    // A guess where the constraint's gradient in the free position vanishes cannot move.
    let text = refused(&pendulum("coord x = 0.6 m, y"));
    assert!(text.contains("could not be solved from `rod`"), "{text}");
    assert!(text.contains("coord y ~ …"), "{text}");
}

#[test]
fn values_given_to_some_digits_are_their_rounding() {
    // √3/2 to 12 digits: the residual is the rounding, not another start.
    let source = pendulum("coord x = 0.5 m, y = -0.866025403784 m");
    let result = cli::check::check_file("scene.lag", &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    // To 3 digits it is another start.
    refused(&pendulum("coord x = 0.5 m, y = -0.866 m"));
}

/// A ball on a turntable whose start rolls only because W = 1: the rows hold at the values
/// the run uses, and `--set W=2` breaks them.
#[test]
fn a_start_that_holds_at_the_parameters_values_is_decided_there() {
    let path = lagrange_tests::examples_dir().join("space/ball_on_turntable.lag");
    let scene = std::fs::read_to_string(path).expect("example");
    let at_values =
        scene.replace("coord y = 0, y' = 0.1 m/s", "coord y = 0, y' = 0.3 m/s").replace(
            "coord e0 = 1, e1 = 0, e2 = 0, e3 = 0, e3' = 0",
            "coord e0 = 1, e0' = 0, e1 = 0, e1' = 0, e2 = 0, e2' = 0, e3 = 0, e3' = 0",
        );
    assert_ne!(at_values, scene);
    let with_expect = format!("{at_values}expect at start: x'' = -2/7*W*y'\n");
    let result = cli::check::check_file("turntable.lag", &with_expect);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(result.held, 3, "{}", result.report);

    let elsewhere = at_values.replace("W = 1 1/s", "W = 2 1/s");
    let text = refused(&elsewhere);
    assert!(text.contains("the rates at the start do not satisfy `roll"), "{text}");

    let options = |set: &[&str]| Options {
        until: Some(0.1),
        set: set.iter().map(|s| s.parse().expect("name=value")).collect(),
        ..Options::default()
    };
    simulate(&at_values, &options(&[])).unwrap_or_else(|e| panic!("{e}"));
    let Err(error) = simulate(&at_values, &options(&["W=2"])) else {
        panic!("W = 2 breaks roll at the start, and the run went ahead")
    };
    assert!(error.to_string().contains("the start's rates break the constraint `roll"), "{error}");
    assert_eq!(error.exit_code(), 2);
}

#[test]
fn set_values_that_move_the_constraint_solve_free_positions_again() {
    let source = pendulum("coord x = 0.6 m, y ~ -1 m");
    let outcome = simulate(
        &source,
        &Options {
            until: Some(0.5),
            set: vec!["L=2".parse().expect("name=value")],
            output: vec!["x^2 + y^2".into()],
            ..Options::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let first = &outcome.run.trajectory.rows[0];
    assert!((first[0] - 4.0).abs() < 1e-12, "{first:?}");

    // Given positions are not moved: a length they do not fit is an error.
    let given = pendulum("coord x = 0.6 m, y = -0.8 m");
    let set = Options {
        until: Some(0.5),
        set: vec!["L=2".parse().expect("name=value")],
        ..Options::default()
    };
    let Err(error) = simulate(&given, &set) else { panic!("L = 2 is off the rod, and it ran") };
    assert!(error.to_string().contains("the start breaks the constraint `rod`"), "{error}");
}

#[test]
fn a_rate_cannot_be_a_guess() {
    let text = refused(&pendulum("coord x = 0.6 m, x' ~ 1, y ~ -1 m"));
    assert!(text.contains("the initial rate `x'` cannot be a guess"), "{text}");
}
