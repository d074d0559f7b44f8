//! The holonomic case: no velocity constraint kept. Exactly, M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ in
//! all the coordinates, K = −∂(f + Jᵀλ)/∂q with the multipliers' symbols, and each position
//! constraint kept with its row J·δq = 0. In numbers: the reference checked on every
//! constraint, the multipliers and the accelerations there, the state moved into the null
//! space of J over the non-cyclic coordinates (δq = N·z, so that Jᵀ·δλ drops out of
//! Nᵀ·(…)), each cyclic coordinate's δq left out, and A = [0, I; −M⁻¹K, −M⁻¹C] in the rest.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;
use nalgebra::{DMatrix, DVector};

use crate::dense::{accelerations_and_multipliers, null_space, regular, rows_of, solve};
use crate::evaluation::Evaluation;
use crate::fault::{Fault, EQUILIBRIUM_TOLERANCE};
use crate::layout::{self, ConstraintRows, Outputs};
use crate::reference::{self, Items, Placed};
use crate::signals::{self, SignalBlocks};
use crate::{
    Case, CaseNumbers, Component, FirstOrder, LinearConstraint, Linearization, Numbers, Signals,
};

/// Linearizes with no velocity constraint kept, `errors` those found in the items already.
pub(crate) fn linearize(
    d: &mut Derivation,
    span: Span,
    items: &Items,
    mut errors: Vec<Diagnostic>,
) -> Result<Linearization, Vec<Diagnostic>> {
    let n = d.coords.len();
    let cyclic = reference::cyclic_flags(d);
    let pool = &mut d.model.pool;
    let mut positions = vec![None; n];
    let mut rates = vec![pool.zero(); n];
    let mut map: HashMap<SymId, ExprId> = HashMap::new();
    for ((coord, rate), (value, item_span)) in items {
        let Some(i) = d.coords.iter().position(|q| q == coord) else { continue };
        if *rate {
            rates[i] = *value;
            map.insert(d.rates[i], *value);
            if !cyclic[i] && !pool.is_zero(*value) {
                let name = pool.symbol_text(*coord, cas::Style::Unicode);
                let why = "cyclic: M or f depends on it";
                let may = "cyclic coordinates (those in neither M nor f)";
                errors.push(reference::moves(*item_span, &name, why, may));
            }
        } else {
            positions[i] = Some(*value);
            map.insert(*coord, *value);
        }
    }
    for i in 0..n {
        map.entry(d.rates[i]).or_insert(pool.zero());
    }
    map.extend(signals::reference_inputs(&d.model.inputs));
    let missing: Vec<SymId> =
        (0..n).filter(|&i| !cyclic[i] && positions[i].is_none()).map(|i| d.coords[i]).collect();
    errors.extend(reference::missing_positions(pool, &missing, span, "a cyclic"));
    if !errors.is_empty() {
        return Err(errors);
    }

    let mut at = |pool: &mut Pool, e: ExprId| {
        let e = pool.subst(e, &map);
        pool.simplify(e)
    };
    let exact = reference::at_reference(d, &cyclic, &mut at);
    let pool = &mut d.model.pool;
    let residual_is_zero =
        d.multipliers.is_empty() && exact.residual.iter().all(|r| pool.is_identically_zero(*r));
    let constraints: Vec<LinearConstraint> = d
        .multipliers
        .iter()
        .map(|m| LinearConstraint {
            constraint: m.constraint,
            positional: m.rows.position.is_some(),
            lambda: m.lambda,
            jacobian: m.rows.jacobian.iter().map(|e| at(pool, *e)).collect(),
            phi: at(pool, m.rows.phi()),
            bias: at(pool, m.rows.bias),
        })
        .collect();

    let matrices = [&exact.mass[..], &exact.damping, &exact.stiffness];
    let all = reference::all_of(matrices, &exact.residual, &constraints, &[]);
    reference::refuse_time_dependence(pool, &all, d.model.time, span)?;

    let inputs: Vec<SymId> = d.model.inputs.iter().map(|u| u.sym).collect();
    let input_forces = signals::input_columns(pool, &d.forcing, &inputs, &mut at);
    let outputs = signals::output_rows(d, &mut at, None)?;
    let signals = Signals { inputs, input_forces, outputs };

    let placed = Placed { cyclic, positions, rates };
    let case = Case::Holonomic { constraints };
    Ok(Linearization::new(d.coords.clone(), placed, exact, residual_is_zero, (case, signals), span))
}

