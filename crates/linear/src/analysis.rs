//! A linearization ready for numbers: its case's expressions lowered once, with the blocks
//! they are read back by, and the analysis at one set of parameter values after another.

use cas::{ExprId, SymId};
use mechanics::Derivation;
use numeric::LowerError;

use crate::evaluation::Evaluation;
use crate::fault::Fault;
use crate::layout::Outputs;
use crate::{holonomic, in_rates, kept, Case, Linearization, Numbers};

/// The lowered matrices of a linearization, ready for any parameter values.
pub struct Analysis {
    lin: Linearization,
    evaluation: Evaluation,
    blocks: Blocks,
    /// The derivation's acceleration symbols, for what a fault reports.
    accels: Vec<SymId>,
}

/// Where each case's matrices sit among the program's outputs.
enum Blocks {
    Holonomic(holonomic::Blocks),
    InRates(in_rates::Blocks),
    Kept(kept::Blocks),
}

impl Analysis {
    /// Lowers what `lin`'s case needs, `parameters` the symbols of the program's first inputs.
    pub fn new(
        d: &Derivation,
        parameters: &[SymId],
        lin: Linearization,
    ) -> Result<Analysis, LowerError> {
        let mut outputs = Outputs::default();
        let mut inputs = parameters.to_vec();
        inputs.extend(lin.constraints().iter().map(|c| c.lambda));
        let blocks = match &lin.case {
            Case::Holonomic { .. } => {
                Blocks::Holonomic(holonomic::Blocks::place(&mut outputs, &lin))
            }
            Case::InRates(r) => {
                Blocks::InRates(in_rates::Blocks::place(&mut outputs, &lin, r, &d.rates))
            }
            Case::Kept(k) => {
                inputs.extend(k.dependent.iter().map(|&i| d.rates[i]));
                Blocks::Kept(kept::Blocks::place(&mut outputs, &lin, k))
            }
        };
        let phis: Vec<ExprId> = lin.constraints().iter().map(|c| c.phi).collect();
        let pool = &d.model.pool;
        let evaluation = Evaluation::new(pool, inputs, &outputs, &lin.residual, &phis)?;
        Ok(Analysis { lin, evaluation, blocks, accels: d.accels.clone() })
    }

    /// The linearization analysed.
    pub fn linearization(&self) -> &Linearization {
        &self.lin
    }

    /// The linearization back, for its report.
    pub fn into_linearization(self) -> Linearization {
        self.lin
    }

    /// The numbers at the parameters' values (in declaration order), or why there are none.
    pub fn at(&mut self, parameters: &[f64]) -> Result<Numbers, Fault> {
        let (e, lin) = (&mut self.evaluation, &self.lin);
        match (&self.blocks, &lin.case) {
            (Blocks::Holonomic(b), Case::Holonomic { .. }) => {
                holonomic::at(e, b, lin, &self.accels, parameters)
            }
            (Blocks::InRates(b), Case::InRates(r)) => in_rates::at(e, b, lin, r, parameters),
            (Blocks::Kept(b), Case::Kept(k)) => kept::at(e, b, lin, k, &self.accels, parameters),
            _ => unreachable!("the blocks are placed for the linearization's own case"),
        }
    }
}
