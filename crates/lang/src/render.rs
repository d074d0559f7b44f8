//! Renders diagnostics the way compilers do: file, line, column, the source line, a caret
//! under the culprit, and a hint. Every front end shows a scene's mistakes through here, so
//! the `lagrange` command and the Python package print them alike.

use codespan_reporting::diagnostic::{Diagnostic as Report, Label, Severity as ReportSeverity};
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term::{self, Config};
use termcolor::{Buffer, WriteColor};

use crate::{Diagnostic, Severity, Span};

fn to_report(d: &Diagnostic) -> Report<()> {
    let severity = match d.severity {
        Severity::Error => ReportSeverity::Error,
        Severity::Warning => ReportSeverity::Warning,
    };
    let mut labels =
        vec![Label::primary((), d.span.start..d.span.end).with_message(d.label.clone())];
    for (span, text) in &d.related {
        labels.push(Label::secondary((), span.start..span.end).with_message(text.clone()));
    }
    let notes = d.hint.iter().map(|h| format!("hint: {h}")).collect();
    Report::new(severity).with_message(d.message.clone()).with_labels(labels).with_notes(notes)
}

/// The diagnostic with its spans inside the text, so that rendering cannot fail on them.
fn clamp(d: &Diagnostic, len: usize) -> Diagnostic {
    let fix = |s: Span| Span::new(s.start.min(len), s.end.min(len).max(s.start.min(len)));
    let mut d = d.clone();
    d.span = fix(d.span);
    d.related = d.related.iter().map(|(s, t)| (fix(*s), t.clone())).collect();
    d
}

/// Writes the diagnostics to `out` (a terminal, in colour where it takes colour), `path`
/// naming the file their spans point into.
pub fn emit(out: &mut dyn WriteColor, path: &str, source: &str, diagnostics: &[Diagnostic]) {
    let file = SimpleFile::new(path, source);
    let config = Config::default();
    for d in diagnostics {
        let d = clamp(d, source.len());
        // Rendering into memory or a terminal; a failure there has nowhere better to go.
        let _ = term::emit(out, &config, &file, &to_report(&d));
    }
}

/// The diagnostics as plain text, as a terminal without colour shows them.
pub fn render(path: &str, source: &str, diagnostics: &[Diagnostic]) -> String {
    let mut buffer = Buffer::no_color();
    emit(&mut buffer, path, source, diagnostics);
    String::from_utf8_lossy(buffer.as_slice()).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diagnostic_names_file_line_and_column_and_points_at_the_culprit() {
        let d = Diagnostic::error(Span::new(8, 9), "unknown name `y`").with_label("not declared");
        let text = render("scene.lag", "coord x\ny\n", &[d]);
        assert!(text.contains("error: unknown name `y`"), "{text}");
        assert!(text.contains("scene.lag:2:1"), "{text}");
        assert!(text.contains("not declared"), "{text}");
    }

    #[test]
    fn spans_past_the_end_are_clamped() {
        let d = Diagnostic::error(Span::new(50, 60), "past the end");
        assert!(render("f", "ab", &[d]).contains("past the end"));
    }
}
