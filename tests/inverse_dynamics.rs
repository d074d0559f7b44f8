//! Inverse dynamics against the forward dynamics it inverts: the torques a driven double
//! pendulum was simulated with come back from its trajectory, and the torques computed for a
//! prescribed motion, applied as generalized forces, make the scene follow that motion; with a
//! constraint kept, τ leaves the constraint its own load, and still reproduces the motion. The
//! two-link arm of examples/control tracks its trajectory by computed torque: its error obeys
//! the law's linear equation, and on the path its torques are the inverse dynamics.

// The prescribed motion and the drive are closed forms in the test, evaluated by the
// platform's functions, far from a last bit.
#![allow(clippy::disallowed_methods)]

use engine::inverse::{inverse_dynamics, InverseDynamics};
use engine::numbers::prepare;
use numeric::Tape;
use sim::{FaultKind, Problem};
use simulation::{simulate, Options};

/// Two links on hinges, each angle from the downward vertical: a shoulder motor between the
/// ground and the upper link, an elbow motor between the links, both functions of time.
const DRIVEN: &str = include_str!("scenes/driven_double_pendulum.lag");

/// The scene's inverse dynamics with the motors off: what it returns is what the motors do.
fn without_motors(source: &str) -> InverseDynamics {
    let mut inverse = inverse_dynamics(source, &Default::default()).unwrap();
    let mut values = inverse.parameters().to_vec();
    for (name, value) in inverse.parameter_names().iter().zip(&mut values) {
        if name.starts_with('A') {
            *value = 0.0;
        }
    }
    inverse.set_parameters(&values).unwrap();
    inverse
}

#[test]
fn the_torques_of_a_driven_run_come_back_from_its_trajectory() {
    let names = ["theta1", "theta2", "theta1'", "theta2'", "theta1''", "theta2''"];
    let options = Options {
        until: Some(5.0),
        method: Some("dop853".into()),
        tolerance: Some(1e-12),
        output: vec![names.join(", ")],
        samples: 201,
        ..Options::default()
    };
    let outcome = simulate(DRIVEN, &options).unwrap();
    assert!(outcome.run.fault.is_none());
    assert_eq!(&outcome.columns[..6], names.map(String::from));
    let mut inverse = without_motors(DRIVEN);
    let (a1, a2, w) = (3.0f64, 1.0f64, 2.0f64);
    let mut worst = 0.0f64;
    let mut tau = [0.0; 2];
    for (t, row) in outcome.run.trajectory.times.iter().zip(&outcome.run.trajectory.rows) {
        inverse.torques(*t, &row[0..2], &row[2..4], &row[4..6], &mut tau).unwrap();
        let applied = [a1 * (w * t).sin() - a2 * (w * t).cos(), a2 * (w * t).cos()];
        for (got, want) in tau.iter().zip(applied) {
            worst = worst.max((got - want).abs());
        }
    }
    assert_eq!(outcome.run.trajectory.times.len(), 201);
    eprintln!("largest difference from the applied torques: {worst:e}");
    assert!(worst < 1e-9, "largest difference from the applied torques: {worst:e}");

    // With the motors on, the scene's own forces account for everything: τ vanishes.
    let mut inverse = inverse_dynamics(DRIVEN, &Default::default()).unwrap();
    let row = &outcome.run.trajectory.rows[100];
    inverse
        .torques(outcome.run.trajectory.times[100], &row[0..2], &row[2..4], &row[4..6], &mut tau)
        .unwrap();
    assert!(tau.iter().all(|v| v.abs() < 1e-9), "{tau:?}");
}

/// A motion given in closed form: positions, rates and accelerations at t, per coordinate.
type Motion = fn(f64) -> [Vec<f64>; 3];

