//! Dense linear algebra of the analysis, in floats: null spaces, least squares, the pivots
//! that choose dependent coordinates and rates, the augmented system at the reference, and the
//! check that a mass matrix is regular.

use nalgebra::{DMatrix, DVector};

use crate::fault::Fault;

/// Iterations the eigenvalue iteration and the SVD may take: a count, never a time.
pub(crate) const MAX_ITERATIONS: usize = 10_000;

/// One pivot column per row of `m` (rows that are combinations of earlier ones get none):
/// Gaussian elimination choosing, in each row, among the columns clearly away from zero, a
/// preferred one if there is one, the largest otherwise.
pub(crate) fn pivots(m: &DMatrix<f64>, preferred: &dyn Fn(usize) -> bool) -> Vec<usize> {
    let columns: Vec<usize> = (0..m.ncols()).collect();
    let mut work = m.clone();
    let scale = work.amax();
    let mut chosen: Vec<usize> = Vec::new();
    for r in 0..work.nrows() {
        let row_max = columns.iter().map(|&c| work[(r, c)].abs()).fold(0.0, f64::max);
        if row_max <= 1e-10 * scale {
            continue;
        }
        let clear = |c: &usize| !chosen.contains(c) && work[(r, *c)].abs() > 1e-3 * row_max;
        let best = |cs: Vec<usize>| {
            cs.into_iter().max_by(|a, b| work[(r, *a)].abs().total_cmp(&work[(r, *b)].abs()))
        };
        let pick = best(columns.iter().copied().filter(|c| clear(c) && preferred(*c)).collect())
            .or_else(|| best(columns.iter().copied().filter(|c| clear(c)).collect()));
        let Some(p) = pick else { continue };
        // Eliminate the pivot column from the rows below.
        for below in r + 1..work.nrows() {
            let factor = work[(below, p)] / work[(r, p)];
            if factor != 0.0 {
                for c in 0..work.ncols() {
                    let v = work[(r, c)];
                    work[(below, c)] -= factor * v;
                }
            }
        }
        chosen.push(p);
    }
    chosen
}

/// X of A·X = B column by column in the least-squares sense, of smallest norm where A is
/// rank-deficient.
pub(crate) fn least_squares_matrix(a: DMatrix<f64>, b: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let svd = nalgebra::SVD::try_new(a, true, true, f64::EPSILON, MAX_ITERATIONS)?;
    let eps = 1e-12 * svd.singular_values.max();
    svd.solve(b, eps).ok()
}

/// q̈ and λ of M·q̈ − Jᵀ·λ = f, J·q̈ = γ, by least squares (dependent constraints at the
/// reference are allowed); NaN where the solve fails.
pub(crate) fn accelerations_and_multipliers(
    mass: &DMatrix<f64>,
    jacobian: &DMatrix<f64>,
    forcing: &DVector<f64>,
    bias: &DVector<f64>,
) -> (DVector<f64>, DVector<f64>) {
    let (n, k) = (mass.nrows(), jacobian.nrows());
    let mut system = DMatrix::zeros(n + k, n + k);
    system.view_mut((0, 0), (n, n)).copy_from(mass);
    system.view_mut((0, n), (n, k)).copy_from(&(-jacobian.transpose()));
    system.view_mut((n, 0), (k, n)).copy_from(jacobian);
    let mut rhs = DVector::zeros(n + k);
    rhs.rows_mut(0, n).copy_from(forcing);
    rhs.rows_mut(n, k).copy_from(bias);
    let x = least_squares(system, &rhs).unwrap_or_else(|| DVector::from_element(n + k, f64::NAN));
    (x.rows(0, n).into_owned(), x.rows(n, k).into_owned())
}

/// The least-squares solution of smallest norm, robust to a rank-deficient system (dependent
/// constraints at the reference): [`least_squares_matrix`] of one column.
pub(crate) fn least_squares(a: DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let column = DMatrix::from_column_slice(b.len(), 1, b.as_slice());
    least_squares_matrix(a, &column).map(|x| x.column(0).into_owned())
}

/// An orthonormal basis of the null space of a k×n matrix, as the columns of an n×r matrix.
pub(crate) fn null_space(j: DMatrix<f64>) -> Option<DMatrix<f64>> {
    null_space_within(j, 1e-10)
}

/// The null space of the singular values below `relative` × the largest.
pub(crate) fn null_space_within(j: DMatrix<f64>, relative: f64) -> Option<DMatrix<f64>> {
    let (k, n) = j.shape();
    // Padded to square, so that the SVD gives every right singular vector, not only k.
    let mut square = DMatrix::zeros(n.max(k), n);
    square.view_mut((0, 0), (k, n)).copy_from(&j);
    let svd = nalgebra::SVD::try_new(square, false, true, f64::EPSILON, MAX_ITERATIONS)?;
    let v_t = svd.v_t?;
    let largest = svd.singular_values.max();
    let columns: Vec<DVector<f64>> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] <= relative * largest)
        .map(|i| v_t.row(i).transpose())
        .collect();
    Some(if columns.is_empty() { DMatrix::zeros(n, 0) } else { DMatrix::from_columns(&columns) })
}

/// The LU factors of a mass matrix, or the fault if it is singular (by its singular values,
/// relative to the largest) or not finite.
pub(crate) fn regular(
    mass: &DMatrix<f64>,
) -> Result<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>, Fault> {
    let svd = nalgebra::SVD::try_new(mass.clone(), false, false, f64::EPSILON, MAX_ITERATIONS)
        .ok_or(Fault::NotFinite("the mass matrix"))?;
    let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
    if mass.nrows() > 0 && smallest <= 1e-12 * largest {
        return Err(Fault::SingularMass { condition: largest / smallest });
    }
    Ok(mass.clone().lu())
}

/// X of M·X = B by the LU factors of a regular M.
pub(crate) fn solve(
    lu: &nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    b: &DMatrix<f64>,
) -> Result<DMatrix<f64>, Fault> {
    lu.solve(b).ok_or(Fault::SingularMass { condition: f64::INFINITY })
}

/// A matrix as rows, as the numbers keep them.
pub(crate) fn rows_of(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows()).map(|j| m.row(j).iter().copied().collect()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_null_space_is_orthonormal_and_annihilated() {
        let j = DMatrix::from_row_slice(1, 3, &[1.0, 2.0, 2.0]);
        let n = null_space(j.clone()).expect("converges");
        assert_eq!(n.ncols(), 2);
        assert!((&j * &n).amax() < 1e-14);
        assert!((n.transpose() * &n - DMatrix::identity(2, 2)).amax() < 1e-14);
    }
}
