//! Renders diagnostics the way compilers do: file, line, column, the source line, a caret
//! under the culprit, and a hint.

use codespan_reporting::diagnostic::{Diagnostic as Report, Label, Severity as ReportSeverity};
use codespan_reporting::files::SimpleFile;
use codespan_reporting::term::{self, Config};
use lang::{Diagnostic, Severity, Span};
use termcolor::{Buffer, ColorChoice, StandardStream, WriteColor};

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

fn clamp(d: &Diagnostic, len: usize) -> Diagnostic {
    let fix = |s: Span| Span::new(s.start.min(len), s.end.min(len).max(s.start.min(len)));
    let mut d = d.clone();
    d.span = fix(d.span);
    d.related = d.related.iter().map(|(s, t)| (fix(*s), t.clone())).collect();
    d
}

fn emit(out: &mut dyn WriteColor, path: &str, source: &str, diagnostics: &[Diagnostic]) {
    let file = SimpleFile::new(path, source);
    let config = Config::default();
    for d in diagnostics {
        let d = clamp(d, source.len());
        // Rendering into memory or a terminal; a failure there has nowhere better to go.
        let _ = term::emit(out, &config, &file, &to_report(&d));
    }
}

/// The diagnostics as plain text (for tests and files).
pub fn render(path: &str, source: &str, diagnostics: &[Diagnostic]) -> String {
    let mut buffer = Buffer::no_color();
    emit(&mut buffer, path, source, diagnostics);
    String::from_utf8_lossy(buffer.as_slice()).into_owned()
}

/// An engine error as text: a scene's diagnostics rendered against the text they point into,
/// anything else as its message, each ending in a newline.
pub fn error(path: &str, error: &engine::Error) -> String {
    match error {
        engine::Error::Scene { diagnostics, source } => render(path, source, diagnostics),
        other => format!("{other}\n"),
    }
}

/// Writes the diagnostics to standard error, in colour when it is a terminal.
pub fn eprint(path: &str, source: &str, diagnostics: &[Diagnostic]) {
    use std::io::IsTerminal;
    let choice =
        if std::io::stderr().is_terminal() { ColorChoice::Auto } else { ColorChoice::Never };
    let mut stream = StandardStream::stderr(choice);
    emit(&mut stream, path, source, diagnostics);
}
