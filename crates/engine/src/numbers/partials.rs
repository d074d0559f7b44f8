//! The expressions of the partials programs, which give the exact Jacobians of
//! [`sim::Mechanical`] and [`sim::Canonical`]: only implicit methods need them, so they are
//! gathered and lowered only for those.

use cas::ExprId;
use numeric::Program;

use super::Prepared;
use crate::Error;

impl Prepared {
    /// The partials program of [`sim::Mechanical`]'s exact Jacobian ([`Prepared::partials_exprs`]
    /// lowered for the observation inputs), lowered once and kept: the runs of a compiled scene,
    /// `orbit`'s variational runs and a linearization along a motion share it.
    pub fn partials_program(&mut self) -> Result<Program, Error> {
        if let Some(program) = &self.partials_program {
            return Ok(program.clone());
        }
        let exprs = self.partials_exprs();
        let program = self.lower(&self.observation_inputs(), &exprs)?;
        self.partials_program = Some(program.clone());
        Ok(program)
    }

    /// ∂(r, c, Φ, Φ̇)/∂(q, q̇) with q̈ and λ held fixed, row-major, for the observation inputs
    /// `[t, q, q̇, q̈, λ, parameters]`: the partials program of [`sim::Layout`], from
    /// [`mechanics::Derivation::partials`].
    pub fn partials_exprs(&mut self) -> Vec<ExprId> {
        let p = self.derivation.partials();
        let mut v = Vec::with_capacity(self.layout.partials_outputs());
        for rows in [&p.residual, &p.constraint, &p.phi, &p.drift_rate] {
            for (positions, rates) in rows.positions.iter().zip(&rows.rates) {
                v.extend(positions);
                v.extend(rates);
            }
        }
        v
    }

    /// ∂p/∂q, ∂g/∂q and ∂g/∂q̇ (each n×n, row-major) of the momenta p = ∂L/∂q̇ and the forces
    /// g = ∂L/∂q + Q of [`Prepared::momentum_exprs`], for the dynamics inputs: the partials
    /// program of [`sim::Canonical`].
    pub fn canonical_partials_exprs(&mut self) -> Vec<ExprId> {
        let momentum = self.momentum_exprs();
        let n = self.layout.coordinates;
        let (momenta, forces) = (&momentum[n * n..n * n + n], &momentum[n * n + n..]);
        let d = &mut self.derivation;
        let mut v = Vec::with_capacity(3 * n * n);
        for (rows, by) in [(momenta, &d.coords), (forces, &d.coords), (forces, &d.rates)] {
            for row in rows {
                for s in by.iter() {
                    v.push(d.model.pool.diff(*row, *s));
                }
            }
        }
        v
    }
}