/// Where the holonomic case's matrices sit among its program's outputs.
pub(crate) struct Blocks {
    equations: layout::Equations,
    constraints: ConstraintRows,
    signals: SignalBlocks,
}

impl Blocks {
    /// Places M, C, K, the residual and each constraint's J and γ; the inputs after the
    /// parameters are the multipliers.
    pub fn place(outputs: &mut Outputs, lin: &Linearization) -> Blocks {
        let equations = layout::Equations::place(outputs, lin);
        let (mut jacobian, mut bias) = (Vec::new(), Vec::new());
        for c in lin.constraints() {
            jacobian.push(outputs.column(&c.jacobian));
            bias.push(outputs.value(c.bias));
        }
        let signals = SignalBlocks::place(outputs, lin);
        Blocks { equations, constraints: ConstraintRows { jacobian, bias }, signals }
    }
}

/// The numbers at `parameters`: see the module's doc.
pub(crate) fn at(
    e: &mut Evaluation,
    blocks: &Blocks,
    lin: &Linearization,
    accels: &[SymId],
    parameters: &[f64],
) -> Result<Numbers, Fault> {
    let n = lin.coords.len();
    let constraints = lin.constraints();
    let k = constraints.len();
    let out = e.outputs(parameters, &vec![0.0; k]);
    if out.iter().any(|v| !v.is_finite()) {
        return Err(Fault::NotFinite("M, C, K or f"));
    }
    let mass = blocks.equations.mass.matrix(&out);
    let forcing = blocks.equations.residual.vector(&out);
    let (jacobian, bias) = blocks.constraints.read(&out, n);

    // On each kept constraint, then the accelerations (and the multipliers) there.
    for (c, (phi, size)) in e.phi(parameters, &vec![0.0; k]).into_iter().enumerate() {
        // NaN is off the constraint too.
        let on = phi.abs() <= EQUILIBRIUM_TOLERANCE * size;
        if !on {
            return Err(Fault::OffConstraint { constraint: constraints[c].constraint, value: phi });
        }
    }
    let (accelerations, multipliers) = if k == 0 {
        let lu = mass.clone().lu();
        let a = lu.solve(&forcing).unwrap_or_else(|| DVector::from_element(n, f64::NAN));
        (a, DVector::zeros(0))
    } else {
        accelerations_and_multipliers(&mass, &jacobian, &forcing, &bias)
    };
    let multipliers: Vec<f64> = multipliers.iter().copied().collect();
    let accelerations: Vec<f64> = accelerations.iter().copied().collect();
    let out = e.outputs(parameters, &multipliers);
    let stiffness = blocks.equations.stiffness.matrix(&out);
    if !lin.residual_is_zero {
        let residual = e.residual(parameters, &multipliers);
        let held = residual.iter().enumerate().all(|(j, (r, size))| {
            // A shift of the reference by a 1e-3 of what the coordinates are measured in
            // would leave this much: below it, rounding of the reference is all there is.
            let floor = 1e-3 * stiffness.row(j).iter().map(|x| x.abs()).sum::<f64>();
            r.abs() <= EQUILIBRIUM_TOLERANCE * size.max(floor)
        });
        if !held || accelerations.iter().any(|a| !a.is_finite()) {
            return Err(Fault::NotEquilibrium { accelerations, symbols: accels.to_vec() });
        }
    }
    let damping = blocks.equations.damping.matrix(&out);
    let forces = blocks.signals.forces(&out);
    let basis = if k == 0 { DMatrix::identity(n, n) } else { basis(&jacobian, &lin.cyclic)? };
    let along = Along { basis: &basis, cyclic: &lin.cyclic, k, keep_cyclic: lin.keep_cyclic };
    let first = first_order(&along, [&mass, &damping, &stiffness], &forces)?;
    let (space, spectrum) = signals::complete(first, &blocks.signals, &out, false)?;
    let case = CaseNumbers::Holonomic { basis: (k > 0).then(|| rows_of(&basis)) };
    let matrices = [&mass, &damping, &stiffness];
    let solved = (multipliers, accelerations);
    Ok(Numbers::new(parameters, matrices, solved, space, spectrum, case))
}

