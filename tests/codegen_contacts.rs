//! The generated impact map, in Rust (built by plain `rustc`) and in C (under `-std=c99 -Wall
//! -Wextra -Werror -pedantic`, with every compiler found): for the bouncing ball, Newton's
//! cradle and the rocking block, at states where the hand result is known (the ball's
//! q̇⁺ = (x', −e·y'), the cradle's (−1/3, 2/3, 2/3)·v0, Housner's ratio with the landing corner
//! at rest after) to 1e-12, and at the state before the first impact of the library's run,
//! against the rates the run jumps to (those three, the falling rod's gripping landing and the
//! rimless wheel's), to 1e-12 of the rates. Also the gaps and the flight between impacts.

use std::fmt::Write;
use std::path::Path;
use std::process::Command;

use sim::ModeChange;
use simulation::{simulate, Options};

/// One call of `impact`: the state before, the contacts flagged touching, and what the rates
/// after must be, each to an absolute tolerance.
struct Case {
    what: String,
    q: Vec<f64>,
    qd: Vec<f64>,
    touching: Vec<bool>,
    /// (index into q̇⁺ or a function of it, expected value, tolerance) checked by `check`.
    expected: Vec<f64>,
    tolerance: f64,
    /// (multiplier slot, impulse) pairs the impulses must hold, to 1e-12 relative.
    impulses: Vec<(usize, f64)>,
}

/// A scene of `examples/contacts/` with its cases.
struct Scene {
    file: &'static str,
    /// The module's name in the Rust driver and the stem of the C files.
    name: &'static str,
    coordinates: usize,
    cases: Vec<Case>,
}

