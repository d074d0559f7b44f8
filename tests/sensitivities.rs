//! The state's sensitivities to the parameters, S = ∂x(t)/∂p, carried beside Φ by a
//! variational run, against central differences of whole runs in each parameter: a damped
//! pendulum (its damping and length), the driven one of the orbits' examples (its drive's
//! amplitude and frequency), a pendulum kept on its rod by a multiplier (the rod's length in
//! Φ and in the start), Chaplygin's sleigh (a kept velocity constraint), and a physical
//! pendulum whose inertia is derived from its mass and length; and the runs S is refused for,
//! by name (across a jump, at an event, with friction, with held inputs).

use std::ops::ControlFlow;

use engine::numbers::{prepare, Prepared};
use sim::variational::{transition_with, End, Options, Refusal};
use sim::Method;

fn settings(until: f64) -> sim::Settings {
    sim::Settings {
        method: Method::Dop853,
        start: 0.0,
        until,
        tolerance: 1e-13,
        step: 1e-3,
        max_steps: 1_000_000,
        samples: 0,
    }
}

/// The free parameters `names` by index.
fn indices(prepared: &Prepared, names: &[&str]) -> Vec<usize> {
    let plan = &prepared.parameter_plan;
    names
        .iter()
        .map(|name| plan.names().position(|n| n == *name).expect("a parameter of the scene"))
        .collect()
}

/// The scene's mechanical problem with its sensitivity program by the parameters `free`.
fn with_sensitivities(
    prepared: &mut Prepared,
    parameters: &[f64],
    free: &[usize],
) -> sim::Mechanical {
    let mut problem = lagrange_tests::mechanical(prepared, parameters);
    let program = prepared.sensitivity_program(free).expect("lowers");
    problem.set_sensitivities(numeric::Tape::new(program), free.len());
    problem
}

/// The largest entry of S at the end of a variational run of `source` over `until`, from the
/// scene's start, less the central differences of whole runs in each of the parameters
/// `names` (the start moved with them, derived parameters following), relative to S's largest
/// entry; and that largest entry.
fn sensitivities_against_differences(source: &str, names: &[&str], until: f64) -> (f64, f64) {
    against_differences(source, names, until, true)
}

/// [`sensitivities_against_differences`], S(0) from the scene's start (`from_scene`) or zero,
/// for a start that does not move with `names` but that the kept constraints solve for.
fn against_differences(source: &str, names: &[&str], until: f64, from_scene: bool) -> (f64, f64) {
    let mut prepared = prepare(source, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, names);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let mut problem = with_sensitivities(&mut prepared, &parameters, &free);
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let s0 = if from_scene {
        prepared.start_sensitivity(&parameters, &[], &free).expect("the start's derivative")
    } else {
        vec![0.0; y0.len() * free.len()]
    };
    let run = settings(until);
    let options = Options { sensitivities: Some(s0), ..Default::default() };
    let exact = transition_with(&mut problem, &y0, &run, End::Time, &options).expect("runs");
    let s = exact.sensitivities.expect("S was asked for");
    let (d, k) = (y0.len(), free.len());
    assert_eq!(s.len(), d * k);
    let largest = s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut end_of = |values: &[f64]| {
        let start = prepared.initial_state(values, &[]).expect("a start");
        problem.set_parameters(values);
        let r = sim::integrate(&mut problem, &start, &run, &[], &mut |_| ControlFlow::Continue(()));
        assert!(r.fault.is_none() && r.final_time == until);
        r.final_state
    };
    let mut worst = 0.0f64;
    for (j, &i) in free.iter().enumerate() {
        // The differences' truncation goes as the step's square: 3.5e-7 of the damped
        // pendulum's S at 1e-4, 3.5e-9 at 1e-5, where the runs' tolerance is still far below.
        let step = 1e-5 * (1.0 + parameters[i].abs());
        let moved = |by: f64| {
            let given = [(i, parameters[i] + by)];
            prepared.parameter_values_given(&[], &given).expect("values")
        };
        let (up, down) = (moved(step), moved(-step));
        let (up, down) = (end_of(&up), end_of(&down));
        for r in 0..d {
            let differenced = (up[r] - down[r]) / (2.0 * step);
            worst = worst.max((s[r * k + j] - differenced).abs() / largest);
        }
    }
    (worst, largest)
}

