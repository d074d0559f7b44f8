//! One snapshot per example file and format: the text, LaTeX and JSON reports of `derive`.

fn derive(path: &std::path::Path, format: cli::Format) -> String {
    let source = std::fs::read_to_string(path).expect("readable example");
    let name = path.file_name().expect("file").to_string_lossy().into_owned();
    match cli::derive(&name, &source, format) {
        Ok(report) => report,
        Err(diagnostics) => panic!("{} does not derive:\n{diagnostics}", path.display()),
    }
}

/// Runs `check_one` on every example with the snapshot named after its path
/// (`ps5__falling_rod`), so adding an example never renames the others' snapshots.
fn each_example(check_one: impl Fn(&std::path::Path, &str)) {
    let examples = lagrange_tests::examples();
    assert!(!examples.is_empty());
    for (rel, _) in examples {
        let path = lagrange_tests::examples_dir().join(rel.trim_start_matches("examples/"));
        let name = rel.trim_start_matches("examples/").trim_end_matches(".lag").replace('/', "__");
        insta::with_settings!({ input_file => &path, omit_expression => true }, {
            check_one(&path, &name);
        });
    }
}

#[test]
fn text() {
    each_example(|path, name| {
        insta::assert_snapshot!(format!("text@{name}"), derive(path, cli::Format::Text))
    });
}

#[test]
fn latex() {
    each_example(|path, name| {
        insta::assert_snapshot!(format!("latex@{name}"), derive(path, cli::Format::Latex))
    });
}

#[test]
fn json() {
    each_example(|path, name| {
        let report = derive(path, cli::Format::Json);
        let parsed: serde_json::Value = serde_json::from_str(&report).expect("valid JSON");
        for key in [
            "coordinates",
            "parameters",
            "mass_matrix",
            "forcing",
            "reactions",
            "shown",
            "at_start",
        ] {
            assert!(parsed.get(key).is_some(), "{} lacks `{key}`", path.display());
        }
        insta::assert_snapshot!(format!("json@{name}"), report);
    });
}

/// The results the problem set's solutions state, read from the JSON report.
#[test]
fn problem_set_results_come_out_exactly() {
    let dir = lagrange_tests::examples_dir().join("ps5");
    let rod: serde_json::Value =
        serde_json::from_str(&derive(&dir.join("falling_rod.lag"), cli::Format::Json))
            .expect("JSON");
    assert_eq!(rod["coordinates"], serde_json::json!(["x", "theta"]));
    assert_eq!(rod["at_start"]["theta''"], "12/7*g/L");
    assert_eq!(rod["at_start"]["floor.force"], "4/7*m*g");
    assert_eq!(rod["equations"][0]["lhs"], "x''");
    assert_eq!(
        rod["equations"][1]["lhs"],
        "(1 + 3*sin(theta)^2)*theta'' + 3*sin(theta)*cos(theta)*theta'^2"
    );
    assert_eq!(rod["equations"][1]["rhs"], "6*g*sin(theta)/L");

    let wedge: serde_json::Value =
        serde_json::from_str(&derive(&dir.join("wedge.lag"), cli::Format::Json)).expect("JSON");
    assert_eq!(
        wedge["mass_matrix"],
        serde_json::json!([["M + m", "m*cos(theta)"], ["m*cos(theta)", "m"]])
    );
    assert_eq!(wedge["forcing"], serde_json::json!(["0", "m*g*sin(theta)"]));

    let disk: serde_json::Value =
        serde_json::from_str(&derive(&dir.join("rolling_disk.lag"), cli::Format::Json))
            .expect("JSON");
    assert_eq!(disk["shown"]["disk.omega"], "(1 + R/r)*theta'");
    assert_eq!(disk["shown"]["KE"], "3/4*m*(r + R)^2*theta'^2");
}

/// The README shows the rod's `derive` output; it must be what `derive` prints today.
#[test]
fn the_readme_shows_the_current_output() {
    let readme = std::fs::read_to_string(lagrange_tests::examples_dir().join("../README.md"))
        .expect("README");
    let section = &readme[readme.find("## What it prints").expect("the section")..];
    let start = section.find("```text\n").expect("a code block") + 8;
    let block = &section[start..start + section[start..].find("```").expect("closed")];
    let path = lagrange_tests::examples_dir().join("ps5/falling_rod.lag");
    assert_eq!(
        block,
        derive(&path, cli::Format::Text),
        "README.md is out of date: paste the new output"
    );
}

/// The manual's page on the language (docs/language.md) quotes the heavy top's kinetic energy
/// and θ equation; each quoted line must be a line `derive` prints today.
#[test]
fn the_manual_quotes_the_heavy_top_as_derived() {
    let page = std::fs::read_to_string(lagrange_tests::examples_dir().join("../docs/language.md"))
        .expect("docs/language.md");
    let section = &page[page.find("## Bodies in space").expect("the section")..];
    let quoted = section.split("```").nth(3).expect("the second code block");
    let quoted = quoted.strip_prefix("text\n").expect("a `text` block");
    let path = lagrange_tests::examples_dir().join("space/heavy_top.lag");
    let printed = derive(&path, cli::Format::Text);
    let lines: Vec<&str> = quoted.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 2, "{quoted}");
    for line in lines {
        assert!(
            printed.lines().any(|p| p == line),
            "docs/language.md quotes `{line}`, derive prints:\n{printed}"
        );
    }
}

/// A pendulum hung at asin(r/L) on a rim, with a stiffness of √2·√3: its report prints
/// cos(π/2 + asin(r/L)) as −r/L (so the pivot is at −r), sin²(acos(r/L)) as 1 − r²/L² and
/// √2·√3 as √6, as a hand derivation writes them.
#[test]
fn printed_forms_are_folded() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/pendulum_hung_at_asin.lag");
    let report = derive(&path, cli::Format::Text);
    for line in [
        "  V = ½·√6·r²·k·th² − m·L·g·cos(th) + m·r·g",
        "  pivot = ⎡ −r ⎤",
        "  L^2*sin(acos(r/L))^2 = L² − r²",
    ] {
        assert!(report.lines().any(|l| l == line), "no `{line}` in\n{report}");
    }
    assert!(!report.contains("π/2 + asin") && !report.contains("√2"), "{report}");
}

#[test]
fn generated_scenes_derive() {
    use lang::generate::{n_link, Family};
    for family in [Family::Pendulum, Family::PendulumOnCart] {
        for n in 1..=3 {
            let scene = n_link(family, n);
            let d = engine::load(&scene).unwrap_or_else(|e| panic!("{scene}\n{e}")).derivation;
            let dof = n + usize::from(family == Family::PendulumOnCart);
            assert_eq!(d.coords.len(), dof);
            assert_eq!(d.mass_matrix.len(), dof);
        }
    }
}
