//! One-sided contacts against their hand results: each scene of `examples/contacts/` run through
//! the library and held to its closed form (the ball's impact times and accumulation, the rod's
//! landing, the ladder and the bead leaving their surfaces, Housner's rocking ratio, McGeer's
//! steady gait, the cradle's rates), no reaction pulling in any recorded row, `check` on every
//! expectation, the contact sections of `derive`, and the methods that take contacts or refuse.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_6, FRAC_PI_8};

use cli::simulate::summary;
use lagrange_tests::column;
use sim::{ModeChange, ModeEvent};
use simulation::{simulate, Options, Outcome};

fn source(name: &str) -> String {
    let path = lagrange_tests::examples_dir().join("contacts").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs `examples/contacts/<name>` with `options` (every step recorded, as `samples` is 0),
/// which must reach its end without a fault.
fn run(name: &str, options: Options) -> Outcome {
    let outcome = simulate(&source(name), &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(outcome.run.fault.is_none(), "{name}: {}", summary(&outcome));
    outcome
}

/// The index of the contact named `name`, as the mode events give it.
fn contact(outcome: &Outcome, name: &str) -> usize {
    outcome.contact_names.iter().position(|c| c == name).expect("a contact of the scene")
}

/// The mode events of `kind`, in time order.
fn events(outcome: &Outcome, kind: ModeChange) -> Vec<ModeEvent> {
    outcome.run.modes.iter().filter(|m| m.kind == kind).copied().collect()
}

/// The rows recorded just before and just after the jump at `time`: the two rows at that time.
fn jump(outcome: &Outcome, time: f64) -> (&[f64], &[f64]) {
    let trajectory = &outcome.run.trajectory;
    let at: Vec<usize> =
        (0..trajectory.times.len()).filter(|&i| trajectory.times[i] == time).collect();
    assert_eq!(at.len(), 2, "the rows at the jump at t = {time}: {at:?}");
    assert_eq!(at[1], at[0] + 1);
    (&trajectory.rows[at[0]], &trajectory.rows[at[1]])
}

/// The rows recorded after `time` (the row after a jump at `time` included, as it is the
/// second at that time).
fn rows_after(outcome: &Outcome, time: f64) -> Vec<&[f64]> {
    let trajectory = &outcome.run.trajectory;
    let first = trajectory.times.iter().position(|&t| t >= time).expect("rows after");
    let skip = usize::from(trajectory.times.get(first + 1) == Some(&time));
    trajectory.rows[first + skip..].iter().map(|r| r.as_slice()).collect()
}

/// Every contact's reaction is recorded, and none pulls below −1e-9 of `scale` in any row.
fn assert_never_pulls(outcome: &Outcome, scale: f64) {
    let forces: Vec<usize> = outcome
        .contact_names
        .iter()
        .map(|name| column(outcome, &format!("{name}.force")))
        .collect();
    assert!(!forces.is_empty());
    let rows = &outcome.run.trajectory.rows;
    assert!(rows.len() > outcome.run.steps, "every step recorded: {} rows", rows.len());
    let mut least = f64::INFINITY;
    for (row, t) in rows.iter().zip(&outcome.run.trajectory.times) {
        for &c in &forces {
            least = least.min(row[c]);
            assert!(
                row[c] >= -1e-9 * scale,
                "{} = {} pulls at t = {t}",
                outcome.columns[c],
                row[c]
            );
        }
    }
    eprintln!("least reaction {least:e} ({:e} of the scale)", least / scale);
}

fn relative(value: f64, exact: f64) -> f64 {
    (value - exact).abs() / exact.abs()
}

#[test]
fn bouncing_ball_impacts_accumulate_where_the_geometric_series_says() {
    let (m, g, h0, e) = (0.5f64, 9.81f64, 1.0f64, 0.8f64);
    let outcome = run(
        "bouncing_ball.lag",
        Options { output: vec!["y, y', floor.force".into()], ..Options::default() },
    );
    let t1 = (2.0 * h0 / g).sqrt();
    let impacts = events(&outcome, ModeChange::Impact);
    assert!(impacts.len() >= 20, "{}", summary(&outcome));
    let mut worst = 0.0f64;
    for (k, impact) in impacts.iter().take(20).enumerate() {
        // Impact k + 1 is at t1·(1 + 2(e + … + e^k)).
        let exact = t1 * (1.0 + 2.0 * (1..=k).map(|j| e.powi(j as i32)).sum::<f64>());
        let error = relative(impact.time, exact);
        worst = worst.max(error);
        assert!(error < 1e-8, "impact {} at {} vs {exact}: {error:e}", k + 1, impact.time);
    }
    eprintln!("ball: worst of the first 20 impact times {worst:e} relative");

    let settled = events(&outcome, ModeChange::Settled);
    assert_eq!(settled.len(), 1, "{}", summary(&outcome));
    let accumulation = t1 * (1.0 + e) / (1.0 - e);
    let error = relative(settled[0].time, accumulation);
    eprintln!("ball: settled at {} vs {accumulation}: {error:e} relative", settled[0].time);
    assert!(error < 1e-8, "settled at {} vs {accumulation}: {error:e}", settled[0].time);
    // Nothing happens after it.
    assert_eq!(outcome.run.modes.last(), settled.last());

    // At rest on the floor from then on, pressed by its weight, to the run's end.
    let (y, rate, force) =
        (column(&outcome, "y"), column(&outcome, "y'"), column(&outcome, "floor.force"));
    let after = rows_after(&outcome, settled[0].time);
    assert!(!after.is_empty());
    let mut worst = 0.0f64;
    for row in &after {
        worst = worst.max(relative(row[force], m * g));
        assert!(row[y].abs() < 1e-9 * h0 && row[rate].abs() < 1e-9 * (g * h0).sqrt(), "{row:?}");
    }
    eprintln!("ball: reaction after settling off m·g by {worst:e} relative");
    assert!(worst < 1e-9);
    assert_eq!(outcome.run.final_time, 5.0);
    // The impacts took all of the energy the drop gave.
    let removed = relative(-outcome.totals.energy_jumps(), m * g * h0);
    assert!(removed < 1e-9, "{removed:e}");
    // The integration restarts at each of about a hundred impacts, but takes no more steps
    // than that calls for.
    let steps = outcome.run.steps;
    assert!((100..1000).contains(&steps), "{steps} steps");
    assert_never_pulls(&outcome, m * g);
}

/// The rod of problem set 5 carried through its landing: the start's results, the landing
/// flat, and the rod's whole kinetic energy taken by the plastic impact.
#[test]
fn falling_rod_lands_flat_and_loses_its_kinetic_energy() {
    let (m, l, g) = (1.0f64, 1.0f64, 9.81f64);
    let tolerance = 1e-12;
    let outcome = run(
        "falling_rod_landing.lag",
        Options {
            tolerance: Some(tolerance),
            output: vec!["theta, theta'', x', y', theta', end_b.force, end_a.force".into()],
            ..Options::default()
        },
    );
    let (theta, accel, n) =
        (column(&outcome, "theta"), column(&outcome, "theta''"), column(&outcome, "end_b.force"));
    let first = &outcome.run.trajectory.rows[0];
    let (n0, a0) =
        (relative(first[n], 4.0 / 7.0 * m * g), relative(first[accel], 12.0 / 7.0 * g / l));
    eprintln!("rod: N(0) {n0:e}, θ''(0) {a0:e} relative");
    assert!(n0 < 1e-12 && a0 < 1e-12, "N(0) = {}, θ''(0) = {}", first[n], first[accel]);

    let impacts = events(&outcome, ModeChange::Impact);
    assert_eq!(impacts.len(), 1, "{}", summary(&outcome));
    let landing = impacts[0];
    assert_eq!(landing.contact, contact(&outcome, "end_a"));
    let (before, after) = jump(&outcome, landing.time);
    let flat = (before[theta] - FRAC_PI_2).abs();
    eprintln!("rod: lands at θ − π/2 = {flat:e}");
    assert!(flat < 1e-8, "lands at θ = {}", before[theta]);

    // The energy the landing removed (end A's impact, and end B's share as it is struck).
    let removed: f64 = -outcome
        .run
        .modes
        .iter()
        .filter(|e| e.time == landing.time)
        .map(|e| e.energy_change)
        .sum::<f64>();
    let exact = m * g * l / 2.0 * FRAC_PI_6.cos();
    let error = relative(removed, exact);
    eprintln!("rod: energy removed {removed} vs {exact}: {error:e} relative");
    assert!(error < 1e-8);
    assert!(relative(-outcome.totals.energy_jumps(), exact) < 1e-8);

    // At rest after it, flat on the floor.
    let rates = [column(&outcome, "x'"), column(&outcome, "y'"), column(&outcome, "theta'")];
    let scale = [(g * l).sqrt(), (g * l).sqrt(), (g / l).sqrt()];
    let mut worst = 0.0f64;
    for row in std::iter::once(after).chain(rows_after(&outcome, landing.time)) {
        for (&c, s) in rates.iter().zip(scale) {
            worst = worst.max(row[c].abs() / s);
        }
        assert!((row[theta] - FRAC_PI_2).abs() < 1e-8, "{row:?}");
    }
    eprintln!("rod: largest rate after landing {worst:e} of its scale");
    assert!(worst < 1e-8);
    // Lying flat, each end carries half its weight.
    let (b, a) = (column(&outcome, "end_b.force"), column(&outcome, "end_a.force"));
    let mut worst = 0.0f64;
    for row in rows_after(&outcome, landing.time) {
        worst = worst.max(relative(row[b], m * g / 2.0)).max(relative(row[a], m * g / 2.0));
    }
    eprintln!("rod: the ends' reactions after landing off m·g/2 by {worst:e}");
    assert!(worst < 1e-8);
    assert!(outcome.run.final_time == 1.0);
    assert_never_pulls(&outcome, m * g);

    // The problem set's scene, whose run stops at θ = π/2, lands at the same time.
    let path = lagrange_tests::examples_dir().join("ps5/falling_rod.lag");
    let ps5 = std::fs::read_to_string(path).expect("ps5");
    let stopped = simulate(&ps5, &Options { tolerance: Some(tolerance), ..Options::default() })
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(stopped.run.stopped_by.is_some(), "{}", summary(&stopped));
    let error = relative(landing.time, stopped.run.final_time);
    eprintln!("rod: lands at {} vs ps5's {}: {error:e}", landing.time, stopped.run.final_time);
    assert!(error < 1e-8);
}

#[test]
fn ladder_leaves_the_wall_at_two_thirds_of_its_starting_height() {
    let (m, l, g, theta0) = (10.0f64, 4.0f64, 9.81f64, FRAC_PI_6);
    let outcome = run(
        "ladder.lag",
        Options { output: vec!["theta, x', wall.force, floor.force".into()], ..Options::default() },
    );
    let lift = events(&outcome, ModeChange::LiftOff);
    assert_eq!(lift.len(), 1, "{}", summary(&outcome));
    assert_eq!(lift[0].contact, contact(&outcome, "wall"));
    let (theta, rate, wall) =
        (column(&outcome, "theta"), column(&outcome, "x'"), column(&outcome, "wall.force"));
    let (before, after) = jump(&outcome, lift[0].time);
    let error = (before[theta].cos() - 2.0 / 3.0 * theta0.cos()).abs();
    eprintln!("ladder: cos θ at lift-off off by {error:e}");
    assert!(error < 1e-8, "leaves at θ = {}", before[theta]);
    // There θ'² = 3g/L·(cos θ0 − cos θ) = g/L·cos θ0, and x' = L/2·cos θ·θ'.
    let exact = l / 3.0 * theta0.cos() * (g / l * theta0.cos()).sqrt();
    let error = relative(after[rate], exact);
    eprintln!("ladder: x' at lift-off {} vs {exact}: {error:e}", after[rate]);
    assert!(error < 1e-8);
    let mut worst = 0.0f64;
    for row in rows_after(&outcome, lift[0].time) {
        worst = worst.max(relative(row[rate], after[rate]));
        assert_eq!(row[wall], 0.0, "{row:?}");
    }
    eprintln!("ladder: x' after lift-off varies by {worst:e} relative");
    assert!(worst < 1e-8);
    assert!(outcome.run.final_time == 1.2);
    assert_never_pulls(&outcome, m * g);
}

/// Housner's ratio at every impact until the block comes to rest: its impacts accumulate
/// (at about 2.011 s), and the last, at a rate about 10⁻⁶ of the first, is the one whose
/// separating corner stays closed (its flight would be rounding), leaving the block at rest.
#[test]
fn rocking_block_loses_housners_ratio_at_each_impact_until_it_rests() {
    let (m, g, b, h, theta0) = (1.0f64, 9.81f64, 0.1f64, 0.3f64, 0.1f64);
    let outcome = run(
        "rocking_block.lag",
        Options {
            until: Some(3.0),
            output: vec!["theta, theta', left.force, right.force".into()],
            ..Options::default()
        },
    );
    let ratio = 1.0 - 1.5 * (b / h).atan().sin().powi(2);
    let (theta, rate) = (column(&outcome, "theta"), column(&outcome, "theta'"));
    let (left, right) = (column(&outcome, "left.force"), column(&outcome, "right.force"));
    let impacts = events(&outcome, ModeChange::Impact);
    assert!(impacts.len() >= 20, "{}", summary(&outcome));
    let (rest, rocking) = impacts.split_last().expect("impacts");
    let mut worst = 0.0f64;
    for impact in rocking {
        let (before, after) = jump(&outcome, impact.time);
        let error = relative(after[rate] / before[rate], ratio);
        worst = worst.max(error);
        assert!(error < 1e-8, "at t = {}: {} → {}", impact.time, before[rate], after[rate]);
    }
    eprintln!("rocking block: {} impacts, worst ratio {worst:e} relative", rocking.len());

    // The last lands both corners, far slower than the first, and the block stays at rest.
    let (first, _) = jump(&outcome, impacts[0].time);
    let (before, _) = jump(&outcome, rest.time);
    assert!(before[rate].abs() < 1e-5 * first[rate].abs(), "{before:?}");
    let last: Vec<&ModeEvent> = outcome.run.modes.iter().filter(|e| e.time == rest.time).collect();
    assert!(last.iter().all(|e| e.closed), "{last:?}");
    assert_eq!(outcome.run.modes.last().map(|e| e.time), Some(rest.time));
    let mut worst = 0.0f64;
    for row in rows_after(&outcome, rest.time) {
        assert!(row[theta].abs() < 1e-12 && row[rate].abs() < 1e-12, "{row:?}");
        worst = worst.max(relative(row[left] + row[right], m * g));
    }
    eprintln!("rocking block: at rest, the corners' reactions off m·g by {worst:e}");
    assert!(worst < 1e-9);
    assert!(outcome.run.final_time == 3.0);
    // The impacts took the height the tilt raised the centre by.
    let raised = m * g * (b * theta0.sin() + h * theta0.cos() - h);
    let error = relative(-outcome.totals.energy_jumps(), raised);
    eprintln!("rocking block: energy removed off the raised height's by {error:e}");
    assert!(error < 1e-8);
    assert_never_pulls(&outcome, m * g);
}

#[test]
fn rimless_wheel_settles_into_mcgeers_gait() {
    let (m, inertia, l, g, gamma) = (1.0f64, 0.1f64, 1.0f64, 9.81f64, 0.1f64);
    let alpha = FRAC_PI_8;
    let forces: Vec<String> = (0..8).map(|k| format!("spoke{k}.force")).collect();
    let outcome = run(
        "rimless_wheel.lag",
        Options {
            until: Some(40.0),
            output: vec![format!("theta', {}", forces.join(", "))],
            ..Options::default()
        },
    );
    let pivot = inertia + m * l * l;
    let c = (inertia + m * l * l * (2.0 * alpha).cos()) / pivot;
    let fall = 4.0 * m * g * l * alpha.sin() * gamma.sin() / pivot;
    let steady = c * fall.sqrt() / (1.0 - c * c).sqrt();
    let rate = column(&outcome, "theta'");
    let impacts = events(&outcome, ModeChange::Impact);
    assert!(impacts.len() >= 50, "{}", summary(&outcome));
    let mut posts = Vec::new();
    let mut worst = 0.0f64;
    for (k, impact) in impacts.iter().enumerate() {
        // Spoke k + 1 lands, from spoke1 round to spoke0.
        assert_eq!(impact.contact, (k + 1) % 8);
        let (before, after) = jump(&outcome, impact.time);
        let error = relative(after[rate] / before[rate], c);
        worst = worst.max(error);
        assert!(error < 1e-8, "landing {k}: {} → {}", before[rate], after[rate]);
        posts.push(-after[rate]);
    }
    eprintln!("rimless wheel: {} landings, worst ratio {worst:e} relative to c", impacts.len());
    // Between landings the hub falls 2·l·sin α·sin γ: ω⁻² = ω⁺² + fall (all but the first
    // stance, which starts off α).
    let mut worst = 0.0f64;
    for pair in posts.windows(2) {
        let error = relative(pair[1], c * (pair[0] * pair[0] + fall).sqrt());
        worst = worst.max(error);
        assert!(error < 1e-8, "{pair:?}");
    }
    eprintln!("rimless wheel: worst step of the return map {worst:e} relative");
    let last = *posts.last().expect("landings");
    let error = relative(last, steady);
    eprintln!("rimless wheel: last post-impact rate {last} vs McGeer's {steady}: {error:e}");
    assert!(error < 1e-8);
    // The first landing is far from it: the convergence is the run's, not the start's.
    assert!(relative(posts[0], steady) > 1e-2);
    assert_never_pulls(&outcome, m * g);
}

/// A physical cradle sends the first ball's rate to the last: the balls are elastic, the
/// impact travels through them as a wave in turn (ball 1 strikes 2, which strikes 3), and ball
/// 3 leaves at about v0 while 1 and 2 stay nearly at rest. The rigid law here lands both
/// contacts at once, in one complementarity problem with Newton's law at each, which keeps
/// momentum and energy but gives (−1/3, 2/3, 2/3)·v0.
#[test]
fn newtons_cradle_shares_the_impact_and_keeps_momentum_and_energy() {
    let (m, v0) = (1.0f64, 1.0f64);
    let outcome = run(
        "newtons_cradle.lag",
        Options {
            output: vec!["x1', x2', x3', first.force, second.force".into()],
            ..Options::default()
        },
    );
    let rates = [column(&outcome, "x1'"), column(&outcome, "x2'"), column(&outcome, "x3'")];
    let last = outcome.run.trajectory.rows.last().expect("rows");
    let exact = [-1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let mut worst = 0.0f64;
    for (&c, r) in rates.iter().zip(exact) {
        worst = worst.max((last[c] - r * v0).abs() / v0);
    }
    eprintln!("cradle: final rates off by {worst:e} of v0");
    assert!(worst < 1e-12, "{last:?}");
    let momentum: f64 = rates.iter().map(|&c| m * last[c]).sum();
    let energy: f64 = rates.iter().map(|&c| m * last[c] * last[c] / 2.0).sum();
    assert!((momentum - m * v0).abs() < 1e-12 * m * v0, "momentum {momentum}");
    assert!((energy - m * v0 * v0 / 2.0).abs() < 1e-12 * m * v0 * v0, "energy {energy}");
    assert!(outcome.totals.energy_jumps().abs() < 1e-12 * m * v0 * v0);
    let impacts = events(&outcome, ModeChange::Impact);
    assert_eq!(impacts.len(), 1);
    assert_eq!(impacts[0].contact, contact(&outcome, "first"));
    // Without gravity the scale of force is an impact's over the balls' radius, m·v0²/a.
    assert_never_pulls(&outcome, m * v0 * v0 / 0.02);
}

#[test]
fn particle_leaves_the_hemisphere_at_two_thirds_of_its_starting_height() {
    let (m, g, radius, phi0) = (1.0f64, 9.81f64, 1.0f64, 0.2f64);
    let outcome = run(
        "particle_on_hemisphere.lag",
        Options { output: vec!["phi, r, sphere.force".into()], ..Options::default() },
    );
    let lift = events(&outcome, ModeChange::LiftOff);
    assert_eq!(lift.len(), 1, "{}", summary(&outcome));
    let (phi, r, force) =
        (column(&outcome, "phi"), column(&outcome, "r"), column(&outcome, "sphere.force"));
    let (before, _) = jump(&outcome, lift[0].time);
    let error = (before[phi].cos() - 2.0 / 3.0 * phi0.cos()).abs();
    eprintln!("hemisphere: cos φ at lift-off off by {error:e}");
    assert!(error < 1e-8, "leaves at φ = {}", before[phi]);
    let after = rows_after(&outcome, lift[0].time);
    assert!(after.len() > 2);
    for row in &after {
        assert_eq!(row[force], 0.0, "{row:?}");
        assert!(row[r] >= radius * (1.0 - 1e-12), "{row:?}");
    }
    // It flies off: well clear of the surface by the end.
    assert!(after.last().expect("rows")[r] > 1.1 * radius);
    assert_never_pulls(&outcome, m * g);
}

/// `check` holds every `expect` line of every contact scene, counted.
#[test]
fn check_holds_every_expectation_of_the_contact_scenes() {
    let held = lagrange_tests::check_every_expectation_in("contacts");
    assert!(held >= 15, "only {held} expectations held");
}

/// The section of `derive`'s text report that describes the contacts: its heading and the
/// indented lines under it.
fn contacts_section(name: &str) -> String {
    let report = cli::derive(name, &source(name), cli::Format::Text)
        .unwrap_or_else(|d| panic!("{name} does not derive:\n{d}"));
    let mut lines = report.lines().skip_while(|l| *l != "Contacts");
    let heading = lines.next().unwrap_or_else(|| panic!("no Contacts section in:\n{report}"));
    let body = lines.take_while(|l| l.starts_with(' '));
    std::iter::once(heading).chain(body).collect::<Vec<_>>().join("\n")
}

#[test]
fn derive_prints_each_contacts_modes_and_impact_law() {
    for name in ["bouncing_ball.lag", "falling_rod_landing.lag", "rocking_block.lag"] {
        let section = contacts_section(name);
        insta::assert_snapshot!(format!("derive@{}", name.trim_end_matches(".lag")), section);
    }
}

/// `derive`'s JSON report lists each contact, with its name and gap, in the order written.
#[test]
fn derive_json_carries_the_contacts() {
    let cases = [
        ("bouncing_ball.lag", vec![("floor", "y")]),
        ("ladder.lag", vec![("wall", "x - 1/2*L*sin(theta)"), ("floor", "y - 1/2*L*cos(theta)")]),
        ("newtons_cradle.lag", vec![("first", "-2*a - x1 + x2"), ("second", "-2*a - x2 + x3")]),
    ];
    for (name, expected) in cases {
        let report = cli::derive(name, &source(name), cli::Format::Json)
            .unwrap_or_else(|d| panic!("{name} does not derive:\n{d}"));
        let json: serde_json::Value = serde_json::from_str(&report).expect("valid JSON");
        let contacts = json["contacts"].as_array().unwrap_or_else(|| panic!("{report}"));
        let got: Vec<(&str, &str)> = contacts
            .iter()
            .map(|c| (c["name"].as_str().expect("name"), c["gap"].as_str().expect("gap")))
            .collect();
        assert_eq!(got, expected, "{name}");
    }
}

/// The ball and the ladder under the other methods that take contacts, to a looser tolerance
/// (radau and auto at their tolerance 1e-10, rk4 at a step of 1e-4 s), and the symplectic
/// methods refusing, naming the contacts.
#[test]
fn other_methods_take_the_ball_and_the_ladder_or_refuse_naming_the_contacts() {
    let (g, h0, e) = (9.81f64, 1.0f64, 0.8f64);
    let t1 = (2.0 * h0 / g).sqrt();
    let theta0 = FRAC_PI_6;
    for (method, step, tolerance) in
        [("radau", None, 1e-6), ("auto", None, 1e-6), ("rk4", Some(1e-4), 1e-6)]
    {
        let options = Options { method: Some(method.into()), step, ..Options::default() };
        let ball = run(
            "bouncing_ball.lag",
            Options { output: vec!["y, floor.force".into()], ..options.clone() },
        );
        let impacts = events(&ball, ModeChange::Impact);
        assert!(impacts.len() >= 20, "{method}: {}", summary(&ball));
        let mut worst = 0.0f64;
        for (k, impact) in impacts.iter().take(20).enumerate() {
            let exact = t1 * (1.0 + 2.0 * (1..=k).map(|j| e.powi(j as i32)).sum::<f64>());
            worst = worst.max(relative(impact.time, exact));
        }
        let settled = events(&ball, ModeChange::Settled);
        assert_eq!(settled.len(), 1, "{method}: {}", summary(&ball));
        let accumulation = relative(settled[0].time, t1 * (1.0 + e) / (1.0 - e));
        eprintln!("{method}: ball's impacts {worst:e}, settling {accumulation:e} relative");
        assert!(worst < tolerance && accumulation < tolerance, "{method}");
        assert_never_pulls(&ball, 0.5 * g);

        let ladder = run(
            "ladder.lag",
            Options { output: vec!["theta, wall.force, floor.force".into()], ..options },
        );
        let lift = events(&ladder, ModeChange::LiftOff);
        assert_eq!(lift.len(), 1, "{method}: {}", summary(&ladder));
        let (before, _) = jump(&ladder, lift[0].time);
        let error = (before[column(&ladder, "theta")].cos() - 2.0 / 3.0 * theta0.cos()).abs();
        eprintln!("{method}: ladder's cos θ at lift-off off by {error:e}");
        assert!(error < tolerance, "{method}: leaves at θ = {}", before[0]);
        assert_never_pulls(&ladder, 10.0 * g);
    }
    for method in ["midpoint", "gauss"] {
        for (name, contacts) in
            [("bouncing_ball.lag", "`floor`"), ("ladder.lag", "`wall`, `floor`")]
        {
            let options = Options { method: Some(method.into()), ..Options::default() };
            let Err(error) = simulate(&source(name), &options) else {
                panic!("{method} ran {name}");
            };
            let message = error.to_string();
            assert!(
                message.contains(&format!("{method} does not take contacts"))
                    && message.contains(contacts),
                "{message}"
            );
            assert_eq!(error.exit_code(), 2, "{message}");
        }
    }
}

/// A contact armed by a condition: the ledge's, while x > a. The ball passes its edge below
/// it (armed inside its gap: no landing, no fault), rises through its level unseen and lands
/// where the throw says, then bounces with its restitution.
#[test]
fn an_armed_ledge_lets_the_ball_rise_through_and_catches_it() {
    let (g, v0, h, e) = (9.81f64, 6.0f64, 1.0f64, 0.5f64);
    let outcome =
        run("ledge.lag", Options { output: vec!["x, y, y'".into()], ..Options::default() });
    let impacts = events(&outcome, ModeChange::Impact);
    assert!(impacts.len() >= 3, "{}", summary(&outcome));
    let rise = (v0 * v0 - 2.0 * g * h).sqrt();
    let t0 = (v0 - rise) / g;
    let mut landing = t0 + 2.0 * rise / g;
    let mut speed = rise;
    for impact in impacts.iter().take(3) {
        let error = relative(impact.time, landing);
        eprintln!("ledge: lands at {} vs {landing}: {error:e}", impact.time);
        assert!(error < 1e-8);
        speed *= e;
        landing += 2.0 * speed / g;
    }
    // Below the ledge's level it was never touched.
    let y = column(&outcome, "y");
    let trajectory = &outcome.run.trajectory;
    let crossing = trajectory.times.iter().position(|&t| t > t0).expect("rows after t0");
    assert!(trajectory.rows[..crossing].iter().all(|r| r[y] < 1e-9));
}

/// The stance leg's angle and rate just after the last heel strike of a walk of
/// `examples/contacts/simplest_walker.lag` with feet of mass `beta`·M: where the gait has
/// settled (its multipliers are about 0.58 in size, so thirty steps leave 1e-7 of any start).
fn walker_after_strike(beta: f64) -> (f64, f64, usize) {
    let outcome = run(
        "simplest_walker.lag",
        Options {
            set: vec![engine::input::Assignment { name: "beta".into(), value: beta.to_string() }],
            output: vec!["th1, th1', th2, th2'".into()],
            ..Options::default()
        },
    );
    let strikes = events(&outcome, ModeChange::Impact);
    let last = strikes.last().expect("it walks");
    let (_, after) = jump(&outcome, last.time);
    // The foot that struck is the new stance foot.
    let (angle, rate) = if outcome.contact_names[last.contact] == "ground1" {
        (column(&outcome, "th1"), column(&outcome, "th1'"))
    } else {
        (column(&outcome, "th2"), column(&outcome, "th2'"))
    };
    (after[angle], after[rate], strikes.len())
}

/// Garcia et al.'s simplest walker: the paper's gait is the limit of feet of vanishing mass.
/// Two small ratios, each off the paper by O(beta), extrapolate to it within 1e-6.
#[test]
fn the_simplest_walker_settles_onto_garcias_gait_as_its_feet_lighten() {
    let paper = (0.20031090049483f64, -0.19983247291764f64);
    let (b1, b2) = (2e-4f64, 1e-4f64);
    let (theta1, rate1, steps) = walker_after_strike(b1);
    let (theta2, rate2, _) = walker_after_strike(b2);
    assert!(steps >= 30, "{steps} steps");
    // Linear in beta: the value at 0 from the two.
    let limit = |a: f64, b: f64| b - (a - b) * b2 / (b1 - b2);
    let (theta, rate) = (limit(theta1, theta2), limit(rate1, rate2));
    let offsets = [(theta1 - paper.0).abs(), (theta2 - paper.0).abs(), (theta - paper.0).abs()];
    eprintln!(
        "walker: θ⁺ off the paper by {:e} (β = {b1}), {:e} (β = {b2}), {:e} extrapolated; \
         θ'⁺ by {:e} extrapolated",
        offsets[0],
        offsets[1],
        offsets[2],
        (rate - paper.1).abs()
    );
    // The approach: halving beta halves the offset.
    assert!(offsets[1] < 0.6 * offsets[0] && offsets[1] > 0.4 * offsets[0], "{offsets:?}");
    assert!(offsets[2] < 1e-6 && (rate - paper.1).abs() < 1e-6, "{theta}, {rate}");
}
