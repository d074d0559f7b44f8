//! Helpers shared by the workspace-level tests: finding the examples and reading them.

use std::path::{Path, PathBuf};

/// The repository's `examples/` folder.
pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

/// Examples the every-example tests leave to tests of their own: the bicycle's derivation
/// takes seconds, its equations print as operation counts, and its generated code would take
/// rustc minutes (tests/bicycle.rs holds it to the benchmark instead).
const OWN_TESTS: [&str; 1] = ["examples/bicycle/whipple.lag"];

/// Every `.lag` file under `examples/`, sorted, as (path relative to the repository, source),
/// except those with tests of their own ([`example`] finds those too).
pub fn examples() -> Vec<(String, String)> {
    let mut all = all_examples();
    all.retain(|(path, _)| !OWN_TESTS.contains(&path.as_str()));
    all
}

/// [`examples`] without the scenes with contacts: those the stages that refuse contacts
/// and the every-example checks of two-sided constraints' numbers (random
/// states on every kept row, the batch evaluator) leave to tests/contacts.rs.
pub fn examples_without_contacts() -> Vec<(String, String)> {
    let mut all = examples();
    all.retain(|(_, source)| !source.lines().any(|l| l.trim_start().starts_with("contact ")));
    all
}

/// The recorded column of a run named `name`.
pub fn column(outcome: &simulation::Outcome, name: &str) -> usize {
    outcome
        .columns
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column `{name}` in {:?}", outcome.columns))
}

/// Runs `check` on every example under `examples/<folder>/`, each of which must hold every
/// `expect` line it has; how many held in all.
pub fn check_every_expectation_in(folder: &str) -> usize {
    let mut held = 0;
    for (path, source) in examples() {
        if !path.starts_with(&format!("examples/{folder}/")) {
            continue;
        }
        let expected = source.lines().filter(|l| l.trim_start().starts_with("expect ")).count();
        let result = cli::check::check_file(&path, &source);
        assert_eq!(result.exit_code, 0, "{path} fails:\n{}", result.report);
        assert_eq!((result.held, result.failed), (expected, 0), "{path}:\n{}", result.report);
        held += result.held;
    }
    held
}

/// Whether a scene has a contact with Coulomb friction (`friction MU` in a contact's block):
/// the stages that do not take friction yet (code generation) leave those to
/// tests/friction.rs.
pub fn has_friction(source: &str) -> bool {
    source.lines().any(|l| l.trim_start().starts_with("contact ") && l.contains("friction "))
}

/// Compiles the Rust program `main` (a file in its folder with the generated modules it
/// includes) with `rustc -O` into `binary`, runs it and gives its standard output; fails the
/// test where it does not compile or run.
pub fn compile_and_run_rust(main: &Path, binary: &Path) -> String {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let status = std::process::Command::new(rustc)
        .args(["--edition", "2021", "-O", "-o"])
        .arg(binary)
        .arg(main)
        .status()
        .expect("rustc runs");
    assert!(status.success(), "the generated Rust does not compile (see {})", main.display());
    let output = std::process::Command::new(binary).output().expect("the program runs");
    assert!(output.status.success(), "the generated program failed");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// The example at `path` (relative to `examples/`), whichever tests hold it.
pub fn example(path: &str) -> String {
    let (_, source) = all_examples()
        .into_iter()
        .find(|(p, _)| p.ends_with(path))
        .unwrap_or_else(|| panic!("no example {path}"));
    source
}

fn all_examples() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![examples_dir()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "lag") {
                let rel = path
                    .strip_prefix(examples_dir())
                    .expect("under examples")
                    .to_string_lossy()
                    .replace('\\', "/");
                let source = std::fs::read_to_string(&path).expect("readable example");
                out.push((format!("examples/{rel}"), source));
            }
        }
    }
    out.sort();
    out
}

/// The first-order problem of a scene loaded for numbers, at `parameters`, with its exact
/// Jacobian: the programs `simulate` lowers for a method that uses one.
/// The scene's contacts as a problem takes them, with their restitutions and coefficients of
/// friction at `parameters` (empty for a scene without contacts).
pub fn contacts(prepared: &engine::numbers::Prepared, parameters: &[f64]) -> Vec<sim::Contact> {
    let restitutions = prepared.restitutions(parameters);
    let frictions = prepared.frictions(parameters);
    prepared
        .contacts
        .iter()
        .zip(restitutions)
        .zip(frictions)
        .map(|((c, restitution), friction)| sim::Contact {
            normal: c.normal,
            grip: c.grip,
            cross: c.cross,
            restitution,
            friction,
        })
        .collect()
}

