//! Syntax errors: where they point, what they say, and the hints they give.

use lang::{parse, Diagnostic};

fn errors(source: &str) -> Vec<Diagnostic> {
    match parse(source) {
        Ok(file) => panic!("{source:?} parsed: {file:?}"),
        Err(diags) => diags,
    }
}

/// The only error of `source`, as `start..end message | hint`.
fn one_error(source: &str) -> String {
    let diags = errors(source);
    assert_eq!(diags.len(), 1, "{diags:#?}");
    let d = &diags[0];
    format!("{}..{} {} | {}", d.span.start, d.span.end, d.message, d.hint.as_deref().unwrap_or("-"))
}

#[test]
fn implicit_multiplication() {
    insta::assert_snapshot!(one_error("let h = 2x"), @"9..10 expected an operator or end of line, found `x` | write `2*x`, not `2x`");
    insta::assert_snapshot!(one_error("let h = 2 theta + 1"), @"10..15 expected an operator or end of line, found `theta` | write `2*theta`, not `2 theta`");
    insta::assert_snapshot!(one_error("expect x y = 0"), @"9..10 expected an operator or `=`, found `y` | write `x*y`, not `x y`");
    insta::assert_snapshot!(one_error("let h = (a)(b)"), @"11..12 expected an operator or end of line, found `(` | write `)*(`, not `)(`");
    insta::assert_snapshot!(one_error("let h = sin (x)"), @"12..13 expected an operator or end of line, found `(` | to call `sin`, write `sin(` with no space; to multiply, write `sin*(`");
}

#[test]
fn side_by_side_hints_know_about_units() {
    // A unit could stand here, but a number is not one.
    insta::assert_snapshot!(one_error("param k = 1/2 1"), @"14..15 expected a unit, an operator, `,` or end of line, found `1` | to multiply, write `2*1`; a unit after a value is a unit name such as `kg` or `m/s^2`, or `1/` and one (`1/m`)");
    insta::assert_snapshot!(one_error("param k = 2 3 kg"), @"12..13 expected a unit, an operator, `,` or end of line, found `3` | to multiply, write `2*3`; a unit after a value is a unit name such as `kg` or `m/s^2`, or `1/` and one (`1/m`)");
    // A unit where none may stand.
    insta::assert_snapshot!(one_error("let h = 2 m"), @"10..11 expected an operator or end of line, found `m` | to multiply, write `2*m`; a unit may follow only the value of a `param` or `coord` item or a `simulate` setting");
    insta::assert_snapshot!(one_error("expect x = 1/2 1/m"), @"15..16 expected an operator or end of line, found `1` | to multiply, write `2*1`; a unit may follow only the value of a `param` or `coord` item or a `simulate` setting");
    insta::assert_snapshot!(one_error("let h = (1 + 2) kg"), @"16..18 expected an operator or end of line, found `kg` | to multiply, write `)*kg`; a unit may follow only the value of a `param` or `coord` item or a `simulate` setting");
    // Two units side by side are multiplied like names.
    insta::assert_snapshot!(one_error("param v = 2 m s"), @"14..15 expected an operator, `,` or end of line, found `s` | write `m*s`, not `m s`");
    // Not a unit: the plain hint.
    insta::assert_snapshot!(one_error("let h = 2 mass"), @"10..14 expected an operator or end of line, found `mass` | write `2*mass`, not `2 mass`");
}

#[test]
fn unbalanced_brackets_name_the_open_one() {
    let diags = errors("let h = (a + b\ngravity g");
    assert_eq!(diags.len(), 1);
    let d = &diags[0];
    assert_eq!(d.message, "unclosed `(`: expected a closing `)`");
    assert_eq!((d.span.start, d.span.end), (14, 14));
    assert_eq!(d.related[0].0, lang::Span::new(8, 9));

    let d = &errors("expect [a, b) = 0")[0];
    assert_eq!(d.message, "mismatched `)`: the innermost open bracket is `[`");
    assert_eq!(d.related[0].0, lang::Span::new(7, 8));

    let d = &errors("let h = a + b)")[0];
    assert_eq!(d.message, "unexpected `)`: there is no `(` to close");

    let d = &errors("body rod {\n  mass m\n")[0];
    assert_eq!(d.message, "unclosed `{`: expected a closing `}`");
    assert_eq!(d.related[0].0, lang::Span::new(9, 10));

    // Brackets in comments and titles do not count.
    assert!(parse("scene \"a (b\" # ) [\nlet x = 1").is_ok());
}

