//! Dense solves in place, allocation-free: LDLᵀ for symmetric positive definite
//! matrices, LU with partial pivoting for the rest, each reporting the columns where it broke
//! down. They work on any [`Square`] storage: `nalgebra`'s dynamic matrices, or [`Small`] on
//! the stack for the few coordinates of most scenes, where indexing a heap matrix cost more
//! than the arithmetic. Both run the same operations in the same order, so the same bits.

use std::ops::{Index, IndexMut};

use nalgebra::{ComplexField, DMatrix, Scalar};
use numeric::LANES;

use crate::FaultKind;

mod saddle;

pub use saddle::Saddle;

/// Square storage the solves work on, indexed (row, column).
pub trait Square<T = f64>:
    Index<(usize, usize), Output = T> + IndexMut<(usize, usize), Output = T>
{
    /// The number of rows, which is that of columns.
    fn order(&self) -> usize;
    fn swap_rows(&mut self, a: usize, b: usize);
    /// The entries, column-major, and the stride between columns: the factorization walks
    /// them as slices.
    fn columns_mut(&mut self) -> (&mut [T], usize);
}

impl<T: Scalar> Square<T> for DMatrix<T> {
    fn order(&self) -> usize {
        self.nrows()
    }

    fn swap_rows(&mut self, a: usize, b: usize) {
        nalgebra::Matrix::swap_rows(self, a, b);
    }

    fn columns_mut(&mut self) -> (&mut [T], usize) {
        let stride = self.nrows();
        (self.as_mut_slice(), stride)
    }
}

/// The largest order [`Small`] holds.
pub const SMALL: usize = 8;

/// A square matrix of order at most [`SMALL`] on the stack, column-major with a fixed stride
/// so that an index is a shift and an add.
#[derive(Clone, Copy, Debug)]
pub struct Small {
    order: usize,
    entries: [f64; SMALL * SMALL],
}

impl Small {
    /// A zero matrix of this order, `None` past [`SMALL`].
    pub fn zeros(order: usize) -> Option<Small> {
        (order <= SMALL).then_some(Small { order, entries: [0.0; SMALL * SMALL] })
    }

    /// Takes the leading `order` rows and columns as the matrix from now on (at most the
    /// order it was made with, which its storage holds).
    pub fn set_order(&mut self, order: usize) {
        debug_assert!(order <= SMALL);
        self.order = order.min(SMALL);
    }
}

impl Index<(usize, usize)> for Small {
    type Output = f64;

    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        &self.entries[i + SMALL * j]
    }
}

impl IndexMut<(usize, usize)> for Small {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        &mut self.entries[i + SMALL * j]
    }
}

impl Square for Small {
    fn order(&self) -> usize {
        self.order
    }

    fn swap_rows(&mut self, a: usize, b: usize) {
        for j in 0..self.order {
            self.entries.swap(a + SMALL * j, b + SMALL * j);
        }
    }

    fn columns_mut(&mut self) -> (&mut [f64], usize) {
        (&mut self.entries, SMALL)
    }
}

/// Systems solved side by side, a value of each per lane.
pub type Lanes = [f64; LANES];

/// Past this estimated condition number the solution has no correct digits left worth
/// integrating; a report beats silently wrong accelerations.
pub const CONDITION_LIMIT: f64 = 1e13;

/// Solves `a·x = b` for symmetric `a`, overwriting `a` with its factors and `b` with `x`.
/// Tries LDLᵀ; if `a` is not positive definite, `reload` puts the matrix back into `a` and LU
/// factors it. Whether the factors left in `a` are LDLᵀ's ([`ldl_solve_columns`] solves with
/// them) rather than LU's.
pub fn solve_symmetric<M: Square>(
    a: &mut M,
    b: &mut [f64],
    pivots: &mut [usize],
    reload: impl FnOnce(&mut M),
) -> Result<bool, FaultKind> {
    if ldl_in_place(a).is_ok() {
        let n = a.order();
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for i in 0..n {
            lo = lo.min(a[(i, i)]);
            hi = hi.max(a[(i, i)]);
        }
        // The ratio of the extreme pivots bounds the condition number from below.
        if hi / lo > CONDITION_LIMIT {
            let worst = (0..n).filter(|&i| a[(i, i)] * CONDITION_LIMIT < hi).collect::<Vec<_>>();
            return Err(FaultKind::SingularMass { coordinates: worst, condition: hi / lo });
        }
        ldl_solve(a, b);
        return Ok(true);
    }
    reload(a);
    solve_general(a, b, pivots).map(|()| false)
}

