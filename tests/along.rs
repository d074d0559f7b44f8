//! Linearization along a motion against the motions themselves: the state-transition matrix
//! of a pendulum swinging at large amplitude is the central difference of whole runs started
//! a little apart, both from a run and from the run's own samples read back as a trajectory,
//! and along a run it is the variational run `orbit` integrates; the same holds of the
//! pendulum written in Cartesian coordinates with its rod a kept constraint, whose A and B
//! along the run are central differences of the right-hand side a run integrates (as are a
//! Chaplygin sleigh's, whose blade is a kept velocity constraint).

use engine::along::{along, linearize_along, Between, DMatrix, Motion};
use simulation::{simulate, Options};

/// Swung from 2.5 rad (143°): far from the small motions, where A(t) changes sign over a swing.
const PENDULUM: &str = "
param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord theta = 5/2
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

const UNTIL: f64 = 3.0;
const TOLERANCE: f64 = 1e-13;

/// The end state of a run from θ = θ0 + dθ, θ' = dω.
fn end_state(d_theta: f64, d_omega: f64) -> [f64; 2] {
    let options = Options {
        until: Some(UNTIL),
        method: Some("dop853".into()),
        tolerance: Some(TOLERANCE),
        set: vec![
            format!("theta = 5/2 + {d_theta:e}").parse().expect("an assignment"),
            format!("theta' = {d_omega:e}").parse().expect("an assignment"),
        ],
        output: vec!["theta".into(), "theta'".into()],
        samples: 2,
        ..Default::default()
    };
    let outcome = simulate(PENDULUM, &options).expect("runs");
    let row = outcome.run.trajectory.rows.last().expect("the end");
    [row[0], row[1]]
}

/// Φ(t_end, 0) by central differences of whole runs, column by column.
fn differenced() -> [[f64; 2]; 2] {
    let h = 1e-5;
    let mut phi = [[0.0; 2]; 2];
    for j in 0..2 {
        let (dq, dw) = if j == 0 { (h, 0.0) } else { (0.0, h) };
        let up = end_state(dq, dw);
        let down = end_state(-dq, -dw);
        for (i, row) in phi.iter_mut().enumerate() {
            row[j] = (up[i] - down[i]) / (2.0 * h);
        }
    }
    phi
}

fn run_options(samples: usize) -> Options {
    Options {
        until: Some(UNTIL),
        method: Some("dop853".into()),
        tolerance: Some(TOLERANCE),
        samples,
        ..Default::default()
    }
}

/// The largest difference relative to Φ's largest entry.
fn relative(phi: &engine::along::DMatrix<f64>, reference: &[[f64; 2]; 2]) -> f64 {
    let scale = phi.amax();
    let mut worst: f64 = 0.0;
    for i in 0..2 {
        for j in 0..2 {
            worst = worst.max((phi[(i, j)] - reference[i][j]).abs() / scale);
        }
    }
    worst
}

#[test]
fn the_state_transition_matrix_of_a_large_swing_is_the_difference_of_whole_runs() {
    let reference = differenced();
    let l = simulation::along::linearize_run(PENDULUM, &run_options(200)).expect("linearizes");
    assert_eq!(l.between, Between::Model);
    let error = relative(&l.transition, &reference);
    assert!(error < 1e-6, "Φ = {}, runs {reference:?}: {error:e}", l.transition);
    // A swing this large stretches small changes: Φ is far from the identity.
    assert!(l.transition.amax() > 5.0, "{}", l.transition);
    // Liouville: with M constant, the flow in (θ, θ') keeps areas as in (θ, p).
    assert!((l.transition.determinant() - 1.0).abs() < 1e-8);
    // Integrated beside the run on its own steps, Φ does not depend on the samples at all.
    let sparse = simulation::along::linearize_run(PENDULUM, &run_options(20)).expect("sparse");
    assert_eq!(sparse.transition, l.transition);
}

#[test]
fn from_the_samples_alone_the_state_transition_matrix_converges_with_their_spacing() {
    let reference = differenced();
    let mut errors = Vec::new();
    for samples in [300, 600, 1200] {
        let l = simulation::along::linearize_run(PENDULUM, &run_options(samples)).expect("run");
        // The run's samples as a trajectory read from a file: A(t) known at them alone.
        let motion = Motion {
            times: l.times.clone(),
            states: recorded_states(samples),
            inputs: vec![Vec::new(); l.times.len()],
        };
        let mut model = along(PENDULUM, &Default::default()).expect("loads");
        let read = linearize_along(&mut model, &motion).expect("reads");
        assert_eq!(read.between, Between::Interpolated);
        assert_eq!(read.samples, l.samples, "the same A at the same states");
        errors.push(relative(&read.transition, &reference));
    }
    // Second order in the spacing: each halving divides the error by about four.
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!((3.0..5.0).contains(&ratio), "{errors:?}");
    }
    assert!(errors[2] < 1e-3, "{errors:?}");
}

