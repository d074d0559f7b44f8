//! The eigenvalues of a real matrix and how far rounding may have moved each of them.
//!
//! The eigenvalues come from A balanced (a diagonal similarity by powers of two, exact in
//! floating point, that evens out the norms of each row and column), reduced to Hessenberg
//! form and iterated by Francis's double-shift QR with exceptional shifts: without those, the
//! iteration can cycle on matrices whose eigenvalues come in groups of equal modulus, as a
//! spinning top's do (±a ± bi), and never converge.
//!
//! The computed eigenvalues are the exact ones of A + E, with ‖E‖ a small multiple of
//! eps·‖A‖. How far E moves an eigenvalue depends on the eigenvalue: by its condition
//! number, 1/|yᴴx| for unit right and left eigenvectors x and y. A group of eigenvalues that
//! rounding cannot tell apart (a double root, or a Jordan block that rounding split) moves
//! together: its condition is that of its invariant subspace, ‖(YᴴX)⁻¹‖ for orthonormal
//! bases X and Y, and each of its eigenvalues may be as far from the true one as the group is
//! spread. So each eigenvalue gets a bound of its own, and a slow root beside a root a
//! billion times faster is judged on the rounding it suffers, not on the fast root's size.

use nalgebra::{Complex, DMatrix};

use crate::dense::MAX_ITERATIONS;

/// How many multiples of eps·‖A‖_F·n the backward error of the reduction and iteration is
/// taken to be: the textbook bound is of that order, with a margin.
const BACKWARD_ERROR_FACTOR: f64 = 10.0;

/// Iterations without a root after which the shift is an exceptional one: often enough to
/// break a cycle, rarely enough that ordinary convergence (quadratic) is not slowed.
const EXCEPTIONAL_EVERY: usize = 10;

/// Iterations allowed for one root (or pair) before the iteration is said not to converge.
const ITERATIONS_PER_ROOT: usize = 60;

/// Steps of inverse iteration for an invariant subspace: from a generic start, a subspace
/// whose eigenvalues are within rounding of the shift is reached in one or two.
const INVERSE_STEPS: usize = 3;

/// An eigenvalue (re, im) with the bound on how far rounding may have moved it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Eigenvalue {
    pub re: f64,
    pub im: f64,
    pub bound: f64,
}

/// The eigenvalues of `a` with their bounds, unsorted; `None` if `a` is not finite or the
/// iteration does not converge.
pub(crate) fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<Eigenvalue>> {
    let n = a.nrows();
    if n == 0 {
        return Some(Vec::new());
    }
    if a.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let balanced = balance(a.clone());
    let values = francis(nalgebra::Hessenberg::new(balanced.clone()).h())?;
    // Two errors: the iteration's, backward stable for the balanced matrix; and A's own,
    // whose entries come rounded from the evaluation of expressions (and from the deflation
    // of first integrals), of the order of eps·‖A‖ in A's coordinates, where balancing may
    // have scaled a small entry up.
    let size = BACKWARD_ERROR_FACTOR * n as f64 * f64::EPSILON;
    let errors = [(&balanced, size * balanced.norm()), (a, size * a.norm())];
    Some(with_bounds(&errors, &values))
}

/// D⁻¹·A·D with D diagonal, powers of two, chosen so that each row and column of the
/// off-diagonal part have norms within a factor of two of each other.
fn balance(mut a: DMatrix<f64>) -> DMatrix<f64> {
    let n = a.nrows();
    // Each sweep either changes nothing or lowers the norm by 5%: a few dozen suffice; the
    // cap keeps a pathological matrix from holding the sweep up.
    for _ in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let column: f64 = (0..n).filter(|&j| j != i).map(|j| a[(j, i)].abs()).sum();
            let row: f64 = (0..n).filter(|&j| j != i).map(|j| a[(i, j)].abs()).sum();
            if column == 0.0 || row == 0.0 {
                continue;
            }
            // c runs as column·f², so that (c + row)/f is the two norms after scaling the
            // column by f and the row by 1/f.
            let (mut c, mut f) = (column, 1.0_f64);
            while c < row / 2.0 {
                c *= 4.0;
                f *= 2.0;
            }
            while c > row * 2.0 {
                c /= 4.0;
                f /= 2.0;
            }
            if (c + row) / f < 0.95 * (column + row) {
                changed = true;
                a.row_mut(i).iter_mut().for_each(|x| *x /= f);
                a.column_mut(i).iter_mut().for_each(|x| *x *= f);
            }
        }
        if !changed {
            break;
        }
    }
    a
}

