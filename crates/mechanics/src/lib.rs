//! Lagrangian mechanics on a resolved model.
//!
//! This crate owns the physics: kinetic and potential energy of particles and planar rigid
//! bodies, holonomic constraints (eliminated when they can be solved for one coordinate, kept
//! with a multiplier otherwise), generalized forces by virtual work, the Euler–Lagrange
//! equations as M(q, t)·q̈ = f(q, q̇, t), reactions where a scene asks for them, and the
//! checking of `expect` lines. It knows nothing of parsing or of files: it starts from a
//! [`model::Model`].

mod admissible;
mod check;
mod derive;
mod present;
mod start;

pub use check::{Failure, Sampling, Verdict, SAMPLES};
pub use derive::{derive, Derivation, Elimination, Multiplier, Reaction};
pub use present::{Equation, NumericValue, ShownAtStart};
pub use start::{NumericStart, StartSolution};
