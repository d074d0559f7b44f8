//! Expressions resolved against a scene already resolved: what a front end's `--output` or
//! `--about` goes through, with the diagnostics' spans in the argument itself.

use model::{Checks, Model, Value};

const SCENE: &str = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord theta = 1/2, x
particle bob { mass m; position (L*sin(theta) + x, -L*cos(theta)) }
gravity g
constraint fixed: x = 0
";

fn model() -> Model {
    let ast = lang::parse(SCENE).expect("parses");
    model::resolve_with(&ast, SCENE, Checks { units: true, ..Checks::default() })
        .expect("resolves")
        .0
}

#[test]
fn an_expression_resolves_to_its_value() {
    let mut m = model();
    let Value::Scalar(e) = m.resolve_expression("L*theta'").expect("resolves") else {
        panic!("a scalar")
    };
    assert_eq!(m.pool.print(e, cas::Style::Ascii).replace(" ", ""), "L*theta'");
    assert!(matches!(m.resolve_expression("(theta, 0)"), Ok(Value::Vector(_))));
}

#[test]
fn a_mistake_points_into_the_expression() {
    let mut m = model();
    let text = "theta + thta";
    let errors = m.resolve_expression(text).expect_err("an unknown name");
    assert_eq!(errors.len(), 1);
    let d = &errors[0];
    assert!(d.message.contains("unknown name `thta`"), "{}", d.message);
    assert_eq!(&text[d.span.start..d.span.end], "thta");
    // A syntax error too, and a mismatch of dimensions.
    let errors = m.resolve_expression("theta +").expect_err("incomplete");
    assert!(errors.iter().all(|d| d.span.end <= "theta +".len()), "{errors:?}");
    let errors = m.resolve_expression("L + m").expect_err("length plus mass");
    assert!(errors[0].message.contains("dimensions do not match"), "{}", errors[0].message);
    assert!(errors[0].span.end <= "L + m".len());
    // A mistake leaves the model as it was: the next expression resolves.
    assert!(m.resolve_expression("L*g").is_ok());
}

#[test]
fn a_reaction_named_is_requested_from_the_derivation() {
    let mut m = model();
    assert!(!m.constraints[0].force_requested);
    m.resolve_expression("fixed.force").expect("resolves");
    assert!(m.constraints[0].force_requested);
}

#[test]
fn a_reference_is_a_linearize_line_after_the_scene() {
    let mut m = model();
    m.resolve_about("theta = 0, theta' = 0").expect("resolves");
    assert_eq!(m.linearize.len(), 1);
    assert_eq!(m.linearize[0].items.len(), 2);
    let text = "theta = L";
    let errors = m.resolve_about(text).expect_err("a length for an angle");
    assert!(errors.iter().all(|d| d.span.end <= text.len()), "{errors:?}");
}
