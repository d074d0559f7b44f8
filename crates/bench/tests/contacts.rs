//! `lagrange-bench contacts` as a process, once over (one repeat, no peer): both scenes'
//! tables, three tolerances each, and every impact matched to the closed forms (a missed or
//! an extra impact would show as an infinite error).

use std::process::{Command, Stdio};

#[test]
fn the_contacts_section_prints_a_table_per_scene_with_every_impact_matched() {
    let out = Command::new(env!("CARGO_BIN_EXE_lagrange-bench"))
        .args(["contacts", "--repeats", "1"])
        .stdin(Stdio::null())
        .output()
        .expect("lagrange-bench runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("### The bouncing ball") && text.contains("### The rocking block"));
    // The rows of the two tables: a tolerance first, then the impacts and their error.
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("| 1e-"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 6, "{text}");
    for row in &rows {
        let impacts: usize = row[2].parse().expect("a count of impacts");
        let error: f64 = row[3].parse().expect("an error");
        assert!(impacts > 10, "{row:?}");
        assert!(error < 1e-3, "{row:?}");
    }
    assert!(!text.contains("SciPy"), "{text}");
}
