//! Linear complementarity problems of contacts: w = A·x + c with, per normal row, x ≥ 0,
//! w ≥ 0 and x·w = 0, and per tangent row of an active normal w = 0 with x free (of an
//! inactive one, x = 0). A stand-in solved by enumerating active sets, fewest active first,
//! each by the least-norm solution of its rows; the contacts' own solver replaces it.

use nalgebra::{DMatrix, DVector};

/// What a row of the problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// x ≥ 0, w ≥ 0, x·w = 0.
    Normal,
    /// Of an active normal: w = 0, x free; of an inactive one: x = 0.
    Tangent { normal: usize },
}

/// A solution: x, w = A·x + c, and which rows are active.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    pub x: Vec<f64>,
    pub w: Vec<f64>,
    pub active: Vec<bool>,
}

/// No active set solves the problem; `rows` are the normal rows that want to be active.
#[derive(Clone, Debug, PartialEq)]
pub struct Inconsistent {
    pub rows: Vec<usize>,
}

/// The most normal rows the stand-in enumerates the active sets of; a larger problem is
/// reported as unsolved, with all its normal rows.
const ENUMERATED: usize = 16;

/// Solves the problem of a symmetric positive semi-definite `a` (possibly singular), with the
/// least-norm x for the active set found; `tolerance` is absolute, in c's units.
pub fn solve(
    a: &DMatrix<f64>,
    c: &[f64],
    rows: &[Row],
    tolerance: f64,
) -> Result<Solution, Inconsistent> {
    let size = c.len();
    let normals: Vec<usize> = (0..size).filter(|&i| rows[i] == Row::Normal).collect();
    let diagonal = (0..size).map(|i| a[(i, i)].abs()).fold(0.0, f64::max);
    // x's tolerance, from c's through A's scale.
    let x_tolerance = if diagonal > 0.0 { tolerance / diagonal } else { tolerance };
    let count = normals.len();
    if count > ENUMERATED {
        return Err(Inconsistent { rows: normals });
    }
    let mut sets: Vec<u32> = (0..1u32 << count).collect();
    sets.sort_by_key(|s| s.count_ones());
    for set in sets {
        let on = |i: usize| match rows[i] {
            Row::Normal => (set >> normals.iter().position(|&k| k == i).expect("normal")) & 1 == 1,
            Row::Tangent { normal } => {
                (set >> normals.iter().position(|&k| k == normal).expect("normal")) & 1 == 1
            }
        };
        let active: Vec<bool> = (0..size).map(on).collect();
        let chosen: Vec<usize> = (0..size).filter(|&i| active[i]).collect();
        let mut x = vec![0.0; size];
        if !chosen.is_empty() {
            let sub =
                DMatrix::from_fn(chosen.len(), chosen.len(), |r, s| a[(chosen[r], chosen[s])]);
            let rhs = DVector::from_iterator(chosen.len(), chosen.iter().map(|&i| -c[i]));
            let Ok(solved) =
                sub.svd(true, true).solve(&rhs, 1e-12 * diagonal.max(f64::MIN_POSITIVE))
            else {
                continue;
            };
            for (r, &i) in chosen.iter().enumerate() {
                x[i] = solved[r];
            }
        }
        let w: Vec<f64> =
            (0..size).map(|i| c[i] + (0..size).map(|j| a[(i, j)] * x[j]).sum::<f64>()).collect();
        let fits = (0..size).all(|i| match (rows[i], active[i]) {
            (_, true) => {
                w[i].abs() <= tolerance && (rows[i] != Row::Normal || x[i] >= -x_tolerance)
            }
            (Row::Normal, false) => w[i] >= -tolerance,
            (Row::Tangent { .. }, false) => true,
        });
        if fits {
            return Ok(Solution { x, w, active });
        }
    }
    Err(Inconsistent { rows: normals.into_iter().filter(|&i| c[i] < -tolerance).collect() })
}
