//! Where each matrix of a case sits among the outputs of its lowered program: blocks placed
//! as the program's outputs are gathered, and read back by the same blocks, so that no offset
//! is computed twice.

use cas::ExprId;
use nalgebra::{DMatrix, DVector};

/// A rows × columns matrix, row by row, from `start` of a program's outputs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Block {
    start: usize,
    rows: usize,
    columns: usize,
}

impl Block {
    /// The matrix in `out`, the program's outputs.
    pub fn matrix(&self, out: &[f64]) -> DMatrix<f64> {
        DMatrix::from_fn(self.rows, self.columns, |j, i| out[self.start + j * self.columns + i])
    }

    /// A block of one column (or one row) as a vector.
    pub fn vector(&self, out: &[f64]) -> DVector<f64> {
        DVector::from_column_slice(&out[self.start..self.start + self.rows * self.columns])
    }

    /// A block of one value.
    pub fn value(&self, out: &[f64]) -> f64 {
        out[self.start]
    }
}

/// The outputs of a program being gathered.
#[derive(Default)]
pub(crate) struct Outputs {
    exprs: Vec<ExprId>,
}

impl Outputs {
    /// A matrix of `columns` columns (given, so that a matrix of no rows keeps its shape).
    pub fn matrix(&mut self, m: &[Vec<ExprId>], columns: usize) -> Block {
        let start = self.exprs.len();
        for row in m {
            debug_assert_eq!(row.len(), columns);
            self.exprs.extend(row);
        }
        Block { start, rows: m.len(), columns }
    }

    /// A column.
    pub fn column(&mut self, v: &[ExprId]) -> Block {
        let start = self.exprs.len();
        self.exprs.extend(v);
        Block { start, rows: v.len(), columns: 1 }
    }

    /// One value.
    pub fn value(&mut self, e: ExprId) -> Block {
        self.column(&[e])
    }

    /// Everything gathered, in order: the program's outputs.
    pub fn exprs(&self) -> &[ExprId] {
        &self.exprs
    }
}

/// M, C, K (n × n) and the residual (n) in all the coordinates, as the holonomic and the kept
/// cases place them first.
pub(crate) struct Equations {
    pub mass: Block,
    pub damping: Block,
    pub stiffness: Block,
    /// f + Jᵀλ, which is f with the multipliers at 0.
    pub residual: Block,
}

impl Equations {
    pub fn place(outputs: &mut Outputs, lin: &crate::Linearization) -> Equations {
        let n = lin.coords.len();
        Equations {
            mass: outputs.matrix(&lin.mass, n),
            damping: outputs.matrix(&lin.damping, n),
            stiffness: outputs.matrix(&lin.stiffness, n),
            residual: outputs.column(&lin.residual),
        }
    }
}

/// The rows of kept constraints, each a block of its own: the rows of J (each n long), then
/// each constraint's γ.
#[derive(Clone, Debug)]
pub(crate) struct ConstraintRows {
    pub jacobian: Vec<Block>,
    pub bias: Vec<Block>,
}

impl ConstraintRows {
    /// J (k × n) and γ (k) in `out`.
    pub fn read(&self, out: &[f64], n: usize) -> (DMatrix<f64>, DVector<f64>) {
        let k = self.jacobian.len();
        let jacobian = DMatrix::from_fn(k, n, |c, i| out[self.jacobian[c].start + i]);
        let bias = DVector::from_fn(k, |c, _| self.bias[c].value(out));
        (jacobian, bias)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_read_back_what_was_placed() {
        let mut pool = cas::Pool::new();
        let e: Vec<ExprId> = (0..7).map(|k| pool.int(k)).collect();
        let mut outputs = Outputs::default();
        let m = outputs.matrix(&[vec![e[0], e[1]], vec![e[2], e[3]]], 2);
        let empty = outputs.matrix(&[], 3);
        let v = outputs.column(&[e[4], e[5]]);
        let s = outputs.value(e[6]);
        assert_eq!(outputs.exprs().len(), 7);
        let out: Vec<f64> = (0..7).map(f64::from).collect();
        assert_eq!(m.matrix(&out), DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 2.0, 3.0]));
        assert_eq!(empty.matrix(&out).shape(), (0, 3));
        assert_eq!(v.vector(&out), DVector::from_column_slice(&[4.0, 5.0]));
        assert_eq!(s.value(&out), 6.0);
    }
}
