//! `simulate --input`: the cart-pole balanced by a state-feedback law placed by hand from the
//! A and B that `linearize` gives, against the same closed loop written out here and
//! integrated by RK4; the laws refused (an unknown input, an acceleration, a reaction, another
//! input, the wrong dimension).

use engine::linearize::{linearize, Options as LinearizeOptions};
use engine::Error;
use numeric::elementary::{apply, pow_int};
use simulation::{simulate, Options, Outcome};

fn sin(a: f64) -> f64 {
    apply(cas::Func::Sin, a)
}

fn cos(a: f64) -> f64 {
    apply(cas::Func::Cos, a)
}

const CART_POLE: &str = "classics/inverted_pendulum_on_cart.lag";
/// The cart-pole's parameters and its initial tilt, as the example declares them.
const M: f64 = 2.0;
const MASS: f64 = 1.0;
const L: f64 = 1.0;
const G: f64 = 9.81;
const TILT: f64 = 0.05;

/// The poles the law places: the slowest decays as e^(−2t).
const POLES: [f64; 4] = [-2.0, -2.5, -3.0, -3.5];

/// Gains k of F = −k·(x, θ, ẋ, θ̇) that give A − B·k the [`POLES`], from A and B as
/// `linearize` gives them. With ẍ = a₂·θ + b₂·F and θ̈ = a₃·θ + b₃·F, and F = −P·x − Q·θ where
/// P = k₁ + k₃·s, Q = k₂ + k₄·s, the closed loop's characteristic polynomial is
/// s⁴ + (b₂·P + b₃·Q − a₃)·s² + (a₂·b₃ − a₃·b₂)·P; matching it with Π(s − pᵢ) term by term
/// gives the gains.
fn gains() -> [f64; 4] {
    let source = lagrange_tests::example(CART_POLE);
    let l = linearize(&source, &LinearizeOptions::default()).expect("linearizes");
    assert_eq!(l.state, ["x", "theta", "x'", "theta'"]);
    let (a, b) = (&l.at.first_order.a, &l.at.first_order.b);
    let (a2, a3, b2, b3) = (a[2][1], a[3][1], b[2][0], b[3][0]);
    // The coefficients c₀ … c₃ of Π(s − pᵢ), lowest first.
    let mut c = vec![1.0];
    for p in POLES {
        let mut next = vec![0.0; c.len() + 1];
        for (i, ci) in c.iter().enumerate() {
            next[i] -= p * ci;
            next[i + 1] += ci;
        }
        c = next;
    }
    let e = a2 * b3 - a3 * b2;
    let (k1, k3) = (c[0] / e, c[1] / e);
    let k4 = (c[3] - b2 * k3) / b3;
    let k2 = (c[2] + a3 - b2 * k1) / b3;
    [k1, k2, k3, k4]
}

/// The law as `--input` takes it. The gains carry units the scene cannot write in an
/// expression, so the runs skip the dimension check.
fn law(k: &[f64; 4]) -> String {
    format!("F=-({}*x + {}*theta + {}*x' + {}*theta')", k[0], k[1], k[2], k[3])
}

fn run(input: &str, method: &str) -> Result<Outcome, Error> {
    let options = Options {
        input: vec![input.parse().expect("an assignment")],
        method: Some(method.into()),
        tolerance: Some(1e-12),
        output: vec!["x, theta, x', theta', F".into()],
        samples: 201,
        no_units: true,
        ..Options::default()
    };
    simulate(&lagrange_tests::example(CART_POLE), &options)
}

/// (ẋ, θ̇, ẍ, θ̈) of the cart-pole under the law, from its equations written out:
/// (M + m)·ẍ + m·L·cos θ·θ̈ − m·L·sin θ·θ̇² = F and L·θ̈ + cos θ·ẍ = g·sin θ.
fn closed_loop(k: &[f64; 4], y: [f64; 4]) -> [f64; 4] {
    let [x, theta, v, w] = y;
    let force = -(k[0] * x + k[1] * theta + k[2] * v + k[3] * w);
    let (s, c) = (sin(theta), cos(theta));
    // [M + m, m·L·c; c, L]·(ẍ, θ̈) = (F + m·L·s·θ̇², g·s), by Cramer's rule.
    let (a11, a12, a21, a22) = (M + MASS, MASS * L * c, c, L);
    let (r1, r2) = (force + MASS * L * s * w * w, G * s);
    let det = a11 * a22 - a12 * a21;
    [v, w, (r1 * a22 - a12 * r2) / det, (a11 * r2 - a21 * r1) / det]
}

