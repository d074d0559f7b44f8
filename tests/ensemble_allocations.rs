//! An ensemble's runs allocate nothing per step: with the explicit methods, a run twice as
//! long (twice the steps, thousands of them) makes as many allocations as a shorter one,
//! alone or side by side in lockstep, to the few the code generator's own vary by. Both are
//! long enough for every tape to have compiled itself (on its 1,000th run, once), so that what
//! would differ is per step.
//! Counted by a global
//! allocator that counts per thread, on the thread that runs the ensemble (`--threads 1`),
//! in a test binary of its own so that no other test pays for the counting.

use ::ensemble::{Ensemble, Options};
use engine::input::Vary;
use simulation as simulate;

const FLIP: &str = "classics/double_pendulum_flip.lag";

/// The allocations of `runs` runs to `until` by `method` (side by side in lockstep from four
/// runs on), from starts that do not flip (no stop is located).
fn allocations(method: &str, until: f64, runs: usize) -> u64 {
    let source = lagrange_tests::example(FLIP);
    let options = Options {
        simulate: simulate::Options {
            until: Some(until),
            method: Some(method.into()),
            // The fixed-step method's step; an adaptive one would refuse it.
            step: (method == "rk4").then_some(0.01),
            ..Default::default()
        },
        vary: vec![Vary::parse(&format!("a1=0.3:0.4:{}", runs.max(2))).expect("a grid axis")],
        record: vec!["t, theta1, max(theta2)".into()],
        ..Default::default()
    };
    let ensemble = Ensemble::new(&source, &options).expect("the ensemble loads");
    let info = allocation_counter::measure(|| {
        let table = ensemble.run(0..runs, 1, &mut ());
        for (row, failure) in table.rows.iter().zip(&table.failures) {
            assert!(failure.is_none() && row[1] == until);
        }
    });
    info.count_total
}

#[test]
fn explicit_runs_allocate_nothing_per_step() {
    for (method, runs) in [("dop853", 1), ("dop853", 9), ("dopri5", 1), ("dopri5", 9), ("rk4", 1)] {
        let (short, long) = (allocations(method, 200.0, runs), allocations(method, 400.0, runs));
        // The code generator's own allocations differ by one or two from one compile of the
        // same program to the next (its hash maps are seeded at random); an allocation per
        // step would add thousands.
        assert!(
            short.abs_diff(long) <= 4,
            "{method} ({runs} runs): {short} allocations to t = 200, {long} to t = 400"
        );
        assert!(short > 0, "{method}: the counter counted nothing");
    }
}
