//! Small motions about a reference, as one stage: from a [`Derivation`] and its
//! `linearize about` lines to the exact second-order form, and from that, at the parameters'
//! values, to the first-order form, its eigenvalues, the verdict on stability and a sweep.
//!
//! A scene linearizes in one of three cases, each a variant of [`Case`] (exact) and of
//! [`CaseNumbers`] (numbers), with its exact and its numeric half in one module:
//!
//! - [`holonomic`]: no velocity constraint kept. M·δq̈ + C·δq̇ + K·δq = Jᵀ·δλ in the
//!   coordinates, with J·δq = 0 for each position constraint kept with a multiplier (the state
//!   then moves in J's null space, δq = N·z).
//! - [`in_rates`]: velocity constraints kept alone. The equations in the independent rates
//!   (Maggi's form) linearized, M̃·δu̇ + C̃·δu + K̃·δp = 0, with the kinematics δṗ = G·(δp, δu).
//! - [`kept`]: position and velocity constraints kept together. M, C, K of all the
//!   coordinates with the dependent rates left as symbols, and each constraint's row at the
//!   velocity level; the dependent rates, the multipliers and the reduction to the
//!   independent coordinates and rates are done in numbers.
//!
//! Every case ends in the same [`StateSpace`]: the state's [`Component`]s and A of ẋ = A·x.
//! The next step's inputs and outputs (ẋ = A·x + B·u, y = C·x + D·u) are more of the same,
//! not new cases:
//!
//! - an input is a generalized force Q_u·u: its exact column ∂f/∂u at the reference joins each
//!   case's expressions as one more block of its layout, and each case forms B where it forms
//!   A's lower rows, −M⁻¹·Q_u (along N in the holonomic case with constraints, projected by
//!   the independent directions in the independent rates, by Qᵀ in the kept case); the
//!   inputs are handed to [`linearize`] and [`Analysis::new`] as a list, not as options;
//! - an output is an expression of the state: its gradient at the reference, lowered with the
//!   rest, gives a row of C (and of D where it names an input), along the same components;
//! - keeping every coordinate (SymPy's convention) rather than dropping cyclic and ignorable
//!   positions changes which [`Component`]s a case lists and adds their zero columns to A; it
//!   is a choice passed to the cases, not a case of its own.
//!
//! The numbers of a case are read from one lowered program through a typed layout: each
//! matrix is a named block of the program's outputs, placed when the program is built.
//!
//! What it does not do: load scenes, resolve the command line's reference (the model's
//! `resolve_about` does, before the derivation), or print; `engine` strings it together and a
//! front end renders it.

pub mod holonomic;
pub mod in_rates;
pub mod kept;

mod analysis;
mod dense;
mod eigen;
mod evaluation;
mod exact;
mod fault;
mod layout;
mod reference;
mod signals;
mod spectrum;
mod sweep;

use cas::{ExprId, Pool, SymId};
use lang::{Diagnostic, Span};
use mechanics::Derivation;

pub use analysis::Analysis;
pub use exact::{exact_state_space, ExactStateSpace};
pub use fault::Fault;
pub use signals::{OutputRow, Rank, RANK_TOLERANCE};
pub use spectrum::{Stability, RELATIVE_TOLERANCE};
pub use sweep::{sweep, Change, Row, Sweep};

/// M·δẍ + C·δẋ + K·δx = 0 about a reference, exactly, where what x is depends on the case
/// ([`Case`]): the coordinates, or the positions kept and the independent rates.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// The remaining coordinates, in the derivation's order.
    pub coords: Vec<SymId>,
    /// Whether each leaves the state: cyclic (in neither M nor f nor a kept constraint), or,
    /// in the independent rates, ignorable. Its δq goes; a neighbouring steady motion may move
    /// it at another rate.
    pub cyclic: Vec<bool>,
    /// The reference position of each coordinate; `None` for one that needs none.
    pub positions: Vec<Option<ExprId>>,
    /// The reference rate of each coordinate (0 unless given; a dependent rate as the
    /// constraints give it, or its own symbol where only numbers can).
    pub rates: Vec<ExprId>,
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    /// What must vanish at the reference (per case: f + Jᵀλ with λ the multipliers' symbols,
    /// or the equations in the independent rates and the rates of dependent positions).
    pub residual: Vec<ExprId>,
    /// Whether the algebra shows the residual zero for every value of the parameters.
    pub residual_is_zero: bool,
    pub case: Case,
    /// The last `linearize about` line, which the reference is reported at.
    pub span: Span,
    /// Whether the positions of cyclic coordinates stay in the state (the default: the
    /// state is (q, q̇) of every coordinate), their eigenvalues zeros set aside from the verdict.
    /// Ignorable positions in the nonholonomic cases leave the state either way.
    pub keep_cyclic: bool,
    /// The scene's inputs, each at the value it takes when nothing drives it.
    pub inputs: Vec<SymId>,
    /// ∂f/∂u at the reference: one row per row of `mass`, one column per input (in the
    /// independent rates, of the right-hand side of M̃·δu̇ + … = B̃·δu).
    pub input_forces: Vec<Vec<ExprId>>,
    /// The scene's outputs' gradients at the reference.
    pub outputs: Vec<OutputRow>,
}

