//! The `check` report: every `expect` line with its verdict, and for a failure the residual and
//! a state where it is not zero.

use cas::Style;
use lang::Diagnostic;
use mechanics::Derivation;
use verify::Verdict;

use engine::expect_linearized::LinearVerdict;
use engine::{line_col, Options};

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
    let mut tally = check_derivation(path, source, &mut d);
    // A scene that does not linearize about its own reference is bad input, as `linearize`
    // says: exit 2 with its diagnostic, after what the other expectations gave.
    let mut refused = None;
    if !d.model.linear_expects.is_empty() {
        match engine::expect_linearized::check_linearized(source, d) {
            Ok((verdicts, d)) => check_linearized(&mut tally, (path, source), &d, &verdicts),
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

/// The `expect linearized:` lines' verdicts, added to the report.
fn check_linearized(
    tally: &mut Tally,
    (path, source): (&str, &str),
    d: &Derivation,
    verdicts: &[LinearVerdict],
) {
    for (expect, verdict) in d.model.linear_expects.iter().zip(verdicts) {
        let (line, _) = line_col(source, expect.span.start);
        let (mark, how) = match verdict {
            LinearVerdict::Holds(how) => ("ok  ", how.clone()),
            LinearVerdict::Fails(what) => ("FAIL", what.clone()),
            LinearVerdict::Undecided(why) => ("FAIL", why.clone()),
        };
        tally.lines.push(format!("{mark} {path}:{line}  {}  — {how}", expect.text));
        if verdict.holds() {
            tally.held += 1;
            continue;
        }
        tally.failed += 1;
        let message = match verdict {
            LinearVerdict::Undecided(_) => "this expectation could not be decided",
            _ => "this expectation does not hold",
        };
        tally.failures.push(Diagnostic::error(expect.span, message).with_label(how));
    }
}

fn check_derivation(path: &str, source: &str, d: &mut Derivation) -> Tally {
    let verdicts = verify::check_all(d);
    let mut lines = Vec::new();
    let mut failures = Vec::new();
    let (mut held, mut failed) = (0, 0);
    for (expect, verdict) in d.model.expects.iter().zip(&verdicts) {
        let (line, _) = line_col(source, expect.span.start);
        let how = verdict.how();
        let mark = if verdict.holds() { "ok  " } else { "FAIL" };
        lines.push(format!("{mark} {path}:{line}  {}  — {how}", expect.text));
        if verdict.holds() {
            held += 1;
        } else {
            failed += 1;
        }
        let pool = &d.model.pool;
        match verdict {
            Verdict::Fails(f) => {
                let which = f.component.map(|k| format!(" (entry {})", k + 1)).unwrap_or_default();
                let state: Vec<String> = f
                    .state
                    .iter()
                    .map(|(s, v)| format!("{} = {v:.6}", pool.symbol_text(*s, Style::Unicode)))
                    .collect();
                let mut diag = Diagnostic::error(
                    expect.span,
                    format!("this expectation does not hold{which}"),
                )
                .with_label(format!("lhs − rhs = {}", pool.print(f.residual, Style::Unicode)));
                diag.hint = Some(if state.is_empty() {
                    format!("the residual is {:.6}, not 0", f.value)
                } else {
                    format!("at {}, lhs − rhs = {:.6}", state.join(", "), f.value)
                });
                failures.push(diag);
            }
            Verdict::Undecided { reason } => {
                failures.push(
                    Diagnostic::error(expect.span, "this expectation could not be decided")
                        .with_label(reason.clone()),
                );
            }
            _ => {}
        }
    }
    Tally { lines, failures, held, failed }
}
