//! `lagrange fit`: the residuals' Jacobian against central differences of whole runs (in
//! parameters, derived ones following, in start values, with a series-driven input and with a
//! kept constraint), the examples' recordings remade from their seeds, each example's fit
//! recovering the values its recording was made with to two standard errors (a damped
//! pendulum; a pushed cart with a hanging pole; a chaotic double pendulum by multiple
//! shooting), the fitted scene written back, and bad data refused at its cell.

use fit::data;

fn example(name: &str) -> String {
    lagrange_tests::example(&format!("fitting/{name}"))
}

/// The push that drives the cart's recording: two sines sampled every 0.05 s over 6 s.
fn push() -> sim::Series {
    let times: Vec<f64> = (0..=120).map(|k| k as f64 * 0.05).collect();
    let sin = |x: f64| numeric::elementary::apply(cas::Func::Sin, x);
    let values = times.iter().map(|t| 2.0 * sin(1.3 * t) + 1.5 * sin(3.1 * t)).collect();
    sim::Series::new(times, values).expect("a series")
}

fn push_csv() -> String {
    let series = push();
    let mut text = String::from("t,F\n");
    for k in 0..=120 {
        let t = k as f64 * 0.05;
        text.push_str(&format!("{t},{:.6}\n", series.at(t)));
    }
    text
}

/// Each example's recording: its scene, the true values, the columns and their noise, the
/// span and samples, the seed.
fn recordings() -> Vec<(&'static str, String)> {
    let pendulum = lagrange_tests::recording(
        &example("damped_pendulum.lag"),
        &[("L", "1.1"), ("c", "0.3")],
        &[],
        &[("theta", 0.01)],
        (10.0, 201),
        7,
    );
    let push = cli::series::parse(&push_csv()).expect("the push reads back");
    let cart = lagrange_tests::recording(
        &example("cart_pendulum.lag"),
        &[("b", "0.8"), ("I", "0.009")],
        &[("F", push)],
        &[("x", 0.002), ("theta", 0.005)],
        (6.0, 241),
        11,
    );
    let double = lagrange_tests::recording(
        &example("double_pendulum.lag"),
        &[("l2", "1"), ("m2", "1")],
        &[],
        &[("theta1", 0.005), ("theta2", 0.005)],
        (4.0, 201),
        13,
    );
    vec![
        ("damped_pendulum.csv", pendulum),
        ("push.csv", push_csv()),
        ("cart_pendulum.csv", cart),
        ("double_pendulum.csv", double),
    ]
}

#[test]
fn the_examples_recordings_are_what_their_seeds_make() {
    let dir = lagrange_tests::examples_dir().join("fitting");
    for (name, text) in recordings() {
        let path = dir.join(name);
        if std::env::var_os("LAGRANGE_REMAKE_RECORDINGS").is_some() {
            std::fs::write(&path, &text).expect("writable");
        }
        let kept = std::fs::read_to_string(&path).expect("the recording is kept");
        assert!(
            kept == text,
            "{name} is not what its seed makes (LAGRANGE_REMAKE_RECORDINGS=1 remakes it)"
        );
    }
}

fn options(free: &str, shots: usize) -> fit::Options {
    fit::Options { free: fit::parse_free(free).expect("names"), shots, ..Default::default() }
}

fn table(name: &str) -> data::Table {
    let path = lagrange_tests::examples_dir().join("fitting").join(name);
    let text = std::fs::read_to_string(path).expect("the recording is kept");
    data::read(&text).expect("the recording reads")
}

/// The fit of `scene` to `recording` freeing `free`: each estimate within two standard errors
/// of `truth`, and the standard errors small against the values.
fn recovers(scene: &str, recording: &str, mut options: fit::Options, truth: &[f64]) -> fit::Fit {
    if recording == "cart_pendulum.csv" {
        options.run.input_series = vec![("F".into(), push())];
    }
    let result = fit::fit(&example(scene), &options, table(recording)).expect("fits");
    within_two_errors(&result, truth);
    for (j, u) in result.unknowns.iter().enumerate() {
        let error = result.standard_errors[j];
        assert!(error < 0.05 * truth[j].abs(), "{}: ± {error} of {}", u.name, truth[j]);
    }
    result
}

/// That the fit converged with each estimate within two standard errors of `truth`.
fn within_two_errors(result: &fit::Fit, truth: &[f64]) {
    assert!(result.ending.converged(), "{:?}", result.ending);
    for (j, u) in result.unknowns.iter().enumerate() {
        let (estimate, error) = (result.estimates[j], result.standard_errors[j]);
        assert!(
            (estimate - truth[j]).abs() <= 2.0 * error,
            "{}: {estimate} ± {error}, truly {}",
            u.name,
            truth[j]
        );
    }
}

