//! Titles and paths that try to break out of the generated code: comment closers and openers,
//! trigraphs, backslashes, quotes, markup and non-ASCII. The C (the module and the FMU's
//! sources) must compile under `-std=c99 -Wall -Wextra -Werror -pedantic`, the Rust under
//! rustc, and the FMU's modelDescription.xml must carry them as escaped text.

use std::path::{Path, PathBuf};
use std::process::Command;

const FLAGS: [&str; 5] = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"];

/// Titles as a scene writes them (the scene's own escapes, `\"` and `\\`, included).
const TITLES: [&str; 9] = [
    r"pendulum */ x /* y",
    r"a // b /*/ c */*/",
    r"back\\slash at the end \\",
    r#"quote \" q \"\" and 'single'"#,
    r"<tag> & ]]> &amp; </model>",
    "θ̇ non-ASCII ∮ ??= ??/ ??' ???",
    "???/",
    r"*/",
    r"/*",
];

/// Paths the generated code names the scene by.
const PATHS: [&str; 3] = ["dir */ x /* y/p.lag", "??/??=/scene.lag", "back\\slash/θ.lag"];

fn scene(title: &str) -> String {
    format!(
        "scene \"{title}\"\nparam m = 1 kg, g = 9.81 m/s^2, L = 1 m\ncoord theta = 1/2\n\
         particle bob {{ mass m; position (L*sin(theta), -L*cos(theta)) }}\ngravity g\n\
         output swing: theta\n"
    )
}

/// A scratch folder for one test, removed when it ends.
struct Scratch(PathBuf);

impl Scratch {
    fn new(test: &str) -> Scratch {
        let dir =
            std::env::temp_dir().join(format!("lagrange-hostile-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn compiler() -> Option<String> {
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".to_string());
    let works = Command::new(&cc).arg("--version").output().is_ok_and(|o| o.status.success());
    let required = std::env::var("LAGRANGE_C_TEST").is_ok_and(|v| v == "required");
    assert!(works || !required, "LAGRANGE_C_TEST=required, and `{cc}` does not run");
    works.then_some(cc)
}

/// Compiles each `.c` of `sources` (written into `dir`) to an object; the compiler's
/// complaints, if any.
fn compile(cc: &str, dir: &Path, sources: &[(String, String)]) -> Option<String> {
    for (name, text) in sources {
        std::fs::write(dir.join(name), text).expect("write");
    }
    for (name, _) in sources.iter().filter(|(n, _)| n.ends_with(".c")) {
        let out = Command::new(cc)
            .args(FLAGS)
            .arg("-c")
            .arg(dir.join(name))
            .arg("-o")
            .arg(dir.join(format!("{name}.o")))
            .output()
            .expect("the compiler runs");
        if !out.status.success() {
            return Some(format!("{name}: {}", String::from_utf8_lossy(&out.stderr)));
        }
    }
    None
}

#[test]
fn hostile_titles_and_paths_compile_as_c() {
    let Some(cc) = compiler() else { return };
    let scratch = Scratch::new("c");
    let mut failures = Vec::new();
    for (k, title) in TITLES.iter().enumerate() {
        for path in PATHS {
            let source = scene(title);
            let module = export::codegen::c(path, &source, engine::Options::default())
                .expect("the scene generates C");
            let dir = scratch.0.join(format!("c{k}-{}", module.name));
            std::fs::create_dir_all(&dir).expect("dir");
            let sources = [
                (format!("{}.h", module.name), module.header.clone()),
                (format!("{}.c", module.name), module.source.clone()),
            ];
            if let Some(complaint) = compile(&cc, &dir, &sources) {
                failures.push(format!("title {title:?}, path {path:?}: {complaint}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn hostile_titles_make_an_fmu_whose_sources_compile_and_whose_xml_escapes_them() {
    let Some(cc) = compiler() else { return };
    let scratch = Scratch::new("fmu");
    let options = export::fmu::ExportOptions::default();
    for (k, title) in TITLES.iter().enumerate() {
        let source = scene(title);
        let fmu = export::fmu::export(PATHS[0], &source, &options).expect("exports");
        let dir = scratch.0.join(format!("fmu{k}"));
        std::fs::create_dir_all(&dir).expect("dir");
        if let Some(complaint) = compile(&cc, &dir, &fmu.sources) {
            panic!("title {title:?}: {complaint}");
        }
        let xml = &fmu.model_description;
        // The title as the scene means it (its escapes resolved), then as XML writes it.
        let meant = title.replace(r#"\""#, "\"").replace(r"\\", "\\");
        let escaped = meant
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
            .replace('"', "&quot;");
        assert!(xml.contains(&format!("modelName=\"{escaped}\"")), "{title:?}:\n{xml}");
        // Every `<` opens markup, every `&` a reference: nothing of the title is left raw.
        for (i, _) in xml.match_indices('&') {
            let rest = &xml[i..];
            assert!(
                ["&amp;", "&lt;", "&gt;", "&quot;", "&#"].iter().any(|r| rest.starts_with(r)),
                "{title:?}: a bare `&` at {i}"
            );
        }
        assert!(!xml.contains("<tag>") && !xml.contains("</model>"), "{title:?}:\n{xml}");
        assert!(fmu.documentation.contains(&escaped), "{title:?}");
    }
}

#[test]
fn hostile_titles_and_paths_compile_as_rust() {
    let scratch = Scratch::new("rust");
    let mut modules = String::new();
    for (k, title) in TITLES.iter().enumerate() {
        for (j, path) in PATHS.iter().enumerate() {
            let source = scene(title);
            let module = export::codegen::codegen(path, &source).expect("the scene generates Rust");
            // A module's `//!` lines document the file it is in: each goes into a file of its
            // own, as a user would put it.
            let name = format!("m{k}_{j}");
            std::fs::write(scratch.0.join(format!("{name}.rs")), &module.source).expect("write");
            modules.push_str(&format!("pub mod {name};\n"));
        }
    }
    std::fs::write(scratch.0.join("lib.rs"), modules).expect("write");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(rustc)
        .args(["--edition", "2021", "--crate-type", "lib", "--emit", "metadata", "-o"])
        .arg(scratch.0.join("hostile.rmeta"))
        .arg(scratch.0.join("lib.rs"))
        .output()
        .expect("rustc runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}
