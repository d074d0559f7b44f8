//! Lowering of symbolic expressions to fast numeric code, and every float computed from an
//! expression.
//!
//! This crate owns the step from a set of [`cas`] expressions to one straight-line
//! [`Program`]: the expression DAG is walked once (hash-consing already shares equal
//! sub-expressions), every node becomes a few instructions on registers, and equal
//! instructions are numbered once more so that products like `2·x` shared by several sums are
//! computed once. A program runs on the [`Tape`] evaluator (no allocation per call; it writes
//! into any `&mut [f64]`, such as the storage of an `nalgebra` matrix), on the [`BatchTape`] at
//! many points at once (the same bits, a vector of points per register); the `export` stage
//! prints it as source. It takes expression ids and a symbol → input-slot mapping and knows
//! nothing of how the expressions were derived: no mechanics, no names, no files, no text.
//!
//! It is also the only float evaluator of expressions: [`Evaluator`] (and [`eval`],
//! [`value_and_scale`]) lower and run the same tape for parameter values, initial states,
//! `expect` checks and the zero test's numbers ([`GenericPoints`], the [`cas::ZeroTest`] every
//! derivation's pool is handed), with the [`elementary`] functions of `libm`, so a value has
//! the same bits wherever and on whatever machine it is computed.

mod batch;
pub mod elementary;
mod eval;
mod lower;
mod tape;
mod zero_test;

pub use batch::BatchTape;
pub use elementary::{pow_int, to_f64, LANES};
pub use eval::{eval, value_and_magnitude, value_and_scale, Evaluator, ScaledEvaluator};
pub use lower::{lower, Instr, LowerError, OpCounts, Program, Reg};
pub use tape::{Slice, Tape};
pub use zero_test::{GenericPoints, GENERIC_POINTS};
