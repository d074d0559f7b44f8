//! Velocity constraints kept alone: the equations in the independent rates (Maggi's form, in
//! which the multipliers cancel) linearized about the reference. The state is the positions
//! kept and the independent rates, δp and δu, with
//!
//! M̃·δu̇ + C̃·δu + K̃·δp = 0 (the [`Linearization`]'s `mass`, `damping`, `stiffness`) and
//! δṗ = G·(δp, δu) (the kinematics: ṗ = u for an independent rate, the dependent rate's
//! expression for a dependent one),
//!
//! so that A = [G; −M̃⁻¹·(K̃, C̃)], whose first integrals (the rates of ignorable coordinates)
//! are deflated before the verdict.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::{Derivation, IndependentForm};
use nalgebra::{DMatrix, DVector};

use crate::dense::{regular, rows_of, solve};
use crate::evaluation::Evaluation;
use crate::fault::{Fault, EQUILIBRIUM_TOLERANCE};
use crate::layout::{Block, Outputs};
use crate::reference::{self, AtReference, Items, Placed};
use crate::signals::{self, SignalBlocks};
use crate::{Case, CaseNumbers, Component, FirstOrder, Linearization, Numbers, Signals};

/// What the equations in the independent rates add to a [`Linearization`].
#[derive(Clone, Debug)]
pub struct InRates {
    /// The independent rates u, in the coordinates' order.
    pub rates: Vec<SymId>,
    /// The coordinates (indices into `coords`) whose positions stay in the state: those the
    /// equations in the independent rates depend on, and those the rates of these depend on,
    /// in the coordinates' order. The others are ignorable (cyclic).
    pub kept: Vec<usize>,
    /// G: one row per position kept; columns the positions kept, then the independent rates.
    pub kinematics: Vec<Vec<ExprId>>,
    /// Each dependent rate and its expression in the positions and the independent rates.
    pub dependent: Vec<(SymId, ExprId)>,
    /// What each entry of the residual stands for: the acceleration of each independent rate
    /// (the residual is that equation's M̃·u̇ + h at u̇ = 0, h), then the rate of each
    /// dependent position kept (which must vanish for the reference to stay).
    pub residual_symbols: Vec<SymId>,
}

/// Linearizes in the independent rates.
pub(crate) fn linearize(
    d: &mut Derivation,
    span: Span,
    items: &Items,
) -> Result<Linearization, Vec<Diagnostic>> {
    let form = independent_form(d, span)?;
    let n = d.coords.len();
    let pool = &mut d.model.pool;
    let accels: Vec<SymId> = form
        .independent
        .iter()
        .map(|u| pool.rate(*u).expect("a rate has an acceleration"))
        .collect();
    // ṗ of each coordinate: u itself, or the dependent rate's expression.
    let dependent_of = |r: SymId| form.dependent.iter().find(|(d, _)| *d == r).map(|(_, e)| *e);
    let kinematic: Vec<ExprId> =
        d.rates.iter().map(|&r| dependent_of(r).unwrap_or_else(|| pool.sym(r))).collect();
    let is_dependent: Vec<bool> = d.rates.iter().map(|&r| dependent_of(r).is_some()).collect();
    let kept = kept_positions(pool, &d.coords, &form.equations, &kinematic);

    let reference = Reference::of(pool, (&d.coords, &d.rates), items, &kept, &is_dependent);
    let Reference { positions, given_rates, mut map, mut errors } = reference;
    for u in &form.independent {
        map.entry(*u).or_insert(pool.zero());
    }
    for a in &accels {
        map.insert(*a, pool.zero());
    }
    map.extend(signals::reference_inputs(&d.model.inputs));
    let missing: Vec<SymId> =
        (0..n).filter(|&i| kept[i] && positions[i].is_none()).map(|i| d.coords[i]).collect();
    errors.extend(reference::missing_positions(pool, &missing, span, "an ignorable"));
    if !errors.is_empty() {
        return Err(errors);
    }

    let at = |pool: &mut Pool, e: ExprId| {
        let e = pool.subst(e, &map);
        pool.simplify(e)
    };
    let kept_index: Vec<usize> = (0..n).filter(|&i| kept[i]).collect();
    let AtReference { mass, damping, stiffness, mut residual } =
        matrices(pool, &form, &accels, &d.coords, &kept_index, at);
    let mut residual_symbols = accels.clone();
    let mut kinematics = Vec::new();
    for &i in &kept_index {
        let mut row = Vec::new();
        for &j in &kept_index {
            let d = pool.diff(kinematic[i], d.coords[j]);
            row.push(at(pool, d));
        }
        for u in &form.independent {
            let d = pool.diff(kinematic[i], *u);
            row.push(at(pool, d));
        }
        kinematics.push(row);
        if is_dependent[i] {
            residual.push(at(pool, kinematic[i]));
            residual_symbols.push(d.rates[i]);
        }
    }
    let rates: Vec<ExprId> = (0..n)
        .map(|i| match is_dependent[i] {
            true => at(pool, kinematic[i]),
            false => given_rates[i].unwrap_or(pool.zero()),
        })
        .collect();
    let residual_is_zero = residual.iter().all(|r| pool.is_identically_zero(*r));

    let matrices = [&mass[..], &damping, &stiffness];
    let more: Vec<ExprId> = kinematics.iter().flatten().copied().collect();
    let all = reference::all_of(matrices, &residual, &[], &more);
    reference::refuse_time_dependence(pool, &all, d.model.time, span)?;

    // M̃·δu̇ + … + (∂h/∂u)·δu = 0: the inputs' forces are −∂h/∂u.
    let inputs: Vec<SymId> = d.model.inputs.iter().map(|u| u.sym).collect();
    let zero_accels: HashMap<SymId, ExprId> = accels.iter().map(|a| (*a, pool.zero())).collect();
    let mut minus_at = |pool: &mut Pool, e: ExprId| {
        let e = pool.subst(e, &zero_accels);
        let e = at(pool, e);
        pool.neg(e)
    };
    let input_forces = signals::input_columns(pool, &form.equations, &inputs, &mut minus_at);
    let dependent: Vec<SymId> = form.dependent.iter().map(|(r, _)| *r).collect();
    let why = "a dependent rate, which the state gives only through the constraints";
    let outputs = signals::output_rows(d, &mut |p, e| at(p, e), Some((&dependent, why)))?;
    let signals = Signals { inputs, input_forces, outputs };

    let placed = Placed { cyclic: kept.iter().map(|k| !k).collect(), positions, rates };
    let exact = AtReference { mass, damping, stiffness, residual };
    let case = Case::InRates(InRates {
        rates: form.independent.clone(),
        kept: kept_index,
        kinematics,
        dependent: form.dependent.clone(),
        residual_symbols,
    });
    Ok(Linearization::new(d.coords.clone(), placed, exact, residual_is_zero, (case, signals), span))
}

