//! Stiff scenes past what an explicit method can follow: `--method auto` switching from
//! DOP853 to radau on the stiff spring pendulum (and staying on DOP853 where it is not stiff),
//! and the messages of a run that fails on stiffness: rk4 past its stability limit told the
//! mode it could not follow, gauss told what its Newton iteration reached.

use cli::simulate::summary;
use sim::Method;
use simulation::{simulate, Options, Outcome};

fn scene(path: &str) -> String {
    let full = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(full).expect("scene")
}

const STIFF: &str = "../examples/classics/stiff_spring_pendulum.lag";

fn stiff(k: &str, options: Options) -> Outcome {
    let options =
        Options { set: vec![format!("k={k}").parse().expect("an assignment")], ..options };
    simulate(&scene(STIFF), &options).unwrap_or_else(|e| panic!("{e}"))
}

fn method(name: &str) -> Options {
    Options { method: Some(name.into()), ..Options::default() }
}

/// The last recorded (r, θ).
fn last(outcome: &Outcome) -> (f64, f64) {
    let row = outcome.run.trajectory.rows.last().expect("rows");
    (row[0], row[1])
}

#[test]
fn auto_switches_to_radau_on_a_stiff_spring_and_agrees_with_it() {
    for k in ["1e8", "1e12"] {
        let auto = stiff(k, method("auto"));
        assert!(auto.run.fault.is_none(), "{}", summary(&auto));
        let segments: Vec<Method> = auto.run.segments.iter().map(|s| s.method).collect();
        assert_eq!(segments, [Method::Dop853, Method::Radau], "k = {k}: {:?}", auto.run.segments);
        // The switch comes within the spring's first transient, a few of its time scales in.
        assert!(auto.run.segments[0].end < 0.01, "k = {k}: {:?}", auto.run.segments);
        assert!(auto.run.steps < 1000, "k = {k}: {} steps", auto.run.steps);
        let radau = stiff(k, method("radau"));
        let ((r1, t1), (r2, t2)) = (last(&auto), last(&radau));
        assert!(
            (r1 - r2).abs() < 1e-6 && (t1 - t2).abs() < 1e-5,
            "k = {k}: {r1}, {t1} / {r2}, {t2}"
        );
        let text = summary(&auto);
        assert!(text.contains("auto: dop853 0–"), "{text}");
        assert!(text.contains("s, radau ") && text.contains("–10 s (1 switch)"), "{text}");
    }
}