#[test]
fn a_damped_pendulums_length_and_damping_are_recovered() {
    let result =
        recovers("damped_pendulum.lag", "damped_pendulum.csv", options("L, c", 1), &[1.1, 0.3]);
    // The noise was 0.01 rad: the residuals' RMS is that, to the sample's spread.
    let rms = result.columns[0].rms;
    assert!((rms - 0.01).abs() < 0.002, "RMS {rms}");
    assert!(result.unidentifiable.is_none());
}

#[test]
fn a_pushed_carts_friction_and_its_poles_inertia_are_recovered() {
    recovers("cart_pendulum.lag", "cart_pendulum.csv", options("b, I", 1), &[0.8, 0.009]);
}

#[test]
fn a_chaotic_double_pendulum_is_fitted_by_multiple_shooting() {
    let result =
        recovers("double_pendulum.lag", "double_pendulum.csv", options("l2, m2", 6), &[1.0, 1.0]);
    assert_eq!(result.shots, 6);
}

/// The largest entry of the residuals' Jacobian less central differences of whole runs, at
/// `theta`, relative to the Jacobian's largest entry.
fn jacobian_against_differences(
    scene: &str,
    recording: &str,
    options: fit::Options,
    theta: &[f64],
) -> f64 {
    let mut problem =
        fit::problem::Problem::load(&example(scene), &options, table(recording)).expect("loads");
    against_differences(&mut problem, theta)
}

#[test]
fn the_jacobian_is_what_differences_of_whole_runs_give() {
    let mut tight = options("L, c, theta(0), theta'(0)", 1);
    tight.run.tolerance = Some(1e-13);
    let pendulum = jacobian_against_differences(
        "damped_pendulum.lag",
        "damped_pendulum.csv",
        tight,
        &[1.05, 0.25, 0.98, 0.1],
    );
    assert!(pendulum < 1e-7, "pendulum: {pendulum:.1e}");
    let mut driven = options("b, I, x'(0)", 1);
    driven.run.tolerance = Some(1e-13);
    driven.run.input_series = vec![("F".into(), push())];
    let cart = jacobian_against_differences(
        "cart_pendulum.lag",
        "cart_pendulum.csv",
        driven,
        &[0.7, 0.01, 0.05],
    );
    assert!(cart < 1e-7, "cart: {cart:.1e}");
    // A value set in terms of a free parameter follows it: c's share in ∂/∂L is taken.
    let mut following = options("L", 1);
    following.run.tolerance = Some(1e-13);
    following.run.set = vec!["c=3*L/11".parse().expect("an assignment")];
    let set = jacobian_against_differences(
        "damped_pendulum.lag",
        "damped_pendulum.csv",
        following,
        &[1.05],
    );
    assert!(set < 1e-7, "c = 3L/11: {set:.1e}");
}

/// The error of fitting the gallery's scene to `data` (its text, shown as `data_path`)
/// freeing `free`, as `lagrange fit` prints it.
fn refused(data_path: &str, data: &str, free: &str) -> String {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bad/fit");
    let scene = std::fs::read_to_string(dir.join("scene.lag")).expect("the gallery's scene");
    let error = match fit::parse_free(free) {
        Err(e) => e,
        Ok(free) => {
            let options = fit::Options { free, ..Default::default() };
            match data::read(data) {
                Err(d) => fit::Error::Data(d),
                Ok(table) => fit::fit(&scene, &options, table).expect_err("refused"),
            }
        }
    };
    assert_eq!(error.exit_code(), 2, "{error:?}");
    cli::fit::error("scene.lag", (data_path, data), &error)
}

#[test]
fn bad_data_and_free_names_are_refused_at_their_place() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bad/fit");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/bad/fit exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "only {} bad data files", files.len());
    for path in files {
        let name = path.file_stem().expect("name").to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&path).expect("readable");
        let shown = format!("{name}.csv");
        let report = refused(&shown, &text, "L, c");
        assert!(report.contains(&format!("{shown}:")), "{name}: no location in\n{report}");
        assert!(report.contains('^'), "{name}: no caret in\n{report}");
        insta::assert_snapshot!(format!("bad_data@{name}"), report);
    }
    let good =
        std::fs::read_to_string(lagrange_tests::examples_dir().join("fitting/damped_pendulum.csv"))
            .expect("the recording");
    let names = [
        ("not_a_parameter", "L, Lc"),
        ("a_coordinate_without_its_zero", "theta"),
        ("a_start_value_not_a_number", "L=abc"),
        ("freed_twice", "m, L, m"),
        ("no_such_coordinate", "x(0)"),
    ];
    for (name, free) in names {
        let report = refused("recording.csv", &good, free);
        assert!(report.contains("--free:1:"), "{name}: no location in\n{report}");
        assert!(report.contains('^'), "{name}: no caret in\n{report}");
        insta::assert_snapshot!(format!("bad_free@{name}"), report);
    }
}

