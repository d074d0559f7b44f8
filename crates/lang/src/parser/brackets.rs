//! The bracket pre-scan: finds unbalanced and too deeply nested brackets before pest sees the
//! text, and reports them.

use super::MAX_BRACKET_DEPTH;
use crate::ast::Span;
use crate::diag::Diagnostic;

/// A bracket problem found by [`scan_brackets`].
#[derive(Debug)]
pub(super) enum BracketProblem {
    /// An opening bracket never closed: its offset and character.
    Unclosed(usize, char),
    /// A closing bracket that does not match the innermost open one.
    Mismatched { close: (usize, char), open: (usize, char) },
    /// A closing bracket with nothing open.
    Stray(usize, char),
}

pub(super) struct BracketScan {
    pub(super) too_deep: Option<Diagnostic>,
    pub(super) problems: Vec<BracketProblem>,
}

/// Walks the brackets outside comments and strings, the way the grammar sees them.
pub(super) fn scan_brackets(source: &str) -> BracketScan {
    let mut stack: Vec<(usize, char)> = Vec::new();
    let mut problems = Vec::new();
    let mut chars = source.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '#' => {
                // A comment runs to the end of the line.
                while chars.next_if(|&(_, c)| c != '\n' && c != '\r').is_some() {}
            }
            '"' => {
                // A string runs to the closing quote or the end of the line; `\` escapes.
                while let Some((_, c)) = chars.next_if(|&(_, c)| c != '\n' && c != '\r') {
                    match c {
                        '"' => break,
                        '\\' => {
                            chars.next_if(|&(_, c)| c != '\n' && c != '\r');
                        }
                        _ => {}
                    }
                }
            }
            '(' | '[' | '{' => {
                stack.push((i, c));
                if stack.len() > MAX_BRACKET_DEPTH {
                    let diag = Diagnostic::error(
                        Span::new(i, i + 1),
                        format!("nesting too deep (over {MAX_BRACKET_DEPTH} levels)"),
                    )
                    .with_label("this bracket is one level too many")
                    .with_hint("split the expression with `let` names");
                    return BracketScan { too_deep: Some(diag), problems };
                }
            }
            ')' | ']' | '}' => match stack.pop() {
                Some((_, open)) if closer(open) == c => {}
                Some(open) => problems.push(BracketProblem::Mismatched { close: (i, c), open }),
                None => problems.push(BracketProblem::Stray(i, c)),
            },
            _ => {}
        }
    }
    problems.extend(stack.into_iter().map(|(i, c)| BracketProblem::Unclosed(i, c)));
    BracketScan { too_deep: None, problems }
}

fn closer(open: char) -> char {
    match open {
        '(' => ')',
        '[' => ']',
        _ => '}',
    }
}

fn opener(close: char) -> char {
    match close {
        ')' => '(',
        ']' => '[',
        _ => '{',
    }
}

pub(super) fn bracket_diagnostics(source: &str, problems: &[BracketProblem]) -> Vec<Diagnostic> {
    problems
        .iter()
        .map(|problem| match *problem {
            BracketProblem::Unclosed(at, open) => {
                let close = closer(open);
                // `(` and `[` are almost always meant to close on their own line; a `{` block
                // may span lines, so its closing brace is missing at the end of the file.
                let expected_at =
                    if open == '{' { source.len() } else { line_content_end(source, at) };
                Diagnostic::error(
                    Span::new(expected_at, expected_at),
                    format!("unclosed `{open}`: expected a closing `{close}`"),
                )
                .with_label(format!("expected `{close}` here"))
                .with_related(Span::new(at, at + 1), format!("this `{open}` is never closed"))
                .with_hint(format!("add the missing `{close}`"))
            }
            BracketProblem::Mismatched { close: (at, close), open: (open_at, open) } => {
                Diagnostic::error(
                    Span::new(at, at + 1),
                    format!("mismatched `{close}`: the innermost open bracket is `{open}`"),
                )
                .with_label(format!("expected `{}` here", closer(open)))
                .with_related(
                    Span::new(open_at, open_at + 1),
                    format!("this `{open}` is still open"),
                )
                .with_hint(format!("close `{open}` with `{}`", closer(open)))
            }
            BracketProblem::Stray(at, close) => Diagnostic::error(
                Span::new(at, at + 1),
                format!("unexpected `{close}`: there is no `{}` to close", opener(close)),
            )
            .with_label("no matching opening bracket")
            .with_hint(format!("remove this `{close}` or add the `{}` it closes", opener(close))),
        })
        .collect()
}

/// The end of the code on the line containing `at`: before a comment and trailing blanks.
fn line_content_end(source: &str, at: usize) -> usize {
    let line_end = source[at..].find(['\n', '\r']).map_or(source.len(), |n| at + n);
    let line = &source[at..line_end];
    // A `#` inside a string would fool this, but the bracket is what matters here.
    let code = line.find('#').map_or(line, |n| &line[..n]);
    at + code.trim_end().len()
}
