//! The C that `lagrange codegen --lang c` writes, for every example: it compiles with
//! `-std=c99 -Wall -Wextra -Werror -pedantic` under the system's C compiler (and clang where
//! it is installed), and a driver linked with it computes, at a few random states, parameter
//! values and input values, the same numbers as the tape to 1e-13 relative to each vector's
//! largest entry: the start, M, f, the constraint rows, the right-hand side, its Jacobian,
//! the energies, the outputs, the reactions and the inverse dynamics. The solves are checked
//! against nalgebra's LU on the tape's M, f and constraint rows. The scenes with contacts are
//! among them, with every contact held open (λ = 0 at its rows) as the generated functions
//! hold them.

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use export::codegen::{CModule, Equations};
use nalgebra::{DMatrix, DVector};
use numeric::Tape;

const TOLERANCE: f64 = 1e-13;
const STATES: usize = 3;
const FLAGS: [&str; 5] = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"];

/// Sources longer than this (the bicycle's, 2 MB) are compiled unoptimised: gcc -O1 takes
/// most of a minute over them, -O0 a second or two. The rest get -O1, under which gcc also
/// warns of a value read before it is set.
const OPTIMISED_UP_TO: usize = 1 << 20;

/// Deterministic pseudo-random numbers in [lo, hi) (xorshift), seeded per example.
struct Random(u64);

impl Random {
    fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One evaluation point: t, the state, the parameters' and the inputs' values, and
/// accelerations for the inverse dynamics.
struct Point {
    t: f64,
    y: Vec<f64>,
    /// The free parameters' values, the fields of the C struct.
    free: Vec<f64>,
    /// Every parameter's value: the free ones, and the derived ones following them.
    parameters: Vec<f64>,
    inputs: Vec<f64>,
    accelerations: Vec<f64>,
}

fn points(e: &Equations, seed: usize) -> Vec<Point> {
    let mut random =
        Random(0x9e37_79b9_7f4a_7c15 ^ (seed as u64 + 1).wrapping_mul(0x2545_f491_4f6c_dd1d));
    let (n, k) = (e.sizes.coordinates, e.sizes.parameters);
    (0..STATES)
        .map(|i| {
            // The scene's parameters first, then values moved by up to a fifth; the inputs
            // away from their declared values (often 0), so that they count.
            let mut moved = |v: f64| if i == 0 { v } else { v * random.next(0.8, 1.2) };
            // The derived parameters follow the free ones, in the C as in every run.
            let free: Vec<f64> = e.free.iter().map(|i| moved(e.values[*i])).collect();
            let mut plan = e.prepared.parameter_plan.clone();
            let parameters = plan.values_of_free(&free).expect("parameter values")[..k].to_vec();
            let inputs: Vec<f64> = e.values[k..].iter().map(|v| moved(*v + 0.5)).collect();
            Point {
                t: random.next(0.0, 2.0),
                y: (0..2 * n).map(|_| random.next(-1.0, 1.0)).collect(),
                free,
                parameters,
                inputs,
                accelerations: (0..n).map(|_| random.next(-1.0, 1.0)).collect(),
            }
        })
        .collect()
}

/// The expected vectors by (function, point), from the tape and nalgebra.
type Expected = BTreeMap<(String, usize), Vec<f64>>;

fn run(p: &numeric::Program, input: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; p.outputs.len()];
    Tape::new(p.clone()).eval(input, &mut out);
    out
}