/// Solves `a·x = b` by LU with partial pivoting, overwriting `a` and `b`.
pub fn solve_general<M: Square>(
    a: &mut M,
    b: &mut [f64],
    pivots: &mut [usize],
) -> Result<(), FaultKind> {
    lu_in_place(a, pivots)?;
    lu_solve(a, pivots, b);
    Ok(())
}

/// a = L·D·Lᵀ in place: the unit lower factor L below the diagonal, the pivots D on it.
/// Cholesky's factor without its square roots, which with the divisions by them made most of
/// a small solve's time: they sit in one dependent chain. Fails at the first column whose
/// pivot is not positive.
pub fn ldl_in_place<M: Square>(a: &mut M) -> Result<(), usize> {
    let n = a.order();
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)] * a[(k, k)];
        }
        if d <= 0.0 || !d.is_finite() {
            return Err(j);
        }
        a[(j, j)] = d;
        // Each entry's sum is one chain of dependent subtractions, which took most of a large
        // factorization's time waiting on each other: four rows' chains side by side overlap
        // them. Every entry still gets the same operations in the same order, so the bits.
        let mut i = j + 1;
        while i + ROWS <= n {
            let mut s: [f64; ROWS] = std::array::from_fn(|r| a[(i + r, j)]);
            for k in 0..j {
                let (ajk, akk) = (a[(j, k)], a[(k, k)]);
                for (r, s) in s.iter_mut().enumerate() {
                    *s -= a[(i + r, k)] * ajk * akk;
                }
            }
            for (r, s) in s.iter().enumerate() {
                a[(i + r, j)] = s / d;
            }
            i += ROWS;
        }
        for i in i..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)] * a[(k, k)];
            }
            a[(i, j)] = s / d;
        }
    }
    Ok(())
}

/// How many rows [`ldl_in_place`] works on side by side.
const ROWS: usize = 4;

/// Solves with the factors of [`ldl_in_place`]: L, then D, then Lᵀ.
fn ldl_solve<M: Square>(ldl: &M, b: &mut [f64]) {
    let n = ldl.order();
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= ldl[(i, k)] * b[k];
        }
        b[i] = s;
    }
    for (i, v) in b.iter_mut().enumerate().take(n) {
        *v /= ldl[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= ldl[(k, i)] * b[k];
        }
        b[i] = s;
    }
}