#[test]
fn auto_on_a_scene_that_is_not_stiff_is_dop853_step_for_step() {
    let source = scene("../examples/classics/double_pendulum.lag");
    let auto = simulate(&source, &method("auto")).unwrap_or_else(|e| panic!("{e}"));
    let dop853 = simulate(&source, &method("dop853")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(auto.run.segments.len(), 1, "{:?}", auto.run.segments);
    assert_eq!(auto.run.segments[0].method, Method::Dop853);
    assert_eq!((auto.run.steps, auto.run.jacobians), (dop853.run.steps, 0));
    assert_eq!(auto.run.trajectory.rows, dop853.run.trajectory.rows);
    assert!(summary(&auto).contains("auto: dop853 0–10 s (0 switches)"), "{}", summary(&auto));
}

#[test]
fn auto_keeps_constraints_with_baumgarte_on_both_sides() {
    // The Cartesian pendulum keeps its rod with a multiplier: auto runs the stabilised ODE,
    // whose drift the summary reports as such.
    let source = scene("../examples/classics/pendulum_cartesian.lag");
    let auto = simulate(&source, &method("auto")).unwrap_or_else(|e| panic!("{e}"));
    assert!(auto.run.fault.is_none(), "{}", summary(&auto));
    assert!(summary(&auto).contains("(Baumgarte-stabilised)"), "{}", summary(&auto));
    assert!(auto.constraint_drift().expect("a kept constraint") < 1e-6);
}

#[test]
fn rk4_past_its_stability_limit_is_told_the_mode_it_could_not_follow() {
    let outcome = stiff("1e12", Options { step: Some(1e-3), ..method("rk4") });
    let fault = outcome.run.fault.as_ref().expect("rk4 at 1e-3 s cannot follow k = 1e12");
    let mode = outcome.fastest_mode.as_ref().expect("the fastest mode");
    // ω = √(k/m) = 1e6 at damping ratio 5: λ = −ω·(5 ± √24); the fast one is −9.899e6.
    let fast = -1e6 * (5.0 + 24f64.sqrt());
    assert!((mode.eigenvalue.0 - fast).abs() < 1e-6 * fast.abs(), "{mode:?}");
    assert_eq!(mode.eigenvalue.1, 0.0);
    // All in r (the spring), none in θ.
    assert_eq!(mode.coordinates.len(), 1, "{mode:?}");
    assert_eq!(mode.coordinates[0].0, 0);
    // rk4's stability interval on the negative axis is 2.785.
    assert!((mode.stable_step * fast.abs() - 2.785).abs() < 1e-3, "{mode:?}");
    assert_eq!(mode.step, Some(1e-3));
    let text = outcome.describe_fault(fault);
    for part in [
        "likely cause: the step, past rk4's stability limit",
        "eigenvalue λ ≈ -9.90e6/s (time scale 1.0e-7 s), moving `r` (100%)",
        "rk4 is stable along it for steps up to 2.8e-7 s, and its step was 1.0e-3 s, 3.6e3 times",
        "use --method radau (or auto)",
        "or --step below that limit",
    ] {
        assert!(text.contains(part), "{part:?} not in\n{text}");
    }
    // The report starts with what happened, as every fault's does.
    assert!(text.starts_with("numeric fault at t = "), "{text}");
}

#[test]
fn rk4_within_its_stability_limit_is_not_blamed_on_stiffness() {
    // A bead whose inertia vanishes at s = 0: the fault is the scene's, at any step, and its
    // fastest mode at the start (|λ| ~ 1/s) is far within rk4's stable steps.
    let source = "param m = 1\ncoord s = 1, s' = -1\nparticle p { mass m; position (s^2/2, 0) }\n";
    let options = Options { until: Some(2.0), step: Some(1e-3), ..method("rk4") };
    let outcome = simulate(source, &options).unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().expect("a fault");
    assert_eq!(outcome.fastest_mode, None);
    let text = outcome.describe_fault(fault);
    assert!(text.contains("likely cause: a division by zero"), "{text}");
    assert!(!text.contains("stability limit"), "{text}");
}

#[test]
fn gauss_whose_newton_fails_says_the_step_the_rate_and_the_jacobian() {
    let outcome = stiff("1e12", Options { step: Some(1e-3), ..method("gauss") });
    let fault = outcome.run.fault.as_ref().expect("gauss at 1e-3 s fails on k = 1e12");
    let sim::FaultKind::NewtonFailed { step, contraction, exact_jacobian } = fault.kind else {
        panic!("{fault:?}")
    };
    assert_eq!(step, 1e-3);
    assert!(exact_jacobian);
    assert!(contraction > 0.5, "{contraction}");
    let text = outcome.describe_fault(fault);
    for part in [
        "Newton's iteration of gauss did not converge at its fixed step of 1.0e-3 s",
        "per iteration, with the exact Jacobian at the start of the step",
        "try --step 1e-4 or smaller, or --method radau",
    ] {
        assert!(text.contains(part), "{part:?} not in\n{text}");
    }
}

#[test]
fn the_scenes_simulate_block_may_ask_for_auto() {
    let source = scene(STIFF).replace("tolerance 1e-8;", "tolerance 1e-8; method auto;");
    assert!(source.contains("method auto"), "the scene's simulate block changed");
    let outcome = simulate(&source, &Options::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(outcome.method, Method::Auto);
    assert_eq!(outcome.run.segments.len(), 2, "{:?}", outcome.run.segments);
}
