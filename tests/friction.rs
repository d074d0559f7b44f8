//! Coulomb friction against its hand results: each scene of `examples/friction/` run through
//! the library and held to its closed form (the block on an incline that stops and then sticks
//! or slides back, the disk that slides until it rolls, the disk's landing that grips or slips
//! through), the cone never exceeded while a contact sticks, and Painlevé's rod ending in the
//! named fault in each of its three cases.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use cli::simulate::summary;
use engine::input::Assignment;
use lagrange_tests::column;
use sim::{FaultKind, ModeChange, ModeEvent, PainleveCase};
use simulation::{simulate, Options, Outcome};

fn source(name: &str) -> String {
    let path = lagrange_tests::examples_dir().join("friction").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn set(pairs: &[(&str, f64)]) -> Vec<Assignment> {
    pairs.iter().map(|(n, v)| Assignment { name: (*n).into(), value: v.to_string() }).collect()
}

/// Runs `examples/friction/<name>` at the tolerance 1e-10 with `values` set, recording
/// `output` at every step; it must reach its end without a fault.
fn run(name: &str, values: &[(&str, f64)], output: &str) -> Outcome {
    let outcome =
        simulate(&source(name), &options(values, output)).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(outcome.run.fault.is_none(), "{name}: {}", summary(&outcome));
    outcome
}

fn options(values: &[(&str, f64)], output: &str) -> Options {
    Options {
        tolerance: Some(1e-10),
        set: set(values),
        output: vec![output.into()],
        ..Options::default()
    }
}

fn events(outcome: &Outcome, kind: ModeChange) -> Vec<ModeEvent> {
    outcome.run.modes.iter().filter(|m| m.kind == kind).copied().collect()
}

fn relative(value: f64, exact: f64) -> f64 {
    (value - exact).abs() / exact.abs()
}

/// In every recorded row, the tangential force is within the cone: |λ_T| ≤ μ·λ + 1e-9·λ.
fn assert_within_cone(outcome: &Outcome, contact: &str, mu: f64) {
    let (normal, tangent) =
        (column(outcome, &format!("{contact}.force")), column(outcome, &format!("{contact}.grip")));
    let rows = &outcome.run.trajectory.rows;
    assert!(rows.len() > outcome.run.steps, "every step recorded");
    let mut worst = f64::NEG_INFINITY;
    for (row, t) in rows.iter().zip(&outcome.run.trajectory.times) {
        let excess = row[tangent].abs() - mu * row[normal];
        worst = worst.max(excess / row[normal].abs().max(f64::MIN_POSITIVE));
        assert!(
            excess <= 1e-9 * row[normal].abs(),
            "|{contact}.grip| = {} beyond μ·N = {} at t = {t}",
            row[tangent].abs(),
            mu * row[normal]
        );
    }
    eprintln!("{contact}: |λ_T| − μ·N at most {worst:e} of N");
}

/// The block slides up, stops at v0/(g(sin γ + μ cos γ)) after v0²/(2g(sin γ + μ cos γ)), and
/// then sticks (tan γ ≤ μ) or slides back at g(sin γ − μ cos γ).
#[test]
fn a_block_pushed_up_an_incline_stops_and_sticks_or_slides_back() {
    let (m, g, gamma, v0) = (2.0f64, 9.81f64, std::f64::consts::FRAC_PI_6, 3.0f64);
    for mu in [0.4f64, 0.7] {
        let outcome =
            run("block_on_incline.lag", &[("mu", mu)], "s, s', s'', plane.force, plane.grip");
        let up = g * (gamma.sin() + mu * gamma.cos());
        let (t1, top) = (v0 / up, v0 * v0 / (2.0 * up));
        let sticks = gamma.tan() <= mu;
        let changes = if sticks {
            events(&outcome, ModeChange::Sticks)
        } else {
            events(&outcome, ModeChange::Slips).into_iter().filter(|e| e.time > 0.0).collect()
        };
        assert_eq!(changes.len(), 1, "μ = {mu}: {}", summary(&outcome));
        let error = relative(changes[0].time, t1);
        eprintln!("block, μ = {mu}: stops at {} vs {t1}: {error:e}", changes[0].time);
        assert!(error < 1e-8);
        if !sticks {
            assert_eq!(changes[0].slip, -1.0, "it slides back down");
        }
        let (s, rate, accel, normal, grip) = (
            column(&outcome, "s"),
            column(&outcome, "s'"),
            column(&outcome, "s''"),
            column(&outcome, "plane.force"),
            column(&outcome, "plane.grip"),
        );
        let n = m * g * gamma.cos();
        let trajectory = &outcome.run.trajectory;
        let mut worst = 0.0f64;
        for (row, &t) in trajectory.rows.iter().zip(&trajectory.times) {
            // The closed form on each side of the stop (the rows at the stop are either).
            let exact = if t < t1 {
                [v0 * t - up * t * t / 2.0, v0 - up * t, -up, -mu * n]
            } else if sticks {
                [top, 0.0, 0.0, m * g * gamma.sin()]
            } else {
                let down = g * (gamma.sin() - mu * gamma.cos());
                let dt = t - t1;
                [top - down * dt * dt / 2.0, -down * dt, -down, mu * n]
            };
            if (t - t1).abs() < 1e-9 {
                continue;
            }
            worst = worst
                .max((row[s] - exact[0]).abs() / top)
                .max((row[rate] - exact[1]).abs() / v0)
                .max((row[accel] - exact[2]).abs() / g)
                .max((row[grip] - exact[3]).abs() / n)
                .max(relative(row[normal], n));
        }
        eprintln!("block, μ = {mu}: off the closed form by {worst:e} at most");
        assert!(worst < 1e-8, "μ = {mu}: {worst:e}");
        assert_within_cone(&outcome, "plane", mu);
    }
}

/// Launched without spin, the disk slides until t = v0/(3μg) and rolls on at 2v0/3, having
/// lost m·v0²/6 to friction.
#[test]
fn a_disk_thrown_sliding_rolls_at_two_thirds_of_its_speed() {
    let (m, r, g, mu, v0) = (1.5f64, 0.2f64, 9.81f64, 0.3f64, 4.0f64);
    let outcome = run("sliding_disk.lag", &[], "x', phi', floor.force, floor.grip, KE");
    let rolls = events(&outcome, ModeChange::Sticks);
    assert_eq!(rolls.len(), 1, "{}", summary(&outcome));
    let t1 = v0 / (3.0 * mu * g);
    let error = relative(rolls[0].time, t1);
    eprintln!("disk: rolls at {} vs {t1}: {error:e}", rolls[0].time);
    assert!(error < 1e-8);
    let (rate, spin, grip, kinetic) = (
        column(&outcome, "x'"),
        column(&outcome, "phi'"),
        column(&outcome, "floor.grip"),
        column(&outcome, "KE"),
    );
    let last = outcome.run.trajectory.rows.last().expect("rows");
    let first = &outcome.run.trajectory.rows[0];
    assert!(relative(last[rate], 2.0 * v0 / 3.0) < 1e-8, "{}", last[rate]);
    assert!(relative(last[spin], -2.0 * v0 / (3.0 * r)) < 1e-8, "{}", last[spin]);
    // Rolling on the flat needs no force.
    assert!(last[grip].abs() < 1e-8 * m * g, "{}", last[grip]);
    let lost = first[kinetic] - last[kinetic];
    let error = relative(lost, m * v0 * v0 / 6.0);
    eprintln!("disk: friction took {lost} vs m·v0²/6: {error:e}");
    assert!(error < 1e-8);
    assert_within_cone(&outcome, "floor", mu);
}

/// Dropped from h with v0 along and no spin, the disk's first landing grips if
/// |v0|/3 ≤ μ(1 + e)·√(2gh), leaving it at 2v0/3, and slips through otherwise, leaving it at
/// v0 − μ(1 + e)·√(2gh).
#[test]
fn a_landing_disk_grips_or_slips_through_the_impact() {
    let (g, mu, e, h) = (9.81f64, 0.3f64, 0.5f64, 0.1f64);
    let fall = (2.0 * g * h).sqrt();
    for v0 in [1.0f64, 4.0] {
        let outcome = run(
            "sliding_disk.lag",
            &[("h", h), ("v0", v0), ("e", e)],
            "x', y', phi', floor.force, floor.grip",
        );
        let impacts = events(&outcome, ModeChange::Impact);
        assert!(!impacts.is_empty(), "{}", summary(&outcome));
        let first = impacts[0].time;
        let trajectory = &outcome.run.trajectory;
        let after = trajectory
            .times
            .iter()
            .rposition(|&t| t == first)
            .map(|i| &trajectory.rows[i])
            .expect("the row after the first landing");
        let grips = v0 / 3.0 <= mu * (1.0 + e) * fall;
        let exact = if grips { 2.0 * v0 / 3.0 } else { v0 - mu * (1.0 + e) * fall };
        let (rate, bounce) = (column(&outcome, "x'"), column(&outcome, "y'"));
        let error = relative(after[rate], exact);
        eprintln!("disk landing at {v0}: x'⁺ = {} vs {exact} ({grips}): {error:e}", after[rate]);
        assert!(error < 1e-8);
        assert!(relative(after[bounce], e * fall) < 1e-8, "{}", after[bounce]);
        // The impacts accumulate, and the disk ends rolling.
        assert_eq!(events(&outcome, ModeChange::Settled).len(), 1, "{}", summary(&outcome));
        assert_within_cone(&outcome, "floor", mu);
    }
}

/// The fault a run of Painlevé's rod ends in, with `values` set.
fn painleve(values: &[(&str, f64)]) -> (PainleveCase, f64, Vec<f64>) {
    let outcome = simulate(&source("painleve_rod.lag"), &options(values, "theta"))
        .unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().unwrap_or_else(|| panic!("{}", summary(&outcome)));
    match &fault.kind {
        FaultKind::Painleve { contacts, case, impact } => {
            assert_eq!((contacts.as_slice(), impact), (&[0][..], &false));
            let words = summary(&outcome);
            assert!(words.contains("Painlevé"), "{words}");
            (*case, fault.time, fault.state.clone())
        }
        other => panic!("{other:?}: {}", summary(&outcome)),
    }
}

#[test]
fn painleves_rod_ends_in_the_case_it_meets() {
    // Inside the region (tan θ ∈ (3 − √5, 3 + √5) at μ = 2, slipping toward −x): pressed in,
    // no normal force obeys the laws; lifting (l·θ'²·sin θ > g), two answers do.
    let (case, time, _) = painleve(&[]);
    assert_eq!((case, time), (PainleveCase::Inconsistent, 0.0));
    let (case, time, _) = painleve(&[("theta'", 6.0), ("y'", 1.5), ("v0", -3.0)]);
    assert_eq!((case, time), (PainleveCase::Indeterminate, 0.0));
    // Outside it and turning into it, the normal force grows without bound where it enters.
    let theta0 = 0.6f64;
    let (case, time, state) = painleve(&[
        ("theta0", theta0),
        ("theta'", 4.0),
        ("y'", 0.5 * theta0.cos() * 4.0),
        ("v0", -5.0),
    ]);
    assert_eq!(case, PainleveCase::Jam);
    let edge = (3.0 - 5.0f64.sqrt()).atan();
    let error = (state[2] - edge).abs();
    eprintln!("Painlevé's rod jams at t = {time}, θ − atan(3 − √5) = {error:e}");
    assert!(time > 0.0 && error < 1e-8, "θ = {}", state[2]);
    // Below μ = 4/3 nothing of the kind: the same start slips, sticks or lifts off.
    let outcome = run("painleve_rod.lag", &[("mu", 1.3)], "theta, floor.force");
    assert!(outcome.run.final_time == 0.5);
}

/// The stages that do not take friction yet refuse a rough scene, naming its contact.
#[test]
fn code_generation_refuses_friction_by_name() {
    let source = source("block_on_incline.lag");
    assert!(lagrange_tests::has_friction(&source));
    for error in [
        export::codegen::codegen("block_on_incline.lag", &source).err().map(|e| e.to_string()),
        export::codegen::c("block_on_incline.lag", &source, engine::Options::default())
            .err()
            .map(|e| e.to_string()),
    ] {
        let error = error.expect("refused");
        assert!(error.contains("Coulomb friction") && error.contains("`plane`"), "{error}");
    }
    // `radau` holds its constraints as they are, and takes no friction either.
    let refused =
        simulate(&source, &Options { method: Some("radau".into()), ..Options::default() });
    let error = refused.err().map(|e| e.to_string()).expect("refused");
    assert!(error.contains("does not take Coulomb friction"), "{error}");
}

/// `check` holds every `expect` line of every rough scene.
#[test]
fn check_holds_every_expectation_of_the_rough_scenes() {
    let held = lagrange_tests::check_every_expectation_in("friction");
    assert!(held >= 6, "only {held} expectations held");
}