/// The equations in the independent rates, or why they could not be formed, at the kept
/// constraint that stands in the way.
fn independent_form(d: &mut Derivation, span: Span) -> Result<IndependentForm, Vec<Diagnostic>> {
    if let Some(form) = d.independent_form() {
        return Ok(form);
    }
    let c = d
        .multipliers
        .iter()
        .find(|m| d.model.constraints[m.constraint].force_requested)
        .or(d.multipliers.first())
        .map(|m| &d.model.constraints[m.constraint]);
    let (at, name) = c.map_or((span, String::new()), |c| (c.span, c.name.clone()));
    Err(vec![Diagnostic::error(
        at,
        "the equations in the independent rates could not be formed, which linearizing \
         with velocity constraints needs",
    )
    .with_label(format!("`{name}` is kept with a multiplier"))
    .with_related(span, "linearized here")
    .with_hint(
        "the dependent rates must solve exactly (at most four kept constraints), and no \
         `show` or `expect` line may ask for a kept constraint's reaction",
    )])
}

/// The positions kept: those the equations depend on, and, in turn, those the rates of kept
/// positions depend on.
fn kept_positions(
    pool: &mut Pool,
    coords: &[SymId],
    equations: &[ExprId],
    kinematic: &[ExprId],
) -> Vec<bool> {
    let n = coords.len();
    let mut kept: Vec<bool> =
        coords.iter().map(|q| equations.iter().any(|e| pool.depends_on(*e, *q))).collect();
    loop {
        let mut grew = false;
        for i in 0..n {
            if !kept[i] {
                continue;
            }
            for (j, q) in coords.iter().enumerate() {
                if !kept[j] && pool.depends_on(kinematic[i], *q) {
                    kept[j] = true;
                    grew = true;
                }
            }
        }
        if !grew {
            return kept;
        }
    }
}

/// The reference's items read for this case: positions and the rates given, the
/// substitution they make, and what is wrong with them.
struct Reference {
    positions: Vec<Option<ExprId>>,
    given_rates: Vec<Option<ExprId>>,
    map: HashMap<SymId, ExprId>,
    errors: Vec<Diagnostic>,
}