/// The eigenvalues of an upper Hessenberg matrix by Francis's implicit double-shift QR,
/// deflating a root (or a pair) whenever a subdiagonal entry falls to rounding of its
/// neighbours, with an exceptional shift after every [`EXCEPTIONAL_EVERY`] iterations
/// without one.
fn francis(mut h: DMatrix<f64>) -> Option<Vec<(f64, f64)>> {
    let n = h.nrows();
    let eps = f64::EPSILON;
    let norm: f64 = (0..n)
        .flat_map(|i| (i.saturating_sub(1)..n).map(move |j| (i, j)))
        .fold(0.0, |s, (i, j)| s + h[(i, j)].abs());
    let mut roots = vec![(0.0, 0.0); n];
    // The active block is rows and columns low..=last; `shifted` is what exceptional shifts
    // have taken off the diagonal, to be put back on the roots.
    let mut last = n as isize - 1;
    let mut shifted = 0.0;
    let mut total = 0;
    while last >= 0 {
        let hi = last as usize;
        let mut iterations = 0;
        loop {
            // The lowest row of the active block: above it, a negligible subdiagonal entry.
            let mut low = hi;
            while low > 0 {
                let mut size = h[(low - 1, low - 1)].abs() + h[(low, low)].abs();
                if size == 0.0 {
                    size = norm;
                }
                if h[(low, low - 1)].abs() <= eps * size {
                    h[(low, low - 1)] = 0.0;
                    break;
                }
                low -= 1;
            }
            let x = h[(hi, hi)];
            if low == hi {
                roots[hi] = (x + shifted, 0.0);
                last -= 1;
                break;
            }
            let y = h[(hi - 1, hi - 1)];
            let w = h[(hi, hi - 1)] * h[(hi - 1, hi)];
            if low == hi - 1 {
                // A 2×2 block: its two roots, real or a conjugate pair.
                let p = 0.5 * (y - x);
                let q = p * p + w;
                let z = q.abs().sqrt();
                let x = x + shifted;
                if q >= 0.0 {
                    let z = p + z.copysign(p);
                    let first = x + z;
                    let second = if z != 0.0 { x - w / z } else { first };
                    roots[hi - 1] = (first, 0.0);
                    roots[hi] = (second, 0.0);
                } else {
                    roots[hi - 1] = (x + p, z);
                    roots[hi] = (x + p, -z);
                }
                last -= 2;
                break;
            }
            if iterations == ITERATIONS_PER_ROOT || total == MAX_ITERATIONS {
                return None;
            }
            // The shifts: the eigenvalues of the trailing 2×2 block, through their sum x + y
            // and product x·y − w; now and then an exceptional pair instead, to break a cycle.
            let (mut x, mut y, mut w) = (x, y, w);
            if iterations > 0 && iterations % EXCEPTIONAL_EVERY == 0 {
                shifted += x;
                for i in 0..=hi {
                    h[(i, i)] -= x;
                }
                let s = h[(hi, hi - 1)].abs() + h[(hi - 1, hi - 2)].abs();
                x = 0.75 * s;
                y = x;
                w = -0.4375 * s * s;
            }
            iterations += 1;
            total += 1;
            // Start the bulge where two consecutive subdiagonal entries are small enough that
            // the first column of the double shift leaves the rows above alone.
            let mut m = hi - 2;
            let (mut p, mut q, mut r);
            loop {
                let z = h[(m, m)];
                let (rr, ss) = (x - z, y - z);
                p = (rr * ss - w) / h[(m + 1, m)] + h[(m, m + 1)];
                q = h[(m + 1, m + 1)] - z - rr - ss;
                r = h[(m + 2, m + 1)];
                let s = p.abs() + q.abs() + r.abs();
                p /= s;
                q /= s;
                r /= s;
                if m == low {
                    break;
                }
                let u = h[(m, m - 1)].abs() * (q.abs() + r.abs());
                let v = p.abs() * (h[(m - 1, m - 1)].abs() + z.abs() + h[(m + 1, m + 1)].abs());
                if u <= eps * v {
                    break;
                }
                m -= 1;
            }
            for i in m + 2..=hi {
                h[(i, i - 2)] = 0.0;
                if i != m + 2 {
                    h[(i, i - 3)] = 0.0;
                }
            }
            chase_bulge(&mut h, (low, m, hi), (p, q, r));
        }
    }
    Some(roots)
}

