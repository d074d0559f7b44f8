//! The `check` report: every `expect` line with its verdict, and for a failure the residual and
//! a state where it is not zero, rendered from `results::check`.

use engine::Options;
use lang::Diagnostic;
use results::check::Checked;

use crate::diagnostics::render;

/// The outcome of checking one file.
pub struct FileCheck {
    /// The report to print.
    pub report: String,
    /// 0: every expectation holds; 1: one does not (or cannot be decided); 2: the file has errors.
    pub exit_code: i32,
    pub held: usize,
    pub failed: usize,
    /// Rendered warnings (empty when there are none).
    pub warnings: String,
}

/// Checks every `expect` line of one scene.
pub fn check_file(path: &str, source: &str) -> FileCheck {
    check_file_with(path, source, Options::default())
}

/// [`check_file`] with options.
pub fn check_file_with(path: &str, source: &str, options: Options) -> FileCheck {
    let engine::Scene { derivation: mut d, warnings } = match engine::load_with(source, options) {
        Ok(scene) => scene,
        Err(e) => {
            return FileCheck {
                report: crate::diagnostics::error(path, &e),
                exit_code: 2,
                held: 0,
                failed: 0,
                warnings: String::new(),
            };
        }
    };
    let mut tally = Tally::default();
    tally.add(path, results::check::expectations(source, &mut d));
    // A scene that does not linearize about its own reference is bad input, as `linearize`
    // says: exit 2 with its diagnostic, after what the other expectations gave.
    let mut refused = None;
    if !d.model.linear_expects.is_empty() {
        match engine::expect_linearized::check_linearized(source, d) {
            Ok((verdicts, d)) => tally.add(path, results::check::linearized(source, &d, &verdicts)),
            Err(e) => refused = Some(crate::diagnostics::error(path, &e)),
        }
    }
    let mut report = tally.lines.join("\n");
    if !report.is_empty() {
        report.push('\n');
    }
    if !tally.failures.is_empty() {
        report.push_str(&render(path, source, &tally.failures));
    }
    let exit_code = match (&refused, tally.failed) {
        (Some(error), _) => {
            report.push_str(error);
            2
        }
        (None, 0) => 0,
        (None, _) => 1,
    };
    FileCheck {
        report,
        exit_code,
        held: tally.held,
        failed: tally.failed,
        warnings: render(path, source, &warnings),
    }
}

/// Each expectation's line of the report, the diagnostics of those that fail, and the counts.
#[derive(Default)]
struct Tally {
    lines: Vec<String>,
    failures: Vec<Diagnostic>,
    held: usize,
    failed: usize,
}

impl Tally {
    fn add(&mut self, path: &str, checked: Vec<Checked>) {
        for c in checked {
            let mark = if c.held { "ok  " } else { "FAIL" };
            self.lines.push(format!("{mark} {path}:{}  {}  — {}", c.line, c.text, c.how));
            if c.held {
                self.held += 1;
            } else {
                self.failed += 1;
            }
            self.failures.extend(c.diagnostic);
        }
    }
}
