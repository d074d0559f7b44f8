//! The parser: runs the pest grammar of `grammar/scene.pest` and turns its pairs into the spanned
//! AST of [`crate::ast`], or into diagnostics a user can act on.
//!
//! The work is split in three:
//! 1. a cheap pre-scan of brackets, which catches unbalanced and absurdly deep nesting before pest
//!    sees the text (pest recurses once per bracket level and would overflow the stack);
//! 2. pest, restarted at the next statement line after each syntax error so that independent
//!    mistakes are all reported;
//! 3. the AST builder, which also checks what the grammar cannot (primes on a `coord` rate, …).

use std::sync::LazyLock;

use pest::error::{ErrorVariant, InputLocation};
use pest::iterators::Pair;
use pest::pratt_parser::{Assoc, Op, PrattParser};
use pest::Parser as _;
use pest_derive::Parser;

use crate::ast::*;
use crate::diag::Diagnostic;

#[derive(Parser)]
#[grammar = "../../grammar/scene.pest"]
struct SceneParser;

/// Deepest bracket nesting the pre-scan lets through to pest.
const MAX_BRACKET_DEPTH: usize = 256;
/// Deepest expression tree the builder accepts; later stages recurse over expressions, so the
/// AST must stay shallow enough for them too.
const MAX_EXPR_DEPTH: usize = 1000;

/// The operator rules of expressions.
const PRATT_OPERATORS: [Rule; 6] =
    [Rule::add_op, Rule::sub_op, Rule::mul_op, Rule::div_op, Rule::pow_op, Rule::neg_op];

/// The statement keywords, in the order they are listed to the user.
pub(crate) const STATEMENT_KEYWORDS: [&str; 20] = [
    "scene",
    "param",
    "let",
    "coord",
    "particle",
    "body",
    "constraint",
    "gravity",
    "potential",
    "force",
    "torque",
    "spring",
    "damper",
    "dissipation",
    "lagrangian",
    "show",
    "expect",
    "simulate",
    "linearize",
    "draw",
];

/// Operator precedence, loosest first: `+ -` < `* /` < unary `-` < `^` (right associative).
static PRATT: LazyLock<PrattParser<Rule>> = LazyLock::new(|| {
    PrattParser::new()
        .op(Op::infix(Rule::add_op, Assoc::Left) | Op::infix(Rule::sub_op, Assoc::Left))
        .op(Op::infix(Rule::mul_op, Assoc::Left) | Op::infix(Rule::div_op, Assoc::Left))
        .op(Op::prefix(Rule::neg_op))
        .op(Op::infix(Rule::pow_op, Assoc::Right))
});

/// Parses a whole scene file.
///
/// On failure, returns every error found: syntax errors (at most one per statement, the parser
/// resumes at the next line that starts with a statement keyword) and the structural checks of
/// the AST builder.
pub fn parse(source: &str) -> Result<SceneFile, Vec<Diagnostic>> {
    // pest's generated code recurses several frames per bracket level, and unoptimised builds
    // use large frames: the 256 levels the pre-scan lets through need a few MB of stack, more
    // than a test thread's 2 MB. So parse on a thread of our own with room to spare.
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("lang-parser".into())
            .stack_size(PARSER_STACK_SIZE)
            .spawn_scoped(scope, || parse_here(source));
        match spawned {
            Ok(handle) => handle.join().unwrap_or_else(|_| {
                Err(vec![Diagnostic::error(Span::default(), "internal error: the parser crashed")])
            }),
            // No thread to be had: parse here, which is fine unless the nesting is extreme.
            Err(_) => parse_here(source),
        }
    })
}

/// Parses one expression on its own (a front end's argument such as `--output theta'`); spans
/// point into `text`.
pub fn parse_expression(text: &str) -> Result<Expr, Vec<Diagnostic>> {
    parse_lone(text, Rule::lone_expr, |builder, pair| {
        let expr = pair.into_inner().find(|p| p.as_rule() == Rule::expr);
        match expr {
            Some(expr) => builder.expr(expr),
            None => Err(Diagnostic::error(Span::default(), "expected an expression")),
        }
    })
}

/// Parses the items of a reference on their own (`--about "theta = 0, phi' = 2"`), as a
/// `linearize about` line has them; spans point into `text`.
pub fn parse_about(text: &str) -> Result<Vec<AboutItem>, Vec<Diagnostic>> {
    parse_lone(text, Rule::lone_about, |builder, pair| {
        let mut items = Vec::new();
        for item in pair.into_inner().filter(|p| p.as_rule() == Rule::about_item) {
            items.push(builder.about_item(item)?);
        }
        Ok(items)
    })
}