impl Reference {
    fn of(
        pool: &Pool,
        (coords, rates): (&[SymId], &[SymId]),
        items: &Items,
        kept: &[bool],
        is_dependent: &[bool],
    ) -> Reference {
        let n = coords.len();
        let mut out = Reference {
            positions: vec![None; n],
            given_rates: vec![None; n],
            map: HashMap::new(),
            errors: Vec::new(),
        };
        for ((coord, rate), (value, item_span)) in items {
            let Some(i) = coords.iter().position(|q| q == coord) else { continue };
            let name = pool.symbol_text(*coord, cas::Style::Unicode);
            if !*rate {
                out.positions[i] = Some(*value);
                out.map.insert(*coord, *value);
            } else if is_dependent[i] {
                out.errors.push(reference::dependent_given(*item_span, &name, "velocity"));
            } else {
                out.given_rates[i] = Some(*value);
                out.map.insert(rates[i], *value);
                if kept[i] && !pool.is_zero(*value) {
                    let why = "ignorable: the equations in the independent rates depend on it";
                    let may = "ignorable coordinates (those in neither the equations in the \
                               independent rates nor the rates of the positions they need)";
                    out.errors.push(reference::moves(*item_span, &name, why, may));
                }
            }
        }
        out
    }
}

/// M̃, C̃, K̃ and the residual of the equations in the independent rates at the reference.
fn matrices(
    pool: &mut Pool,
    form: &IndependentForm,
    accels: &[SymId],
    coords: &[SymId],
    kept: &[usize],
    at: impl Fn(&mut Pool, ExprId) -> ExprId,
) -> AtReference {
    let zero_accels: HashMap<SymId, ExprId> = accels.iter().map(|a| (*a, pool.zero())).collect();
    let (mut mass, mut damping, mut stiffness, mut residual) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for e in &form.equations {
        let h = pool.subst(*e, &zero_accels);
        let mut m = Vec::new();
        for a in accels {
            let d = pool.diff(*e, *a);
            m.push(at(pool, d));
        }
        let mut c = Vec::new();
        for u in &form.independent {
            let d = pool.diff(h, *u);
            c.push(at(pool, d));
        }
        let mut k = Vec::new();
        for &i in kept {
            let d = pool.diff(h, coords[i]);
            k.push(at(pool, d));
        }
        mass.push(m);
        damping.push(c);
        stiffness.push(k);
        residual.push(at(pool, h));
    }
    AtReference { mass, damping, stiffness, residual }
}

/// Where the matrices of the equations in the independent rates sit among the program's
/// outputs; the program has no inputs but the parameters.
pub(crate) struct Blocks {
    mass: Block,
    damping: Block,
    stiffness: Block,
    residual: Block,
    kinematics: Block,
    /// The independent rates' coordinates (indices into `coords`).
    rates: Vec<usize>,
    signals: SignalBlocks,
}

impl Blocks {
    pub fn place(
        outputs: &mut Outputs,
        lin: &Linearization,
        r: &InRates,
        rates: &[SymId],
    ) -> Blocks {
        let (nu, np) = (r.rates.len(), r.kept.len());
        Blocks {
            mass: outputs.matrix(&lin.mass, nu),
            damping: outputs.matrix(&lin.damping, nu),
            stiffness: outputs.matrix(&lin.stiffness, np),
            residual: outputs.column(&lin.residual),
            kinematics: outputs.matrix(&r.kinematics, np + nu),
            rates: r.rates.iter().filter_map(|u| rates.iter().position(|v| v == u)).collect(),
            signals: SignalBlocks::place(outputs, lin),
        }
    }
}

