//! Expression structure (precedence, associativity, postfix forms) and units.

use lang::{parse, Expr, StmtKind, Unit};

/// The expression of `let e = <text>`.
fn expr(text: &str) -> Expr {
    let file = parse(&format!("let e = {text}")).unwrap_or_else(|d| panic!("{text:?}: {d:#?}"));
    match file.stmts.into_iter().next().map(|s| s.kind) {
        Some(StmtKind::Let { value, .. }) => value,
        other => panic!("not a let: {other:?}"),
    }
}

fn sexpr(text: &str) -> String {
    expr(text).to_sexpr()
}

/// `a` and `b` parse to the same tree, spans aside.
fn same(a: &str, b: &str) {
    assert_eq!(sexpr(a), sexpr(b), "{a:?} vs {b:?}");
}

#[test]
fn additive_and_multiplicative_operators_are_left_associative() {
    same("a - b - c", "(a - b) - c");
    same("a + b - c + d", "((a + b) - c) + d");
    same("a/b*c", "(a/b)*c");
    same("a/b/c", "(a/b)/c");
    assert_eq!(sexpr("a - b - c"), "(- (- a b) c)");
}

#[test]
fn multiplication_binds_tighter_than_addition() {
    same("a + b*c", "a + (b*c)");
    same("a*b + c/d", "(a*b) + (c/d)");
    same("m/2*x'^2 - k/2*x^2", "((m/2)*(x'^2)) - ((k/2)*(x^2))");
}

#[test]
fn power_is_right_associative_and_binds_tighter_than_unary_minus() {
    same("2^3^2", "2^(3^2)");
    same("-x^2", "-(x^2)");
    assert_eq!(sexpr("-x^2"), "(neg (^ x 2))");
    same("a*b^c", "a*(b^c)");
    same("x^-2", "x^(-2)");
    same("x^-2*y", "(x^(-2))*y");
    same("-a*b", "(-a)*b");
    same("a - -b", "a - (-b)");
}

#[test]
fn postfix_forms() {
    assert_eq!(sexpr("theta''"), "theta''");
    assert_eq!(sexpr("x'"), "x'");
    assert_eq!(sexpr("disk.omega"), "disk.omega");
    assert_eq!(sexpr("atan2(y, x)"), "(call atan2 y x)");
    assert_eq!(sexpr("sin(theta)^2"), "(^ (call sin theta) 2)");
    assert_eq!(sexpr("(x, y, z)"), "(tuple x y z)");
    assert_eq!(sexpr("(a + b)"), "(+ a b)");
    assert_eq!(sexpr("[a, b; c, d]"), "(matrix (a b) (c d))");
    assert_eq!(sexpr("[x''; s'']"), "(matrix (x'') (s''))");
    assert_eq!(sexpr("θ + θ'"), "(+ θ θ')");
    assert_eq!(sexpr("_k2"), "_k2");
}

#[test]
fn numbers_keep_their_text() {
    for n in ["12", "0.1", "1e-3", "2.5E+4", "007"] {
        assert_eq!(sexpr(n), n);
    }
}

#[test]
fn spans_cover_the_text() {
    let e = expr("(a + b)*c");
    assert_eq!((e.span.start, e.span.end), (8, 17));
    let e = expr("-x^2");
    assert_eq!((e.span.start, e.span.end), (8, 12));
}

#[test]
fn brackets_may_span_lines_after_commas() {
    same("(a,\n  b)", "(a, b)");
    same("[a, b;\n c, d\n]", "[a, b; c, d]");
    same("atan2(\n y,\n x\n)", "atan2(y, x)");
}

fn param_units(line: &str) -> Vec<Option<Unit>> {
    match parse(line).map(|f| f.stmts.into_iter().next().map(|s| s.kind)) {
        Ok(Some(StmtKind::Param(decls))) => decls.into_iter().map(|d| d.unit).collect(),
        other => panic!("{line:?}: {other:?}"),
    }
}