/// The reduced coordinates: δq = N·z, N's columns those of the null space of the kept
/// constraints (or the coordinates themselves without), then one per cyclic coordinate.
struct Along<'a> {
    basis: &'a DMatrix<f64>,
    cyclic: &'a [bool],
    /// How many constraints are kept.
    k: usize,
    keep_cyclic: bool,
}

/// The reduced coordinates with constraints kept: the null space of J over the non-cyclic
/// coordinates, then each cyclic coordinate as it is.
fn basis(jacobian: &DMatrix<f64>, cyclic: &[bool]) -> Result<DMatrix<f64>, Fault> {
    let n = cyclic.len();
    let kept: Vec<usize> = (0..n).filter(|&i| !cyclic[i]).collect();
    let free: Vec<usize> = (0..n).filter(|&i| cyclic[i]).collect();
    let restricted = DMatrix::from_fn(jacobian.nrows(), kept.len(), |c, i| jacobian[(c, kept[i])]);
    let null = null_space(restricted).ok_or(Fault::NotFinite("the constraints' Jacobian"))?;
    let mut basis = DMatrix::zeros(n, null.ncols() + free.len());
    for (row, &i) in kept.iter().enumerate() {
        for col in 0..null.ncols() {
            basis[(i, col)] = null[(row, col)];
        }
    }
    for (col, &i) in free.iter().enumerate() {
        basis[(i, null.ncols() + col)] = 1.0;
    }
    Ok(basis)
}

/// The state, A and B along the reduced coordinates: the positions of the reduced
/// coordinates (the cyclic ones' only if kept), then the rates of all of them;
/// A = [0, I; −M⁻¹K, −M⁻¹C] and B = [0; M⁻¹·Q_u], with M, C, K and the input forces Q_u
/// taken along N.
fn first_order(
    along: &Along,
    [mass, damping, stiffness]: [&DMatrix<f64>; 3],
    forces: &DMatrix<f64>,
) -> Result<FirstOrder, Fault> {
    let Along { basis, cyclic, k, keep_cyclic } = *along;
    let n = cyclic.len();
    let free_coords: Vec<usize> = (0..n).filter(|&i| cyclic[i]).collect();
    let free = free_coords.len();
    let r = basis.ncols();
    if r == 0 {
        return Err(Fault::NoMotion);
    }
    let reduce = |m: &DMatrix<f64>| basis.transpose() * m * basis;
    let (mr, cr, kr) = (reduce(mass), reduce(damping), reduce(stiffness));
    // Whether each reduced coordinate is a cyclic one, whose position stays only if kept.
    let is_cyclic = |j: usize| if k == 0 { cyclic[j] } else { j >= r - free };
    let positions: Vec<usize> = (0..r).filter(|&j| keep_cyclic || !is_cyclic(j)).collect();
    let lu = regular(&mr)?;
    let p = positions.len();
    let size = p + r;
    let mut a = DMatrix::zeros(size, size);
    for (row, &j) in positions.iter().enumerate() {
        a[(row, p + j)] = 1.0;
    }
    let stiff = DMatrix::from_fn(r, p, |row, col| kr[(row, positions[col])]);
    a.view_mut((p, 0), (r, p)).copy_from(&(-solve(&lu, &stiff)?));
    a.view_mut((p, p), (r, r)).copy_from(&(-solve(&lu, &cr)?));
    let mut b = DMatrix::zeros(size, forces.ncols());
    b.view_mut((p, 0), (r, forces.ncols())).copy_from(&solve(&lu, &(basis.transpose() * forces))?);

    // δq = N·(positions of x), δq̇ = N·(rates of x).
    let mut at_positions = DMatrix::zeros(n, size);
    let mut at_rates = DMatrix::zeros(n, size);
    for (row, &j) in positions.iter().enumerate() {
        at_positions.column_mut(row).copy_from(&basis.column(j));
    }
    for j in 0..r {
        at_rates.column_mut(p + j).copy_from(&basis.column(j));
    }
    let cyclic_rows: Vec<usize> = (0..p).filter(|&row| is_cyclic(positions[row])).collect();

    let position_of = |j: usize| match k {
        0 => Component::Position(j),
        _ if j >= r - free => Component::Position(free_coords[j - (r - free)]),
        _ => Component::Along(j),
    };
    let rate_of = |j: usize| match k {
        0 => Component::Rate(j),
        _ if j >= r - free => Component::Rate(free_coords[j - (r - free)]),
        _ => Component::RateAlong(j),
    };
    let state = positions.iter().map(|&j| position_of(j)).chain((0..r).map(rate_of)).collect();
    Ok(FirstOrder { state, a, b, positions: at_positions, rates: at_rates, cyclic: cyclic_rows })
}