fn source(file: &str) -> String {
    let path = lagrange_tests::examples_dir().join("contacts").join(file);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The state just before the first impact of the scene's run, and the rates just after: the
/// run's rows at the jump, with the columns `q` then `qd` as named.
fn first_impact(file: &str, q: &[&str], qd: &[&str]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let names: Vec<&str> = q.iter().chain(qd).copied().collect();
    let options = Options { output: vec![names.join(", ")], ..Options::default() };
    let outcome = simulate(&source(file), &options).unwrap_or_else(|e| panic!("{file}: {e}"));
    let impact = outcome.run.modes.iter().find(|m| m.kind == ModeChange::Impact).expect("impact");
    let trajectory = &outcome.run.trajectory;
    let at: Vec<usize> =
        (0..trajectory.times.len()).filter(|&i| trajectory.times[i] == impact.time).collect();
    assert_eq!(at.len(), 2, "{file}: the rows at the jump");
    let column = |name: &str| outcome.columns.iter().position(|c| c == name).expect(name);
    let pick = |row: &[f64], of: &[&str]| of.iter().map(|n| row[column(n)]).collect::<Vec<f64>>();
    let (before, after) = (&trajectory.rows[at[0]], &trajectory.rows[at[1]]);
    (pick(before, q), pick(before, qd), pick(after, qd))
}

fn scenes() -> Vec<Scene> {
    // The ball: m = 1/2, e = 4/5 (the scene's values).
    let e = 0.8;
    let (q, qd, after) = first_impact("bouncing_ball.lag", &["x", "y"], &["x'", "y'"]);
    let ball = Scene {
        file: "bouncing_ball.lag",
        name: "bouncing_ball",
        coordinates: 2,
        cases: vec![
            Case {
                what: "landing at (0.7, -4.2)".into(),
                q: vec![0.3, 0.0],
                qd: vec![0.7, -4.2],
                touching: vec![true],
                expected: vec![0.7, e * 4.2],
                tolerance: 1e-12 * 4.2,
                impulses: vec![(0, 0.5 * (1.0 + e) * 4.2)],
            },
            Case {
                what: "the run's first impact".into(),
                q,
                qd,
                touching: vec![true],
                expected: after,
                tolerance: 1e-12 * 4.5,
                impulses: vec![],
            },
        ],
    };
    // The cradle: a = 1/50, v0 = 1.
    let (a, v0) = (0.02, 1.0);
    let (q, qd, after) =
        first_impact("newtons_cradle.lag", &["x1", "x2", "x3"], &["x1'", "x2'", "x3'"]);
    let cradle = Scene {
        file: "newtons_cradle.lag",
        name: "newtons_cradle",
        coordinates: 3,
        cases: vec![
            Case {
                what: "both contacts, the first ball at v0".into(),
                q: vec![-2.0 * a, 0.0, 2.0 * a],
                qd: vec![v0, 0.0, 0.0],
                touching: vec![true, true],
                expected: vec![-v0 / 3.0, 2.0 * v0 / 3.0, 2.0 * v0 / 3.0],
                tolerance: 1e-12 * v0,
                // Ball 1 loses 4/3·m·v0, ball 3 gains 2/3·m·v0 (m = 1).
                impulses: vec![(0, 4.0 / 3.0 * v0), (1, 2.0 / 3.0 * v0)],
            },
            Case {
                what: "the first contact alone: the rates swap".into(),
                q: vec![-2.0 * a, 0.0, 2.0 * a],
                qd: vec![v0, 0.0, 0.0],
                touching: vec![true, false],
                expected: vec![0.0, v0, 0.0],
                tolerance: 1e-12 * v0,
                impulses: vec![(0, v0), (1, 0.0)],
            },
            Case {
                what: "the run's first impact".into(),
                q,
                qd,
                touching: vec![true, true],
                expected: after,
                tolerance: 1e-12 * v0,
                impulses: vec![],
            },
        ],
    };
    // The block: b = 1/10, h = 3/10, pivoting about its left corner at θ' = w, landing flat.
    let (b, h, w) = (0.1f64, 0.3f64, -1.3f64);
    #[allow(clippy::disallowed_methods)]
    let ratio = 1.0 - 1.5 * (b / h).atan().sin().powi(2);
    let (q, qd, after) =
        first_impact("rocking_block.lag", &["x", "y", "theta"], &["x'", "y'", "theta'"]);
    let block = Scene {
        file: "rocking_block.lag",
        name: "rocking_block",
        coordinates: 3,
        cases: vec![
            Case {
                what: "landing flat on the right corner, pivoting on the left".into(),
                q: vec![b, h, 0.0],
                qd: vec![-h * w, b * w, w],
                touching: vec![true, true],
                // Housner's ratio on θ', and the right corner (b, −h) from the centre at rest:
                // x' = −h·θ', y' = −b·θ'.
                expected: vec![-h * ratio * w, -b * ratio * w, ratio * w],
                tolerance: 1e-12 * w.abs(),
                // The left corner lifts off: no impulse at its normal (slot 0) or grip (1).
                impulses: vec![(0, 0.0), (1, 0.0)],
            },
            Case {
                what: "the run's first impact".into(),
                q,
                qd,
                touching: vec![true, true],
                expected: after,
                tolerance: 1e-12 * 2.0,
                impulses: vec![],
            },
        ],
    };
    let mut all = vec![ball, cradle, block];
    // The other scenes that land: the rod (a plastic landing of a gripping end) and the
    // rimless wheel (eight gripping spokes, one landing while another stands), at the run's
    // first impact, touching where the tape's gap is within 1e-9 m.
    for (file, name) in
        [("falling_rod_landing.lag", "falling_rod_landing"), ("rimless_wheel.lag", "rimless_wheel")]
    {
        let module = export::codegen::codegen(file, &source(file)).unwrap();
        let names = module.prepared.state_names();
        let n = names.len() / 2;
        let (coordinates, rates): (Vec<&str>, Vec<&str>) = (
            names[..n].iter().map(|s| s.as_str()).collect(),
            names[n..].iter().map(|s| s.as_str()).collect(),
        );
        let (q, qd, after) = first_impact(file, &coordinates, &rates);
        let program = &module.programs.iter().find(|(p, _)| p == "constraints").unwrap().1;
        let mut input = vec![0.0];
        input.extend(&q);
        input.extend(&qd);
        input.extend(&module.parameters);
        let mut rows = vec![0.0; program.outputs.len()];
        numeric::Tape::new(program.clone()).eval(&input, &mut rows);
        let touching: Vec<bool> = module
            .prepared
            .contacts
            .iter()
            .map(|c| rows[c.normal * (n + 3) + n + 1].abs() <= 1e-9)
            .collect();
        assert!(touching.iter().filter(|t| **t).count() >= 1, "{file}: {touching:?}");
        let scale = qd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        all.push(Scene {
            file,
            name,
            coordinates: n,
            cases: vec![Case {
                what: format!("the run's first impact, touching {touching:?}"),
                q,
                qd,
                touching,
                expected: after,
                tolerance: 1e-12 * scale,
                impulses: vec![],
            }],
        });
    }
    all
}

fn list(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ")
}

/// Reads the driver's output, a line `status q̇⁺…` per case, and checks every case.
fn check(language: &str, scenes: &[Scene], output: &str) -> usize {
    let mut lines = output.lines();
    let mut checked = 0;
    for scene in scenes {
        for case in &scene.cases {
            let line = lines.next().unwrap_or_else(|| panic!("{language}: output ends early"));
            let values: Vec<f64> = line.split_whitespace().map(|v| v.parse().unwrap()).collect();
            assert_eq!(
                values[0], 0.0,
                "{language}, {}: {}: status {}",
                scene.file, case.what, values[0]
            );
            let plus = &values[1..1 + scene.coordinates];
            let worst = plus
                .iter()
                .zip(&case.expected)
                .map(|(got, want)| (got - want).abs())
                .fold(0.0f64, f64::max);
            eprintln!("{language}, {}: {}: q̇⁺ off by {worst:e}", scene.file, case.what);
            assert!(
                worst <= case.tolerance,
                "{language}, {}: {}: {plus:?} vs {:?}",
                scene.file,
                case.what,
                case.expected
            );
            let impulses = &values[1 + scene.coordinates..];
            for &(slot, want) in &case.impulses {
                let got = impulses[slot];
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "{language}, {}: {}: impulse {slot} {got} vs {want}",
                    scene.file,
                    case.what
                );
            }
            checked += 1;
        }
    }
    // The ball in flight at (0.3, 1.5) with rates (0.7, −4.2): its gap and normal rate, and
    // the right-hand side with the floor open (free fall, g = 9.81).
    let line = lines.next().unwrap_or_else(|| panic!("{language}: no flight line"));
    let values: Vec<f64> = line.split_whitespace().map(|v| v.parse().unwrap()).collect();
    let want = [1.5, -4.2, 0.7, -4.2, 0.0, -9.81];
    for (got, want) in values.iter().zip(want) {
        assert!((got - want).abs() <= 1e-12 * 10.0, "{language}: flight {values:?} vs {want:?}");
    }
    assert_eq!(values.len(), want.len(), "{language}: {values:?}");
    checked
}

