//! The benchmarks' library half: the exact references integrators are measured against
//! ([`reference`]), which `lagrange-bench` (the binary, `main.rs`) and the workspace tests
//! share. They are measuring instruments, not part of any product crate.

pub mod reference;
