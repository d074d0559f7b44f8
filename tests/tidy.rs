//! House rules that a reviewer would otherwise check by hand: every Rust file opens with a
//! `//!` line saying what it is for, no source names a particular machine's paths, crates
//! depend only on what ARCHITECTURE.md allows, `cas` and `mechanics` name no float type,
//! `numeric` makes no text, `linear` parses nothing, and the modules of a crate form no
//! circles.

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
    let mut above = Vec::new();
    for line in table.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let name = cells[1].trim_matches('`').to_string();
        let deps: Vec<String> = if cells[2] == "all of the above" {
            above.clone()
        } else {
            let deps = cells[2].split(',').map(|d| d.trim().trim_matches('`').to_string());
            deps.filter(|d| !d.is_empty() && d != "—").collect()
        };
        above.push(name.clone());
        allowed.insert(name, deps);
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
                    rule.iter().any(|r| r == dep),
                    "crates/{name} depends on {dep}, which ARCHITECTURE.md does not allow"
                );
            }
        }
    }
}

/// `line` without its `//` comment; a `//` inside a string or a character literal is kept.
fn code_of(line: &str) -> &str {
    let bytes = line.as_bytes();
    let mut in_string = false;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' if in_string => i += 1,
            b'"' => in_string = !in_string,
            // A character literal such as '"' or '\\'; a lifetime has no closing quote.
            b'\'' if !in_string => {
                if bytes.get(i + 1) == Some(&b'\\') {
                    i += bytes[i + 2..].iter().position(|&b| b == b'\'').map_or(0, |p| p + 2);
                } else if bytes.get(i + 2) == Some(&b'\'') {
                    i += 2;
                }
            }
            b'/' if !in_string && bytes.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
        i += 1;
    }
    line
}

/// The code of a source file as the module rules read it: comments dropped, and nothing from
/// the first top-level `#[cfg(test)]` on (tests sit at the end of a file and may reach
/// anywhere).
fn code_without_tests(text: &str) -> String {
    let mut code = String::new();
    for line in text.lines() {
        if line.trim_end() == "#[cfg(test)]" {
            break;
        }
        code.push_str(code_of(line));
        code.push('\n');
    }
    code
}

/// The first line of `crate`'s source that names one of `words` (comments left out), as
/// `file:line: word`.
fn first_naming(name: &str, words: &[&str]) -> Option<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    rust_files(&root.join("crates").join(name).join("src"), &mut files);
    assert!(!files.is_empty(), "no source in crates/{name}");
    for f in files {
        let text = std::fs::read_to_string(&f).expect("readable");
        for (n, line) in text.lines().enumerate() {
            let mut found = code_of(line).split(|c: char| !c.is_alphanumeric() && c != '_');
            if let Some(word) = found.find(|w| words.contains(w)) {
                return Some(format!("{}:{}: {word}", f.display(), n + 1));
            }
        }
    }
    None
}

/// No `f64` in `cas` or `mechanics`: they evaluate no floats (ARCHITECTURE.md); the numbers
/// `cas`'s zero test needs come from `numeric` through `cas::ZeroTest`, and what needs numbers
/// of a derivation is `verify`'s and `linear`'s.
#[test]
fn cas_and_mechanics_have_no_floats() {
    for name in ["cas", "mechanics"] {
        let float = first_naming(name, &["f64", "f32"]);
        assert!(float.is_none(), "`{name}` names a float type: {}", float.unwrap_or_default());
    }
}

/// `numeric` lowers and evaluates; printing a program as source is the `export` stage's
/// (ARCHITECTURE.md), so `numeric` makes no text.
#[test]
fn numeric_makes_no_text() {
    let text = first_naming("numeric", &["String", "format"]);
    assert!(text.is_none(), "`numeric` makes text: {}", text.unwrap_or_default());
}

/// `linear` starts from a derivation: it parses and resolves nothing (the command line's
/// reference reaches it resolved by the model, ARCHITECTURE.md).
#[test]
fn linear_parses_and_resolves_nothing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    rust_files(&root.join("crates/linear/src"), &mut files);
    assert!(!files.is_empty());
    let banned = ["lang::parse", "model::resolve", "resolve_about", "resolve_expression"];
    for f in files {
        let code = code_without_tests(&std::fs::read_to_string(&f).expect("readable"));
        for name in banned {
            assert!(!code.contains(name), "{}: `linear` calls {name}", f.display());
        }
    }
}

/// Words and punctuation, `::` as one token.
fn tokens(code: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(c) = rest.chars().next() {
        let len = if c.is_alphanumeric() || c == '_' {
            rest.find(|d: char| !d.is_alphanumeric() && d != '_').unwrap_or(rest.len())
        } else if rest.starts_with("::") {
            2
        } else {
            c.len_utf8()
        };
        if !c.is_whitespace() {
            out.push(&rest[..len]);
        }
        rest = &rest[len..];
    }
    out
}

fn is_word(t: &str) -> bool {
    t.chars().all(|c| c.is_alphanumeric() || c == '_')
}

/// The paths a path or `use` tree at `t[i..]` names, each after `prefix`: `a::{b, c::d}` gives
/// `a::b` and `a::c::d`. Returns where the tree ends.
fn use_tree(t: &[&str], mut i: usize, mut path: Vec<String>, out: &mut Vec<Vec<String>>) -> usize {
    loop {
        match t.get(i).copied() {
            Some("{") => {
                i += 1;
                while i < t.len() && t[i] != "}" {
                    i = use_tree(t, i, path.clone(), out);
                    if t.get(i) == Some(&",") {
                        i += 1;
                    } else {
                        break;
                    }
                }
                return i + 1;
            }
            Some(w) if is_word(w) && w != "self" => {
                path.push(w.to_string());
                i += 1;
            }
            _ => break,
        }
        if t.get(i) != Some(&"::") {
            break;
        }
        i += 1;
    }
    out.push(path);
    i
}