pub fn mechanical(prepared: &mut engine::numbers::Prepared, parameters: &[f64]) -> sim::Mechanical {
    let lower = |prepared: &engine::numbers::Prepared, inputs: &[cas::SymId], exprs| {
        numeric::Tape::new(prepared.lower(inputs, exprs).expect("lowers"))
    };
    let (dynamics_inputs, observation_inputs) =
        (prepared.dynamics_inputs(), prepared.observation_inputs());
    let exprs = prepared.dynamics_exprs();
    let dynamics = lower(prepared, &dynamics_inputs, &exprs);
    let observation = lower(prepared, &observation_inputs, &[]);
    let exprs = prepared.partials_exprs();
    let partials = lower(prepared, &observation_inputs, &exprs);
    sim::Mechanical::new(prepared.layout, dynamics, observation, parameters.to_vec())
        .with_kinds(prepared.stabilisation())
        .with_partials(partials)
}

/// Andrews' squeezer (`source`, the example) with its start positions left to the kept
/// constraints: each published position replaced by a guess (`coord gamma ~ 0.4`).
pub fn andrews_with_guesses(source: &str) -> String {
    let mut guessed = source.to_string();
    for (given, guess) in [
        ("coord Theta = 0,", "coord Theta ~ 0.1,"),
        ("coord gamma = 0.455279819163070380255912382449,", "coord gamma ~ 0.4,"),
        ("coord Phi = 0.222668390165885884674473185609,", "coord Phi ~ 0.2,"),
        ("coord delta = 0.487364979543842550225598953530,", "coord delta ~ 0.5,"),
        ("coord Omega = -0.222668390165885884674473185609,", "coord Omega ~ -0.2,"),
        ("coord epsilon = 1.23054744454982119249735015568,", "coord epsilon ~ 1.2,"),
    ] {
        assert!(guessed.contains(given), "{given}");
        guessed = guessed.replace(given, guess);
    }
    guessed
}

/// A recording made from a scene for a fit to recover: the scene run with `set` (the true
/// values) to `until`, `columns` recorded at `samples` evenly spaced times, each with
/// Gaussian noise of its level in `noise` (seeded: the same text on every machine), as CSV
/// with a column `t`. `series` drive the scene's inputs.
pub fn recording(
    source: &str,
    set: &[(&str, &str)],
    series: &[(&str, sim::Series)],
    columns: &[(&str, f64)],
    (until, samples): (f64, usize),
    seed: u64,
) -> String {
    use rand::{Rng, SeedableRng};
    let options = simulation::Options {
        until: Some(until),
        tolerance: Some(1e-12),
        samples,
        output: vec![columns.iter().map(|c| c.0).collect::<Vec<_>>().join(",")],
        set: set.iter().map(|(n, v)| format!("{n}={v}").parse().expect("an assignment")).collect(),
        input_series: series.iter().map(|(n, s)| (n.to_string(), s.clone())).collect(),
        ..Default::default()
    };
    let outcome = simulation::simulate(source, &options).expect("the recording runs");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    // Box–Muller: two uniforms give a standard normal.
    let mut normal = move || {
        let u: f64 = 1.0 - rng.gen::<f64>();
        let v: f64 = rng.gen::<f64>();
        use numeric::elementary::apply;
        // The elementary functions of the tape, so that the noise has its bits everywhere.
        (-2.0 * apply(cas::Func::Ln, u)).sqrt()
            * apply(cas::Func::Cos, 2.0 * std::f64::consts::PI * v)
    };
    let mut text = String::from("t");
    for (name, _) in columns {
        text.push_str(&format!(",{name}"));
    }
    text.push('\n');
    let trajectory = &outcome.run.trajectory;
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        text.push_str(&format!("{t}"));
        for (k, (_, sigma)) in columns.iter().enumerate() {
            text.push_str(&format!(",{:.6}", row[k] + sigma * normal()));
        }
        text.push('\n');
    }
    text
}