fn powers(unit: &Option<Unit>) -> Vec<(String, i32)> {
    let unit = unit.as_ref().expect("a unit");
    unit.factors.iter().map(|(name, p)| (name.name.clone(), *p)).collect()
}

fn pairs(list: &[(&str, i32)]) -> Vec<(String, i32)> {
    list.iter().map(|&(n, p)| (n.to_string(), p)).collect()
}

#[test]
fn units_have_the_right_powers() {
    let line =
        "param m = 1 kg, g = 9.81 m/s^2, I = 2 kg*m^2, T = 3 N*m, r = 1/10 m, k = 5 kg/s^2/m^-1, c";
    let units = param_units(line);
    assert_eq!(powers(&units[0]), pairs(&[("kg", 1)]));
    assert_eq!(powers(&units[1]), pairs(&[("m", 1), ("s", -2)]));
    assert_eq!(powers(&units[2]), pairs(&[("kg", 1), ("m", 2)]));
    assert_eq!(powers(&units[3]), pairs(&[("N", 1), ("m", 1)]));
    assert_eq!(powers(&units[4]), pairs(&[("m", 1)]));
    assert_eq!(powers(&units[5]), pairs(&[("kg", 1), ("s", -2), ("m", 1)]));
    assert!(units[6].is_none());
    let span = units[1].as_ref().map(|u| &line[u.span.start..u.span.end]);
    assert_eq!(span, Some("m/s^2"));
}

