//! `lagrange-bench` as a process. Progress is for a person at a terminal: with stderr a pipe, a
//! benchmark that draws a bar writes its tables to stdout and nothing to stderr. `derive`
//! writes one line of JSON; a usage error exits 2.

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

#[test]
fn derive_prints_one_line_of_json_for_the_sympy_comparison() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagrange-bench"))
        .args(["derive", "n-link-pendulum", "2"])
        .stdin(Stdio::null())
        .output()
        .expect("lagrange-bench runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 1, "{text}");
    let line: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(line["n"], 2, "{line}");
    for key in ["derive_s", "lowered_s"] {
        assert!(line[key].as_f64().is_some_and(|s| s > 0.0), "{key}: {line}");
    }
    assert!(line["nodes"].as_u64().is_some_and(|n| n > 0), "{line}");
    assert!(line["ops"].as_u64().is_some_and(|n| n > 0), "{line}");
    assert!(line["peak_rss_bytes"].is_u64() || line["peak_rss_bytes"].is_null(), "{line}");
}

#[test]
fn an_unknown_family_is_a_usage_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagrange-bench"))
        .args(["derive", "n-link-chain", "2"])
        .output()
        .expect("lagrange-bench runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("one of n-link-pendulum, n-link-pendulum-on-cart"), "{stderr}");
}
