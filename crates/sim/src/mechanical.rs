//! Equations of motion as a first-order problem: the state (q, q̇) with accelerations from
//! M q̈ = f, or (q, p) in canonical variables for the symplectic method, each with its exact
//! Jacobian when the partials of its equations were lowered too.

use nalgebra::DMatrix;
use numeric::{Slice, Tape};

use crate::linalg::{self, Saddle, Small, Square};
use crate::{check_finite, rate, Contact, FaultKind, Hold, NonFiniteAt, Problem, Series};

mod jacobian;
mod many;
mod modes;
mod saltation;

pub use modes::Watched;

pub(crate) use many::{finite_lanes, solve_lanes};

/// How the slots of the programs are laid out. The dynamics program takes
/// `[t, q (n), q̇ (n), parameters (k)]` and gives `M` (n×n, column-major), `f` (n), then per
/// multiplier the Jacobian row J (n values), γ, Φ and Φ̇. The observation program takes
/// `[t, q, q̇, q̈ (n), λ (m), parameters]` and gives the recorded quantities. The partials
/// program, which only implicit methods need, takes the observation inputs and gives
/// ∂(r, c, Φ, Φ̇)/∂(q, q̇) with q̈ and λ held fixed, row-major: the rows are r = M q̈ − Jᵀλ − f
/// (n), then c = J q̈ − γ, Φ and Φ̇ of each multiplier (m each, the drift rows as the dynamics
/// program gives them), and each row has its n partials in q, then its n in q̇.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    pub coordinates: usize,
    pub multipliers: usize,
    pub parameters: usize,
}

impl Layout {
    pub fn dynamics_outputs(&self) -> usize {
        let (n, m) = (self.coordinates, self.multipliers);
        n * n + n + m * (n + 3)
    }

    /// What the dynamics program's output `index` is: an entry of M, of f, or a constraint's.
    pub fn dynamics_entry(&self, index: usize) -> NonFiniteAt {
        let n = self.coordinates;
        if index < n * n {
            NonFiniteAt::Mass { row: index % n, column: index / n }
        } else if index < n * n + n {
            NonFiniteAt::Force { coordinate: index - n * n }
        } else {
            NonFiniteAt::Constraint { constraint: (index - n * n - n) / (n + 3) }
        }
    }

    pub fn dynamics_inputs(&self) -> usize {
        1 + 2 * self.coordinates + self.parameters
    }

    pub fn observation_inputs(&self) -> usize {
        1 + 3 * self.coordinates + self.multipliers + self.parameters
    }

    /// The partials program's outputs: (n + 3m) rows of 2n.
    pub fn partials_outputs(&self) -> usize {
        (self.coordinates + 3 * self.multipliers) * 2 * self.coordinates
    }

    /// A sensitivity program's outputs for `columns` parameters: (n + 3m) rows of `columns`.
    pub fn sensitivity_outputs(&self, columns: usize) -> usize {
        (self.coordinates + 3 * self.multipliers) * columns
    }
}

/// How the integrator keeps one kept constraint from drifting: the slot after γ holds Φ and
/// the next Φ̇ for a position constraint; for a velocity constraint the first holds its
/// residual A·q̇ + b and the second is unused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stabilisation {
    /// J q̈ = γ − 2α Φ̇ − α² Φ.
    Position,
    /// J q̈ = γ − α·(A q̇ + b): a velocity constraint has no position level to drift at.
    Velocity,
}

/// The rate α = β (1/s) at which Baumgarte stabilisation pulls kept constraints back, in every
/// run and in the generated code, so that both integrate the same right-hand side.
///
/// It limits the explicit methods' steps: their stages leave the constraint manifold by their
/// own truncation, Baumgarte's terms answer at rate α, and the error estimate sees that once
/// h·α nears 1, well inside the stability region. At 10/s a rimless wheel on dop853 at 1e-10
/// took 192 steps over 6 s (h ≈ 0.03 s), Garcia's walker 2749 over 120 s; at 2/s they take 73
/// and 434, the Cartesian pendulum's swing 44 rather than 109 (33 in its angle alone), with
/// the drift still below the tolerance (`lagrange simulate` prints it). Below 2/s the drift of
/// a quaternion's norm moved a sphere's stop by 2.5e-8 (`tests/friction.rs`).
pub const BAUMGARTE_RATE: f64 = 2.0;

/// Whether the outputs a slice of the dynamics program gave in `out` are finite, naming the
/// first that is not.
fn slice_finite(out: &[f64], slice: &Slice, layout: Layout) -> Result<(), FaultKind> {
    match slice.outputs().iter().find(|&&o| !out[o].is_finite()) {
        Some(&o) => Err(FaultKind::NonFinite { at: layout.dynamics_entry(o) }),
        None => Ok(()),
    }
}

/// How many slices of the dynamics or the partials program a problem keeps, one per set of
/// kept rows ([`Mechanical::kept_accelerations`], [`Mechanical::kept_partials_at`]).
const SLICES: usize = 64;