#[test]
fn units_may_be_denominators_only_and_follow_any_value() {
    let line = "param k = 1/2 1/m, w = 3 1/s, a = 2 rad/s^2, s = 1/2 N/m, q = 2 m^-1, \
                I = sqrt(3)/2 kg*m^2, f = 2*pi 1 / s";
    let units = param_units(line);
    assert_eq!(powers(&units[0]), pairs(&[("m", -1)]));
    assert_eq!(powers(&units[1]), pairs(&[("s", -1)]));
    assert_eq!(powers(&units[2]), pairs(&[("rad", 1), ("s", -2)]));
    assert_eq!(powers(&units[3]), pairs(&[("N", 1), ("m", -1)]));
    assert_eq!(powers(&units[4]), pairs(&[("m", -1)]));
    assert_eq!(powers(&units[5]), pairs(&[("kg", 1), ("m", 2)]));
    assert_eq!(powers(&units[6]), pairs(&[("s", -1)]));
    let span = units[0].as_ref().map(|u| &line[u.span.start..u.span.end]);
    assert_eq!(span, Some("1/m"));

    let Ok(file) = parse(line) else { panic!("{line:?} does not parse") };
    let Some(StmtKind::Param(decls)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    let values: Vec<String> =
        decls.iter().map(|d| d.value.as_ref().map(Expr::to_sexpr).unwrap_or_default()).collect();
    assert_eq!(values[0], "(/ 1 2)");
    assert_eq!(values[5], "(/ (call sqrt 3) 2)");
    assert_eq!(values[6], "(* 2 pi)");

    // Without a value before it, `1/m` is a division, as it always was.
    let file = parse("param k = 1/m").expect("parses");
    let Some(StmtKind::Param(decls)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    assert!(decls[0].unit.is_none());
    assert_eq!(decls[0].value.as_ref().map(Expr::to_sexpr).as_deref(), Some("(/ 1 m)"));

    let file = parse("coord theta = 0, theta' = 1/2 1/s").expect("parses");
    let Some(StmtKind::Coord(decls)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    assert_eq!(powers(&decls[0].rate_unit), pairs(&[("s", -1)]));
}

#[test]
fn coord_lines_attach_rates_and_units() {
    let file = parse("coord theta = 30 deg, theta' = 2 rad/s, x").expect("parses");
    let Some(StmtKind::Coord(decls)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    assert_eq!(decls.len(), 2);
    assert_eq!(decls[0].name.name, "theta");
    assert_eq!(decls[0].value.as_ref().map(Expr::to_sexpr).as_deref(), Some("30"));
    assert_eq!(powers(&decls[0].value_unit), pairs(&[("deg", 1)]));
    assert_eq!(decls[0].rate.as_ref().map(Expr::to_sexpr).as_deref(), Some("2"));
    assert_eq!(powers(&decls[0].rate_unit), pairs(&[("rad", 1), ("s", -1)]));
    assert_eq!(decls[1].name.name, "x");
    assert!(decls[1].value.is_none() && decls[1].rate.is_none());
}

#[test]
fn simulate_settings_keep_values_and_units() {
    let file = parse(
        "simulate {\n  until 2 s\n  method dop853; tolerance 1e-10\n  output theta, KE + PE\n}",
    )
    .expect("parses");
    let Some(StmtKind::Simulate(settings)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    let keys: Vec<&str> = settings.iter().map(|s| s.key.name.as_str()).collect();
    assert_eq!(keys, ["until", "method", "tolerance", "output"]);
    assert_eq!(powers(&settings[0].unit), pairs(&[("s", 1)]));
    let out: Vec<String> = settings[3].values.iter().map(Expr::to_sexpr).collect();
    assert_eq!(out, ["theta", "(+ KE PE)"]);
}

#[test]
fn linearize_about_gives_positions_and_rates() {
    let file = parse("linearize about theta = pi, x' = 0, psi' = 60 rad/s").expect("parses");
    let Some(StmtKind::Linearize(items)) = file.stmts.first().map(|s| &s.kind) else { panic!() };
    let written: Vec<(String, u8, String)> =
        items.iter().map(|i| (i.name.name.clone(), i.primes, i.value.to_sexpr())).collect();
    let expected = [("theta", 0, "pi"), ("x", 1, "0"), ("psi", 1, "60")];
    let expected: Vec<(String, u8, String)> =
        expected.iter().map(|(n, p, v)| (n.to_string(), *p, v.to_string())).collect();
    assert_eq!(written, expected);
    assert_eq!(powers(&items[2].unit), pairs(&[("rad", 1), ("s", -1)]));
    let source = "linearize about theta = pi, x' = 0, psi' = 60 rad/s";
    assert_eq!(&source[items[0].span.start..items[0].span.end], "theta = pi");

    let errors = parse("linearize about theta'' = 0").expect_err("an acceleration");
    assert!(errors[0].message.contains("positions and rates only"), "{errors:?}");
    let errors = parse("linearize theta = 0").expect_err("no `about`");
    assert!(errors[0].message.contains("`about`"), "{errors:?}");
}

#[test]
fn other_statements() {
    let file = parse(
        "scene \"A \\\"quoted\\\" title\"\nconstraint x^2 + y^2 = L^2\ngravity g along (0, -1)\n\
         force push on bead: (F0*cos(w*t), 0)\ntorque drive on rod: tau0\n\
         let start = 1 # keywords are names elsewhere\nshow at, on",
    )
    .expect("parses");
    let kinds: Vec<&StmtKind> = file.stmts.iter().map(|s| &s.kind).collect();
    assert!(matches!(kinds[0], StmtKind::Scene { title } if title == "A \"quoted\" title"));
    assert!(matches!(kinds[1], StmtKind::Constraint { name: None, .. }));
    assert!(
        matches!(kinds[2], StmtKind::Gravity { direction: Some(d), .. } if d.to_sexpr() == "(tuple 0 (neg 1))")
    );
    assert!(
        matches!(kinds[3], StmtKind::Force { name, body, .. } if name.name == "push" && body.name == "bead")
    );
    assert!(matches!(kinds[4], StmtKind::Torque { body, .. } if body.name == "rod"));
    assert!(matches!(kinds[5], StmtKind::Let { name, .. } if name.name == "start"));
    assert!(matches!(kinds[6], StmtKind::Show { at_start: false, items } if items.len() == 2));
}