/// What the generated functions must compute at `point`, by the tape.
fn expected_at(e: &Equations, point: &Point, at: usize, expected: &mut Expected) {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let mut put = |name: &str, values: Vec<f64>| {
        expected.insert((name.to_string(), at), values);
    };
    let mut start_input = vec![0.0];
    start_input.extend(&point.parameters);
    start_input.extend(&e.values[e.sizes.parameters..]);
    put("initial_state", run(&e.start, &start_input));
    let mut input = vec![point.t];
    input.extend(&point.y);
    input.extend(&point.parameters);
    input.extend(&point.inputs);
    let program = |name: &str| e.program(name).expect("a program");
    for name in ["mass_matrix", "forcing", "constraints", "energies", "outputs"] {
        if let Some(p) = e.program(name) {
            put(name, run(p, &input));
        }
    }
    let mass = run(program("mass_matrix"), &input);
    let f = run(program("forcing"), &input);
    let rows = e.program("constraints").map(|p| run(p, &input)).unwrap_or_default();
    let size = n + m;
    let mut a = DMatrix::zeros(size, size);
    let mut b = DVector::zeros(size);
    for i in 0..n {
        for j in 0..n {
            a[(i, j)] = mass[j * n + i];
        }
        b[i] = f[i];
    }
    let kinds = e.prepared.stabilisation();
    let alpha = sim::BAUMGARTE_RATE;
    for c in 0..m {
        for j in 0..n {
            a[(n + c, j)] = rows[c * (n + 3) + j];
            a[(j, n + c)] = -rows[c * (n + 3) + j];
        }
        // γ stabilised as a run stabilises it: −2α·Φ̇ − α²·Φ, or −α·Φ for a velocity row.
        let [gamma, phi, phi_rate] = [0, 1, 2].map(|k| rows[c * (n + 3) + n + k]);
        b[n + c] = match kinds[c] {
            sim::Stabilisation::Position => gamma - 2.0 * alpha * phi_rate - alpha * alpha * phi,
            sim::Stabilisation::Velocity => gamma - alpha * phi,
        };
    }
    // The contacts' rows held open, as the generated functions hold them: λ = 0.
    let open = e.contact_slots();
    for &c in &open {
        for j in 0..n {
            a[(n + c, j)] = 0.0;
            a[(j, n + c)] = 0.0;
        }
        a[(n + c, n + c)] = 1.0;
        b[n + c] = 0.0;
    }
    let lu = a.clone().lu();
    let Some(solved) = lu.solve(&b) else { return };
    let mut dy = point.y[n..].to_vec();
    dy.extend(solved.iter().take(n));
    put("rhs", dy);
    let mut held = input[..1 + 2 * n].to_vec();
    held.extend(solved.iter());
    held.extend(&input[1 + 2 * n..]);
    let d = run(program("partials"), &held);
    let width = 2 * n;
    let mut jac = vec![0.0; width * width];
    for i in 0..n {
        jac[i * width + n + i] = 1.0;
    }
    for col in 0..width {
        // The rows' partials with those of the stabilisation, as the right-hand side has it.
        let row = |block: usize, c: usize| d[(n + block * m + c) * width + col];
        let stabilised = |i: usize| {
            if i < n {
                return d[i * width + col];
            }
            let c = i - n;
            if open.contains(&c) {
                return 0.0;
            }
            match kinds[c] {
                sim::Stabilisation::Position => {
                    row(0, c) + 2.0 * alpha * row(2, c) + alpha * alpha * row(1, c)
                }
                sim::Stabilisation::Velocity => row(0, c) + alpha * row(1, c),
            }
        };
        let rhs = DVector::from_iterator(size, (0..size).map(|i| -stabilised(i)));
        let x = lu.solve(&rhs).expect("regular");
        for i in 0..n {
            jac[(n + i) * width + col] = x[i];
        }
    }
    put("jacobian", jac);
    if let Some(p) = e.program("reactions") {
        put("reactions", run(p, &held));
    }
    let mut tau: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| a[(i, j)] * point.accelerations[j]).sum::<f64>() - f[i])
        .collect();
    if m > 0 {
        let rhs = DVector::from_iterator(size, (0..size).map(|i| if i < n { tau[i] } else { 0.0 }));
        let mu = lu.solve(&rhs).expect("regular");
        for c in 0..m {
            for (j, t) in tau.iter_mut().enumerate() {
                *t += a[(n + c, j)] * mu[n + c];
            }
        }
    }
    put("inverse_dynamics", tau);
}

