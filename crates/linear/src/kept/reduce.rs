//! The kept case in numbers. The dependent rates at the reference come first, from the
//! constraints at the velocity level; then q̈ and the multipliers there, as for position
//! constraints alone. Then the reduction: the position constraints give δq = N·δz (one
//! dependent coordinate per row, the rest of z the coordinates themselves), the velocity
//! constraints A·δq̇ + B·δq = 0 give δż = T·δu + S·δz (u the independent rates, again
//! coordinates' own), and the equations of motion along Q = N·T, where the multipliers cancel:
//!
//! M̃ = QᵀMQ, C̃ = Qᵀ(M·N·S·T + C·Q), K̃ = Qᵀ(M·N·S·S + C·N·S + K·N),
//!
//! M̃·δu̇ + C̃·δu + K̃·δz = 0. Positions that neither K̃ nor the rates of the positions kept
//! depend on leave the state (ignorable); first integrals leave the eigenvalues as zeros.

use nalgebra::{DMatrix, DVector};

use super::{Kept, Reduced};
use crate::dense::{
    accelerations_and_multipliers, least_squares, least_squares_matrix, pivots, regular, rows_of,
    solve,
};
use crate::evaluation::Evaluation;
use crate::fault::{Fault, EQUILIBRIUM_TOLERANCE};
use crate::layout::{self, Block, ConstraintRows, Outputs};
use crate::signals::{self, SignalBlocks};
use crate::{CaseNumbers, Component, FirstOrder as FirstOrderSpace, Linearization, Numbers};

/// Where the kept case's matrices sit among its program's outputs; the inputs after the
/// parameters are the multipliers, then the dependent rates.
pub(crate) struct Blocks {
    equations: layout::Equations,
    constraints: ConstraintRows,
    /// Each constraint's row at the velocity level.
    rates: Vec<Block>,
    /// Each velocity constraint's B row (by the constraint's index; `None` for a position
    /// constraint).
    positions: Vec<Option<Block>>,
    signals: SignalBlocks,
}

impl Blocks {
    pub fn place(outputs: &mut Outputs, lin: &Linearization, kept: &Kept) -> Blocks {
        let equations = layout::Equations::place(outputs, lin);
        let (mut jacobian, mut bias, mut rates, mut positions) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (c, row) in kept.constraints.iter().zip(&kept.rows) {
            jacobian.push(outputs.column(&c.jacobian));
            bias.push(outputs.value(c.bias));
            rates.push(outputs.value(row.rate));
            let b = outputs.column(&row.positions);
            positions.push((!c.positional).then_some(b));
        }
        let constraints = ConstraintRows { jacobian, bias };
        let signals = SignalBlocks::place(outputs, lin);
        Blocks { equations, constraints, rates, positions, signals }
    }

    /// B of the velocity constraints, one row each, n columns.
    fn velocity_positions(&self, out: &[f64], n: usize) -> DMatrix<f64> {
        let rows: Vec<DVector<f64>> =
            self.positions.iter().flatten().map(|b| b.vector(out)).collect();
        DMatrix::from_fn(rows.len(), n, |r, i| rows[r][i])
    }
}

/// M, C, K, J and B at the reference, with the multipliers and the accelerations there.
struct AtReference {
    mass: DMatrix<f64>,
    damping: DMatrix<f64>,
    stiffness: DMatrix<f64>,
    jacobian: DMatrix<f64>,
    velocity_positions: DMatrix<f64>,
    multipliers: Vec<f64>,
    accelerations: Vec<f64>,
}

