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

use pest::iterators::Pair;
use pest::pratt_parser::{Assoc, Op, PrattParser};
use pest::Parser as _;
use pest_derive::Parser;

use crate::ast::*;
use crate::diag::Diagnostic;

mod brackets;
mod builder;
mod errors;

use brackets::{bracket_diagnostics, scan_brackets};
use builder::{Builder, Built};
use errors::{next_statement_line, syntax_error};

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
pub(crate) const STATEMENT_KEYWORDS: [&str; 23] = [
    "scene",
    "param",
    "let",
    "coord",
    "input",
    "output",
    "particle",
    "body",
    "constraint",
    "contact",
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

/// Parses a value with an optional unit on its own, as a scene writes a setting's value
/// (`20 ms`, `2*pi`, `1/4 min`): a front end's time or value; spans point into `text`.
pub fn parse_quantity(text: &str) -> Result<(Expr, Option<Unit>), Vec<Diagnostic>> {
    parse_lone(text, Rule::lone_quantity, |builder, pair| {
        let mut parts =
            pair.into_inner().filter(|p| matches!(p.as_rule(), Rule::expr | Rule::unit));
        let Some(value) = parts.next() else {
            return Err(Diagnostic::error(Span::default(), "expected a value"));
        };
        let value = builder.expr(value)?;
        let unit = parts.next().map(|p| builder.unit(p)).transpose()?;
        Ok((value, unit))
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
