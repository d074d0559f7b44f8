//! What a run meets on the way and must not get wrong silently: a stop condition or an event
//! whose expression leaves its domain (NaN) within a step, alone and in the lockstep of an
//! ensemble.

use engine::ensemble::{Ensemble, Options as EnsembleOptions};
use engine::input::Vary;
use engine::simulate::{simulate, Options};

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