/// The closed loop by RK4 with step `h` from the example's start, at every multiple of `every`
/// steps.
fn rk4(k: &[f64; 4], h: f64, steps: usize, every: usize) -> Vec<[f64; 4]> {
    let mut y = [0.0, TILT, 0.0, 0.0];
    let mut out = vec![y];
    let add = |y: [f64; 4], d: [f64; 4], f: f64| std::array::from_fn(|i| y[i] + f * d[i]);
    for step in 1..=steps {
        let k1 = closed_loop(k, y);
        let k2 = closed_loop(k, add(y, k1, h / 2.0));
        let k3 = closed_loop(k, add(y, k2, h / 2.0));
        let k4 = closed_loop(k, add(y, k3, h));
        y = std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if step % every == 0 {
            out.push(y);
        }
    }
    out
}

#[test]
fn a_state_feedback_law_balances_the_cart_pole_as_the_closed_loop_by_hand_does() {
    let k = gains();
    // Tilted towards +x, the cart is pushed that way.
    assert!(k.iter().all(|g| *g < 0.0), "{k:?}");
    // 10 s in 201 samples: one every 0.05 s, 50 RK4 steps of 1 ms.
    let hand = rk4(&k, 1e-3, 10_000, 50);
    for method in ["dop853", "radau"] {
        let outcome = run(&law(&k), method).unwrap_or_else(|e| panic!("{method}: {e}"));
        assert!(outcome.run.fault.is_none(), "{method}: {:?}", outcome.run.fault);
        let rows = &outcome.run.trajectory.rows;
        assert_eq!(rows.len(), hand.len(), "{method}");
        let mut largest = 0.0f64;
        for ((t, row), y) in outcome.run.trajectory.times.iter().zip(rows).zip(&hand) {
            for i in 0..4 {
                largest = largest.max((row[i] - y[i]).abs());
            }
            // The input recorded is the law's value, not the declared 0.
            let force = -(k[0] * row[0] + k[1] * row[1] + k[2] * row[2] + k[3] * row[3]);
            assert!((row[4] - force).abs() <= 1e-9 * force.abs().max(1.0), "t = {t}: {row:?}");
        }
        assert!(largest < 1e-6, "{method}: differs from RK4 by {largest:e}");
        let last = rows.last().expect("rows");
        assert_eq!(*outcome.run.trajectory.times.last().expect("times"), 10.0);
        assert!(last[1].abs() < 1e-6, "{method}: θ(10) = {}", last[1]);
        // Without the law it falls over.
        let free = run("F=0", method).expect("runs");
        let theta = free.run.trajectory.rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
        assert!(theta > 1.0, "{method}: the free cart-pole stays within {theta}");
    }
}

/// The message and the part of the law a refused `--input` points at.
fn refused(source: &str, input: &str) -> (String, String) {
    let options = Options {
        input: vec![input.parse().expect("an assignment")],
        until: Some(0.1),
        ..Options::default()
    };
    let text = input.split_once('=').expect("name=law").1;
    match simulate(source, &options).err().expect("refused") {
        Error::Expression { diagnostics, text: law } => {
            assert_eq!(law, text);
            let span = diagnostics[0].span;
            (diagnostics[0].message.clone(), law[span.start..span.end].to_string())
        }
        other => (other.to_string(), String::new()),
    }
}

#[test]
fn laws_that_cannot_drive_an_input_are_refused_where_they_go_wrong() {
    let cart_pole = lagrange_tests::example(CART_POLE);
    let (message, _) = refused(&cart_pole, "f=0");
    assert_eq!(message, "error: `input` f: no input of that name; did you mean `F`? (inputs: F)");
    let (message, part) = refused(&cart_pole, "F=M*g*(theta + x''/g)");
    assert_eq!(message, "what drives an input cannot depend on an acceleration");
    assert_eq!(part, "x''");
    let (message, part) = refused(&cart_pole, "F=M*x");
    assert!(message.starts_with("dimensions do not match between the input `F`"), "{message}");
    assert_eq!(part, "M*x");
    let (message, part) = refused(&cart_pole, "F=2*F");
    assert_eq!((message.as_str(), part.as_str()), ("what drives `F` cannot name an input", "2*F"));
    let rod = format!(
        "{}input P = 0 N\nforce push on rod: (P, 0)\n",
        lagrange_tests::example("ps5/falling_rod.lag")
    );
    let (message, part) = refused(&rod, "P=-floor.force");
    assert_eq!(message, "what drives `P` cannot name a reaction");
    assert_eq!(part, "-floor.force");
    let (message, _) = refused(&lagrange_tests::example("classics/double_pendulum.lag"), "F=1");
    assert!(message.contains("the scene has no input"), "{message}");
}

