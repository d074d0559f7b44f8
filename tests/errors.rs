//! Bad input gets a clear error: file, line, column, a caret under the culprit, and a hint.
//! Each case's whole rendered diagnostic is pinned by a snapshot.

/// Runs the pipeline on a broken scene and returns the rendered diagnostics.
fn diagnose(source: &str) -> String {
    match engine::load(source) {
        Ok(_) => panic!("expected an error for:\n{source}"),
        Err(e) => cli::diagnostics::error("bad.lag", &e),
    }
}

fn assert_pinpointed(rendered: &str, line: usize, col: usize) {
    assert!(
        rendered.contains(&format!("bad.lag:{line}:{col}")),
        "no bad.lag:{line}:{col} in:\n{rendered}"
    );
    assert!(rendered.contains('^'), "no caret in:\n{rendered}");
    assert!(rendered.contains("hint:"), "no hint in:\n{rendered}");
}

#[test]
fn unknown_name() {
    let r = diagnose("param m, g\ncoord theta\nparticle p { mass m; position (sin(thta), 0) }\n");
    assert_pinpointed(&r, 3, 36);
    assert!(r.contains("did you mean `theta`?"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn unbalanced_bracket() {
    let r = diagnose("param m\ncoord x\nparticle p { mass m; position ((x, 0) }\n");
    assert!(r.contains("bad.lag:3:"), "{r}");
    assert!(r.contains('^'), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn constraint_on_an_undeclared_coordinate() {
    let r = diagnose(
        "param m, L\ncoord x\nparticle p { mass m; position (x, 0) }\nconstraint c: y = L\n",
    );
    assert_pinpointed(&r, 4, 15);
    assert!(r.contains("`coord y`"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn body_without_mass() {
    let r = diagnose(
        "param L\ncoord theta\nbody rod { inertia L^2/12; position (0, 0); angle theta }\n",
    );
    assert_pinpointed(&r, 3, 6);
    assert!(r.contains("has no mass"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn implicit_multiplication() {
    let r = diagnose("param m, g\ncoord y\nparticle p { mass m; position (0, 2y) }\n");
    assert!(r.contains("2*y"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn coordinate_used_before_it_is_declared() {
    let r = diagnose("param m\nparticle p { mass m; position (x, 0) }\ncoord x\n");
    assert_pinpointed(&r, 2, 32);
    assert!(r.contains("declared here"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn several_errors_are_all_reported() {
    let r = diagnose("param m\ncoord x\nparticle p { mass mm; position (x, 0) }\nparticle q { mass m; position (xx, 0) }\n");
    assert!(r.contains("bad.lag:3:"), "{r}");
    assert!(r.contains("bad.lag:4:"), "{r}");
}

#[test]
fn a_coordinate_nothing_moves_with() {
    let r = diagnose("param m\ncoord x, y\nparticle p { mass m; position (x, 0) }\n");
    assert!(r.contains("no kinetic energy depends on the rate of `y`"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn a_dimension_mistake_names_both_terms() {
    let r = diagnose(
        "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord theta = pi/6\nparticle p { mass m; position (L*sin(theta), -L*cos(theta)) }\npotential m*g*theta\n",
    );
    assert!(r.contains("kg·m/s² here, kg·m²/s² there"), "{r}");
    assert!(r.contains("bad.lag:4:11"), "{r}");
    assert!(
        r.contains("3 │ particle p") && r.contains("- kg·m²/s²"),
        "the other term is not shown:\n{r}"
    );
    insta::assert_snapshot!(r);
}

#[test]
fn an_unknown_unit() {
    let r = diagnose("param m = 1 KG\ncoord x\nparticle p { mass m; position (x, 0) }\n");
    assert_pinpointed(&r, 1, 13);
    assert!(r.contains("did you mean `kg`?"), "{r}");
    insta::assert_snapshot!(r);
}

#[test]
fn units_can_be_switched_off() {
    let source = "param m = 1 kg, g = 9.81 m/s^2\ncoord theta\nparticle p { mass m; position (sin(theta), -cos(theta)) }\npotential m*g*theta\n";
    assert!(engine::load(source).is_err());
    assert!(engine::load_with(source, engine::Options { units: false }).is_ok());
}

#[test]
fn an_unused_parameter_is_a_warning() {
    let source =
        "param m, k, spare\ncoord x\nparticle p { mass m; position (x, 0) }\npotential k/2*x^2\n";
    let warnings = engine::load(source).expect("derives despite the warning").warnings;
    let r = cli::diagnostics::render("bad.lag", source, &warnings);
    assert!(r.contains("warning: parameter `spare` is never used"), "{r}");
    assert!(r.contains("bad.lag:1:13"), "{r}");
}

#[test]
fn an_initial_value_the_constraint_overrides_is_a_warning() {
    let source = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord x = L/4\ncoord y = 2 m\ncoord theta = pi/6\nbody rod { mass m; inertia m*L^2/12; position (x, y); angle theta }\nconstraint floor: y = L/2*cos(theta)\ngravity g\n";
    let warnings = engine::load(source).expect("derives despite the warning").warnings;
    let r = cli::diagnostics::render("bad.lag", source, &warnings);
    assert!(r.contains("warning: the initial value of `y` is ignored"), "{r}");
    assert!(r.contains("bad.lag:3:7"), "{r}");
    // A value that agrees with the constraint is no reason to warn.
    let agreeing = source.replace("coord y = 2 m", "coord y = sqrt(3)/4 m");
    let warnings = engine::load(&agreeing).expect("derives").warnings;
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[test]
fn an_empty_scene_is_refused() {
    for source in ["", "\n\n", "# only a comment\n"] {
        let r = diagnose(source);
        assert!(r.contains("error: the scene is empty"), "{r}");
        assert_pinpointed(&r, 1, 1);
    }
    let r = diagnose("param m = 1 kg, L = 1 m\nparticle p { mass m; position (L, 0) }\n");
    assert!(r.contains("the scene declares no coordinate"), "{r}");
    assert_pinpointed(&r, 2, 10);
}

#[test]
fn a_third_derivative_is_refused_where_it_is_written() {
    let scene = "param m = 1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\n";
    let r = diagnose(&format!("{scene}expect x''' = 0\n"));
    assert!(r.contains("`x'''` is a third derivative"), "{r}");
    assert_pinpointed(&r, 4, 8);
    let r = diagnose(&format!("{scene}let a = x''\nshow a'\n"));
    assert!(r.contains("`a'` needs the third derivative of `x`"), "{r}");
    assert_pinpointed(&r, 5, 6);
    // A long row of primes on a `let` name is refused before its derivatives are built.
    let primes = "'".repeat(200);
    let r = diagnose(&format!("{scene}let s = sin(x)^3\nshow s{primes}\n"));
    assert!(r.contains("derivative"), "{r}");
}

#[test]
fn masses_and_inertias_of_the_wrong_sign_are_refused() {
    let r = diagnose("param m = -1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\n");
    assert!(r.contains("the mass of `p` is negative"), "{r}");
    assert!(r.contains("`m` is -1 kg"), "{r}");
    assert_pinpointed(&r, 3, 19);
    let r = diagnose("coord x\nparticle p { mass 0; position (x, 0) }\n");
    assert!(r.contains("the mass of `p` is zero"), "{r}");
    let r = diagnose("param m = 1 kg, L = 1 m\ncoord th\nbody b { mass m; inertia -m*L^2; position (0, 0); angle th }\n");
    assert!(r.contains("the inertia of `b` is negative"), "{r}");
    assert_pinpointed(&r, 3, 26);
    // Without values the sign is unknown, and the scene stands.
    assert!(engine::load("param m\ncoord x\nparticle p { mass -m; position (x, 0) }\n").is_ok());
    let zero_inertia = "param m = 1 kg, L = 1 m\ncoord th\nbody b { mass m; inertia 0; position (th*L, 0); angle th }\n";
    assert!(engine::load_with(zero_inertia, engine::Options { units: false }).is_ok());
}

#[test]
fn constants_that_are_not_real_numbers_are_refused() {
    let scene = "coord x\nparticle p { mass m; position (x, 0) }\n";
    for (value, message, col) in [
        ("sqrt(-1)", "the square root of a negative number is not real", 11),
        ("ln(-1)", "the logarithm of a negative number is not real", 11),
        ("ln(0)", "the logarithm of 0", 11),
        ("acos(3/2)", "acos of a number outside [-1, 1]", 11),
        ("1e400", "this value is not a finite number", 11),
        ("(-1)^(1/2)", "a negative number to a fractional power", 11),
    ] {
        let r = diagnose(&format!("param m = 1 kg, a = {value}\n{scene}"));
        assert!(r.contains(message), "{value}:\n{r}");
        assert_pinpointed(&r, 1, col + 10);
    }
    let r = diagnose(&format!("param m = 1 kg, a = 0, b = 1/a\n{scene}"));
    assert!(r.contains("division by zero") && r.contains("`a` is 0"), "{r}");
    assert_pinpointed(&r, 1, 30);
    // A function of a coordinate is no constant: its domain is the motion's business.
    assert!(engine::load(
        "param m = 1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\nshow sqrt(-1 - x^2)\n"
    )
    .is_ok());
}

#[test]
fn rates_are_refused_where_only_the_configuration_counts() {
    let r = diagnose("param m = 1 kg\ncoord x\nparticle p { mass m; position (x', 0) }\n");
    assert!(r.contains("a position cannot depend on a rate"), "{r}");
    assert!(!r.contains("no kinetic energy"), "{r}");
    assert_pinpointed(&r, 3, 32);
    let r = diagnose("param m = 1 kg, k = 1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\npotential k*x'^2\n");
    assert!(r.contains("a potential cannot depend on a rate"), "{r}");
    assert_pinpointed(&r, 4, 13);
    let r = diagnose("param m = 1 kg\ncoord x\nlet v = x'\nparticle p { mass m; position (x, 0) }\nparticle q { mass m; position (x, v*1) }\n");
    assert!(r.contains("depends on the rate of `x`"), "{r}");
    assert_pinpointed(&r, 5, 35);
    let r = diagnose("param m = 1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\nforce f on p: (-m*x'', 0)\n");
    assert!(r.contains("a force cannot depend on an acceleration"), "{r}");
    // Rates are what forces, dissipation and a Lagrangian are made of.
    assert!(engine::load("param m = 1 kg, c = 1 kg/s\ncoord x\nparticle p { mass m; position (x, 0) }\nforce f on p: (-c*x', 0)\ndissipation c/2*x'^2\nlagrangian c*x*x'\n").is_ok());
}

#[test]
fn an_expectation_check_cannot_decide_is_a_warning() {
    let source = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\ngravity g\nexpect x'' = 0\nexpect sqrt(-1 - x^2/L^2) = 0\nexpect x'' = ln(-(x/L)^2 - 1)*g\nexpect sqrt(x/L) = sqrt(-x/L)\n";
    let warnings = engine::load(source).expect("derives despite the warnings").warnings;
    let r = cli::diagnostics::render("bad.lag", source, &warnings);
    assert_eq!(r.matches("warning: `check` cannot decide this expectation").count(), 3, "{r}");
    assert!(r.contains("bad.lag:6:8"), "{r}");
    assert!(r.contains("√(−1 − x²/L²) is not a real number"), "{r}");
    assert!(r.contains("bad.lag:7:14"), "{r}");
    assert!(r.contains("bad.lag:8:1"), "{r}");
    assert!(!r.contains("bad.lag:5:"), "a decidable line is not warned about:\n{r}");
    // The warning foresees what check finds.
    let checked = cli::check::check_file("bad.lag", source);
    assert_eq!(checked.exit_code, 1);
    assert_eq!(checked.report.matches("UNDECIDED").count(), 3, "{}", checked.report);
    insta::assert_snapshot!(r);

    let singular = "param m = 1 kg, k = 1 N/m\ncoord r = 0 m, phi\nparticle p { mass m; position (r*cos(phi), r*sin(phi)) }\npotential k/2*r^2\nexpect at start: r'' = 0\n";
    let warnings = engine::load(singular).expect("derives despite the warning").warnings;
    let r = cli::diagnostics::render("bad.lag", singular, &warnings);
    assert!(r.contains("the mass matrix is singular at the start"), "{r}");
    assert!(r.contains("bad.lag:5:1"), "{r}");
    let checked = cli::check::check_file("bad.lag", singular);
    assert!(checked.report.contains("UNDECIDED"), "{}", checked.report);
}