/// The equations of motion M q̈ − Jᵀλ = f, J q̈ = γ as y' = F(t, y) with y = (q, q̇).
///
/// Constraints kept with multipliers drift at the position and velocity level, because only
/// their second derivative is imposed. Baumgarte stabilisation replaces J q̈ = γ by
/// J q̈ = γ − 2α Φ̇ − β² Φ, which makes Φ decay like a critically damped oscillator with the
/// rate `baumgarte` (α = β); the run reports the largest |Φ| it saw.
///
/// A clone is a problem of its own (its programs' registers and its solver's buffers copied):
/// an ensemble clones one per thread and runs it at one set of parameters after another.
#[derive(Clone)]
pub struct Mechanical {
    pub layout: Layout,
    dynamics: Tape,
    observation: Tape,
    parameters: Vec<f64>,
    /// α = β of the Baumgarte stabilisation, in 1/time.
    pub baumgarte: f64,
    /// One per kept constraint; position constraints unless [`Mechanical::with_kinds`] says.
    stabilisation: Vec<Stabilisation>,
    dyn_out: Vec<f64>,
    obs_input: Vec<f64>,
    /// The augmented system on the heap, for large systems and the exact Jacobian.
    system: DMatrix<f64>,
    backup: DMatrix<f64>,
    /// The same on the stack when it is small enough, as it is for most scenes.
    small: Option<Small>,
    /// The kept rows' system on the heap past the stack's order, and its factors.
    kept_factors: KeptFactors,
    solution: Vec<f64>,
    /// The Baumgarte rate (as bits) `solution` was solved with at the state and parameters in
    /// the dynamics program's inputs; `None` once `input`, `dyn_out` or `solution` moved on. A step's observations
    /// are taken where its last stage was evaluated: this saves solving there again.
    solved: Option<u64>,
    pivots: Vec<usize>,
    /// The partials program and its outputs, when an exact Jacobian was asked for.
    partials: Option<Tape>,
    partials_out: Vec<f64>,
    /// Slices of the partials program for the exact Jacobian, one for each set of kept rows
    /// met so far ([`Mechanical::kept_partials_at`]).
    partial_slices: Vec<(Vec<bool>, Slice)>,
    /// Slices of the dynamics program for a variational stage, one for each set of kept rows
    /// met so far: M, the forces and the kept rows alone ([`Mechanical::kept_accelerations`]).
    /// Each with the slice of the other rows, which completes it where they are needed, and
    /// whether it saves enough to be run rather than the whole program.
    dynamics_slices: Vec<(Vec<bool>, Slice, Slice, bool)>,
    /// Where `dyn_out` holds only such a slice's outputs at the inputs `solved_at` compares
    /// (the rows not kept older), which: what needs them (an open contact's gap) completes it.
    sliced: Option<usize>,
    /// Each contact's gap alone, a slice of the dynamics program made on first use: what
    /// locating its landing asks at each probe ([`Mechanical::open_gap`]).
    gap_slices: Vec<Option<Slice>>,
    /// The partials by the parameters a caller varies, and how many they are
    /// ([`Mechanical::set_sensitivities`]), and their outputs.
    sensitivities: Option<(Tape, usize)>,
    sensitivities_out: Vec<f64>,
    /// Parameter slots that follow a time series: set from t before each evaluation.
    signals: Vec<(usize, Series)>,
    /// Parameter slots that hold laws of the state sampled every period.
    hold: Option<Hold>,
    /// The dynamics program over many states at once, made on the first [`Mechanical::rhs_many`].
    many: Option<many::Many>,
    /// The one-sided contacts among the kept constraints ([`Mechanical::with_contacts`]).
    contacts: Vec<Contact>,
    /// Whether each multiplier's row is kept now: a two-sided one always, a contact's while it
    /// is closed. A row not kept gives λ = 0: its row and column of the augmented system are
    /// the identity's, its right-hand side 0.
    kept: Vec<bool>,
    /// The contacts' modes and the scales their tolerances are measured against.
    modes: modes::Modes,
    /// The normal columns a slipping contact's friction bends: its force acts along the
    /// normal's gradient plus `factor` (−μ·s) times its tangential row's.
    bends: Vec<Bend>,
    /// The contacts' arming conditions (one output each, 1 for a contact without one) and
    /// their values at the last evaluation, when a contact has one.
    arming: Option<(Tape, Vec<f64>)>,
    /// The program of q̈ by the recursive form, where the scene has one and no multiplier
    /// ([`Mechanical::with_chain`]).
    chain: Option<Tape>,
    /// That program over many states at once, made on the first [`Mechanical::rhs_many`].
    chain_many: Option<numeric::BatchTape>,
    /// The same sweep with its factors among the outputs, for the columns of the exact
    /// Jacobian, the sensitivities and a variational stage.
    chain_factored: Option<ChainFactored>,
    /// Whether `dyn_out` holds the dense program's outputs at the inputs `solved_at` compares
    /// (the recursive form leaves it behind).
    dense: bool,
    /// Whether `small` (at its order) or else `system` holds the LDLᵀ factors of M from the
    /// solve of the accelerations `solved` names, for the exact Jacobian's columns to solve
    /// with: true only from that solve (no multipliers, M positive definite) until the next
    /// evaluation of the dynamics program.
    mass_factored: bool,
}

/// The recursive form's sweep with its factors among its outputs ([`crate::Recursive`]).
#[derive(Clone)]
struct ChainFactored {
    chain: crate::Chain,
    tape: Tape,
    /// Its outputs at the last state: q̈, then the factors.
    out: Vec<f64>,
    /// Scratch for [`crate::Chain::solve_columns`].
    work: Vec<[f64; jacobian::COLUMNS]>,
}

/// A slipping contact's friction in the augmented system: the column of multiplier `normal`
/// is −(J_normal + factor·J_tangent)ᵀ, and the tangential force `factor`·λ_normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bend {
    pub normal: usize,
    pub tangent: usize,
    pub factor: f64,
    /// In space, where the factor comes from: the exact cone's −μ·γ_i/‖γ_T‖, which follows
    /// the state and is aimed again before each solve ([`Mechanical::aim_bends`]).
    pub cone: Option<Cone>,
}

/// A slipping contact in space: its two tangential rows (`rates`, the multipliers whose Φ
/// slots are γ₁ and γ₂), which of them a bend is along, μ, the direction its slip was decided
/// with (opposed while ‖γ_T‖ is within `band`, where γ_T's own direction is rounding's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cone {
    pub rates: [usize; 2],
    pub which: usize,
    pub mu: f64,
    pub fallback: [f64; 2],
    pub band: f64,
}

impl Cone {
    /// The slip velocity γ_T from the dynamics outputs, and the unit direction friction
    /// opposes: γ_T/‖γ_T‖ beyond the band, the decided one within it.
    fn aim(&self, out: &[f64], layout: Layout) -> ([f64; 2], [f64; 2]) {
        let n = layout.coordinates;
        let rate = self.rates.map(|c| out[n * n + n + c * (n + 3) + n + 1]);
        let size = crate::linalg::size2(rate[0], rate[1]);
        let direction =
            if size > self.band { [rate[0] / size, rate[1] / size] } else { self.fallback };
        (rate, direction)
    }
}

impl Mechanical {
    pub fn new(layout: Layout, dynamics: Tape, observation: Tape, parameters: Vec<f64>) -> Self {
        assert_eq!(dynamics.inputs(), layout.dynamics_inputs());
        assert_eq!(dynamics.outputs(), layout.dynamics_outputs());
        assert_eq!(observation.inputs(), layout.observation_inputs());
        assert_eq!(parameters.len(), layout.parameters);
        let size = layout.coordinates + layout.multipliers;
        // The parameters close both programs' inputs; a run changes them seldom, if at all.
        let state = 1 + 2 * layout.coordinates;
        let dynamics = dynamics.with_fixed_inputs(state..layout.dynamics_inputs());
        let observed = state + layout.coordinates + layout.multipliers;
        let observation = observation.with_fixed_inputs(observed..layout.observation_inputs());
        Mechanical {
            layout,
            dynamics,
            observation,
            parameters,
            baumgarte: BAUMGARTE_RATE,
            stabilisation: vec![Stabilisation::Position; layout.multipliers],
            dyn_out: vec![0.0; layout.dynamics_outputs()],
            obs_input: vec![0.0; layout.observation_inputs()],
            system: DMatrix::zeros(size, size),
            backup: DMatrix::zeros(size, size),
            small: Small::zeros(size),
            kept_factors: KeptFactors::default(),
            solution: vec![0.0; size],
            solved: None,
            pivots: vec![0; size],
            partials: None,
            partials_out: Vec::new(),
            partial_slices: Vec::new(),
            dynamics_slices: Vec::new(),
            sliced: None,
            gap_slices: Vec::new(),
            sensitivities: None,
            sensitivities_out: Vec::new(),
            signals: Vec::new(),
            hold: None,
            many: None,
            contacts: Vec::new(),
            kept: vec![true; layout.multipliers],
            modes: modes::Modes::default(),
            bends: Vec::new(),
            arming: None,
            chain: None,
            chain_many: None,
            chain_factored: None,
            dense: false,
            mass_factored: false,
        }
    }