/// A C driver that prints `function point index value` for every value the test compares.
fn driver(module: &CModule, points: &[Point]) -> String {
    let name = &module.name;
    let e = &module.equations;
    let n = e.sizes.coordinates;
    let mut s = format!("#include <stdio.h>\n#include \"{name}.h\"\n\n");
    s.push_str("static void show(const char *what, int at, const double *v, int count)\n{\n");
    s.push_str("    int i;\n    for (i = 0; i < count; i++) {\n");
    s.push_str("        printf(\"%s %d %d %.17g\\n\", what, at, i, v[i]);\n    }\n}\n\n");
    s.push_str("int main(void)\n{\n");
    let width = 2 * n;
    let longest =
        [width * width, e.sizes.constraints * (n + 3), e.outputs.len(), e.reactions.len()];
    let _ = writeln!(s, "    double out[{}];", longest.iter().max().copied().unwrap_or(1));
    let _ = writeln!(s, "    {name}_parameters p;");
    let literal = |v: &[f64]| {
        let items: Vec<String> = v.iter().map(|x| export::source::c::literal(*x)).collect();
        if items.is_empty() {
            "0.0".to_string()
        } else {
            items.join(", ")
        }
    };
    let fields = field_names(module);
    for (at, point) in points.iter().enumerate() {
        let _ = writeln!(s, "    {{\n        const double y[] = {{ {} }};", literal(&point.y));
        let _ = writeln!(s, "        const double u[] = {{ {} }};", literal(&point.inputs));
        let _ =
            writeln!(s, "        const double qdd[] = {{ {} }};", literal(&point.accelerations));
        let _ = writeln!(s, "        const double t = {};", export::source::c::literal(point.t));
        let _ = writeln!(s, "        p = {name}_default_parameters;");
        assert_eq!(fields.len(), point.free.len(), "a field per free parameter");
        for (field, v) in fields.iter().zip(&point.free) {
            let _ = writeln!(s, "        p.{field} = {};", export::source::c::literal(*v));
        }
        let _ = writeln!(s, "        {name}_initial_state(&p, out);");
        let _ = writeln!(s, "        show(\"initial_state\", {at}, out, {width});");
        for (function, count) in [
            ("mass_matrix", n * n),
            ("forcing", n),
            ("constraints", e.sizes.constraints * (n + 3)),
            ("energies", 2),
            ("outputs", e.outputs.len()),
            ("rhs", width),
            ("jacobian", width * width),
            ("reactions", e.reactions.len()),
        ] {
            let _ = writeln!(
                s,
                "        if ({name}_{function}(t, y, &p, u, out) == 0) {{\n            show(\"{function}\", {at}, out, {count});\n        }}"
            );
        }
        let _ = writeln!(
            s,
            "        if ({name}_inverse_dynamics(t, y, y + {n}, qdd, &p, u, out) == 0) {{\n            show(\"inverse_dynamics\", {at}, out, {n});\n        }}\n    }}"
        );
    }
    s.push_str("    return 0;\n}\n");
    s
}

/// The parameters' fields, read back from the header's struct.
fn field_names(module: &CModule) -> Vec<String> {
    let start = module.header.find("typedef struct {").expect("the parameters' struct");
    let end = start + module.header[start..].find('}').expect("its end");
    module.header[start..end]
        .lines()
        .filter_map(|l| l.trim().strip_prefix("double "))
        .map(|l| l.split(';').next().unwrap_or_default().to_string())
        .collect()
}

