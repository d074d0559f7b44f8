//! House rules that a reviewer would otherwise check by hand: every Rust file opens with a
//! `//!` line saying what it is for, and no source names a particular machine's paths.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if name != "target" && !name.starts_with('.') {
                rust_files(&path, out);
            }
        } else if name.ends_with(".rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_rust_file_opens_with_its_purpose() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    rust_files(&root.join("crates"), &mut files);
    rust_files(&root.join("tests"), &mut files);
    assert!(files.len() > 20);
    for f in files {
        let text = std::fs::read_to_string(&f).expect("readable");
        assert!(text.starts_with("//!"), "{} does not open with a `//!` line", f.display());
        let machine_path = concat!("/", "work", "/");
        assert!(
            !text.contains(machine_path),
            "{} names a path of a particular machine",
            f.display()
        );
    }
}

/// The dependency rules of ARCHITECTURE.md: each crate depends only on the crates its row of
/// the table allows, and every crate has a row and a section there.
#[test]
fn crates_depend_only_on_what_architecture_md_allows() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let architecture =
        std::fs::read_to_string(root.join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let table =
        architecture.split("## Dependency rules").nth(1).expect("a Dependency rules section");
    let mut allowed: std::collections::BTreeMap<String, Vec<String>> = Default::default();
    for line in table.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let name = cells[1].trim_matches('`').to_string();
        let deps = cells[2].split(',').map(|d| d.trim().trim_matches('`').to_string());
        allowed.insert(name, deps.filter(|d| !d.is_empty() && d != "—").collect());
    }
    let ours: Vec<String> = std::fs::read_dir(root.join("crates"))
        .expect("crates/")
        .flatten()
        .filter(|e| e.path().join("Cargo.toml").exists())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(ours.len() >= 8, "only {ours:?}");
    for name in &ours {
        assert!(
            architecture.contains(&format!("### `crates/{name}`")),
            "ARCHITECTURE.md has no section for crates/{name}"
        );
        let rule = allowed.get(name).unwrap_or_else(|| panic!("no dependency rule for {name}"));
        let manifest = std::fs::read_to_string(root.join("crates").join(name).join("Cargo.toml"))
            .expect("manifest");
        // Only [dependencies]: tests and benchmarks may use more.
        let section = manifest
            .split("[dependencies]")
            .nth(1)
            .map(|s| s.split("\n[").next().unwrap_or(""))
            .unwrap_or("");
        for line in section.lines() {
            let dep = line.split(['=', '.']).next().unwrap_or("").trim();
            if ours.iter().any(|o| o == dep) && dep != name {
                assert!(
                    name == "cli" || rule.iter().any(|r| r == dep),
                    "crates/{name} depends on {dep}, which ARCHITECTURE.md does not allow"
                );
            }
        }
    }
}