/// One double-shift QR step on rows and columns `low..=hi` of `h`, from the bulge that the
/// first column (p, q, r) of the shifted product makes at row `m`, chased down by 3×3
/// Householder reflections.
fn chase_bulge(h: &mut DMatrix<f64>, (low, m, hi): (usize, usize, usize), start: (f64, f64, f64)) {
    let (mut p, mut q, mut r) = start;
    let mut scale = 0.0;
    for k in m..hi {
        let in_three = k != hi - 1;
        if k != m {
            p = h[(k, k - 1)];
            q = h[(k + 1, k - 1)];
            r = if in_three { h[(k + 2, k - 1)] } else { 0.0 };
            scale = p.abs() + q.abs() + r.abs();
            if scale != 0.0 {
                p /= scale;
                q /= scale;
                r /= scale;
            }
        }
        let s = (p * p + q * q + r * r).sqrt().copysign(p);
        if s == 0.0 {
            continue;
        }
        if k == m {
            if low != m {
                h[(k, k - 1)] = -h[(k, k - 1)];
            }
        } else {
            h[(k, k - 1)] = -s * scale;
        }
        p += s;
        let (x, y, z) = (p / s, q / s, r / s);
        q /= p;
        r /= p;
        for j in k..=hi {
            let mut t = h[(k, j)] + q * h[(k + 1, j)];
            if in_three {
                t += r * h[(k + 2, j)];
                h[(k + 2, j)] -= t * z;
            }
            h[(k + 1, j)] -= t * y;
            h[(k, j)] -= t * x;
        }
        for i in low..=hi.min(k + 3) {
            let mut t = x * h[(i, k)] + y * h[(i, k + 1)];
            if in_three {
                t += z * h[(i, k + 2)];
                h[(i, k + 2)] -= t * r;
            }
            h[(i, k + 1)] -= t * q;
            h[(i, k)] -= t;
        }
    }
}

/// Each eigenvalue's bound: the roots grouped until no group's disc (its centre, radius the
/// sum over `errors` of its condition in that matrix × that error, plus its spread) meets
/// another's, closest pairs first; a root's bound is its group's radius.
fn with_bounds(errors: &[(&DMatrix<f64>, f64)], roots: &[(f64, f64)]) -> Vec<Eigenvalue> {
    let point = |i: usize| Complex::new(roots[i].0, roots[i].1);
    let disc = |members: &[usize]| -> (Complex<f64>, f64) {
        let centre = members.iter().map(|&i| point(i)).sum::<Complex<f64>>() / members.len() as f64;
        let spread = members.iter().map(|&i| modulus(point(i) - centre)).fold(0.0, f64::max);
        let moved: f64 = errors
            .iter()
            // A zero matrix has exact eigenvalues, whatever the condition.
            .filter(|(_, error)| *error > 0.0)
            .map(|(a, error)| condition(a, centre, members.len(), *error) * error)
            .sum();
        (centre, moved + spread)
    };
    let mut groups: Vec<(Vec<usize>, Complex<f64>, f64)> = (0..roots.len())
        .map(|i| {
            let (centre, radius) = disc(&[i]);
            (vec![i], centre, radius)
        })
        .collect();
    loop {
        let mut closest: Option<(usize, usize, f64)> = None;
        for i in 0..groups.len() {
            for j in i + 1..groups.len() {
                let distance = modulus(groups[i].1 - groups[j].1);
                let meet = distance <= groups[i].2 + groups[j].2;
                if meet && closest.is_none_or(|(_, _, d)| distance < d) {
                    closest = Some((i, j, distance));
                }
            }
        }
        let Some((i, j, _)) = closest else { break };
        let (other, ..) = groups.remove(j);
        let mut members = std::mem::take(&mut groups[i].0);
        members.extend(other);
        let (centre, radius) = disc(&members);
        groups[i] = (members, centre, radius);
    }
    let mut bounds = vec![0.0; roots.len()];
    for (members, _, radius) in &groups {
        members.iter().for_each(|&i| bounds[i] = *radius);
    }
    roots.iter().zip(bounds).map(|(&(re, im), bound)| Eigenvalue { re, im, bound }).collect()
}