/// A mass on a spring of its own law: x'' = F/m with F = −k·x − c·ẋ, as the scene's
/// `simulate` block drives it; the command line's law for the same input wins.
const DRIVEN_BY_THE_SCENE: &str = "\
param m = 1 kg, k = 4 N/m, c = 1 N*s/m
input F = 0 N
coord x = 1
particle p { mass m; position (x, 0) }
force push on p: (F, 0)
simulate { until 1 s; input F = -k*x - c*x'; output x, F }
";

#[test]
fn the_scene_s_simulate_block_drives_an_input_and_the_command_line_overrides_it() {
    let options = Options { samples: 3, tolerance: Some(1e-12), ..Options::default() };
    let scene = simulate(DRIVEN_BY_THE_SCENE, &options).expect("runs");
    // x'' + x' + 4·x = 0 from x = 1 at rest: x = e^(−t/2)·(cos ωt + sin ωt/(2ω)), ω² = 15/4.
    let w = 15f64.sqrt() / 2.0;
    let exact = |t: f64| apply(cas::Func::Exp, -t / 2.0) * (cos(w * t) + sin(w * t) / (2.0 * w));
    for (t, row) in scene.run.trajectory.times.iter().zip(&scene.run.trajectory.rows) {
        assert!((row[0] - exact(*t)).abs() < 1e-9, "t = {t}: x = {}", row[0]);
    }
    let input = vec!["F=0".parse().expect("an assignment")];
    let held = simulate(DRIVEN_BY_THE_SCENE, &Options { input, ..options }).expect("runs");
    assert!(held.run.trajectory.rows.iter().all(|r| r[0] == 1.0 && r[1] == 0.0));
    let misnamed = DRIVEN_BY_THE_SCENE.replace("input F = -k", "input G = -k");
    let error = simulate(&misnamed, &Options::default()).err().expect("refused").to_string();
    assert!(error.contains("no input `G` (line 6, column 29)"), "{error}");
}

/// A free mass pushed by a force given as samples: F = 2·t up to t = 1, then 2, linear in
/// between; x = t³/6, then 1/6 + (t − 1)/2 + (t − 1)²/2.
#[test]
fn an_input_follows_a_time_series_between_its_samples() {
    let scene = "\
param m = 2 kg
input F = 0 N
coord x
particle p { mass m; position (x, 0) }
force push on p: (F, 0)
";
    let series = cli::series::parse("t, F\n0, 0\n1, 2\n2, 2\n").expect("a series");
    let options = Options {
        input_series: vec![("F".into(), series.clone())],
        until: Some(2.0),
        samples: 9,
        tolerance: Some(1e-12),
        output: vec!["x, F".into()],
        ..Options::default()
    };
    let exact = |t: f64| {
        if t <= 1.0 {
            pow_int(t, 3) / 6.0
        } else {
            1.0 / 6.0 + (t - 1.0) / 2.0 + pow_int(t - 1.0, 2) / 2.0
        }
    };
    for method in ["dop853", "radau"] {
        let options = Options { method: Some(method.into()), ..options.clone() };
        let run = simulate(scene, &options).unwrap_or_else(|e| panic!("{method}: {e}"));
        for (t, row) in run.run.trajectory.times.iter().zip(&run.run.trajectory.rows) {
            assert!((row[0] - exact(*t)).abs() < 1e-8, "{method} t = {t}: x = {}", row[0]);
            assert_eq!(row[1], series.at(*t), "{method} t = {t}");
        }
    }
    let longer = Options { until: Some(3.0), ..options.clone() };
    let error = simulate(scene, &longer).err().expect("past the series").to_string();
    assert!(error.contains("the series spans t = 0 to 2 s"), "{error}");
    let twice = Options { input: vec!["F=1".parse().expect("an assignment")], ..options };
    let error = simulate(scene, &twice).err().expect("driven twice").to_string();
    assert!(error.contains("driven twice"), "{error}");
}

/// A `draw` line that shows the input draws what drives it: here from the mass to
/// x + F/k = 0, always at the origin.
#[test]
fn a_drawing_of_a_driven_input_shows_its_law() {
    let scene = "\
param m = 1 kg, k = 4 N/m
input F = 0 N
coord x = 1
particle p { mass m; position (x, 0) }
force push on p: (F, 0)
draw line from p to p.position + (F/k, 0)
";
    let options = Options {
        input: vec!["F=-k*x".parse().expect("an assignment")],
        until: Some(1.0),
        samples: 11,
        animate: true,
        ..Options::default()
    };
    let outcome = simulate(scene, &options).expect("runs");
    let animation = outcome.animation.expect("an animation");
    let line = animation.figures.iter().find(|f| f.label.contains("F/k")).expect("the line");
    assert_eq!(line.frames.len(), 11);
    for frame in &line.frames {
        // (x, 0) to (x + F/k, 0) = (0, 0), with x moving.
        assert!(frame[2].abs() < 1e-12, "{frame:?}");
    }
    assert!(line.frames.iter().any(|f| (f[0] - 1.0).abs() > 0.1), "the mass moves");
}

/// A mass pushed by an input that stands in a potential, not a force.
const PUSHED_INSIDE_A_POTENTIAL: &str = "\
param m = 1 kg
input F = 0 N
coord x = 1
particle p { mass m; position (x, 0) }
potential -F*x
";

/// gauss and midpoint differentiate the Lagrangian, where an input in a potential would
/// bring its law's derivative along; they refuse such a run, and dop853 takes it.
#[test]
fn the_symplectic_methods_refuse_an_input_driven_inside_a_potential() {
    let scene = PUSHED_INSIDE_A_POTENTIAL;
    let options = |method: &str| Options {
        input: vec!["F=1".parse().expect("an assignment")],
        method: Some(method.into()),
        until: Some(0.1),
        samples: 2,
        ..Options::default()
    };
    for method in ["gauss", "midpoint"] {
        let error = simulate(scene, &options(method)).err().expect("refused").to_string();
        assert!(error.contains("must not be in it (through a potential): `F` is"), "{error}");
    }
    // Held, the input is a constant between samples, which the Lagrangian may hold.
    let held = Options { hold: Some(0.05), ..options("gauss") };
    let x = simulate(scene, &held).expect("runs").run.trajectory.rows.last().expect("rows")[0];
    assert!((x - 1.005).abs() < 1e-12, "x(0.1) = {x}");
    // x'' = F/m = 1 from rest: x = 1 + t²/2.
    let run = simulate(scene, &options("dop853")).expect("runs");
    let x = run.run.trajectory.rows.last().expect("rows")[0];
    assert!((x - 1.005).abs() < 1e-12, "x(0.1) = {x}");
}

/// `lagrange bench --input`: every run, the reference included, is of the driven scene, and
/// the methods that refuse it are left out with the reason rather than failing the bench.
#[test]
fn bench_measures_the_driven_scene_and_leaves_out_the_methods_that_refuse_it() {
    let scene = PUSHED_INSIDE_A_POTENTIAL;
    let base = Options {
        input: vec!["F=1".parse().expect("an assignment")],
        until: Some(0.1),
        ..Options::default()
    };
    let report = simulation::bench::bench(scene, &base, 1, &mut ()).expect("benchmarks");
    let left_out: Vec<(&str, &str)> =
        report.inapplicable.iter().map(|m| (m.method.name(), m.reason)).collect();
    let reason = simulation::DRIVEN_IN_LAGRANGIAN;
    assert_eq!(left_out, [("midpoint", reason), ("gauss", reason)]);
    assert!(report.trials.iter().all(|t| !t.method.is_symplectic()));
    // Undriven, x would stay at 1 and be 5e-3 from the reference's 1.005.
    let worst = report.trials.iter().map(|t| t.error).fold(0.0, f64::max);
    assert!(worst < 1e-6, "the largest error is {worst:e}");
    // Held, the input is a constant between samples, which the symplectic methods take.
    let held = Options { hold: Some(0.05), ..base };
    let report = simulation::bench::bench(scene, &held, 1, &mut ()).expect("benchmarks");
    assert!(report.inapplicable.is_empty());
}

/// A pendulum whose pivot slides along x as `driver` says.
fn sliding_pivot(driver: &str) -> String {
    format!(
        "param m = 1 kg, L = 1 m, g = 9.81 m/s^2, A = 0.1 m, w = 2 rad/s
input s = 0.05 m
coord x = 0.3, y ~ -1
particle bob {{ mass m; position (x, y) }}
gravity g
constraint rod: (x - {driver})^2 + y^2 = L^2
"
    )
}

fn rows(source: &str, input: &[&str], method: &str) -> Result<Vec<Vec<f64>>, Error> {
    let options = Options {
        input: input.iter().map(|i| i.parse().expect("an assignment")).collect(),
        method: Some(method.into()),
        until: Some(2.0),
        tolerance: Some(1e-11),
        output: vec!["x, y, x', y', rod.force".into()],
        samples: 41,
        ..Options::default()
    };
    let outcome = simulate(source, &options)?;
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    Ok(outcome.run.trajectory.rows)
}

fn largest_gap(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().flatten().zip(b.iter().flatten()).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max)
}

