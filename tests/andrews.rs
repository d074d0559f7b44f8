//! Andrews' squeezing mechanism (`examples/classics/andrews_squeezer.lag`) against the numbers
//! published for it: seven bodies, six loop constraints kept with multipliers (13 unknowns at
//! the start, past the exact solve), a drive torque and a spring.
//!
//! The references are those of the Test Set for IVP Solvers (Mazzia, Magherini et al.,
//! University of Bari), problem "andrews", as also given by Hairer & Wanner, Solving ODEs II,
//! section VII.7: the consistent initial accelerations and multipliers, and the solution at
//! t = 0.03 s, computed there with PSIDE at tolerances 1e-14 in Cray double precision.
//!
//! Sign convention: the test set writes M·q̈ = f − Gᵀ·λ with g = (the loops' residuals), lagrange
//! M·q̈ = f + Jᵀ·λ with Φ = lhs − rhs. The scene's loops are written so that Φ is the test set's
//! g, row for row (`loop_b.x`, `loop_b.y`, `loop_a.x`, …), so each multiplier here is minus the
//! test set's, in the same order.

use simulation::{simulate, Options};

const SCENE: &str = "classics/andrews_squeezer.lag";

/// β̈, Θ̈, γ̈, Φ̈, δ̈, Ω̈, ε̈ at the consistent start (the test set's initial y(15..21), given
/// there to 30 digits, here to a double's).
const ACCELERATIONS: [f64; 7] =
    [14_222.443_919_954_114, -10_666.832_939_965_585, 0.0, 0.0, 0.0, 0.0, 0.0];

/// The test set's λ₁ … λ₆ at the start (its y(22..27)), with its sign.
const MULTIPLIERS: [f64; 6] = [98.566_870_396_241_09, -6.122_688_344_255_662, 0.0, 0.0, 0.0, 0.0];

/// β, Θ, γ, Φ, δ, Ω, ε at t = 0.03 s (the test set's reference solution, y(1..7)).
const AT_003: [f64; 7] = [
    0.158_107_711_962_990_4e2,
    -0.157_563_710_598_429_8e2,
    0.408_222_401_307_310_1e-1,
    -0.534_730_116_322_694_8,
    0.524_409_965_880_530_4,
    0.534_730_116_322_694_8,
    0.104_808_074_104_226_3e1,
];

/// The same angles at t = 0.03 s from an RK4 of the test set's equations with Richardson
/// extrapolation (see the test that uses them); its two runs differ by 5e-13 at most.
const INDEPENDENT: [f64; 7] = [
    15.810_771_195_153_817,
    -15.756_371_058_412_006,
    0.040_822_240_119_542_54,
    -0.534_730_116_342_269_1,
    0.524_409_965_879_954_4,
    0.534_730_116_342_252_1,
    1.048_080_741_041_882_4,
];

fn scene() -> String {
    lagrange_tests::example(SCENE)
}

fn report(source: &str) -> String {
    cli::derive("andrews_squeezer.lag", source, cli::Format::Text).unwrap_or_else(|e| panic!("{e}"))
}

