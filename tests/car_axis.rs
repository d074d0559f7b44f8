//! The car axis (`examples/classics/car_axis.lag`) against the reference solution of the Test
//! Set for IVP Solvers (Mazzia, Magherini et al., University of Bari), problem "caraxis": an
//! index-3 problem of dimension 10 (four positions, four velocities, two multipliers) whose
//! small wheel masses (5e-4 kg on springs of 1 N/m) make it stiff.
//!
//! Sign convention: the test set writes K·p̈ = f + Gᵀ·λ with g = (xb·xl + yb·yl,
//! (xl − xr)² + (yl − yr)² − L²), lagrange M·q̈ = f + Jᵀ·λ with Φ = lhs − rhs; the scene writes
//! the constraints as the test set's g, so the multipliers are the test set's, sign and all.

use simulation::{simulate, Options};

const SCENE: &str = "classics/car_axis.lag";

/// xl, yl, xr, yr, their rates, λ₁, λ₂ at t = 3 (the test set's reference solution, with the
/// digits it publishes).
#[allow(clippy::excessive_precision)]
const AT_3: [f64; 10] = [
    0.493_455_784_275_402_809e-1,
    0.496_989_460_230_171_154,
    0.104_174_252_488_542_152e1,
    0.373_911_027_265_361_257,
    -0.770_583_684_040_972_358e-1,
    0.744_686_658_723_778_553e-2,
    0.175_568_157_537_232_222e-1,
    0.770_341_043_779_251_976,
    -0.473_688_659_084_893_325e-2,
    -0.110_468_033_125_734_369e-2,
];

const OUTPUT: &str = "xl, yl, xr, yr, xl', yl', xr', yr', perpendicular.force, axle.force";

/// The state at t = 3 of a run with `method` at `tolerance`.
fn at_three(method: &str, tolerance: f64) -> Vec<f64> {
    let options = Options {
        samples: 2,
        method: Some(method.into()),
        tolerance: Some(tolerance),
        output: vec![OUTPUT.into()],
        ..Options::default()
    };
    let source = lagrange_tests::example(SCENE);
    let outcome = simulate(&source, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{:?}", outcome.run.fault);
    let times = &outcome.run.trajectory.times;
    assert!((times.last().copied().unwrap_or(0.0) - 3.0).abs() < 1e-15, "{times:?}");
    outcome.run.trajectory.rows.last().expect("rows").clone()
}

/// The largest difference from the reference, component by component, relative to each
/// component's size (or to 1e-3, below which the test set's own accuracy is absolute).
fn mixed_error(got: &[f64]) -> f64 {
    got.iter().zip(AT_3).map(|(g, w)| (g - w).abs() / w.abs().max(1e-3)).fold(0.0, f64::max)
}

#[test]
fn dop853_reaches_the_reference_at_tolerance_1e_12() {
    let got = at_three("dop853", 1e-12);
    let error = mixed_error(&got);
    assert!(error < 1e-8, "{got:?}: {error:e} off the reference");
}

#[test]
fn a_looser_tolerance_lands_further_off() {
    // The comparison can fail: at 1e-6 the same run is visibly off the reference.
    let tight = mixed_error(&at_three("dop853", 1e-12));
    let loose = mixed_error(&at_three("dop853", 1e-5));
    assert!(loose > 10.0 * tight, "loose {loose:e}, tight {tight:e}");
}

#[test]
fn radau_reaches_the_reference_as_the_index_3_system() {
    // Integrated as the differential–algebraic system, no stabilisation: the positions keep
    // nine digits, the velocities (index 2) and multipliers (solved from them) seven to eight.
    let got = at_three("radau", 1e-12);
    let error = mixed_error(&got);
    assert!(error < 1e-7, "{got:?}: {error:e} off the reference");
    let positions = mixed_error(&[&got[..4], &AT_3[4..]].concat());
    assert!(positions < 5e-9, "positions {:?}: {positions:e} off", &got[..4]);
}