/// The run's recorded states, as `simulate --output theta,theta'` writes them.
fn recorded_states(samples: usize) -> Vec<Vec<f64>> {
    let options = Options { output: vec!["theta".into(), "theta'".into()], ..run_options(samples) };
    let outcome = simulate(PENDULUM, &options).expect("runs");
    outcome.run.trajectory.rows.iter().map(|r| r[..2].to_vec()).collect()
}

#[test]
fn contacts_are_refused_by_name() {
    let source = include_str!("../examples/contacts/bouncing_ball.lag");
    let e = along(source, &Default::default()).err().expect("refused").to_string();
    assert!(e.contains("linearization along a motion does not take contacts"), "{e}");
    let name = source.lines().find_map(|l| l.strip_prefix("contact ")).expect("a contact");
    let name = name.split([':', ' ']).next().expect("its name");
    assert!(e.contains(&format!("`{name}`")), "{e}");
}

/// The pendulum of [`PENDULUM`] with its bob in Cartesian coordinates: the rod a constraint
/// kept with a multiplier, and a push on the bob for B.
const CARTESIAN: &str = "
param m = 1 kg, L = 1 m, g = 9.81 m/s^2
input F = 0 N
coord x = L*sin(5/2), y = -L*cos(5/2)
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
force push on bob: (F, 0)
gravity g
output height: y
";

const CARTESIAN_STATE: [&str; 4] = ["x", "y", "x'", "y'"];

/// The states a run of `source` records at its samples (the columns `state`), with `set`.
fn recorded(source: &str, set: &[String], state: &[&str], samples: usize) -> Vec<Vec<f64>> {
    let options = Options {
        set: set.iter().map(|s| s.parse().expect("an assignment")).collect(),
        output: state.iter().map(|s| s.to_string()).collect(),
        ..run_options(samples)
    };
    let outcome = simulate(source, &options).expect("runs");
    outcome.run.trajectory.rows.iter().map(|r| r[..state.len()].to_vec()).collect()
}

/// Checks A (and B, with inputs) at every sample of a run of `source` against central
/// differences of the right-hand side at the sample's state: the run's own, which with kept
/// constraints holds Baumgarte's terms. Gives the number of entries compared.
fn right_hand_side_differences(source: &str, state: &[&str]) -> usize {
    let samples = 40;
    let l = simulation::along::linearize_run(source, &run_options(samples)).expect("linearizes");
    let states = recorded(source, &[], state, samples);
    assert_eq!(states.len(), l.times.len());
    let mut model = along(source, &Default::default()).expect("loads");
    let inputs = model.resting_inputs();
    // The samples of a file: the same A at the same states, with constraints kept too.
    let motion = Motion {
        times: l.times.clone(),
        states: states.clone(),
        inputs: vec![inputs.clone(); l.times.len()],
    };
    let read = linearize_along(&mut model, &motion).expect("reads");
    assert_eq!(read.samples, l.samples);
    let h = 1e-5;
    let mut compared = 0;
    let mut fastest: f64 = 0.0;
    for ((t, x), at) in l.times.iter().zip(&states).zip(&l.samples) {
        fastest = fastest.max(x[x.len() / 2..].iter().fold(0.0, |m: f64, v| m.max(v.abs())));
        let rate = |model: &mut engine::along::Along, x: &[f64], u: &[f64]| {
            model.rate(*t, x, u).expect("a rate")
        };
        let scale = at.a.amax();
        for j in 0..x.len() {
            let (mut up, mut down) = (x.clone(), x.clone());
            up[j] += h;
            down[j] -= h;
            let (up, down) = (rate(&mut model, &up, &inputs), rate(&mut model, &down, &inputs));
            for i in 0..x.len() {
                let difference = (up[i] - down[i]) / (2.0 * h);
                let error = (difference - at.a[(i, j)]).abs() / scale;
                assert!(
                    error < 1e-7,
                    "t = {t}: A[{i},{j}] = {}, differences {difference}",
                    at.a[(i, j)]
                );
                compared += 1;
            }
        }
        for k in 0..inputs.len() {
            let (mut up, mut down) = (inputs.clone(), inputs.clone());
            up[k] += h;
            down[k] -= h;
            let (up, down) = (rate(&mut model, x, &up), rate(&mut model, x, &down));
            let scale = at.b.amax();
            for i in 0..x.len() {
                let difference = (up[i] - down[i]) / (2.0 * h);
                let error = (difference - at.b[(i, k)]).abs() / scale;
                assert!(
                    error < 1e-7,
                    "t = {t}: B[{i},{k}] = {}, differences {difference}",
                    at.b[(i, k)]
                );
                compared += 1;
            }
        }
    }
    // Along a motion, not about a rest.
    assert!(fastest > 1.0, "the fastest rate along the run is {fastest}");
    compared
}

