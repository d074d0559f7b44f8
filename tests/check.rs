//! `check` on every example: all expectations hold, and a deliberately wrong copy of each one
//! fails, naming its line.

use lang::{ExprKind, StmtKind};

#[test]
fn every_example_passes_check() {
    let examples = lagrange_tests::examples();
    assert!(examples.len() >= 3, "the examples folder is missing");
    for (path, source) in examples {
        let result = cli::check::check_file(&path, &source);
        assert_eq!(result.exit_code, 0, "{path} fails:\n{}", result.report);
        assert_eq!(result.failed, 0);
        assert!(!result.report.contains("FAIL"), "{}", result.report);
    }
}

/// Inserts ` + 1/3` into each expectation in turn (after its right-hand side, or after the
/// first entry of a matrix right-hand side), and checks that exactly that line fails. The
/// dimension check would catch most of these first; it is off here so that the algebra is
/// what gets tested.
#[test]
fn a_wrong_copy_of_each_expectation_fails() {
    let mut mutated = 0;
    for (path, source) in lagrange_tests::examples() {
        let ast = lang::parse(&source).expect("examples parse");
        for stmt in &ast.stmts {
            let StmtKind::Expect { rhs, .. } = &stmt.kind else { continue };
            let at = match &rhs.kind {
                ExprKind::Matrix(rows) => rows[0][0].span.end,
                _ => rhs.span.end,
            };
            let wrong = format!("{} + 1/3{}", &source[..at], &source[at..]);
            let line = source[..stmt.span.start].matches('\n').count() + 1;
            let result =
                cli::check::check_file_with(&path, &wrong, engine::Options { units: false });
            assert_eq!(
                result.exit_code, 1,
                "{path}:{line} with `+ 1/3` still passes:\n{}",
                result.report
            );
            assert_eq!(result.failed, 1, "{}", result.report);
            assert!(
                result.report.contains(&format!("FAIL {path}:{line} ")),
                "the report does not name line {line}:\n{}",
                result.report
            );
            assert!(result.report.contains("lhs − rhs"), "no residual in:\n{}", result.report);
            mutated += 1;
        }
    }
    assert!(mutated >= 10, "only {mutated} expectations were mutated");
}

/// A wrong equation of motion reports its residual and a state where it is not zero.
#[test]
fn a_failure_shows_the_residual_and_a_state() {
    let source =
        "param m, g\ncoord x\nparticle p { mass m; position (0, x) }\ngravity g\nexpect x'' = g\n";
    let result = cli::check::check_file("drop.lag", source);
    assert_eq!(result.exit_code, 1);
    assert!(result.report.contains("drop.lag:5:1"), "{}", result.report);
    assert!(result.report.contains("at g = "), "{}", result.report);
}

/// A derived parameter (`w0 = sqrt(k/m)`) is sampled as its definition gives it from the
/// parameters it names, as every run sets it: drawn on its own it made a true line fail.
#[test]
fn an_expectation_with_a_derived_parameter_is_judged_where_it_means_what_the_scene_says() {
    let scene = "param m = 2 kg, k = 8 N/m\nparam w0 = sqrt(k/m)\ncoord x = 1 m\n\
        particle p { mass m; position (x, 0) }\npotential k/2*x^2\n";
    let holds = format!("{scene}expect x'' = -w0^2*x\nexpect at start: x'' = -w0^2*x\n");
    let result = cli::check::check_file("osc.lag", &holds);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    let wrong = format!("{scene}expect x'' = -2*w0^2*x\n");
    let result = cli::check::check_file("osc.lag", &wrong);
    assert_eq!(result.exit_code, 1, "{}", result.report);
}
