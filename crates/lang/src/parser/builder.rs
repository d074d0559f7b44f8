//! The AST builder: turns the pairs of a parse into the spanned AST, with the checks the grammar
//! cannot make.

use pest::iterators::Pair;

use super::errors::is_statement_keyword;
use super::{Rule, MAX_EXPR_DEPTH, PRATT, PRATT_OPERATORS};
use crate::ast::*;
use crate::diag::Diagnostic;

/// Builds AST nodes from pairs of a parse of `source[base..]`.
pub(super) struct Builder<'d> {
    /// Offset of the parsed text in the whole source, added to every span.
    pub(super) base: usize,
    /// Structural errors found while building.
    pub(super) diags: &'d mut Vec<Diagnostic>,
}

pub(super) type Built<T> = Result<T, Diagnostic>;

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
                | kw_linearized
                | kw_eigenvalue
                | kw_critical
                | kw_at
                | kw_start
                | kw_impact
                | kw_where
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
/// The next part of a statement. The grammar guarantees the shape of every statement; a
/// missing part is a bug here, reported as an error rather than a panic.
fn next_part<'i>(items: &mut impl Iterator<Item = Pair<'i, Rule>>) -> Built<Pair<'i, Rule>> {
    items.next().ok_or_else(|| {
        Diagnostic::error(Span::default(), "internal error: unexpected parse tree shape")
    })
}

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

    pub(super) fn file(mut self, file: Pair<'_, Rule>, stmts: &mut Vec<Stmt>) {
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
        let impact = pair
            .clone()
            .into_inner()
            .find(|p| p.as_rule() == Rule::at_impact)
            .and_then(|p| parts(p).find(|q| q.as_rule() == Rule::ident))
            .map(|name| self.ident(&name));
        let linearized = pair.clone().into_inner().any(|p| p.as_rule() == Rule::kw_linearized);
        let mut items =
            parts(pair).filter(|p| !matches!(p.as_rule(), Rule::at_start | Rule::at_impact));
        let mut next = || next_part(&mut items);
        Ok(match rule {
            Rule::scene_stmt => {
                let string = next()?;
                let text = parts(string).next().map_or("", |p| p.as_str());
                StmtKind::Scene { title: unescape(text) }
            }
            // An `input` line's items are written as a `param` line's.
            Rule::param_stmt | Rule::input_stmt => {
                let mut decls = Vec::new();
                while let Ok(item) = next() {
                    decls.push(self.param_item(item)?);
                }
                match rule {
                    Rule::param_stmt => StmtKind::Param(decls),
                    _ => StmtKind::Input(decls),
                }
            }
            Rule::output_stmt => {
                let name = self.ident(&next()?);
                StmtKind::Output { name, value: self.expr(next()?)? }
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
            Rule::particle_stmt | Rule::body_stmt => self.body_stmt(rule, &mut items)?,
            Rule::constraint_stmt => self.constraint_stmt(&mut items)?,
            Rule::contact_stmt => self.contact_stmt(&mut items)?,
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
            Rule::spring_stmt | Rule::damper_stmt => self.link_stmt(rule, &mut items)?,
            Rule::force_stmt | Rule::torque_stmt => self.load_stmt(rule, &mut items)?,
            Rule::show_stmt => {
                let mut items = Vec::new();
                while let Ok(item) = next() {
                    items.push(self.expr(item)?);
                }
                StmtKind::Show { at_start, items }
            }
            Rule::expect_stmt if linearized => {
                let expectation = next()?;
                StmtKind::ExpectLinearized(self.linear_expectation(expectation)?)
            }
            Rule::expect_stmt => {
                let lhs = self.expr(next()?)?;
                let rhs = self.expr(next()?)?;
                let mut before = Vec::new();
                while let Ok(item) = next() {
                    before.push(self.about_item(item)?);
                }
                StmtKind::Expect { at_start, impact, lhs, rhs, before }
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

    /// A `particle` or `body` statement: its name and its properties.
    fn body_stmt<'i>(
        &mut self,
        rule: Rule,
        items: &mut impl Iterator<Item = Pair<'i, Rule>>,
    ) -> Built<StmtKind> {
        let mut next = || next_part(items);
        let name = self.ident(&next()?);
        let mut props = Vec::new();
        while let Ok(prop) = next() {
            let mut kv = parts(prop);
            let (Some(key), Some(value)) = (kv.next(), kv.next()) else {
                continue;
            };
            props.push(Property { key: self.ident(&key), value: self.expr(value)? });
        }
        Ok(if rule == Rule::particle_stmt {
            StmtKind::Particle { name, props }
        } else {
            StmtKind::Body { name, props }
        })
    }

    /// A constraint: its name if given, and its two sides.
    fn constraint_stmt<'i>(
        &mut self,
        items: &mut impl Iterator<Item = Pair<'i, Rule>>,
    ) -> Built<StmtKind> {
        let mut next = || next_part(items);
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
        Ok(StmtKind::Constraint { name, lhs: self.expr(lhs)?, rhs: self.expr(rhs)? })
    }

    /// A contact: its name, its two sides and which one is the greater, and its laws.
    fn contact_stmt<'i>(
        &mut self,
        items: &mut impl Iterator<Item = Pair<'i, Rule>>,
    ) -> Built<StmtKind> {
        let mut next = || next_part(items);
        let name = self.ident(&next()?);
        let lhs = self.expr(next()?)?;
        let at_least = next()?.as_rule() == Rule::at_least;
        let rhs = self.expr(next()?)?;
        let mut laws = Vec::new();
        while let Ok(law) = next() {
            let mut kv = parts(law);
            let (Some(key), Some(value)) = (kv.next(), kv.next()) else {
                continue;
            };
            laws.push(Property { key: self.ident(&key), value: self.expr(value)? });
        }
        Ok(StmtKind::Contact { name, lhs, rhs, at_least, laws })
    }

    /// A `spring` or `damper`: its name, its two ends and its coefficient (and a spring's rest length).
    fn link_stmt<'i>(
        &mut self,
        rule: Rule,
        items: &mut impl Iterator<Item = Pair<'i, Rule>>,
    ) -> Built<StmtKind> {
        let mut next = || next_part(items);
        let name = self.ident(&next()?);
        let a = self.expr(next()?)?;
        let b = self.expr(next()?)?;
        let coefficient = self.expr(next()?)?;
        Ok(if rule == Rule::spring_stmt {
            let rest = match next() {
                Ok(p) => Some(self.expr(p)?),
                Err(_) => None,
            };
            StmtKind::Spring { name, a, b, stiffness: coefficient, rest }
        } else {
            StmtKind::Damper { name, a, b, coefficient }
        })
    }

    /// A `force` or `torque`: its name, its body, where a force acts if not at the centre of mass, and its value.
    fn load_stmt<'i>(
        &mut self,
        rule: Rule,
        items: &mut impl Iterator<Item = Pair<'i, Rule>>,
    ) -> Built<StmtKind> {
        let mut next = || next_part(items);
        let name = self.ident(&next()?);
        let body = self.ident(&next()?);
        let first = self.expr(next()?)?;
        // `at P` comes before the value when it is given.
        let (at, value) = match next() {
            Ok(p) => (Some(first), self.expr(p)?),
            Err(_) => (None, first),
        };
        Ok(if rule == Rule::force_stmt {
            StmtKind::Force { name, body, at, value }
        } else {
            StmtKind::Torque { name, body, value }
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

    fn linear_expectation(&self, pair: Pair<'_, Rule>) -> Built<LinearExpectation> {
        let inner = parts(pair).next();
        let missing = || Diagnostic::error(Span::default(), "internal error: expect linearized");
        let inner = inner.ok_or_else(missing)?;
        match inner.as_rule() {
            Rule::verdict_word => {
                let word = inner.as_str().split_whitespace().collect::<Vec<_>>().join(" ");
                Ok(LinearExpectation::Verdict { word, span: self.span(&inner) })
            }
            Rule::eigenvalue_item => {
                let value = parts(inner).next().ok_or_else(missing)?;
                Ok(LinearExpectation::Eigenvalue(self.expr(value)?))
            }
            _ => {
                let mut items = parts(inner);
                let (Some(parameter), Some(value)) = (items.next(), items.next()) else {
                    return Err(missing());
                };
                let parameter = self.ident(&parameter);
                Ok(LinearExpectation::Critical { parameter, value: self.expr(value)? })
            }
        }
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
    pub(super) fn about_item(&self, item: Pair<'_, Rule>) -> Built<AboutItem> {
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
        let (mut target, mut values, mut unit) = (None, Vec::new(), None);
        for p in parts {
            match p.as_rule() {
                Rule::unit => unit = Some(self.unit(p)?),
                Rule::setting_target => {
                    target = p.into_inner().next().map(|name| self.ident(&name));
                }
                Rule::eq => {}
                _ => values.push(self.expr(p)?),
            }
        }
        Ok(Setting { key, target, values, unit })
    }

    pub(super) fn unit(&self, pair: Pair<'_, Rule>) -> Built<Unit> {
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
    pub(super) fn expr(&self, pair: Pair<'_, Rule>) -> Built<Expr> {
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
