//! Stability at the extremes: mass ratios from 1e-9 to 1e9, lengths and masses from 1e-6 to
//! 1e6, a start a hair from the unstable equilibrium, a million steps, a stiff spring and a
//! near-singular mass matrix. Each test asserts a correct result (or a clear error); none is
//! timed.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use bench::reference::{elliptic_k, gauss_legendre};
use cli::simulate::summary;
use engine::numbers::prepare;
use numeric::Tape;
use sim::{FaultKind, Mechanical, Problem};
use simulation::{simulate, Options, Outcome};

fn example(rel: &str) -> String {
    std::fs::read_to_string(lagrange_tests::examples_dir().join(rel)).expect("example")
}

fn run(rel: &str, source: &str, options: Options) -> Outcome {
    let outcome = simulate(source, &options).unwrap_or_else(|e| panic!("{rel}: {e}"));
    assert!(outcome.run.fault.is_none(), "{}", summary(&outcome));
    outcome
}

/// The accelerations of a scene at state `y` with the given parameter values, through the
/// lowered tape and the solve the integrators use.
fn accelerations(
    rel: &str,
    source: &str,
    set: &dyn Fn(&[String], &mut [f64]),
    y: &[f64],
) -> Result<Vec<f64>, FaultKind> {
    let mut p =
        prepare(source, &[], engine::Options::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let names: Vec<String> = p.derivation.model.params.iter().map(|q| q.name.clone()).collect();
    let mut values = p.parameter_values(&[]).expect("values");
    set(&names, &mut values);
    let exprs = p.dynamics_exprs();
    let dynamics = p.lower(&p.dynamics_inputs(), &exprs).expect("lowers");
    let observation = p.lower(&p.observation_inputs(), &[]).expect("lowers");
    let mut m = Mechanical::new(p.layout, Tape::new(dynamics), Tape::new(observation), values);
    let mut dy = vec![0.0; y.len()];
    m.rhs(0.0, y, &mut dy)?;
    Ok(dy[y.len() / 2..].to_vec())
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
}

#[test]
fn wedge_accelerations_hold_for_mass_ratios_from_1e_minus_9_to_1e9() {
    let source = example("ps5/wedge.lag");
    let (m, g, theta) = (1.0f64, 9.81f64, std::f64::consts::FRAC_PI_6);
    for k in -9..=9 {
        let ratio = 10f64.powi(k);
        let big_m = ratio * m;
        let set = |names: &[String], v: &mut [f64]| {
            let at = |n: &str| names.iter().position(|x| x == n).expect("parameter");
            v[at("M")] = big_m;
            v[at("m")] = m;
        };
        // q = (x, s); the accelerations do not depend on the state.
        let a = accelerations("wedge.lag", &source, &set, &[0.3, 0.7, -0.2, 0.4]).unwrap();
        let (sin, cos) = theta.sin_cos();
        let denominator = big_m + m * sin * sin;
        let s_exact = g * sin * (big_m + m) / denominator;
        let x_exact = -m * g * sin * cos / denominator;
        assert!(relative(a[1], s_exact) < 1e-12, "M/m = {ratio:e}: s'' = {} vs {s_exact}", a[1]);
        assert!(relative(a[0], x_exact) < 1e-12, "M/m = {ratio:e}: x'' = {} vs {x_exact}", a[0]);
    }
}

#[test]
fn the_pendulum_period_is_scale_free_from_1e_minus_6_to_1e6() {
    let source = example("classics/simple_pendulum.lag");
    let (g, theta0) = (9.81f64, 0.5f64);
    let exact = 4.0 * elliptic_k((theta0 / 2.0).sin());
    let mut reference = None;
    for (l, m) in [("1/1000000", "1"), ("1", "1/1000000"), ("1", "1"), ("1000000", "1000000")] {
        let length: f64 = {
            let (a, b) = l.split_once('/').unwrap_or((l, "1"));
            a.parse::<f64>().unwrap() / b.parse::<f64>().unwrap()
        };
        let scale = (length / g).sqrt();
        // Released from rest, θ' next vanishes at half a period.
        let outcome = run(
            "simple_pendulum.lag",
            &source,
            Options {
                method: Some("dop853".into()),
                tolerance: Some(1e-13),
                until: Some(2.0 * exact * scale),
                stop_when: vec!["theta'".into()],
                set: vec![
                    format!("L={l}").parse().expect("name=value"),
                    format!("m={m}").parse().expect("name=value"),
                ],
                ..Options::default()
            },
        );
        let dimensionless = 2.0 * outcome.run.final_time / scale;
        assert!(relative(dimensionless, exact) < 1e-10, "L = {l}, m = {m}: {dimensionless}");
        let r = *reference.get_or_insert(dimensionless);
        assert!(relative(dimensionless, r) < 1e-10, "L = {l}, m = {m}: {dimensionless} vs {r}");
    }
}

#[test]
fn a_rod_released_1e_minus_8_from_vertical_lands_when_the_energy_integral_says() {
    let source = example("ps5/falling_rod.lag");
    let (l, g, theta0) = (1.0f64, 9.81f64, 1e-8f64);
    // T = ∫ dθ/θ' from θ0 to π/2 with θ'² = 12 g (cos θ0 − cos θ) / (L (1 + 3 sin² θ)). Near
    // θ0 the motion is exponential escape, θ ≈ θ0 cosh(√(6g/L) t), so θ = θ0 cosh w makes
    // the integrand smooth; cos θ0 − cos θ = 2 sin((θ + θ0)/2) sin((θ − θ0)/2) with
    // θ − θ0 = 2 θ0 sinh²(w/2) keeps every digit where θ is still close to θ0.
    let end = (std::f64::consts::FRAC_PI_2 / theta0).acosh();
    let integrand = |w: f64| {
        let theta = theta0 * w.cosh();
        let gap = 2.0 * theta0 * (w / 2.0).sinh().powi(2);
        let drop = 2.0 * ((theta + theta0) / 2.0).sin() * (gap / 2.0).sin();
        let rate = (12.0 * g * drop / (l * (1.0 + 3.0 * theta.sin().powi(2)))).sqrt();
        theta0 * w.sinh() / rate
    };
    let exact = gauss_legendre(integrand, 0.0, end, 20_000);
    // The fall time grows like ln(1/θ0): about 2.4 s here, against 0.5 s from π/6.
    assert!(exact > 2.0, "{exact}");
    // The tolerance is absolute as well as relative, and θ starts at 1e-8: at 1e-14 the first
    // steps may lose 1e-6 of θ0, which shifts the landing by ~3e-9 relative (measured). At
    // 1e-16 (174 steps) the landing agrees to ~6e-11.
    let outcome = run(
        "falling_rod.lag",
        &source,
        Options {
            method: Some("dop853".into()),
            tolerance: Some(1e-16),
            until: Some(10.0),
            set: vec!["theta=1/100000000".parse().expect("name=value")],
            ..Options::default()
        },
    );
    assert!(outcome.run.stopped_by.is_some(), "{}", summary(&outcome));
    let landed = outcome.run.final_time;
    assert!(relative(landed, exact) < 1e-10, "landed at {landed}, energy integral {exact}");
}

#[test]
fn a_million_steps_symplectic_energy_stays_bounded_while_rk4_drifts() {
    let source = example("classics/simple_pendulum.lag");
    let energy_error = |method: &str| {
        let outcome = run(
            "simple_pendulum.lag",
            &source,
            Options {
                method: Some(method.into()),
                step: Some(0.01),
                until: Some(10_000.0),
                set: vec!["theta=2".parse().expect("name=value")],
                output: vec!["theta".into()],
                ..Options::default()
            },
        );
        assert!(outcome.run.steps >= 1_000_000, "{}", outcome.run.steps);
        let e = outcome.energy();
        let e0 = e[0];
        let tenth = e.len() / 10;
        let worst = |s: &[f64]| s.iter().map(|v| (v - e0).abs()).fold(0.0, f64::max);
        (worst(&e[..tenth]), worst(&e[e.len() - tenth..]), e0.abs())
    };
    let (gauss_early, gauss_late, scale) = energy_error("gauss");
    let (rk4_early, rk4_late, _) = energy_error("rk4");
    // Gauss–Legendre is symplectic: its energy error oscillates and does not grow.
    assert!(gauss_late < 1.5 * gauss_early, "gauss: {gauss_early:e} then {gauss_late:e}");
    assert!(gauss_late < 1e-6 * scale, "gauss: {gauss_late:e}");
    // RK4 is not: its (dissipative) error grows with time and ends far above Gauss's.
    assert!(rk4_late > 5.0 * rk4_early, "rk4: {rk4_early:e} then {rk4_late:e}");
    assert!(rk4_late > 10.0 * gauss_late, "rk4 {rk4_late:e} vs gauss {gauss_late:e}");
    eprintln!(
        "10^6 steps of h = 0.01 from θ = 2: gauss |ΔE| ≤ {gauss_late:.2e}, rk4 drift \
         {rk4_early:.2e} → {rk4_late:.2e} (E scale {scale:.2})"
    );
}

/// A bob on a stiff spring (k/m = 1e8) swinging slowly as a pendulum.
const STIFF: &str = "scene \"stiff elastic pendulum\"
param m = 1 kg, k = 100000000 N/m, L = 1 m, g = 9.81 m/s^2
coord r = L + m*g/k
coord theta = 1/2
particle bob { mass m; position (r*sin(theta), -r*cos(theta)) }
potential k/2*(r - L)^2
gravity g
";

#[test]
fn a_stiff_spring_in_a_slow_system_stays_stable_and_is_reported_as_stiff() {
    for method in ["dopri5", "dop853"] {
        let outcome = run(
            "stiff.lag",
            STIFF,
            Options {
                method: Some(method.into()),
                tolerance: Some(1e-6),
                until: Some(2.0),
                ..Options::default()
            },
        );
        let (_, relative) = outcome.energy_drift();
        assert!(relative < 1e-4, "{method}: energy drift {relative:e}");
        // The pendulum alone needs tens of steps at this tolerance; the spring's period
        // 2π·1e-4 s forces thousands: the step count reflects the stiffness.
        let r = &outcome.run;
        assert!(r.steps > 2_000, "{method}: {} steps", r.steps);
        assert!(r.stiff_steps * 10 >= r.steps, "{method}: {} of {} stiff", r.stiff_steps, r.steps);
        let summary = summary(&outcome);
        assert!(summary.contains("limited by stability"), "{summary}");
    }
}

#[test]
fn a_link_of_mass_1e_minus_12_gives_right_accelerations_or_a_clear_error() {
    let source = example("classics/double_pendulum.lag");
    let (m1, l1, l2, g) = (1.0f64, 1.0f64, 1.0f64, 9.81f64);
    let (t1, t2, w1, w2) = (0.4f64, -0.9f64, 0.3f64, -1.1f64);
    for m2 in [1e-6, 1e-9, 1e-12, 1e-15] {
        let set = |names: &[String], v: &mut [f64]| {
            let at = |n: &str| names.iter().position(|x| x == n).expect("parameter");
            v[at("m2")] = m2;
        };
        // The textbook closed form, free of cancellation for a light second bob.
        let d = t1 - t2;
        let den = 2.0 * m1 + m2 - m2 * (2.0 * d).cos();
        let a1 = (-g * (2.0 * m1 + m2) * t1.sin()
            - m2 * g * (t1 - 2.0 * t2).sin()
            - 2.0 * d.sin() * m2 * (w2 * w2 * l2 + w1 * w1 * l1 * d.cos()))
            / (l1 * den);
        let a2 = 2.0
            * d.sin()
            * (w1 * w1 * l1 * (m1 + m2) + g * (m1 + m2) * t1.cos() + w2 * w2 * l2 * m2 * d.cos())
            / (l2 * den);
        match accelerations("double.lag", &source, &set, &[t1, t2, w1, w2]) {
            Ok(a) => {
                // Correct to the digits the conditioning (about 1/m2) leaves.
                let tolerance = 1e-15 / m2;
                assert!(relative(a[0], a1) < tolerance, "m2 = {m2:e}: θ1'' {} vs {a1}", a[0]);
                assert!(relative(a[1], a2) < tolerance, "m2 = {m2:e}: θ2'' {} vs {a2}", a[1]);
            }
            Err(FaultKind::SingularMass { coordinates, condition }) => {
                // A clear error names the coordinate whose inertia vanishes.
                assert!(m2 < 1e-12, "m2 = {m2:e} should still solve (condition {condition:e})");
                assert_eq!(coordinates, [1], "m2 = {m2:e}");
            }
            Err(other) => panic!("m2 = {m2:e}: {other:?}"),
        }
    }
}
