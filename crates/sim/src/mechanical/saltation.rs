//! Exact derivatives of a contact's jump, of which `sim::variational` makes its saltation
//! matrices: the impulse of Newton's law without friction, its rows that took an impulse held,
//! and the least-change projections that put a state on a mode's manifold. Each is a linear
//! solve with the augmented matrix [M −Gᵀ; G 0] of the rows it holds, its right-hand sides
//! the partials program's rows ([`Mechanical::partials_at`]), so no step size enters.
//!
//! The partials program differentiates r = M·a − Jᵀ·λ − f and c = J·a − γ with a and λ
//! given: evaluated once at the impulse (a = Δq̇, λ = Λ) and once at a = 0, λ = 0, its
//! difference is ∂(M·Δq̇ − Jᵀ·Λ) and ∂(J·Δq̇), the terms of f and γ gone. The rates a law
//! or a projection holds (Φ̇ of a position row, A·q̇ + b of a velocity row) have their
//! partials in the same program.

use nalgebra::DMatrix;

use super::jacobian::COLUMNS;
use super::modes::Struck;
use super::{Layout, Mechanical, Stabilisation};
use crate::linalg::{self, identity};
use crate::FaultKind;

/// The partials program's outputs at (t, x) with (a, λ) = `unknowns`, and the rows of them a
/// derivative reads: row i of r, and each multiplier's c, Φ and Φ̇ rows.
struct Partials {
    out: Vec<f64>,
    n: usize,
    m: usize,
}

impl Partials {
    fn at(&self, row: usize, k: usize) -> f64 {
        self.out[row * 2 * self.n + k]
    }

    fn residual(&self, i: usize, k: usize) -> f64 {
        self.at(i, k)
    }

    fn constraint(&self, c: usize, k: usize) -> f64 {
        self.at(self.n + c, k)
    }

    /// The partial of the rate multiplier `c`'s row holds at a jump: Φ̇ of a position row,
    /// A·q̇ + b (its Φ) of a velocity row.
    fn rate(&self, c: usize, kind: Stabilisation, k: usize) -> f64 {
        match kind {
            Stabilisation::Position => self.at(self.n + 2 * self.m + c, k),
            Stabilisation::Velocity => self.at(self.n + self.m + c, k),
        }
    }

    /// ∂Φ/∂x of a position row (0 for a velocity row, which no position projection holds).
    fn position(&self, c: usize, kind: Stabilisation, k: usize) -> f64 {
        match kind {
            Stabilisation::Position => self.at(self.n + self.m + c, k),
            Stabilisation::Velocity => 0.0,
        }
    }
}

