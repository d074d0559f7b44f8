//! The linear system of one instant in floating point: rows · (q̈, λ) = rhs at a state, as
//! `check` and the numeric start solve it.

use cas::{ExprId, SymId};
use mechanics::Derivation;
use nalgebra::{DMatrix, DVector};
use numeric::Evaluator;

/// The system's matrix and right-hand side, lowered once.
pub(crate) struct System {
    unknowns: Vec<SymId>,
    /// The matrix row after row, then the right-hand side.
    evaluator: Evaluator,
}

impl System {
    pub(crate) fn new(d: &mut Derivation) -> System {
        let (rows, rhs) = d.system();
        let exprs: Vec<ExprId> = rows.iter().flatten().chain(&rhs).copied().collect();
        System { unknowns: d.unknowns(), evaluator: Evaluator::new(&d.model.pool, &exprs) }
    }

    pub(crate) fn unknowns(&self) -> &[SymId] {
        &self.unknowns
    }

    /// The matrix and right-hand side at a state; `None` where an entry is not finite.
    pub(crate) fn at(&mut self, values: &[f64]) -> Option<(DMatrix<f64>, DVector<f64>)> {
        let n = self.unknowns.len();
        let out = self.evaluator.eval(values);
        let a = DMatrix::from_fn(n, n, |i, j| out[i * n + j]);
        let b = DVector::from_fn(n, |i, _| out[n * n + i]);
        a.iter().chain(b.iter()).all(|x| x.is_finite()).then_some((a, b))
    }

    /// Solves for the unknowns at a state and writes them into it; `None` where the system
    /// is undefined or singular there.
    pub(crate) fn solve(&mut self, values: &mut [f64]) -> Option<()> {
        if self.unknowns.is_empty() {
            return Some(());
        }
        let (a, b) = self.at(values)?;
        let x = a.lu().solve(&b)?;
        for (u, v) in self.unknowns.iter().zip(x.iter()) {
            values[u.index()] = *v;
        }
        Some(())
    }
}

/// Solves for the unknowns at a state (see [`System::solve`]), lowering the system on first
/// use: a derivation whose checks never need the unknowns never builds it.
pub(crate) fn solve_unknowns(
    d: &mut Derivation,
    system: &mut Option<System>,
    values: &mut [f64],
) -> Option<()> {
    if d.unknowns().is_empty() {
        return Some(());
    }
    system.get_or_insert_with(|| System::new(d)).solve(values)
}