#[test]
fn a_damped_pendulums_sensitivities_are_what_differences_of_whole_runs_give() {
    let pendulum = "param m = 1 kg, l = 1 m, g = 9.81 m/s^2, c = 1/2 N*m*s
coord theta = 6/5, theta' = -7/10
body bob { mass m; inertia 0; position (l*sin(theta), -l*cos(theta)); angle theta }
gravity g
dissipation c/2*theta'^2
";
    let (worst, largest) = sensitivities_against_differences(pendulum, &["c", "l"], 2.5);
    eprintln!("the damped pendulum's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the damped pendulum's S is off by {worst:.1e}");
    // Driven from rest: the response is the drive's alone, and so is S by its amplitude.
    let driven = lagrange_tests::example("orbits/driven_pendulum.lag");
    let (worst, largest) = sensitivities_against_differences(&driven, &["c", "l", "A", "w"], 3.0);
    eprintln!("the driven pendulum's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the driven pendulum's S is off by {worst:.1e}");
}

/// S recorded at a fit's data times on the way, each against differences of whole runs to
/// that time; the last, at the end, is the end's.
#[test]
fn sensitivities_are_recorded_at_given_times() {
    let source = "param m = 1 kg, l = 1 m, g = 9.81 m/s^2, c = 1/2 N*m*s
coord theta = 6/5, theta' = -7/10
body bob { mass m; inertia 0; position (l*sin(theta), -l*cos(theta)); angle theta }
gravity g
dissipation c/2*theta'^2
";
    let mut prepared = prepare(source, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, &["l", "c"]);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let mut problem = with_sensitivities(&mut prepared, &parameters, &free);
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let s0 = prepared.start_sensitivity(&parameters, &[], &free).expect("the start's derivative");
    let times = vec![0.0, 0.35, 1.0, 1.7, 2.0];
    let options = Options { sensitivities: Some(s0), times: times.clone(), ..Default::default() };
    let exact =
        transition_with(&mut problem, &y0, &settings(2.0), End::Time, &options).expect("runs");
    let recorded: Vec<f64> = exact.samples.iter().map(|s| s.time).collect();
    assert_eq!(recorded, times);
    let last = exact.samples.last().expect("the end's");
    assert_eq!(last.sensitivities, exact.sensitivities);
    assert_eq!((&last.state, &last.matrix), (&exact.state, &exact.matrix));
    assert_eq!(exact.samples[0].sensitivities, Some(vec![0.0; 4]), "S(0): the start holds none");
    let mut worst = 0.0f64;
    for sample in &exact.samples[1..] {
        let s = sample.sensitivities.as_ref().expect("S was asked for");
        let largest = s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let run = settings(sample.time);
        for (j, &i) in free.iter().enumerate() {
            let step = 1e-5 * (1.0 + parameters[i].abs());
            let mut end_of = |by: f64| {
                let values = prepared.parameter_values_given(&[], &[(i, parameters[i] + by)]);
                problem.set_parameters(&values.expect("values"));
                let mut go = |_: f64| ControlFlow::Continue(());
                sim::integrate(&mut problem, &y0, &run, &[], &mut go).final_state
            };
            let (up, down) = (end_of(step), end_of(-step));
            for r in 0..2 {
                let differenced = (up[r] - down[r]) / (2.0 * step);
                worst = worst.max((s[r * 2 + j] - differenced).abs() / largest);
            }
        }
        problem.set_parameters(&parameters);
    }
    eprintln!("S at the recorded times against differences: {worst:.1e}");
    assert!(worst < 1e-7, "S at a recorded time is off by {worst:.1e}");
    let backwards = Options { times: vec![1.0, 0.5], ..Default::default() };
    let refused = transition_with(&mut problem, &y0, &settings(2.0), End::Time, &backwards);
    assert_eq!(refused.unwrap_err(), Refusal::SampleTime { time: 0.5 });
}

