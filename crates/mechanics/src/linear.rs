//! Exact solution of small linear systems whose entries are expressions.

use cas::{ExprId, Pool};

/// Solves `a · x = b` by Gaussian elimination, choosing as pivot the first entry not
/// identically zero. `None` when the matrix is singular as far as the algebra can tell.
/// Meant for small systems (accelerations at the start, reactions): entries grow with size.
pub fn solve(pool: &mut Pool, a: &[Vec<ExprId>], b: &[ExprId]) -> Option<Vec<ExprId>> {
    let n = b.len();
    let mut m: Vec<Vec<ExprId>> = a
        .iter()
        .zip(b)
        .map(|(row, rhs)| {
            let mut r = row.clone();
            r.push(*rhs);
            r
        })
        .collect();
    for col in 0..n {
        let pivot = (col..n).find(|&r| !pool.is_identically_zero(m[r][col]))?;
        m.swap(col, pivot);
        let inv = pool.powi(m[col][col], -1);
        for entry in m[col][col..].iter_mut() {
            let v = pool.mul2(*entry, inv);
            *entry = pool.simplify(v);
        }
        let pivot_row = m[col].clone();
        for (r, row) in m.iter_mut().enumerate() {
            if r == col || pool.is_zero(row[col]) {
                continue;
            }
            let factor = row[col];
            for (entry, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                let p = pool.mul2(factor, *p);
                let d = pool.sub(*entry, p);
                *entry = pool.simplify(d);
            }
        }
    }
    Some(m.into_iter().map(|row| row[n]).collect())
}