/// The Rust driver: each scene's module, and a line per case.
fn rust_driver(dir: &Path, scenes: &[Scene]) -> String {
    let mut main = String::new();
    for scene in scenes {
        let module = export::codegen::codegen(scene.file, &source(scene.file)).unwrap();
        std::fs::write(dir.join(format!("{}.rs", scene.name)), &module.source).unwrap();
        let _ = writeln!(
            main,
            "#[allow(dead_code)]\n#[path = \"{}.rs\"]\nmod {};",
            scene.name, scene.name
        );
    }
    main.push_str("fn main() {\n");
    for scene in scenes {
        let name = scene.name;
        for case in &scene.cases {
            let touching = case.touching.iter().map(|t| t.to_string()).collect::<Vec<_>>();
            let _ = writeln!(
                main,
                "    {{ let mut plus = [0.0; {n}]; let mut impulses = [0.0; {name}::CONSTRAINTS]; \
                 let status = {name}::impact(0.0, &[{}], &[{}], &{name}::PARAMETERS, &[], &[{}], &mut plus, &mut impulses); \
                 print!(\"{{}}\", status as i32); for v in plus.iter().chain(&impulses) {{ print!(\" {{v:?}}\"); }} println!(); }}",
                list(&case.q),
                list(&case.qd),
                touching.join(", "),
                n = scene.coordinates
            );
        }
    }
    main.push_str(
        "    { let mut g = [0.0; 2]; let mut dy = [0.0; 4]; \
         bouncing_ball::gaps(0.0, &[0.3, 1.5], &[0.7, -4.2], &bouncing_ball::PARAMETERS, &[], &mut g); \
         assert!(bouncing_ball::rhs(0.0, &[0.3, 1.5, 0.7, -4.2], &bouncing_ball::PARAMETERS, &[], &mut dy)); \
         for v in g.iter().chain(&dy) { print!(\"{v:?} \"); } println!(); }\n",
    );
    main.push_str("}\n");
    main
}

