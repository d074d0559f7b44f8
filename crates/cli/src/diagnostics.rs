//! Shows diagnostics on the terminal and engine errors as text; the rendering itself is
//! `lang::render`'s, shared with the other front ends.

use lang::Diagnostic;
use termcolor::{ColorChoice, StandardStream};

pub use lang::render::render;

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
    lang::render::emit(&mut stream, path, source, diagnostics);
}