impl Mechanical {
    fn partials_copy(
        &mut self,
        t: f64,
        x: &[f64],
        unknowns: &[f64],
    ) -> Result<Option<Partials>, FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        Ok(self.partials_at(t, x, unknowns)?.map(|p| Partials { out: p.to_vec(), n, m }))
    }

    /// The augmented matrix [M −Gᵀ; G 0] of the multipliers `rows` at the last evaluation,
    /// factored; `None` where it is singular (rows that depend on each other).
    fn factored(&self, rows: &[usize]) -> Option<(DMatrix<f64>, Vec<usize>)> {
        let n = self.layout.coordinates;
        let order = n + rows.len();
        let mut system = DMatrix::zeros(order, order);
        super::load_kept(&self.dyn_out, n, rows, &[], &mut system);
        let mut pivots = vec![0; order];
        linalg::lu_in_place(&mut system, &mut pivots).ok()?;
        Some((system, pivots))
    }

    /// ∂x⁺/∂x (row-major, 2n × 2n) of the last jump's impulse from the state `x` before it at
    /// `t`, its law and its rows held as the jump decided them; `None` where that law was
    /// Coulomb's, or its rows depend on each other.
    ///
    /// With G the two-sided rows and those that took the impulse, the impulse solves
    /// [M −Gᵀ; G 0]·(Δq̇, Λ) = (0, −k·γ⁻) (k = 1 + e of a normal row, 1 of a grip and 0 of a
    /// two-sided row); its derivative solves the same matrix for −∂(M·Δq̇ − Gᵀ·Λ) and
    /// −∂(G·Δq̇) − k·∂γ⁻.
    pub(crate) fn impact_derivative(
        &mut self,
        t: f64,
        x: &[f64],
    ) -> Result<Option<Vec<f64>>, FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let width = 2 * n;
        let (took, factors) = match &self.modes.struck {
            Struck::None => return Ok(Some(identity(width))),
            Struck::Coulomb => return Ok(None),
            Struck::Frictionless { rows, factors } => (rows.clone(), factors.clone()),
        };
        self.dynamics_at(t, x)?;
        let two_sided = self.two_sided();
        let mut rows: Vec<usize> = (0..m).filter(|&c| two_sided[c]).collect();
        let held = rows.len();
        rows.extend(&took);
        let Some((system, pivots)) = self.factored(&rows) else { return Ok(None) };
        let factor = |r: usize| if r < held { 0.0 } else { factors[r - held] };
        let mut impulse = vec![0.0; n + rows.len()];
        for (r, &c) in rows.iter().enumerate() {
            impulse[n + r] = -factor(r) * self.row_rate(c);
        }
        linalg::lu_solve(&system, &pivots, &mut impulse);
        let mut unknowns = vec![0.0; n + m];
        unknowns[..n].copy_from_slice(&impulse[..n]);
        for (r, &c) in rows.iter().enumerate() {
            unknowns[n + c] = impulse[n + r];
        }
        let Some(struck) = self.partials_copy(t, x, &unknowns)? else { return Ok(None) };
        let Some(free) = self.partials_copy(t, x, &vec![0.0; n + m])? else { return Ok(None) };
        let mut out = identity(width);
        // The columns side by side, eight a block, as in `projection_derivative`.
        let mut block = vec![[0.0; COLUMNS]; n + rows.len()];
        for first in (0..width).step_by(COLUMNS) {
            let columns = (width - first).min(COLUMNS);
            block.fill([0.0; COLUMNS]);
            for k in first..first + columns {
                for (i, row) in block[..n].iter_mut().enumerate() {
                    row[k - first] = free.residual(i, k) - struck.residual(i, k);
                }
                for (r, &c) in rows.iter().enumerate() {
                    let moved = struck.constraint(c, k) - free.constraint(c, k);
                    block[n + r][k - first] =
                        -moved - factor(r) * free.rate(c, self.stabilisation[c], k);
                }
            }
            linalg::lu_solve_columns(&system, &pivots, &mut block);
            for (i, row) in block[..n].iter().enumerate() {
                for (k, v) in row[..columns].iter().enumerate() {
                    out[(n + i) * width + first + k] += v;
                }
            }
        }
        Ok(Some(out))
    }

    /// ∂x'/∂x (row-major, 2n × 2n) of the projection a jump ends with at a state `x` on the
    /// current mode's manifold at `t`: the positions moved onto the kept position rows by the
    /// least change in M's metric, then the rates onto every kept row's rate
    /// ([`Mechanical::project_positions`], [`Mechanical::project_velocities`]). On the manifold
    /// the residuals are zero, so only their partials move the projection: each pass is
    /// [M −Jᵀ; J 0]·(Δ, μ) = (0, −∂ρ·δ). `None` where the kept rows depend on each other.
    pub(crate) fn projection_derivative(
        &mut self,
        t: f64,
        x: &[f64],
    ) -> Result<Option<Vec<f64>>, FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let width = 2 * n;
        let rows: Vec<usize> = (0..m).filter(|&c| self.kept[c]).collect();
        if rows.is_empty() {
            return Ok(Some(identity(width)));
        }
        self.dynamics_at(t, x)?;
        let Some((system, pivots)) = self.factored(&rows) else { return Ok(None) };
        let Some(partials) = self.partials_copy(t, x, &vec![0.0; n + m])? else {
            return Ok(None);
        };
        // The columns side by side, eight a block, each with the operations one column at a
        // time had (the same bits): solved one by one, they had been a third of a landing's
        // derivatives.
        let mut out = vec![0.0; width * width];
        let mut block = vec![[0.0; COLUMNS]; n + rows.len()];
        let mut d = vec![[0.0; COLUMNS]; width];
        for first in (0..width).step_by(COLUMNS) {
            let columns = (width - first).min(COLUMNS);
            for (j, d) in d.iter_mut().enumerate() {
                *d = std::array::from_fn(|c| if j == first + c { 1.0 } else { 0.0 });
            }
            block.fill([0.0; COLUMNS]);
            for (r, &c) in rows.iter().enumerate() {
                let kind = self.stabilisation[c];
                for (k, entry) in block[n + r][..columns].iter_mut().enumerate() {
                    *entry = -(0..n).map(|j| partials.position(c, kind, j) * d[j][k]).sum::<f64>();
                }
            }
            linalg::lu_solve_columns(&system, &pivots, &mut block);
            for i in 0..n {
                for k in 0..columns {
                    d[i][k] += block[i][k];
                }
            }
            block.fill([0.0; COLUMNS]);
            for (r, &c) in rows.iter().enumerate() {
                let kind = self.stabilisation[c];
                for (k, entry) in block[n + r][..columns].iter_mut().enumerate() {
                    *entry = -(0..width).map(|j| partials.rate(c, kind, j) * d[j][k]).sum::<f64>();
                }
            }
            linalg::lu_solve_columns(&system, &pivots, &mut block);
            for i in 0..n {
                for k in 0..columns {
                    d[n + i][k] += block[i][k];
                }
            }
            for (i, d) in d.iter().enumerate() {
                out[i * width + first..i * width + first + columns].copy_from_slice(&d[..columns]);
            }
        }
        Ok(Some(out))
    }
}
