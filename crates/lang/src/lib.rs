//! The scene language: the pest grammar in `grammar/scene.pest`, a parser that yields a spanned
//! AST, the diagnostics type every later stage reports through, and their rendering against
//! the scene's text ([`render`]) that every front end prints, and scenes of any size written
//! by a generator ([`generate`]).
//!
//! This crate knows what a scene file looks like, not what its statements mean: resolving names,
//! building expressions and checking physics belong to `model` and `mechanics`.

pub mod ast;
pub mod diag;
pub mod generate;
mod parser;
pub mod render;

pub use ast::*;
pub use diag::{Diagnostic, Severity};
pub use parser::{parse, parse_about, parse_expression, parse_quantity};
