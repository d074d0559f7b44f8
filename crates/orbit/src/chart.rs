//! The linear algebra of a return map: the chart of the section within the manifold the
//! motion keeps to, the map's Jacobian in it, the Newton step and the multipliers.

use nalgebra::{Complex, DMatrix, DVector, SymmetricEigen};

/// A rank below this fraction of the largest (squared singular value, rows normalised) is a
/// direction the normals do not restrain.
const RANK: f64 = 1e-10;

/// An orthonormal basis (columns, `size` rows) of the directions that every row of `normals`
/// and `flow` (if given) is orthogonal to: the section's tangent within the manifold the
/// constraints kept hold the state on. Baumgarte's terms act across it, the motion along it.
pub fn tangent(normals: &[Vec<f64>], flow: Option<&[f64]>, size: usize) -> DMatrix<f64> {
    let mut rows: Vec<&[f64]> = normals.iter().map(|r| r.as_slice()).collect();
    rows.extend(flow);
    let mut gram = DMatrix::<f64>::zeros(size, size);
    for row in rows {
        let length = row.iter().map(|v| v * v).sum::<f64>().sqrt();
        if length == 0.0 {
            continue;
        }
        for i in 0..size {
            for j in 0..size {
                gram[(i, j)] += row[i] * row[j] / (length * length);
            }
        }
    }
    let eigen = SymmetricEigen::new(gram);
    let largest = eigen.eigenvalues.iter().fold(1.0_f64, |m: f64, v: &f64| m.max(v.abs()));
    let mut free: Vec<usize> =
        (0..size).filter(|&k| eigen.eigenvalues[k].abs() <= RANK * largest).collect();
    // The basis in a fixed order, each vector's sign fixed: the same chart on every run.
    free.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
    let mut basis = DMatrix::zeros(size, free.len());
    for (c, &k) in free.iter().enumerate() {
        let mut v = eigen.eigenvectors.column(k).into_owned();
        let lead = v.iter().copied().fold(0.0_f64, |m, x| if x.abs() > m.abs() { x } else { m });
        if lead < 0.0 {
            v = -v;
        }
        basis.set_column(c, &v);
    }
    basis
}

/// A row whose component in the range is below this fraction of its length holds there
/// already (to the differences' accuracy): it restrains nothing more.
const HELD: f64 = 1e-6;

/// A direction of the surface's range keeps at least this fraction of its length on the
/// manifold's tangent at the start, or it is one across the manifold.
const ON_MANIFOLD: f64 = 0.5;

