//! What can go wrong between a scene and its numbers, typed: the scene's own diagnostics,
//! input that makes no sense, or a numeric fault. A front end renders them and exits with
//! [`Error::exit_code`].

use std::fmt;

use lang::{Diagnostic, Severity};

/// Why a front end's request could not be carried out.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// The scene has errors: its diagnostics, with the text their spans point into, the
    /// scene's as loaded.
    Scene { diagnostics: Vec<Diagnostic>, source: String },
    /// Errors of the scene with a front end's argument resolved against it (`linearize
    /// --about`): spans before [`lang::render::argument_start`] of `source` point into the
    /// scene, spans from it on into `argument`, the text given for `setting`.
    WithArgument {
        diagnostics: Vec<Diagnostic>,
        source: String,
        setting: Setting,
        argument: String,
    },
    /// An expression given besides the scene (a front end's output, event or value, or one of
    /// the scene's `simulate` block) has errors: its diagnostics, with the expression their
    /// spans point into.
    Expression { diagnostics: Vec<Diagnostic>, text: String },
    /// A setting, option or value that cannot be used: what is wrong with it.
    Input(String),
    /// A front end's setting that cannot be used, in words that name the settings abstractly
    /// so that each front end can word them as its users write them ([`Error::worded`]).
    Setting(Vec<Piece>),
    /// The numbers went wrong (a run that should have finished faulted): what happened.
    Numeric(String),
}

impl Error {
    /// The exit code of a command that failed this way: 2 for bad input (the scene's errors
    /// included), 1 for a numeric fault.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Scene { .. }
            | Error::WithArgument { .. }
            | Error::Expression { .. }
            | Error::Input(_)
            | Error::Setting(_) => 2,
            Error::Numeric(_) => 1,
        }
    }
}

/// One line per problem, `error: …`; a scene's diagnostics with their line and column but
/// without the source context a front end may add.
impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Scene { diagnostics, source: text }
            | Error::Expression { diagnostics, text } => {
                let source = text;
                for (k, d) in diagnostics.iter().enumerate() {
                    let (line, col) = line_col(source, d.span.start);
                    let severity = severity_word(d.severity);
                    if k > 0 {
                        writeln!(f)?;
                    }
                    write!(f, "{severity}: {} (line {line}, column {col})", d.message)?;
                }
                Ok(())
            }
            Error::WithArgument { diagnostics, source, setting, argument } => {
                let start = lang::render::argument_start(source);
                for (k, d) in diagnostics.iter().enumerate() {
                    let severity = severity_word(d.severity);
                    if k > 0 {
                        writeln!(f)?;
                    }
                    let at = match d.span.start.checked_sub(start) {
                        Some(offset) => {
                            let (_, col) = line_col(argument, offset);
                            format!("column {col} of `{}`", setting.name())
                        }
                        None => {
                            let (line, col) = line_col(source, d.span.start);
                            format!("line {line}, column {col}")
                        }
                    };
                    write!(f, "{severity}: {} ({at})", d.message)?;
                }
                Ok(())
            }
            Error::Input(message) | Error::Numeric(message) => write!(f, "error: {message}"),
            Error::Setting(_) => write!(f, "error: {}", self.worded(Piece::plain)),
        }
    }
}

fn severity_word(severity: Severity) -> &'static str {
    match severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
    }
}

/// A setting of a run or a linearization as a front end takes it: `--until` on the command
/// line, the keyword `until` in Python. Errors name it and leave the words to the front end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Setting {
    Until,
    Tolerance,
    Step,
    /// Values in place of the scene's, `name=value`.
    Set,
    Sweep,
    About,
    /// An input driven in a run, `name=expression`.
    Input,
    /// The period of the zero-order hold of the inputs driven by laws.
    Hold,
    /// A parameter an ensemble varies, `name=a:b:n` or a distribution.
    Vary,
    /// The number of an ensemble's random draws.
    Runs,
    /// The number of evenly spaced times a run records.
    Samples,
}