    /// Solves for q̈ by the recursive form (`recursive`, [`crate::Chain::lower`]'s programs,
    /// which take the dynamics program's inputs) rather than by factoring M: O(n) rather than
    /// O(n³) on a long chain. Past the stack's order the exact Jacobian's, the sensitivities'
    /// and a variational stage's columns solve with the sweep's factors. The dense program
    /// still says why where the sweep gives no number. Ignored where the problem has
    /// multipliers.
    pub fn with_chain(mut self, recursive: crate::Recursive) -> Self {
        let crate::Recursive { accelerations, factored, chain } = recursive;
        let inputs = self.layout.dynamics_inputs();
        assert_eq!(accelerations.inputs, inputs);
        assert_eq!(accelerations.outputs.len(), self.layout.coordinates);
        assert_eq!(factored.outputs.len(), self.layout.coordinates + chain.factor_outputs());
        if self.layout.multipliers > 0 {
            return self;
        }
        let state = 1 + 2 * self.layout.coordinates;
        let fixed = |program| {
            let mut tape = Tape::new(program).with_fixed_inputs(state..inputs);
            tape.inputs_mut()[state..].copy_from_slice(&self.parameters);
            tape
        };
        let (accelerations, factored) = (fixed(accelerations), fixed(factored));
        let out = vec![0.0; factored.outputs()];
        self.chain = Some(accelerations);
        self.chain_factored = Some(ChainFactored { chain, tape: factored, out, work: Vec::new() });
        self.solved = None;
        self
    }

    /// Whether q̈ is solved by the recursive form.
    pub fn recursive(&self) -> bool {
        self.chain.is_some()
    }

    /// The parameter values the programs are evaluated at, in declaration order.
    pub fn parameters(&self) -> &[f64] {
        &self.parameters
    }

    /// Evaluates the programs at these parameter values from now on.
    pub fn set_parameters(&mut self, values: &[f64]) {
        assert_eq!(values.len(), self.layout.parameters);
        self.parameters.copy_from_slice(values);
        // The dynamics program's parameter inputs follow, for a caller that sets its state
        // inputs alone (`rhs_from_outputs`).
        let state = 1 + 2 * self.layout.coordinates;
        self.dynamics.inputs_mut()[state..state + values.len()].copy_from_slice(values);
        if let Some(program) = &mut self.chain {
            program.inputs_mut()[state..state + values.len()].copy_from_slice(values);
        }
        if let Some(factored) = &mut self.chain_factored {
            factored.tape.inputs_mut()[state..state + values.len()].copy_from_slice(values);
        }
        self.solved = None;
    }

    /// Gives the problem its exact Jacobian: `partials` is the partials program of the
    /// [`Layout`].
    pub fn with_partials(mut self, partials: Tape) -> Self {
        self.set_partials(partials);
        self
    }

    /// [`Mechanical::with_partials`] on a problem already built (its Jacobian asked for late).
    pub fn set_partials(&mut self, partials: Tape) {
        assert_eq!(partials.inputs(), self.layout.observation_inputs());
        assert_eq!(partials.outputs(), self.layout.partials_outputs());
        self.partials_out = vec![0.0; partials.outputs()];
        self.partial_slices.clear();
        self.partials = Some(partials);
    }

    /// Makes each parameter slot given follow its series: the slot takes the series' value
    /// at t before every evaluation at t.
    pub fn with_signals(mut self, signals: Vec<(usize, Series)>) -> Self {
        assert!(signals.iter().all(|(slot, _)| *slot < self.layout.parameters));
        self.signals = signals;
        self
    }

    /// Holds the laws of `hold` in their parameter slots, sampled every period from the first
    /// sample at the start of a run.
    pub fn with_hold(mut self, hold: Hold) -> Self {
        self.hold = Some(hold);
        self
    }

    /// Puts the signals' values at `t` into their parameter slots.
    pub(crate) fn follow_signals(&mut self, t: f64) {
        for (slot, series) in &self.signals {
            self.parameters[*slot] = series.at(t);
        }
    }

    /// Says which kept constraints restrain velocities rather than positions.
    pub fn with_kinds(mut self, kinds: Vec<Stabilisation>) -> Self {
        assert_eq!(kinds.len(), self.layout.multipliers);
        self.stabilisation = kinds;
        self.solved = None;
        self
    }

    /// The dynamics program's outputs at (t, q, q̇) (see [`Layout`]).
    pub(crate) fn dynamics_at(&mut self, t: f64, y: &[f64]) -> Result<&[f64], FaultKind> {
        self.solved = None;
        self.mass_factored = false;
        self.follow_signals(t);
        fill_inputs(self.dynamics.inputs_mut(), t, y, &self.parameters);
        self.dynamics.run(&mut self.dyn_out);
        self.dense = true;
        self.sliced = None;
        let layout = self.layout;
        check_finite(&self.dyn_out, |i| layout.dynamics_entry(i))?;
        Ok(&self.dyn_out)
    }

    /// Which kept constraints restrain positions and which velocities.
    pub(crate) fn kinds(&self) -> &[Stabilisation] {
        &self.stabilisation
    }

    /// Whether each multiplier's row is kept now (an open contact's is not).
    pub(crate) fn kept(&self) -> &[bool] {
        &self.kept
    }

    /// `run` on the problem with no Baumgarte stabilisation: the constraints' second
    /// derivatives as they are, as the differential–algebraic form holds them.
    pub(crate) fn unstabilised<T>(&mut self, run: impl FnOnce(&mut Self) -> T) -> T {
        let rate = std::mem::replace(&mut self.baumgarte, 0.0);
        let result = run(self);
        self.baumgarte = rate;
        result
    }

