//! Renders diagnostics the way compilers do: file, line, column, the source line, a caret
//! under the culprit, and a hint. Every front end shows a scene's mistakes through here, so
//! the `lagrange` command and the Python package print them alike.

use codespan_reporting::diagnostic::{Diagnostic as Report, Label, Severity as ReportSeverity};
use codespan_reporting::files::{SimpleFile, SimpleFiles};
use codespan_reporting::term::{self, Config};
use termcolor::{Buffer, WriteColor};

use crate::{Diagnostic, Severity, Span};

fn severity(severity: Severity) -> ReportSeverity {
    match severity {
        Severity::Error => ReportSeverity::Error,
        Severity::Warning => ReportSeverity::Warning,
    }
}

fn to_report(d: &Diagnostic) -> Report<()> {
    let mut labels =
        vec![Label::primary((), d.span.start..d.span.end).with_message(d.label.clone())];
    for (span, text) in &d.related {
        labels.push(Label::secondary((), span.start..span.end).with_message(text.clone()));
    }
    let notes = d.hint.iter().map(|h| format!("hint: {h}")).collect();
    Report::new(severity(d.severity))
        .with_message(d.message.clone())
        .with_labels(labels)
        .with_notes(notes)
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

/// Where a front end's argument starts when it is resolved against a scene and its spans
/// follow the scene's (`linearize --about`): a byte past the scene's end, so that no offset
/// points into both.
pub fn argument_start(source: &str) -> usize {
    source.len() + 1
}

/// Writes diagnostics whose spans point into the scene `source` (named `path`) or, from
/// [`argument_start`] on, into a front end's `argument` (named as the front end spells it:
/// `--about`); one diagnostic may point into both.
pub fn emit_with_argument(
    out: &mut dyn WriteColor,
    (path, source): (&str, &str),
    (name, argument): (&str, &str),
    diagnostics: &[Diagnostic],
) {
    let mut files = SimpleFiles::new();
    let scene = files.add(path, source);
    let given = files.add(name, argument);
    let start = argument_start(source);
    // Each span in the text it points into, clamped there.
    let place = |s: Span| -> (usize, std::ops::Range<usize>) {
        let (file, base, len) = if s.start >= start {
            (given, start, argument.len())
        } else {
            (scene, 0, source.len())
        };
        let from = (s.start - base).min(len);
        (file, from..(s.end.saturating_sub(base)).min(len).max(from))
    };
    let config = Config::default();
    for d in diagnostics {
        let (file, range) = place(d.span);
        let mut labels = vec![Label::primary(file, range).with_message(d.label.clone())];
        for (span, text) in &d.related {
            let (file, range) = place(*span);
            labels.push(Label::secondary(file, range).with_message(text.clone()));
        }
        let notes = d.hint.iter().map(|h| format!("hint: {h}")).collect();
        let report = Report::new(severity(d.severity))
            .with_message(d.message.clone())
            .with_labels(labels)
            .with_notes(notes);
        // As in `emit`: a failure to write has nowhere better to go.
        let _ = term::emit(out, &config, &files, &report);
    }
}

/// [`emit_with_argument`] as plain text.
pub fn render_with_argument(
    scene: (&str, &str),
    argument: (&str, &str),
    diagnostics: &[Diagnostic],
) -> String {
    let mut buffer = Buffer::no_color();
    emit_with_argument(&mut buffer, scene, argument, diagnostics);
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
    fn an_argument_after_the_scene_is_rendered_against_itself() {
        let source = "coord x\nlinearize about x = 0\n";
        let start = argument_start(source);
        let d = Diagnostic::error(Span::new(start + 4, start + 5), "off the rod")
            .with_label("here")
            .with_related(Span::new(0, 7), "declared");
        let text = render_with_argument(("s.lag", source), ("--about", "x = 2"), &[d]);
        assert!(text.contains("--about:1:5"), "{text}");
        assert!(text.contains("s.lag:1:1"), "{text}");
        assert!(text.contains("1 │ x = 2"), "{text}");
    }

    #[test]
    fn spans_past_the_end_are_clamped() {
        let d = Diagnostic::error(Span::new(50, 60), "past the end");
        assert!(render("f", "ab", &[d]).contains("past the end"));
    }
}