/// Compiles the module and its driver with `compiler`, runs it, and checks what it prints;
/// the failures, as messages.
fn check_with(compiler: &str, dir: &Path, module: &CModule, expected: &Expected) -> Vec<String> {
    let binary = dir.join(format!("driver-{compiler}"));
    let output = Command::new(compiler)
        .args(FLAGS)
        .arg(if module.source.len() > OPTIMISED_UP_TO { "-O0" } else { "-O1" })
        .arg(dir.join(format!("{}.c", module.name)))
        .arg(dir.join("driver.c"))
        .arg("-o")
        .arg(&binary)
        .arg("-lm")
        .output()
        .expect("the compiler runs");
    if !output.status.success() {
        return vec![format!(
            "{compiler} refuses {}: {}",
            module.name,
            String::from_utf8_lossy(&output.stderr)
        )];
    }
    let run = Command::new(&binary).output().expect("the driver runs");
    let text = String::from_utf8(run.stdout).expect("text");
    let mut got: Expected = BTreeMap::new();
    for line in text.lines() {
        let parts: Vec<&str> = line.split(' ').collect();
        let value: f64 = parts[3].parse().expect("a number");
        got.entry((parts[0].to_string(), parts[1].parse().expect("a point")))
            .or_default()
            .push(value);
    }
    let mut failures = Vec::new();
    if got.keys().ne(expected.keys()) {
        failures.push(format!(
            "{}: the driver printed {:?}, the tape has {:?}",
            module.name,
            got.keys().collect::<Vec<_>>(),
            expected.keys().collect::<Vec<_>>()
        ));
    }
    for (key, want) in expected {
        let Some(have) = got.get(key) else { continue };
        let scale = want.iter().fold(f64::MIN_POSITIVE, |s, v| s.max(v.abs()));
        for (i, (h, w)) in have.iter().zip(want).enumerate() {
            if (h - w).abs() > TOLERANCE * scale || have.len() != want.len() {
                failures.push(format!(
                    "{} ({compiler}) {} at point {}, entry {i}: C {h:e}, tape {w:e}",
                    module.name, key.0, key.1
                ));
            }
        }
    }
    failures
}

/// The C compilers to test with: the system's `cc` (or `CC`), and clang where installed.
/// With `LAGRANGE_C_TEST=required` (CI sets it) both must run.
fn compilers() -> Vec<String> {
    let system = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let required = std::env::var("LAGRANGE_C_TEST").is_ok_and(|v| v == "required");
    let mut found = Vec::new();
    for compiler in [system, "clang".to_string()] {
        let works =
            Command::new(&compiler).arg("--version").output().is_ok_and(|o| o.status.success());
        assert!(works || !required, "LAGRANGE_C_TEST=required, and `{compiler}` does not run");
        if works && !found.contains(&compiler) {
            found.push(compiler);
        }
    }
    found
}

/// Scenes of corner cases the examples leave out, derived without the dimension check: no
/// parameter, no input, no output and every function of the language; names that C reserves
/// or spells otherwise, with an input and outputs.
const CORNERS: [(&str, &str); 2] = [
    (
        "no_parameters.lag",
        "coord x = 3/10\ncoord θ = 1/5, θ' = 1\nparticle p { mass 1; position (x, 0) }\n\
         particle q { mass 2; position (x + cos(θ), sin(θ)) }\ngravity 9.81\n\
         force push on p: (-sign(x')*abs(x)^(3/2) - atan2(x, 1 + x^2)*exp(-x^2)/sqrt(2 + x^2) \
         + x^7 - tanh(x) + ln(2 + x) + asin(x/9) + acos(x/9) + atan(x) + sinh(x) + cosh(x) \
         + tan(x/3), 0)\n",
    ),
    (
        "int.lag",
        "param double = 2, α = 3, _hidden = 1/2\ninput int = 1\ncoord x = double/10\n\
         particle p { mass double; position (x, 0) }\npotential α*(x - _hidden)^2/2\n\
         force drive on p: (int, 0)\noutput stretch: x - _hidden\noutput doubled: 2*x*int\n",
    ),
];

/// Generates, compiles and checks one scene (the `seed`-th) in a folder of its own under
/// `root`; the mismatches, and how many values were compared.
fn check_scene(
    root: &Path,
    seed: usize,
    (rel, source, options): (&str, &str, engine::Options),
    compilers: &[String],
) -> (Vec<String>, usize) {
    let module = export::codegen::c(rel, source, options).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let dir = root.join(&module.name);
    std::fs::create_dir_all(&dir).unwrap();
    let points = points(&module.equations, seed);
    let mut expected = Expected::new();
    for (at, point) in points.iter().enumerate() {
        expected_at(&module.equations, point, at, &mut expected);
    }
    std::fs::write(dir.join(format!("{}.h", module.name)), &module.header).unwrap();
    std::fs::write(dir.join(format!("{}.c", module.name)), &module.source).unwrap();
    std::fs::write(dir.join("driver.c"), driver(&module, &points)).unwrap();
    let mut failures = Vec::new();
    for compiler in compilers {
        failures.extend(check_with(compiler, &dir, &module, &expected));
    }
    (failures, expected.values().map(Vec::len).sum())
}