    /// q̈ and λ at (t, q, q̇) from the constraints' second derivatives alone, J q̈ = γ, with no
    /// stabilisation: the consistent start of the differential–algebraic form.
    pub(crate) fn unstabilised_accelerations(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Vec<f64>, FaultKind> {
        let rate = std::mem::replace(&mut self.baumgarte, 0.0);
        let solved = self.accelerations(t, y);
        self.baumgarte = rate;
        solved.map(|()| self.solution.clone())
    }

    /// Solves for q̈ and λ at (t, q, q̇); they are left in `self.solution`.
    fn accelerations(&mut self, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        if self.solved_at(t, y) {
            return Ok(());
        }
        if self.completed_at(t, y)? {
            return Ok(());
        }
        if self.chain.is_some() {
            return self.recursive_accelerations(t, y);
        }
        self.dynamics_at(t, y)?;
        self.solve_dynamics()
    }

    /// [`Mechanical::accelerations`] with the dense program's outputs at (t, y) in `dyn_out`,
    /// for what needs M: the accelerations solved from them, not by the recursive form.
    pub(crate) fn dense_accelerations(&mut self, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        if self.dense && self.solved_at(t, y) {
            return Ok(());
        }
        if self.completed_at(t, y)? {
            return Ok(());
        }
        self.dynamics_at(t, y)?;
        self.solve_dynamics()
    }

    /// [`Problem::rhs`] for a variational run that carries the state alone (a return map's
    /// run onto its section): with contacts, the kept rows alone as
    /// [`Mechanical::kept_accelerations`] solves them.
    pub(crate) fn kept_rates(
        &mut self,
        t: f64,
        y: &[f64],
        dy: &mut [f64],
    ) -> Result<(), FaultKind> {
        if self.contacts.is_empty() {
            return self.rhs(t, y, dy);
        }
        let n = self.layout.coordinates;
        self.kept_accelerations(t, y)?;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        dy[n..].copy_from_slice(&self.solution[..n]);
        check_finite(dy, rate)
    }

    /// [`Mechanical::dense_accelerations`] for a variational stage, which reads M, the forces
    /// and the kept rows alone: with contacts and no friction, from a slice of the dynamics
    /// program for the rows kept now. A rimless wheel on one of its eight spokes had evaluated
    /// its sixteen contact rows (gaps, Jacobian rows, their rates) at every stage, for the two
    /// it keeps; the open rows' gaps are the guards', read after the step at its end.
    pub(crate) fn kept_accelerations(&mut self, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        if self.contacts.is_empty() || !self.bends.is_empty() || self.kept.iter().all(|&k| k) {
            return self.dense_accelerations(t, y);
        }
        if self.dense && self.solved_on(t, y) {
            return Ok(());
        }
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let kept = &self.kept;
        let same =
            |rows: &[bool]| rows.len() == kept.len() && rows.iter().zip(kept).all(|(a, b)| a == b);
        let index = match self.dynamics_slices.iter().position(|(rows, ..)| same(rows)) {
            Some(index) => index,
            None => {
                let rows = |keep: bool| {
                    (0..m)
                        .filter(move |&c| kept[c] == keep)
                        .flat_map(|c| n * n + n + c * (n + 3)..n * n + n + (c + 1) * (n + 3))
                };
                let slice = self.dynamics.slice((0..n * n + n).chain(rows(true)));
                let rest = self.dynamics.slice(rows(false));
                // A step's end completes the slice with the rest, which shares the kept rows'
                // subexpressions: a slice of most of the program saves nothing (a walker
                // keeping one foot's two rows of four ran 1% more of them).
                let worth = 2 * slice.operations() <= self.dynamics.operations();
                // The modes a run meets are few; a problem that meets ever more starts over.
                if self.dynamics_slices.len() >= SLICES {
                    self.dynamics_slices.clear();
                }
                self.dynamics_slices.push((kept.clone(), slice, rest, worth));
                self.dynamics_slices.len() - 1
            }
        };
        if !self.dynamics_slices[index].3 {
            return self.dense_accelerations(t, y);
        }
        self.solved = None;
        self.mass_factored = false;
        self.follow_signals(t);
        fill_inputs(self.dynamics.inputs_mut(), t, y, &self.parameters);
        let slice = &mut self.dynamics_slices[index].1;
        self.dynamics.run_slice(slice, &mut self.dyn_out);
        self.dense = true;
        self.sliced = Some(index);
        slice_finite(&self.dyn_out, slice, self.layout)?;
        self.solve_dynamics()
    }

    /// q̈ at (t, y) by the recursive form's sweep, into `self.solution`.
    fn recursive_accelerations(&mut self, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        let n = self.layout.coordinates;
        self.begin_recursive(t, y);
        let program = self.chain.as_mut().expect("a recursive form");
        fill_inputs(program.inputs_mut(), t, y, &self.parameters);
        program.run(&mut self.solution[..n]);
        if self.solution[..n].iter().all(|a| a.is_finite()) {
            self.solved = Some(self.baumgarte.to_bits());
            return Ok(());
        }
        // No number: a term of the form, or a node's inertia that vanished. The dense route
        // tells which, or solves where only the sweep overflowed.
        self.dynamics_at(t, y)?;
        self.solve_dynamics()
    }

    /// What a solve by the recursive form does before its program runs at (t, y): forgets the
    /// last solve and M's factors, follows the signals, and gives the dense program the inputs
    /// `solved_at` compares (its outputs stay behind).
    fn begin_recursive(&mut self, t: f64, y: &[f64]) {
        self.solved = None;
        self.mass_factored = false;
        self.follow_signals(t);
        fill_inputs(self.dynamics.inputs_mut(), t, y, &self.parameters);
        self.dense = false;
    }

    /// Solves for q̈ and λ from the dynamics outputs in `self.dyn_out`; they are left in
    /// `self.solution`.
    fn solve_dynamics(&mut self) -> Result<(), FaultKind> {
        self.aim_bends();
        self.kept_factors.valid = false;
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let out = &self.dyn_out;
        self.solution[..n].copy_from_slice(&out[n * n..n * n + n]);
        let a = self.baumgarte;
        // A row not kept is not read: a wheel's fourteen open rows of sixteen.
        let rows = self.solution[n..n + m].iter_mut().zip(&self.kept).zip(&self.stabilisation);
        for (c, ((slot, &kept), kind)) in rows.enumerate() {
            if !kept {
                *slot = 0.0;
                continue;
            }
            let base = n * n + n + c * (n + 3);
            let (gamma, phi, phi_rate) = (out[base + n], out[base + n + 1], out[base + n + 2]);
            *slot = match kind {
                Stabilisation::Position => gamma - 2.0 * a * phi_rate - a * a * phi,
                Stabilisation::Velocity => gamma - a * phi,
            };
        }
        let (solution, pivots, kept) = (&mut self.solution, &mut self.pivots, &self.kept);
        let bends = &self.bends;
        let solved = match (self.small.as_mut(), kept.iter().all(|&k| k)) {
            (Some(small), true) => {
                solve_system(out, self.layout, kept, bends, small, solution, pivots)
            }
            (None, true) => {
                solve_system(out, self.layout, kept, bends, &mut self.system, solution, pivots)
            }
            // In the factors the exact Jacobian solves with again at the same state.
            (_, false) => {
                solve_kept_factored(out, self.layout, kept, bends, solution, &mut self.kept_factors)
                    .map(|()| false)
            }
        };
        self.mass_factored = matches!(solved, Ok(true));
        match solved {
            Ok(_) => {
                // A slipping contact's tangential force is μ·λ against the slip, not a
                // multiplier of its own: it is reported in its slot.
                for bend in &self.bends {
                    self.solution[n + bend.tangent] = bend.factor * self.solution[n + bend.normal];
                }
                self.solved = Some(self.baumgarte.to_bits());
                Ok(())
            }
            // A slipping contact's bent column makes the system singular where Painlevé's
            // coefficient vanishes, at the jam its guard watches for: the solve may meet it
            // first, as the normal force grows without bound on the way.
            Err(FaultKind::SingularMass { .. }) if !self.bends.is_empty() => {
                let contacts = self.slipping_contacts();
                Err(FaultKind::Painleve { contacts, case: crate::PainleveCase::Jam, impact: false })
            }
            Err(FaultKind::SingularMass { .. }) if m > 0 => Err(self.which_lost_rank()),
            Err(fault) => Err(fault),
        }
    }

    /// Aims the bends of the contacts slipping in space along their slip velocities at the
    /// last evaluation: the friction force is −μ·λ·γ_T/‖γ_T‖, its factors the state's.
    fn aim_bends(&mut self) {
        let (out, layout) = (&self.dyn_out, self.layout);
        for bend in &mut self.bends {
            if let Some(cone) = bend.cone {
                bend.factor = -cone.mu * cone.aim(out, layout).1[cone.which];
            }
        }
    }

    /// Whether `self.solution` holds the accelerations at (t, y) as they would be solved now:
    /// the last evaluation was at the same bits of t, y and the parameters, with the same
    /// Baumgarte rate.
    fn solved_at(&mut self, t: f64, y: &[f64]) -> bool {
        self.sliced.is_none() && self.solved_on(t, y)
    }

    /// Where a slice's run solved the accelerations at (t, y): the whole dynamics program run
    /// there too (its inputs are in place), the solution kept, which the outputs the slice
    /// gave decided with the same bits. False elsewhere: nothing was run.
    pub(crate) fn completed_at(&mut self, t: f64, y: &[f64]) -> Result<bool, FaultKind> {
        let Some(index) = self.sliced else { return Ok(false) };
        if !(self.dense && self.solved_on(t, y)) {
            return Ok(false);
        }
        let rest = &mut self.dynamics_slices[index].2;
        self.dynamics.run_slice(rest, &mut self.dyn_out);
        self.sliced = None;
        slice_finite(&self.dyn_out, rest, self.layout)?;
        Ok(true)
    }

    /// [`Mechanical::solved_at`], whether `dyn_out` is whole or a slice's (what a variational
    /// stage reads).
    fn solved_on(&mut self, t: f64, y: &[f64]) -> bool {
        if self.solved != Some(self.baumgarte.to_bits()) {
            return false;
        }
        self.follow_signals(t);
        let same = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(u, v)| u.to_bits() == v.to_bits())
        };
        let state = 1 + y.len();
        let input = self.dynamics.inputs_mut();
        input[0].to_bits() == t.to_bits()
            && same(&input[1..state], y)
            && same(&input[state..], &self.parameters)
    }

    /// Moves the velocities q̇ = y[n..2n] onto the constraints' velocity level at q = y[..n]:
    /// by the least change in M's metric, Δq̇ = M⁻¹Jᵀμ with J·(q̇ + Δq̇) = −∂Φ/∂t (a velocity
    /// constraint: A·(q̇ + Δq̇) + b = 0), the augmented system [M −Jᵀ; J 0]·(Δq̇, μ) =
    /// (0, −Φ̇) solved once. A velocity error of that form is the kind a multiplier's error
    /// leaves (v' = M⁻¹(f + Jᵀλ)), and the kind the index-3 system controls worst.
    pub(crate) fn project_velocities(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.layout.coordinates;
        // −Φ̇ of a position row, −(A·q̇ + b) of a velocity row: the residual at the rate level.
        self.least_change(t, y, n, |kind, slots| match kind {
            Stabilisation::Position => -slots[2],
            Stabilisation::Velocity => -slots[1],
        })
    }

    /// Moves the positions q = y[..n] onto the kept position constraints, Φ = 0, by the least
    /// change in M's metric: one Newton step, [M −Jᵀ; J 0]·(Δq, μ) = (0, −Φ), enough for the
    /// drift the stabilisation leaves. A jump of the contacts' modes puts the state on the new
    /// mode's constraints with it, so that the stabilisation does not push a contact that just
    /// closed below its surface back out (at the rate of the rocking it disturbs).
    pub(crate) fn project_positions(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        self.least_change(t, y, 0, |kind, slots| match kind {
            Stabilisation::Position => -slots[1],
            Stabilisation::Velocity => 0.0,
        })?;
        self.solved = None;
        Ok(())
    }

    /// The least change in M's metric that puts the kept rows' residuals at zero: the augmented
    /// system [M −Jᵀ; J 0]·(Δ, μ) = (0, r) solved once at (t, y), each kept row's r given by
    /// `residual` from its kind and its slots (γ, Φ, Φ̇) of the dynamics outputs (an open
    /// contact's rows none), and Δ added to the n components of `y` from `at`.
    fn least_change(
        &mut self,
        t: f64,
        y: &mut [f64],
        at: usize,
        residual: impl Fn(Stabilisation, &[f64]) -> f64,
    ) -> Result<(), FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        self.dynamics_at(t, y)?;
        let out = &self.dyn_out;
        let mut change = vec![0.0; n + m];
        for c in 0..m {
            let base = n * n + n + c * (n + 3);
            if self.kept[c] {
                change[n + c] = residual(self.stabilisation[c], &out[base + n..base + n + 3]);
            }
        }
        let (pivots, kept) = (&mut self.pivots, &self.kept);
        match (self.small.as_mut(), kept.iter().all(|&k| k)) {
            (Some(small), true) => {
                solve_system(out, self.layout, kept, &[], small, &mut change, pivots)?;
            }
            (Some(small), false) => {
                solve_kept(out, self.layout, kept, &[], small, &mut change, pivots)?
            }
            (None, true) => {
                solve_system(out, self.layout, kept, &[], &mut self.system, &mut change, pivots)?;
            }
            (None, false) => {
                let mut work = KeptFactors::default();
                solve_kept_factored(out, self.layout, kept, &[], &mut change, &mut work)?
            }
        }
        for (v, d) in y[at..at + n].iter_mut().zip(&change[..n]) {
            *v += d;
        }
        Ok(())
    }

    /// After the augmented system [M −Jᵀ; J 0] failed: whether M itself or the constraint
    /// Jacobian J lost rank, the two faults a user fixes in different places.
    fn which_lost_rank(&self) -> FaultKind {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        let out = &self.dyn_out;
        let mut mass = DMatrix::from_fn(n, n, |i, j| out[j * n + i]);
        let mut pivots = vec![0; n];
        if let Err(fault) = linalg::lu_in_place(&mut mass, &mut pivots) {
            return fault;
        }
        // The rows kept now: an open contact's is no constraint.
        let rows: Vec<usize> = (0..m).filter(|&c| self.kept[c]).collect();
        let jacobian =
            DMatrix::from_fn(rows.len(), n, |r, j| out[n * n + n + rows[r] * (n + 3) + j]);
        let dependent = linalg::dependent_rows(&jacobian);
        FaultKind::SingularConstraints { constraints: dependent.iter().map(|&r| rows[r]).collect() }
    }

    /// [`Problem::begin_modes`] for a start a run reached on its contacts (a periodic orbit's
    /// section, or one a Newton step moved): a contact touching and at rest to half the
    /// tolerance's digits is held closed and the start projected onto it, so that neither a
    /// closed contact's drift nor a Newton step's second-order offset reads as flight.
    pub fn begin_modes_held(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<crate::ModeEvent>, FaultKind> {
        if self.contacts.is_empty() {
            return Ok(Vec::new());
        }
        self.begin_contacts(t, y, tolerance, true)
    }

    /// Φ of each kept constraint at the last evaluation (0 for an open contact's rows, which
    /// are no constraints while open).
    pub fn constraint_values(&self) -> impl Iterator<Item = f64> + '_ {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        (0..m).map(
            move |c| {
                if self.kept[c] {
                    self.dyn_out[n * n + n + c * (n + 3) + n + 1]
                } else {
                    0.0
                }
            },
        )
    }
}