/// An input in a constraint takes its law before the equations are derived, so that the
/// driver's rates and second derivative in γ are the law's, exactly: driven by a law of t, or
/// of a coordinate, the pivot moves as the same driver written into the constraint moves it,
/// and as θ's own equation integrated here says.
#[test]
fn an_input_drives_a_constraint_as_its_law_written_there_does() {
    let driven = sliding_pivot("s");
    for (law, written) in
        [("s=A*(1 - cos(w*t))", "A*(1 - cos(w*t))"), ("s=x*cos(w*t)/4", "x*cos(w*t)/4")]
    {
        for method in ["dop853", "radau"] {
            let by_input = rows(&driven, &[law], method).expect("runs");
            let by_hand = rows(&sliding_pivot(written), &[], method).expect("runs");
            let gap = largest_gap(&by_input, &by_hand);
            assert!(gap < 1e-12, "{law} by {method}: {gap:e} from the driver written out");
            // The pivot moves: the run is not the undriven one.
            let still = rows(&sliding_pivot("0.05"), &[], method).expect("runs");
            assert!(largest_gap(&by_input, &still) > 1e-3, "{law} by {method}");
        }
    }
    // Independently: with θ from the downward vertical, x = s + L·sin θ, y = −L·cos θ and
    // L·θ̈ + s̈·cos θ + g·sin θ = 0, s̈ = A·w²·cos(w·t); integrated here by RK4.
    let by_input = rows(&driven, &["s=A*(1 - cos(w*t))"], "dop853").expect("runs");
    let (a, w, g, l) = (0.1, 2.0, 9.81, 1.0);
    let rate = |t: f64, [theta, omega]: [f64; 2]| {
        let pivot = a * w * w * cos(w * t);
        [omega, -(pivot * cos(theta) + g * sin(theta)) / l]
    };
    let (h, mut t, mut y) = (1e-4, 0.0, [apply(cas::Func::Asin, 0.3), 0.0]);
    for (k, row) in by_input.iter().enumerate() {
        while t < 0.05 * k as f64 - 1e-9 {
            let k1 = rate(t, y);
            let k2 = rate(t + h / 2.0, [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]]);
            let k3 = rate(t + h / 2.0, [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]]);
            let k4 = rate(t + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for i in 0..2 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
        }
        let pivot = a * (1.0 - cos(w * t));
        let (x, height) = (pivot + l * sin(y[0]), -l * cos(y[0]));
        assert!((row[0] - x).abs() < 1e-9 && (row[1] - height).abs() < 1e-9, "t = {t}: {row:?}");
    }
}