#[test]
fn with_a_kept_constraint_a_and_b_along_a_run_are_differences_of_the_right_hand_side() {
    let compared = right_hand_side_differences(CARTESIAN, &CARTESIAN_STATE);
    assert!(compared >= 40 * (16 + 4), "{compared}");
    let sleigh = lagrange_tests::example("classics/chaplygin_sleigh.lag");
    let compared = right_hand_side_differences(&sleigh, &["x", "y", "theta", "x'", "y'", "theta'"]);
    assert!(compared >= 40 * 36, "{compared}");
}

/// Φ over [0, UNTIL] from `start` by the variational run of `orbit`, over a fixed period.
fn orbit_transition(source: &str, start: &[f64]) -> DMatrix<f64> {
    let options = orbit::Options {
        run: run_options(0),
        section: orbit::Section::Period(format!("{UNTIL} s")),
        swaps: Vec::new(),
        shifts: Vec::new(),
        ignore: Vec::new(),
        iterations: 1,
    };
    let search = orbit::Search::new(source, &options).expect("loads");
    let (_, matrix, _) = search.evaluate(start).expect("a variational run");
    DMatrix::from_row_slice(start.len(), start.len(), &matrix)
}

#[test]
fn along_a_run_the_state_transition_matrix_is_the_variational_run_orbit_uses() {
    let swing = simulation::along::linearize_run(PENDULUM, &run_options(50)).expect("swing");
    let rod = simulation::along::linearize_run(CARTESIAN, &run_options(50)).expect("rod");
    let start = recorded(CARTESIAN, &[], &CARTESIAN_STATE, 2)[0].clone();
    for (l, source, start) in [(&swing, PENDULUM, vec![2.5, 0.0]), (&rod, CARTESIAN, start)] {
        let variational = orbit_transition(source, &start);
        let error = (&l.transition - &variational).amax() / variational.amax();
        assert!(error < 1e-9, "Φ = {}, orbit's {variational}: {error:e}", l.transition);
    }
}

#[test]
fn with_a_kept_constraint_the_state_transition_matrix_is_the_difference_of_whole_runs() {
    let l = simulation::along::linearize_run(CARTESIAN, &run_options(50)).expect("linearizes");
    assert_eq!(l.between, Between::Model);
    // The start moved along the rod: x or x', and y or y' with it on the constraint.
    let h = 1e-5;
    let mut worst: f64 = 0.0;
    for column in 0..2 {
        let run = |sign: f64| {
            let d = sign * h;
            let set = match column {
                0 => [
                    format!("x = L*(sin(5/2) + {d:e})"),
                    format!("y = L*sqrt(1 - (sin(5/2) + {d:e})^2)"),
                ],
                // x·x' + y·y' = 0 at the start.
                _ => [format!("x' = {d:e} m/s"), format!("y' = tan(5/2)*{d:e} m/s")],
            };
            let states = recorded(CARTESIAN, &set, &CARTESIAN_STATE, 2);
            (states[0].clone(), states[states.len() - 1].clone())
        };
        let ((start_up, end_up), (start_down, end_down)) = (run(1.0), run(-1.0));
        let moved: Vec<f64> =
            start_up.iter().zip(&start_down).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        // The settled component moved too: the perturbation is not along a coordinate axis.
        assert!(moved.iter().filter(|v| v.abs() > 0.1).count() == 2, "{moved:?}");
        let predicted = &l.transition * nalgebra::DVector::from_vec(moved);
        let reference: Vec<f64> =
            end_up.iter().zip(&end_down).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        let scale = reference.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
        assert!(scale > 1.0, "{reference:?}");
        for (p, r) in predicted.iter().zip(&reference) {
            worst = worst.max((p - r).abs() / scale);
        }
    }
    assert!(worst < 1e-6, "{worst:e}");
}

/// A chain of ten links, past the stack's order, where the runs solve q̈ by the recursive
/// form's sweep and the variational run's columns by its factors: A and B along a run are
/// central differences of the right-hand side, a push on the third link giving B.
#[test]
fn on_a_long_chain_a_and_b_along_a_run_are_differences_of_the_right_hand_side() {
    let source = lang::generate::n_link(lang::generate::Family::Pendulum, 10)
        .replace("coord theta1 = 1/10", "coord theta1 = 1")
        .replace("coord theta4 = 1/10", "coord theta4 = -1")
        + "input F = 0 N\nforce push on p3: (F, 0)\n";
    let mut prepared =
        engine::numbers::prepare(&source, &[], engine::Options::default()).expect("prepares");
    assert!(prepared.recursive().expect("lowers").is_some(), "the sweep solves q̈");
    let names: Vec<String> = (1..=10).map(|i| format!("theta{i}")).collect();
    let rates: Vec<String> = names.iter().map(|q| format!("{q}'")).collect();
    let state: Vec<&str> = names.iter().chain(&rates).map(String::as_str).collect();
    let compared = right_hand_side_differences(&source, &state);
    assert!(compared >= 40 * (400 + 20), "{compared}");
}
