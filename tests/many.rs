//! `Mechanical::rhs_many` against `Problem::rhs` one state at a time: the same bits at the
//! admissible states of every example (kept multipliers included), and the row and fault of
//! the first state that fails.

use engine::numbers::prepare;
use sim::{FaultKind, Problem};

const STATES: usize = 19;

#[test]
fn every_example_gives_the_bits_of_one_state_at_a_time() {
    let mut compared = 0;
    for (rel, source) in lagrange_tests::examples_without_contacts() {
        let mut prepared = prepare(&source, &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let states = verify::admissible_states(&mut prepared.derivation, STATES, 0x5eed_0b17);
        let parameters: Vec<f64> = {
            let values = &states[0];
            prepared.parameters.iter().map(|s| values[s.index()]).collect()
        };
        let mut mechanical = lagrange_tests::mechanical(&mut prepared, &parameters);
        let d = &prepared.derivation;
        let width = mechanical.dim();
        let (mut times, mut ys, mut expected) = (Vec::new(), Vec::new(), Vec::<f64>::new());
        let mut dy = vec![0.0; width];
        for values in &states {
            let y: Vec<f64> = d.coords.iter().chain(&d.rates).map(|s| values[s.index()]).collect();
            let t = values[d.model.time.index()];
            // A random state may be singular (a dead point): only regular ones are compared.
            if mechanical.rhs(t, &y, &mut dy).is_ok() {
                times.push(t);
                ys.extend(&y);
                expected.extend(&dy);
            }
        }
        let mut many = vec![0.0; ys.len()];
        mechanical.rhs_many(&times, &ys, &mut many).unwrap_or_else(|(row, fault)| {
            panic!("{rel}: row {row} failed in the batch: {fault:?}")
        });
        for (k, (a, b)) in many.iter().zip(&expected).enumerate() {
            assert!(a.to_bits() == b.to_bits(), "{rel}: value {k}: {a} in the batch, {b} alone");
        }
        // Calls alone after the batch still agree: it leaves no stale solve behind.
        if let Some(t) = times.last() {
            let last = &ys[ys.len() - width..];
            mechanical.rhs(*t, last, &mut dy).expect("regular");
            assert_eq!(dy, expected[expected.len() - width..], "{rel}: after the batch");
        }
        compared += times.len();
    }
    assert!(compared >= 400, "too few states compared: {compared}");
}

#[test]
fn a_state_that_fails_is_named_by_its_row() {
    let source = std::fs::read_to_string(
        lagrange_tests::examples_dir().join("classics/simple_pendulum.lag"),
    )
    .expect("reads");
    let mut prepared = prepare(&source, &[], engine::Options::default()).expect("derives");
    let parameters = prepared.parameter_values(&[]).expect("values");
    let mut mechanical = lagrange_tests::mechanical(&mut prepared, &parameters);
    let width = mechanical.dim();
    let mut ys = vec![0.1; 3 * width];
    ys[width] = f64::NAN;
    let mut dys = vec![0.0; ys.len()];
    let Err((row, fault)) = mechanical.rhs_many(&[0.0, 0.0, 0.0], &ys, &mut dys) else {
        panic!("a NaN state was accepted");
    };
    assert_eq!(row, 1);
    assert!(matches!(fault, FaultKind::NonFinite { .. }), "{fault:?}");
}