/// What every case adds about inputs and outputs (see [`Linearization`]'s fields).
pub(crate) struct Signals {
    pub inputs: Vec<SymId>,
    pub input_forces: Vec<Vec<ExprId>>,
    pub outputs: Vec<OutputRow>,
}

/// What the matrices of a [`Linearization`] mean, and what else its case needs.
#[derive(Clone, Debug)]
pub enum Case {
    /// No velocity constraint kept: M, C, K of all the coordinates, with the position
    /// constraints kept with multipliers (none for a scene without).
    Holonomic { constraints: Vec<LinearConstraint> },
    /// Velocity constraints kept alone: the equations in the independent rates.
    InRates(in_rates::InRates),
    /// Position and velocity constraints kept together.
    Kept(kept::Kept),
}

/// A kept constraint at the reference: its linearized row J·δq = 0, and Φ and γ there.
#[derive(Clone, Debug)]
pub struct LinearConstraint {
    /// Its index among the model's constraints.
    pub constraint: usize,
    /// Whether it restrains positions (Φ(q, t) = 0), rather than rates alone (A·q̇ + b = 0).
    pub positional: bool,
    /// The multiplier's symbol (`rod.force`), which appears in K and in the residual.
    pub lambda: SymId,
    /// ∂Φ/∂q for a position constraint, ∂Φ/∂q̇ for a velocity constraint: its row of
    /// J·q̈ = γ, and the direction of its reaction.
    pub jacobian: Vec<ExprId>,
    /// Φ at the reference: zero on a position constraint (for a velocity constraint kept with
    /// position ones, with the dependent rates at 0).
    pub phi: ExprId,
    pub bias: ExprId,
}

impl Linearization {
    /// The constraints kept with multipliers (none in the independent rates, where the
    /// multipliers cancel).
    pub fn constraints(&self) -> &[LinearConstraint] {
        match &self.case {
            Case::Holonomic { constraints } => constraints,
            Case::Kept(kept) => &kept.constraints,
            Case::InRates(_) => &[],
        }
    }

    /// The equations in the independent rates, if that is the case.
    pub fn in_rates(&self) -> Option<&in_rates::InRates> {
        match &self.case {
            Case::InRates(r) => Some(r),
            _ => None,
        }
    }

    /// Position and velocity constraints kept together, if that is the case.
    pub fn kept(&self) -> Option<&kept::Kept> {
        match &self.case {
            Case::Kept(k) => Some(k),
            _ => None,
        }
    }

    /// The reference as the scene's terms: each coordinate's position (where it has one),
    /// then each rate.
    pub fn reference(&self) -> Vec<(SymId, bool, ExprId)> {
        let positions = self.coords.iter().zip(&self.positions);
        let mut out: Vec<_> = positions.filter_map(|(q, p)| p.map(|p| (*q, false, p))).collect();
        out.extend(self.coords.iter().zip(&self.rates).map(|(q, r)| (*q, true, *r)));
        out
    }
}

impl Linearization {
    /// The parts every case fills alike: where the reference puts each coordinate, and the
    /// exact second-order form there.
    pub(crate) fn new(
        coords: Vec<SymId>,
        placed: reference::Placed,
        exact: reference::AtReference,
        residual_is_zero: bool,
        (case, signals): (Case, Signals),
        span: Span,
    ) -> Linearization {
        let reference::Placed { cyclic, positions, rates } = placed;
        let reference::AtReference { mass, damping, stiffness, residual } = exact;
        let Signals { inputs, input_forces, outputs } = signals;
        Linearization {
            keep_cyclic: true,
            inputs,
            input_forces,
            outputs,
            coords,
            cyclic,
            positions,
            rates,
            mass,
            damping,
            stiffness,
            residual,
            residual_is_zero,
            case,
            span,
        }
    }
}