#[test]
fn a_kept_rods_length_moves_its_constraint_and_its_start() {
    // The rod's length is in Φ (and so in the stabilisation) and in the start, on the rod.
    let cartesian = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2, w = 8/5 rad/s
coord x = L*sin(3/5), x' = w*L*cos(3/5)
coord y = -L*cos(3/5), y' = w*L*sin(3/5)
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";
    let (worst, largest) = sensitivities_against_differences(cartesian, &["L", "m", "g", "w"], 1.5);
    eprintln!("the Cartesian pendulum's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the Cartesian pendulum's S is off by {worst:.1e}");
    // A start that stays where it is as L moves leaves the rod at other lengths: there the
    // stabilisation's pull back onto it, by Φ's and Φ̇'s partials in L, is what S follows.
    let fixed = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord x = 3/5 m, y = -4/5 m
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";
    let (worst, largest) = sensitivities_against_differences(fixed, &["L"], 1.5);
    eprintln!("the rod off its length's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the rod off its length's S is off by {worst:.1e}");
    // A velocity constraint, stabilised on its residual alone: Chaplygin's sleigh, whose
    // blade's offset a moves its inertia about the contact and its drift. Its start's lateral
    // rate is the blade's to give, 0 whatever m, I and a.
    let sleigh = lagrange_tests::example("classics/chaplygin_sleigh.lag");
    let (worst, largest) = against_differences(&sleigh, &["m", "I", "a"], 3.0, false);
    eprintln!("the sleigh's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the sleigh's S is off by {worst:.1e}");
    // The example itself, from rest at the bottom: S follows y = −L there and nothing moves.
    let example = lagrange_tests::example("classics/pendulum_cartesian.lag");
    let (worst, largest) = sensitivities_against_differences(&example, &["L"], 1.0);
    assert!((largest - 1.0).abs() < 1e-9, "∂y/∂L = −1 all along, not {largest}");
    assert!(worst < 1e-7, "the example's S is off by {worst:.1e}");
}

#[test]
fn a_derived_inertia_follows_its_mass_and_length() {
    // A rod about its end, I = m·L²/12 about its centre, moves with m and L, which are what a
    // user sets.
    let rod = "param L = 1 m, m = 2 kg, I = m*L^2/12, g = 9.81 m/s^2, c = 1/10 N*m*s
coord theta = 1, theta' = 1/2
body rod { mass m; inertia I; position (L/2*sin(theta), -L/2*cos(theta)); angle theta }
gravity g
dissipation c/2*theta'^2
";
    let (worst, largest) = sensitivities_against_differences(rod, &["L", "m", "c"], 2.0);
    eprintln!("the physical pendulum's S (largest {largest:.2}) against differences: {worst:.1e}");
    assert!(worst < 1e-7, "the physical pendulum's S is off by {worst:.1e}");
    let mut prepared = prepare(rod, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, &["m"]);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let mut problem = with_sensitivities(&mut prepared, &parameters, &free);
    let mut change = vec![f64::NAN; 1];
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    assert!(problem.parameter_derivative(0.0, &y0, &mut change).expect("evaluates"));
    // θ̈ = −(c·θ̇ + m·g·L/2·sin θ)/(m·L²/3), so ∂θ̈/∂m = c·θ̇/(m²·L²/3): the damping's torque
    // does not grow with the mass, and gravity's share cancels only if I moves with m.
    let (l, m, c) = (1.0, 2.0, 0.1);
    let expected = c * y0[1] / (m * m * l * l / 3.0);
    assert!((change[0] - expected).abs() < 1e-14, "∂θ̈/∂m = {} against {expected}", change[0]);
    // A start the kept constraints solve for moves with the parameters through the solve.
    let solved = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2
coord x = 3/5 m
coord y ~ -1 m
particle bob { mass m; position (x, y) }
constraint rod: x^2 + y^2 = L^2
gravity g
";
    let mut solved = prepare(solved, &[], engine::Options::default()).expect("derives");
    let values = solved.parameter_values(&[]).expect("values");
    let free = indices(&solved, &["L"]);
    let refused = solved.start_sensitivity(&values, &[], &free).unwrap_err().to_string();
    assert!(refused.contains("the start of `y` is left to the kept constraints"), "{refused}");
    // A derived parameter is not one to vary.
    let derived = indices(&prepared, &["I"]);
    let refused = prepared.sensitivity_program(&derived).map(|_| ()).unwrap_err();
    assert_eq!(
        refused.to_string(),
        "error: no sensitivity is taken by a derived parameter: parameter `I` is derived from `L` and \
         `m`; set `L` and `m` instead"
    );
}

