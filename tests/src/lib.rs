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

/// Exact references the accuracy tests compare against.
pub mod reference {
    /// The complete elliptic integral of the first kind, K(k) = π / (2 AGM(1, √(1 − k²))).
    pub fn elliptic_k(k: f64) -> f64 {
        let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
        while (a - b).abs() > 1e-16 * a {
            (a, b) = ((a + b) / 2.0, (a * b).sqrt());
        }
        std::f64::consts::PI / (2.0 * a)
    }

    /// ∫ f over [a, b] by composite three-point Gauss–Legendre, which never evaluates the ends
    /// (where the integrands of fall times are singular).
    pub fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
        let nodes = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
        let h = (b - a) / panels as f64;
        (0..panels)
            .map(|i| {
                let mid = a + (i as f64 + 0.5) * h;
                nodes.iter().map(|(x, w)| w * f(mid + x * h / 2.0)).sum::<f64>() * h / 2.0
            })
            .sum()
    }
}