/// |z| by the square root, correctly rounded everywhere (`hypot` is the platform's).
fn modulus(z: Complex<f64>) -> f64 {
    z.norm_sqr().sqrt()
}

/// The condition of the invariant subspace of the `count` eigenvalues of `a` near `centre`:
/// ‖(YᴴX)⁻¹‖₂ for orthonormal bases X of the right subspace and Y of the left one (for one
/// simple eigenvalue, 1/|yᴴx|). Infinite where the two are orthogonal (or where the inverse
/// iteration fails), so that the bound takes in everything.
fn condition(a: &DMatrix<f64>, centre: Complex<f64>, count: usize, error: f64) -> f64 {
    let complex = a.map(|x| Complex::new(x, 0.0));
    let right = subspace(&complex, centre, count, error);
    let left = subspace(&complex.adjoint(), centre.conj(), count, error);
    let (Some(x), Some(y)) = (right, left) else { return f64::INFINITY };
    let overlap = y.adjoint() * x;
    let Some(svd) = nalgebra::SVD::try_new(overlap, false, false, f64::EPSILON, MAX_ITERATIONS)
    else {
        return f64::INFINITY;
    };
    let smallest = svd.singular_values.min();
    if smallest > 0.0 {
        1.0 / smallest
    } else {
        f64::INFINITY
    }
}