impl Problem for Mechanical {
    fn dim(&self) -> usize {
        2 * self.layout.coordinates
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.layout.coordinates;
        self.accelerations(t, y)?;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        dy[n..].copy_from_slice(&self.solution[..n]);
        check_finite(dy, rate)
    }

    /// ∂(q̇, q̈)/∂(q, q̇) from the partials and the augmented matrix, when they were lowered.
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        self.exact_jacobian(t, y, jac)
    }

    fn observations(&self) -> usize {
        self.observation.outputs() + self.layout.multipliers
    }

    /// The next sample of a held law, or the next knot of a series: the right-hand side jumps
    /// at the one and its slope at the other (a series is linear between its samples), and a
    /// step across either would lose the method's order.
    fn next_sample(&self, t: f64) -> Option<f64> {
        let held = self.hold.as_ref().map(|h| h.next_after(t));
        let knot = self.signals.iter().filter_map(|(_, s)| s.next_knot_after(t)).reduce(f64::min);
        match (held, knot) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let Some(hold) = &mut self.hold else { return Ok(()) };
        // A series' knot that falls between samples changes nothing held (the start, where
        // the first sample is, is t = 0 = 0·T).
        if !hold.is_sample_time(t) {
            return Ok(());
        }
        let n = self.layout.coordinates;
        hold.sample(t, &y[..2 * n], &mut self.parameters)
            .map_err(|slot| FaultKind::NonFinite { at: NonFiniteAt::HeldLaw { slot } })
    }

    /// The observation program's outputs, then |Φ| of each kept constraint.
    fn observe(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        self.accelerations(t, y)?;
        let solution = std::mem::take(&mut self.solution);
        self.observe_given(t, y, &solution, out);
        self.solution = solution;
        Ok(())
    }

    /// One per contact: its reaction λ while closed, its gap g while open.
    fn guards(&self) -> usize {
        self.contact_guard_count()
    }

    fn guard_values(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        self.contact_guards(t, y, out)
    }

    fn guard_value(
        &mut self,
        t: f64,
        y: &[f64],
        k: usize,
        scratch: &mut [f64],
    ) -> Result<f64, FaultKind> {
        match self.open_gap(t, y, k)? {
            Some(gap) => Ok(gap),
            None => {
                self.contact_guards(t, y, scratch)?;
                Ok(scratch[k])
            }
        }
    }

    fn begin_modes(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<crate::ModeEvent>, FaultKind> {
        if self.contacts.is_empty() {
            return Ok(Vec::new());
        }
        self.begin_contacts(t, y, tolerance, false)
    }

    fn jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<crate::ModeEvent>, FaultKind> {
        self.contact_jump(t, y, fired)
    }
}