#[test]
fn sensitivities_are_refused_across_a_jump_and_at_an_event() {
    let ball = lagrange_tests::example("contacts/bouncing_ball.lag");
    let mut prepared = prepare(&ball, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, &["g", "h0"]);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let contacts = lagrange_tests::contacts(&prepared, &parameters);
    let mut problem = with_sensitivities(&mut prepared, &parameters, &free).with_contacts(contacts);
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let s0 = prepared.start_sensitivity(&parameters, &[], &free).expect("the start's derivative");
    // ∂y(0)/∂h0 = 1, the ball dropped from h0.
    assert_eq!(s0, [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    let options = Options { sensitivities: Some(s0.clone()), ..Default::default() };
    let run = settings(1.0);
    let refused = transition_with(&mut problem, &y0, &run, End::Time, &options).unwrap_err();
    let Refusal::SensitivitiesAcrossJump { time, .. } = refused else {
        panic!("refused as {refused:?}")
    };
    // The first impact, at sqrt(2·h0/g).
    assert!((time - (2.0f64 / 9.81).sqrt()).abs() < 1e-9, "refused at {time}");
    let landing = End::Landing { contact: None };
    let refused = transition_with(&mut problem, &y0, &run, landing, &options).unwrap_err();
    assert_eq!(refused, Refusal::SensitivitiesAtEvent);
    let short = Options { sensitivities: Some(s0[..4].to_vec()), ..Default::default() };
    let refused = transition_with(&mut problem, &y0, &run, End::Time, &short).unwrap_err();
    assert_eq!(refused, Refusal::SensitivityStart { expected: 8, given: 4 });
    // A block sliding up a rough incline has no jump for a while, but its friction force
    // holds μ outside the sensitivity program.
    let block = lagrange_tests::example("friction/block_on_incline.lag");
    let mut prepared = prepare(&block, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, &["mu"]);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let contacts = lagrange_tests::contacts(&prepared, &parameters);
    let mut sliding = with_sensitivities(&mut prepared, &parameters, &free).with_contacts(contacts);
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let options = Options { sensitivities: Some(vec![0.0; y0.len()]), ..Default::default() };
    let refused = transition_with(&mut sliding, &y0, &settings(0.1), End::Time, &options);
    assert_eq!(refused.unwrap_err(), Refusal::SensitivitiesWithFriction);
    // A drive's amplitude held between samples moves with the parameters at each sample.
    let driven = lagrange_tests::example("orbits/driven_pendulum.lag");
    let mut prepared = prepare(&driven, &[], engine::Options::default()).expect("derives");
    let free = indices(&prepared, &["A"]);
    let parameters = prepared.parameter_values(&[]).expect("values");
    let law = prepared.derivation.model.pool.sym(prepared.parameters[free[0]]);
    let laws = prepared.lower(&prepared.dynamics_inputs(), &[law]).expect("lowers");
    let hold = sim::Hold::new(0.1, free.clone(), numeric::Tape::new(laws));
    let mut held = with_sensitivities(&mut prepared, &parameters, &free).with_hold(hold);
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let options = Options { sensitivities: Some(vec![0.0; y0.len()]), ..Default::default() };
    let refused = transition_with(&mut held, &y0, &settings(0.5), End::Time, &options);
    assert_eq!(refused.unwrap_err(), Refusal::SensitivitiesWithHold);
}
