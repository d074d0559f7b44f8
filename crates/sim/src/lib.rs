//! Numerical integration of lowered equations of motion.
//!
//! This crate owns everything between a straight-line program and a trajectory: solving
//! M(q)·q̈ = f for the accelerations (LDLᵀ where M is symmetric positive definite, LU with
//! pivoting otherwise, the augmented system with Baumgarte stabilisation when constraints
//! keep multipliers, or those constraints as they are, the differential–algebraic system of
//! index 3) and the exact Jacobians of those problems from the lowered partials of their
//! equations, the integrators and their table (`methods`: each one's names, the form of problem
//! it integrates, its capabilities and its stepper; fixed-step RK4, the adaptive explicit pairs
//! with dense output, implicit Gauss–Legendre collocation that is symplectic in canonical
//! variables, adaptive implicit Radau IIA for stiff and differential–algebraic systems, and
//! `auto`, which switches between DOP853 and Radau IIA as the problem turns stiff and back),
//! the fastest mode of a Jacobian and the step an explicit method is stable at for it,
//! events located on the dense output, signals given as time series put into their parameter
//! slots before each evaluation, laws of the state held between samples (a zero-order hold, at
//! whose samples a run stops and restarts its method), one-sided contacts (their modes, guards
//! located on the dense output, impacts and lift-offs as jumps after which a run restarts its
//! method) with the complementarity problems they pose (`complementarity`: the impulses of an
//! impact, the forces of touching contacts), the sensitivities of a run (`variational`: the
//! state transition matrix integrated on the run's own steps from the exact Jacobian, carried
//! across jumps by saltation matrices, ended at a time, a section or a landing with the
//! event's time varied with the start: what a return map's Newton iteration and its Floquet
//! multipliers are made of), and the measurements of a run (steps,
//! evaluations, Jacobians, factorizations, energy and constraint drift). It works on numbered
//! slots and [`numeric::Tape`]s: it knows no symbols, names or files, and nothing of how the
//! equations were derived.

// Numeric kernels index several arrays in step; iterator chains would hide that.
#![allow(clippy::needless_range_loop)]

mod auto;
mod chain;
pub mod complementarity;
mod constrained;
mod contact;
pub mod coulomb;
mod erk;
mod gauss;
mod hold;
pub mod linalg;
mod lockstep;
mod mechanical;
pub mod methods;
mod radau;
mod run;
mod series;
mod spectrum;
mod stepper;
pub mod variational;

pub use chain::{Chain, Recursive};
pub use constrained::Constrained;
pub use contact::{Contact, ModeChange, ModeEvent};
pub use erk::{dop853_tableau, Dop853Tableau};
pub use hold::Hold;
pub use lockstep::{Job, Lockstep};
pub use mechanical::{Canonical, Layout, Mechanical, Stabilisation, Watched, BAUMGARTE_RATE};
pub use methods::{Form, Jacobian, Method};
pub use run::{
    integrate, integrate_into, Event, EventHit, Rows, Run, Segment, Settings, Trajectory,
};
pub use series::{Series, SeriesError};
pub use spectrum::{fastest_mode, spectral_radius, Mode};