/// [`solve_symmetric`]'s LDLᵀ path for [`LANES`] systems at once, kept lane by lane: `a`
/// holds the lower triangle row by row (entry (i, j), j ≤ i, at `i * n + j`) and is
/// overwritten by the factors, `b` by the solutions. Each lane does the operations of
/// [`ldl_in_place`], the condition test and [`ldl_solve`], in their order, so a lane whose
/// flag comes back true holds the bits `solve_symmetric` gives it. A false flag (a pivot
/// that is not positive, or too ill-conditioned) leaves that lane to `solve_symmetric`,
/// which falls back to LU or names the fault.
#[inline(always)]
pub fn solve_symmetric_lanes(n: usize, a: &mut [Lanes], b: &mut [Lanes]) -> [bool; LANES] {
    let mut ok = [true; LANES];
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            for l in 0..LANES {
                d[l] -= a[j * n + k][l] * a[j * n + k][l] * a[k * n + k][l];
            }
        }
        for l in 0..LANES {
            ok[l] &= d[l] > 0.0 && d[l].is_finite();
        }
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                for l in 0..LANES {
                    s[l] -= a[i * n + k][l] * a[j * n + k][l] * a[k * n + k][l];
                }
            }
            for l in 0..LANES {
                a[i * n + j][l] = s[l] / d[l];
            }
        }
    }
    let (mut lo, mut hi) = ([f64::INFINITY; LANES], [0.0f64; LANES]);
    for i in 0..n {
        for l in 0..LANES {
            lo[l] = lo[l].min(a[i * n + i][l]);
            hi[l] = hi[l].max(a[i * n + i][l]);
        }
    }
    // Where hi ≤ lo·limit/2 the quotient cannot pass the limit (the product's rounding is far
    // from closing a factor of two, and lo > 0 in a lane still solving): no lane then needs
    // the division, the slowest operation here. Otherwise each lane divides as
    // `solve_symmetric` does (NaN passing there as here).
    let mut certain = true;
    for l in 0..LANES {
        certain &= !ok[l] || hi[l] <= lo[l] * (0.5 * CONDITION_LIMIT);
    }
    if !certain {
        for l in 0..LANES {
            if hi[l] / lo[l] > CONDITION_LIMIT {
                ok[l] = false;
            }
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            for l in 0..LANES {
                s[l] -= a[i * n + k][l] * b[k][l];
            }
        }
        b[i] = s;
    }
    for i in 0..n {
        for l in 0..LANES {
            b[i][l] /= a[i * n + i][l];
        }
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            for l in 0..LANES {
                s[l] -= a[k * n + i][l] * b[k][l];
            }
        }
        b[i] = s;
    }
    ok
}

/// LU with partial pivoting; `pivots[k]` is the row swapped into place k. A pivot that
/// vanishes relative to the largest entry, or an extreme pivot ratio, is a singular matrix.
pub fn lu_in_place<M: Square>(a: &mut M, pivots: &mut [usize]) -> Result<(), FaultKind> {
    let n = a.order();
    let (a, stride) = a.columns_mut();
    // The small orders each their own copy, the order a constant: a constrained system's
    // five or six rows are factored at every stage, and the rimless wheel's order-5 LU took
    // half the instructions so (the walker's order 6 a fifth fewer).
    if stride == SMALL {
        if let Ok(entries) = <&mut [f64; SMALL * SMALL]>::try_from(&mut *a) {
            match n {
                1 => return lu_fixed::<1>(entries, pivots),
                2 => return lu_fixed::<2>(entries, pivots),
                3 => return lu_fixed::<3>(entries, pivots),
                4 => return lu_fixed::<4>(entries, pivots),
                5 => return lu_fixed::<5>(entries, pivots),
                6 => return lu_fixed::<6>(entries, pivots),
                7 => return lu_fixed::<7>(entries, pivots),
                8 => return lu_fixed::<8>(entries, pivots),
                _ => {}
            }
        }
    }
    lu_columns(a, stride, n, pivots)
}

/// [`lu_columns`] on [`Small`]'s entries with the order a constant: every index provably
/// within the array and every loop's length known, so the same operations in the same order
/// (the same bits) with the bounds checks and the slices' set-up gone. The walker's order-6
/// LU had cost about 2,000 instructions, four times its arithmetic.
fn lu_fixed<const N: usize>(
    a: &mut [f64; SMALL * SMALL],
    pivots: &mut [usize],
) -> Result<(), FaultKind> {
    let pivots = &mut pivots[..N];
    // Comparisons rather than `max` and `min`, which spend instructions on a NaN operand:
    // neither ever takes a NaN here (a NaN entry compares false and is passed over, as `max`
    // passes it over), so the same values.
    let mut scale = 0.0f64;
    for j in 0..N {
        for i in 0..N {
            let v = a[i + SMALL * j].abs();
            if v > scale {
                scale = v;
            }
        }
    }
    if !scale.is_finite() {
        return Err(FaultKind::NonFinite { at: crate::NonFiniteAt::System });
    }
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    let mut vanished = Vec::new();
    for k in 0..N {
        let mut p = k;
        for i in k + 1..N {
            if a[i + SMALL * k].abs() > a[p + SMALL * k].abs() {
                p = i;
            }
        }
        pivots[k] = p;
        if p != k {
            for j in 0..N {
                a.swap(k + SMALL * j, p + SMALL * j);
            }
        }
        let pivot = a[k + SMALL * k];
        let size = pivot.abs();
        if size < lo {
            lo = size;
        }
        if size > hi {
            hi = size;
        }
        if size <= scale * f64::EPSILON * N as f64 {
            vanished.push(k);
            continue;
        }
        for i in k + 1..N {
            a[i + SMALL * k] /= pivot;
        }
        for j in k + 1..N {
            let u = a[k + SMALL * j];
            for i in k + 1..N {
                a[i + SMALL * j] -= a[i + SMALL * k] * u;
            }
        }
    }
    if !vanished.is_empty() || hi / lo > CONDITION_LIMIT {
        if vanished.is_empty() {
            vanished = (0..N).filter(|&k| a[k + SMALL * k].abs() * CONDITION_LIMIT < hi).collect();
        }
        return Err(FaultKind::SingularMass { coordinates: vanished, condition: hi / lo });
    }
    Ok(())
}

