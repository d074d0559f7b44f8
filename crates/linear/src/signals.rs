//! Inputs and outputs about the reference: exactly, each input's generalized force (a column
//! of ∂f/∂u, in the rows of the case's equations) and each output's gradient in the
//! coordinates, the rates and the inputs; in numbers, B from the case's reduction and C and D
//! from where the state puts δq and δq̇ (δq = P·x, δq̇ = V·x), so that every case forms them
//! alike.

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;
use nalgebra::DMatrix;

use crate::layout::{Block, Outputs};

/// An output's gradient at the reference: the row of C before the state is chosen, and the
/// row of D.
#[derive(Clone, Debug)]
pub struct OutputRow {
    pub name: String,
    /// ∂y/∂q, per coordinate.
    pub positions: Vec<ExprId>,
    /// ∂y/∂q̇, per coordinate.
    pub rates: Vec<ExprId>,
    /// ∂y/∂u, per input: the row of D.
    pub inputs: Vec<ExprId>,
    /// Where the output is written.
    pub span: Span,
}

/// Each input at the value it takes when nothing drives it: the reference's inputs.
pub(crate) fn reference_inputs(inputs: &[model::Input]) -> Vec<(SymId, ExprId)> {
    inputs.iter().map(|u| (u.sym, u.value)).collect()
}

/// ∂g/∂u of each of `rows` (one expression an equation), put through `at`: one row per
/// equation, one column per input.
pub(crate) fn input_columns(
    pool: &mut Pool,
    rows: &[ExprId],
    inputs: &[SymId],
    at: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId,
) -> Vec<Vec<ExprId>> {
    let mut out = Vec::new();
    for g in rows {
        let mut row = Vec::new();
        for u in inputs {
            let d = pool.diff(*g, *u);
            row.push(at(pool, d));
        }
        out.push(row);
    }
    out
}

/// Each output's gradient at the reference (the outputs expanded into the remaining
/// coordinates first); refused where an output names a rate the case's state does not give
/// (`unavailable`, with why).
pub(crate) fn output_rows(
    d: &mut Derivation,
    at: &mut dyn FnMut(&mut Pool, ExprId) -> ExprId,
    unavailable: Option<(&[SymId], &str)>,
) -> Result<Vec<OutputRow>, Vec<Diagnostic>> {
    let mut rows = Vec::new();
    let mut errors = Vec::new();
    let inputs: Vec<SymId> = d.model.inputs.iter().map(|u| u.sym).collect();
    for output in d.model.outputs.clone() {
        let y = d.expand_quantities(output.value, false);
        let pool = &mut d.model.pool;
        if let Some((rates, why)) = unavailable {
            if let Some(r) = rates.iter().find(|r| pool.depends_on(y, **r)) {
                let name = pool.symbol_text(*r, cas::Style::Unicode);
                errors.push(
                    Diagnostic::error(output.span, format!("this output depends on `{name}`"))
                        .with_label(why.to_string())
                        .with_hint("measure the coordinates and the independent rates"),
                );
                continue;
            }
        }
        let mut gradient = |of: &[SymId]| -> Vec<ExprId> {
            of.iter()
                .map(|s| {
                    let g = pool.diff(y, *s);
                    at(pool, g)
                })
                .collect()
        };
        let positions = gradient(&d.coords);
        let rates_of = gradient(&d.rates);
        let inputs_of = gradient(&inputs);
        rows.push(OutputRow {
            name: output.name.clone(),
            positions,
            rates: rates_of,
            inputs: inputs_of,
            span: output.span,
        });
    }
    if errors.is_empty() {
        Ok(rows)
    } else {
        Err(errors)
    }
}

/// Where the input columns and the outputs' gradients sit among a case's program's outputs.
pub(crate) struct SignalBlocks {
    /// One row per equation of the case, one column per input.
    forces: Block,
    positions: Block,
    rates: Block,
    inputs: Block,
}

impl SignalBlocks {
    pub fn place(outputs: &mut Outputs, lin: &crate::Linearization) -> SignalBlocks {
        let (n, ni) = (lin.coords.len(), lin.inputs.len());
        let rows = &lin.outputs;
        let take = |f: fn(&OutputRow) -> &Vec<ExprId>| -> Vec<Vec<ExprId>> {
            rows.iter().map(|r| f(r).clone()).collect()
        };
        SignalBlocks {
            forces: outputs.matrix(&lin.input_forces, ni),
            positions: outputs.matrix(&take(|r| &r.positions), n),
            rates: outputs.matrix(&take(|r| &r.rates), n),
            inputs: outputs.matrix(&take(|r| &r.inputs), ni),
        }
    }

    /// The input columns, one row per equation of the case.
    pub fn forces(&self, out: &[f64]) -> DMatrix<f64> {
        self.forces.matrix(out)
    }

    /// C and D, with δq = `positions`·x and δq̇ = `rates`·x (n × the state's size each).
    pub fn outputs(
        &self,
        out: &[f64],
        positions: &DMatrix<f64>,
        rates: &DMatrix<f64>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let c = self.positions.matrix(out) * positions + self.rates.matrix(out) * rates;
        (c, self.inputs.matrix(out))
    }
}