/// A piece of text by one rule of the grammar, built by `build`, with the checks of [`parse`].
fn parse_lone<T: Send>(
    text: &str,
    rule: Rule,
    build: impl Fn(&Builder<'_>, Pair<'_, Rule>) -> Built<T> + Send + Sync,
) -> Result<T, Vec<Diagnostic>> {
    let here = || {
        let scan = scan_brackets(text);
        if let Some(too_deep) = scan.too_deep {
            return Err(vec![too_deep]);
        }
        if !scan.problems.is_empty() {
            return Err(bracket_diagnostics(text, &scan.problems));
        }
        let mut pairs = match SceneParser::parse(rule, text) {
            Ok(pairs) => pairs,
            Err(err) => return Err(vec![syntax_error(text, 0, &err).1]),
        };
        let mut diags = Vec::new();
        let built = {
            let builder = Builder { base: 0, diags: &mut diags };
            let Some(pair) = pairs.next() else {
                return Err(vec![Diagnostic::error(Span::default(), "expected an expression")]);
            };
            build(&builder, pair)
        };
        match built {
            Ok(value) if diags.is_empty() => Ok(value),
            Ok(_) => Err(diags),
            Err(d) => {
                diags.push(d);
                Err(diags)
            }
        }
    };
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("lang-parser".into())
            .stack_size(PARSER_STACK_SIZE)
            .spawn_scoped(scope, here);
        match spawned {
            Ok(handle) => handle.join().unwrap_or_else(|_| {
                Err(vec![Diagnostic::error(Span::default(), "internal error: the parser crashed")])
            }),
            Err(_) => here(),
        }
    })
}

/// Stack for the parser thread: ample for [`MAX_BRACKET_DEPTH`] levels even in a debug build.
const PARSER_STACK_SIZE: usize = 64 * 1024 * 1024;

/// [`parse`], on the current thread's stack.
fn parse_here(source: &str) -> Result<SceneFile, Vec<Diagnostic>> {
    let scan = scan_brackets(source);
    if let Some(too_deep) = scan.too_deep {
        return Err(vec![too_deep]);
    }
    if !scan.problems.is_empty() {
        return Err(bracket_diagnostics(source, &scan.problems));
    }

    let mut diags = Vec::new();
    let mut stmts = Vec::new();
    let mut offset = 0;
    loop {
        match SceneParser::parse(Rule::file, &source[offset..]) {
            Ok(mut pairs) => {
                let builder = Builder { base: offset, diags: &mut diags };
                if let Some(file) = pairs.next() {
                    builder.file(file, &mut stmts);
                }
                break;
            }
            Err(err) => {
                let (pos, diag) = syntax_error(source, offset, &err);
                diags.push(diag);
                match next_statement_line(source, pos) {
                    Some(next) => offset = next,
                    None => break,
                }
            }
        }
    }
    if diags.is_empty() {
        Ok(SceneFile { stmts })
    } else {
        Err(diags)
    }
}

// ---------------------------------------------------------------------------------------------
// Bracket pre-scan

/// A bracket problem found by [`scan_brackets`].
#[derive(Debug)]
enum BracketProblem {
    /// An opening bracket never closed: its offset and character.
    Unclosed(usize, char),
    /// A closing bracket that does not match the innermost open one.
    Mismatched { close: (usize, char), open: (usize, char) },
    /// A closing bracket with nothing open.
    Stray(usize, char),
}

struct BracketScan {
    too_deep: Option<Diagnostic>,
    problems: Vec<BracketProblem>,
}