/// What went wrong numerically, with the slots involved.
#[derive(Clone, Debug, PartialEq)]
pub enum FaultKind {
    /// The mass matrix (or the augmented system) is singular or too ill-conditioned to solve;
    /// `coordinates` are the indices of the coordinates whose pivots vanished.
    SingularMass { coordinates: Vec<usize>, condition: f64 },
    /// The mass matrix is fine but the kept constraints' Jacobian lost rank: their gradients
    /// became dependent (a dead point of a linkage, or constraints that coincide here), so
    /// the multipliers are not determined. `constraints` are the ones that depend on earlier
    /// ones.
    SingularConstraints { constraints: Vec<usize> },
    /// A value came out NaN or infinite; `at` says which.
    NonFinite { at: NonFiniteAt },
    /// The adaptive step fell below what floating point can resolve at this time.
    StepTooSmall { step: f64 },
    /// The rates at the start of the run (or of a restart) are too large for the step control
    /// to weigh against the tolerance (their weighted norm overflows); the rate of state
    /// `component` is `rate`, the largest weighed.
    RatesOverflow { component: usize, rate: f64 },
    /// Newton's iteration of a fixed-step implicit method (gauss, midpoint) did not converge
    /// at its `step`; `contraction` is the last ratio of successive Newton updates (≥ 1:
    /// diverging), `exact_jacobian` whether the iteration had the problem's exact Jacobian
    /// (else forward differences).
    NewtonFailed { step: f64, contraction: f64, exact_jacobian: bool },
    /// Newton's iteration of an adaptive implicit method (radau) did not converge although it
    /// cut the step to `step`; `contraction` is the last ratio of successive Newton updates
    /// (≥ 1: diverging), `singular` whether its iteration matrix was singular instead, and
    /// `exact_jacobian` as for [`FaultKind::NewtonFailed`].
    NewtonStalled { step: f64, contraction: f64, singular: bool, exact_jacobian: bool },
    /// The run took more steps than allowed.
    TooManySteps { limit: usize },
    /// At the start, `contact`'s gap is `gap` < 0 beyond the touching tolerance: the start
    /// penetrates it.
    Penetrating { contact: usize, gap: f64 },
    /// The problem's mode jumped `jumps` times in a row at the same time, the `guards` firing
    /// again after each: its modes chatter there instead of settling on one.
    ModesChatter { guards: Vec<usize>, jumps: usize },
    /// The complementarity problem of these contacts' impact (`impact`) or reactions has no
    /// solution: their gradients conflict with each other or the two-sided constraints.
    ContactsInconsistent { contacts: Vec<usize>, impact: bool },
    /// The complementarity problem of these contacts' impact (`impact`) or reactions could not
    /// be solved, though it may have a solution: `why` says what stopped the solver.
    ContactsUnsolved { contacts: Vec<usize>, impact: bool, why: &'static str },
    /// Painlevé's paradox: with friction, the forces (or, at an `impact`, the impulses) of
    /// these contacts have no solution or several, or their normal forces grow without bound
    /// while they slip. A run never goes on from here with a motion of its choosing.
    Painleve { contacts: Vec<usize>, case: PainleveCase, impact: bool },
}

/// Which of Painlevé's cases a run met ([`FaultKind::Painleve`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PainleveCase {
    /// No modes of the contacts give forces that obey their laws (the rod pressed into a
    /// rough floor with μ past 4/3 at some angles, and no force that pushes).
    Inconsistent,
    /// Modes that obey the laws give different motions (the same rod lifting: it may fly, or
    /// slip pressed to the floor).
    Indeterminate,
    /// While slipping, the normal forces' coefficient (Painlevé's a) reached zero: they grow
    /// without bound (the dynamic jam, or an impact without collision, which no law here
    /// decides).
    Jam,
}

/// Which value came out NaN or infinite: each names the array it indexes, so that a front end
/// can name the thing (a coordinate, an entry of M, a constraint, an input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NonFiniteAt {
    /// The mass matrix's entry in the rows of coordinate `row` and the column of `column`.
    Mass { row: usize, column: usize },
    /// f's entry for `coordinate` (M·q̈ = f; ∂L/∂q + Q in canonical variables).
    Force { coordinate: usize },
    /// The canonical momentum p = ∂L/∂q̇ of `coordinate`.
    Momentum { coordinate: usize },
    /// A kept constraint's Jacobian row, γ, or its drift Φ and Φ̇.
    Constraint { constraint: usize },
    /// The rate of state `component` (q then q̇: the rate of q̇ is q̈).
    Rate { component: usize },
    /// The rate of the canonical momentum of `coordinate`.
    MomentumRate { coordinate: usize },
    /// The residual M·q̈ − f − Jᵀλ of `coordinate`'s equation (the differential–algebraic
    /// system).
    Residual { coordinate: usize },
    /// The value a held law gave for parameter slot `slot` (an input's).
    HeldLaw { slot: usize },
    /// The lowered partials the exact Jacobian is made of.
    Partials,
    /// The Jacobian of the right-hand side.
    Jacobian,
    /// The matrix the accelerations (and multipliers) are solved with.
    System,
}

