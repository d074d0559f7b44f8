//! Exact solution of linear systems whose entries are expressions: Cramer's rule with
//! cancelled quotients for small systems, Gauss–Jordan elimination under a node budget beyond.

use std::collections::BTreeMap;

use crate::number::{Signed, Zero};
use crate::{ExprId, Node, Pool, Rational};

/// Up to this size, Cramer's rule with cancelled quotients; beyond, Gaussian elimination.
const CRAMER_LIMIT: usize = 4;

/// Solves `a · x = b`. `None` when the matrix is singular as far as the algebra can tell.
/// Small systems use Cramer's rule, which keeps each unknown one quotient of polynomials with
/// their common factors cancelled (λ = m·(g·y − ẋ² − ẏ²)/(2·x² + 2·y²)).
pub fn solve(pool: &mut Pool, a: &[Vec<ExprId>], b: &[ExprId]) -> Option<Vec<ExprId>> {
    match solve_within(pool, a, b, usize::MAX) {
        Solution::Solved(x) => Some(x),
        Solution::Singular | Solution::TooLarge => None,
    }
}

/// The outcome of [`solve_within`].
#[derive(Clone, Debug, PartialEq)]
pub enum Solution {
    Solved(Vec<ExprId>),
    /// The matrix is singular as far as the algebra can tell.
    Singular,
    /// The elimination built more than the budget of new expression nodes and was abandoned:
    /// dense symbolic systems grow without bound, and a numeric answer beats a hang.
    TooLarge,
}

/// [`solve`] that gives up once it has added `budget` nodes to the pool. The budget counts
/// nodes, not time, so the same scene gets the same answer on every machine.
pub fn solve_within(pool: &mut Pool, a: &[Vec<ExprId>], b: &[ExprId], budget: usize) -> Solution {
    let limit = pool.len().saturating_add(budget);
    let result = if b.len() <= CRAMER_LIMIT {
        cramer(pool, a, b).ok_or(Stop::Singular)
    } else {
        gauss(pool, a, b, limit)
    };
    match result {
        Ok(x) if pool.len() <= limit => Solution::Solved(x),
        _ if pool.len() > limit => Solution::TooLarge,
        Ok(x) => Solution::Solved(x),
        Err(Stop::TooLarge) => Solution::TooLarge,
        Err(Stop::Singular) => Solution::Singular,
    }
}

/// Why Gauss–Jordan elimination stopped short of a solution.
enum Stop {
    /// No pivot in a column: the matrix is singular.
    Singular,
    /// An entry outgrew the size a simplification may start from, or the pool its budget.
    TooLarge,
}

fn cramer(pool: &mut Pool, a: &[Vec<ExprId>], b: &[ExprId]) -> Option<Vec<ExprId>> {
    let d = determinant(pool, a);
    if pool.is_identically_zero(d) {
        return None;
    }
    let mut out = Vec::with_capacity(b.len());
    for i in 0..b.len() {
        let replaced: Vec<Vec<ExprId>> = a
            .iter()
            .zip(b)
            .map(|(row, rhs)| {
                let mut r = row.clone();
                r[i] = *rhs;
                r
            })
            .collect();
        let n = determinant(pool, &replaced);
        out.push(quotient(pool, n, d));
    }
    Some(out)
}

/// Laplace expansion along the first row; fine for the sizes Cramer's rule is used at.
fn determinant(pool: &mut Pool, m: &[Vec<ExprId>]) -> ExprId {
    match m.len() {
        0 => pool.one(),
        1 => m[0][0],
        _ => {
            let mut terms = Vec::new();
            for (j, &entry) in m[0].iter().enumerate() {
                if pool.is_zero(entry) {
                    continue;
                }
                let minor: Vec<Vec<ExprId>> = m[1..]
                    .iter()
                    .map(|row| {
                        row.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, e)| *e).collect()
                    })
                    .collect();
                let sub = determinant(pool, &minor);
                let t = pool.mul2(entry, sub);
                terms.push(if j % 2 == 0 { t } else { pool.neg(t) });
            }
            let sum = pool.add(&terms);
            pool.expand(sum)
        }
    }
}

/// `n / d` with denominators cleared from both and their common monomial factor cancelled.
pub fn quotient(pool: &mut Pool, n: ExprId, d: ExprId) -> ExprId {
    let (n, d) = (pool.expand(n), pool.expand(d));
    // Multiply both by every denominator either has, so both are polynomials.
    let mut clear: BTreeMap<ExprId, Rational> = BTreeMap::new();
    for e in [n, d] {
        for t in pool.terms(e) {
            let (_, fs) = pool.factors(t);
            for (base, x) in fs {
                if x.is_negative() && pool.as_num(base).is_none() {
                    let need = -x.floor();
                    let slot = clear.entry(base).or_insert_with(Rational::zero);
                    if need > *slot {
                        *slot = need;
                    }
                }
            }
        }
    }
    let factors: Vec<(ExprId, Rational)> = clear.into_iter().collect();
    let c = pool.product(&Rational::from_integer(1.into()), &factors);
    let mut scaled = [n, d];
    for e in scaled.iter_mut() {
        let parts: Vec<ExprId> = pool
            .terms(*e)
            .into_iter()
            .map(|t| {
                let m = pool.mul2(t, c);
                pool.expand(m)
            })
            .collect();
        let sum = pool.add(&parts);
        *e = pool.expand(sum);
    }
    let [n, d] = scaled;
    let (content, n) = pool.common_content(&[n, d]);
    let inverse = pool.powi(content, -1);
    let d = pool.mul2(d, inverse);
    let d = pool.expand(d);
    let (n, d) = if pool.looks_negative(d) { (pool.neg(n), pool.neg(d)) } else { (n, d) };
    let n = pool.factor_content(n);
    let d = pool.simplify(d);
    if let Node::Num(q) = pool.node(d) {
        let q = q.clone();
        return pool.scale(n, &q.recip());
    }
    pool.div(n, d)
}