/// The numbers at `parameters`: see the module's doc.
pub(crate) fn at(
    e: &mut Evaluation,
    blocks: &Blocks,
    lin: &Linearization,
    kept: &Kept,
    accels: &[cas::SymId],
    parameters: &[f64],
) -> Result<Numbers, Fault> {
    let n = lin.coords.len();
    let k = kept.constraints.len();
    let nd = kept.dependent.len();
    // On each kept position constraint.
    for (c, (phi, size)) in e.phi(parameters, &vec![0.0; k + nd]).into_iter().enumerate() {
        let constraint = &kept.constraints[c];
        if !constraint.positional {
            continue;
        }
        if phi.abs() > EQUILIBRIUM_TOLERANCE * size || !phi.is_finite() {
            return Err(Fault::OffConstraint { constraint: constraint.constraint, value: phi });
        }
    }
    let rates = dependent_rates(e, blocks, kept, parameters)?;
    let r = at_reference(e, blocks, lin, accels, parameters, &rates)?;

    // δq = N·δz along the position constraints, δż = T·δu + S·δz along the velocity ones.
    let preferred = |i: usize| kept.dependent.contains(&i);
    let rows = |positional: bool| -> Vec<usize> {
        (0..k).filter(|&c| kept.constraints[c].positional == positional).collect()
    };
    let position_rows = rows(true);
    let velocity_rows = rows(false);
    let p_rows =
        DMatrix::from_fn(position_rows.len(), n, |row, i| r.jacobian[(position_rows[row], i)]);
    let (basis, z) = along_positions(&p_rows, &preferred)?;
    let a_rows =
        DMatrix::from_fn(velocity_rows.len(), n, |row, i| r.jacobian[(velocity_rows[row], i)]);
    let an = &a_rows * &basis;
    let bn = &r.velocity_positions * &basis;
    let z_preferred = |c: usize| preferred(z[c]);
    let rates_along = along_rates(&an, &bn, &z_preferred)?;
    let out: Vec<f64> = r.multipliers.iter().chain(&rates).copied().collect();
    let out = e.outputs(parameters, &out);
    let forces = blocks.signals.forces(&out);
    let first = first_order(&r, &basis, &rates_along, &forces)?;
    let positions: Vec<usize> = first.kept_z.iter().map(|&c| z[c]).collect();
    let independent: Vec<usize> = rates_along.independent.iter().map(|&c| z[c]).collect();
    let state = positions.iter().map(|&i| Component::Position(i));
    let state = state.chain(independent.iter().map(|&i| Component::Rate(i))).collect();
    // δq = N·δz of the positions kept; δq̇ = N·(S·δz + T·δu).
    let (np, nu) = (first.kept_z.len(), independent.len());
    let mut at_positions = DMatrix::zeros(n, np + nu);
    let mut at_rates = DMatrix::zeros(n, np + nu);
    for (col, &c) in first.kept_z.iter().enumerate() {
        at_positions.column_mut(col).copy_from(&basis.column(c));
        at_rates.column_mut(col).copy_from(&(&basis * rates_along.s.column(c)));
    }
    for col in 0..nu {
        at_rates.column_mut(np + col).copy_from(&(&basis * rates_along.t.column(col)));
    }
    let reduced = FirstOrderSpace {
        state,
        a: first.a,
        b: first.b,
        positions: at_positions,
        rates: at_rates,
        cyclic: Vec::new(),
    };
    let (space, spectrum) = signals::complete(reduced, &blocks.signals, &out, true)?;
    let case = CaseNumbers::Kept(Reduced {
        dependent_rates: rates,
        kinematics: rows_of(&first.kinematics),
        positions,
        rates: independent,
    });
    let matrices = [&first.mass, &first.damping, &first.stiffness];
    let solved = (r.multipliers, r.accelerations);
    Ok(Numbers::new(parameters, matrices, solved, space, spectrum, case))
}

/// The dependent rates: J[:, dependent]·r = −(the rows with them at 0).
fn dependent_rates(
    e: &mut Evaluation,
    blocks: &Blocks,
    kept: &Kept,
    parameters: &[f64],
) -> Result<Vec<f64>, Fault> {
    let (k, nd) = (kept.constraints.len(), kept.dependent.len());
    let out = e.outputs(parameters, &vec![0.0; k + nd]);
    if out.iter().any(|v| !v.is_finite()) {
        return Err(Fault::NotFinite("M, C, K, f or a constraint's rows"));
    }
    let n = kept.constraints.first().map_or(0, |c| c.jacobian.len());
    let (jacobian, _) = blocks.constraints.read(&out, n);
    let rate_rows = DVector::from_fn(k, |c, _| blocks.rates[c].value(&out));
    let restrained = DMatrix::from_fn(k, nd, |c, d| jacobian[(c, kept.dependent[d])]);
    let rhs = -&rate_rows;
    let solved = least_squares(restrained.clone(), &rhs)
        .ok_or(Fault::DependentRates { residual: f64::NAN })?;
    let miss = (&restrained * &solved - &rhs).amax();
    let scale = restrained.amax() * solved.amax() + rhs.amax();
    if miss > EQUILIBRIUM_TOLERANCE * scale.max(f64::MIN_POSITIVE) {
        return Err(Fault::DependentRates { residual: miss });
    }
    Ok(solved.iter().copied().collect())
}