/// The rank of a matrix by its singular values, with what makes the count doubtful.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rank {
    /// How many singular values are above the tolerance.
    pub rank: usize,
    /// Of how many the full rank would be.
    pub full: usize,
    /// The tolerance on singular values relative to the largest: [`RANK_TOLERANCE`].
    pub tolerance: f64,
    /// The smallest singular value counted, relative to the largest (1 when none or one).
    pub smallest_counted: f64,
    /// The largest singular value left out, relative to the largest (0 when none).
    pub largest_left_out: f64,
}

/// A singular value below this fraction of the largest counts as zero.
pub const RANK_TOLERANCE: f64 = 1e-9;

/// Within this factor of the tolerance, either way, a singular value could fall on the other
/// side with a small change of the parameters: the rank is doubtful.
const DOUBT_FACTOR: f64 = 1e3;

impl Rank {
    /// Whether a singular value lies within [`DOUBT_FACTOR`] of the tolerance.
    pub fn doubtful(&self) -> bool {
        let near = |s: f64| s < self.tolerance * DOUBT_FACTOR && s > self.tolerance / DOUBT_FACTOR;
        near(self.smallest_counted) || near(self.largest_left_out)
    }
}

/// The rank of `m` (of full rank `full`) by its singular values.
fn rank_of(m: &DMatrix<f64>, full: usize) -> Rank {
    let tolerance = RANK_TOLERANCE;
    if m.is_empty() || m.iter().any(|x| !x.is_finite()) {
        return Rank { rank: 0, full, tolerance, smallest_counted: 1.0, largest_left_out: 0.0 };
    }
    let mut values: Vec<f64> =
        m.clone().svd(false, false).singular_values.iter().copied().collect();
    values.sort_by(|a, b| b.total_cmp(a));
    let largest = values.first().copied().unwrap_or(0.0);
    if largest == 0.0 {
        return Rank { rank: 0, full, tolerance, smallest_counted: 1.0, largest_left_out: 0.0 };
    }
    let relative: Vec<f64> = values.iter().map(|s| s / largest).collect();
    let rank = relative.iter().filter(|s| **s > tolerance).count();
    let smallest_counted = relative[..rank].last().copied().unwrap_or(1.0);
    let largest_left_out = relative.get(rank).copied().unwrap_or(0.0);
    Rank { rank, full, tolerance, smallest_counted, largest_left_out }
}

/// Each column of a matrix scaled to unit length (zero columns left alone), so that the
/// singular values compare directions rather than units.
fn balanced(m: DMatrix<f64>) -> DMatrix<f64> {
    let mut m = m;
    for mut col in m.column_iter_mut() {
        let norm = col.norm();
        if norm > 0.0 {
            col /= norm;
        }
    }
    m
}

/// The rank of the controllability matrix [B, AB, …, Aⁿ⁻¹B] (its columns scaled to unit
/// length), `None` without inputs.
pub(crate) fn controllability(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Option<Rank> {
    let n = a.nrows();
    if b.ncols() == 0 || n == 0 {
        return None;
    }
    let mut blocks = Vec::with_capacity(n);
    let mut power = b.clone();
    for _ in 0..n {
        blocks.push(power.clone());
        power = a * power;
    }
    let m = DMatrix::from_fn(n, n * b.ncols(), |r, c| blocks[c / b.ncols()][(r, c % b.ncols())]);
    Some(rank_of(&balanced(m), n))
}

/// The rank of the observability matrix [C; CA; …; CAⁿ⁻¹] (by its transpose's controllability),
/// `None` without outputs.
pub(crate) fn observability(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Option<Rank> {
    controllability(&a.transpose(), &c.transpose())
}

/// The state space of a case's first-order form: C and D from the outputs' gradients, the
/// ranks, and the spectrum (deflated of first integrals where `deflate`), with the zeros of
/// the cyclic positions kept set aside from the verdict: their columns of A are zero, so the
/// eigenvalues are those of A without them, and one 0 each.
pub(crate) fn complete(
    first: crate::FirstOrder,
    blocks: &SignalBlocks,
    out: &[f64],
    deflate: bool,
) -> Result<(crate::StateSpace, crate::spectrum::Spectrum), crate::Fault> {
    use crate::dense::rows_of;
    let crate::FirstOrder { state, a, b, positions, rates, cyclic } = first;
    let (c, d) = blocks.outputs(out, &positions, &rates);
    let rest: Vec<usize> = (0..a.nrows()).filter(|i| !cyclic.contains(i)).collect();
    let reduced = a.select_rows(&rest).select_columns(&rest);
    let spectrum = match deflate {
        true => crate::spectrum::Spectrum::deflated(&reduced),
        false => crate::spectrum::Spectrum::of(&reduced),
    };
    let spectrum = spectrum
        .ok_or(crate::Fault::NotFinite("the first-order matrix A"))?
        .with_cyclic_zeros(cyclic.len());
    let space = crate::StateSpace {
        state,
        controllability: controllability(&a, &b),
        observability: observability(&a, &c),
        a: rows_of(&a),
        b: rows_of(&b),
        c: rows_of(&c),
        d: rows_of(&d),
    };
    Ok((space, spectrum))
}
