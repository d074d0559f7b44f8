//! A case's expressions lowered once and evaluated at one set of values after another: the
//! program of its matrices (read back through its [`crate::layout`] blocks), and the residual
//! and the constraints' Φ evaluated with the size of their terms, which says how near zero
//! counts as zero.

use cas::{ExprId, Pool, SymId};
use numeric::{LowerError, ScaledEvaluator, Tape};

use crate::layout::Outputs;

pub(crate) struct Evaluation {
    tape: Tape,
    /// The program's inputs: the parameters, then what the case adds (the multipliers, the
    /// dependent rates).
    inputs: Vec<SymId>,
    residual: ScaledEvaluator,
    phi: ScaledEvaluator,
    symbol_count: usize,
}

impl Evaluation {
    pub fn new(
        pool: &Pool,
        inputs: Vec<SymId>,
        outputs: &Outputs,
        residual: &[ExprId],
        phis: &[ExprId],
    ) -> Result<Evaluation, LowerError> {
        let tape = Tape::new(numeric::lower(pool, &inputs, outputs.exprs())?);
        Ok(Evaluation {
            tape,
            inputs,
            residual: ScaledEvaluator::new(pool, residual),
            phi: ScaledEvaluator::new(pool, phis),
            symbol_count: pool.symbol_count(),
        })
    }

    /// The program's outputs at the parameters' values and `rest` of the inputs (0 past it).
    pub fn outputs(&mut self, parameters: &[f64], rest: &[f64]) -> Vec<f64> {
        let mut input = parameters.to_vec();
        input.extend(rest);
        input.resize(self.inputs.len(), 0.0);
        let mut out = vec![0.0; self.tape.outputs()];
        self.tape.eval(&input, &mut out);
        out
    }

    /// Values by symbol, for the scaled evaluators.
    fn by_symbol(&self, parameters: &[f64], rest: &[f64]) -> Vec<f64> {
        let mut values = vec![f64::NAN; self.symbol_count];
        for (s, v) in self.inputs.iter().zip(parameters.iter().chain(rest)) {
            values[s.index()] = *v;
        }
        values
    }

    /// The residual's entries, each with the size of its terms.
    pub fn residual(&mut self, parameters: &[f64], rest: &[f64]) -> Vec<(f64, f64)> {
        let values = self.by_symbol(parameters, rest);
        self.residual.eval(&values)
    }

    /// Each kept constraint's Φ, with the size of its terms.
    pub fn phi(&mut self, parameters: &[f64], rest: &[f64]) -> Vec<(f64, f64)> {
        let values = self.by_symbol(parameters, rest);
        self.phi.eval(&values)
    }
}
