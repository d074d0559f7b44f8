//! A small exact computer-algebra core: hash-consed expressions over exact rationals, with
//! differentiation, substitution, expansion, zero recognition, printing, and the exact solution
//! of linear systems whose entries are expressions ([`linear_system`]).
//!
//! This crate owns expressions and nothing else: it knows no mechanics, no files and no
//! grammar. Everything lives in a [`Pool`]; expressions are small copyable [`ExprId`]s, and
//! structurally equal expressions are the same id. Constructors (`add`, `mul`, `powq`, `func`,
//! …) return canonical forms, so like terms are collected as they are built. Derivatives are
//! memoised per (node, symbol), which keeps the derivatives of large Lagrangians shared.
//!
//! It evaluates no floats: the one float evaluator of expressions is `numeric`'s, which sits
//! above this crate and hands the zero test its numbers ([`ZeroTest`], [`Pool::set_zero_test`]).

mod diff;
mod expand;
mod fold;
pub mod linear_system;
pub mod number;
mod pool;
pub mod print;
mod subst;

pub use number::Rational;
pub use pool::{Collected, ExprId, Func, Node, Pool, SymId, Symbol, SymbolKind, ZeroTest};
pub use print::{greek_word, Style};