/// The numbers after `label ≈` in a text report: one, or a vector's components.
fn shown(text: &str, label: &str) -> Vec<f64> {
    let prefix = format!("{label} ≈ ");
    let line = text
        .lines()
        .map(str::trim_start)
        .find(|l| l.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no `{prefix}` in\n{text}"));
    line[prefix.len()..]
        .trim_matches(|c| c == '(' || c == ')')
        .split(", ")
        .map(|v| v.trim().replace('−', "-").parse().unwrap_or_else(|_| panic!("{line}")))
        .collect()
}

/// The largest difference between `got` and `want`, relative to the largest of `want`: the
/// zeros of the reference are compared on the scale of the values that are not zero.
fn relative(got: &[f64], want: &[f64]) -> f64 {
    assert_eq!(got.len(), want.len());
    let scale = want.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    got.iter().zip(want).fold(0.0f64, |m, (g, w)| m.max((g - w).abs())) / scale
}

const ACCELERATION_LABELS: [&str; 7] =
    ["β\u{308}", "Θ\u{308}", "γ\u{308}", "Φ\u{308}", "δ\u{308}", "Ω\u{308}", "ε\u{308}"];

#[test]
fn the_start_shows_the_published_accelerations_and_multipliers() {
    let text = report(&scene());
    assert!(text.contains("solved numerically: 13 unknowns"), "{text}");

    let accelerations: Vec<f64> =
        ACCELERATION_LABELS.iter().map(|label| shown(&text, label)[0]).collect();
    let off = relative(&accelerations, &ACCELERATIONS);
    assert!(off < 1e-9, "accelerations {accelerations:?}: {off:e} off");

    // The test set's λ in its order, with its sign: minus ours.
    let multipliers: Vec<f64> = ["loop_b.force", "loop_a.force", "loop_c.force"]
        .iter()
        .flat_map(|label| shown(&text, label))
        .map(|l| -l)
        .collect();
    let off = relative(&multipliers, &MULTIPLIERS);
    assert!(off < 1e-9, "multipliers {multipliers:?}: {off:e} off");

    // The same from the numeric start itself, to all the digits it keeps.
    let mut d = engine::load(&scene()).expect("derives").derivation;
    assert_eq!(d.unknowns().len(), 13);
    let params = verify::parameter_values(&d).expect("every parameter has a value");
    let start = verify::start_numeric(&mut d, &params).expect("regular at the start");
    let accelerations: Vec<f64> = d.accels.iter().map(|a| start.values[a.index()]).collect();
    let off = relative(&accelerations, &ACCELERATIONS);
    assert!(off < 1e-14, "accelerations {accelerations:?}: {off:e} off");
    let names: Vec<&str> =
        d.multipliers.iter().map(|m| d.model.constraints[m.constraint].name.as_str()).collect();
    assert_eq!(names, ["loop_b.x", "loop_b.y", "loop_a.x", "loop_a.y", "loop_c.x", "loop_c.y"]);
    let multipliers: Vec<f64> =
        d.multipliers.iter().map(|m| -start.values[m.lambda.index()]).collect();
    let off = relative(&multipliers, &MULTIPLIERS);
    assert!(off < 1e-12, "multipliers {multipliers:?}: {off:e} off");
    assert!(start.digits >= 9, "only {} digits", start.digits);
}

/// The test set's 30-digit angles lie on the loops to their rounding and are taken as given;
/// one of them cut to 7 digits is refused; given β alone, the six other angles are solved from
/// the loops by Newton's method from rough guesses, and they are the test set's.
#[test]
fn the_published_start_is_on_the_loops_and_follows_from_beta() {
    let source = scene();
    let result = cli::check::check_file("andrews_squeezer.lag", &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);

    let cut =
        source.replace("coord gamma = 0.455279819163070380255912382449", "coord gamma = 0.4552798");
    assert_ne!(cut, source);
    let result = cli::check::check_file("andrews_squeezer.lag", &cut);
    assert_eq!(result.exit_code, 2, "{}", result.report);
    assert!(
        result.report.contains("the start positions do not satisfy `loop_b.x`"),
        "{}",
        result.report
    );

    let guessed = lagrange_tests::andrews_with_guesses(&source);
    let given = engine::load(&source).expect("derives").derivation;
    let published: Vec<f64> = given
        .model
        .coords
        .iter()
        .map(|c| numeric::eval(&given.model.pool, c.initial, &[]))
        .collect();
    let mut d = engine::load(&guessed).expect("derives").derivation;
    assert_eq!(d.solved_start_positions.len(), 6);
    let params = verify::parameter_values(&d).expect("every parameter has a value");
    let start = verify::start_numeric(&mut d, &params).expect("regular at the start");
    let solved: Vec<f64> = d.coords.iter().map(|q| start.values[q.index()]).collect();
    for (k, (s, p)) in solved.iter().zip(&published).enumerate() {
        assert!((s - p).abs() < 1e-14, "angle {k}: solved {s}, published {p}");
    }
    // Newton's positions are the published ones to 1e-14; the accelerations move by 1e-12.
    let accelerations: Vec<f64> = d.accels.iter().map(|a| start.values[a.index()]).collect();
    let off = relative(&accelerations, &ACCELERATIONS);
    assert!(off < 1e-11, "accelerations {accelerations:?}: {off:e} off");
}

/// DOP853 at the scene's tolerance (1e-12) to t = 0.03 s: the angles against the published
/// solution, and the work of the drive against the energy.
#[test]
fn dop853_reaches_the_published_solution_at_three_hundredths_of_a_second() {
    let options = Options {
        samples: 2,
        output: vec!["beta, Theta, gamma, Phi, delta, Omega, epsilon, KE + PE - mom*beta".into()],
        ..Options::default()
    };
    let outcome = simulate(&scene(), &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    let rows = &outcome.run.trajectory.rows;
    let (first, last) = (&rows[0], rows.last().expect("rows"));
    assert!((outcome.run.trajectory.times.last().copied().unwrap_or(0.0) - 0.03).abs() < 1e-15);
    // The published solution agrees with this run to 1.1e-9 in β and 1.4e-9 in Θ (which have
    // turned about 2.5 times, to 15.8 rad), 2e-11 in γ, Φ and Ω, and 6e-13 in δ and ε.
    for (k, want) in AT_003.iter().enumerate() {
        let got = last[k];
        assert!((got - want).abs() < 2e-9, "angle {k}: {got} against {want}");
    }
    // The difference is the reference's: RK4 of the test set's own M, f and G (its Fortran
    // formulas, not lagrange's derivation) in plain floats, index 1 (G·q̈ = −Ġ·q̇), with 40000
    // and 80000 steps extrapolated (Richardson), agrees with this run to 1e-12.
    for (k, want) in INDEPENDENT.iter().enumerate() {
        let got = last[k];
        assert!((got - want).abs() < 1e-11, "angle {k}: {got} against {want}");
    }
    // The torque is constant, so T + V − mom·β is conserved.
    let drift = (last[7] - first[7]).abs();
    assert!(drift < 1e-9, "T + V − mom·β drifted by {drift:e}");
}

/// The loops as they are, under radau: the index-3 system in (q, q̇, q̈, λ), no Baumgarte.
#[test]
fn radau_on_the_index_three_system_reaches_the_published_solution() {
    let options = Options { method: Some("radau".into()), samples: 2, ..Options::default() };
    let outcome = simulate(&scene(), &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    assert_eq!(outcome.run.final_time, 0.03);
    let last = outcome.run.trajectory.rows.last().expect("rows");
    // At the scene's tolerance, 1e-12, the angles are within 1.7e-12 of dop853's at 1e-14,
    // relative to each angle where it exceeds 1 (lagrange-bench tolerance); against the
    // published solution, itself 1e-9 off in β and Θ (above), within 1e-8 relative to β
    // (which has turned to 15.8 rad).
    let scale = AT_003[0].abs();
    for (k, want) in AT_003.iter().enumerate() {
        let off = (last[k] - want).abs() / scale;
        assert!(off < 1e-8, "angle {k}: {} against {want}, {off:e} relative", last[k]);
    }
    let drift = outcome.constraint_drift_at_steps().expect("six loops");
    assert!(drift < 1e-11, "{}", cli::simulate::summary(&outcome));
}

/// `expect at start:` with the published numbers holds (decided at the parameters' values,
/// where the start is), and a value off in the eighth digit does not.
#[test]
fn expectations_at_the_start_hold_and_wrong_ones_fail() {
    let source = scene();
    let result = cli::check::check_file("andrews_squeezer.lag", &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(result.held, 4, "{}", result.report);
    assert!(result.report.contains("13 unknowns solved numerically"), "{}", result.report);

    let line = "expect at start: beta'' = 14222.4439199541138705911625887";
    assert!(source.contains(line));
    let wrong = source.replace(line, "expect at start: beta'' = 14222.444");
    let result = cli::check::check_file("andrews_squeezer.lag", &wrong);
    assert_eq!(result.exit_code, 1, "{}", result.report);
    assert_eq!(result.failed, 1, "{}", result.report);
    assert!(result.report.contains("DOES NOT HOLD"), "{}", result.report);

    // The multiplier with the test set's sign is minus lagrange's: that fails too.
    let line = "expect at start: loop_b.force.x = -98.5668703962410896057654982170";
    assert!(source.contains(line));
    let flipped =
        source.replace(line, "expect at start: loop_b.force.x = 98.5668703962410896057654982170");
    let result = cli::check::check_file("andrews_squeezer.lag", &flipped);
    assert_eq!(result.exit_code, 1, "{}", result.report);
}
