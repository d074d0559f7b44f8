//! `--method radau` on scenes: a pendulum hung from a spring stiff up to k = 1e12 N/m in a few
//! hundred steps where an explicit method needs millions, stops and events on its dense
//! output, and constraints kept with multipliers integrated as the index-3 system itself (the
//! Cartesian pendulum against the pendulum in its angle, the Chaplygin sleigh's blade at index
//! 2), with no Baumgarte stabilisation; Andrews' squeezer under radau is in tests/andrews.rs.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use bench::reference::elliptic_k;
use cli::simulate::summary;
use simulation::{simulate, Options, Outcome};

fn scene(path: &str) -> String {
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(full).expect("scene")
}

fn run(source: &str, options: Options) -> Outcome {
    let outcome = simulate(source, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{}", summary(&outcome));
    outcome
}

fn radau(options: Options) -> Options {
    Options { method: Some("radau".into()), ..options }
}

const STIFF: &str = "../examples/classics/stiff_spring_pendulum.lag";

fn stiff(k: &str, method: &str) -> Outcome {
    let options = Options {
        method: Some(method.into()),
        set: vec![format!("k={k}").parse().expect("name=value")],
        ..Options::default()
    };
    run(&scene(STIFF), options)
}

/// The last recorded (r, θ).
fn last(outcome: &Outcome) -> (f64, f64) {
    let row = outcome.run.trajectory.rows.last().expect("rows");
    (row[0], row[1])
}

#[test]
fn a_stiff_spring_costs_radau_the_same_few_hundred_steps_at_any_stiffness() {
    // The scene's block: to t = 10 s at tolerance 1e-8, damping ratio 5, from 60°.
    let mut steps = Vec::new();
    for k in ["1e4", "1e8", "1e12"] {
        let outcome = stiff(k, "radau");
        assert_eq!(outcome.run.final_time, 10.0);
        let r = &outcome.run;
        assert!(r.steps < 1000, "k = {k}: {}", summary(&outcome));
        // The spring barely stretches: by m·g/k along the rope, and the swing's pull.
        let (rope, _) = last(&outcome);
        let k: f64 = k.parse().expect("number");
        assert!((rope - 1.0).abs() < 30.0 / k, "r = {rope} at k = {k:e}");
        assert!(r.jacobians > 0 && r.factorizations >= r.jacobians);
        steps.push(r.steps);
    }
    let (least, most) = (steps.iter().min().expect("runs"), steps.iter().max().expect("runs"));
    assert!(*most <= 2 * least, "steps {steps:?}");
}

#[test]
fn radau_and_dop853_agree_on_the_stiff_pendulum_where_dop853_can_still_run() {
    // At k = 1e6 dop853 takes some 15 000 steps, bound by the spring's fastest mode.
    let (explicit, implicit) = (stiff("1e6", "dop853"), stiff("1e6", "radau"));
    assert!(explicit.run.stiff_steps * 2 > explicit.run.steps, "{}", summary(&explicit));
    assert!(implicit.run.steps * 20 < explicit.run.steps, "{}", summary(&implicit));
    let ((r1, theta1), (r2, theta2)) = (last(&explicit), last(&implicit));
    // Ten seconds of swinging at tolerance 1e-8: the phase agrees to the tolerance's order.
    assert!((theta1 - theta2).abs() < 5e-7, "θ(10): dop853 {theta1}, radau {theta2}");
    assert!((r1 - r2).abs() < 1e-9, "r(10): dop853 {r1}, radau {r2}");
}

#[test]
fn stops_and_events_fall_where_dop853_puts_them() {
    // The simple pendulum from θ = 1/2: θ' vanishes at half a period; θ crosses zero at a
    // quarter and three quarters.
    let source = lagrange_tests::example("classics/simple_pendulum.lag");
    let options = Options {
        tolerance: Some(1e-12),
        until: Some(3.0),
        stop_when: vec!["theta'".into()],
        events: vec!["theta".into()],
        ..Options::default()
    };
    let outcome = run(&source, radau(options));
    let half = outcome.run.final_time;
    let exact = 4.0 * (1.0f64 / 9.81).sqrt() * elliptic_k(0.25f64.sin());
    assert!((2.0 * half - exact).abs() < 1e-9 * exact, "period {} vs {exact}", 2.0 * half);
    assert_eq!(outcome.run.stopped_by, Some(0));
    let crossings: Vec<f64> =
        outcome.run.events.iter().filter(|e| e.event == 1).map(|e| e.time).collect();
    assert_eq!(crossings.len(), 1, "{:?}", outcome.run.events);
    assert!((crossings[0] - exact / 4.0).abs() < 1e-9, "{} vs {}", crossings[0], exact / 4.0);
}

/// The Cartesian pendulum released from 60°, and the same pendulum in its angle.
fn pendulums(until: f64) -> (Outcome, Outcome) {
    let cartesian = lagrange_tests::example("classics/pendulum_cartesian.lag");
    let options = Options {
        until: Some(until),
        tolerance: Some(1e-10),
        output: vec!["x, y, KE + PE".into()],
        set: vec![
            "x=L*sin(pi/3)".parse().expect("name=value"),
            "y=-L*cos(pi/3)".parse().expect("name=value"),
        ],
        events: vec!["x".into()],
        samples: 0,
        ..Options::default()
    };
    let kept = run(&cartesian, radau(options));
    let angle = lagrange_tests::example("classics/simple_pendulum.lag");
    let options = Options {
        until: Some(until),
        tolerance: Some(1e-12),
        output: vec!["L*sin(theta), -L*cos(theta), KE + PE".into()],
        set: vec!["theta=pi/3".parse().expect("name=value")],
        ..Options::default()
    };
    (kept, run(&angle, options))
}

#[test]
fn a_pendulum_kept_by_its_rod_holds_it_without_baumgarte_and_swings_as_in_its_angle() {
    let (kept, angle) = pendulums(10.0);
    let drift = kept.constraint_drift().expect("one kept constraint");
    assert!(drift <= 1e-9, "{}", summary(&kept));
    let text = summary(&kept);
    assert!(text.contains("no stabilisation") && text.contains("Jacobians"), "{text}");
    // The energy: the velocities are index-2 components, held to the tolerance times h⁻¹.
    let (energy, relative) = kept.energy_drift();
    assert!(relative < 1e-6, "energy drift {energy:e} ({relative:e})");
    // The period from x's zero crossings (two a period), against the elliptic integral.
    let crossings: Vec<f64> = kept.run.events.iter().map(|e| e.time).collect();
    assert!(crossings.len() >= 6, "{crossings:?}");
    let period = crossings[4] - crossings[2];
    let exact = 4.0 * (1.0f64 / 9.81).sqrt() * elliptic_k((std::f64::consts::FRAC_PI_6).sin());
    assert!((period - exact).abs() < 1e-8 * exact, "period {period} vs {exact}");
    // Where the two are at t = 10.
    let (a, b) = (last_row(&kept), last_row(&angle));
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < 1e-6, "column {k}: kept {a:?}, angle {b:?}");
    }
}

fn last_row(outcome: &Outcome) -> Vec<f64> {
    outcome.run.trajectory.rows.last().expect("rows")[..3].to_vec()
}

#[test]
fn a_velocity_constraint_is_held_as_the_index_two_system() {
    // The Chaplygin sleigh's blade, a velocity constraint: no position level, index 2.
    let source = lagrange_tests::example("classics/chaplygin_sleigh.lag");
    let options = Options { tolerance: Some(1e-10), samples: 2, ..Options::default() };
    let kept = run(&source, radau(options.clone()));
    let stabilised = run(&source, options);
    let drift = kept.constraint_drift_at_steps().expect("the blade");
    assert!(drift < 1e-11, "{}", summary(&kept));
    // At the steps of each: dop853's are where Baumgarte's terms have had least time to pull
    // the blade back.
    let baumgarte = stabilised.constraint_drift_at_steps().expect("the blade");
    assert!(drift * 100.0 < baumgarte, "{drift:e} against {baumgarte:e}");
    let (a, b) = (last_row(&kept), last_row(&stabilised));
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < 1e-8, "column {k}: radau {a:?}, dop853 {b:?}");
    }
}
