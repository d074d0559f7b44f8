//! The lowering's and the tapes' tests in one binary (one link instead of five), a module
//! each, with the helpers they share in `common`.

mod abs_and_sign;
mod common;
mod eval;
mod native;
mod pow_lanes;
mod sin_cos_lanes;
mod tape;