#[test]
fn unknown_statement_keywords() {
    let d = &errors("parma m = 1 kg")[0];
    assert_eq!(d.message, "unknown statement `parma`");
    assert_eq!((d.span.start, d.span.end), (0, 5));
    let hint = d.hint.as_deref().unwrap_or("");
    assert!(hint.starts_with("did you mean `param`?"), "{hint}");
    assert!(hint.contains("scene, param, let, coord"), "{hint}");

    let d = &errors("let a = 1\n  gravty g")[0];
    assert_eq!(d.message, "unknown statement `gravty`");
    assert_eq!((d.span.start, d.span.end), (12, 18));
    assert!(d.hint.as_deref().unwrap_or("").starts_with("did you mean `gravity`?"));

    let d = &errors("frobnicate x")[0];
    assert_eq!(d.message, "unknown statement `frobnicate`");
    assert!(!d.hint.as_deref().unwrap_or("").contains("did you mean"));

    insta::assert_snapshot!(one_error("= 3").split(" | ").next().unwrap_or(""), @"0..1 expected a statement, found `=`");
}

#[test]
fn expected_tokens_are_named_for_people() {
    insta::assert_snapshot!(one_error("let x = "), @"8..8 expected an expression, found end of file | -");
    insta::assert_snapshot!(one_error("force push bead: 1"), @"11..15 expected `on`, found `bead` | -");
    insta::assert_snapshot!(one_error("show at start theta"), @"14..19 expected `:`, found `theta` | -");
    insta::assert_snapshot!(one_error("let x 3"), @"6..7 expected `=`, found `3` | -");
    insta::assert_snapshot!(one_error("scene foo"), @r#"6..9 expected a quoted title like "A title", found `foo` | -"#);
    insta::assert_snapshot!(one_error("particle p { mass m, position (x, y) }"), @"19..20 expected an operator, `;` or a closing `}`, found `,` | separate the items of a block with `;` or a new line");
}

#[test]
fn coord_rates_must_belong_to_a_coordinate_of_the_line() {
    insta::assert_snapshot!(one_error("coord theta = 1, phi' = 2"), @"17..21 `phi'` gives the rate of `phi`, which is not declared on this line | declare the coordinate and its rate together: `coord phi = …, phi' = …`");
    insta::assert_snapshot!(one_error("coord x, x'' = 2"), @"10..12 `x''`: only the initial rate (one prime) can be given | write `x' = …`");
    insta::assert_snapshot!(one_error("coord x, x'"), @"9..11 the initial rate `x'` needs a value | write `x' = 0`, or leave the rate out (it defaults to 0)");
}

#[test]
fn independent_errors_on_several_lines_are_all_reported() {
    let diags = errors("parma x = 1\nlet y = 2 z\nlet ok = 1\ngravity g g\n");
    let spans: Vec<(usize, usize)> = diags.iter().map(|d| (d.span.start, d.span.end)).collect();
    assert_eq!(spans, [(0, 5), (22, 23), (45, 46)]);
}

#[test]
fn pathological_nesting_is_refused_without_overflow() {
    let deep = format!("let x = {}1{}", "(".repeat(10_000), ")".repeat(10_000));
    let d = &errors(&deep)[0];
    assert_eq!(d.message, "nesting too deep (over 256 levels)");

    let deep = format!("let x = {}1{}", "[".repeat(300), "]".repeat(300));
    assert_eq!(errors(&deep)[0].message, "nesting too deep (over 256 levels)");

    // Just under the limit is fine.
    let ok = format!("let x = {}1{}", "(".repeat(256), ")".repeat(256));
    assert!(parse(&ok).is_ok());

    for long in [
        format!("let x = {}1", "-".repeat(100_000)),
        format!("let x = 1{}", "^2".repeat(100_000)),
        format!("let x = 1{}", "+1".repeat(100_000)),
    ] {
        assert!(errors(&long)[0].message.starts_with("expression too long"));
    }
    let primes = format!("let x = y{}", "'".repeat(1000));
    assert_eq!(errors(&primes)[0].message, "too many primes");
}