fn swing(t: f64) -> [Vec<f64>; 3] {
    let (a, b, p, r) = (0.6, 0.4, 1.3, 0.7);
    [
        vec![a * (p * t).sin(), b * (1.0 - (r * t).cos())],
        vec![a * p * (p * t).cos(), b * r * (r * t).sin()],
        vec![-a * p * p * (p * t).sin(), b * r * r * (r * t).cos()],
    ]
}

/// M·q̈ = f + Jᵀλ + τ(t), J·q̈ = γ, with τ(t) the inverse dynamics of `motion`: computed-torque
/// control without feedback. Constraints are imposed at the acceleration level only, as the
/// test starts on them and runs briefly.
struct Driven {
    n: usize,
    m: usize,
    dynamics: Tape,
    parameters: Vec<f64>,
    inverse: InverseDynamics,
    motion: Motion,
    input: Vec<f64>,
    output: Vec<f64>,
}

impl Driven {
    fn new(source: &str, motion: Motion) -> Driven {
        let mut prepared = prepare(source, &[], engine::Options::default()).unwrap();
        let exprs = prepared.dynamics_exprs();
        let program = prepared.lower(&prepared.dynamics_inputs(), &exprs).unwrap();
        let inverse = without_motors(source);
        let parameters = inverse.slots().to_vec();
        let (n, m) = (prepared.layout.coordinates, prepared.layout.multipliers);
        Driven {
            n,
            m,
            input: vec![0.0; program.inputs],
            output: vec![0.0; exprs.len()],
            dynamics: Tape::new(program),
            parameters,
            inverse,
            motion,
        }
    }
}

impl Problem for Driven {
    fn dim(&self) -> usize {
        2 * self.n
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        let (n, m) = (self.n, self.m);
        let [q, rates, accelerations] = (self.motion)(t);
        let mut tau = vec![0.0; n];
        self.inverse.torques(t, &q, &rates, &accelerations, &mut tau).unwrap();
        self.input[0] = t;
        self.input[1..1 + 2 * n].copy_from_slice(y);
        self.input[1 + 2 * n..].copy_from_slice(&self.parameters);
        self.dynamics.eval(&self.input, &mut self.output);
        let out = &self.output;
        let mut a = nalgebra::DMatrix::zeros(n + m, n + m);
        let mut b = nalgebra::DVector::zeros(n + m);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = out[j * n + i];
            }
            b[i] = out[n * n + i] + tau[i];
        }
        for c in 0..m {
            let base = n * n + n + c * (n + 3);
            for j in 0..n {
                a[(n + c, j)] = out[base + j];
                a[(j, n + c)] = -out[base + j];
            }
            b[n + c] = out[base + n];
        }
        let solution = a.lu().solve(&b).expect("regular");
        dy[..n].copy_from_slice(&y[n..]);
        dy[n..].copy_from_slice(&solution.as_slice()[..n]);
        Ok(())
    }

    fn observations(&self) -> usize {
        2 * self.n
    }

    fn observe(&mut self, _t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        out.copy_from_slice(y);
        Ok(())
    }
}

/// The largest difference between the run of `source` driven by the inverse dynamics of
/// `motion` and the motion itself, over `until` seconds.
fn tracking_error(source: &str, motion: Motion, until: f64) -> f64 {
    let mut problem = Driven::new(source, motion);
    let [q0, rates0, _] = motion(0.0);
    let y0: Vec<f64> = q0.into_iter().chain(rates0).collect();
    let settings = sim::Settings {
        method: sim::Method::Dop853,
        start: 0.0,
        until,
        tolerance: 1e-13,
        step: 0.0,
        max_steps: 1_000_000,
        samples: 101,
    };
    let run = sim::integrate(&mut problem, &y0, &settings, &[], &mut |_| {
        std::ops::ControlFlow::Continue(())
    });
    assert!(run.fault.is_none());
    assert_eq!(run.trajectory.times.len(), 101);
    let mut worst = 0.0f64;
    for (t, row) in run.trajectory.times.iter().zip(&run.trajectory.rows) {
        let [q, rates, _] = motion(*t);
        for (got, want) in row.iter().zip(q.iter().chain(&rates)) {
            worst = worst.max((got - want).abs());
        }
    }
    worst
}