/// The first-order form ẋ = A·x + B·u, y = C·x + D·u of the small motions, its state named.
#[derive(Clone, Debug)]
pub struct StateSpace {
    /// What each component of x is.
    pub state: Vec<Component>,
    /// A, one row per component of x.
    pub a: Vec<Vec<f64>>,
    /// B, one row per component of x, one column per input.
    pub b: Vec<Vec<f64>>,
    /// C, one row per output, one column per component of x.
    pub c: Vec<Vec<f64>>,
    /// D, one row per output, one column per input.
    pub d: Vec<Vec<f64>>,
    /// The rank of the controllability matrix (`None` without inputs).
    pub controllability: Option<Rank>,
    /// The rank of the observability matrix (`None` without outputs).
    pub observability: Option<Rank>,
}

/// A case's first-order form in numbers, before C and D: the state, A and B, and where the
/// state puts δq and δq̇ (δq = P·x, δq̇ = V·x, n × the state's size each).
pub(crate) struct FirstOrder {
    pub state: Vec<Component>,
    pub a: nalgebra::DMatrix<f64>,
    pub b: nalgebra::DMatrix<f64>,
    pub positions: nalgebra::DMatrix<f64>,
    pub rates: nalgebra::DMatrix<f64>,
    /// The components that are the positions of cyclic coordinates kept: their columns of A
    /// are zero, so each is an eigenvalue 0, set aside from the verdict.
    pub cyclic: Vec<usize>,
}

/// A component of the state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    /// δq of a coordinate (its index among the linearization's `coords`).
    Position(usize),
    /// δq̇ of a coordinate.
    Rate(usize),
    /// δz of a direction along the kept constraints' null space (counted from 0).
    Along(usize),
    /// δż of such a direction.
    RateAlong(usize),
}

impl Component {
    /// `theta`, `theta'`, `z1`, `z1'`: the name a report gives it.
    pub fn name(self, pool: &Pool, coords: &[SymId]) -> String {
        let coord = |i: usize| pool.symbol(coords[i]).name.clone();
        match self {
            Component::Position(i) => coord(i),
            Component::Rate(i) => format!("{}'", coord(i)),
            Component::Along(j) => format!("z{}", j + 1),
            Component::RateAlong(j) => format!("z{}'", j + 1),
        }
    }
}

/// The linearization at one set of parameter values.
#[derive(Clone, Debug)]
pub struct Numbers {
    /// The parameters' values, in declaration order.
    pub parameters: Vec<f64>,
    /// M, C, K as the case has them (reduced in numbers, in the kept case).
    pub mass: Vec<Vec<f64>>,
    pub damping: Vec<Vec<f64>>,
    /// With the multipliers at their reference values.
    pub stiffness: Vec<Vec<f64>>,
    /// The multipliers at the reference, in the order of the derivation's.
    pub multipliers: Vec<f64>,
    /// The accelerations at the reference (zero within the tolerance), per coordinate; in the
    /// independent rates, per independent rate, then the rate of each dependent position kept
    /// (the [`in_rates::InRates`]'s `residual_symbols`).
    pub accelerations: Vec<f64>,
    /// ẋ = A·x.
    pub first_order: StateSpace,
    /// (re, im), by real part from the largest down (those within their bound of zero as
    /// zero), then by imaginary part.
    pub eigenvalues: Vec<(f64, f64)>,
    /// How far rounding may have moved each eigenvalue (in the same order): eps·‖A‖ with a
    /// margin (the rounding of A's entries, and the iteration's own in A balanced) times the
    /// eigenvalue's condition (that of its group where rounding cannot tell the group apart),
    /// plus the group's spread. The verdict compares each real part with its own bound.
    pub bounds: Vec<f64>,
    pub stability: Stability,
    /// The largest of the bounds.
    pub tolerance: f64,
    /// How many of the zero eigenvalues are first integrals' (conserved combinations of the
    /// state, which the verdict leaves aside: they lead to neighbouring steady motions).
    pub first_integrals: usize,
    /// How many of the zero eigenvalues are those of cyclic coordinates' positions kept in the
    /// state (the verdict leaves them aside too: such a position drifts with its rate).
    pub cyclic_zeros: usize,
    pub case: CaseNumbers,
}

