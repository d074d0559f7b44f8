//! The parser's tests in one binary (one link instead of four), a module each.

mod errors;
mod expressions;
mod robustness;
mod scenes;
