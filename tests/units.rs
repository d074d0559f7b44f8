//! The dimension check never rejects a consistent scene: every example and every cross-check
//! scene passes it, and so do the scenes of issue 9 (a zero in a matrix expectation, initial
//! values written as expressions, units like `1/m`); an inconsistent scene is still refused.

use std::path::Path;

/// Every `.lag` under `tests/sympy/scenes` and `tests/scenes`, sorted, as (path, source).
fn crosscheck_scenes() -> Vec<(String, String)> {
    let mut out = scenes_in("sympy/scenes");
    out.extend(scenes_in("scenes"));
    out
}

fn scenes_in(folder: &str) -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let mut out: Vec<(String, String)> = std::fs::read_dir(&dir)
        .expect("the test scenes exist")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .map(|p| {
            let name = p.file_name().expect("name").to_string_lossy().into_owned();
            let source = std::fs::read_to_string(&p).expect("readable");
            (format!("tests/{folder}/{name}"), source)
        })
        .collect();
    out.sort();
    out
}

/// The dimension errors of a scene that parses.
fn dimension_errors(path: &str, source: &str) -> String {
    let ast = match lang::parse(source) {
        Ok(ast) => ast,
        Err(e) => panic!("{path} does not parse:\n{}", cli::diagnostics::render(path, source, &e)),
    };
    cli::diagnostics::render(path, source, &model::dimension_errors(&ast))
}

#[test]
fn every_example_and_crosscheck_scene_is_dimensionally_consistent() {
    let mut scenes = lagrange_tests::examples();
    scenes.extend(crosscheck_scenes());
    assert!(scenes.len() >= 25, "only {} scenes", scenes.len());
    for (path, source) in scenes {
        assert_eq!(dimension_errors(&path, &source), "", "{path}");
        // And the whole pipeline, units on, accepts it.
        if let Err(e) = engine::load(&source) {
            panic!("{path}:\n{}", cli::diagnostics::error(&path, &e));
        }
    }
}

const CHARGE: &str = "scene \"charge\"
param m = 1 kg, q = 1 C, B = 2 T
coord x = 1 m, x' = 0
coord y = 0, y' = 1 m/s
lagrangian m/2*(x'^2 + y'^2) + q*B/2*(x*y' - y*x')
expect [m, 0; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']
";

const PENDULUM: &str = "scene \"t\"
param m = 1 kg, L = 1 m, g = 9.81 m/s^2, k = 1/2 1/m
coord theta = 0, theta' = 1/2*sqrt(3)
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

#[test]
fn a_zero_in_a_matrix_expectation_has_every_dimension() {
    let result = cli::check::check_file("charge.lag", CHARGE);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(result.failed, 0, "{}", result.report);
}

#[test]
fn values_written_as_expressions_and_inverse_units_derive() {
    let warnings = match engine::load(PENDULUM) {
        Ok(scene) => scene.warnings,
        Err(e) => panic!("{}", cli::diagnostics::error("t.lag", &e)),
    };
    let rendered = cli::diagnostics::render("t.lag", PENDULUM, &warnings);
    // `k` is declared for the sake of its unit and used nowhere: a warning, nothing worse.
    assert!(warnings.iter().all(|w| w.message.contains("`k`")), "{rendered}");
}

#[test]
fn inconsistent_scenes_are_still_refused() {
    let time_plus_length =
        "param m = 1 kg, L = 1 m\ncoord x = 1 s\nparticle p { mass m; position (x + L, 0) }\n";
    let e = dimension_errors("a.lag", time_plus_length);
    assert!(e.contains("s here, m there"), "{e}");

    let mismatched =
        "param m = 1 kg\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\nexpect m*x'' = x\n";
    let e = dimension_errors("b.lag", mismatched);
    assert!(e.contains("kg·m/s² here, m there"), "{e}");

    // A number that is not zero is a dimensionless coefficient, even in a matrix.
    let e = dimension_errors("c.lag", &CHARGE.replace("[m, 0; 0, m]", "[m, 1/2; 0, m]"));
    assert!(e.contains("matrix product"), "{e}");
}

/// A unit with two denominator factors prints so that it reads back as itself.
#[test]
fn a_unit_with_two_denominators_prints_as_it_reads() {
    let source = "param m = 1 kg, c = 2 kg/m/s, L = 1 m\ncoord x = 0 m\nparticle p { mass m; position (x, 0) }\ndissipation c*L/2*x'^2\n";
    let text =
        cli::derive_with("damped.lag", source, cli::Format::Text, engine::Options::default())
            .expect("derives");
    assert!(text.contains("c = 2 kg/m/s"), "{text}");
    let json =
        cli::derive_with("damped.lag", source, cli::Format::Json, engine::Options::default())
            .expect("derives");
    assert!(json.contains("\"unit\": \"kg/m/s\""), "{json}");
}