/// [`lu_in_place`] on column-major entries `stride` apart, of order `n`.
#[inline(always)]
fn lu_columns(
    a: &mut [f64],
    stride: usize,
    n: usize,
    pivots: &mut [usize],
) -> Result<(), FaultKind> {
    if n == 0 {
        return Ok(());
    }
    let a = &mut a[..(n - 1) * stride + n];
    let pivots = &mut pivots[..n];
    let mut scale = 0.0f64;
    for j in 0..n {
        for v in &a[j * stride..j * stride + n] {
            scale = scale.max(v.abs());
        }
    }
    if !scale.is_finite() {
        return Err(FaultKind::NonFinite { at: crate::NonFiniteAt::System });
    }
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    let mut vanished = Vec::new();
    for k in 0..n {
        let column = &a[k * stride..k * stride + n];
        let mut p = k;
        for i in k + 1..n {
            if column[i].abs() > column[p].abs() {
                p = i;
            }
        }
        pivots[k] = p;
        if p != k {
            for j in 0..n {
                a.swap(j * stride + k, j * stride + p);
            }
        }
        let pivot = a[k * stride + k];
        lo = lo.min(pivot.abs());
        hi = hi.max(pivot.abs());
        if pivot.abs() <= scale * f64::EPSILON * n as f64 {
            vanished.push(k);
            continue;
        }
        for factor in &mut a[k * stride + k + 1..k * stride + n] {
            *factor /= pivot;
        }
        // Column by column: each entry still takes its updates in the order of k, so the
        // factors are the bits a row-by-row sweep gives.
        for j in k + 1..n {
            let (left, right) = a.split_at_mut(j * stride);
            let u = right[k];
            let factors = &left[k * stride + k + 1..k * stride + n];
            for (entry, factor) in right[k + 1..n].iter_mut().zip(factors) {
                *entry -= factor * u;
            }
        }
    }
    if !vanished.is_empty() || hi / lo > CONDITION_LIMIT {
        if vanished.is_empty() {
            vanished = (0..n).filter(|&k| a[k * stride + k].abs() * CONDITION_LIMIT < hi).collect();
        }
        return Err(FaultKind::SingularMass { coordinates: vanished, condition: hi / lo });
    }
    Ok(())
}

/// The rows of `a` that are (nearly) combinations of the rows before them, by Gram–Schmidt
/// in order: a row whose remainder is tiny against its own size depends on earlier ones.
pub fn dependent_rows(a: &DMatrix<f64>) -> Vec<usize> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut dependent = Vec::new();
    for (i, row) in a.row_iter().enumerate() {
        let mut r: Vec<f64> = row.iter().copied().collect();
        let size = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        for b in &basis {
            let dot: f64 = r.iter().zip(b).map(|(x, y)| x * y).sum();
            for (x, y) in r.iter_mut().zip(b) {
                *x -= dot * y;
            }
        }
        let rest = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        if rest <= 1e-8 * size || size == 0.0 {
            dependent.push(i);
        } else {
            basis.push(r.iter().map(|x| x / rest).collect());
        }
    }
    dependent
}

