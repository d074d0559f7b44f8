//! Constraints kept with multipliers: `expect` decided on the constraint surface (exactly
//! where the constraints reduce the residual, numerically at projected states otherwise),
//! repeated and contradicting constraints refused, values at the start found in bounded
//! time however many unknowns there are, and a lost Jacobian rank named in `simulate`.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use std::path::Path;

fn scene(name: &str) -> (String, String) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let source = std::fs::read_to_string(&path).expect("test scene");
    (format!("tests/scenes/{name}"), source)
}

#[test]
fn a_tension_that_holds_only_on_the_circle_holds_exactly_there() {
    let (path, source) = scene("pendulum_on_its_constraint.lag");
    let result = cli::check::check_file(&path, &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!((result.held, result.failed), (4, 0));
    assert_eq!(
        result.report.matches("holds exactly on the constraint surface").count(),
        4,
        "{}",
        result.report
    );
}

#[test]
fn a_wrong_tension_still_fails_on_the_circle() {
    let (path, source) = scene("pendulum_on_its_constraint.lag");
    let wrong = source.replace("(g*y - x'^2 - y'^2)", "(g*y + x'^2 - y'^2)");
    assert_ne!(wrong, source);
    let result = cli::check::check_file(&path, &wrong);
    assert_eq!(result.exit_code, 1, "{}", result.report);
    assert_eq!(result.failed, 1, "{}", result.report);
    // The state it names is on the circle.
    assert!(result.report.contains("DOES NOT HOLD"), "{}", result.report);
}

#[test]
fn numbers_decide_on_projected_states_where_the_algebra_cannot() {
    let (path, source) = scene("bead_on_a_cubic.lag");
    let result = cli::check::check_file(&path, &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(
        result.report.matches("random states on the constraint surface").count(),
        2,
        "{}",
        result.report
    );
    let wrong = source.replace("expect y^3 = c^3 - a^3", "expect y^3 = c^3 + a^3");
    let result = cli::check::check_file(&path, &wrong);
    assert_eq!(result.exit_code, 1, "{}", result.report);
}

/// The states a numeric check samples satisfy the constraints: Φ = 0 and Φ̇ = 0 there.
#[test]
fn the_state_of_a_failure_is_on_the_constraint() {
    let (path, source) = scene("bead_on_a_cubic.lag");
    let wrong = source.replace("expect y^3 = c^3 - a^3", "expect y^3 = c^3 + a^3");
    let mut d = engine::load(&wrong).expect("derives").derivation;
    let verdicts = verify::check_all(&mut d);
    let verify::Verdict::Fails(failure) = &verdicts[0] else { panic!("{path}: {:?}", verdicts[0]) };
    let value = |name: &str| {
        failure
            .state
            .iter()
            .find(|(s, _)| d.model.pool.symbol(*s).name == name)
            .map(|(_, v)| *v)
            .unwrap_or_else(|| panic!("no {name} in the failure's state"))
    };
    let (a, c, x, y) = (value("a"), value("c"), value("x"), value("y"));
    let phi = a.powi(3) * (x / a).sin() + y.powi(3) - c.powi(3);
    assert!(phi.abs() < 1e-9, "Φ = {phi} at the failing state");
}

#[test]
fn a_repeated_constraint_is_named_at_derive_time() {
    let source = "param m, L, g\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\n\
                  constraint rod: x^2 + y^2 = L^2\nconstraint again: 2*x^2 + 2*y^2 = 2*L^2\ngravity g\n";
    let result = cli::check::check_file("twice.lag", source);
    assert_eq!(result.exit_code, 2, "{}", result.report);
    assert!(
        result.report.contains("constraint `again` repeats the ones before it"),
        "{}",
        result.report
    );
    assert!(result.report.contains("twice.lag:6:1"), "{}", result.report);
}

#[test]
fn a_contradicting_constraint_is_named_at_derive_time() {
    let source = "param m, L, g\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\n\
                  constraint rod: x^2 + y^2 = L^2\nconstraint other: x^2 + y^2 = 4*L^2\ngravity g\n";
    let result = cli::check::check_file("both.lag", source);
    assert_eq!(result.exit_code, 2, "{}", result.report);
    assert!(
        result.report.contains("constraint `other` contradicts the ones before it"),
        "{}",
        result.report
    );
}

/// A velocity constraint that asks the time derivative of a kept position constraint for
/// another value: named as a contradiction, not as start rates a hint could fix.
#[test]
fn a_velocity_constraint_contradicting_a_position_one_is_named() {
    let source = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2, v0 = 1 m^2/s\n\
                  coord x = 0.6 m, y = -0.8 m\nparticle p { mass m; position (x, y) }\n\
                  constraint rod: x^2 + y^2 = L^2\nconstraint push: x*x' + y*y' = v0\ngravity g\n";
    let result = cli::check::check_file("push.lag", source);
    assert_eq!(result.exit_code, 2, "{}", result.report);
    assert!(
        result.report.contains("constraint `push` contradicts the ones before it"),
        "{}",
        result.report
    );
    assert!(!result.report.contains("rates at the start"), "{}", result.report);
}

#[test]
fn a_constraint_no_start_reaches_is_warned_about() {
    let source = "param m, L, g\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\n\
                  constraint ring: x^2 + y^2 = -L^2\ngravity g\n";
    let warnings = engine::load(source).expect("derives").warnings;
    assert!(
        warnings
            .iter()
            .any(|w| w.message.contains("no random start reached a state where `ring` holds")),
        "{warnings:?}"
    );
}

/// Independent constraints (a double pendulum in Cartesian coordinates) are not flagged.
#[test]
fn independent_constraints_pass() {
    let source = "param m, L, g\ncoord x1\ncoord y1\ncoord x2\ncoord y2\n\
                  particle p { mass m; position (x1, y1) }\nparticle q { mass m; position (x2, y2) }\n\
                  constraint one: x1^2 + y1^2 = L^2\nconstraint two: (x2 - x1)^2 + (y2 - y1)^2 = L^2\ngravity g\n";
    let result = cli::check::check_file("double.lag", source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
}

/// Thirteen unknowns at the start: the values come numerically, saying so and with a digit
/// count, instead of an exact solve that runs for minutes.
#[test]
fn thirteen_unknowns_at_the_start_are_solved_numerically() {
    let (_, source) = scene("seven_links_six_loops.lag");
    let mut d = engine::load(&source).expect("derives").derivation;
    assert_eq!(d.unknowns().len(), 13);
    let text = cli::report::text(&mut d);
    assert!(text.contains("solved numerically: 13 unknowns"), "{text}");
    let line = text.lines().find(|l| l.contains(" ≈ ")).expect("t7'' is shown");
    let shown: f64 = line
        .split('≈')
        .nth(1)
        .expect("a value")
        .trim()
        .replace('−', "-")
        .parse()
        .expect("a number");
    // At rest, the constraints' acceleration rows say J·q̈ = 0; the solved start satisfies
    // every row of the system.
    let params = verify::parameter_values(&d).expect("every parameter has a value");
    let start = verify::start_numeric(&mut d, &params).expect("regular at the start");
    let t7 = d.accels[6];
    assert!((start.values[t7.index()] - shown).abs() <= 1e-9 * shown.abs().max(1.0));
    let (rows, rhs) = d.system();
    for (row, b) in rows.iter().zip(&rhs) {
        let lhs: f64 = row
            .iter()
            .zip(d.unknowns())
            .map(|(e, u)| numeric::eval(&d.model.pool, *e, &start.values) * start.values[u.index()])
            .sum();
        let b = numeric::eval(&d.model.pool, *b, &start.values);
        assert!((lhs - b).abs() < 1e-9 * (1.0 + b.abs()), "row residual {}", lhs - b);
    }
    assert!(start.digits >= 8, "only {} digits", start.digits);

    let result = cli::check::check_file("seven.lag", &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert!(result.report.contains("13 unknowns solved numerically"), "{}", result.report);
    let wrong = source.replace("expect at start: KE = 0", "expect at start: t7'' = 0");
    let result = cli::check::check_file("seven.lag", &wrong);
    assert_eq!(result.exit_code, 1, "{}", result.report);
}

/// Where the exact solve fits its budget, the numeric one agrees with it: the 4-link
/// pendulum at distinct angles, moving.
#[test]
fn the_numeric_start_agrees_with_the_exact_one() {
    let family = lang::generate::Family::from_name("n-link-pendulum").expect("a family");
    let mut source = lang::generate::n_link(family, 4);
    for k in 1..=4 {
        source = source.replace(
            &format!("coord theta{k} = 1/10"),
            &format!("coord theta{k} = {k}/10, theta{k}' = 1"),
        );
    }
    let mut d = engine::load(&source).expect("derives").derivation;
    let mechanics::StartSolution::Exact(exact) = d.unknowns_at_start() else {
        panic!("the 4-link start fits the budget")
    };
    let params = verify::parameter_values(&d).expect("values");
    let start = verify::start_numeric(&mut d, &params).expect("regular");
    for u in d.unknowns() {
        let x = numeric::eval(&d.model.pool, exact[&u], &start.values);
        let y = start.values[u.index()];
        assert!((x - y).abs() < 1e-10 * (1.0 + x.abs()), "{x} against {y}");
    }
}

/// A constraint whose gradient vanishes where the run starts: simulate says the Jacobian,
/// not the mass matrix, lost rank, and names the constraint.
#[test]
fn simulate_names_a_constraint_that_lost_its_gradient() {
    let source = "param m = 1, g = 9.81\ncoord x = 0\ncoord y = 0\n\
                  particle bead { mass m; position (x, y) }\nconstraint line: x^3 = y^3\ngravity g\n";
    let options = simulation::Options { until: Some(1.0), ..Default::default() };
    let outcome = simulation::simulate(source, &options).unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().expect("a fault");
    assert!(matches!(fault.kind, sim::FaultKind::SingularConstraints { .. }), "{fault:?}");
    let text = outcome.describe_fault(fault);
    assert!(text.contains("constraints' Jacobian lost rank"), "{text}");
    assert!(text.contains("`line`"), "{text}");
}

/// A velocity constraint (set in the model: the language does not write one yet) is kept,
/// and checks sample states whose rates satisfy it: a knife edge at angle theta that cannot
/// slide sideways, sin(theta)·ẋ = cos(theta)·ẏ, which holds nowhere else.
#[test]
fn checks_sample_rates_that_satisfy_a_velocity_constraint() {
    let source = "param m = 1 kg, I = 1 kg*m^2\ncoord x\ncoord y\ncoord theta\n\
                  body blade { mass m; inertia I; position (x, y); angle theta }\n\
                  constraint edge: x^2 = y^2\n\
                  expect sin(theta)*x' = cos(theta)*y'\nexpect x' = y'\n";
    let ast = lang::parse(source).expect("parses");
    let (mut model, _) = model::resolve(&ast, source).expect("resolves");
    let pool = &mut model.pool;
    let rate = |pool: &mut cas::Pool, name: &str| {
        let s = pool.lookup_symbol(name).expect("declared");
        let r = pool.rate(s).expect("a coordinate");
        pool.sym(r)
    };
    let (xd, yd) = (rate(pool, "x"), rate(pool, "y"));
    let theta = pool.lookup_symbol("theta").expect("declared");
    let theta = pool.sym(theta);
    let (s, c) = (pool.sin(theta), pool.cos(theta));
    let (a, b) = (pool.mul2(s, xd), pool.mul2(c, yd));
    model.constraints[0].kind = model::ConstraintKind::Velocity;
    model.constraints[0].phi = pool.sub(a, b);
    let mut d = mechanics::derive(model).expect("derives");
    assert_eq!(d.coords.len(), 3, "a velocity constraint eliminates nothing");
    assert_eq!(d.multipliers.len(), 1);
    let verdicts = verify::check_all(&mut d);
    assert!(
        matches!(
            verdicts[0],
            verify::Verdict::Numeric { sampling: verify::Sampling::OnConstraints, .. }
        ),
        "{:?}",
        verdicts[0]
    );
    assert!(matches!(verdicts[1], verify::Verdict::Fails(_)), "{:?}", verdicts[1]);
}

/// A velocity constraint the position constraints imply is left out with a warning, and the
/// report lists it as left out, with why, not as kept with a multiplier.
#[test]
fn a_constraint_left_out_is_listed_as_left_out() {
    let source = "param m, L = 1, g\ncoord x = 1, y = 0\nparticle bead { mass m; position (x, y) }\n\
                  gravity g\nconstraint ring: x^2 + y^2 = L^2\nconstraint radial: x*x' + y*y' = 0\n";
    let report = cli::derive("radial.lag", source, cli::Format::Text).expect("derives");
    let listed = report.split("  radial:").nth(1).expect("radial is listed");
    let said = listed.lines().nth(1).unwrap_or_default();
    assert_eq!(
        said,
        "    left out, as it restrains nothing more: the time derivative of `ring` says as much",
        "{report}"
    );
    assert!(!listed.contains("multiplier radial.force"), "{report}");
}

/// Reports name a vector constraint's component reactions `roll.x.force`; a scene may write
/// that name as well as `roll.force.x`.
#[test]
fn a_component_reaction_goes_by_the_name_the_report_prints() {
    let scene = lagrange_tests::example("space/ball_on_turntable.lag");
    let both = format!("{scene}expect roll.x.force = roll.force.x\n");
    let result = cli::check::check_file("turntable.lag", &both);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert!(
        result.report.contains("expect roll.x.force = roll.force.x  — holds exactly"),
        "{}",
        result.report
    );
    let other = format!("{scene}expect roll.x.force = roll.force.y\n");
    assert_eq!(cli::check::check_file("turntable.lag", &other).exit_code, 1);
}
