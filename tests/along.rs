//! Linearization along a motion against the motions themselves: the state-transition matrix
//! of a pendulum swinging at large amplitude is the central difference of whole runs started
//! a little apart, both from a run and from the run's own samples read back as a trajectory;
//! a cart-pole's A and B along a moving run are central differences of its right-hand side,
//! and at rest they are `linearize`'s.

use engine::along::{along, linearize_along, Between, Motion};
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
    // Riding the scene's equations between samples, Φ does not need them close together.
    let sparse = simulation::along::linearize_run(PENDULUM, &run_options(20)).expect("sparse");
    let error = relative(&sparse.transition, &reference);
    assert!(error < 1e-6, "20 samples: {error:e}");
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
        let read = linearize_along(&mut model, &motion, Between::Interpolated).expect("reads");
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