#[test]
fn the_torques_of_a_prescribed_motion_make_the_scene_follow_it() {
    let worst = tracking_error(DRIVEN, swing, 5.0);
    eprintln!("largest difference from the prescribed motion: {worst:e}");
    assert!(worst < 1e-9, "largest difference from the prescribed motion: {worst:e}");
}

/// A cart on a rail with a pendulum, written in Cartesian coordinates with the rod kept as a
/// constraint: the cart's position x and the bob's (px, py), with (px − x)² + py² = L².
const CART: &str = "param M = 2 kg, m = 1/2 kg, L = 1 m, g = 9.81 m/s^2, A = 0 N
coord x = 0
coord px = 0
coord py = -1 m
particle cart { mass M; position (x, 0) }
particle bob { mass m; position (px, py) }
gravity g
constraint rod: (px - x)^2 + py^2 = L^2
force push on cart: (A, 0)
";

fn cart_swing(t: f64) -> [Vec<f64>; 3] {
    // The cart moves; the bob swings on the rod: px = x + sin θ, py = −cos θ.
    let (x, xd, xdd) = (0.3 * (0.9 * t).sin(), 0.27 * (0.9 * t).cos(), -0.243 * (0.9 * t).sin());
    let (th, thd, thdd) = (0.5 * (1.1 * t).sin(), 0.55 * (1.1 * t).cos(), -0.605 * (1.1 * t).sin());
    let (s, c) = th.sin_cos();
    [
        vec![x, x + s, -c],
        vec![xd, xd + c * thd, s * thd],
        vec![xdd, xdd + c * thdd - s * thd * thd, s * thdd + c * thd * thd],
    ]
}

#[test]
fn with_a_kept_constraint_the_torques_leave_it_its_own_load() {
    let mut inverse = inverse_dynamics(CART, &Default::default()).unwrap();
    assert_eq!(inverse.kept_constraints(), ["rod"]);
    assert_eq!(inverse.coordinates(), ["x", "px", "py"]);
    // The scene swinging on its own needs no force: the rod holds the bob.
    let names = ["x", "px", "py", "x'", "px'", "py'", "x''", "px''", "py''"];
    let options = Options {
        until: Some(2.0),
        tolerance: Some(1e-12),
        output: vec![names.join(", ")],
        set: engine::input::assignments(&["px=0.6", "py=-0.8", "x'=0.3", "px'=0.3"]).unwrap(),
        samples: 41,
        ..Options::default()
    };
    let outcome = simulate(CART, &options).unwrap();
    assert!(outcome.run.fault.is_none());
    let mut tau = [0.0; 3];
    let mut worst = 0.0f64;
    for (t, row) in outcome.run.trajectory.times.iter().zip(&outcome.run.trajectory.rows) {
        inverse.torques(*t, &row[0..3], &row[3..6], &row[6..9], &mut tau).unwrap();
        worst = tau.iter().fold(worst, |w, v| w.max(v.abs()));
    }
    eprintln!("largest force a free swing needs: {worst:e}");
    assert!(worst < 1e-9, "largest force a free swing needs: {worst:e}");
    // And the forces of a prescribed motion make the scene follow it.
    let worst = tracking_error(CART, cart_swing, 2.0);
    eprintln!("largest difference from the prescribed motion: {worst:e}");
    assert!(worst < 1e-9, "largest difference from the prescribed motion: {worst:e}");
}

/// examples/control/two_link_arm.lag: the shoulder and elbow torques driven by the
/// computed-torque law of its `simulate` block, written from the hand-derived model.
const ARM: &str = "control/two_link_arm.lag";