impl Numbers {
    /// The parts every case fills alike, from its matrices in numbers.
    pub(crate) fn new(
        parameters: &[f64],
        [mass, damping, stiffness]: [&nalgebra::DMatrix<f64>; 3],
        (multipliers, accelerations): (Vec<f64>, Vec<f64>),
        first_order: StateSpace,
        spectrum: spectrum::Spectrum,
        case: CaseNumbers,
    ) -> Numbers {
        Numbers {
            parameters: parameters.to_vec(),
            mass: dense::rows_of(mass),
            damping: dense::rows_of(damping),
            stiffness: dense::rows_of(stiffness),
            multipliers,
            accelerations,
            first_order,
            eigenvalues: spectrum.eigenvalues,
            bounds: spectrum.bounds,
            stability: spectrum.stability,
            tolerance: spectrum.tolerance,
            first_integrals: spectrum.first_integrals,
            cyclic_zeros: spectrum.cyclic_zeros,
            case,
        }
    }

    /// In the kept case, the coordinates whose positions stay in the state, then those whose
    /// rates are the independent rates, as the numbers chose them.
    pub fn reduced(&self) -> Option<(Vec<usize>, Vec<usize>)> {
        match &self.case {
            CaseNumbers::Kept(r) => Some((r.positions.clone(), r.rates.clone())),
            _ => None,
        }
    }
}

/// The numbers particular to a case at one set of parameter values.
#[derive(Clone, Debug)]
pub enum CaseNumbers {
    /// With constraints kept: the basis N of their null space (one column per reduced
    /// coordinate z, then one per cyclic coordinate; one row per coordinate), δq = N·z.
    /// `None` without.
    Holonomic { basis: Option<Vec<Vec<f64>>> },
    /// G of δṗ = G·(δp, δu), one row per position kept.
    InRates { kinematics: Vec<Vec<f64>> },
    /// The reduction in numbers.
    Kept(kept::Reduced),
}

/// Linearizes the equations of motion about the reference of the scene's `linearize about`
/// lines (a later line overrides an earlier one item by item), in the case the kept
/// constraints call for. Errors point at the items or lines at fault: a coordinate that was
/// eliminated, a position missing, a non-cyclic coordinate given a rate, equations that
/// depend on time there.
///
/// With `keep_cyclic`, the positions of cyclic coordinates stay in the state (the default of
/// every front end); without, they leave it as their rates' first integrals do.
pub fn linearize(d: &mut Derivation, keep_cyclic: bool) -> Result<Linearization, Vec<Diagnostic>> {
    let mut lin = linearize_case(d)?;
    lin.keep_cyclic = keep_cyclic;
    Ok(lin)
}

fn linearize_case(d: &mut Derivation) -> Result<Linearization, Vec<Diagnostic>> {
    let Some(span) = d.model.linearize.last().map(|l| l.span) else {
        return Err(vec![Diagnostic::error(Span::default(), "no `linearize about` line")
            .with_hint("add `linearize about q = …` naming the reference")]);
    };
    let items = reference::items(d);
    let errors = reference::eliminated(d, &items);
    let velocity = d.multipliers.iter().any(|m| m.rows.position.is_none());
    let position = d.multipliers.iter().any(|m| m.rows.position.is_some());
    if !velocity {
        // The holonomic case goes on to report what else is wrong with the items.
        return holonomic::linearize(d, span, &items, errors);
    }
    if !errors.is_empty() {
        Err(errors)
    } else if position || d.multipliers.len() > mechanics::DEPENDENT_LIMIT {
        kept::linearize(d, span, &items)
    } else {
        in_rates::linearize(d, span, &items)
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Scenes derived for the cases' tests.

    /// A scene derived whole.
    pub fn derived(source: &str) -> mechanics::Derivation {
        let ast = lang::parse(source).expect("the scene parses");
        let (model, _warnings) = model::resolve(&ast, source).expect("the scene resolves");
        mechanics::derive(model).expect("the scene derives")
    }

    /// A matrix as text, row by row.
    pub fn text(pool: &cas::Pool, m: &[Vec<cas::ExprId>]) -> Vec<Vec<String>> {
        m.iter().map(|r| r.iter().map(|e| pool.print(*e, cas::Style::Ascii)).collect()).collect()
    }
}
