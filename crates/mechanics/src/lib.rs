//! Lagrangian mechanics on a resolved model.
//!
//! This crate owns the physics: kinetic and potential energy of particles and rigid bodies
//! (planar, and spatial with ω from the orientation), constraints (a holonomic one eliminated
//! when it can be solved for one coordinate, kept with a multiplier otherwise; a velocity
//! constraint integrated when its coefficients are constant, kept otherwise; a kept one with
//! its rows at every level, built once by its kind), generalized
//! forces by virtual work, the Euler–Lagrange equations as M(q, t)·q̈ = f(q, q̇, t), the same
//! in the independent rates where velocity constraints are kept, reactions where a scene asks
//! for them, the algebraic side of checking `expect` lines, and the equations' exact partials
//! in the state, which every exact Jacobian is made of (the linearization about a reference is
//! the `linear` crate's). It is purely symbolic: what needs numbers
//! (random states, the numeric start, verdicts sampled at states) is the `verify` crate's. It
//! knows nothing of parsing or of files: it starts from a [`model::Model`].

mod check;
mod contact;
mod derive;
mod independent;
mod partials;
mod present;
mod start;
mod start_solution;

pub use independent::{IndependentForm, DEPENDENT_LIMIT};
pub use present::collect_by_motion;

pub use check::Decision;
pub use contact::{ContactRows, ContactSlots, ImpactLaw};
pub use derive::{
    derive, ChainForm, ChainNode, ConstraintRows, Derivation, Elimination, Multiplier, Reaction,
    Stabilisation,
};
pub use partials::{ParameterPartials, Partials, StatePartials};
pub use present::{Equation, NumericStart, StartShows};
pub use start_solution::StartSolution;
