//! Accuracy of `simulate` against exact references: the pendulum's period, the falling rod's
//! energy, reaction and landing time, and the bounded energy error of the symplectic method.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use bench::reference::{elliptic_k, gauss_legendre};
use cli::simulate::summary;
use simulation::{simulate, Options, Outcome};

fn run(rel: &str, options: Options) -> Outcome {
    let path = lagrange_tests::examples_dir().join(rel);
    let source = std::fs::read_to_string(&path).expect("example");
    let outcome = simulate(&source, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{}", summary(&outcome));
    outcome
}

#[test]
fn pendulum_period_matches_the_elliptic_integral() {
    // Released from rest, θ' next vanishes at half a period.
    let outcome = run(
        "classics/simple_pendulum.lag",
        Options {
            method: Some("dop853".into()),
            tolerance: Some(1e-13),
            until: Some(3.0),
            stop_when: vec!["theta'".into()],
            ..Options::default()
        },
    );
    let half = outcome.run.final_time;
    let (l, g, theta0) = (1.0f64, 9.81f64, 0.5f64);
    let exact = 4.0 * (l / g).sqrt() * elliptic_k((theta0 / 2.0).sin());
    let relative = (2.0 * half - exact).abs() / exact;
    assert!(relative < 1e-10, "period {} vs {exact}: {relative:e}", 2.0 * half);
}

#[test]
fn falling_rod_conserves_energy_and_lands_when_the_energy_integral_says() {
    let outcome = run(
        "ps5/falling_rod.lag",
        Options {
            method: Some("dop853".into()),
            tolerance: Some(1e-12),
            until: Some(1.0),
            output: vec!["theta, floor.force".into()],
            ..Options::default()
        },
    );
    let (m, l, g) = (1.0f64, 1.0f64, 9.81f64);
    // The scene's simulate block stops the run when the rod lies flat.
    assert!(outcome.run.stopped_by.is_some(), "{}", summary(&outcome));
    let rows = &outcome.run.trajectory.rows;
    let last = rows.last().expect("rows");
    assert!((last[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // N(0) = 4/7 m g.
    let n0 = rows[0][1];
    assert!((n0 - 4.0 / 7.0 * m * g).abs() < 1e-12 * m * g, "N(0) = {n0}");
    // Energy, relative to its scale.
    let (_, relative) = outcome.energy_drift();
    assert!(relative < 1e-9, "energy drift {relative:e}");

    // The landing time from energy: θ'² = 12 g (cos θ0 − cos θ) / (L (1 + 3 sin² θ)), so
    // T = ∫ dθ/θ' from θ0 to π/2. With θ = θ0 + (π/2 − θ0) u² the 1/√(θ − θ0) singularity
    // at the start becomes a smooth integrand in u.
    let theta0 = std::f64::consts::FRAC_PI_6;
    let span = std::f64::consts::FRAC_PI_2 - theta0;
    let integrand = |u: f64| {
        let theta = theta0 + span * u * u;
        let rate2 =
            12.0 * g * (theta0.cos() - theta.cos()) / (l * (1.0 + 3.0 * theta.sin().powi(2)));
        2.0 * span * u / rate2.sqrt()
    };
    let exact = gauss_legendre(integrand, 0.0, 1.0, 4000);
    let landed = outcome.run.final_time;
    assert!((landed - exact).abs() < 1e-10 * exact, "landed at {landed}, energy integral {exact}");
}

#[test]
fn symplectic_energy_error_stays_bounded_over_a_hundred_thousand_steps() {
    let outcome = run(
        "classics/simple_pendulum.lag",
        Options {
            method: Some("gauss".into()),
            step: Some(0.01),
            until: Some(1000.0),
            set: vec!["theta=2".parse().expect("name=value")],
            ..Options::default()
        },
    );
    assert!(outcome.run.steps >= 100_000);
    let e = outcome.energy();
    let e0 = e[0];
    let window = e.len() / 10;
    let worst = |s: &[f64]| s.iter().map(|v| (v - e0).abs()).fold(0.0, f64::max);
    let (early, late) = (worst(&e[..window]), worst(&e[e.len() - window..]));
    // Bounded and not growing: the last tenth of the run is no worse than the first.
    assert!(early < 1e-5 * e0.abs(), "early energy error {early:e}");
    assert!(late < 1.5 * early, "energy error grew from {early:e} to {late:e}");
}

#[test]
fn bad_input_is_an_error_with_exit_code_two() {
    let path = lagrange_tests::examples_dir().join("ps5/falling_rod.lag");
    let source = std::fs::read_to_string(path).unwrap();
    for options in [
        Options { set: vec!["thta=1".parse().expect("name=value")], ..Options::default() },
        Options { output: vec!["thta".into()], ..Options::default() },
        Options { method: Some("euler".into()), ..Options::default() },
        Options { set: vec!["y=1".parse().expect("name=value")], ..Options::default() },
    ] {
        let Err(e) = simulate(&source, &options) else {
            panic!("{options:?} should fail");
        };
        let (message, code) = (e.to_string(), e.exit_code());
        assert_eq!(code, 2, "{message}");
        assert!(message.contains("error"), "{message}");
    }
}

#[test]
fn until_in_the_scene_must_be_in_seconds() {
    let scene = "param m = 1 kg, k = 1 N/m\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\npotential k/2*x^2\nsimulate { until UNIT }\n";
    let options = Options::default();
    assert!(simulate(&scene.replace("UNIT", "1 s"), &options).is_ok());
    // `1/s` and `s^2` name s too, but are not times.
    for unit in ["2 1/s", "2 s^2"] {
        let Err(e) = simulate(&scene.replace("UNIT", unit), &options) else {
            panic!("`until {unit}` was taken as a time");
        };
        let (message, code) = (e.to_string(), e.exit_code());
        assert_eq!(code, 2, "{message}");
        assert!(message.contains("`until` is a time, not in"), "{message}");
    }
}

#[test]
fn a_singular_mass_matrix_stops_the_run_with_the_state() {
    // A bead on a wire whose inertia vanishes at s = 0: M = m s², reached from s = 1.
    let source = "param m = 1\ncoord s = 1, s' = -1\nparticle p { mass m; position (s^2/2, 0) }\n";
    let outcome = simulate(source, &Options { until: Some(2.0), ..Options::default() })
        .unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().expect("a fault");
    let text = outcome.describe_fault(fault);
    assert!(text.contains("s = "), "{text}");
    assert!(outcome.run.trajectory.rows.len() > 1, "what was computed is kept");
}

/// `samples` records at that many evenly spaced times, the start and the end included (as
/// numpy.linspace counts them), from the dense output, and those values agree with a run
/// that steps exactly to each of them.
#[test]
fn evenly_spaced_samples_come_from_the_dense_output() {
    let sampled = run(
        "classics/simple_pendulum.lag",
        Options { until: Some(2.0), samples: 41, tolerance: Some(1e-12), ..Options::default() },
    );
    let times = &sampled.run.trajectory.times;
    assert_eq!(times.len(), 41, "{times:?}");
    for (k, t) in times.iter().enumerate() {
        assert!((t - 2.0 * k as f64 / 40.0).abs() < 1e-12, "sample {k} at {t}");
    }
    // θ at t = 1.25 from the dense output, against a run that ends there.
    let direct = run(
        "classics/simple_pendulum.lag",
        Options { until: Some(1.25), tolerance: Some(1e-12), ..Options::default() },
    );
    let theta_direct = direct.run.trajectory.rows.last().expect("rows")[0];
    let theta_sampled = sampled.run.trajectory.rows[25][0];
    assert!((theta_direct - theta_sampled).abs() < 1e-9, "{theta_direct} vs {theta_sampled}");
}

/// The summary says the energy is not conserved whenever T + V need not be: loads that no
/// potential accounts for, or time anywhere, even where the equations of motion do not show
/// it (the spinning rod's r̈ = ω²·r has no t, yet its motor works on the bead).
#[test]
fn the_energy_line_says_when_the_energy_is_not_conserved() {
    let pendulum = "param m = 1, L = 1, g = 9.81\ncoord th = 1/2\ngravity g\n";
    let bob = "particle bob { mass m; position (L*sin(th), -L*cos(th)) }\n";
    let scenes = [
        ("a pendulum", format!("{pendulum}{bob}"), true),
        (
            "a pivot shaken in time",
            format!("{pendulum}particle bob {{ mass m; position (sin(t) + L*sin(th), -L*cos(th)) }}\n"),
            false,
        ),
        (
            "a body turned in time",
            format!("{pendulum}{bob}body wheel {{ mass m; inertia m; position (0, 0); angle th + t }}\n"),
            false,
        ),
        (
            "a potential in time alone",
            format!("{pendulum}{bob}potential m*g*L*sin(t)\n"),
            false,
        ),
        ("dissipation", format!("{pendulum}{bob}dissipation th'^2/10\n"), false),
        ("a force", format!("{pendulum}{bob}force push on bob: (1, 0)\n"), false),
        (
            "a drive eliminated",
            "param m = 1, w = 2\ncoord r = 1\ncoord phi\n\
             particle bead { mass m; position (r*cos(phi), r*sin(phi)) }\n\
             constraint motor: phi = w*t\n"
                .to_string(),
            false,
        ),
    ];
    for (what, source, conserved) in scenes {
        // Units are beside the point here: t stands in angles and lengths as it is.
        let options = Options { until: Some(0.1), no_units: true, ..Options::default() };
        let outcome = simulate(&source, &options).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(outcome.conservative, conserved, "{what}");
        let summary = summary(&outcome);
        assert_eq!(!summary.contains("not conserved"), conserved, "{what}:\n{summary}");
    }
    let spinning = run("classics/bead_on_spinning_rod.lag", Options::default());
    assert!(summary(&spinning).contains("not conserved"), "{}", summary(&spinning));
}

#[test]
fn a_stop_condition_with_abs_and_a_force_that_flips_sign() {
    // V = k·|x| from rest at x0 = 1 m, k/m = 2 m/s²: x = 1 − t² until the bottom, so |x| = ½
    // at t = √½; the period is 4·√(2·m·x0/k) = 4 s, across two jumps of the force.
    let options = |stop: Vec<String>| Options {
        method: Some("dop853".into()),
        tolerance: Some(1e-12),
        until: Some(4.0),
        output: vec!["x".into()],
        stop_when: stop,
        ..Options::default()
    };
    let outcome = run("classics/bead_in_a_v.lag", options(vec!["abs(x) = 1/2".into()]));
    let t = outcome.run.final_time;
    assert!((t - 0.5f64.sqrt()).abs() < 1e-12, "stopped at {t}");
    let outcome = run("classics/bead_in_a_v.lag", options(Vec::new()));
    let x = outcome.run.trajectory.rows.last().expect("rows")[0];
    assert!((outcome.run.final_time - 4.0).abs() < 1e-12 && (x - 1.0).abs() < 1e-8, "x(4) = {x}");
}

/// L = 2*a and I = m*L^2/12 are derived parameters: `--set a=2` moves them, and setting one
/// of them is refused, naming what it follows.
const DERIVED: &str = include_str!("scenes/derived_length_pendulum.lag");

#[test]
fn derived_parameters_follow_set_and_cannot_be_set_themselves() {
    let first = |set: &str| -> f64 {
        let options = Options {
            set: vec![set.parse().expect("name=value")],
            output: vec!["theta''".into()],
            until: Some(1e-3),
            samples: 2,
            ..Options::default()
        };
        let outcome = simulate(DERIVED, &options).unwrap_or_else(|e| panic!("{e}"));
        outcome.run.trajectory.rows[0][0]
    };
    // θ̈ = −3/2·g·sin θ/L for a rod of length L hung from its end, with L = 2a.
    for a in [1.0f64, 2.0, 0.25] {
        let exact = -1.5 * 9.81 * 0.5f64.sin() / (2.0 * a);
        let got = first(&format!("a={a}"));
        assert!((got - exact).abs() < 1e-14 * exact.abs(), "a = {a}: {got} against {exact}");
    }
    // The inverse dynamics at a = 2 needs no torque for the scene's own acceleration there.
    let set = vec!["a=2".parse().expect("name=value")];
    let options = engine::inverse::Options { set, no_units: false };
    let mut inverse = engine::inverse::inverse_dynamics(DERIVED, &options).unwrap();
    assert_eq!(inverse.parameter_names(), ["a", "m", "g"]);
    assert_eq!(inverse.derived_parameter_names(), ["L", "I"]);
    assert_eq!(inverse.derived_parameters(), [4.0, 4.0 / 3.0]);
    let mut tau = [0.0];
    inverse.torques(0.0, &[0.5], &[0.0], &[first("a=2")], &mut tau).unwrap();
    assert!(tau[0].abs() < 1e-13, "{tau:?}");
    inverse.set_parameters(&[1.0, 1.0, 9.81]).unwrap();
    assert_eq!(inverse.derived_parameters(), [2.0, 1.0 / 3.0]);
    // Setting a derived parameter, in a run, a linearization or an ensemble.
    let expected = "parameter `L` is derived from `a`; set `a` instead";
    let set = vec!["L=3".parse().expect("name=value")];
    let e = simulate(DERIVED, &Options { set, ..Options::default() }).err().unwrap();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains(expected), "{e}");
    let options = engine::linearize::Options {
        about: Some("theta=0".into()),
        sweep: Some("L=1:2:3".into()),
        ..Default::default()
    };
    let e = engine::linearize::linearize(DERIVED, &options).err().unwrap();
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains(expected), "{e}");
    let e = engine::inverse::inverse_dynamics(
        DERIVED,
        &engine::inverse::Options { set: vec!["I=3".parse().unwrap()], no_units: false },
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("`I` is derived from `m` and `L`"), "{e}");
}

/// The table as it was written before rows streamed: the whole object built and printed by
/// serde_json, the CSV record by record from the kept rows.
fn tables_the_old_way(outcome: &Outcome) -> (String, String) {
    let shown = outcome.shown;
    let number = |x: f64| {
        serde_json::Number::from_f64(x)
            .map(serde_json::Value::Number)
            .unwrap_or(serde_json::Value::Null)
    };
    let trajectory = &outcome.run.trajectory;
    let rows: Vec<serde_json::Value> = trajectory
        .times
        .iter()
        .zip(&trajectory.rows)
        .map(|(t, r)| {
            let mut v = vec![number(*t)];
            v.extend(r[..shown].iter().map(|x| number(*x)));
            serde_json::Value::Array(v)
        })
        .collect();
    let mut columns = vec!["t".to_string()];
    columns.extend(outcome.columns[..shown].iter().cloned());
    // Events and summary as the streamed writer gives them (read back, their floats could
    // lose a last bit): the rows are what changed.
    let value = serde_json::json!({ "columns": columns, "rows": rows, "events": [] });
    let json = serde_json::to_string_pretty(&value).expect("json");
    let streamed = cli::simulate::json(outcome);
    let tail = &streamed[streamed.rfind("\n  \"events\"").expect("events")..];
    let json =
        json.strip_suffix("\n  \"events\": []\n}").expect("the events last").to_string() + tail;
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record(&columns).expect("memory");
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        let numbers = std::iter::once(t).chain(&row[..shown]);
        csv.write_record(numbers.map(|x| cli::simulate::number(*x))).expect("memory");
    }
    (String::from_utf8(csv.into_inner().expect("memory")).expect("UTF-8"), json)
}

/// Rows handed to a sink as they are made give the bytes that the rows kept gave, for CSV and
/// JSON, with events, stops, kept constraints, a fault and no samples (a row per step).
#[test]
fn a_streamed_table_is_the_table_of_the_kept_rows() {
    let cases: [(&str, Options); 4] = [
        ("classics/simple_pendulum.lag", Options { samples: 50, ..Options::default() }),
        (
            "classics/double_pendulum_flip.lag",
            Options { until: Some(4.0), events: vec!["theta1".into()], ..Options::default() },
        ),
        ("classics/pendulum_cartesian.lag", Options { samples: 40, ..Options::default() }),
        (
            "classics/simple_pendulum.lag",
            Options { set: vec!["L=0".parse().expect("name=value")], ..Options::default() },
        ),
    ];
    for (rel, options) in cases {
        let source =
            std::fs::read_to_string(lagrange_tests::examples_dir().join(rel)).expect("example");
        let kept = simulate(&source, &options).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let (csv, json) = tables_the_old_way(&kept);
        assert_eq!(cli::simulate::csv(&kept), csv, "{rel}");
        assert_eq!(cli::simulate::json(&kept), json, "{rel}");
        for as_json in [false, true] {
            let mut table = cli::simulate::Table::new(as_json, Vec::new());
            let streamed = simulation::simulate_into(&source, &options, &mut (), &mut table)
                .expect("the same run");
            assert!(streamed.run.trajectory.rows.is_empty(), "{rel}: rows kept");
            let bytes = table.finish(&streamed).expect("memory");
            let text = String::from_utf8(bytes).expect("UTF-8");
            assert_eq!(&text, if as_json { &json } else { &csv }, "{rel}");
            assert_eq!(
                summary(&streamed).lines().skip(1).collect::<Vec<_>>(),
                summary(&kept).lines().skip(1).collect::<Vec<_>>(),
                "{rel}"
            );
        }
    }
}
