//! The first-order form exactly, where the algebra can give it: in the holonomic case with no
//! constraint kept, A = [0, I; −M⁻¹K, −M⁻¹C] and B = [0; M⁻¹·Q_u] as expressions of the
//! parameters, solved by `cas`'s exact linear systems within a budget, and C and D, the
//! outputs' gradients along the state.

use cas::linear_system::{solve_within, Solution};
use cas::{ExprId, Pool};

use crate::{Case, Component, Linearization};

/// How many new expression nodes the exact solve may build before numbers are left to do it.
const BUDGET: usize = 200_000;

/// A, B, C and D exactly, the state as the numbers name it (every coordinate's position, or
/// all but the cyclic ones', then every rate).
#[derive(Clone, Debug)]
pub struct ExactStateSpace {
    pub state: Vec<Component>,
    pub a: Vec<Vec<ExprId>>,
    pub b: Vec<Vec<ExprId>>,
    /// One row per output: its gradient along the state.
    pub c: Vec<Vec<ExprId>>,
    /// One row per output, one column per input.
    pub d: Vec<Vec<ExprId>>,
}

/// A and B exactly, or `None`: with constraints kept or velocity constraints (where the
/// reduction is done in numbers), or where M is singular or too large to solve within the
/// budget.
pub fn exact_state_space(pool: &mut Pool, lin: &Linearization) -> Option<ExactStateSpace> {
    if !matches!(&lin.case, Case::Holonomic { constraints } if constraints.is_empty()) {
        return None;
    }
    let n = lin.coords.len();
    let positions: Vec<usize> = (0..n).filter(|&i| lin.keep_cyclic || !lin.cyclic[i]).collect();
    let ni = lin.inputs.len();
    // Each right-hand side of M·X = (−K, −C, Q_u) solved, column by column.
    let column = |pool: &mut Pool, rhs: Vec<ExprId>| -> Option<Vec<ExprId>> {
        match solve_within(pool, &lin.mass, &rhs, BUDGET) {
            Solution::Solved(x) => Some(x.into_iter().map(|e| pool.simplify(e)).collect()),
            Solution::Singular | Solution::TooLarge => None,
        }
    };
    let mut stiffness = Vec::new();
    for &i in &positions {
        let rhs: Vec<ExprId> = (0..n).map(|j| pool.neg(lin.stiffness[j][i])).collect();
        stiffness.push(column(pool, rhs)?);
    }
    let mut damping = Vec::new();
    for i in 0..n {
        let rhs: Vec<ExprId> = (0..n).map(|j| pool.neg(lin.damping[j][i])).collect();
        damping.push(column(pool, rhs)?);
    }
    let mut forces = Vec::new();
    for k in 0..ni {
        let rhs: Vec<ExprId> = (0..n).map(|j| lin.input_forces[j][k]).collect();
        forces.push(column(pool, rhs)?);
    }
    let p = positions.len();
    let (zero, one) = (pool.zero(), pool.one());
    let mut a = vec![vec![zero; p + n]; p + n];
    let mut b = vec![vec![zero; ni]; p + n];
    for (row, &i) in positions.iter().enumerate() {
        a[row][p + i] = one;
    }
    for j in 0..n {
        for col in 0..p {
            a[p + j][col] = stiffness[col][j];
        }
        for col in 0..n {
            a[p + j][p + col] = damping[col][j];
        }
        for k in 0..ni {
            b[p + j][k] = forces[k][j];
        }
    }
    let state: Vec<Component> = positions
        .iter()
        .map(|&i| Component::Position(i))
        .chain((0..n).map(Component::Rate))
        .collect();
    let along = |row: &crate::OutputRow| -> Vec<ExprId> {
        let of = |c: &Component| match *c {
            Component::Position(i) => row.positions[i],
            Component::Rate(i) => row.rates[i],
            Component::Along(_) | Component::RateAlong(_) => zero,
        };
        state.iter().map(of).collect()
    };
    let c = lin.outputs.iter().map(along).collect();
    let d = lin.outputs.iter().map(|row| row.inputs.clone()).collect();
    Some(ExactStateSpace { state, a, b, c, d })
}
