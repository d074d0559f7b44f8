//! Numerical integration of lowered equations of motion.
//!
//! This crate owns everything between a straight-line program and a trajectory: solving
//! M(q)·q̈ = f for the accelerations (Cholesky where M is symmetric positive definite, LU with
//! pivoting otherwise, the augmented system with Baumgarte stabilisation when constraints
//! keep multipliers) and the exact Jacobians of those problems from the lowered partials of
//! their equations, the integrators (fixed-step RK4, adaptive Dormand–Prince 5(4) and
//! DOP853 with dense output, implicit Gauss–Legendre collocation that is symplectic in
//! canonical variables), events located on the dense output, and the measurements of a run
//! (steps, evaluations, energy and constraint drift). It works on numbered slots and
//! [`numeric::Tape`]s: it knows no symbols, names or files, and nothing of how the equations
//! were derived.

// Numeric kernels index several arrays in step; iterator chains would hide that.
#![allow(clippy::needless_range_loop)]

mod erk;
mod gauss;
pub mod linalg;
mod mechanical;
pub mod reference;
mod run;

pub use mechanical::{Canonical, Layout, Mechanical, Stabilisation};
pub use run::{integrate, Event, EventHit, Method, Run, Settings, Trajectory};

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
    /// A right-hand side or observation came out NaN or infinite at this component.
    NonFinite { component: usize },
    /// The adaptive step fell below what floating point can resolve at this time.
    StepTooSmall { step: f64 },
    /// Newton's iteration of an implicit method did not converge even at small steps.
    NewtonFailed,
    /// The run took more steps than allowed.
    TooManySteps { limit: usize },
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
    /// The state in the physical variables (q, q̇), for reports of a fault or a run's end.
    fn physical(&mut self, t: f64, y: &[f64]) -> Vec<f64> {
        let _ = t;
        y.to_vec()
    }
}

pub(crate) fn check_finite(v: &[f64]) -> Result<(), FaultKind> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(component) => Err(FaultKind::NonFinite { component }),
        None => Ok(()),
    }
}