/// The identity on `size` components, row-major (a transition matrix's start, a jump's
/// derivative where nothing moves).
pub(crate) fn identity(size: usize) -> Vec<f64> {
    let mut m = vec![0.0; size * size];
    for i in 0..size {
        m[i * size + i] = 1.0;
    }
    m
}

/// Solves with the factors of [`lu_in_place`].
pub fn lu_solve<M: Square>(lu: &M, pivots: &[usize], b: &mut [f64]) {
    lu_factor_solve(lu, pivots, b);
}

/// [`lu_solve`] for several right-hand sides at once, `b[i]` holding entry i of each. Each
/// substitution is a chain of dependent subtractions; the columns' chains side by side overlap
/// them. Every column gets [`lu_solve`]'s operations in its order, so its bits.
pub fn lu_solve_columns<M: Square, const C: usize>(lu: &M, pivots: &[usize], b: &mut [[f64; C]]) {
    let n = lu.order();
    for k in 0..n {
        b.swap(k, pivots[k]);
    }
    unit_lower_solve_columns(lu, b);
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            let u = lu[(i, k)];
            for (s, b) in s.iter_mut().zip(&b[k]) {
                *s -= u * b;
            }
        }
        let d = lu[(i, i)];
        b[i] = s.map(|s| s / d);
    }
}

/// L·x = b for the columns of `b` side by side, L the unit lower triangle of `l` (LU's and
/// LDLᵀ's first substitution), each entry's sum kept in registers while it runs.
fn unit_lower_solve_columns<M: Square, const C: usize>(l: &M, b: &mut [[f64; C]]) {
    for i in 0..l.order() {
        let mut s = b[i];
        for k in 0..i {
            let lik = l[(i, k)];
            for (s, b) in s.iter_mut().zip(&b[k]) {
                *s -= lik * b;
            }
        }
        b[i] = s;
    }
}

/// Solves with the LDLᵀ factors [`ldl_in_place`] leaves for the columns of `b` side by side
/// (row i of `b` holds their entries i).
pub fn ldl_solve_columns<M: Square, const C: usize>(ldl: &M, b: &mut [[f64; C]]) {
    let n = ldl.order();
    unit_lower_solve_columns(ldl, b);
    for (i, row) in b.iter_mut().enumerate().take(n) {
        let d = ldl[(i, i)];
        *row = row.map(|s| s / d);
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            let l = ldl[(k, i)];
            for (s, x) in s.iter_mut().zip(&b[k]) {
                *s -= l * x;
            }
        }
        b[i] = s;
    }
}

/// LU with partial pivoting of a real or complex matrix, for the iteration matrices of an
/// implicit method. Unlike [`lu_in_place`] it sets no condition limit: those matrices mix
/// 1/h with the Jacobian's entries and are badly scaled without being singular, and Newton's
/// iteration corrects what the factors lose. Fails with the first column whose pivot is zero
/// or not finite.
pub fn lu_factor<T: ComplexField<RealField = f64> + Copy>(
    a: &mut DMatrix<T>,
    pivots: &mut [usize],
) -> Result<(), usize> {
    let n = a.nrows();
    for k in 0..n {
        let mut p = k;
        for i in k + 1..n {
            if a[(i, k)].norm1() > a[(p, k)].norm1() {
                p = i;
            }
        }
        pivots[k] = p;
        if p != k {
            a.swap_rows(k, p);
        }
        let pivot = a[(k, k)];
        let size = pivot.norm1();
        if size == 0.0 || !size.is_finite() {
            return Err(k);
        }
        let inverse = T::one() / pivot;
        for i in k + 1..n {
            let factor = a[(i, k)] * inverse;
            a[(i, k)] = factor;
            if factor.norm1() != 0.0 {
                for j in k + 1..n {
                    let u = a[(k, j)];
                    a[(i, j)] -= factor * u;
                }
            }
        }
    }
    Ok(())
}

/// Solves with the factors of [`lu_factor`].
pub fn lu_factor_solve<T: ComplexField<RealField = f64> + Copy, M: Square<T>>(
    lu: &M,
    pivots: &[usize],
    b: &mut [T],
) {
    let n = lu.order();
    for k in 0..n {
        b.swap(k, pivots[k]);
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= lu[(i, k)] * b[k];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= lu[(i, k)] * b[k];
        }
        b[i] = s / lu[(i, i)];
    }
}

