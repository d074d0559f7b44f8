//! The sample scenes of the design sketch parse, with the statements and spans expected.

use lang::{parse, Expr, ExprKind, SceneFile, Shape, StmtKind};

const INCLINE: &str = include_str!("scenes/incline.lag");
const DISK: &str = include_str!("scenes/disk.lag");
const ROD: &str = include_str!("scenes/rod.lag");
const SKETCH: &str = include_str!("scenes/sketch.lag");

fn parse_ok(source: &str) -> SceneFile {
    match parse(source) {
        Ok(file) => file,
        Err(diags) => panic!("parse failed: {diags:#?}"),
    }
}

/// Every expression of a statement, outermost first.
fn exprs_of(kind: &StmtKind) -> Vec<&Expr> {
    let mut out: Vec<&Expr> = Vec::new();
    match kind {
        StmtKind::Scene { .. } => {}
        StmtKind::Param(decls) | StmtKind::Input(decls) => {
            out.extend(decls.iter().filter_map(|d| d.value.as_ref()))
        }
        StmtKind::Output { value, .. } => out.push(value),
        StmtKind::ExpectLinearized(lang::LinearExpectation::Eigenvalue(value))
        | StmtKind::ExpectLinearized(lang::LinearExpectation::Critical { value, .. }) => {
            out.push(value)
        }
        StmtKind::ExpectLinearized(_) => {}
        StmtKind::Let { value, .. } => out.push(value),
        StmtKind::Coord(decls) => {
            for d in decls {
                out.extend(d.value.iter().chain(d.rate.iter()));
            }
        }
        StmtKind::Particle { props, .. } | StmtKind::Body { props, .. } => {
            out.extend(props.iter().map(|p| &p.value))
        }
        StmtKind::Constraint { lhs, rhs, .. } | StmtKind::Expect { lhs, rhs, .. } => {
            out.extend([lhs, rhs])
        }
        StmtKind::Contact { lhs, rhs, laws, .. } => {
            out.extend([lhs, rhs]);
            out.extend(laws.iter().map(|p| &p.value));
        }
        StmtKind::Gravity { strength, direction } => {
            out.push(strength);
            out.extend(direction.iter());
        }
        StmtKind::Potential(e) | StmtKind::Dissipation(e) | StmtKind::Lagrangian(e) => out.push(e),
        StmtKind::Force { value, .. } | StmtKind::Torque { value, .. } => out.push(value),
        StmtKind::Spring { a, b, stiffness, rest, .. } => {
            out.extend([a, b, stiffness]);
            out.extend(rest.iter());
        }
        StmtKind::Damper { a, b, coefficient, .. } => out.extend([a, b, coefficient]),
        StmtKind::Show { items, .. } => out.extend(items.iter()),
        StmtKind::Simulate(settings) => out.extend(settings.iter().flat_map(|s| s.values.iter())),
        StmtKind::Linearize(items) => out.extend(items.iter().map(|i| &i.value)),
        StmtKind::Draw(Shape::Line { from, to }) => out.extend([from, to]),
        StmtKind::Draw(Shape::Circle { centre, radius }) => out.extend([centre, radius]),
        StmtKind::Draw(Shape::Polyline(points)) => out.extend(points.iter()),
    }
    out
}

fn subexprs<'a>(expr: &'a Expr, out: &mut Vec<&'a Expr>) {
    out.push(expr);
    match &expr.kind {
        ExprKind::Number(_) | ExprKind::Name { .. } | ExprKind::Member { .. } => {}
        ExprKind::Neg(inner) => subexprs(inner, out),
        ExprKind::Binary { lhs, rhs, .. } => {
            subexprs(lhs, out);
            subexprs(rhs, out);
        }
        ExprKind::Call { args: items, .. } | ExprKind::Tuple(items) => {
            items.iter().for_each(|e| subexprs(e, out))
        }
        ExprKind::Matrix(rows) => rows.iter().flatten().for_each(|e| subexprs(e, out)),
    }
}

#[test]
fn sample_scenes_parse() {
    for source in [INCLINE, DISK, ROD, SKETCH] {
        let file = parse_ok(source);
        assert!(matches!(file.stmts[0].kind, StmtKind::Scene { .. } | StmtKind::Param(_)));
    }
}

#[test]
fn rod_scene_has_the_expected_statements() {
    let file = parse_ok(ROD);
    let texts: Vec<&str> = file.stmts.iter().map(|s| &ROD[s.span.start..s.span.end]).collect();
    assert_eq!(
        texts,
        [
            "scene \"Rod falls with its end on a frictionless floor\"",
            "param m = 1 kg, L = 1 m, g = 9.81 m/s^2",
            "coord x = L/4",
            "coord y",
            "coord theta = pi/6",
            "body rod { mass m; inertia m*L^2/12; position (x, y); angle theta }",
            "constraint floor: y = L/2*cos(theta)",
            "gravity g",
            "show at start: theta'', floor.force",
            "expect x'' = 0",
            "expect theta''*(1 + 3*sin(theta)^2) + 3*theta'^2*sin(theta)*cos(theta) = 6*g/L*sin(theta)",
            "expect at start: theta'' = 12/7*g/L",
            "expect at start: floor.force = 4/7*m*g",
        ]
    );
    let StmtKind::Body { name, props } = &file.stmts[5].kind else { panic!("not a body") };
    assert_eq!(name.name, "rod");
    let keys: Vec<&str> = props.iter().map(|p| p.key.name.as_str()).collect();
    assert_eq!(keys, ["mass", "inertia", "position", "angle"]);
    let StmtKind::Show { at_start: true, items } = &file.stmts[8].kind else {
        panic!("not show at start")
    };
    let items: Vec<String> = items.iter().map(Expr::to_sexpr).collect();
    assert_eq!(items, ["theta''", "floor.force"]);
}