/// The numbers at `parameters`: see the module's doc.
pub(crate) fn at(
    e: &mut Evaluation,
    blocks: &Blocks,
    lin: &Linearization,
    r: &InRates,
    parameters: &[f64],
) -> Result<Numbers, Fault> {
    let (nu, np) = (r.rates.len(), r.kept.len());
    let out = e.outputs(parameters, &[]);
    if out.iter().any(|v| !v.is_finite()) {
        return Err(Fault::NotFinite("M̃, C̃, K̃, the kinematics or the residual"));
    }
    let mass = blocks.mass.matrix(&out);
    let damping = blocks.damping.matrix(&out);
    let stiffness = blocks.stiffness.matrix(&out);
    let residual_values = blocks.residual.vector(&out);
    let kinematics = blocks.kinematics.matrix(&out);

    let lu = regular(&mass)?;
    let h = DVector::from_fn(nu, |j, _| residual_values[j]);
    let solved = lu.solve(&h).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
    let mut accelerations: Vec<f64> = solved.iter().map(|a| -a).collect();
    accelerations.extend((nu..lin.residual.len()).map(|j| residual_values[j]));
    if !lin.residual_is_zero {
        let residual = e.residual(parameters, &[]);
        let held = residual.iter().enumerate().all(|(j, (r, size))| {
            // As for M·q̈ = f: a shift of the reference by 1e-3 leaves this much.
            let row: f64 = if j < nu {
                stiffness.row(j).iter().map(|x| x.abs()).sum()
            } else {
                kinematics.row(j - nu).iter().map(|x| x.abs()).sum()
            };
            r.abs() <= EQUILIBRIUM_TOLERANCE * size.max(1e-3 * row)
        });
        if !held || accelerations.iter().any(|a| !a.is_finite()) {
            let symbols = r.residual_symbols.clone();
            return Err(Fault::NotEquilibrium { accelerations, symbols });
        }
    }

    let size = np + nu;
    let mut a = DMatrix::zeros(size, size);
    a.view_mut((0, 0), (np, size)).copy_from(&kinematics);
    let mut forces = DMatrix::zeros(nu, size);
    forces.view_mut((0, 0), (nu, np)).copy_from(&stiffness);
    forces.view_mut((0, np), (nu, nu)).copy_from(&damping);
    a.view_mut((np, 0), (nu, size)).copy_from(&(-solve(&lu, &forces)?));
    if size == 0 {
        return Err(Fault::NoMotion);
    }
    let forces = blocks.signals.forces(&out);
    let mut b = DMatrix::zeros(size, forces.ncols());
    b.view_mut((np, 0), (nu, forces.ncols())).copy_from(&solve(&lu, &forces)?);
    // δq of the positions kept; δq̇ of the independent rates, and of the positions kept by G.
    let n = lin.coords.len();
    let mut at_positions = DMatrix::zeros(n, size);
    let mut at_rates = DMatrix::zeros(n, size);
    for (row, &i) in r.kept.iter().enumerate() {
        at_positions[(i, row)] = 1.0;
    }
    for (j, &i) in blocks.rates.iter().enumerate() {
        at_rates[(i, np + j)] = 1.0;
    }
    for (row, &i) in r.kept.iter().enumerate() {
        at_rates.row_mut(i).copy_from(&kinematics.row(row));
    }
    let positions = r.kept.iter().map(|&i| Component::Position(i));
    let state = positions.chain(blocks.rates.iter().map(|&i| Component::Rate(i))).collect();
    let first =
        FirstOrder { state, a, b, positions: at_positions, rates: at_rates, cyclic: vec![] };
    let (space, spectrum) = signals::complete(first, &blocks.signals, &out, true)?;
    let case = CaseNumbers::InRates { kinematics: rows_of(&kinematics) };
    let matrices = [&mass, &damping, &stiffness];
    let solved = (Vec::new(), accelerations);
    Ok(Numbers::new(parameters, matrices, solved, space, spectrum, case))
}

#[cfg(test)]
mod tests {
    use crate::testing::{derived, text};
    use crate::{Analysis, Component, Stability};

    /// A Chaplygin sleigh gliding straight on at speed v.
    const SLEIGH: &str = "
param m = 1 kg, I = 1/10 kg*m^2, a = 1/5 m, v = 1 m/s
coord x = 0, x' = v
coord y = 0
coord theta = 0, theta' = 0
body sleigh { mass m; inertia I; position (x + a*cos(theta), y + a*sin(theta)); angle theta }
constraint blade: y'*cos(theta) = x'*sin(theta)
linearize about theta = 0, x' = v
";

    #[test]
    fn the_sleigh_is_linearized_in_its_independent_rates_and_turns_back_straight() {
        let mut d = derived(SLEIGH);
        let lin = crate::linearize(&mut d, true).expect("linearizes");
        let r = lin.in_rates().expect("in the independent rates");
        let pool = &d.model.pool;
        let names: Vec<&str> = r.rates.iter().map(|u| pool.symbol(*u).name.as_str()).collect();
        assert_eq!(names, ["x'", "theta'"]);
        assert_eq!(r.kept, [2], "only θ's position matters");
        assert_eq!(text(pool, &lin.damping), [["0", "0"], ["0", "m*a*v"]]);
        assert!(lin.constraints().is_empty(), "the multipliers cancel");

        let parameters: Vec<cas::SymId> = d.model.params.iter().map(|p| p.sym).collect();
        let mut analysis = Analysis::new(&d, &parameters, lin).expect("lowers");
        let at = analysis.at(&[1.0, 0.1, 0.2, 1.0]).expect("an equilibrium");
        let state = [Component::Position(2), Component::Rate(0), Component::Rate(2)];
        assert_eq!(at.first_order.state, state);
        assert_eq!(at.first_order.a.len(), 3);
        // The heading and the speed are neutral; the turn dies out.
        assert_eq!((at.first_integrals, at.stability), (2, Stability::Stable));
        let turning = -0.2 / (0.1 + 0.04);
        assert!(at.eigenvalues.iter().any(|z| (z.0 - turning).abs() < 1e-12), "{at:?}");
    }
}