/// What cannot drive a constraint is refused naming the input and the constraint: a law of
/// the rates, a time series, a hold. A run that does not drive it, and every command that
/// derives the equations with the input as a symbol, refuse the scene where the input stands,
/// with the hint of what works.
#[test]
fn an_input_in_a_constraint_is_refused_where_its_rates_are_not_known() {
    let driven = sliding_pivot("s");
    let error = |options: Options| simulate(&driven, &options).err().expect("refused").to_string();
    let law = |text: &str| vec![text.parse().expect("an assignment")];
    let of_rates = error(Options { input: law("s=A*x'/(w*L)"), ..Options::default() });
    assert!(of_rates.contains("`input` s: drives the constraint `rod`, so its law may name t"));
    let series = sim::Series::new(vec![0.0, 20.0], vec![0.0, 1.0]).expect("a series");
    let given = Options { input_series: vec![("s".into(), series)], ..Options::default() };
    assert!(error(given).contains("and a time series has none"));
    let held = Options { input: law("s=A*sin(w*t)"), hold: Some(0.1), ..Options::default() };
    assert!(error(held).contains("which a held value would make jump at every sample"));

    let refused = [engine::load(&driven).err(), simulate(&driven, &Options::default()).err()];
    for error in refused {
        let Some(Error::Scene { diagnostics, .. }) = error else {
            panic!("an input in a constraint with no law is refused as a scene error");
        };
        let d = &diagnostics[0];
        assert_eq!(d.message, "a constraint cannot depend on the input `s`");
        assert_eq!(&driven[d.span.start..d.span.end], "s");
        assert!(driven[..d.span.start].ends_with("constraint rod: (x - "));
        let hint = d.hint.as_deref().unwrap_or_default();
        assert!(hint.contains("`simulate --input s=…` puts a law of `t`"), "{hint}");
    }
}
