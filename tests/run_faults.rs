//! What a run meets on the way and must not get wrong silently: a stop condition or an event
//! whose expression leaves its domain (NaN) within a step, alone and in the lockstep of an
//! ensemble.

use ::ensemble::{Ensemble, Options as EnsembleOptions};
use engine::input::Vary;
use sim::{FaultKind, NonFiniteAt};
use simulation::{simulate, Options};

/// x'' = −(k/m)·x from x = 1 at rest: x = cos(√(k/m)·t).
const OSCILLATOR: &str = "scene \"Oscillator\"\nparam m = 1, k = 1\ncoord x = 1\n\
                          particle p { mass m; position (x, 0) }\npotential k/2*x^2\n";

/// √(x − 0.9) − 0.1 is zero where x = 0.91 and NaN once x < 0.9, a little later: a step that
/// ends past that sees no sign, only a NaN.
const THROUGH_NAN: &str = "sqrt(x - 0.9) - 0.1";

// The root's last bit shows nowhere in the tolerance it is checked to.
#[allow(clippy::disallowed_methods)]
fn root(k: f64) -> f64 {
    0.91f64.acos() / k.sqrt()
}

#[test]
fn a_stop_condition_that_passes_through_nan_stops_the_run_at_its_root() {
    let options =
        Options { until: Some(1.0), stop_when: vec![THROUGH_NAN.into()], ..Options::default() };
    let outcome = simulate(OSCILLATOR, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    assert_eq!(outcome.run.stopped_by, Some(0), "{}", cli::simulate::summary(&outcome));
    let off = (outcome.run.final_time - root(1.0)).abs();
    assert!(off < 1e-9, "stopped at {}, the root is at {}", outcome.run.final_time, root(1.0));
    let summary = cli::simulate::summary(&outcome);
    assert!(summary.contains("stopped at t = 0.4275"), "{summary}");
}

#[test]
fn an_event_that_passes_through_nan_is_recorded() {
    for method in ["dop853", "dopri5", "radau", "auto"] {
        let options = Options {
            until: Some(1.0),
            method: Some(method.into()),
            events: vec![THROUGH_NAN.into()],
            ..Options::default()
        };
        let outcome = simulate(OSCILLATOR, &options).unwrap_or_else(|e| panic!("{e}"));
        let hits = &outcome.run.events;
        assert_eq!(hits.len(), 1, "{method}: {hits:?}");
        // radau's collocation polynomial keeps the time to its own accuracy: 4e-9 here.
        assert!((hits[0].time - root(1.0)).abs() < 1e-8, "{method}: {hits:?}");
    }
}

/// The ensemble's lockstep locates its stops with the same code: each run stops at its own
/// root, side by side as alone.
#[test]
fn an_ensemble_stops_through_nan_in_lockstep_and_alone() {
    let options = EnsembleOptions {
        simulate: Options {
            until: Some(2.0),
            stop_when: vec![THROUGH_NAN.into()],
            ..Options::default()
        },
        vary: vec![Vary::parse("k=1:4:11").expect("an axis")],
        record: vec!["t".into()],
        ..EnsembleOptions::default()
    };
    let mut ensemble = Ensemble::new(OSCILLATOR, &options).expect("loads");
    let side_by_side = ensemble.run(0..ensemble.runs(), 1, &mut ());
    ensemble.set_lockstep(false);
    let alone = ensemble.run(0..ensemble.runs(), 1, &mut ());
    for table in [&side_by_side, &alone] {
        assert!(table.failures.iter().all(Option::is_none), "{:?}", table.failures);
        for row in &table.rows {
            let (k, t) = (row[0], row[1]);
            assert!((t - root(k)).abs() < 1e-9, "k = {k}: stopped at {t}, root at {}", root(k));
        }
    }
}

/// m·ẍ = −k·x + F, F an input.
const PUSHED: &str = "scene \"A pushed block\"\nparam m = 2 kg, k = 8 N/m\ninput F = 0 N\n\
                      coord x = 0.1\nparticle block { mass m; position (x, 0) }\n\
                      potential k/2*x^2\nforce push on block: (F, 0)\n";

/// A push F = e^(t + 700) (in N, t in s), already at e^700 ≈ 1e304 N at the start: the rates'
/// weighted norm overflowed, the first step came out 0, and the run faulted at once with "the
/// step size fell to 0". Every step's error is weighed in that norm, so no step can be
/// controlled: the fault now names the rate that overflows it and why.
#[test]
fn a_push_beyond_the_step_controls_range_is_named() {
    for method in ["dop853", "dopri5", "radau", "auto"] {
        let options = Options {
            until: Some(1.0),
            method: Some(method.into()),
            input: vec!["F=exp(t + 700)".parse().expect("an assignment")],
            no_units: true,
            ..Options::default()
        };
        let outcome = simulate(PUSHED, &options).unwrap_or_else(|e| panic!("{e}"));
        let fault = outcome.run.fault.as_ref().unwrap_or_else(|| panic!("{method}: no fault"));
        let FaultKind::RatesOverflow { component, rate } = fault.kind else {
            panic!("{method}: {fault:?}");
        };
        // x'' = (F − k·x)/m at x = 0.1.
        assert_eq!(component, 1, "{method}");
        assert!((rate / ((exp(700.0) - 0.8) / 2.0) - 1.0).abs() < 1e-12, "{method}: {rate:e}");
        let summary = cli::simulate::summary(&outcome);
        assert!(
            summary.contains("the rate of `x'` is 5.1e303: too large for the step control"),
            "{method}: {summary}"
        );
    }
    // The norm squares its terms, so at tolerance 1e-10 rates past about 1e144 overflow it;
    // below, the push is integrated: e^300 N.
    let options = Options {
        until: Some(1.0),
        input: vec!["F=exp(t + 300)".parse().expect("an assignment")],
        output: vec!["x, x'".into()],
        no_units: true,
        samples: 2,
        ..Options::default()
    };
    let outcome = simulate(PUSHED, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    let rate = outcome.run.trajectory.rows.last().expect("rows")[1];
    // ẍ = F/2 − 4x: x = A·(eᵗ − cos 2t − sin(2t)/2) with A = e^300/10 (the start's x = 0.1 is
    // lost against it), so ẋ(1) = A·(e + 2 sin 2 − cos 2).
    let exact = exp(300.0) / 10.0 * (exp(1.0) + 2.0 * sin(2.0) - cos(2.0));
    assert!((rate / exact - 1.0).abs() < 1e-8, "x' = {rate:e}, not {exact:e}");
}

// References whose last bits show nowhere.
#[allow(clippy::disallowed_methods)]
fn exp(x: f64) -> f64 {
    x.exp()
}

#[allow(clippy::disallowed_methods)]
fn sin(x: f64) -> f64 {
    x.sin()
}

#[allow(clippy::disallowed_methods)]
fn cos(x: f64) -> f64 {
    x.cos()
}

/// A held law that gives NaN once the block passes x = 0.05 (√ of a negative): the fault used to
/// say "component 6", an index past the state into the parameter slots; it names the input.
#[test]
fn a_held_law_that_gives_nan_names_its_input() {
    let options = Options {
        until: Some(3.0),
        input: vec!["F=sqrt(x - 0.05)".parse().expect("an assignment")],
        hold: Some(0.1),
        no_units: true,
        ..Options::default()
    };
    let outcome = simulate(PUSHED, &options).unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().expect("the law's NaN stops the run");
    assert!(
        matches!(fault.kind, FaultKind::NonFinite { at: NonFiniteAt::HeldLaw { .. } }),
        "{fault:?}"
    );
    let summary = cli::simulate::summary(&outcome);
    assert!(summary.contains("the held law driving `F` gave NaN or infinity"), "{summary}");
    // Sampled at a multiple of the period, where x had just passed 0.05.
    let periods = fault.time / 0.1;
    assert!((periods - periods.round()).abs() < 1e-9 && fault.state[0] < 0.05, "{fault:?}");
}

/// The same law applied continuously: the NaN is in f, the force side of x's equation, and the
/// fault says so rather than "component 2".
#[test]
fn a_law_that_gives_nan_names_the_equation_it_enters() {
    let options = Options {
        until: Some(3.0),
        input: vec!["F=sqrt(x - 0.05)".parse().expect("an assignment")],
        no_units: true,
        ..Options::default()
    };
    let outcome = simulate(PUSHED, &options).unwrap_or_else(|e| panic!("{e}"));
    let fault = outcome.run.fault.as_ref().expect("the law's NaN stops the run");
    assert_eq!(fault.kind, FaultKind::NonFinite { at: NonFiniteAt::Force { coordinate: 0 } });
    let summary = cli::simulate::summary(&outcome);
    assert!(summary.contains("the force side f of `x`'s equation (M·q̈ = f)"), "{summary}");
}

/// The knots of a piecewise-linear push: times and values in N.
const KNOTS: [(f64, f64); 6] =
    [(0.0, 0.0), (0.37, 5.0), (0.81, -3.0), (1.3, 4.0), (2.05, -2.0), (3.0, 1.0)];

/// A push given as a series, on the block with no spring (k = 0): ẍ = F/m is piecewise linear, x
/// piecewise cubic, and the exact state at t = 3 sums each piece's integral. A step across a
/// knot, where the slope of F jumps, lost the method's order: at tolerance 1e-8 the state ended
/// 3.4e-7 off under dop853, 1.5e-5 under dopri5 and 2.5e-7 under radau. Each step now ends at a
/// knot and the method restarts there, as at a held sample; between knots the pieces are
/// polynomials each method integrates exactly.
#[test]
fn a_series_input_restarts_the_method_at_its_knots() {
    let (m, x0) = (2.0, 0.1);
    let (mut x, mut v) = (x0, 0.0);
    for w in KNOTS.windows(2) {
        let ((t0, f0), (t1, f1)) = (w[0], w[1]);
        let (h, a, b) = (t1 - t0, f0 / m, (f1 - f0) / (t1 - t0) / m);
        x += v * h + a * h * h / 2.0 + b * h * h * h / 6.0;
        v += a * h + b * h * h / 2.0;
    }
    let (times, values): (Vec<f64>, Vec<f64>) = KNOTS.iter().copied().unzip();
    let series = sim::Series::new(times, values).expect("a series");
    for method in ["dop853", "dopri5", "radau", "auto"] {
        let options = Options {
            until: Some(3.0),
            method: Some(method.into()),
            tolerance: Some(1e-8),
            set: vec!["k=0".parse().expect("an assignment")],
            input_series: vec![("F".into(), series.clone())],
            ..Options::default()
        };
        let outcome = simulate(PUSHED, &options).unwrap_or_else(|e| panic!("{e}"));
        assert!(outcome.run.fault.is_none(), "{method}: {:?}", outcome.run.fault);
        let state = &outcome.run.final_state;
        let error = (state[0] - x).abs().max((state[1] - v).abs());
        assert!(
            error < 1e-11,
            "{method}: ({}, {}) against ({x}, {v}): {error:e}",
            state[0],
            state[1]
        );
    }
}