#[cfg(test)]
mod tests {
    use crate::testing::{derived, text};

    /// M, C and K of a scene about its reference.
    fn matrices(source: &str) -> [Vec<Vec<String>>; 3] {
        let mut d = derived(source);
        let lin = crate::linearize(&mut d, true).expect("linearizes");
        let pool = &d.model.pool;
        [text(pool, &lin.mass), text(pool, &lin.damping), text(pool, &lin.stiffness)]
    }

    const PENDULUM: &str = "
param m, L, g
coord theta
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

    #[test]
    fn the_pendulum_hangs_stably_and_stands_unstably() {
        let [m, c, k] = matrices(&format!("{PENDULUM}linearize about theta = 0"));
        assert_eq!(
            (m, c, k),
            (vec![vec!["m*L^2".to_string()]], vec![vec!["0".into()]], vec![vec!["m*L*g".into()]])
        );
        let [_, _, k] = matrices(&format!("{PENDULUM}linearize about theta = pi"));
        assert_eq!(k, [["-m*L*g"]]);
    }

    #[test]
    fn a_cart_is_cyclic_and_needs_no_position() {
        let source = "
param M, m, L, g
coord x, theta
particle cart { mass M; position (x, 0) }
particle bob { mass m; position (x + L*sin(theta), -L*cos(theta)) }
gravity g
linearize about theta = 0
";
        let mut d = derived(source);
        let lin = crate::linearize(&mut d, true).expect("linearizes");
        assert_eq!(lin.cyclic, [true, false]);
        assert!(lin.residual_is_zero);
        let [m, _, k] = matrices(source);
        assert_eq!(m, [["M + m", "m*L"], ["m*L", "m*L^2"]]);
        assert_eq!(k, [["0", "0"], ["0", "m*L*g"]]);
    }

    #[test]
    fn a_reference_names_every_position_and_moves_only_cyclic_coordinates() {
        let source = "
param m, L, g, w
coord theta, phi
particle bob { mass m; position (L*sin(theta)*cos(phi), L*sin(theta)*sin(phi), -L*cos(theta)) }
gravity g
";
        let mut d = derived(&format!("{source}linearize about phi' = w"));
        let errors = crate::linearize(&mut d, true).expect_err("θ has no position");
        assert!(errors[0].message.contains("no position for `theta`"), "{errors:?}");
        let mut d = derived(&format!("{source}linearize about theta = 0, theta' = w"));
        let errors = crate::linearize(&mut d, true).expect_err("θ moves");
        assert!(errors[0].message.contains("does not stay put"), "{errors:?}");
    }

    #[test]
    fn a_drive_in_time_has_no_reference() {
        let source = "
param m, k, F, w
coord x
particle p { mass m; position (x, 0) }
potential k/2*x^2
force push on p: (F*cos(w*t), 0)
linearize about x = 0
";
        let errors = crate::linearize(&mut derived(source), true).expect_err("driven");
        assert!(errors[0].message.contains("depend on time"), "{errors:?}");
    }
}