/// A pendulum kept on its rod by a multiplier, its bob's start height solved from the rod.
const KEPT: &str = "scene \"A pendulum kept on its rod\"
param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord x = L*sin(1/2)
coord y ~ -L
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";

#[test]
fn a_kept_rods_length_and_gravity_are_recovered_with_the_start_solved_on_the_rod() {
    let text = lagrange_tests::recording(
        KEPT,
        &[("L", "1.2"), ("g", "9.7")],
        &[],
        &[("x", 0.002), ("y", 0.002)],
        (4.0, 161),
        17,
    );
    let recording = data::read(&text).expect("reads");
    let mut tight = options("L, g", 1);
    tight.run.tolerance = Some(1e-12);
    let mut problem = fit::problem::Problem::load(KEPT, &tight, recording.clone()).expect("loads");
    // The start's height is solved on the rod, and its derivative differenced.
    let error = against_differences(&mut problem, &[1.1, 9.75]);
    assert!(error < 1e-6, "{error:.1e}");
    let result = fit::fit(KEPT, &tight, recording).expect("fits");
    within_two_errors(&result, &[1.2, 9.7]);
}

#[test]
fn the_fitted_scene_holds_the_estimates_in_its_units() {
    let source = "scene \"s\"\nparam m = 1 kg, L = 80 cm, g = 9.81 m/s^2, c = 0.1 N*m*s\ncoord theta = 1, theta' = 0\nparticle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\ngravity g\ndissipation c/2*theta'^2\n";
    let options = options("L, c, theta'(0)", 1);
    let result = fit::fit(source, &options, table("damped_pendulum.csv")).expect("fits");
    let written = fit::scene::written(source, &result).expect("writes");
    let length = result.estimates[0] * 100.0;
    assert!(written.contains(&format!("L = {length} cm")), "{written}");
    assert!(written.contains(&format!("c = {} N*m*s", result.estimates[1])), "{written}");
    assert!(written.contains(&format!("theta' = {}", result.estimates[2])), "{written}");
    // The fitted scene fits at once: its values are the optimum, to the iteration's own
    // tolerance, a millionth of a standard error.
    let again = fit::fit(&written, &options, table("damped_pendulum.csv")).expect("fits");
    for j in 0..3 {
        let (a, b, error) = (again.estimates[j], result.estimates[j], result.standard_errors[j]);
        assert!((a - b).abs() <= 1e-6 * error, "{a} against {b} ± {error}");
    }
    assert!(again.iterations <= 3, "{} iterations from the optimum", again.iterations);
}

#[test]
fn a_mass_and_a_damping_seen_only_as_their_ratio_are_named_unidentifiable() {
    // θ'' = −(g/L)·sin θ − c/(m·L²)·θ': the data fix c/m, not c and m apart.
    let result = fit::fit(
        &example("damped_pendulum.lag"),
        &options("m, c, L", 1),
        table("damped_pendulum.csv"),
    )
    .expect("fits");
    let combination = result.unidentifiable.expect("named");
    let coefficient =
        |name: &str| combination.terms.iter().find(|t| t.0 == name).map_or(0.0, |t| t.1);
    // δm/m = δc/c leaves c/m alone: the combination is (δm/m + δc/c)/√2 up to sign.
    assert!((coefficient("m") - coefficient("c")).abs() < 1e-6, "{combination:?}");
    assert!((coefficient("m").abs() - 0.5f64.sqrt()).abs() < 1e-6, "{combination:?}");
    assert!(coefficient("L").abs() < 1e-3, "{combination:?}");
}