#[test]
fn disk_scene_has_a_multiline_body_and_a_named_constraint() {
    let file = parse_ok(DISK);
    let body = file.stmts.iter().find_map(|s| match &s.kind {
        StmtKind::Body { props, .. } => Some(props),
        _ => None,
    });
    let props = body.expect("a body");
    assert_eq!(props.len(), 4);
    assert_eq!(props[3].value.to_sexpr(), "(+ phi theta)");
    let constraint = file.stmts.iter().find_map(|s| match &s.kind {
        StmtKind::Constraint { name, lhs, rhs } => Some((name, lhs, rhs)),
        _ => None,
    });
    let (name, lhs, rhs) = constraint.expect("a constraint");
    assert_eq!(name.as_ref().map(|n| n.name.as_str()), Some("rolling"));
    assert_eq!(lhs.to_sexpr(), "(* r phi)");
    assert_eq!(rhs.to_sexpr(), "(* R theta)");
}

#[test]
fn incline_scene_has_the_matrix_expectation() {
    let file = parse_ok(INCLINE);
    let Some(StmtKind::Expect { lhs, rhs, at_start: false, .. }) =
        file.stmts.last().map(|s| &s.kind)
    else {
        panic!("last statement is not an expect")
    };
    assert_eq!(
        lhs.to_sexpr(),
        "(* (matrix ((+ (/ M m) 1) (call cos theta)) ((call cos theta) 1)) (matrix (x'') (s'')))"
    );
    assert_eq!(rhs.to_sexpr(), "(matrix (0) ((* g (call sin theta))))");
}

/// Every expression's span is exactly its text: re-parsing that text gives the same tree.
#[test]
fn expression_spans_are_exact() {
    for source in [INCLINE, DISK, ROD, SKETCH] {
        let file = parse_ok(source);
        for stmt in &file.stmts {
            for top in exprs_of(&stmt.kind) {
                let mut all = Vec::new();
                subexprs(top, &mut all);
                for expr in all {
                    let text = &source[expr.span.start..expr.span.end];
                    let again = parse_ok(&format!("let e = {text}"));
                    let StmtKind::Let { value, .. } = &again.stmts[0].kind else { panic!() };
                    assert_eq!(value.to_sexpr(), expr.to_sexpr(), "span text {text:?}");
                }
            }
        }
    }
}

#[test]
fn springs_and_dampers_parse() {
    let file =
        lang::parse("spring s between cart and (0, 1): k, l0\ndamper d between cart and bob: c\n")
            .expect("parses");
    let StmtKind::Spring { name, a, b, stiffness, rest } = &file.stmts[0].kind else {
        panic!("not a spring")
    };
    assert_eq!(name.name, "s");
    assert_eq!(a.to_sexpr(), "cart");
    assert_eq!(b.to_sexpr(), "(tuple 0 1)");
    assert_eq!(stiffness.to_sexpr(), "k");
    assert_eq!(rest.as_ref().map(|r| r.to_sexpr()), Some("l0".to_string()));
    let StmtKind::Damper { coefficient, .. } = &file.stmts[1].kind else { panic!("not a damper") };
    assert_eq!(coefficient.to_sexpr(), "c");
}

#[test]
fn drawings_parse() {
    let file = lang::parse(
        "draw line from (0, 0) to bob.position\ndraw circle at disk radius r/2\n\
         draw polyline (0, 0), bob1, bob2 + (l, 0)\n",
    )
    .expect("parses");
    let StmtKind::Draw(Shape::Line { from, to }) = &file.stmts[0].kind else { panic!("a line") };
    assert_eq!((from.to_sexpr().as_str(), to.to_sexpr().as_str()), ("(tuple 0 0)", "bob.position"));
    let StmtKind::Draw(Shape::Circle { centre, radius }) = &file.stmts[1].kind else {
        panic!("a circle")
    };
    assert_eq!((centre.to_sexpr().as_str(), radius.to_sexpr().as_str()), ("disk", "(/ r 2)"));
    let StmtKind::Draw(Shape::Polyline(points)) = &file.stmts[2].kind else { panic!("a polyline") };
    let points: Vec<String> = points.iter().map(Expr::to_sexpr).collect();
    assert_eq!(points, ["(tuple 0 0)", "bob1", "(+ bob2 (tuple l 0))"]);
    // `line`, `to` and the like stay ordinary names outside a `draw` line.
    lang::parse("let line = to + from*radius\n").expect("names, not keywords");
}
