//! Time derivatives of what the derivation computes: `dt(KE)`, `KE'`, `dt(PE)` and the rate
//! of a reaction are the derivatives of the energies and forces the scene turns out to have,
//! not of stand-in constants; and no `dt` reaches past the accelerations.

// The finite-difference reference is plain arithmetic on the recorded columns.
#![allow(clippy::disallowed_methods)]

use simulation::{simulate, Options};

/// A block on a spring, pushed by a constant force: T = ½·m·x\u{307}², V = ½·k·x², and the power
/// balance d(T + V)/dt = F·x\u{307}.
const PUSHED: &str = "scene \"Pushed block\"
param m = 2 kg, k = 3 N/m, F = 1 N
coord x = 1 m, x' = 1 m/s
particle b { mass m; position (x, 0) }
potential k/2*x^2
force push on b: (F, 0)
";

fn derive(source: &str) -> String {
    cli::derive("scene.lag", source, cli::Format::Text).unwrap_or_else(|e| panic!("{e}"))
}

fn refused(source: &str) -> String {
    match cli::derive("scene.lag", source, cli::Format::Text) {
        Ok(report) => panic!("accepted:\n{report}"),
        Err(diagnostics) => diagnostics,
    }
}

#[test]
fn the_rate_of_the_kinetic_energy_is_the_power_of_the_forces() {
    let report = derive(&format!("{PUSHED}show dt(KE), KE', dt(KE*x), dt(PE)\n"));
    assert!(report.contains("KE′ = (F − k·x)·x\u{307}"), "{report}");
    // The product rule, with KE's own rate: x\u{307}·KE + x·(F − k·x)·x\u{307}.
    assert!(report.contains("dt(KE*x) = ½·(m·x\u{307}² − 2·k·x² + 2·F·x)·x\u{307}"), "{report}");
    assert!(report.contains("PE′ = k·x·x\u{307}"), "{report}");
}

#[test]
fn a_power_balance_holds_and_a_false_conservation_fails() {
    let balance = format!("{PUSHED}expect dt(KE + PE) = F*x'\n");
    let result = cli::check::check_file("pushed.lag", &balance);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(result.held, 1, "{}", result.report);

    // With KE and PE taken as constants this passed, exactly.
    let conserved = format!("{PUSHED}expect dt(KE + PE) = 0\n");
    let result = cli::check::check_file("pushed.lag", &conserved);
    assert_eq!(result.exit_code, 1, "{}", result.report);
    assert_eq!(result.failed, 1, "{}", result.report);
}

/// The recorded `dt(KE)` and `dt(floor.force)` of the falling rod agree with central
/// differences of the recorded KE and reaction.
#[test]
fn recorded_rates_match_finite_differences_of_the_recorded_values() {
    let path = lagrange_tests::examples_dir().join("ps5/falling_rod.lag");
    let source = std::fs::read_to_string(path).expect("example");
    let outcome = simulate(
        &source,
        &Options {
            method: Some("dop853".into()),
            tolerance: Some(1e-12),
            until: Some(0.4),
            samples: 400,
            output: vec!["KE, dt(KE), floor.force, dt(floor.force)".into()],
            ..Options::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let rows = &outcome.run.trajectory.rows;
    let times = &outcome.run.trajectory.times;
    assert!(rows.len() > 100);
    let mut compared = 0;
    for i in 1..rows.len() - 1 {
        let h = times[i + 1] - times[i - 1];
        for (value, rate) in [(0, 1), (2, 3)] {
            let difference = (rows[i + 1][value] - rows[i - 1][value]) / h;
            let scale = 1.0 + rows[i][rate].abs();
            assert!(
                (difference - rows[i][rate]).abs() < 1e-3 * scale,
                "t = {}: column {rate} is {}, the difference {difference}",
                times[i],
                rows[i][rate]
            );
            compared += 1;
        }
    }
    assert!(compared > 200);
    // The rod speeds up from rest: KE rises, so its rate is not the stand-in's 0.
    assert!(rows[rows.len() / 2][1] > 1.0, "{:?}", rows[rows.len() / 2]);
}

#[test]
fn no_rate_reaches_past_the_accelerations() {
    let third = refused(&format!("{PUSHED}show dt(x'')\n"));
    assert!(third.contains("`dt(x'')` needs the third derivative of `x`"), "{third}");
    let nested = refused(&format!("{PUSHED}show dt(dt(dt(x)))\n"));
    assert!(nested.contains("needs the third derivative of `x`"), "{nested}");
    let energy = refused(&format!("{PUSHED}show dt(dt(KE))\n"));
    assert!(
        energy.contains("`dt(dt(KE))` needs a third derivative of the coordinates"),
        "{energy}"
    );
    assert!(energy.contains("`KE` can be differentiated once"), "{energy}");
    // V has positions only: twice is fine.
    let report = derive(&format!("{PUSHED}show PE''\n"));
    assert!(report.contains("PE′′ = k·(x\u{307}² − k·x²/m + F·x/m)"), "{report}");
}

/// Past four unknowns the reactions are not solved symbolically, and their rates are refused
/// at the `dt` that asks for one.
#[test]
fn the_rate_of_a_reaction_needs_the_symbolic_solve() {
    let path = lagrange_tests::examples_dir().join("../tests/scenes/seven_links_six_loops.lag");
    let source = std::fs::read_to_string(path).expect("scene");
    let diagnostics = refused(&format!("{source}show dt(loop1.force)\n"));
    assert!(diagnostics.contains("the rate of `loop1.force` is not available"), "{diagnostics}");
    assert!(diagnostics.contains("only up to 4 unknowns, and this scene has 13"), "{diagnostics}");
}
