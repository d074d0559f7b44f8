//! Helpers shared by the workspace-level tests: finding the examples and reading them.

use std::path::{Path, PathBuf};

/// The repository's `examples/` folder.
pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

/// Every `.lag` file under `examples/`, sorted, as (path relative to the repository, source).
pub fn examples() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut stack = vec![examples_dir()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "lag") {
                let rel = path
                    .strip_prefix(examples_dir())
                    .expect("under examples")
                    .to_string_lossy()
                    .replace('\\', "/");
                let source = std::fs::read_to_string(&path).expect("readable example");
                out.push((format!("examples/{rel}"), source));
            }
        }
    }
    out.sort();
    out
}