/// The C driver: a line per case.
fn c_driver(scenes: &[Scene]) -> String {
    let mut main = String::from("#include <stdio.h>\n\n");
    for scene in scenes {
        let _ = writeln!(main, "#include \"{}.h\"", scene.name);
    }
    main.push_str("\nint main(void)\n{\n    int i;\n");
    for scene in scenes {
        let name = scene.name;
        for case in &scene.cases {
            let touching =
                case.touching.iter().map(|t| i32::from(*t).to_string()).collect::<Vec<_>>();
            let _ = writeln!(
                main,
                "    {{\n        const double q[] = {{ {} }};\n        const double qd[] = {{ {} }};\n        \
                 const int touching[] = {{ {} }};\n        double plus[{n}];\n        double impulses[{name}_CONSTRAINTS];\n        \
                 int status = {name}_impact(0.0, q, qd, &{name}_default_parameters, NULL, touching, plus, impulses);\n        \
                 printf(\"%d\", status);\n        for (i = 0; i < {n}; i++) {{\n            printf(\" %.17g\", plus[i]);\n        }}\n        \
                 for (i = 0; i < {name}_CONSTRAINTS; i++) {{\n            printf(\" %.17g\", impulses[i]);\n        }}\n        \
                 printf(\"\\n\");\n    }}",
                list(&case.q),
                list(&case.qd),
                touching.join(", "),
                n = scene.coordinates
            );
        }
    }
    main.push_str(
        "    {\n        const double y[] = { 0.3, 1.5, 0.7, -4.2 };\n        double out[6];\n        \
         bouncing_ball_gaps(0.0, y, y + 2, &bouncing_ball_default_parameters, NULL, out);\n        \
         if (bouncing_ball_rhs(0.0, y, &bouncing_ball_default_parameters, NULL, out + 2)) {\n            return 1;\n        }\n        \
         for (i = 0; i < 6; i++) {\n            printf(\"%.17g \", out[i]);\n        }\n        printf(\"\\n\");\n    }\n",
    );
    main.push_str("    return 0;\n}\n");
    main
}