/// Walks the brackets outside comments and strings, the way the grammar sees them.
fn scan_brackets(source: &str) -> BracketScan {
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

fn bracket_diagnostics(source: &str, problems: &[BracketProblem]) -> Vec<Diagnostic> {
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

// ---------------------------------------------------------------------------------------------
// Syntax errors

/// The offset of the first line after `pos` that starts with a statement keyword.
fn next_statement_line(source: &str, pos: usize) -> Option<usize> {
    let mut line_start = source[pos..].find('\n').map(|n| pos + n + 1)?;
    loop {
        let rest = &source[line_start..];
        let trimmed = rest.trim_start_matches([' ', '\t']);
        let word = leading_word(trimmed);
        if STATEMENT_KEYWORDS.contains(&word) {
            return Some(line_start);
        }
        line_start += rest.find('\n')? + 1;
    }
}

/// The name-like word at the start of `text` (empty if none).
fn leading_word(text: &str) -> &str {
    let end = text
        .char_indices()
        .find(|&(i, c)| !(c.is_alphanumeric() || c == '_') || (i == 0 && c.is_ascii_digit()))
        .map_or(text.len(), |(i, _)| i);
    &text[..end]
}

/// The number or name at the start of `text`, or its first character.
fn leading_token(text: &str) -> &str {
    let word = if text.starts_with(|c: char| c.is_ascii_digit()) {
        let end = text
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
            .unwrap_or(text.len());
        &text[..end]
    } else {
        leading_word(text)
    };
    if word.is_empty() {
        text.chars().next().map_or("", |c| &text[..c.len_utf8()])
    } else {
        word
    }
}

/// A user-facing name for what a rule stands for, with its rank in the "expected" list.
fn friendly(rule: Rule) -> Option<(u8, &'static str)> {
    use Rule::*;
    Some(match rule {
        kw_scene | kw_param | kw_let | kw_coord | kw_particle | kw_body | kw_constraint
        | kw_gravity | kw_potential | kw_force | kw_torque | kw_spring | kw_damper
        | kw_dissipation | kw_lagrangian | kw_show | kw_expect | kw_simulate | kw_linearize
        | kw_draw => (0, "a statement"),
        kw_line | kw_circle | kw_polyline => (2, "a shape (`line`, `circle` or `polyline`)"),
        expr | number | call | func | member | name | paren | matrix | matrix_row | neg_op => {
            (1, "an expression")
        }
        ident | coord_name | param_item | coord_item | about_item => (2, "a name"),
        property => (2, "a property such as `mass m`"),
        setting => (2, "a setting such as `until 2 s`"),
        unit | unit_factor | unit_one => (3, "a unit"),
        unit_power => (3, "an integer power"),
        string | quote => (3, "a quoted title like \"A title\""),
        string_text => (3, "the text of the title"),
        kw_along => (4, "`along`"),
        kw_about => (4, "`about`"),
        kw_on => (4, "`on`"),
        kw_between => (4, "`between`"),
        kw_and => (4, "`and`"),
        kw_from => (4, "`from`"),
        kw_to => (4, "`to`"),
        kw_radius => (4, "`radius`"),
        at_start | kw_at => (4, "`at start:`"),
        kw_start => (4, "`start`"),
        add_op | sub_op | mul_op | div_op | pow_op => (5, "an operator"),
        eq => (6, "`=`"),
        near => (6, "`~`"),
        colon => (6, "`:`"),
        lparen => (6, "`(`"),
        lbracket => (6, "`[`"),
        lbrace => (6, "`{`"),
        comma => (7, "`,`"),
        semicolon => (7, "`;`"),
        rparen => (8, "a closing `)`"),
        rbracket => (8, "a closing `]`"),
        rbrace => (8, "a closing `}`"),
        EOI => (9, "end of line"),
        _ => return None,
    })
}

/// Whether pest, failing on `rule`, was looking for the start of a statement. pest reports the
/// outermost rule that failed where it started: a statement rule, or `file` on the first line.
fn is_statement_start(rule: Rule) -> bool {
    use Rule::*;
    is_statement_keyword(rule)
        || matches!(
            rule,
            file | scene_stmt
                | param_stmt
                | let_stmt
                | coord_stmt
                | particle_stmt
                | body_stmt
                | constraint_stmt
                | gravity_stmt
                | potential_stmt
                | force_stmt
                | torque_stmt
                | dissipation_stmt
                | lagrangian_stmt
                | show_stmt
                | expect_stmt
                | simulate_stmt
                | linearize_stmt
                | draw_stmt
        )
}

fn is_statement_keyword(rule: Rule) -> bool {
    use Rule::*;
    matches!(
        rule,
        kw_scene
            | kw_param
            | kw_let
            | kw_coord
            | kw_particle
            | kw_body
            | kw_constraint
            | kw_spring
            | kw_damper
            | kw_gravity
            | kw_potential
            | kw_force
            | kw_torque
            | kw_dissipation
            | kw_lagrangian
            | kw_show
            | kw_expect
            | kw_simulate
            | kw_linearize
            | kw_draw
    )
}

/// "a, b or c"
fn or_list(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).to_string(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// Turns a pest error (from parsing `source[offset..]`) into a diagnostic; returns the absolute
/// error position too.
fn syntax_error(
    source: &str,
    offset: usize,
    err: &pest::error::Error<Rule>,
) -> (usize, Diagnostic) {
    let pos = offset
        + match err.location {
            InputLocation::Pos(p) => p,
            InputLocation::Span((p, _)) => p,
        };
    let positives = match &err.variant {
        ErrorVariant::ParsingError { positives, .. } => positives.as_slice(),
        ErrorVariant::CustomError { message } => {
            // pest's own limits (call or stack limit); not expected with the pre-scan.
            return (pos, Diagnostic::error(Span::new(pos, pos), message.clone()));
        }
    };
    (pos, describe_syntax_error(source, pos, positives))
}

fn describe_syntax_error(source: &str, pos: usize, positives: &[Rule]) -> Diagnostic {
    let rest = &source[pos..];
    let found_token = leading_token(rest);
    let found = if rest.is_empty() {
        "end of file".to_string()
    } else if rest.starts_with(['\n', '\r']) {
        "end of line".to_string()
    } else {
        format!("`{found_token}`")
    };
    let span = Span::new(pos, pos + found_token.len().min(rest.len()));

    // At the start of a statement: an unknown keyword, probably misspelt.
    if positives.iter().any(|&r| is_statement_start(r)) {
        let word = leading_word(rest);
        let list = format!("a statement starts with one of: {}", STATEMENT_KEYWORDS.join(", "));
        return if word.is_empty() {
            Diagnostic::error(span, format!("expected a statement, found {found}"))
                .with_label("expected a statement keyword")
                .with_hint(list)
        } else {
            let hint = match nearest_keyword(word) {
                Some(kw) => format!("did you mean `{kw}`? ({list})"),
                None => list,
            };
            Diagnostic::error(span, format!("unknown statement `{word}`"))
                .with_label("not a statement keyword")
                .with_hint(hint)
        };
    }

    let mut expected: Vec<(u8, &str)> = positives.iter().filter_map(|&r| friendly(r)).collect();
    expected.sort();
    expected.dedup();
    let names: Vec<&str> = expected.iter().map(|&(_, n)| n).collect();
    let message = if names.is_empty() {
        format!("unexpected {found}")
    } else {
        format!("expected {}, found {found}", or_list(&names))
    };
    let label = match names.first() {
        Some(first) => format!("expected {first}"),
        None => "unexpected".to_string(),
    };
    let mut diag = Diagnostic::error(span, message).with_label(label);

    let wants_operator = positives.iter().any(|r| {
        matches!(r, Rule::add_op | Rule::sub_op | Rule::mul_op | Rule::div_op | Rule::pow_op)
    });
    let line_start = source[..pos].rfind('\n').map_or(0, |n| n + 1);
    let mut statement = source[line_start..pos].split_whitespace();
    let in_polyline = statement.next() == Some("draw") && statement.next() == Some("polyline");
    if positives.contains(&Rule::kw_line) {
        diag =
            diag.with_hint("draw `line from A to B`, `circle at C radius r` or `polyline A, B, C`");
    } else if in_polyline && positives.contains(&Rule::comma) {
        diag = diag.with_hint("a polyline joins two points or more: `draw polyline A, B, C`");
    } else if positives.contains(&Rule::semicolon) && rest.starts_with(',') {
        diag = diag.with_hint("separate the items of a block with `;` or a new line");
    } else if wants_operator {
        let unit_allowed = positives.iter().any(|r| matches!(r, Rule::unit | Rule::unit_factor));
        if let Some(hint) = juxtaposition_hint(source, pos, unit_allowed) {
            diag = diag.with_hint(hint);
        }
    }
    diag
}

/// When two operands stand side by side (`2x`, `2 theta`, `sin (x)`), how to write it.
/// `unit_allowed` says whether a unit could have stood at `pos` (after the value of a `param`
/// or `coord` item or a `simulate` setting): the second token may have been meant as a unit.
fn juxtaposition_hint(source: &str, pos: usize, unit_allowed: bool) -> Option<String> {
    let rest = &source[pos..];
    let next = rest.chars().next()?;
    if !(next.is_alphanumeric() || next == '_' || next == '(' || next == '[') {
        return None;
    }
    let right = if next == '(' || next == '[' { &rest[..1] } else { leading_token(rest) };

    // The operand just before, skipping blanks: a name or number (with primes), or a bracket.
    let before = source[..pos].trim_end_matches([' ', '\t']);
    let last = before.chars().next_back()?;
    let left_start = if last == ')' || last == ']' {
        before.len() - 1
    } else if last.is_alphanumeric() || last == '_' || last == '\'' || last == '.' {
        before
            .char_indices()
            .rev()
            .take_while(|&(_, c)| c.is_alphanumeric() || c == '_' || c == '\'' || c == '.')
            .last()
            .map_or(before.len(), |(i, _)| i)
    } else {
        return None;
    };
    let left = &before[left_start..];
    let written = &source[left_start..pos + right.len()];
    let is_name = left.starts_with(|c: char| c.is_alphabetic() || c == '_');
    if next == '(' && is_name && !left.contains('\'') {
        Some(format!(
            "to call `{left}`, write `{left}(` with no space; to multiply, write `{left}*(`"
        ))
    } else if !unit_allowed && is_value(left) && looks_like_unit(rest) {
        // `let h = 2 m`: "write `2*m`" alone would hide that units are not allowed here.
        Some(format!(
            "to multiply, write `{left}*{right}`; a unit may follow only the value of a `param` \
             or `coord` item or a `simulate` setting"
        ))
    } else if unit_allowed && next.is_ascii_digit() {
        // `param k = 1/2 1`: a unit was possible here, and a number is not one.
        Some(format!(
            "to multiply, write `{left}*{right}`; a unit after a value is a unit name such as \
             `kg` or `m/s^2`, or `1/` and one (`1/m`)"
        ))
    } else {
        Some(format!("write `{left}*{right}`, not `{written}`"))
    }
}

/// Whether an operand as written is a value a unit could follow: a number or a bracket.
fn is_value(operand: &str) -> bool {
    operand.starts_with(|c: char| c.is_ascii_digit()) || operand == ")"
}

/// Whether `text` starts with what reads as a unit: a unit name as a whole word, or `1/`.
fn looks_like_unit(text: &str) -> bool {
    if let Some(after_one) = text.strip_prefix('1') {
        return after_one.trim_start_matches([' ', '\t']).starts_with('/');
    }
    let word = leading_word(text);
    !word.is_empty() && UNIT_NAMES.contains(&word)
}

/// The statement keyword within edit distance 2 of `word`, if there is a clear nearest one.
fn nearest_keyword(word: &str) -> Option<&'static str> {
    let lower = word.to_lowercase();
    STATEMENT_KEYWORDS
        .iter()
        .map(|&kw| (strsim::levenshtein(&lower, kw), kw))
        .filter(|&(d, _)| d <= 2)
        .min_by_key(|&(d, _)| d)
        .map(|(_, kw)| kw)
}

// ---------------------------------------------------------------------------------------------
// AST builder

/// Builds AST nodes from pairs of a parse of `source[base..]`.
struct Builder<'d> {
    /// Offset of the parsed text in the whole source, added to every span.
    base: usize,
    /// Structural errors found while building.
    diags: &'d mut Vec<Diagnostic>,
}

type Built<T> = Result<T, Diagnostic>;

/// Punctuation and keywords: in the tree only so that errors can name them.
fn is_noise(rule: Rule) -> bool {
    use Rule::*;
    is_statement_keyword(rule)
        || matches!(
            rule,
            kw_along
                | kw_about
                | kw_on
                | kw_between
                | kw_and
                | kw_line
                | kw_circle
                | kw_polyline
                | kw_from
                | kw_to
                | kw_radius
                | kw_at
                | kw_start
                | eq
                | colon
                | comma
                | semicolon
                | lparen
                | rparen
                | lbracket
                | rbracket
                | lbrace
                | rbrace
                | quote
                | EOI
        )
}

/// The inner pairs that carry meaning.
fn parts(pair: Pair<'_, Rule>) -> impl Iterator<Item = Pair<'_, Rule>> {
    pair.into_inner().filter(|p| !is_noise(p.as_rule()))
}

/// The end of the last token inside `pair`. A rule that ends in an optional part may have
/// swallowed the blanks before it; its last token never does.
fn last_token_end(pair: &Pair<'_, Rule>) -> usize {
    match pair.clone().into_inner().last() {
        Some(last) => last_token_end(&last),
        None => pair.as_span().end(),
    }
}

impl Builder<'_> {
    /// The span of a pair's text, without trailing blanks.
    fn span(&self, pair: &Pair<'_, Rule>) -> Span {
        Span::new(self.base + pair.as_span().start(), self.base + last_token_end(pair))
    }

    fn ident(&self, pair: &Pair<'_, Rule>) -> Ident {
        Ident { name: pair.as_str().to_string(), span: self.span(pair) }
    }

    fn file(mut self, file: Pair<'_, Rule>, stmts: &mut Vec<Stmt>) {
        for pair in parts(file) {
            let span = self.span(&pair);
            match self.stmt(pair) {
                Ok(kind) => stmts.push(Stmt { kind, span }),
                Err(diag) => self.diags.push(diag),
            }
        }
    }

    fn stmt(&mut self, pair: Pair<'_, Rule>) -> Built<StmtKind> {
        let rule = pair.as_rule();
        let at_start = pair.clone().into_inner().any(|p| p.as_rule() == Rule::at_start);
        let mut items = parts(pair).filter(|p| p.as_rule() != Rule::at_start);
        // The grammar guarantees the shape of every statement; a missing part is a bug here,
        // reported as an error rather than a panic.
        let mut next = || {
            items.next().ok_or_else(|| {
                Diagnostic::error(Span::default(), "internal error: unexpected parse tree shape")
            })
        };
        Ok(match rule {
            Rule::scene_stmt => {
                let string = next()?;
                let text = parts(string).next().map_or("", |p| p.as_str());
                StmtKind::Scene { title: unescape(text) }
            }
            Rule::param_stmt => {
                let mut decls = Vec::new();
                while let Ok(item) = next() {
                    decls.push(self.param_item(item)?);
                }
                StmtKind::Param(decls)
            }
            Rule::let_stmt => {
                let name = self.ident(&next()?);
                StmtKind::Let { name, value: self.expr(next()?)? }
            }
            Rule::coord_stmt => {
                let mut items = Vec::new();
                while let Ok(item) = next() {
                    items.push(item);
                }
                StmtKind::Coord(self.coord_items(items)?)
            }
            Rule::particle_stmt | Rule::body_stmt => {
                let name = self.ident(&next()?);
                let mut props = Vec::new();
                while let Ok(prop) = next() {
                    let mut kv = parts(prop);
                    let (Some(key), Some(value)) = (kv.next(), kv.next()) else {
                        continue;
                    };
                    props.push(Property { key: self.ident(&key), value: self.expr(value)? });
                }
                if rule == Rule::particle_stmt {
                    StmtKind::Particle { name, props }
                } else {
                    StmtKind::Body { name, props }
                }
            }
            Rule::constraint_stmt => {
                let mut rest = Vec::new();
                while let Ok(p) = next() {
                    rest.push(p);
                }
                let name = match rest.first() {
                    Some(p) if p.as_rule() == Rule::ident => Some(self.ident(&rest.remove(0))),
                    _ => None,
                };
                let mut rest = rest.into_iter();
                let (Some(lhs), Some(rhs)) = (rest.next(), rest.next()) else {
                    return Err(Diagnostic::error(Span::default(), "internal error: constraint"));
                };
                StmtKind::Constraint { name, lhs: self.expr(lhs)?, rhs: self.expr(rhs)? }
            }
            Rule::gravity_stmt => {
                let strength = self.expr(next()?)?;
                let direction = match next() {
                    Ok(dir) => Some(self.expr(dir)?),
                    Err(_) => None,
                };
                StmtKind::Gravity { strength, direction }
            }
            Rule::potential_stmt => StmtKind::Potential(self.expr(next()?)?),
            Rule::dissipation_stmt => StmtKind::Dissipation(self.expr(next()?)?),
            Rule::lagrangian_stmt => StmtKind::Lagrangian(self.expr(next()?)?),
            Rule::spring_stmt | Rule::damper_stmt => {
                let name = self.ident(&next()?);
                let a = self.expr(next()?)?;
                let b = self.expr(next()?)?;
                let coefficient = self.expr(next()?)?;
                if rule == Rule::spring_stmt {
                    let rest = match next() {
                        Ok(p) => Some(self.expr(p)?),
                        Err(_) => None,
                    };
                    StmtKind::Spring { name, a, b, stiffness: coefficient, rest }
                } else {
                    StmtKind::Damper { name, a, b, coefficient }
                }
            }
            Rule::force_stmt | Rule::torque_stmt => {
                let name = self.ident(&next()?);
                let body = self.ident(&next()?);
                let first = self.expr(next()?)?;
                // `at P` comes before the value when it is given.
                let (at, value) = match next() {
                    Ok(p) => (Some(first), self.expr(p)?),
                    Err(_) => (None, first),
                };
                if rule == Rule::force_stmt {
                    StmtKind::Force { name, body, at, value }
                } else {
                    StmtKind::Torque { name, body, value }
                }
            }
            Rule::show_stmt => {
                let mut items = Vec::new();
                while let Ok(item) = next() {
                    items.push(self.expr(item)?);
                }
                StmtKind::Show { at_start, items }
            }
            Rule::expect_stmt => {
                let lhs = self.expr(next()?)?;
                let rhs = self.expr(next()?)?;
                StmtKind::Expect { at_start, lhs, rhs }
            }
            Rule::simulate_stmt => {
                let mut settings = Vec::new();
                while let Ok(setting) = next() {
                    settings.push(self.setting(setting)?);
                }
                StmtKind::Simulate(settings)
            }
            Rule::linearize_stmt => {
                let mut items = Vec::new();
                while let Ok(item) = next() {
                    items.push(self.about_item(item)?);
                }
                StmtKind::Linearize(items)
            }
            Rule::draw_stmt => StmtKind::Draw(self.shape(next()?)?),
            _ => {
                return Err(Diagnostic::error(Span::default(), "internal error: unknown statement"))
            }
        })
    }

    /// The shape of a `draw` line: its kind from the rule, its points as expressions.
    fn shape(&self, pair: Pair<'_, Rule>) -> Built<Shape> {
        let rule = pair.as_rule();
        let exprs = parts(pair).map(|p| self.expr(p)).collect::<Built<Vec<Expr>>>()?;
        let mut items = exprs.into_iter();
        let shape = match rule {
            Rule::draw_polyline => Some(Shape::Polyline(items.collect())),
            Rule::draw_line => match (items.next(), items.next()) {
                (Some(from), Some(to)) => Some(Shape::Line { from, to }),
                _ => None,
            },
            Rule::draw_circle => match (items.next(), items.next()) {
                (Some(centre), Some(radius)) => Some(Shape::Circle { centre, radius }),
                _ => None,
            },
            _ => None,
        };
        shape.ok_or_else(|| Diagnostic::error(Span::default(), "internal error: draw"))
    }

    fn param_item(&self, item: Pair<'_, Rule>) -> Built<ParamDecl> {
        let mut parts = parts(item);
        let name = parts
            .next()
            .map(|p| self.ident(&p))
            .unwrap_or_else(|| Ident { name: String::new(), span: Span::default() });
        let value = parts.next().map(|p| self.expr(p)).transpose()?;
        let unit = parts.next().map(|p| self.unit(p)).transpose()?;
        Ok(ParamDecl { name, value, unit })
    }

    /// The items of one `coord` line: coordinates, and rates (`name' = …`) that attach to a
    /// coordinate of the same line.
    fn coord_items(&self, items: Vec<Pair<'_, Rule>>) -> Built<Vec<CoordDecl>> {
        struct Item {
            name: Ident,
            primes: usize,
            primes_span: Span,
            value: Option<Expr>,
            unit: Option<Unit>,
            /// Where `~` stands, when the value is a guess.
            near: Option<Span>,
        }
        let mut parsed = Vec::new();
        for item in items {
            let item_span = self.span(&item);
            let mut parts = parts(item);
            let Some(coord_name) = parts.next() else { continue };
            let mut name_parts = coord_name.clone().into_inner();
            let name =
                name_parts.next().map_or_else(|| self.ident(&coord_name), |p| self.ident(&p));
            let (primes, primes_span) = match name_parts.next() {
                Some(p) => (p.as_str().len(), self.span(&p)),
                None => (0, item_span),
            };
            // `~` is kept by `parts` (it means something); `=` is not.
            let mut rest = parts.peekable();
            let near = rest.next_if(|p| p.as_rule() == Rule::near).map(|p| self.span(&p));
            let value = rest.next().map(|p| self.expr(p)).transpose()?;
            let unit = rest.next().map(|p| self.unit(p)).transpose()?;
            parsed.push(Item { name, primes, primes_span, value, unit, near });
        }

        let mut decls: Vec<CoordDecl> = parsed
            .iter()
            .filter(|it| it.primes == 0)
            .map(|it| CoordDecl {
                name: it.name.clone(),
                value: it.value.clone(),
                value_unit: it.unit.clone(),
                guess: it.near.is_some(),
                rate: None,
                rate_unit: None,
            })
            .collect();
        for it in parsed.into_iter().filter(|it| it.primes > 0) {
            let written = format!("{}{}", it.name.name, "'".repeat(it.primes.min(3)));
            if it.primes > 1 {
                return Err(Diagnostic::error(
                    it.primes_span,
                    format!("`{written}`: only the initial rate (one prime) can be given"),
                )
                .with_label("too many primes")
                .with_hint(format!("write `{}' = …`", it.name.name)));
            }
            if let Some(near) = it.near {
                return Err(Diagnostic::error(
                    near,
                    format!("the initial rate `{written}` cannot be a guess"),
                )
                .with_label("`~` is for positions")
                .with_hint(format!(
                    "rates the kept constraints fix are solved exactly: leave `{written}` \
                     without a value, or give it with `=`"
                )));
            }
            let Some(value) = it.value else {
                return Err(Diagnostic::error(
                    it.name.span.join(it.primes_span),
                    format!("the initial rate `{written}` needs a value"),
                )
                .with_label("expected `=` and a value")
                .with_hint(format!(
                    "write `{written} = 0`, or leave the rate out (it defaults to 0)"
                )));
            };
            let Some(decl) = decls.iter_mut().find(|d| d.name.name == it.name.name) else {
                return Err(Diagnostic::error(
                    it.name.span.join(it.primes_span),
                    format!(
                        "`{written}` gives the rate of `{}`, which is not declared on this line",
                        it.name.name
                    ),
                )
                .with_label("no such coordinate on this line")
                .with_hint(format!(
                    "declare the coordinate and its rate together: `coord {0} = …, {0}' = …`",
                    it.name.name
                )));
            };
            if let Some(previous) = &decl.rate {
                return Err(Diagnostic::error(
                    value.span,
                    format!("the rate of `{}` is given twice", it.name.name),
                )
                .with_related(previous.span, "first given here"));
            }
            decl.rate = Some(value);
            decl.rate_unit = it.unit;
        }
        Ok(decls)
    }

    /// `theta = 0` or `theta' = 0` of a `linearize about` line.
    fn about_item(&self, item: Pair<'_, Rule>) -> Built<AboutItem> {
        let span = self.span(&item);
        let mut parts = parts(item);
        let internal = || Diagnostic::error(span, "internal error: linearize item");
        let coord_name = parts.next().ok_or_else(internal)?;
        let mut name_parts = coord_name.clone().into_inner();
        let name = name_parts.next().map_or_else(|| self.ident(&coord_name), |p| self.ident(&p));
        let (primes, primes_span) = match name_parts.next() {
            Some(p) => (p.as_str().len(), self.span(&p)),
            None => (0, name.span),
        };
        if primes > 1 {
            let written = format!("{}{}", name.name, "'".repeat(primes.min(3)));
            return Err(Diagnostic::error(
                primes_span,
                format!("`{written}`: a reference gives positions and rates only"),
            )
            .with_label("too many primes")
            .with_hint(format!(
                "write `{0} = …` or `{0}' = …`; the reference's accelerations are zero",
                name.name
            )));
        }
        let value = self.expr(parts.next().ok_or_else(internal)?)?;
        let unit = parts.next().map(|p| self.unit(p)).transpose()?;
        Ok(AboutItem { name, primes: primes as u8, value, unit, span })
    }

    fn setting(&self, pair: Pair<'_, Rule>) -> Built<Setting> {
        let mut parts = parts(pair);
        let key = parts
            .next()
            .map(|p| self.ident(&p))
            .unwrap_or_else(|| Ident { name: String::new(), span: Span::default() });
        let mut values = Vec::new();
        let mut unit = None;
        for p in parts {
            match p.as_rule() {
                Rule::unit => unit = Some(self.unit(p)?),
                _ => values.push(self.expr(p)?),
            }
        }
        Ok(Setting { key, values, unit })
    }

    fn unit(&self, pair: Pair<'_, Rule>) -> Built<Unit> {
        let span = self.span(&pair);
        let mut factors = Vec::new();
        let mut sign = 1;
        for p in pair.into_inner() {
            match p.as_rule() {
                Rule::mul_op => sign = 1,
                Rule::div_op => sign = -1,
                Rule::unit_factor => {
                    let mut inner = p.into_inner().filter(|p| p.as_rule() != Rule::pow_op);
                    let Some(name) = inner.next() else { continue };
                    let power = match inner.next() {
                        Some(power) => power.as_str().parse::<i32>().map_err(|_| {
                            Diagnostic::error(self.span(&power), "unit power out of range")
                        })?,
                        None => 1,
                    };
                    factors.push((self.ident(&name), sign * power));
                }
                _ => {}
            }
        }
        Ok(Unit { factors, span })
    }

    /// An expression: the flat row of operands and operators, structured by the Pratt parser.
    fn expr(&self, pair: Pair<'_, Rule>) -> Built<Expr> {
        let span = self.span(&pair);
        // The Pratt parser recurses once per `^` or unary `-` in a row, and a long chain of
        // operators makes a deep tree; refuse both before building anything.
        let operators =
            pair.clone().into_inner().filter(|p| PRATT_OPERATORS.contains(&p.as_rule())).count();
        if operators > MAX_EXPR_DEPTH {
            return Err(Diagnostic::error(
                span,
                format!("expression too long (over {MAX_EXPR_DEPTH} operators)"),
            )
            .with_hint("split the expression with `let` names"));
        }
        let expr = PRATT
            .map_primary(|p| self.operand(p))
            .map_prefix(|op, rhs| {
                let rhs = rhs?;
                let span = Span::new(self.base + op.as_span().start(), rhs.span.end);
                Ok(Expr { kind: ExprKind::Neg(Box::new(rhs)), span })
            })
            .map_infix(|lhs, op, rhs| {
                let (lhs, rhs) = (lhs?, rhs?);
                let op = match op.as_rule() {
                    Rule::add_op => BinOp::Add,
                    Rule::sub_op => BinOp::Sub,
                    Rule::mul_op => BinOp::Mul,
                    Rule::div_op => BinOp::Div,
                    _ => BinOp::Pow,
                };
                let span = lhs.span.join(rhs.span);
                Ok(Expr {
                    kind: ExprKind::Binary { op, lhs: Box::new(lhs), rhs: Box::new(rhs) },
                    span,
                })
            })
            .parse(pair.into_inner())?;
        if depth_exceeds(&expr, MAX_EXPR_DEPTH) {
            return Err(Diagnostic::error(
                span,
                format!("expression nested too deeply (over {MAX_EXPR_DEPTH} levels)"),
            )
            .with_hint("split the expression with `let` names"));
        }
        Ok(expr)
    }

    fn operand(&self, pair: Pair<'_, Rule>) -> Built<Expr> {
        let span = self.span(&pair);
        let kind = match pair.as_rule() {
            Rule::number => ExprKind::Number(pair.as_str().to_string()),
            Rule::name => {
                let mut inner = pair.into_inner();
                let name = inner.next().map_or("", |p| p.as_str()).to_string();
                let primes = match inner.next() {
                    Some(p) => u8::try_from(p.as_str().len()).map_err(|_| {
                        Diagnostic::error(self.span(&p), "too many primes")
                            .with_label("more than 255 time derivatives")
                    })?,
                    None => 0,
                };
                ExprKind::Name { name, primes }
            }
            Rule::member => {
                let mut inner = pair.into_inner();
                let (Some(object), Some(field)) = (inner.next(), inner.next()) else {
                    return Err(Diagnostic::error(span, "internal error: member"));
                };
                let component = inner.next().map(|c| self.ident(&c));
                ExprKind::Member {
                    object: self.ident(&object),
                    field: self.ident(&field),
                    component,
                }
            }
            Rule::call => {
                let mut inner = parts(pair);
                let Some(func) = inner.next() else {
                    return Err(Diagnostic::error(span, "internal error: call"));
                };
                let args = inner.map(|p| self.expr(p)).collect::<Built<Vec<_>>>()?;
                ExprKind::Call { func: self.ident(&func), args }
            }
            Rule::paren => {
                let mut items = parts(pair).map(|p| self.expr(p)).collect::<Built<Vec<_>>>()?;
                if items.len() == 1 {
                    // A parenthesised expression keeps its node but spans the parentheses, so
                    // that the span of `(a + b)*c` covers the whole text.
                    if let Some(mut inner) = items.pop() {
                        inner.span = span;
                        return Ok(inner);
                    }
                }
                ExprKind::Tuple(items)
            }
            Rule::matrix => {
                let rows = parts(pair)
                    .map(|row| parts(row).map(|p| self.expr(p)).collect::<Built<Vec<_>>>())
                    .collect::<Built<Vec<_>>>()?;
                ExprKind::Matrix(rows)
            }
            _ => return Err(Diagnostic::error(span, "internal error: unknown operand")),
        };
        Ok(Expr { kind, span })
    }
}

/// Whether the tree under `expr` is deeper than `limit`. Subtrees were checked when built, so
/// the recursion here stays within about twice the limit.
fn depth_exceeds(expr: &Expr, limit: usize) -> bool {
    fn depth(expr: &Expr) -> usize {
        1 + match &expr.kind {
            ExprKind::Number(_) | ExprKind::Name { .. } | ExprKind::Member { .. } => 0,
            ExprKind::Neg(inner) => depth(inner),
            ExprKind::Binary { lhs, rhs, .. } => depth(lhs).max(depth(rhs)),
            ExprKind::Call { args, .. } | ExprKind::Tuple(args) => {
                args.iter().map(depth).max().unwrap_or(0)
            }
            ExprKind::Matrix(rows) => rows.iter().flatten().map(depth).max().unwrap_or(0),
        }
    }
    depth(expr) > limit
}

/// Resolves `\"` and `\\` (and any other `\c` to `c`) in a title.
fn unescape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            if let Some(escaped) = chars.next() {
                out.push(escaped);
            }
        } else {
            out.push(c);
        }
    }
    out
}