/// A numeric fault, at the time and state where it happened.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    pub kind: FaultKind,
    pub time: f64,
    pub state: Vec<f64>,
}

/// A first-order system y' = F(t, y), plus what a run records of each state.
pub trait Problem {
    /// The length of the state y.
    fn dim(&self) -> usize;
    /// Writes F(t, y) to `dy`.
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind>;
    /// The number of quantities [`Problem::observe`] writes.
    fn observations(&self) -> usize;
    /// Writes the recorded quantities of the state (outputs, event functions, energies).
    fn observe(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind>;
    /// Writes the exact Jacobian ∂F/∂y at (t, y) into `jac` (row-major, dim × dim) and
    /// returns `Ok(true)`. A problem without one returns `Ok(false)`, and implicit methods
    /// difference [`Problem::rhs`] instead.
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        let _ = (t, y, jac);
        Ok(false)
    }
    /// How many of y's components, from the first, the explicit methods' step control weighs:
    /// all of them, unless the rest are carried along the state rather than wanted to the
    /// tolerance themselves (a fit's sensitivities, integrated on the state's steps, which
    /// makes them the exact derivatives of the state those steps computed).
    fn controlled(&self) -> usize {
        self.dim()
    }
    /// Times, increasing, at which the problem records its whole state itself
    /// ([`Problem::record`]), from the method's dense output between steps (the start's and
    /// the end's exactly): a fit's data times, where a variational run wants x, Φ and S
    /// without ending a step at each.
    fn recorded_times(&self) -> &[f64] {
        &[]
    }
    /// Records y at one of [`Problem::recorded_times`].
    fn record(&mut self, t: f64, y: &[f64]) {
        let _ = (t, y);
    }
    /// How the components of y enter the problem: all differential, index 1, unless the
    /// problem is differential–algebraic (only a method of [`Form::Algebraic`] integrates those).
    fn components(&self) -> Components {
        Components::ordinary(self.dim())
    }
    /// Why the problem cannot be solved for its algebraic components at (t, y), when an
    /// implicit method found its iteration matrix singular there; `None` if it can.
    fn explain_singular(&mut self, t: f64, y: &[f64]) -> Option<FaultKind> {
        let _ = (t, y);
        None
    }
    /// The first time after `t` at which the right-hand side jumps (a held input takes its
    /// next sample) or its slope does (a series input passes a knot), if any: a run ends its
    /// step there and restarts its method after [`Problem::sample`].
    fn next_sample(&self, t: f64) -> Option<f64> {
        let _ = t;
        None
    }
    /// Takes the samples due at (t, y). The held values change the right-hand side, and `y`
    /// where the state depends on them (canonical momenta, a DAE's accelerations and
    /// multipliers).
    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let _ = (t, y);
        Ok(())
    }
    /// Moves the state of an accepted step back onto the constraints it should satisfy and
    /// that the method's equations do not hold it to (a differential–algebraic system's hidden
    /// constraints); nothing by default.
    fn project(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        let _ = (t, y);
        Ok(())
    }
    /// The number of guards: functions of (t, y) positive while the problem's current mode
    /// (which contacts are closed, say) holds. None by default.
    fn guards(&self) -> usize {
        0
    }
    /// Writes the guards' values at (t, y) to `out`. A run watches each that goes from > 0 to
    /// ≤ 0 over a step, locates the earliest such crossing and calls [`Problem::jump`] there.
    fn guard_values(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let _ = (t, y, out);
        Ok(())
    }
    /// Guard `k` alone at (t, y), `scratch` a buffer of [`Problem::guards`] values: what
    /// locating a crossing asks at each probe. By default all of them, one kept; a problem
    /// whose guard needs less than the others (an open contact's gap, no solve) gives it so.
    fn guard_value(
        &mut self,
        t: f64,
        y: &[f64],
        k: usize,
        scratch: &mut [f64],
    ) -> Result<f64, FaultKind> {
        self.guard_values(t, y, scratch)?;
        Ok(scratch[k])
    }
    /// Decides the mode at the start of a run of tolerance `tolerance` at (t, y), changing `y`
    /// in place where that takes an impulse (a contact closing at the start), and says what
    /// happened.
    fn begin_modes(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let _ = (t, y, tolerance);
        Ok(Vec::new())
    }
    /// Jumps at (t, y), where the guards `fired` reached zero: changes the mode and the state
    /// in place and says what happened. The run restarts its method after it.
    fn jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let _ = (t, y, fired);
        Ok(Vec::new())
    }
    /// The state in the physical variables (q, q̇), for reports of a fault or a run's end.
    fn physical(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        let _ = t;
        y.to_vec()
    }
}