impl Mechanical {
    /// The observations at (t, q, q̇) with the accelerations and multipliers `solution`, after
    /// the dynamics program was evaluated there.
    pub(crate) fn observe_given(&mut self, t: f64, y: &[f64], solution: &[f64], out: &mut [f64]) {
        let Layout { coordinates: n, multipliers: m, parameters: k } = self.layout;
        self.follow_signals(t);
        let inp = &mut self.obs_input;
        inp[0] = t;
        inp[1..1 + 2 * n].copy_from_slice(y);
        inp[1 + 2 * n..1 + 3 * n + m].copy_from_slice(solution);
        inp[1 + 3 * n + m..1 + 3 * n + m + k].copy_from_slice(&self.parameters);
        let shown = self.observation.outputs();
        self.observation.eval(inp, &mut out[..shown]);
        for (o, phi) in out[shown..].iter_mut().zip(self.constraint_values()) {
            *o = phi.abs();
        }
    }
}

/// The same system in canonical variables y = (q, p), p = ∂L/∂q̇, for methods that are
/// symplectic only there: q̇ = M⁻¹(p − b(q)), ṗ = ∂L/∂q + Q. The momentum program takes the
/// dynamics inputs and gives M (n×n), p(q, q̇) (n) and ∂L/∂q + Q (n); since p is affine in q̇,
/// b(q) = p(q, 0). Constraints kept with multipliers are not supported here.
#[derive(Clone)]
pub struct Canonical {
    pub inner: Mechanical,
    momentum: Tape,
    input: Vec<f64>,
    out: Vec<f64>,
    rates: Vec<f64>,
    physical: Vec<f64>,
    /// The canonical partials program and its outputs, when an exact Jacobian was asked for.
    partials: Option<Tape>,
    partials_out: Vec<f64>,
}

impl Canonical {
    pub fn new(inner: Mechanical, momentum: Tape) -> Self {
        let n = inner.layout.coordinates;
        assert_eq!(inner.layout.multipliers, 0);
        assert_eq!(momentum.inputs(), inner.layout.dynamics_inputs());
        assert_eq!(momentum.outputs(), n * n + 2 * n);
        let k = inner.layout.parameters;
        Canonical {
            input: vec![0.0; inner.layout.dynamics_inputs()],
            out: vec![0.0; n * n + 2 * n],
            rates: vec![0.0; n],
            physical: vec![0.0; 2 * n],
            inner,
            momentum: momentum.with_fixed_inputs(1 + 2 * n..1 + 2 * n + k),
            partials: None,
            partials_out: Vec::new(),
        }
    }

    /// Gives the problem its exact Jacobian. `partials` takes the dynamics inputs and gives,
    /// row-major and n×n each, ∂p/∂q, ∂g/∂q and ∂g/∂q̇ of p = ∂L/∂q̇ and g = ∂L/∂q + Q.
    pub fn with_partials(mut self, partials: Tape) -> Self {
        let n = self.inner.layout.coordinates;
        assert_eq!(partials.inputs(), self.inner.layout.dynamics_inputs());
        assert_eq!(partials.outputs(), 3 * n * n);
        self.partials_out = vec![0.0; 3 * n * n];
        self.partials = Some(partials);
        self
    }

    fn set_input(&mut self, t: f64, q: &[f64], rates: Option<&[f64]>) {
        let n = q.len();
        self.input[0] = t;
        self.input[1..1 + n].copy_from_slice(q);
        match rates {
            Some(r) => self.input[1 + n..1 + 2 * n].copy_from_slice(r),
            None => self.input[1 + n..1 + 2 * n].iter_mut().for_each(|v| *v = 0.0),
        }
        self.inner.follow_signals(t);
        let k = self.inner.parameters.len();
        self.input[1 + 2 * n..1 + 2 * n + k].copy_from_slice(&self.inner.parameters);
    }

    /// q̇ from (q, p), left in `self.rates`.
    fn velocities(&mut self, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        let n = self.inner.layout.coordinates;
        self.set_input(t, &y[..n], None);
        self.momentum.eval(&self.input, &mut self.out);
        // M (n×n), p (n), ∂L/∂q + Q (n).
        check_finite(&self.out, |i| match i {
            i if i < n * n => NonFiniteAt::Mass { row: i % n, column: i / n },
            i if i < n * n + n => NonFiniteAt::Momentum { coordinate: i - n * n },
            i => NonFiniteAt::Force { coordinate: i - n * n - n },
        })?;
        let sys = &mut self.inner.system;
        for j in 0..n {
            for i in 0..n {
                sys[(i, j)] = self.out[j * n + i];
            }
            self.rates[j] = y[n + j] - self.out[n * n + j];
        }
        let inner = &mut self.inner;
        inner.backup.copy_from(&inner.system);
        linalg::solve_symmetric(&mut inner.system, &mut self.rates, &mut inner.pivots, |a| {
            a.copy_from(&inner.backup)
        })
        .map(|_| ())
    }

    /// (q, p) from (q, q̇).
    pub fn from_physical(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        let n = self.inner.layout.coordinates;
        self.set_input(t, &y[..n], Some(&y[n..]));
        self.momentum.eval(&self.input, &mut self.out);
        let mut z = y.to_vec();
        z[n..].copy_from_slice(&self.out[n * n..n * n + n]);
        z
    }
}