/// ‖(a, b)‖: the size of a slip velocity or of a tangential force in space. The square root
/// is correctly rounded, so its bits are every platform's (`hypot`'s are not); the squares
/// overflow only past 1e154, far beyond any rate or force a scene has.
pub fn size2(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers uniform in [−0.5, 0.5) from `seed` (xorshift64): the same on every machine.
    fn uniform_from(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// Symmetric systems of orders 1 to 6, eight to a call: positive definite and well
    /// conditioned, near the condition limit on either side, indefinite (LU's), singular and
    /// with NaN. Each lane solved side by side must be the bits `solve_symmetric` gives by
    /// LDLᵀ, and each lane it declines must be one `solve_symmetric` factors by LU or rejects.
    #[test]
    fn the_lanes_solve_as_solve_symmetric_does_or_decline() {
        let mut uniform = uniform_from(0x2545_f491_4f6c_dd1du64);
        let (mut side_by_side, mut declined) = (0, 0);
        for n in 1..=6 {
            for round in 0..40 {
                let mut systems = Vec::new();
                for lane in 0..LANES {
                    // A Gram matrix BᵀB plus a diagonal scaled towards the condition limit.
                    let b = DMatrix::from_fn(n, n, |_, _| uniform());
                    let spread = match (round + lane) % 8 {
                        0 => 1e13 * 2.05,
                        1 => 1e13 * 1.95,
                        2 => 1e12,
                        _ => 1.0,
                    };
                    let mut m = b.transpose() * &b;
                    for i in 0..n {
                        m[(i, i)] += if i == 0 { spread } else { 1.0 };
                    }
                    match (round * 8 + lane) % 13 {
                        3 if n > 1 => m[(1, 1)] = -m[(1, 1)],
                        5 => m[(0, 0)] = f64::NAN,
                        7 if n > 1 => m.fill(1.0),
                        _ => {}
                    }
                    let rhs: Vec<f64> = (0..n).map(|_| uniform()).collect();
                    systems.push((m, rhs));
                }
                let mut a = vec![[0.0; LANES]; n * n];
                let mut x = vec![[0.0; LANES]; n];
                for (lane, (m, rhs)) in systems.iter().enumerate() {
                    for i in 0..n {
                        for j in 0..=i {
                            a[i * n + j][lane] = m[(i, j)];
                        }
                        x[i][lane] = rhs[i];
                    }
                }
                let ok = solve_symmetric_lanes(n, &mut a, &mut x);
                for (lane, (m, rhs)) in systems.iter().enumerate() {
                    let mut alone = m.clone();
                    let mut solution = rhs.clone();
                    let mut pivots = vec![0; n];
                    let mut by_lu = false;
                    let solved = solve_symmetric(&mut alone, &mut solution, &mut pivots, |a| {
                        by_lu = true;
                        a.copy_from(m);
                    });
                    if ok[lane] {
                        side_by_side += 1;
                        assert!(solved.is_ok() && !by_lu, "n = {n}: a lane LDLᵀ refused solved");
                        for i in 0..n {
                            assert_eq!(x[i][lane].to_bits(), solution[i].to_bits(), "n = {n}");
                        }
                    } else {
                        declined += 1;
                        assert!(by_lu || solved.is_err(), "n = {n}: a lane declined LDLᵀ takes");
                    }
                }
            }
        }
        assert!(
            side_by_side > 1000 && declined > 200,
            "{side_by_side} solved, {declined} declined"
        );
    }

    /// The factorization's rows taken four side by side give the bits of one row at a time,
    /// at every order from 1 to 40 (whole blocks of four, and one to three rows left over).
    #[test]
    fn ldl_rows_side_by_side_are_the_bits_of_one_at_a_time() {
        let mut uniform = uniform_from(0x9e37_79b9_7f4a_7c15u64);
        for n in 1..=40 {
            let b = DMatrix::from_fn(n, n, |_, _| uniform());
            let m = b.transpose() * &b + DMatrix::identity(n, n);
            let mut one = m.clone();
            for j in 0..n {
                let mut d = one[(j, j)];
                for k in 0..j {
                    d -= one[(j, k)] * one[(j, k)] * one[(k, k)];
                }
                one[(j, j)] = d;
                for i in j + 1..n {
                    let mut s = one[(i, j)];
                    for k in 0..j {
                        s -= one[(i, k)] * one[(j, k)] * one[(k, k)];
                    }
                    one[(i, j)] = s / d;
                }
            }
            let mut four = m.clone();
            ldl_in_place(&mut four).expect("positive definite");
            for j in 0..n {
                for i in j..n {
                    assert_eq!(four[(i, j)].to_bits(), one[(i, j)].to_bits(), "n = {n}");
                }
            }
        }
    }

    /// Right-hand sides solved side by side give the bits of each solved alone.
    #[test]
    fn lu_columns_side_by_side_are_the_bits_of_one_at_a_time() {
        let mut uniform = uniform_from(0x2545_f491_4f6c_dd1du64);
        for n in 1..=20 {
            let mut a = DMatrix::from_fn(n, n, |_, _| uniform());
            let mut pivots = vec![0; n];
            lu_in_place(&mut a, &mut pivots).expect("regular");
            let columns: Vec<Vec<f64>> =
                (0..4).map(|_| (0..n).map(|_| uniform()).collect()).collect();
            let mut block: Vec<[f64; 4]> =
                (0..n).map(|i| std::array::from_fn(|c| columns[c][i])).collect();
            lu_solve_columns(&a, &pivots, &mut block);
            for (c, column) in columns.iter().enumerate() {
                let mut alone = column.clone();
                lu_solve(&a, &pivots, &mut alone);
                for i in 0..n {
                    assert_eq!(block[i][c].to_bits(), alone[i].to_bits(), "n = {n}");
                }
            }
        }
    }

    /// The same for LDLᵀ's factors: each column side by side has the bits `ldl_solve` gives
    /// it alone, so the exact Jacobian's columns are the accelerations' own solve.
    #[test]
    fn ldl_columns_side_by_side_are_the_bits_of_one_at_a_time() {
        let mut uniform = uniform_from(0x9e37_79b9_7f4a_7c15u64);
        for n in 1..=20 {
            // BᵀB + n·I: symmetric positive definite.
            let b = DMatrix::from_fn(n, n, |_, _| uniform());
            let mut a = b.transpose() * &b + DMatrix::identity(n, n) * n as f64;
            ldl_in_place(&mut a).expect("positive definite");
            let columns: Vec<Vec<f64>> =
                (0..8).map(|_| (0..n).map(|_| uniform()).collect()).collect();
            let mut block: Vec<[f64; 8]> =
                (0..n).map(|i| std::array::from_fn(|c| columns[c][i])).collect();
            ldl_solve_columns(&a, &mut block);
            for (c, column) in columns.iter().enumerate() {
                let mut alone = column.clone();
                ldl_solve(&a, &mut alone);
                for i in 0..n {
                    assert_eq!(block[i][c].to_bits(), alone[i].to_bits(), "n = {n}");
                }
            }
        }
    }

    #[test]
    fn ldl_and_lu_solve_the_same_system() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let want = [1.0, -2.0, 0.5];
        let rhs: Vec<f64> = (0..3).map(|i| (0..3).map(|j| m[(i, j)] * want[j]).sum()).collect();
        let mut pivots = [0; 3];
        let mut a = m.clone();
        let mut x = rhs.clone();
        solve_symmetric(&mut a, &mut x, &mut pivots, |a| a.copy_from(&m)).unwrap();
        let mut a = m.clone();
        let mut y = rhs.clone();
        solve_general(&mut a, &mut y, &mut pivots).unwrap();
        for i in 0..3 {
            assert!((x[i] - want[i]).abs() < 1e-14);
            assert!((y[i] - want[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn stack_and_heap_storage_give_the_same_bits() {
        // A symmetric positive definite 3×3 by LDLᵀ and a 4×4 with a zero corner by LU.
        let entries = [
            (3, vec![4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]),
            (
                4,
                vec![
                    2.0, 0.3, 1.0, 0.0, 0.3, 1.5, -1.0, 0.7, -1.0, 1.0, 0.0, 0.0, 0.0, -0.7, 0.0,
                    0.0,
                ],
            ),
        ];
        for (n, values) in entries {
            let heap = DMatrix::from_column_slice(n, n, &values);
            let mut small = Small::zeros(n).expect("small enough");
            for j in 0..n {
                for i in 0..n {
                    small[(i, j)] = heap[(i, j)];
                }
            }
            let rhs: Vec<f64> = (0..n).map(|i| 1.0 / (i as f64 + 0.7)).collect();
            let (mut x, mut y) = (rhs.clone(), rhs.clone());
            let (mut a, mut b) = (heap.clone(), small);
            if n == 3 {
                solve_symmetric(&mut a, &mut x, &mut [0; 3], |a| a.copy_from(&heap)).unwrap();
                solve_symmetric(&mut b, &mut y, &mut [0; 3], |_| unreachable!()).unwrap();
            } else {
                solve_general(&mut a, &mut x, &mut [0; 4]).unwrap();
                solve_general(&mut b, &mut y, &mut [0; 4]).unwrap();
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&y));
            let residual = (0..n)
                .map(|i| ((0..n).map(|j| heap[(i, j)] * x[j]).sum::<f64>() - rhs[i]).abs())
                .fold(0.0, f64::max);
            assert!(residual < 1e-14, "{residual}");
        }
        assert!(Small::zeros(SMALL + 1).is_none());
    }

    #[test]
    fn indefinite_falls_back_to_lu() {
        let m = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 1.0, 0.0]);
        let mut a = m.clone();
        let mut x = [2.0, 3.0];
        solve_symmetric(&mut a, &mut x, &mut [0; 2], |a| a.copy_from(&m)).unwrap();
        assert_eq!(x, [3.0, 2.0]);
    }

    #[test]
    fn dependent_rows_are_found_in_order() {
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 0.0, 1.0, 2.0, 5.0]);
        assert_eq!(dependent_rows(&a), vec![2]);
        let b = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 1.0, 0.0]);
        assert_eq!(dependent_rows(&b), vec![0]);
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        assert!(dependent_rows(&c).is_empty());
    }

    #[test]
    fn singular_matrix_names_the_vanishing_column() {
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        let mut a = m.clone();
        let err =
            solve_symmetric(&mut a, &mut [1.0, 1.0], &mut [0; 2], |a| a.copy_from(&m)).unwrap_err();
        assert!(
            matches!(err, FaultKind::SingularMass { ref coordinates, .. } if coordinates == &[1])
        );
    }
    #[test]
    fn complex_lu_solves_a_complex_system() {
        use nalgebra::Complex;
        let c = |re, im| Complex::new(re, im);
        let m = DMatrix::from_row_slice(
            3,
            3,
            &[
                c(0.0, 1.0),
                c(2.0, 0.0),
                c(0.0, 0.0),
                c(1.0, -1.0),
                c(0.5, 0.5),
                c(3.0, 0.0),
                c(0.0, 0.0),
                c(1.0, 2.0),
                c(-1.0, 1.0),
            ],
        );
        let want = [c(1.0, 2.0), c(-0.5, 0.25), c(0.0, -3.0)];
        let mut b: Vec<Complex<f64>> =
            (0..3).map(|i| (0..3).map(|j| m[(i, j)] * want[j]).sum()).collect();
        let mut lu = m.clone();
        let mut pivots = [0; 3];
        lu_factor(&mut lu, &mut pivots).unwrap();
        lu_factor_solve(&lu, &pivots, &mut b);
        for i in 0..3 {
            assert!((b[i] - want[i]).norm() < 1e-14, "{:?}", b);
        }
        let mut singular = DMatrix::from_element(2, 2, c(1.0, 1.0));
        assert_eq!(lu_factor(&mut singular, &mut [0; 2]), Err(1));
    }
}
