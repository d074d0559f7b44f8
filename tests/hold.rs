//! `simulate --hold`: a block on a spring pushed by a state-feedback law sampled every period
//! and held in between (a zero-order hold), against the exact discrete-time solution
//! x_{k+1} = Φ·x_k + Γ·u_k from the plant's matrix exponential; the held value recorded as
//! held; a short period approaching the continuous law; the hold refused where it holds
//! nothing.

use numeric::elementary::apply;
use simulation::{simulate, Options, Outcome};

/// m·ẍ = −k·x + F, with F = −kp·x − kd·ẋ sampled and held.
const BLOCK: &str = "scene \"A block on a spring, pushed by a held feedback\"
param m = 2 kg, k = 8 N/m, kp = 20 N/m, kd = 5 N*s/m
input F = 0 N
coord x = 0.1
particle block { mass m; position (x, 0) }
potential k/2*x^2
force push on block: (F, 0)
";
const MASS: f64 = 2.0;
const STIFFNESS: f64 = 8.0;
const KP: f64 = 20.0;
const KD: f64 = 5.0;
const LAW: &str = "F=-kp*x - kd*x'";

fn adaptive(method: &str) -> bool {
    sim::Method::from_name(method).expect("a method").is_adaptive()
}

fn run(method: &str, hold: Option<f64>, until: f64, samples: usize) -> Outcome {
    let options = Options {
        input: vec![LAW.parse().expect("an assignment")],
        hold,
        method: Some(method.into()),
        // Each method is given the setting it uses; the other would be refused.
        tolerance: adaptive(method).then_some(1e-12),
        step: (!adaptive(method)).then_some(1e-3),
        until: Some(until),
        output: vec!["x, x', F".into()],
        samples,
        ..Options::default()
    };
    let outcome = simulate(BLOCK, &options).expect("runs");
    assert!(outcome.run.fault.is_none(), "{method}: {:?}", outcome.run.fault);
    outcome
}

/// The state (x, ẋ) at each sample time k·T and the force held from it, k = 0 … n, from the
/// exact transition over one period of the plant ẋ = (v, (−k·x + u)/m): with ω² = k/m,
/// Φ = [[cos ωT, sin ωT/ω], [−ω·sin ωT, cos ωT]] and Γ = ∫₀ᵀ e^{Aτ}·B dτ =
/// ((1 − cos ωT)/k, sin ωT/(m·ω)).
fn exact(period: f64, n: usize) -> Vec<([f64; 2], f64)> {
    let w = (STIFFNESS / MASS).sqrt();
    let (c, s) = (apply(cas::Func::Cos, w * period), apply(cas::Func::Sin, w * period));
    let phi = [[c, s / w], [-w * s, c]];
    let gamma = [(1.0 - c) / STIFFNESS, s / (MASS * w)];
    let mut state = [0.1, 0.0];
    let mut samples = Vec::new();
    for _ in 0..=n {
        let u = -KP * state[0] - KD * state[1];
        samples.push((state, u));
        state = [
            phi[0][0] * state[0] + phi[0][1] * state[1] + gamma[0] * u,
            phi[1][0] * state[0] + phi[1][1] * state[1] + gamma[1] * u,
        ];
    }
    samples
}

/// The largest difference between the run's rows and the exact held solution: (x, ẋ) at each
/// sample time, and the force at every recorded time (the one held since the last sample).
fn worst(outcome: &Outcome, period: f64, exact: &[([f64; 2], f64)]) -> (f64, f64) {
    let (mut state, mut force) = (0.0f64, 0.0f64);
    let trajectory = &outcome.run.trajectory;
    for (t, row) in trajectory.times.iter().zip(&trajectory.rows) {
        let k = (t / period + 1e-9).floor() as usize;
        let ([x, v], u) = exact[k];
        if (t - k as f64 * period).abs() < 1e-12 {
            state = state.max((row[0] - x).abs()).max((row[1] - v).abs());
        }
        force = force.max((row[2] - u).abs());
    }
    (state, force)
}