/// An orthonormal basis of the section's tangent at a start: the range of `surface` (the
/// derivative along the surface the state arrived on, row-major, the symmetry applied) moved
/// onto the tangent of the manifold at the start (the directions every row of `normals` is
/// orthogonal to), within it the directions every row of `ignored` (the components left out)
/// is orthogonal to.
///
/// The range is the section's tangent where the previous return arrived, and a Newton step
/// starts a little away from there: the manifold's normals have turned by as much as the step
/// is long (a walker's stance foot, its coordinates swapped, is normal to a range taken
/// 3·10⁻⁴ away by 4·10⁻⁶). Projected, the range keeps its dimension; restrained by those
/// normals, each such turn would take a direction away.
pub fn section(
    surface: &[f64],
    normals: &[Vec<f64>],
    ignored: &[Vec<f64>],
    size: usize,
) -> DMatrix<f64> {
    let matrix = DMatrix::from_row_slice(size, size, surface);
    let svd = matrix.svd(true, false);
    let Some(u) = svd.u else { return DMatrix::zeros(size, 0) };
    let largest = svd.singular_values.iter().fold(0.0_f64, |m: f64, v: &f64| m.max(*v));
    let kept: Vec<usize> =
        (0..size).filter(|&k| svd.singular_values[k] > RANK.sqrt() * largest).collect();
    let mut arrived = DMatrix::zeros(size, kept.len());
    for (c, &k) in kept.iter().enumerate() {
        arrived.set_column(c, &u.column(k));
    }
    let on = tangent(normals, None, size);
    let projected = &on * (on.transpose() * &arrived);
    let svd = projected.svd(true, false);
    let Some(u) = svd.u else { return DMatrix::zeros(size, 0) };
    let kept: Vec<usize> =
        (0..svd.singular_values.len()).filter(|&k| svd.singular_values[k] > ON_MANIFOLD).collect();
    let mut range = DMatrix::zeros(size, kept.len());
    for (c, &k) in kept.iter().enumerate() {
        range.set_column(c, &u.column(k));
    }
    let mut restraints = Vec::new();
    for row in ignored {
        let length = row.iter().map(|v| v * v).sum::<f64>().sqrt();
        if length == 0.0 {
            continue;
        }
        let r = DVector::from_column_slice(row).transpose() * &range / length;
        if r.norm() > HELD {
            restraints.push(r.iter().copied().collect::<Vec<f64>>());
        }
    }
    let within = tangent(&restraints, None, kept.len());
    let basis = range * within;
    // Signs fixed as `tangent` fixes them: the same chart on every run.
    let mut out = basis.clone();
    for c in 0..out.ncols() {
        let lead =
            out.column(c)
                .iter()
                .copied()
                .fold(0.0_f64, |m, x| if x.abs() > m.abs() { x } else { m });
        if lead < 0.0 {
            let negated = -out.column(c).into_owned();
            out.set_column(c, &negated);
        }
    }
    out
}

/// The full map's Jacobian (row-major, `size` × `size`) in the chart: Tᵀ·M·T.
pub fn reduced(matrix: &[f64], chart: &DMatrix<f64>) -> DMatrix<f64> {
    let size = chart.nrows();
    let m = DMatrix::from_row_slice(size, size, matrix);
    chart.transpose() * m * chart
}

/// A singular value of C − I below this (relative to the largest, and to 1) is a multiplier
/// at 1 to rounding: a direction along a family of orbits, which the step leaves alone.
const FAMILY: f64 = 1e-9;
/// ... or below this many times the run's tolerance: a loose run's C is that far off, and a
/// family's multiplier read as 1 − 10⁻⁶ would send the step far along it.
const FAMILY_PER_TOLERANCE: f64 = 100.0;

/// The Newton step dz of (C − I)·dz = −ρ, least-squares where C has a multiplier at 1 (a
/// family of orbits, one per energy of a conservative scene): the step moves along no such
/// direction, so that Newton stays on the member it started nearest rather than leaping
/// along the family by the rounding in ρ. C is the map's at `tolerance`. `None` if the step
/// is not finite.
pub fn newton_step(
    reduced: &DMatrix<f64>,
    residual: &DVector<f64>,
    tolerance: f64,
) -> Option<DVector<f64>> {
    let d = reduced.nrows();
    let system = reduced - DMatrix::identity(d, d);
    let svd = system.svd(true, true);
    let largest = svd.singular_values.iter().fold(1.0_f64, |m: f64, v: &f64| m.max(*v));
    let family = FAMILY.max(FAMILY_PER_TOLERANCE * tolerance);
    let step = svd.solve(&(-residual), family * largest).ok()?;
    step.iter().all(|v| v.is_finite()).then_some(step)
}

/// The eigenvalues of C, largest modulus first (then by angle, counter-clockwise from the
/// positive reals): the Floquet multipliers on the section.
pub fn multipliers(reduced: &DMatrix<f64>) -> Vec<Complex<f64>> {
    if reduced.nrows() == 0 {
        return Vec::new();
    }
    let mut values: Vec<Complex<f64>> =
        reduced.clone().complex_eigenvalues().iter().copied().collect();
    values.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(a.arg().total_cmp(&b.arg())));
    values
}