impl Setting {
    /// The plain name: a command line prefixes `--`, Python takes it as a keyword.
    pub fn name(self) -> &'static str {
        match self {
            Setting::Until => "until",
            Setting::Tolerance => "tolerance",
            Setting::Step => "step",
            Setting::Set => "set",
            Setting::Sweep => "sweep",
            Setting::About => "about",
            Setting::Input => "input",
            Setting::Hold => "hold",
            Setting::Vary => "vary",
            Setting::Runs => "runs",
            Setting::Samples => "samples",
        }
    }
}

/// A piece of an [`Error::Setting`]'s text.
#[derive(Clone, Debug, PartialEq)]
pub enum Piece {
    Text(String),
    /// A setting by its name.
    Setting(Setting),
    /// A setting with what it was given: the name it sets (`--set gg`), the sweep it was
    /// asked for (`--sweep w=0:1:2`), the reference (`--about theta=0`).
    Given(Setting, String),
}

impl Piece {
    /// Words for a reader who knows neither front end: the setting's name in backticks.
    pub fn plain(&self) -> String {
        match self {
            Piece::Text(text) => text.clone(),
            Piece::Setting(s) => format!("`{}`", s.name()),
            Piece::Given(s, given) => format!("`{}` {given}", s.name()),
        }
    }
}

impl Error {
    /// `setting` followed by `rest`: "`until` must be positive".
    pub fn setting(setting: Setting, rest: impl Into<String>) -> Error {
        Error::Setting(vec![Piece::Setting(setting), Piece::Text(rest.into())])
    }

    /// `setting` with what it was given, then `rest`: "`set` gg: no parameter …".
    pub fn given(setting: Setting, given: impl Into<String>, rest: impl Into<String>) -> Error {
        Error::Setting(vec![Piece::Given(setting, given.into()), Piece::Text(rest.into())])
    }

    /// The text of an [`Error::Setting`] with each setting in `word`'s words; the message of
    /// any other error as it is (a scene's diagnostics as [`fmt::Display`] shows them).
    pub fn worded(&self, word: impl Fn(&Piece) -> String) -> String {
        match self {
            Error::Setting(pieces) => pieces.iter().map(word).collect(),
            Error::Input(message) | Error::Numeric(message) => message.clone(),
            Error::Scene { .. } | Error::WithArgument { .. } | Error::Expression { .. } => {
                self.to_string()
            }
        }
    }
}

impl std::error::Error for Error {}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let before = &source[..offset];
    let line = before.matches('\n').count() + 1;
    let col =
        before.rfind('\n').map_or(before.chars().count(), |i| before[i + 1..].chars().count()) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_and_messages() {
        let input = Error::Input("`until` must be positive".into());
        assert_eq!(input.exit_code(), 2);
        assert_eq!(input.to_string(), "error: `until` must be positive");
        assert_eq!(Error::Numeric("the reference run failed".into()).exit_code(), 1);
        let setting = Error::Setting(vec![
            Piece::Given(Setting::Set, "gg".into()),
            Piece::Text(": no parameter of that name".into()),
        ]);
        assert_eq!(setting.exit_code(), 2);
        assert_eq!(setting.to_string(), "error: `set` gg: no parameter of that name");
        let flags = |p: &Piece| match p {
            Piece::Given(s, given) => format!("--{} {given}", s.name()),
            other => other.plain(),
        };
        assert_eq!(setting.worded(flags), "--set gg: no parameter of that name");
        let d = Diagnostic::error(lang::Span::new(8, 9), "unknown name `y`");
        let scene = Error::Scene { diagnostics: vec![d], source: "coord x\ny\n".into() };
        assert_eq!(scene.exit_code(), 2);
        assert_eq!(scene.to_string(), "error: unknown name `y` (line 2, column 1)");
    }

    #[test]
    fn line_and_column_count_characters() {
        assert_eq!(line_col("ab\nθx", 5), (2, 2));
        assert_eq!(line_col("ab", 99), (1, 3));
    }
}