#[test]
fn a_held_feedback_meets_the_exact_discrete_time_solution() {
    let (period, until) = (0.1, 3.0);
    let exact = exact(period, 30);
    // Every accepted step, and evenly spaced samples on the hold's own grid (k·T and k·3/30
    // differ by an ulp at some k: the row there must still show the new sample).
    for (method, samples) in [
        ("dop853", 0),
        ("dop853", 31),
        ("dopri5", 0),
        ("auto", 0),
        ("radau", 0),
        ("rk4", 0),
        ("gauss", 0),
    ] {
        let outcome = run(method, Some(period), until, samples);
        let times = &outcome.run.trajectory.times;
        let on_samples =
            (0..=30).filter(|k| times.iter().any(|t| (t - *k as f64 * period).abs() < 1e-12));
        assert_eq!(on_samples.count(), 31, "{method}: a row at every sample time");
        let (state, force) = worst(&outcome, period, &exact);
        assert!(state < 1e-9, "{method} with {samples} samples: the state is off by {state:e}");
        assert!(force < 1e-9, "{method} with {samples} samples: the force is off by {force:e}");
    }
}

#[test]
fn the_held_force_is_constant_between_samples_and_jumps_at_them() {
    let outcome = run("dop853", Some(0.25), 1.0, 0);
    let trajectory = &outcome.run.trajectory;
    let held: Vec<(f64, f64)> =
        trajectory.times.iter().zip(&trajectory.rows).map(|(t, r)| (*t, r[2])).collect();
    for interval in 0..4 {
        let (from, to) = (interval as f64 * 0.25, (interval + 1) as f64 * 0.25);
        let inside: Vec<f64> =
            held.iter().filter(|(t, _)| *t >= from && *t < to).map(|(_, f)| *f).collect();
        assert!(inside.len() > 1, "steps inside [{from}, {to})");
        assert!(inside.iter().all(|f| *f == inside[0]), "held over [{from}, {to}): {inside:?}");
    }
    // The continuous law moves with the state at every step.
    let free = run("dop853", None, 1.0, 0);
    let forces: Vec<f64> = free.run.trajectory.rows.iter().map(|r| r[2]).collect();
    assert!(forces.windows(2).all(|w| w[0] != w[1]));
}

#[test]
fn a_short_period_approaches_the_continuous_law() {
    let continuous = run("dop853", None, 1.0, 0).run.final_state;
    let gap = |period: f64| {
        let held = run("dop853", Some(period), 1.0, 0).run.final_state;
        held.iter().zip(&continuous).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
    };
    let (coarse, fine) = (gap(1e-2), gap(1e-3));
    // A hold lags the law by half a period on average: the gap is first order in T.
    assert!(fine < 1e-3, "at T = 1 ms the held run is {fine:e} from the continuous one");
    assert!(coarse / fine > 5.0 && coarse / fine < 20.0, "gaps {coarse:e} and {fine:e}");
}

#[test]
fn the_scene_holds_as_the_option_does() {
    let scene = format!("{BLOCK}simulate {{ input {LAW}; hold 100 ms; until 1 s; output x, F }}\n");
    let from_scene = simulate(&scene, &Options { samples: 0, ..Options::default() }).expect("runs");
    let given = Options {
        input: vec![LAW.parse().expect("an assignment")],
        hold: Some(0.1),
        until: Some(1.0),
        output: vec!["x, F".into()],
        samples: 0,
        ..Options::default()
    };
    let from_options = simulate(BLOCK, &given).expect("runs");
    assert_eq!(from_scene.run.trajectory.rows, from_options.run.trajectory.rows);
    let exact = exact(0.1, 10);
    let last = from_scene.run.trajectory.rows.last().expect("rows");
    assert!((last[0] - exact[10].0[0]).abs() < 1e-9, "{} against {}", last[0], exact[10].0[0]);
}

#[test]
fn a_hold_with_nothing_to_hold_or_no_period_is_refused() {
    let error = |options: Options| simulate(BLOCK, &options).err().expect("refused").to_string();
    let nothing = error(Options { hold: Some(0.1), ..Options::default() });
    assert!(nothing.contains("`hold` samples the laws that drive inputs"), "{nothing}");
    let law = vec![LAW.parse().expect("an assignment")];
    let zero = error(Options { hold: Some(0.0), input: law, ..Options::default() });
    assert!(zero.contains("`hold` must be a positive time, not 0"), "{zero}");
}