/// q̈ and the multipliers at the reference (M·q̈ − Jᵀ·λ = f, J·q̈ = γ), checked to be an
/// equilibrium, and the matrices there.
fn at_reference(
    e: &mut Evaluation,
    blocks: &Blocks,
    lin: &Linearization,
    accels: &[cas::SymId],
    parameters: &[f64],
    rates: &[f64],
) -> Result<AtReference, Fault> {
    let n = lin.coords.len();
    let k = blocks.rates.len();
    let inputs =
        |multipliers: &[f64]| -> Vec<f64> { multipliers.iter().chain(rates).copied().collect() };
    let out = e.outputs(parameters, &inputs(&vec![0.0; k]));
    if out.iter().any(|v| !v.is_finite()) {
        return Err(Fault::NotFinite("M, C, K, f or a constraint's rows"));
    }
    let mass = blocks.equations.mass.matrix(&out);
    let forcing = blocks.equations.residual.vector(&out);
    let (jacobian, bias) = blocks.constraints.read(&out, n);
    let (accelerations, multipliers) =
        accelerations_and_multipliers(&mass, &jacobian, &forcing, &bias);
    let accelerations: Vec<f64> = accelerations.iter().copied().collect();
    let multipliers: Vec<f64> = multipliers.iter().copied().collect();
    let out = e.outputs(parameters, &inputs(&multipliers));
    let stiffness = blocks.equations.stiffness.matrix(&out);
    let damping = blocks.equations.damping.matrix(&out);
    let residual = e.residual(parameters, &inputs(&multipliers));
    // Relative to the largest force in any row, f's or a reaction's: rows that vanish by
    // symmetry have no size of their own, and an expression too large to simplify hides
    // its terms inside products.
    let reactions =
        |j: usize| -> f64 { (0..k).map(|c| (jacobian[(c, j)] * multipliers[c]).abs()).sum() };
    let scale =
        (0..n).map(|j| residual[j].1.max(forcing[j].abs() + reactions(j))).fold(0.0, f64::max);
    let held = residual.iter().all(|(r, _)| r.abs() <= EQUILIBRIUM_TOLERANCE * scale);
    if !held || accelerations.iter().any(|a| !a.is_finite()) {
        return Err(Fault::NotEquilibrium { accelerations, symbols: accels.to_vec() });
    }
    let velocity_positions = blocks.velocity_positions(&out, n);
    Ok(AtReference {
        mass,
        damping,
        stiffness,
        jacobian,
        velocity_positions,
        multipliers,
        accelerations,
    })
}

/// δq = N·δz along the position constraints' rows: N, and the coordinates that are z (the
/// others, one pivot per row, preferably a dependent rate's coordinate, follow from them).
fn along_positions(
    p_rows: &DMatrix<f64>,
    preferred: &dyn Fn(usize) -> bool,
) -> Result<(DMatrix<f64>, Vec<usize>), Fault> {
    let n = p_rows.ncols();
    let eliminated = pivots(p_rows, preferred);
    let z: Vec<usize> = (0..n).filter(|i| !eliminated.contains(i)).collect();
    let nz = z.len();
    let mut basis = DMatrix::zeros(n, nz);
    for (col, &i) in z.iter().enumerate() {
        basis[(i, col)] = 1.0;
    }
    if !eliminated.is_empty() {
        let dep =
            DMatrix::from_fn(p_rows.nrows(), eliminated.len(), |r, d| p_rows[(r, eliminated[d])]);
        let ind = DMatrix::from_fn(p_rows.nrows(), nz, |r, c| p_rows[(r, z[c])]);
        let x = least_squares_matrix(dep, &(-ind)).ok_or(Fault::NoMotion)?;
        for (d, &i) in eliminated.iter().enumerate() {
            for c in 0..nz {
                basis[(i, c)] = x[(d, c)];
            }
        }
    }
    Ok((basis, z))
}

/// δż = T·δu + S·δz along the velocity constraints (A·N·δż + B·N·δz = 0).
struct AlongRates {
    t: DMatrix<f64>,
    s: DMatrix<f64>,
    /// The z whose rates are the independent rates u.
    independent: Vec<usize>,
}