#[test]
fn generated_c_compiles_warning_free_and_matches_the_tape() {
    let compilers = compilers();
    if compilers.is_empty() {
        eprintln!("skipped: no C compiler (cc, $CC or clang) runs on this machine");
        return;
    }
    let root = std::env::temp_dir().join(format!("lagrange-codegen-c-{}", std::process::id()));
    // The contact scenes too, their contacts held open (tests/codegen_contacts.rs tests the
    // impact map), but for the rough ones, which code generation refuses.
    let mut scenes = lagrange_tests::examples();
    scenes.retain(|(_, source)| !lagrange_tests::has_friction(source));
    scenes.push((
        "examples/bicycle/whipple.lag".into(),
        lagrange_tests::example("bicycle/whipple.lag"),
    ));
    // A chain long enough that rhs takes the recursive form's accelerations.
    scenes.push((
        "generated/pendulum_on_cart_9.lag".into(),
        lang::generate::n_link(lang::generate::Family::PendulumOnCart, 9),
    ));
    let examples = scenes.len();
    scenes.extend(CORNERS.iter().map(|(name, text)| (name.to_string(), text.to_string())));
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let compared = AtomicUsize::new(0);
    // Two workers: the deriving and the compiling of one scene overlap another's.
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some((rel, source)) = scenes.get(k) else { break };
                let options = engine::Options { units: k < examples };
                let (found, count) = check_scene(&root, k, (rel, source, options), &compilers);
                failures.lock().unwrap().extend(found);
                compared.fetch_add(count, Ordering::SeqCst);
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{} mismatches:\n{}", failures.len(), failures.join("\n"));
    let compared = compared.into_inner();
    assert!(compared > 5_000, "only {compared} values compared");
    let _ = std::fs::remove_dir_all(&root);
}

/// The fenced blocks of a page tagged `tag`, in order.
pub(crate) fn blocks(page: &str, tag: &str) -> Vec<String> {
    let mut found = Vec::new();
    // The open block's tag and text.
    let mut open: Option<(String, String)> = None;
    for line in page.lines() {
        match (line.strip_prefix("```"), open.take()) {
            (Some(fence), None) => open = Some((fence.trim().to_string(), String::new())),
            (Some(_), Some((t, text))) => {
                if t == tag {
                    found.push(text);
                }
            }
            (None, Some((t, mut text))) => {
                text.push_str(line);
                text.push('\n');
                open = Some((t, text));
            }
            (None, None) => {}
        }
    }
    found
}

/// Compiles `program` with the module's C in `dir` and runs it; what it prints.
pub(crate) fn build_and_run(compiler: &str, dir: &Path, module: &CModule, program: &str) -> String {
    std::fs::write(dir.join("driver.c"), program).unwrap();
    let binary = dir.join("driver");
    let built = Command::new(compiler)
        .args(FLAGS)
        .args(["-O2", "-o"])
        .arg(&binary)
        .arg(dir.join("driver.c"))
        .arg(dir.join(format!("{}.c", module.name)))
        .arg("-lm")
        .output()
        .expect("the compiler runs");
    assert!(built.status.success(), "{}", String::from_utf8_lossy(&built.stderr));
    let ran = Command::new(&binary).output().expect("the driver runs");
    assert!(ran.status.success(), "the driver fails");
    String::from_utf8(ran.stdout).unwrap()
}

