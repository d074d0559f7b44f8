//! Syntax errors: turns a pest failure into a diagnostic that names what was expected, and
//! finds where the parser resumes after it.

use pest::error::{ErrorVariant, InputLocation};

use super::{Rule, STATEMENT_KEYWORDS};
use crate::ast::{Span, UNIT_NAMES};
use crate::diag::Diagnostic;

/// The offset of the first line after `pos` that starts with a statement keyword.
pub(super) fn next_statement_line(source: &str, pos: usize) -> Option<usize> {
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
        kw_scene | kw_param | kw_input | kw_output | kw_let | kw_coord | kw_particle | kw_body
        | kw_constraint | kw_contact | kw_gravity | kw_potential | kw_force | kw_torque
        | kw_spring | kw_damper | kw_dissipation | kw_lagrangian | kw_show | kw_expect
        | kw_simulate | kw_linearize | kw_draw => (0, "a statement"),
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
        kw_linearized => (4, "`linearized:`"),
        linear_expectation | verdict_word | eigenvalue_item | critical_item | kw_eigenvalue
        | kw_critical => {
            (2, "`stable`, `unstable`, `marginally stable`, `eigenvalue = …` or `critical p = …`")
        }
        kw_on => (4, "`on`"),
        kw_between => (4, "`between`"),
        kw_and => (4, "`and`"),
        kw_from => (4, "`from`"),
        kw_to => (4, "`to`"),
        kw_radius => (4, "`radius`"),
        at_start | kw_at => (4, "`at start:`"),
        at_impact | kw_impact => (4, "`impact NAME:`"),
        kw_where => (4, "`where`"),
        kw_start => (4, "`start`"),
        add_op | sub_op | mul_op | div_op | pow_op => (5, "an operator"),
        eq => (6, "`=`"),
        at_least | at_most => (6, "`>=` or `<=`"),
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
                | input_stmt
                | output_stmt
                | let_stmt
                | coord_stmt
                | particle_stmt
                | body_stmt
                | constraint_stmt
                | contact_stmt
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

pub(super) fn is_statement_keyword(rule: Rule) -> bool {
    use Rule::*;
    matches!(
        rule,
        kw_scene
            | kw_param
            | kw_input
            | kw_output
            | kw_let
            | kw_coord
            | kw_particle
            | kw_body
            | kw_constraint
            | kw_contact
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
pub(super) fn syntax_error(
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