fn along_rates(
    an: &DMatrix<f64>,
    bn: &DMatrix<f64>,
    preferred: &dyn Fn(usize) -> bool,
) -> Result<AlongRates, Fault> {
    let nz = an.ncols();
    let dependent_z = pivots(an, preferred);
    let independent: Vec<usize> = (0..nz).filter(|c| !dependent_z.contains(c)).collect();
    let nu = independent.len();
    let mut t = DMatrix::zeros(nz, nu);
    let mut s = DMatrix::zeros(nz, nz);
    for (col, &c) in independent.iter().enumerate() {
        t[(c, col)] = 1.0;
    }
    if !dependent_z.is_empty() {
        let dep = DMatrix::from_fn(an.nrows(), dependent_z.len(), |r, d| an[(r, dependent_z[d])]);
        let ind = DMatrix::from_fn(an.nrows(), nu, |r, c| an[(r, independent[c])]);
        let x_t = least_squares_matrix(dep.clone(), &(-ind))
            .ok_or(Fault::DependentRates { residual: f64::NAN })?;
        let x_s = least_squares_matrix(dep, &(-bn))
            .ok_or(Fault::DependentRates { residual: f64::NAN })?;
        for (d, &c) in dependent_z.iter().enumerate() {
            for col in 0..nu {
                t[(c, col)] = x_t[(d, col)];
            }
            for col in 0..nz {
                s[(c, col)] = x_s[(d, col)];
            }
        }
    }
    Ok(AlongRates { t, s, independent })
}

/// The reduced second-order form and A.
struct FirstOrder {
    mass: DMatrix<f64>,
    damping: DMatrix<f64>,
    /// K̃ of the positions kept.
    stiffness: DMatrix<f64>,
    kinematics: DMatrix<f64>,
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    /// The z whose positions stay in the state.
    kept_z: Vec<usize>,
}

fn first_order(
    r: &AtReference,
    basis: &DMatrix<f64>,
    along: &AlongRates,
    input_forces: &DMatrix<f64>,
) -> Result<FirstOrder, Fault> {
    let (t, s) = (&along.t, &along.s);
    let (nz, nu) = (t.nrows(), t.ncols());
    let q = basis * t;
    let ns = basis * s;
    let m_reduced = q.transpose() * &r.mass * &q;
    let c_reduced = q.transpose() * (&r.mass * &ns * t + &r.damping * &q);
    let k_reduced = q.transpose() * (&r.mass * &ns * s + &r.damping * &ns + &r.stiffness * basis);

    // The positions kept: those K̃ depends on, and those the rates of kept ones depend on.
    let k_tol = 1e-9 * k_reduced.amax();
    let s_tol = 1e-9 * s.amax().max(t.amax());
    let mut keep: Vec<bool> = (0..nz).map(|c| k_reduced.column(c).amax() > k_tol).collect();
    loop {
        let mut grew = false;
        for i in 0..nz {
            if !keep[i] {
                continue;
            }
            for j in 0..nz {
                if !keep[j] && s[(i, j)].abs() > s_tol {
                    keep[j] = true;
                    grew = true;
                }
            }
        }
        if !grew {
            break;
        }
    }
    let kept_z: Vec<usize> = (0..nz).filter(|&c| keep[c]).collect();
    let np = kept_z.len();
    let size = np + nu;
    if size == 0 || nu == 0 {
        return Err(Fault::NoMotion);
    }
    let lu = regular(&m_reduced)?;
    let k_kept = DMatrix::from_fn(nu, np, |row, c| k_reduced[(row, kept_z[c])]);
    let mut kinematics = DMatrix::zeros(np, size);
    for (row, &i) in kept_z.iter().enumerate() {
        for (col, &j) in kept_z.iter().enumerate() {
            kinematics[(row, col)] = s[(i, j)];
        }
        for col in 0..nu {
            kinematics[(row, np + col)] = t[(i, col)];
        }
    }
    let mut forces = DMatrix::zeros(nu, size);
    forces.view_mut((0, 0), (nu, np)).copy_from(&k_kept);
    forces.view_mut((0, np), (nu, nu)).copy_from(&c_reduced);
    let mut a = DMatrix::zeros(size, size);
    a.view_mut((0, 0), (np, size)).copy_from(&kinematics);
    a.view_mut((np, 0), (nu, size)).copy_from(&(-solve(&lu, &forces)?));
    // The inputs' forces along Q, where the multipliers cancel: M̃·δu̇ + … = Qᵀ·Q_u·δu.
    let mut b = DMatrix::zeros(size, input_forces.ncols());
    let along_q = q.transpose() * input_forces;
    b.view_mut((np, 0), (nu, input_forces.ncols())).copy_from(&solve(&lu, &along_q)?);
    Ok(FirstOrder {
        mass: m_reduced,
        damping: c_reduced,
        stiffness: k_kept,
        kinematics,
        a,
        b,
        kept_z,
    })
}