/// docs/c.md's driver: compiled with the cart-pole's C, it prints the line the page shows,
/// and ends where `simulate` ends the same RK4 run with the same law driving F, to 1e-9
/// relative.
#[test]
fn the_pages_driver_balances_the_cart_pole_as_simulate_does() {
    let Some(compiler) = compilers().into_iter().next() else {
        eprintln!("skipped: no C compiler (cc, $CC or clang) runs on this machine");
        return;
    };
    let page = std::fs::read_to_string(lagrange_tests::examples_dir().join("../docs/c.md"))
        .expect("docs/c.md");
    // The page's first program and the first line shown are the cart-pole's; the contacts'
    // section has its own (tests/codegen_contacts.rs).
    let programs = blocks(&page, "c");
    let program = programs.first().expect("the cart-pole's program");
    assert!(program.contains("inverted_pendulum_on_cart.h"), "{program}");
    let shown =
        blocks(&page, "text").into_iter().find(|t| t.starts_with("x = ")).expect("its line");
    let rel = "examples/classics/inverted_pendulum_on_cart.lag";
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag");
    let module = export::codegen::c(rel, &source, Default::default()).expect("generates");
    let dir = std::env::temp_dir().join(format!("lagrange-c-page-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{}.h", module.name)), &module.header).unwrap();
    std::fs::write(dir.join(format!("{}.c", module.name)), &module.source).unwrap();
    let printed = build_and_run(&compiler, &dir, &module, program);
    assert_eq!(printed, shown, "docs/c.md shows another line than its program prints");
    // The same program printing every digit.
    let exact = program.replace("%.2e", "%.17g");
    let printed = build_and_run(&compiler, &dir, &module, &exact);
    let number = |after: &str| -> f64 {
        let rest = &printed[printed.find(after).expect("printed") + after.len()..];
        rest.split(' ').next().unwrap().parse().expect("a number")
    };
    let (x, theta) = (number("x = "), number("theta = "));
    let options = simulation::Options {
        input: vec!["F=10.7*x + 129.6*theta + 16.26*x' + 38.26*theta'".parse().unwrap()],
        method: Some("rk4".into()),
        step: Some(1e-3),
        until: Some(10.0),
        output: vec!["x, theta".into()],
        no_units: true,
        ..Default::default()
    };
    let outcome = simulation::simulate(&source, &options).expect("runs");
    let last = outcome.run.trajectory.rows.last().expect("rows");
    assert_eq!(*outcome.run.trajectory.times.last().unwrap(), 10.0);
    // Balanced, the state is small at the end: the agreement is relative.
    assert!(
        (last[0] - x).abs() <= 1e-9 * x.abs(),
        "simulate ends at x = {}, the driver at {x}",
        last[0]
    );
    assert!(
        (last[1] - theta).abs() <= 1e-9 * theta.abs(),
        "simulate ends at theta = {}, the driver at {theta}",
        last[1]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Andrews' squeezer with its start positions left to the kept constraints (guesses only):
/// they are solved in numbers when the scene is derived, so the C's start is those numbers
/// whatever the parameters, and the header says so.
#[test]
fn a_start_solved_in_numbers_is_fixed_and_said_so() {
    let source = lagrange_tests::example("classics/andrews_squeezer.lag");
    let guessed = lagrange_tests::andrews_with_guesses(&source);
    let module =
        export::codegen::c("andrews.lag", &guessed, Default::default()).expect("generates");
    let e = &module.equations;
    assert_eq!(e.fixed_start().len(), 6);
    assert!(
        module.header.contains("The start of Theta, gamma, Phi, delta, Omega, epsilon was solved"),
        "{}",
        module.header
    );
    let at = |scale: f64| {
        let mut input = vec![0.0];
        input.extend(e.values.iter().map(|v| v * scale));
        run(&e.start, &input)
    };
    let (scene, moved) = (at(1.0), at(1.1));
    let n = e.sizes.coordinates;
    let names = e.prepared.state_names();
    let mut fixed = 0;
    for (k, name) in names[..n].iter().enumerate() {
        if e.fixed_start().contains(name) {
            fixed += 1;
            assert_eq!(scene[k], moved[k], "{name}");
        }
    }
    assert_eq!(fixed, 6);
    let y0 = e.prepared.initial_state(&e.values, &[]).expect("a start");
    assert_eq!(scene, y0);
}
