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
        // The scene's and the argument's diagnostics, each against its own text.
        engine::Error::WithArgument { diagnostics, source, setting, argument } => {
            let name = format!("--{}", setting.name());
            lang::render::render_with_argument((path, source), (&name, argument), diagnostics)
        }
        // An expression given besides the scene, rendered against itself.
        engine::Error::Expression { diagnostics, text } => render("expression", text, diagnostics),
        engine::Error::Setting(_) => format!("error: {}\n", error.worded(flag)),
        other => format!("{other}\n"),
    }
}

/// A setting as the command line spells it: `--set gg`.
fn flag(piece: &engine::Piece) -> String {
    match piece {
        engine::Piece::Text(text) => text.clone(),
        engine::Piece::Setting(s) => format!("--{}", s.name()),
        // Quoted when the shell would split it, as a user would type it.
        engine::Piece::Given(s, given) if given.contains([' ', '\'']) => {
            format!("--{} '{given}'", s.name())
        }
        engine::Piece::Given(s, given) => format!("--{} {given}", s.name()),
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
