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
        for k in col..=n {
            let v = pool.mul2(m[col][k], inv);
            m[col][k] = pool.simplify(v);
        }
        for r in 0..n {
            if r == col || pool.is_zero(m[r][col]) {
                continue;
            }
            let factor = m[r][col];
            for k in col..=n {
                let p = pool.mul2(factor, m[col][k]);
                let d = pool.sub(m[r][k], p);
                m[r][k] = pool.simplify(d);
            }
        }
    }
    Some(m.into_iter().map(|row| row[n]).collect())
}