/// Under a budget, the largest entry (in distinct nodes) the elimination will simplify.
const ENTRY_LIMIT: usize = 1_500;

/// The number of distinct nodes of `e`, counted up to `cap`.
fn dag_size(pool: &Pool, e: ExprId, cap: usize) -> usize {
    let mut seen = std::collections::HashSet::new();
    let mut stack = vec![e];
    while let Some(x) = stack.pop() {
        if seen.len() >= cap {
            break;
        }
        if seen.insert(x) {
            stack.extend(pool.children(x));
        }
    }
    seen.len()
}

/// Gauss–Jordan elimination, choosing as pivot the first entry not identically zero.
/// Stops (returning `None`) as soon as the pool grows past `limit` nodes.
fn gauss(
    pool: &mut Pool,
    a: &[Vec<ExprId>],
    b: &[ExprId],
    limit: usize,
) -> Result<Vec<ExprId>, Stop> {
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
        let pivot =
            (col..n).find(|&r| !pool.is_identically_zero(m[r][col])).ok_or(Stop::Singular)?;
        m.swap(col, pivot);
        let inv = pool.powi(m[col][col], -1);
        for entry in m[col][col..].iter_mut() {
            let v = pool.mul2(*entry, inv);
            if limit != usize::MAX && dag_size(pool, v, ENTRY_LIMIT) >= ENTRY_LIMIT {
                return Err(Stop::TooLarge);
            }
            *entry = pool.simplify(v);
            if pool.len() > limit {
                return Err(Stop::TooLarge);
            }
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
                // One simplification of a large entry can build millions of nodes by itself;
                // past the budget, refuse before starting it.
                if limit != usize::MAX && dag_size(pool, d, ENTRY_LIMIT) >= ENTRY_LIMIT {
                    return Err(Stop::TooLarge);
                }
                *entry = pool.simplify(d);
                if pool.len() > limit {
                    return Err(Stop::TooLarge);
                }
            }
        }
    }
    Ok(m.into_iter().map(|row| row[n]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Style;

    /// An entry past the size a simplification may start from stops the elimination as too
    /// large: it used to read as "no pivot", and a regular start was reported singular.
    #[test]
    fn an_entry_too_large_to_simplify_is_too_large_not_singular() {
        let mut p = Pool::new();
        let symbols: Vec<ExprId> = (0..900)
            .map(|k| {
                let s = p.param(&format!("s{k}"));
                p.sym(s)
            })
            .collect();
        let products: Vec<ExprId> = symbols.windows(2).map(|w| p.mul2(w[0], w[1])).collect();
        let mut large = products;
        large.push(p.one());
        let large = p.add(&large);
        let n = 5;
        let a: Vec<Vec<ExprId>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| match (i, j) {
                        (0, 0) => large,
                        _ if i == j => p.one(),
                        (0, _) => symbols[j],
                        _ => p.zero(),
                    })
                    .collect()
            })
            .collect();
        let b: Vec<ExprId> = (0..n).map(|i| symbols[i + 10]).collect();
        assert_eq!(solve_within(&mut p, &a, &b, 50_000_000), Solution::TooLarge);
    }

    #[test]
    fn pendulum_multiplier_cancels() {
        let mut p = Pool::new();
        let names = ["m", "g", "x", "y", "u", "v"];
        let e: Vec<ExprId> = names
            .iter()
            .map(|n| {
                let s = p.param(n);
                p.sym(s)
            })
            .collect();
        let (m, g, x, y, u, v) = (e[0], e[1], e[2], e[3], e[4], e[5]);
        let zero = p.zero();
        let two = crate::number::int(2);
        let mx = p.scale(x, &-two.clone());
        let my = p.scale(y, &-two.clone());
        let px = p.scale(x, &two);
        let py = p.scale(y, &two);
        let mg = p.mul2(m, g);
        let mg = p.neg(mg);
        let u2 = p.powi(u, 2);
        let v2 = p.powi(v, 2);
        let s = p.add2(u2, v2);
        let gamma = p.scale(s, &-two);
        let a = vec![vec![m, zero, mx], vec![zero, m, my], vec![px, py, zero]];
        let b = vec![zero, mg, gamma];
        let sol = solve(&mut p, &a, &b).unwrap();
        assert_eq!(p.print(sol[2], Style::Ascii), "-m*(-g*y + u^2 + v^2)/(2*x^2 + 2*y^2)");
    }
}