impl Problem for Canonical {
    fn dim(&self) -> usize {
        2 * self.inner.layout.coordinates
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        let n = self.inner.layout.coordinates;
        self.velocities(t, y)?;
        let rates = std::mem::take(&mut self.rates);
        self.set_input(t, &y[..n], Some(&rates));
        self.momentum.eval(&self.input, &mut self.out);
        dy[..n].copy_from_slice(&rates);
        dy[n..].copy_from_slice(&self.out[n * n + n..]);
        self.rates = rates;
        check_finite(dy, |i| match i {
            i if i < n => rate(i),
            i => NonFiniteAt::MomentumRate { coordinate: i - n },
        })
    }

    /// ∂(q̇, ṗ)/∂(q, p) from the canonical partials and M, when they were lowered.
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        self.exact_jacobian(t, y, jac)
    }

    fn observations(&self) -> usize {
        self.inner.observations()
    }

    fn observe(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let physical = self.physical_state(t, y)?;
        self.inner.observe(t, &physical, out)
    }

    fn physical(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        self.physical_state(t, y).unwrap_or_else(|_| y.to_vec())
    }

    fn next_sample(&self, t: f64) -> Option<f64> {
        self.inner.next_sample(t)
    }

    /// The rates carry over a sample (the held force is finite), the momenta are taken anew:
    /// an input in a term of the Lagrangian with the rates moves p.
    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let mut physical = self.physical_state(t, y)?;
        self.inner.sample(t, &mut physical)?;
        y.copy_from_slice(&self.from_physical(t, &physical));
        Ok(())
    }
}

impl Canonical {
    fn physical_state(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, FaultKind> {
        let n = self.inner.layout.coordinates;
        self.velocities(t, y)?;
        self.physical[..n].copy_from_slice(&y[..n]);
        self.physical[n..].copy_from_slice(&self.rates);
        Ok(self.physical.clone())
    }
}

/// `[t, y, parameters]` into the first slots of a program's inputs.
fn fill_inputs(input: &mut [f64], t: f64, y: &[f64], parameters: &[f64]) {
    input[0] = t;
    input[1..1 + y.len()].copy_from_slice(y);
    input[1 + y.len()..1 + y.len() + parameters.len()].copy_from_slice(parameters);
}

/// Writes the augmented matrix [M −Jᵀ; J 0] of the dynamics outputs `out` into `a`, with the
/// identity's row and column for each multiplier not `kept`.
fn load_system(out: &[f64], layout: Layout, kept: &[bool], bends: &[Bend], a: &mut impl Square) {
    let Layout { coordinates: n, multipliers: m, .. } = layout;
    for j in 0..n {
        for i in 0..n {
            a[(i, j)] = out[j * n + i];
        }
    }
    for c in 0..m {
        let base = n * n + n + c * (n + 3);
        for j in 0..n {
            let jac = if kept[c] { out[base + j] } else { 0.0 };
            a[(n + c, j)] = jac;
            a[(j, n + c)] = -jac;
        }
        if kept[c] {
            for bend in bends.iter().filter(|b| b.normal == c) {
                let tangent = n * n + n + bend.tangent * (n + 3);
                for j in 0..n {
                    a[(j, n + c)] -= bend.factor * out[tangent + j];
                }
            }
        }
        for d in 0..m {
            a[(n + c, n + d)] = if !kept[c] && c == d { 1.0 } else { 0.0 };
        }
    }
}

/// [`solve_system`] with only the kept rows factored: an open contact's multiplier is 0
/// without its identity row in the factorization, so a ball in flight solves M alone by LDLᵀ
/// and a rocking block on one corner five rows rather than seven. `a` is resized to the kept
/// order and left so (the full solve sets its order again).
fn solve_kept(
    out: &[f64],
    layout: Layout,
    kept: &[bool],
    bends: &[Bend],
    a: &mut Small,
    b: &mut [f64],
    pivots: &mut [usize],
) -> Result<(), FaultKind> {
    let Layout { coordinates: n, multipliers: m, .. } = layout;
    let mut rows = [0usize; linalg::SMALL];
    let mut k = 0;
    for c in (0..m).filter(|&c| kept[c]) {
        rows[k] = c;
        k += 1;
    }
    let rows = &rows[..k];
    let load = |a: &mut Small| {
        a.set_order(n + k);
        load_kept(out, n, rows, bends, a);
    };
    load(a);
    let mut x = [0.0; linalg::SMALL];
    x[..n].copy_from_slice(&b[..n]);
    for (r, &c) in rows.iter().enumerate() {
        x[n + r] = b[n + c];
    }
    let solved = if k == 0 {
        linalg::solve_symmetric(a, &mut x[..n], pivots, load).map(|_| ())
    } else {
        linalg::solve_general(a, &mut x[..n + k], pivots)
    };
    a.set_order(n + m);
    solved?;
    b[..n].copy_from_slice(&x[..n]);
    b[n..n + m].fill(0.0);
    for (r, &c) in rows.iter().enumerate() {
        b[n + c] = x[n + r];
    }
    Ok(())
}

/// The augmented system of the kept `rows` alone into `a` (of order n + rows): M, each row's
/// J and −Jᵀ (a slipping contact's column bent by its friction), zeros in the corner.
pub(super) fn load_kept(
    out: &[f64],
    n: usize,
    rows: &[usize],
    bends: &[Bend],
    a: &mut impl Square,
) {
    // Column by column as slices (the entries are column-major): entry by entry through the
    // index, the load had cost the walker's order-6 system about 700 instructions a stage.
    let (entries, stride) = a.columns_mut();
    let order = n + rows.len();
    for j in 0..n {
        entries[j * stride..j * stride + n].copy_from_slice(&out[j * n..j * n + n]);
    }
    for (r, &c) in rows.iter().enumerate() {
        let base = n * n + n + c * (n + 3);
        let row = &out[base..base + n];
        for (j, v) in row.iter().enumerate() {
            entries[j * stride + n + r] = *v;
        }
        let column = &mut entries[(n + r) * stride..(n + r) * stride + order];
        for (entry, v) in column[..n].iter_mut().zip(row) {
            *entry = -v;
        }
        for bend in bends.iter().filter(|b| b.normal == c) {
            let tangent = n * n + n + bend.tangent * (n + 3);
            for (entry, v) in column[..n].iter_mut().zip(&out[tangent..tangent + n]) {
                *entry -= bend.factor * v;
            }
        }
        column[n..].fill(0.0);
    }
}

/// [`solve_kept`] in the buffers of `work`, which keep the LU factors for the exact Jacobian at
/// the same state ([`KeptFactors`]): an open contact's multiplier 0 without its identity row
/// (a rimless wheel on one spoke solves five rows, not nineteen), on the stack where the kept
/// rows fit it. The Jacobian had factored the stack's system again at every stage.
fn solve_kept_factored(
    out: &[f64],
    layout: Layout,
    kept: &[bool],
    bends: &[Bend],
    b: &mut [f64],
    work: &mut KeptFactors,
) -> Result<(), FaultKind> {
    let Layout { coordinates: n, multipliers: m, .. } = layout;
    work.valid = false;
    work.keep(kept);
    if work.by_blocks(out, n, bends) {
        // In place: an open row's multiplier is 0.
        work.saddle.solve_scattered(b, &work.rows);
        for (c, &kept) in kept.iter().enumerate() {
            if !kept {
                b[n + c] = 0.0;
            }
        }
        work.valid = true;
        return Ok(());
    }
    work.load(out, n, bends);
    let KeptFactors { lu, small, pivots, rows, x, .. } = &mut *work;
    x.clear();
    x.extend_from_slice(&b[..n]);
    x.extend(rows.iter().map(|&c| b[n + c]));
    let order = n + rows.len();
    let solved = if order <= linalg::SMALL {
        solve_loaded(small, out, n, rows, bends, x, &mut pivots[..order])
    } else {
        solve_loaded(lu, out, n, rows, bends, x, &mut pivots[..order])
    };
    work.valid = solved? && !work.rows.is_empty();
    let KeptFactors { rows, x, .. } = work;
    b[..n].copy_from_slice(&x[..n]);
    b[n..n + m].fill(0.0);
    for (r, &c) in rows.iter().enumerate() {
        b[n + c] = x[n + r];
    }
    Ok(())
}

/// Solves the kept rows' system loaded into `a` for `x`, in place: by LDLᵀ with no kept rows
/// (M alone, symmetric), else by LU, whose factors are left in `a` (true).
fn solve_loaded<M: Square>(
    a: &mut M,
    out: &[f64],
    n: usize,
    rows: &[usize],
    bends: &[Bend],
    x: &mut [f64],
    pivots: &mut [usize],
) -> Result<bool, FaultKind> {
    if rows.is_empty() {
        let load = |a: &mut M| load_kept(out, n, rows, bends, a);
        linalg::solve_symmetric(a, x, pivots, load)?;
        Ok(false)
    } else {
        linalg::solve_general(a, x, pivots)?;
        Ok(true)
    }
}

/// The kept rows' augmented system, its buffers kept from solve to solve, and after the
/// accelerations' solve (`valid`) its factors, which the exact Jacobian at the same state
/// solves with again rather than factoring the same matrix a second time. Factored by its
/// blocks ([`Saddle`]) where they serve, else by LU: on the stack where its order fits
/// [`Small`] (a walker on one foot: six rows of eight), on the heap past it (a rimless wheel's
/// nineteen rows with one spoke's two kept: five).
#[derive(Clone, Debug)]
pub(crate) struct KeptFactors {
    lu: DMatrix<f64>,
    small: Small,
    pivots: Vec<usize>,
    saddle: Saddle,
    /// Whether the factors are `saddle`'s rather than LU's.
    blocks: bool,
    /// The multipliers kept, in the order of the system's rows past M's.
    rows: Vec<usize>,
    x: Vec<f64>,
    /// Whether `saddle`, or else `lu` (or `small`, by the order), holds the factors of the
    /// system the last solve of the accelerations used (M alone is solved by LDLᵀ, which the
    /// Jacobian's columns cannot reuse).
    valid: bool,
    /// The exact Jacobian's and the sensitivities' right-hand sides and solutions, kept: a
    /// variational run solves with them twice per stage, and allocating them each time was a
    /// third of a fit's time.
    pub(crate) reduced: Vec<f64>,
    pub(crate) block: Vec<[f64; jacobian::COLUMNS]>,
    pub(crate) column: Vec<f64>,
}

impl Default for KeptFactors {
    fn default() -> Self {
        KeptFactors {
            lu: DMatrix::zeros(0, 0),
            small: Small::zeros(linalg::SMALL).expect("the stack's order"),
            pivots: Vec::new(),
            saddle: Saddle::default(),
            blocks: false,
            rows: Vec::new(),
            x: Vec::new(),
            valid: false,
            reduced: Vec::new(),
            block: Vec::new(),
            column: Vec::new(),
        }
    }
}

impl KeptFactors {
    /// Takes the rows `kept` as the system's.
    fn keep(&mut self, kept: &[bool]) {
        self.rows.clear();
        self.rows.extend((0..kept.len()).filter(|&c| kept[c]));
    }

