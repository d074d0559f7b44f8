//! Progress is for a person at a terminal: with stderr a pipe, a benchmark that draws a bar
//! writes its tables to stdout and nothing to stderr.

use std::process::{Command, Stdio};

#[test]
fn a_piped_benchmark_writes_no_progress() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagrange-bench"))
        .args(["scaling", "--max", "2"])
        .stdin(Stdio::null())
        .output()
        .expect("lagrange-bench runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let tables = String::from_utf8_lossy(&out.stdout);
    assert!(tables.contains("n-link-pendulum"), "{tables}");
    assert!(out.stderr.is_empty(), "{:?}", String::from_utf8_lossy(&out.stderr));
}