/// The circles between the modules of one crate, given its source files as (path under
/// `src/`, text). A file's module is its path (`lib.rs` and `main.rs` the root, `a/mod.rs` is
/// `a`); it refers to another module by a `crate::…` or `super::…` path, in a `use` or in
/// code, and the reference counts for the longest module the path names. A module includes its
/// submodules (`mod` declarations make the tree), and a module and its own submodules may use
/// each other freely, as Rust's `super::` idiom does; what must not happen is that two
/// siblings (two modules under the same parent, each with its submodules) depend on each other,
/// directly or round a longer circle. Paths through the crate root's re-exports (`crate::Name`)
/// count for the root, and so for no sibling.
fn module_cycles(files: &[(String, String)]) -> Vec<String> {
    use std::collections::{BTreeMap, BTreeSet};
    let module = |path: &str| -> Vec<String> {
        let mut parts: Vec<String> =
            path.trim_end_matches(".rs").split('/').map(str::to_string).collect();
        if parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main")
            || parts.last().map(String::as_str) == Some("mod")
        {
            parts.pop();
        }
        parts
    };
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(p, _)| module(p)).collect();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (path, text) in files {
        let from = module(path);
        let code = code_without_tests(text);
        let t = tokens(&code);
        for i in 0..t.len() {
            if !(matches!(t[i], "crate" | "super") && t.get(i + 1) == Some(&"::"))
                || (i > 0 && t[i - 1] == "::")
            {
                continue;
            }
            let mut base = from.clone();
            let mut j = i;
            if t[j] == "crate" {
                base.clear();
                j += 2;
            } else {
                while t[j] == "super" && t.get(j + 1) == Some(&"::") {
                    base.pop();
                    j += 2;
                }
            }
            let mut paths = Vec::new();
            use_tree(&t, j, base, &mut paths);
            for p in paths {
                let target =
                    (0..=p.len()).rev().map(|k| p[..k].to_vec()).find(|m| modules.contains(m));
                let Some(to) = target else { continue };
                let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
                if common < from.len() && common < to.len() {
                    let entry = edges.entry(from[..=common].to_vec()).or_default();
                    entry.insert(to[..=common].to_vec());
                }
            }
        }
    }
    // Depth first; an edge back to a module on the stack closes a circle.
    fn visit(
        m: &Vec<String>,
        edges: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        stack: &mut Vec<Vec<String>>,
        done: &mut BTreeSet<Vec<String>>,
        found: &mut Vec<String>,
    ) {
        stack.push(m.clone());
        for next in edges.get(m).into_iter().flatten() {
            if let Some(at) = stack.iter().position(|s| s == next) {
                let circle: Vec<String> =
                    stack[at..].iter().chain([next]).map(|s| s.join("::")).collect();
                found.push(circle.join(" → "));
            } else if !done.contains(next) {
                visit(next, edges, stack, done, found);
            }
        }
        stack.pop();
        done.insert(m.clone());
    }
    let mut found = Vec::new();
    let mut done = BTreeSet::new();
    for m in edges.keys() {
        if !done.contains(m) {
            visit(m, &edges, &mut Vec::new(), &mut done, &mut found);
        }
    }
    found
}

/// No two modules of a crate use each other, directly or round a circle (see
/// [`module_cycles`]): each module sits above or below another, so that it can be read, tested
/// and moved on its own.
#[test]
fn no_module_circles_within_a_crate() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut circles = Vec::new();
    for entry in std::fs::read_dir(root.join("crates")).expect("crates/").flatten() {
        let src = entry.path().join("src");
        let mut paths = Vec::new();
        rust_files(&src, &mut paths);
        let files: Vec<(String, String)> = paths
            .iter()
            .map(|p| {
                let rel = p.strip_prefix(&src).expect("under src").to_string_lossy();
                (rel.replace('\\', "/"), std::fs::read_to_string(p).expect("readable"))
            })
            .collect();
        let name = entry.file_name().to_string_lossy().into_owned();
        circles.extend(module_cycles(&files).into_iter().map(|c| format!("crates/{name}: {c}")));
    }
    assert!(circles.is_empty(), "module circles:\n{}", circles.join("\n"));
}

/// The circle check sees a circle through a `use` group and a submodule, and lets a submodule
/// use its parent.
#[test]
fn the_circle_check_finds_circles() {
    let files = |list: &[(&str, &str)]| -> Vec<(String, String)> {
        list.iter().map(|(p, t)| (p.to_string(), t.to_string())).collect()
    };
    let fine = files(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "mod inner;\nuse crate::b::B;\npub struct A;\n"),
        ("a/inner.rs", "use super::A; // crate::b is fine too\n"),
        ("b.rs", "pub struct B;\n#[cfg(test)]\nmod tests { use crate::a::A; }\n"),
    ]);
    assert!(module_cycles(&fine).is_empty(), "{:?}", module_cycles(&fine));
    let circle = files(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "mod inner;\nuse crate::{b::B, Other};\npub struct A;\n"),
        ("a/inner.rs", "fn f() -> super::super::b::B { todo!() }\n"),
        ("b.rs", "pub struct B(crate::a::A);\n"),
    ]);
    assert_eq!(module_cycles(&circle), vec!["a → b → a"]);
}