#[test]
fn the_generated_impact_map_is_the_runs() {
    let scenes = scenes();
    let dir =
        std::env::temp_dir().join(format!("lagrange-codegen-contacts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Rust.
    std::fs::write(dir.join("main.rs"), rust_driver(&dir, &scenes)).unwrap();
    let printed = lagrange_tests::compile_and_run_rust(&dir.join("main.rs"), &dir.join("impacts"));
    let mut checked = check("rust", &scenes, &printed);
    // C, with each compiler found.
    let mut units = vec![dir.join("main.c")];
    for scene in &scenes {
        let module =
            export::codegen::c(scene.file, &source(scene.file), Default::default()).unwrap();
        assert_eq!(module.name, scene.name);
        std::fs::write(dir.join(format!("{}.h", scene.name)), &module.header).unwrap();
        std::fs::write(dir.join(format!("{}.c", scene.name)), &module.source).unwrap();
        units.push(dir.join(format!("{}.c", scene.name)));
    }
    std::fs::write(dir.join("main.c"), c_driver(&scenes)).unwrap();
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let mut compilers = vec![compiler];
    if Command::new("clang").arg("--version").output().is_ok_and(|o| o.status.success()) {
        compilers.push("clang".into());
    }
    for compiler in compilers {
        let binary = dir.join(format!("impacts-{compiler}"));
        let built = Command::new(&compiler)
            .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-I"])
            .arg(&dir)
            .args(&units)
            .arg("-lm")
            .arg("-o")
            .arg(&binary)
            .output()
            .expect("the C compiler runs");
        assert!(built.status.success(), "{compiler}: {}", String::from_utf8_lossy(&built.stderr));
        let output = Command::new(&binary).output().expect("the driver runs");
        checked += check(&compiler, &scenes, &String::from_utf8_lossy(&output.stdout));
    }
    assert!(checked >= 20, "{checked} cases checked");
    std::fs::remove_dir_all(&dir).ok();
}

/// The FMU's wrapper integrates with every contact open and knows no impact: `export --fmu`
/// refuses a scene with contacts, naming them, while `codegen` takes it.
#[test]
fn the_fmu_refuses_contacts_naming_them() {
    for (file, names) in
        [("bouncing_ball.lag", "`floor`"), ("rocking_block.lag", "`left`, `right`")]
    {
        let Err(error) =
            export::fmu::export(file, &source(file), &export::fmu::ExportOptions::default())
        else {
            panic!("export --fmu took {file}");
        };
        let message = error.to_string();
        assert!(
            message.contains("export --fmu does not take contacts") && message.contains(names),
            "{message}"
        );
        assert!(export::codegen::c(file, &source(file), Default::default()).is_ok());
    }
}

/// docs/c.md's program for Newton's cradle prints the lines the page shows.
#[test]
fn the_pages_cradle_program_prints_what_the_page_shows() {
    let page = std::fs::read_to_string(lagrange_tests::examples_dir().join("../docs/c.md"))
        .expect("docs/c.md");
    let programs = crate::codegen_c::blocks(&page, "c");
    let program = programs.iter().find(|p| p.contains("newtons_cradle.h")).expect("the program");
    let texts = crate::codegen_c::blocks(&page, "text");
    let shown = texts.iter().find(|t| t.starts_with("gaps ")).expect("what it prints");
    let file = "newtons_cradle.lag";
    let module = export::codegen::c(file, &source(file), Default::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("lagrange-c-cradle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{}.h", module.name)), &module.header).unwrap();
    std::fs::write(dir.join(format!("{}.c", module.name)), &module.source).unwrap();
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let printed = crate::codegen_c::build_and_run(&compiler, &dir, &module, program);
    assert_eq!(&printed, shown, "docs/c.md shows other lines than its program prints");
    std::fs::remove_dir_all(&dir).ok();
}

/// Two walls that cross, a particle between them: `pushed` moves right at 2 m/s, `pulled`
/// left at 1 m/s, both touching the particle at rest at t = 0. No impulses satisfy both
/// (w₁ + w₂ = −3 whatever they are), and `impact` says so, in Rust and in C, leaving its
/// outputs as they were; with one wall alone it pushes the particle to the wall's speed.
const CROSSING_WALLS: &str = "scene \"A particle between two walls that cross\"\n\
    param m = 1 kg\ncoord x = 0\nparticle p { mass m; position (x, 0) }\n\
    contact pushed: x - 2*t >= 0 { restitution 0 }\n\
    contact pulled: -t - x >= 0 { restitution 0 }\n";

#[test]
fn an_impact_without_solution_is_a_status() {
    let dir = std::env::temp_dir().join(format!("lagrange-crossing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let module = export::codegen::codegen("crossing_walls.lag", CROSSING_WALLS).unwrap();
    std::fs::write(dir.join("crossing_walls.rs"), &module.source).unwrap();
    let main = "#[allow(dead_code)]\n#[path = \"crossing_walls.rs\"]\nmod walls;\nfn main() {\n    \
        for touching in [[true, true], [true, false]] {\n        let mut plus = [7.0];\n        \
        let mut impulses = [7.0; 2];\n        \
        let status = walls::impact(0.0, &[0.0], &[0.0], &walls::PARAMETERS, &[], &touching, &mut plus, &mut impulses);\n        \
        println!(\"{} {:?} {:?}\", status as i32, plus[0], impulses);\n    }\n}\n";
    std::fs::write(dir.join("main.rs"), main).unwrap();
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let binary = dir.join("walls");
    let built = Command::new(rustc)
        .args(["--edition", "2021", "-o"])
        .arg(&binary)
        .arg(dir.join("main.rs"))
        .output()
        .expect("rustc runs");
    assert!(built.status.success(), "{}", String::from_utf8_lossy(&built.stderr));
    let output = Command::new(&binary).output().expect("runs");
    assert_eq!(String::from_utf8_lossy(&output.stdout), "2 7.0 [7.0, 7.0]\n0 2.0 [2.0, 0.0]\n");

    let module =
        export::codegen::c("crossing_walls.lag", CROSSING_WALLS, Default::default()).unwrap();
    std::fs::write(dir.join("crossing_walls.h"), &module.header).unwrap();
    std::fs::write(dir.join("crossing_walls.c"), &module.source).unwrap();
    let program = "#include <stdio.h>\n\n#include \"crossing_walls.h\"\n\nint main(void)\n{\n    \
        const double q[] = { 0.0 }, qd[] = { 0.0 };\n    const int both[] = { 1, 1 }, one[] = { 1, 0 };\n    \
        double plus[] = { 7.0 }, impulses[] = { 7.0, 7.0 };\n    \
        int status = crossing_walls_impact(0.0, q, qd, &crossing_walls_default_parameters, NULL, both, plus, impulses);\n    \
        printf(\"%d %g %g %g\\n\", status, plus[0], impulses[0], impulses[1]);\n    \
        status = crossing_walls_impact(0.0, q, qd, &crossing_walls_default_parameters, NULL, one, plus, impulses);\n    \
        printf(\"%d %g %g %g\\n\", status, plus[0], impulses[0], impulses[1]);\n    return 0;\n}\n";
    let compiler = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let printed = crate::codegen_c::build_and_run(&compiler, &dir, &module, program);
    assert_eq!(printed, "2 7 7 7\n0 2 2 0\n");
    std::fs::remove_dir_all(&dir).ok();
}