/// An orthonormal basis of the invariant subspace of the `count` eigenvalues of `a` near
/// `shift`, by inverse iteration from a fixed start (shifted off the eigenvalue by `error`,
/// so that the factors are never exactly singular).
fn subspace(
    a: &DMatrix<Complex<f64>>,
    shift: Complex<f64>,
    count: usize,
    error: f64,
) -> Option<DMatrix<Complex<f64>>> {
    let n = a.nrows();
    let nudge = error.max(f64::MIN_POSITIVE) * Complex::new(1.0, 1.0);
    let mut shifted = a.clone();
    for i in 0..n {
        shifted[(i, i)] -= shift + nudge;
    }
    let lu = shifted.lu();
    // A start with a component along every direction: fractional parts of multiples of the
    // golden ratio, deterministic so that the bounds are the same from one run to the next.
    let golden = 0.618_033_988_749_895_f64;
    let mut basis = DMatrix::from_fn(n, count, |i, j| {
        let k = (i * count + j + 1) as f64;
        Complex::new((k * golden).fract() - 0.5, (k * golden * golden).fract() - 0.5)
    });
    for _ in 0..INVERSE_STEPS {
        let mut next = lu.solve(&basis)?;
        for mut column in next.column_iter_mut() {
            let norm = column.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
            if !norm.is_finite() || norm == 0.0 {
                return None;
            }
            column /= Complex::new(norm, 0.0);
        }
        basis = next.qr().q();
    }
    Some(basis)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted(mut values: Vec<Eigenvalue>) -> Vec<Eigenvalue> {
        values.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
        values
    }

    #[test]
    fn a_spinning_tops_matrix_converges() {
        // The sliding top's A (reduced) at w = 25, where nalgebra's Schur iteration cycles:
        // four roots ±a ± bi of equal modulus beside two zeros.
        let (g, l, a, c, m, w) = (9.81, 0.04, 0.0004, 0.0006, 0.5, 25.0);
        let (s, p) = (m * g * l / a, c * w / a);
        #[rustfmt::skip]
        let rows = [
            0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
            0.0, -s * l, 0.0, 0.0, -p * l, 0.0, 0.0,
            s * l, 0.0, 0.0, 0.0, 0.0, -p * l, 0.0,
            s, 0.0, 0.0, 0.0, 0.0, -p, 0.0,
            0.0, s, 0.0, 0.0, p, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ];
        let matrix = DMatrix::from_row_slice(7, 7, &rows);
        let values = eigenvalues(&matrix).expect("converges");
        // λ² ± i·p·λ − s = 0: λ = ∓i·p/2 ± √(s − p²/4).
        let real = (s - p * p / 4.0).sqrt();
        let found = sorted(values);
        assert!((found[0].re + real).abs() < 1e-9 && (found[6].re - real).abs() < 1e-9);
        assert!(found.iter().all(|z| z.bound < 1e-9), "{found:?}");
    }

    #[test]
    fn a_slow_root_beside_a_fast_one_has_its_own_bound() {
        // s² + (1e9 + 1)·s + 1e9: roots −1 and −1e9.
        let matrix = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1e9, -(1e9 + 1.0)]);
        let found = sorted(eigenvalues(&matrix).expect("converges"));
        assert!((found[0].re + 1e9).abs() < 1e-3 * 1e9, "{found:?}");
        assert!((found[1].re + 1.0).abs() < 1e-6, "{found:?}");
        assert!(found[1].bound < 1e-3, "{found:?}");
    }

    #[test]
    fn a_double_root_is_bounded_as_a_group() {
        // Two equal oscillators: ±2i, each twice, semisimple.
        #[rustfmt::skip]
        let rows = [
            0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            -4.0, 0.0, 0.0, 0.0,
            0.0, -4.0, 0.0, 0.0,
        ];
        let found = eigenvalues(&DMatrix::from_row_slice(4, 4, &rows)).expect("converges");
        assert!(found.iter().all(|z| z.bound < 1e-12 && z.re.abs() <= z.bound), "{found:?}");
        // A Jordan block of order three at 2 in a skew basis: rounding splits the root by
        // about the cube root of eps, and each bound covers its distance from 2.
        let jordan = DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 0.0, 2.0, 1.0, 0.0, 0.0, 2.0]);
        let basis = DMatrix::from_row_slice(3, 3, &[1.0, 0.3, 0.7, 0.2, 1.0, 0.1, 0.5, 0.4, 1.0]);
        let inverse = basis.clone().try_inverse().expect("regular");
        let found = eigenvalues(&(&basis * jordan * inverse)).expect("converges");
        let away = |z: &Eigenvalue| modulus(Complex::new(z.re - 2.0, z.im));
        assert!(found.iter().any(|z| away(z) > 1e-9), "rounding splits it: {found:?}");
        assert!(found.iter().all(|z| away(z) <= z.bound && z.bound < 1e-3), "{found:?}");
    }

    #[test]
    fn the_roots_agree_with_an_independent_iteration_where_it_converges() {
        // Matrices of order 1 to 12 with entries spread over six orders of magnitude, from a
        // fixed sequence: the roots match nalgebra's Schur form (where it converges) as
        // multisets, within their bounds, and add up to the trace.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut compared = 0;
        for n in 1..=12 {
            for _ in 0..5 {
                let matrix = DMatrix::from_fn(n, n, |_, _| {
                    let magnitude = [1e-3, 1.0, 1e3][(next() * 3.0) as usize % 3];
                    (next() - 0.5) * magnitude
                });
                let found = eigenvalues(&matrix).expect("converges");
                let trace: f64 = found.iter().map(|z| z.re).sum();
                let scale = matrix.norm();
                assert!((trace - matrix.trace()).abs() <= 1e-12 * scale, "{matrix}");
                let Some(schur) = nalgebra::Schur::try_new(matrix.clone(), f64::EPSILON, 10_000)
                else {
                    continue;
                };
                let mut theirs: Vec<Complex<f64>> =
                    schur.complex_eigenvalues().iter().copied().collect();
                for z in &found {
                    let here = Complex::new(z.re, z.im);
                    let nearest = (0..theirs.len())
                        .min_by(|&a, &b| {
                            modulus(theirs[a] - here).total_cmp(&modulus(theirs[b] - here))
                        })
                        .expect("as many roots");
                    // Both are within rounding of the true root: the two bounds' worth.
                    let apart = modulus(theirs[nearest] - here);
                    assert!(apart <= 1e-9 * scale && apart <= 2.0 * z.bound, "{matrix}: {z:?}");
                    theirs.remove(nearest);
                }
                compared += 1;
            }
        }
        assert!(compared > 40, "{compared}");
    }

    #[test]
    fn balancing_keeps_the_eigenvalues() {
        let matrix = DMatrix::from_row_slice(2, 2, &[1.0, 1e6, 1e-6, 2.0]);
        let balanced = balance(matrix.clone());
        assert!(balanced[(0, 1)].abs() < 1e3, "{balanced}");
        assert!((balanced.trace() - matrix.trace()).abs() < 1e-15);
        assert!((balanced.determinant() - matrix.determinant()).abs() < 1e-9);
    }
}