/// The multipliers on the section, `reduced`'s eigenvalues, each taken as the eigenvalue of
/// `whole` (the map's Jacobian on the whole state, row-major `size` × `size`) nearest it, then
/// ordered as [`multipliers`] orders them.
///
/// The map keeps the manifold the kept constraints hold the state on, so the eigenvalues of
/// its Jacobian on the manifold's tangent are among the whole Jacobian's, whatever the chart;
/// the compression to the chart has them only as far as the chart spans that tangent's
/// directions on the section. On a walker's mid-stance section the compression's multipliers
/// depended on the chart, built from the previous return's surface or from the run's own, by
/// 1.2·10⁻⁸ at tolerance 10⁻¹⁰ and 5·10⁻⁷ at 10⁻¹², where the whole Jacobian's converged with
/// the tolerance (why the compression is that sensitive there was not found). The chart still
/// says which of the whole Jacobian's are the section's: the rest are the trivial ones (0 for
/// the flow and the directions across the manifold, 1 for a coordinate left out of the
/// comparison), far from a multiplier or equal to it.
pub fn multipliers_within(reduced: &DMatrix<f64>, whole: &[f64], size: usize) -> Vec<Complex<f64>> {
    let section = multipliers(reduced);
    if section.is_empty() {
        return section;
    }
    let mut candidates: Vec<Option<Complex<f64>>> = DMatrix::from_row_slice(size, size, whole)
        .complex_eigenvalues()
        .iter()
        .copied()
        .map(Some)
        .collect();
    let mut values: Vec<Complex<f64>> = section
        .iter()
        .map(|m| {
            // A candidate taken is at an infinite distance: each is matched once.
            let distance = |k: usize| candidates[k].map_or(f64::INFINITY, |c| (c - m).norm());
            let nearest =
                (0..candidates.len()).min_by(|&a, &b| distance(a).total_cmp(&distance(b)));
            nearest.and_then(|k| candidates[k].take()).unwrap_or(*m)
        })
        .collect();
    values.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(a.arg().total_cmp(&b.arg())));
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tangent_is_orthogonal_to_the_normals_and_flow() {
        let normals = vec![vec![1.0, 1.0, 0.0, 0.0]];
        let flow = [0.0, 0.0, 2.0, 0.0];
        let t = tangent(&normals, Some(&flow), 4);
        assert_eq!(t.ncols(), 2);
        for c in 0..2 {
            let v = t.column(c);
            assert!((v[0] + v[1]).abs() < 1e-14 && v[2].abs() < 1e-14);
            assert!((v.norm() - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn the_multipliers_within_are_the_whole_jacobians_the_chart_picks() {
        // A map keeping the plane z = 0 (the manifold), with 0.5 and 0.25 on it and 0.01
        // across; its chart turned out of the plane by 10⁻³ compresses the map to values
        // off by about that, and the whole map's own are taken instead.
        let whole = [0.5, 0.1, 0.3, 0.0, 0.25, 0.2, 0.0, 0.0, 0.01];
        let tilt = 1e-3_f64;
        let chart =
            DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, (1.0 - tilt * tilt).sqrt(), 0.0, tilt]);
        let reduced = reduced(&whole, &chart);
        let compressed = multipliers(&reduced);
        assert!((compressed[1].re - 0.25).abs() > 1e-5, "{compressed:?}");
        let within = multipliers_within(&reduced, &whole, 3);
        assert_eq!(within.len(), 2);
        assert!((within[0].re - 0.5).abs() < 1e-14 && (within[1].re - 0.25).abs() < 1e-14);
    }

    #[test]
    fn multipliers_of_a_rotation_are_its_conjugate_pair() {
        let (c, s) = (0.6, 0.8);
        let m = DMatrix::from_row_slice(2, 2, &[0.5 * c, -0.5 * s, 0.5 * s, 0.5 * c]);
        let mu = multipliers(&m);
        assert!((mu[0].norm() - 0.5).abs() < 1e-15 && (mu[1].norm() - 0.5).abs() < 1e-15);
        assert!((mu[0].im + mu[1].im).abs() < 1e-15 && (mu[0].re - 0.3).abs() < 1e-15);
    }
}