#[test]
fn accelerations_and_reactions_are_measured_columns_with_exact_derivatives() {
    // An accelerometer on the pendulum, and the kept rod's tension with the bob's x.
    let text = "t,theta''\n0.5,-5\n1,-2\n1.5,3\n2,6\n2.5,1\n";
    let recording = data::read(text).expect("reads");
    let mut pendulum = options("L, c, theta(0)", 1);
    pendulum.run.tolerance = Some(1e-13);
    let mut problem =
        fit::problem::Problem::load(&example("damped_pendulum.lag"), &pendulum, recording)
            .expect("loads");
    let error = against_differences(&mut problem, &[1.05, 0.25, 0.98]);
    assert!(error < 1e-7, "theta'': {error:.1e}");
    let text = lagrange_tests::recording(
        KEPT,
        &[("L", "1.2"), ("g", "9.7")],
        &[],
        &[("x", 0.002), ("rod.force", 0.05)],
        (4.0, 81),
        19,
    );
    let recording = data::read(&text).expect("reads");
    let mut kept = options("L, g", 1);
    kept.run.tolerance = Some(1e-12);
    let mut problem = fit::problem::Problem::load(KEPT, &kept, recording.clone()).expect("loads");
    let error = against_differences(&mut problem, &[1.1, 9.75]);
    assert!(error < 1e-6, "rod.force: {error:.1e}");
    let result = fit::fit(KEPT, &kept, recording).expect("fits");
    within_two_errors(&result, &[1.2, 9.7]);
}

/// The largest entry of the problem's Jacobian at `theta` less central differences of its
/// residuals, relative to the Jacobian's largest entry.
fn against_differences(problem: &mut fit::problem::Problem, theta: &[f64]) -> f64 {
    let exact = problem.evaluate(theta).expect("runs");
    let width = theta.len();
    let largest = exact.jacobian.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for j in 0..width {
        let h = 1e-5 * theta[j].abs().max(1e-2);
        let (mut up, mut down) = (theta.to_vec(), theta.to_vec());
        up[j] += h;
        down[j] -= h;
        let up = problem.evaluate(&up).expect("runs").residuals;
        let down = problem.evaluate(&down).expect("runs").residuals;
        for i in 0..up.len() {
            let difference = (up[i] - down[i]) / (2.0 * h);
            worst = worst.max((exact.jacobian[i * width + j] - difference).abs());
        }
    }
    worst / largest
}

#[test]
fn shots_on_a_kept_rod_join_into_the_single_shots_fit() {
    // Each shot's start is free of the rod; the joins bring every start back onto it.
    let text = lagrange_tests::recording(
        KEPT,
        &[("L", "1.2"), ("g", "9.7")],
        &[],
        &[("x", 0.002), ("y", 0.002), ("x'", 0.01), ("y'", 0.01)],
        (4.0, 161),
        17,
    );
    let recording = data::read(&text).expect("reads");
    let fitted = |shots: usize| {
        let mut o = options("L, g", shots);
        o.run.tolerance = Some(1e-12);
        fit::fit(KEPT, &o, recording.clone()).expect("fits")
    };
    let (four, one) = (fitted(4), fitted(1));
    assert!(four.ending.converged(), "{:?}", four.ending);
    for j in 0..2 {
        let (a, b) = (four.estimates[j], one.estimates[j]);
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{a} against {b}");
        let (a, b) = (four.standard_errors[j], one.standard_errors[j]);
        assert!((a - b).abs() <= 1e-6 * b.abs(), "± {a} against ± {b}");
    }
}

#[test]
fn a_fits_runs_end_their_steps_at_an_inputs_knots_as_a_simulation_does() {
    // Data every 0.03 s, the push's knots every 0.05 s: the runs stop at the knots, and read
    // the data times between.
    let scene = example("cart_pendulum.lag");
    let run = simulation::Options {
        until: Some(6.0),
        tolerance: Some(1e-12),
        samples: 201,
        output: vec!["x, theta".into()],
        set: vec!["b=0.8".parse().expect("set"), "I=0.009".parse().expect("set")],
        input_series: vec![("F".into(), push())],
        ..Default::default()
    };
    let outcome = simulation::simulate(&scene, &run).expect("runs");
    let trajectory = &outcome.run.trajectory;
    let mut text = String::from("t,x,theta\n");
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        text.push_str(&format!("{t},{},{}\n", row[0], row[1]));
    }
    let mut o = options("b, I", 1);
    o.run.tolerance = Some(1e-12);
    o.run.input_series = vec![("F".into(), push())];
    let table = data::read(&text).expect("reads");
    let mut problem = fit::problem::Problem::load(&scene, &o, table).expect("loads");
    let at_truth = problem.evaluate(&[0.8, 0.009]).expect("runs");
    let worst = at_truth.residuals.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    assert!(worst < 1e-9, "the fit's run is {worst:.1e} from the simulation's");
    // The push's 120 knots end a step each, however loose the tolerance; the data times,
    // read from the dense output, end none.
    o.run.tolerance = Some(1e-4);
    let table = data::read(&text).expect("reads");
    let mut problem = fit::problem::Problem::load(&scene, &o, table).expect("loads");
    let steps = problem.evaluate(&[0.8, 0.009]).expect("runs").steps;
    assert!((120..200).contains(&steps), "{steps} steps");
}
