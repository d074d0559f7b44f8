//! Lowering of symbolic expressions to fast numeric code.
//!
//! This crate owns the step from a set of [`cas`] expressions to one straight-line
//! [`Program`]: the expression DAG is walked once (hash-consing already shares equal
//! sub-expressions), every node becomes a few instructions on registers, and equal
//! instructions are numbered once more so that products like `2·x` shared by several sums are
//! computed once. A program runs on the [`Tape`] evaluator (no allocation per call; it writes
//! into any `&mut [f64]`, such as the storage of an `nalgebra` matrix) or is printed as Rust
//! source by [`rust`]. It takes expression ids and a symbol → input-slot mapping and knows
//! nothing of how the expressions were derived: no mechanics, no names, no files.

mod lower;
pub mod rust;
mod tape;

pub use lower::{lower, Instr, LowerError, OpCounts, Program};
pub use tape::Tape;

/// `x^n` by binary powering: the same sequence of multiplications on every machine, in the
/// tape and in generated code (`f64::powi` leaves its precision unspecified).
pub fn pow_int(x: f64, n: i32) -> f64 {
    let mut base = x;
    let mut k = n.unsigned_abs();
    let mut acc = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            acc *= base;
        }
        base *= base;
        k >>= 1;
    }
    if n < 0 {
        1.0 / acc
    } else {
        acc
    }
}
