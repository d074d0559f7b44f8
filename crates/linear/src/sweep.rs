//! The eigenvalues against one parameter: n values from a to b, and every change of the
//! verdict between neighbours found by bisection.

use crate::spectrum::largest_real_part;
use crate::{Numbers, Stability};

/// Bisection stops when the bracket of a change of stability is this narrow, relatively.
const SWEEP_PRECISION: f64 = 1e-10;

/// One value of a sweep.
#[derive(Clone, Debug)]
pub struct Row {
    pub value: f64,
    pub eigenvalues: Vec<(f64, f64)>,
    /// Each eigenvalue's bound on rounding, as [`Numbers`] has them.
    pub bounds: Vec<f64>,
    pub stability: Stability,
    /// M, C and K at this value, as [`Numbers`] has them.
    pub mass: Vec<Vec<f64>>,
    pub damping: Vec<Vec<f64>>,
    pub stiffness: Vec<Vec<f64>>,
}

/// A value of the swept parameter where the verdict changes, bracketed by bisection.
#[derive(Clone, Copy, Debug)]
pub struct Change {
    pub value: f64,
    /// The verdict just before (towards the start of the sweep) and just after.
    pub from: Stability,
    pub to: Stability,
    /// The last bracket: `from` holds at its first end, `to` at its second.
    pub bracket: (f64, f64),
}

/// The eigenvalues against one parameter.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub parameter: String,
    pub rows: Vec<Row>,
    pub changes: Vec<Change>,
}

/// n evenly spaced values from a to b, each analysed by `analyse`, and every change of the
/// verdict between neighbours bisected (one per pair of neighbours: a finer sweep finds
/// changes closer together).
pub fn sweep<E>(
    parameter: String,
    (a, b, n): (f64, f64, usize),
    mut analyse: impl FnMut(f64) -> Result<Numbers, E>,
) -> Result<Sweep, E> {
    let mut rows = Vec::with_capacity(n);
    for k in 0..n {
        let value = if k == n - 1 { b } else { a + (b - a) * k as f64 / (n - 1) as f64 };
        let numbers = analyse(value)?;
        rows.push(Row {
            value,
            eigenvalues: numbers.eigenvalues,
            bounds: numbers.bounds,
            stability: numbers.stability,
            mass: numbers.mass,
            damping: numbers.damping,
            stiffness: numbers.stiffness,
        });
    }
    let mut changes = Vec::new();
    for pair in rows.windows(2) {
        let (first, second) = (&pair[0], &pair[1]);
        if first.stability != second.stability {
            changes.push(bisect(first, second, &mut analyse)?);
        }
    }
    Ok(Sweep { parameter, rows, changes })
}

/// The change of the verdict between two neighbouring rows, bracketed.
fn bisect<E>(
    first: &Row,
    second: &Row,
    analyse: &mut impl FnMut(f64) -> Result<Numbers, E>,
) -> Result<Change, E> {
    let (from, mut to) = (first.stability, second.stability);
    let (mut lo, mut hi) = (first.value, second.value);
    // Between stable and unstable, the largest real part crosses zero: bisecting on its sign
    // finds the crossing itself, where the verdict would stop at the edge of the tolerance
    // band around zero.
    let through_zero = matches!(
        (from, to),
        (Stability::Stable, Stability::Unstable) | (Stability::Unstable, Stability::Stable)
    );
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let narrow = (hi - lo).abs() <= SWEEP_PRECISION * lo.abs().max(hi.abs());
        if narrow || mid == lo || mid == hi {
            break;
        }
        let numbers = analyse(mid)?;
        let like_from = if through_zero {
            (largest_real_part(&numbers) > 0.0) == (from == Stability::Unstable)
        } else {
            numbers.stability == from
        };
        if like_from {
            lo = mid;
        } else {
            hi = mid;
            if !through_zero {
                to = numbers.stability;
            }
        }
    }
    Ok(Change { value: 0.5 * (lo + hi), from, to, bracket: (lo, hi) })
}
