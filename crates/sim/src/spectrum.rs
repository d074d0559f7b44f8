//! The fastest mode of a Jacobian: the eigenvalue of largest modulus and the shape of its
//! eigenvector. It sets the largest step an explicit method stays stable at, which decides
//! when `auto` leaves radau and what a blown-up explicit run is told.

use nalgebra::{Complex, DMatrix};

use crate::linalg;

/// Iterations the Schur decomposition may take: a count, never a time.
const MAX_ITERATIONS: usize = 10_000;

/// An eigenvalue of a Jacobian and the moduli of its eigenvector's components, scaled so that
/// the largest is 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    pub eigenvalue: Complex<f64>,
    pub shape: Vec<f64>,
}

/// The eigenvalues of the `n × n` row-major matrix `jac`; `None` if the decomposition does not
/// converge or the matrix is not finite.
fn eigenvalues(jac: &[f64], n: usize) -> Option<Vec<Complex<f64>>> {
    if n == 0 || jac.len() != n * n || jac.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let a = DMatrix::from_row_slice(n, n, jac);
    let schur = nalgebra::Schur::try_new(a, f64::EPSILON, MAX_ITERATIONS)?;
    Some(schur.complex_eigenvalues().iter().copied().collect())
}

/// The largest |λ| of `jac`'s eigenvalues.
pub fn spectral_radius(jac: &[f64], n: usize) -> Option<f64> {
    Some(eigenvalues(jac, n)?.iter().map(|z| z.norm()).fold(0.0, f64::max))
}

/// The eigenvalue of `jac` of largest modulus (of a complex pair, the one with positive
/// imaginary part), with its eigenvector's shape from two steps of inverse iteration at a
/// shift just off it.
pub fn fastest_mode(jac: &[f64], n: usize) -> Option<Mode> {
    let values = eigenvalues(jac, n)?;
    let eigenvalue = values
        .into_iter()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()).then(a.im.total_cmp(&b.im)))?;
    // The shift is off the eigenvalue by a relative 1e-8, so the shifted matrix is nearly
    // singular but factors: the solves amplify the eigenvector's direction by ~1e8 each.
    let shift = eigenvalue + Complex::new(1e-8 * eigenvalue.norm().max(1.0), 0.0);
    let mut a = DMatrix::from_fn(n, n, |i, j| {
        let entry = Complex::new(jac[i * n + j], 0.0);
        if i == j {
            entry - shift
        } else {
            entry
        }
    });
    let mut pivots = vec![0; n];
    let mut v: Vec<Complex<f64>> =
        (0..n).map(|i| Complex::new(1.0 + i as f64 * 0.1, 0.0)).collect();
    if linalg::lu_factor(&mut a, &mut pivots).is_ok() {
        for _ in 0..2 {
            linalg::lu_factor_solve(&a, &pivots, &mut v);
            let largest = v.iter().map(|z| z.norm()).fold(0.0, f64::max);
            if !(largest.is_finite() && largest > 0.0) {
                return None;
            }
            v.iter_mut().for_each(|z| *z /= largest);
        }
    }
    let largest = v.iter().map(|z| z.norm()).fold(0.0, f64::max);
    Some(Mode { eigenvalue, shape: v.iter().map(|z| z.norm() / largest).collect() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fastest_mode_of_a_stiff_oscillator_and_its_shape() {
        // x'' = −100·x − 202·x' (λ² + 202·λ + 100 = 0: λ ≈ −0.5 and −201.5), beside a slow,
        // uncoupled y' = −y.
        let jac = [0.0, 1.0, 0.0, -100.0, -202.0, 0.0, 0.0, 0.0, -1.0];
        let mode = fastest_mode(&jac, 3).expect("a mode");
        let expected = -101.0 - (101.0f64 * 101.0 - 100.0).sqrt();
        assert!((mode.eigenvalue.re - expected).abs() < 1e-9 * expected.abs());
        assert_eq!(mode.eigenvalue.im, 0.0);
        // The eigenvector is (1, λ, 0): the rate dominates, y takes no part.
        assert!((mode.shape[1] - 1.0).abs() < 1e-9);
        assert!((mode.shape[0] - 1.0 / expected.abs()).abs() < 1e-9);
        assert!(mode.shape[2] < 1e-12);
        assert!((spectral_radius(&jac, 3).unwrap() - expected.abs()).abs() < 1e-9);
    }

    #[test]
    fn a_complex_pair_is_named_by_its_upper_member() {
        // x'' = -1e4·x: λ = ±100i.
        let mode = fastest_mode(&[0.0, 1.0, -1e4, 0.0], 2).expect("a mode");
        assert!(mode.eigenvalue.re.abs() < 1e-9 && (mode.eigenvalue.im - 100.0).abs() < 1e-9);
        assert!((mode.shape[0] - 0.01).abs() < 1e-9 && (mode.shape[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn nothing_is_made_of_a_matrix_that_is_not_finite() {
        assert_eq!(fastest_mode(&[f64::NAN], 1), None);
        assert_eq!(spectral_radius(&[], 0), None);
    }
}