/// The arm's desired motion as the scene writes it (w = 1 rad/s): positions, rates and
/// accelerations of (q1, q2) at t.
fn arm_motion(t: f64) -> [Vec<f64>; 3] {
    let (s, c, s2, c2) = (t.sin(), t.cos(), (2.0 * t).sin(), (2.0 * t).cos());
    [
        vec![-std::f64::consts::FRAC_PI_2 + 0.8 * s, 0.6 * (1.0 - c2)],
        vec![0.8 * c, 1.2 * s2],
        vec![-0.8 * s, 2.4 * c2],
    ]
}

fn arm_run(set: &[&str]) -> simulation::Outcome {
    let options = Options {
        tolerance: Some(1e-12),
        output: vec!["q1, q2, q1', q2', tau1, tau2".into()],
        set: engine::input::assignments(set).unwrap(),
        samples: 121,
        ..Options::default()
    };
    let outcome = simulate(&lagrange_tests::example(ARM), &options).unwrap();
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    assert_eq!(*outcome.run.trajectory.times.last().unwrap(), 6.0);
    outcome
}

#[test]
fn the_arm_tracks_its_trajectory_by_computed_torque() {
    // The law cancels the arm's dynamics only if the model written in the scene is the one
    // lagrange derives: then e = qd − q obeys e'' + 20·e' + 100·e = 0 exactly, whose solution
    // is e = (e(0) + (e'(0) + 10·e(0))·t)·exp(−10·t). From q = (−π/2 + 0.1, 0.1) at rest,
    // e(0) = (−0.1, −0.1) and e'(0) = qd'(0) = (0.8, 0), so e1 = (−0.1 − 0.2·t)·exp(−10·t) and
    // e2 = (−0.1 − t)·exp(−10·t).
    let outcome = arm_run(&[]);
    let (mut off_law, mut late) = (0.0f64, 0.0f64);
    for (t, row) in outcome.run.trajectory.times.iter().zip(&outcome.run.trajectory.rows) {
        let [qd, _, _] = arm_motion(*t);
        let error = [qd[0] - row[0], qd[1] - row[1]];
        let law = [(-0.1 - 0.2 * t) * (-10.0 * t).exp(), (-0.1 - t) * (-10.0 * t).exp()];
        for (e, expected) in error.iter().zip(law) {
            off_law = off_law.max((e - expected).abs());
        }
        if *t >= 1.0 {
            late = late.max(error[0].abs()).max(error[1].abs());
        }
    }
    eprintln!("largest departure from e'' + kd·e' + kp·e = 0: {off_law:e}");
    eprintln!("largest tracking error after 1 s: {late:e}");
    assert!(off_law < 1e-9, "the error departs from its law by {off_law:e}");
    assert!(late < 1e-4, "the tracking error after 1 s reaches {late:e}");

    // Started on the trajectory it stays there, and the torques the law applies are the
    // inverse dynamics of the desired motion (the inputs at their value 0: the motors' part).
    let outcome = arm_run(&["q1=-pi/2", "q2=0", "q1'=0.8"]);
    let mut inverse = inverse_dynamics(&lagrange_tests::example(ARM), &Default::default()).unwrap();
    let (mut off_path, mut off_torque) = (0.0f64, 0.0f64);
    let mut tau = [0.0; 2];
    for (t, row) in outcome.run.trajectory.times.iter().zip(&outcome.run.trajectory.rows) {
        let [q, rates, accelerations] = arm_motion(*t);
        for (got, want) in row[..4].iter().zip(q.iter().chain(&rates)) {
            off_path = off_path.max((got - want).abs());
        }
        inverse.torques(*t, &q, &rates, &accelerations, &mut tau).unwrap();
        for (got, want) in row[4..6].iter().zip(tau) {
            off_torque = off_torque.max((got - want).abs());
        }
    }
    eprintln!("on the path: {off_path:e} from it, torques {off_torque:e} from inverse dynamics");
    assert!(off_path < 1e-9, "{off_path:e}");
    assert!(off_torque < 1e-9, "{off_torque:e}");
}