/// The structure of a problem M·y' = F(t, y) with M = diag(I, 0): how many leading components
/// of y are differential, and how many, in order, have differential index 1, 2 and 3. An
/// implicit method scales the errors of index-2 and index-3 components by h and h², whose
/// local errors are of lower order (Hairer & Wanner, Solving ODEs II, VII.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Components {
    pub differential: usize,
    pub by_index: [usize; 3],
}

impl Components {
    /// An ordinary differential equation of `dim` components.
    pub fn ordinary(dim: usize) -> Self {
        Components { differential: dim, by_index: [dim, 0, 0] }
    }

    /// The differential index of component `i`.
    pub fn index(&self, i: usize) -> u8 {
        let [one, two, _] = self.by_index;
        if i < one {
            1
        } else if i < one + two {
            2
        } else {
            3
        }
    }
}

/// `Err` at the first entry of `v` that is NaN or infinite, named by `at` from its index.
pub(crate) fn check_finite(
    v: &[f64],
    at: impl FnOnce(usize) -> NonFiniteAt,
) -> Result<(), FaultKind> {
    if all_finite(v) {
        return Ok(());
    }
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(FaultKind::NonFinite { at: at(index) }),
        None => Ok(()),
    }
}

/// Whether every entry is finite. 0·x is 0 for a finite x and NaN for an infinity or a NaN,
/// and sums side by side in eight lanes vectorize where a search stopping at the first
/// non-finite entry does not: a 64×64 Jacobian's check had cost a tenth of it.
pub(crate) fn all_finite(v: &[f64]) -> bool {
    let mut lanes = [0.0; 8];
    let chunks = v.chunks_exact(8);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (lane, x) in lanes.iter_mut().zip(chunk) {
            *lane += 0.0 * x;
        }
    }
    lanes.iter().chain(rest).all(|x| x.is_finite())
}

/// The index of the state y = (q, q̇) as the rate it is.
pub(crate) fn rate(component: usize) -> NonFiniteAt {
    NonFiniteAt::Rate { component }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An infinity or a NaN anywhere (in the lanes or the remainder past them) is found, and
    /// `check_finite` names its index; finite values of every size, zeros of both signs and
    /// subnormals pass.
    #[test]
    fn every_non_finite_entry_is_found_wherever_it_is() {
        let finite: Vec<f64> = (0..21)
            .map(|i| [1e308, -0.0, 0.0, 5e-324, -3.5][i % 5] * (i as f64 + 1.0).recip())
            .collect();
        assert!(all_finite(&finite) && check_finite(&finite, |_| NonFiniteAt::Jacobian).is_ok());
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for at in 0..finite.len() {
                let mut v = finite.clone();
                v[at] = bad;
                assert!(!all_finite(&v), "{bad} at {at}");
                let found = check_finite(&v, |i| NonFiniteAt::Rate { component: i });
                assert_eq!(
                    found,
                    Err(FaultKind::NonFinite { at: NonFiniteAt::Rate { component: at } })
                );
            }
        }
    }
}