    /// Factors the kept rows' system at `out` by its blocks, if they serve: kept rows, none
    /// bent by friction (which leaves the system unsymmetric), and [`Saddle::factor`]'s
    /// conditions. Whether it did.
    fn by_blocks(&mut self, out: &[f64], n: usize, bends: &[Bend]) -> bool {
        self.blocks =
            !self.rows.is_empty() && bends.is_empty() && self.saddle.factor(out, n, &self.rows);
        self.blocks
    }

    /// The system of the rows kept at `out` (bent by `bends`), unfactored, for LU.
    fn load(&mut self, out: &[f64], n: usize, bends: &[Bend]) {
        let order = n + self.rows.len();
        if self.pivots.len() < order {
            self.pivots.resize(order, 0);
        }
        if order <= linalg::SMALL {
            self.small.set_order(order);
            load_kept(out, n, &self.rows, bends, &mut self.small);
            return;
        }
        if self.lu.nrows() != order {
            self.lu = DMatrix::zeros(order, order);
        }
        load_kept(out, n, &self.rows, bends, &mut self.lu);
    }

    /// The factors of the kept rows' system at `out`: the accelerations' own where their
    /// solve left them, else made here as that solve makes them (a slipping contact's column
    /// bent by its friction, as the solve's is).
    pub(crate) fn ready(
        &mut self,
        out: &[f64],
        n: usize,
        kept: &[bool],
        bends: &[Bend],
    ) -> Result<(), FaultKind> {
        if !self.valid {
            self.keep(kept);
            if !self.by_blocks(out, n, bends) {
                self.load(out, n, bends);
                let order = self.order(n);
                let pivots = &mut self.pivots[..order];
                if order <= linalg::SMALL {
                    linalg::lu_in_place(&mut self.small, pivots)?;
                } else {
                    linalg::lu_in_place(&mut self.lu, pivots)?;
                }
            }
            self.valid = true;
        }
        Ok(())
    }

    /// The order of the system last loaded.
    pub(crate) fn order(&self, n: usize) -> usize {
        n + self.rows.len()
    }

    /// Solves with the factors for the columns of `block` side by side.
    pub(crate) fn solve_columns(&self, n: usize, block: &mut [[f64; jacobian::COLUMNS]]) {
        if self.blocks {
            return self.saddle.solve_columns(block);
        }
        let order = self.order(n);
        let pivots = &self.pivots[..order];
        if order <= linalg::SMALL {
            linalg::lu_solve_columns(&self.small, pivots, block);
        } else {
            linalg::lu_solve_columns(&self.lu, pivots, block);
        }
    }

    /// The kept multipliers, in the order of the system's rows past M's.
    pub(crate) fn rows(&self) -> &[usize] {
        &self.rows
    }
}

/// Solves the augmented system of `out` for the right side `b`, in place: by LDLᵀ when
/// there are no multipliers (M alone, symmetric), by LU otherwise. Whether `a` is left
/// holding M's LDLᵀ factors.
fn solve_system<M: Square>(
    out: &[f64],
    layout: Layout,
    kept: &[bool],
    bends: &[Bend],
    a: &mut M,
    b: &mut [f64],
    pivots: &mut [usize],
) -> Result<bool, FaultKind> {
    load_system(out, layout, kept, bends, a);
    if layout.multipliers == 0 {
        linalg::solve_symmetric(a, b, pivots, |a| load_system(out, layout, kept, bends, a))
    } else {
        linalg::solve_general(a, b, pivots).map(|()| false)
    }
}
