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
    painleve_in("painleve_rod.lag", values)
}

/// The fault a run of `scene` (a Painlevé rod) ends in, with `values` set.
fn painleve_in(scene: &str, values: &[(&str, f64)]) -> (PainleveCase, f64, Vec<f64>) {
    let outcome =
        simulate(&source(scene), &options(values, "theta")).unwrap_or_else(|e| panic!("{e}"));
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

/// The same rod as a body in space, its end slipping with the exact cone: started in its
/// vertical plane it meets the planar rod's three cases, the jam where the plane's does.
#[test]
fn painleves_rod_in_space_ends_in_the_same_cases() {
    let scene = "painleve_rod_in_space.lag";
    let (case, time, _) = painleve_in(scene, &[]);
    assert_eq!((case, time), (PainleveCase::Inconsistent, 0.0));
    let (case, time, _) = painleve_in(scene, &[("theta'", 6.0), ("z'", 1.5), ("v0", -3.0)]);
    assert_eq!((case, time), (PainleveCase::Indeterminate, 0.0));
    let theta0 = 0.6f64;
    let (case, time, state) = painleve_in(
        scene,
        &[("theta0", theta0), ("theta'", 4.0), ("z'", 0.5 * theta0.cos() * 4.0), ("v0", -5.0)],
    );
    assert_eq!(case, PainleveCase::Jam);
    // The state is (x, y, z, theta, psi, ...).
    let edge = (3.0 - 5.0f64.sqrt()).atan();
    let error = (state[3] - edge).abs();
    eprintln!("Painlevé's rod in space jams at t = {time}, θ − atan(3 − √5) = {error:e}");
    assert!(time > 0.0 && error < 1e-8, "θ = {}", state[3]);
    assert!(state[1].abs() < 1e-12 && state[4].abs() < 1e-12, "left its plane: {state:?}");
    let outcome = run(scene, &[("mu", 1.3)], "theta, floor.force");
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

/// In space, the tangential force within the exact cone in every recorded row:
/// ‖λ_T‖ ≤ μ·λ + 1e-9·λ, `norm(NAME.grip)` the size of its two components.
fn assert_within_the_cone(outcome: &Outcome, contact: &str, mu: f64) {
    let normal = column(outcome, &format!("{contact}.force"));
    let tangent = column(outcome, &format!("norm({contact}.grip)"));
    let rows = &outcome.run.trajectory.rows;
    assert!(rows.len() > outcome.run.steps, "every step recorded");
    let mut worst = f64::NEG_INFINITY;
    for (row, t) in rows.iter().zip(&outcome.run.trajectory.times) {
        let excess = row[tangent] - mu * row[normal];
        worst = worst.max(excess / row[normal].abs().max(f64::MIN_POSITIVE));
        assert!(
            excess <= 1e-9 * row[normal].abs(),
            "‖λ_T‖ = {} beyond μ·N at t = {t}",
            row[tangent]
        );
    }
    eprintln!("{contact}: ‖λ_T‖ − μ·N at most {worst:e} of N");
}

/// The row recorded last at time `t` (after a jump there).
fn row_after(outcome: &Outcome, t: f64) -> &[f64] {
    let trajectory = &outcome.run.trajectory;
    let i = trajectory.times.iter().rposition(|&s| s == t).expect("a row at the event");
    &trajectory.rows[i]
}

/// A block launched across a floor at (u, v) decelerates at μg against its velocity: a
/// straight line, stopping at |v0|/(μg) after |v0|²/(2μg), and sticking there.
#[test]
fn a_block_launched_in_space_stops_on_a_straight_line_and_sticks() {
    let (g, mu) = (9.81f64, 0.3f64);
    for (u, v) in [(3.0f64, 4.0f64), (-1.0, 0.25), (0.0, -2.0)] {
        let outcome = run(
            "block_in_space.lag",
            &[("u", u), ("v", v)],
            "x, y, x', y', floor.force, norm(floor.grip)",
        );
        let speed = u.hypot(v);
        let stops = events(&outcome, ModeChange::Sticks);
        assert_eq!(stops.len(), 1, "{}", summary(&outcome));
        let t1 = speed / (mu * g);
        let error = relative(stops[0].time, t1);
        eprintln!("block at ({u}, {v}): stops at {} vs {t1}: {error:e}", stops[0].time);
        assert!(error < 1e-8);
        let c = ["x", "y", "x'", "y'", "norm(floor.grip)"].map(|n| column(&outcome, n));
        let (du, dv) = (u / speed, v / speed);
        let reach = speed * speed / (2.0 * mu * g);
        for (row, &t) in outcome.run.trajectory.rows.iter().zip(&outcome.run.trajectory.times) {
            // Before the stop: s(t) = |v0|·t − μg·t²/2 along the launch, at |v0| − μg·t.
            let (along, rate) = if t < stops[0].time {
                (speed * t - mu * g * t * t / 2.0, speed - mu * g * t)
            } else {
                (reach, 0.0)
            };
            let near = |value: f64, exact: f64| (value - exact).abs() <= 1e-8 * speed.max(reach);
            assert!(
                near(row[c[0]], along * du) && near(row[c[1]], along * dv),
                "position at {t}: {row:?}"
            );
            assert!(
                near(row[c[2]], rate * du) && near(row[c[3]], rate * dv),
                "rates at {t}: {row:?}"
            );
        }
        // Stuck on the flat, nothing holds it.
        let last = outcome.run.trajectory.rows.last().expect("rows");
        assert!(last[c[4]] < 1e-9 * 2.0 * g, "{}", last[c[4]]);
        assert_within_the_cone(&outcome, "floor", mu);
    }
}

/// Pushed from rest by F at the angle φ, the block stays put while F < μmg, held by F; beyond
/// it, it slips from rest along the push at (F − μmg)/m, the direction found on the circle.
#[test]
fn a_block_pushed_from_rest_in_space_sticks_or_slips_along_the_push() {
    let (m, g, mu, phi) = (2.0f64, 9.81f64, 0.3f64, 0.7f64);
    for push in [5.0f64, 8.0] {
        let values = [("u", 0.0), ("v", 0.0), ("F", push), ("phi", phi)];
        let outcome = run("block_in_space.lag", &values, "x, y, floor.force, norm(floor.grip)");
        let slips = push > mu * m * g;
        let kind = if slips { ModeChange::Slips } else { ModeChange::Sticks };
        let decided = events(&outcome, kind);
        assert_eq!(decided.len(), 1, "{}", summary(&outcome));
        assert_eq!(decided[0].time, 0.0);
        let c = ["x", "y", "norm(floor.grip)"].map(|n| column(&outcome, n));
        let a = if slips { (push - mu * m * g) / m } else { 0.0 };
        let friction = if slips { mu * m * g } else { push };
        for (row, &t) in outcome.run.trajectory.rows.iter().zip(&outcome.run.trajectory.times) {
            let along = a * t * t / 2.0;
            let scale = along.max(1.0);
            assert!((row[c[0]] - along * phi.cos()).abs() <= 1e-8 * scale, "x at {t}: {row:?}");
            assert!((row[c[1]] - along * phi.sin()).abs() <= 1e-8 * scale, "y at {t}: {row:?}");
            assert!(relative(row[c[2]], friction) < 1e-9, "‖λ_T‖ at {t}: {row:?}");
        }
        eprintln!("block pushed by {push}: {}", if slips { "slips" } else { "sticks" });
        assert_within_the_cone(&outcome, "floor", mu);
    }
}

/// A sphere launched sliding without spin slides on a straight line until
/// t = 2|v0|/(7μg), and rolls on at 5v0/7, spinning at |v|/r: written with two spin rates,
/// and as a body in space.
#[test]
fn a_sphere_launched_sliding_rolls_at_five_sevenths_of_its_speed() {
    let (r, g, mu) = (0.0286f64, 9.81f64, 0.2f64);
    // The sphere with two spin rates, then as a body in space oriented by Euler parameters.
    for (scene, (u, v)) in [
        ("sliding_sphere.lag", (2.0f64, -1.0f64)),
        ("sliding_sphere.lag", (-0.5, 3.0)),
        ("sliding_ball.lag", (2.0, -1.0)),
        ("sliding_ball.lag", (0.3, 1.1)),
    ] {
        let spins = scene == "sliding_sphere.lag";
        let recorded = if spins {
            "x', y', a', b', floor.force, norm(floor.grip)"
        } else {
            "x', y', floor.force, norm(floor.grip)"
        };
        let outcome = run(scene, &[("u", u), ("v", v)], recorded);
        let speed = u.hypot(v);
        let rolls = events(&outcome, ModeChange::Sticks);
        assert_eq!(rolls.len(), 1, "{}", summary(&outcome));
        let t1 = 2.0 * speed / (7.0 * mu * g);
        let error = relative(rolls[0].time, t1);
        eprintln!("{scene} at ({u}, {v}): rolls at {} vs {t1}: {error:e}", rolls[0].time);
        assert!(error < 1e-8);
        let c = ["x'", "y'"].map(|n| column(&outcome, n));
        for (row, &t) in outcome.run.trajectory.rows.iter().zip(&outcome.run.trajectory.times) {
            // Along the launch: the centre's speed |v0| − μg·t until it rolls, then 5|v0|/7.
            let rate = if t < rolls[0].time { speed - mu * g * t } else { 5.0 * speed / 7.0 };
            let near = |value: f64, exact: f64| (value - exact).abs() <= 1e-8 * speed;
            assert!(
                near(row[c[0]], rate * u / speed) && near(row[c[1]], rate * v / speed),
                "at {t}: {row:?}"
            );
        }
        let last = outcome.run.trajectory.rows.last().expect("rows");
        assert!(relative(last[c[0]], 5.0 * u / 7.0) < 1e-8, "{}", last[c[0]]);
        assert!(relative(last[c[1]], 5.0 * v / 7.0) < 1e-8, "{}", last[c[1]]);
        if spins {
            // Rolling: the contact point at rest, x' = r·a' and y' = −r·b'.
            let (a, b) = (column(&outcome, "a'"), column(&outcome, "b'"));
            assert!((last[c[0]] - r * last[a]).abs() < 1e-9 * speed);
            assert!((last[c[1]] + r * last[b]).abs() < 1e-9 * speed);
        }
        assert_within_the_cone(&outcome, "floor", mu);
    }
}

/// Dropped from h at (u, v) without spin, the sphere's first landing grips if
/// 2|v0|/7 ≤ μ(1 + e)·√(2gh), leaving it at 5v0/7, and otherwise slips through along v0,
/// leaving it at v0 − μ(1 + e)·√(2gh)·v0/|v0|.
#[test]
fn a_landing_sphere_grips_or_slips_through_the_impact_in_space() {
    let (g, mu, e, h) = (9.81f64, 0.2f64, 0.5f64, 0.1f64);
    let fall = (2.0 * g * h).sqrt();
    for (u, v) in [(0.6f64, -0.8f64), (2.0, -1.0)] {
        let values = [("h", h), ("e", e), ("u", u), ("v", v)];
        let outcome = run("sliding_sphere.lag", &values, "x', y', floor.force, norm(floor.grip)");
        let impacts = events(&outcome, ModeChange::Impact);
        assert!(!impacts.is_empty(), "{}", summary(&outcome));
        let after = row_after(&outcome, impacts[0].time);
        let speed = u.hypot(v);
        let grips = 2.0 * speed / 7.0 <= mu * (1.0 + e) * fall;
        let left = if grips { 5.0 * speed / 7.0 } else { speed - mu * (1.0 + e) * fall };
        let (x, y) = (column(&outcome, "x'"), column(&outcome, "y'"));
        let error = relative(after[x], left * u / speed).max(relative(after[y], left * v / speed));
        eprintln!(
            "sphere landing at ({u}, {v}): ({}, {}) ({grips}): {error:e}",
            after[x], after[y]
        );
        assert!(error < 1e-8);
        assert_eq!(events(&outcome, ModeChange::Settled).len(), 1, "{}", summary(&outcome));
        assert_within_the_cone(&outcome, "floor", mu);
    }
}

/// While a contact slips in space its friction's direction γ_T/‖γ_T‖ moves with the state: the
/// exact Jacobian carries that turn (∂(direction)/∂(q, q̇)), and agrees with central
/// differences of the right-hand side, which re-aim the friction at each state.
#[test]
fn the_exact_jacobian_turns_with_a_slip_in_space() {
    use sim::Problem;
    let mut prepared =
        engine::numbers::prepare(&source("sliding_sphere.lag"), &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("{e}"));
    let values = prepared.parameter_values(&[]).expect("parameters");
    let slots = prepared.contacts.clone();
    let mu = 0.2;
    let contacts = slots
        .iter()
        .map(|s| sim::Contact {
            normal: s.normal,
            grip: s.grip,
            cross: s.cross,
            restitution: 0.0,
            friction: Some(mu),
        })
        .collect();
    let mut problem = lagrange_tests::mechanical(&mut prepared, &values).with_contacts(contacts);
    let r = 0.0286;
    // Sliding with spin: (x, y, z, a, b) and rates, the contact point slipping both ways.
    let mut y = vec![0.1, -0.2, r, 0.3, -0.4, 1.3, -0.7, 0.0, 11.0, 9.0];
    let events = problem.begin_modes(0.0, &mut y, 1e-10).expect("begins");
    assert!(events.iter().any(|e| e.kind == ModeChange::Slips), "{events:?}");
    let d = y.len();
    let mut exact = vec![0.0; d * d];
    assert!(problem.jacobian(0.0, &y, &mut exact).expect("a Jacobian"));
    let mut worst = 0.0f64;
    let mut turning = 0.0f64;
    for k in 0..d {
        let h = 1e-5 * y[k].abs().max(1.0);
        let mut at = |shift: f64| {
            let mut state = y.clone();
            state[k] += shift;
            let mut rates = vec![0.0; d];
            problem.rhs(0.0, &state, &mut rates).expect("rhs");
            rates
        };
        let (plus, minus, plus2, minus2) = (at(h), at(-h), at(h / 2.0), at(-h / 2.0));
        for i in 0..d {
            let wide = (plus[i] - minus[i]) / (2.0 * h);
            let narrow = (plus2[i] - minus2[i]) / h;
            let differenced = (4.0 * narrow - wide) / 3.0;
            worst = worst.max((exact[i * d + k] - differenced).abs());
            // The horizontal accelerations' dependence on the rates: the turn itself.
            if k >= d / 2 && (i == d / 2 || i == d / 2 + 1) && k != d / 2 + 2 {
                turning = turning.max(differenced.abs());
            }
        }
    }
    eprintln!("sphere slipping: exact Jacobian off differences by {worst:e}, turn {turning:e}");
    assert!(turning > 1e-2, "the slip's direction does not turn with the rates here");
    assert!(worst < 1e-7, "{worst:e}");
}

/// Launched across an incline with tan α = μ, the block's velocity turns downhill with v + s'
/// held at v0 in every row, and it ends sliding straight down at v0/2: the slip's direction
/// turns by a right angle, and the run re-aims its guard on the way without an event.
#[test]
fn a_block_across_an_incline_at_the_angle_of_friction_ends_at_half_its_speed() {
    let (v0, alpha) = (2.0f64, std::f64::consts::PI / 9.0);
    let outcome = run("incline_in_space.lag", &[], "w', s', plane.force, norm(plane.grip)");
    assert_eq!(events(&outcome, ModeChange::Slips).len(), 1, "{}", summary(&outcome));
    assert!(events(&outcome, ModeChange::Sticks).is_empty(), "{}", summary(&outcome));
    let c = ["w'", "s'", "plane.force", "norm(plane.grip)"].map(|n| column(&outcome, n));
    let mut worst = 0.0f64;
    for (row, &t) in outcome.run.trajectory.rows.iter().zip(&outcome.run.trajectory.times) {
        let speed = (row[c[0]] * row[c[0]] + row[c[1]] * row[c[1]]).sqrt();
        worst = worst.max((speed + row[c[1]] - v0).abs() / v0);
        assert!((speed + row[c[1]] - v0).abs() <= 1e-8 * v0, "v + s' at {t}: {row:?}");
        // Slipping throughout: the force on the cone's edge.
        assert!(relative(row[c[3]], alpha.tan() * row[c[2]]) < 1e-9, "at {t}: {row:?}");
    }
    let last = outcome.run.trajectory.rows.last().expect("rows");
    eprintln!("incline: v + s' off v0 by {worst:e}; ends at s' = {}", last[c[1]]);
    assert!(relative(last[c[1]], v0 / 2.0) < 1e-8 && last[c[0]].abs() < 1e-8 * v0);
    // The jump where its guard was re-aimed, recorded without a mode change.
    let times = &outcome.run.trajectory.times;
    assert!(times.windows(2).any(|w| w[0] == w[1]), "no jump re-aimed the slip's guard");
    assert_within_the_cone(&outcome, "plane", alpha.tan());
}
