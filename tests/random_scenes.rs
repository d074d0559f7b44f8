//! Random but valid scenes through the whole pipeline (parse → resolve → derive → check →
//! every report): nothing panics, and each scene finishes in bounded time.

use std::time::{Duration, Instant};

use proptest::prelude::*;

/// An expression over the given names, small enough to derive quickly.
fn expr(names: Vec<String>, depth: u32) -> BoxedStrategy<String> {
    let leaf = prop_oneof![
        proptest::sample::select(names.clone()),
        (1i32..5).prop_map(|n| n.to_string()),
        (1i32..5, 2i32..7).prop_map(|(a, b)| format!("{a}/{b}")),
    ]
    .boxed();
    if depth == 0 {
        return leaf;
    }
    let inner = expr(names, depth - 1);
    prop_oneof![
        2 => leaf,
        1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} + {b})")),
        1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} - {b})")),
        1 => (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("{a}*{b}")),
        1 => (inner.clone(), 1i32..3).prop_map(|(a, n)| format!("({a})^{n}")),
        1 => (proptest::sample::select(vec!["sin", "cos"]), inner).prop_map(|(f, a)| format!("{f}({a})")),
    ]
    .boxed()
}

/// A scene: parameters, one to three coordinates, particles and bodies placed by random
/// expressions, maybe gravity, a spring, a constraint, and a few `show` and `expect` lines.
fn scene() -> impl Strategy<Value = String> {
    (1usize..4).prop_flat_map(|n| {
        let coords: Vec<String> = (1..=n).map(|i| format!("q{i}")).collect();
        let mut names = coords.clone();
        names.extend(["a", "b"].map(String::from));
        let position = (expr(names.clone(), 2), expr(names.clone(), 2))
            .prop_map(|(x, y)| format!("({x}, {y})"));
        (
            Just(coords),
            proptest::collection::vec(position, 1..4),
            proptest::option::of(expr(names.clone(), 1)),
            any::<bool>(),
            proptest::option::of((expr(names.clone(), 1), expr(names.clone(), 1))),
            proptest::collection::vec((expr(names.clone(), 1), expr(names, 1)), 0..3),
        )
            .prop_map(|(coords, positions, potential, gravity, constraint, expects)| {
                let mut s = String::from("param a = 2, b = 1/3, g = 9.81\n");
                for c in &coords {
                    s.push_str(&format!("coord {c} = 1/10\n"));
                }
                for (i, p) in positions.iter().enumerate() {
                    if i == 0 {
                        s.push_str(&format!(
                            "body b{i} {{ mass a; inertia b; position {p}; angle {} }}\n",
                            coords[0]
                        ));
                    } else {
                        s.push_str(&format!("particle p{i} {{ mass a; position {p} }}\n"));
                    }
                }
                // Every coordinate moves a particle, so the mass matrix has a chance to be regular.
                for c in &coords {
                    s.push_str(&format!("particle m_{c} {{ mass b; position ({c}, 0) }}\n"));
                }
                if gravity {
                    s.push_str("gravity g\n");
                }
                if let Some(v) = potential {
                    s.push_str(&format!("potential {v}\n"));
                }
                if let Some((l, r)) = constraint {
                    s.push_str(&format!("constraint c: {l} = {r}\nshow c.force\n"));
                }
                s.push_str("show KE, PE\n");
                for (l, r) in expects {
                    s.push_str(&format!("expect {l} = {r}\n"));
                }
                s
            })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn random_scenes_run_through_without_panicking(source in scene()) {
        let start = Instant::now();
        let options = cli::Options { units: false };
        let checked = cli::check::check_file_with("random.lag", &source, options);
        prop_assert!(checked.exit_code <= 2);
        for format in [cli::Format::Text, cli::Format::Latex, cli::Format::Json] {
            let _ = cli::derive_with("random.lag", &source, format, options);
        }
        // Generous: these are small scenes, and a debug build on a shared machine.
        prop_assert!(start.elapsed() < Duration::from_secs(20), "took {:?}:\n{source}", start.elapsed());
    }
}
