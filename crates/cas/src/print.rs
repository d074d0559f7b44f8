//! Printers: Unicode for people (θ̇, ½, √3), ASCII in the scene syntax (parses back to the same
//! expression), and LaTeX. Terms and factors are ordered by structure and declaration order,
//! never by arena ids, so the same scene prints the same text in every run.

use std::cmp::Ordering;

use num_traits::{One, Signed, ToPrimitive, Zero};
use rustc_hash::{FxHashMap, FxHashSet};

use crate::number::Rational;
use crate::pool::{ExprId, Node, Pool, SymId, SymbolKind};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// For terminals: θ̇, x², ½, √3, ·, −.
    Unicode,
    /// The scene syntax: `theta'`, `x^2`, `1/2*m`, `sqrt(3)`. Parses back to the same expression.
    Ascii,
    /// LaTeX math: `\dot{\theta}`, `\frac{1}{2}`, `\sqrt{3}`.
    Latex,
}

const GREEK: [(&str, char, &str); 34] = [
    ("alpha", 'α', "\\alpha"),
    ("beta", 'β', "\\beta"),
    ("gamma", 'γ', "\\gamma"),
    ("delta", 'δ', "\\delta"),
    ("epsilon", 'ε', "\\epsilon"),
    ("zeta", 'ζ', "\\zeta"),
    ("eta", 'η', "\\eta"),
    ("theta", 'θ', "\\theta"),
    ("iota", 'ι', "\\iota"),
    ("kappa", 'κ', "\\kappa"),
    ("lambda", 'λ', "\\lambda"),
    ("mu", 'μ', "\\mu"),
    ("nu", 'ν', "\\nu"),
    ("xi", 'ξ', "\\xi"),
    ("omicron", 'ο', "o"),
    ("rho", 'ρ', "\\rho"),
    ("sigma", 'σ', "\\sigma"),
    ("tau", 'τ', "\\tau"),
    ("upsilon", 'υ', "\\upsilon"),
    ("phi", 'φ', "\\varphi"),
    ("chi", 'χ', "\\chi"),
    ("psi", 'ψ', "\\psi"),
    ("omega", 'ω', "\\omega"),
    ("Gamma", 'Γ', "\\Gamma"),
    ("Delta", 'Δ', "\\Delta"),
    ("Theta", 'Θ', "\\Theta"),
    ("Lambda", 'Λ', "\\Lambda"),
    ("Xi", 'Ξ', "\\Xi"),
    ("Pi", 'Π', "\\Pi"),
    ("Sigma", 'Σ', "\\Sigma"),
    ("Upsilon", 'Υ', "\\Upsilon"),
    ("Phi", 'Φ', "\\Phi"),
    ("Psi", 'Ψ', "\\Psi"),
    ("Omega", 'Ω', "\\Omega"),
];

/// The spelled-out name of a Greek letter (`θ` → `theta`), so `θ` and `theta` are one symbol.
pub fn greek_word(letter: char) -> Option<&'static str> {
    GREEK.iter().find(|(_, c, _)| *c == letter).map(|(w, _, _)| *w)
}

/// Splits `theta1` into (`theta`, `1`) and `m_cart` into (`m`, `cart`).
fn split_subscript(name: &str) -> (&str, &str) {
    if let Some(i) = name.find('_') {
        if i > 0 && i + 1 < name.len() {
            return (&name[..i], &name[i + 1..]);
        }
    }
    let digits = name.len() - name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    if digits > 0 && digits < name.len() {
        (&name[..name.len() - digits], &name[name.len() - digits..])
    } else {
        (name, "")
    }
}

fn unicode_subscript(sub: &str) -> String {
    if sub.chars().all(|c| c.is_ascii_digit()) {
        sub.chars()
            .map(|c| char::from_u32('₀' as u32 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
            .collect()
    } else {
        format!("_{sub}")
    }
}

/// Unicode superscript digits and minus, for powers.
pub fn superscript(text: &str) -> String {
    text.chars()
        .map(|c| match c {
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            '-' => '⁻',
            other => other,
        })
        .collect()
}

fn vulgar(q: &Rational) -> Option<&'static str> {
    let pairs: [((i64, i64), &str); 11] = [
        ((1, 2), "½"),
        ((1, 3), "⅓"),
        ((2, 3), "⅔"),
        ((1, 4), "¼"),
        ((3, 4), "¾"),
        ((1, 5), "⅕"),
        ((1, 6), "⅙"),
        ((5, 6), "⅚"),
        ((1, 8), "⅛"),
        ((3, 8), "⅜"),
        ((5, 8), "⅝"),
    ];
    pairs.iter().find(|((n, d), _)| *q == Rational::new((*n).into(), (*d).into())).map(|(_, s)| *s)
}

/// Past this many nodes written out, an expression prints as its operation count.
pub const PRINT_NODE_LIMIT: usize = 2_000;

#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Prec {
    Sum,
    Product,
    Power,
    Atom,
}

impl Pool {
    /// Prints an expression in the given style; one whose printed form would run past
    /// [`PRINT_NODE_LIMIT`] nodes (a bicycle's equations, shared subexpressions printed each time
    /// they occur) prints as how many operations it holds instead.
    pub fn print(&self, e: ExprId, style: Style) -> String {
        if self.tree_exceeds(e, PRINT_NODE_LIMIT) {
            let count = self.operation_count(e);
            return match style {
                Style::Latex => format!(r"\langle\text{{{count} operations}}\rangle"),
                Style::Ascii => format!("<{count} operations>"),
                Style::Unicode => format!("⟨{count} operations⟩"),
            };
        }
        self.fmt(e, style).0
    }

    /// Whether `e` prints in full rather than as its operation count (see [`Pool::print`]):
    /// where it does not, making it readable first is wasted.
    pub fn prints_in_full(&self, e: ExprId) -> bool {
        !self.tree_exceeds(e, PRINT_NODE_LIMIT)
    }

    /// Whether `e` written out as a tree has more than `limit` nodes (each shared
    /// subexpression counted every time it occurs), without writing it out.
    pub fn tree_exceeds(&self, e: ExprId, limit: usize) -> bool {
        fn size(pool: &Pool, e: ExprId, cap: usize, memo: &mut FxHashMap<ExprId, usize>) -> usize {
            if let Some(&n) = memo.get(&e) {
                return n;
            }
            let mut n = 1usize;
            pool.for_each_child(e, |c| n = n.saturating_add(size(pool, c, cap, memo)).min(cap));
            memo.insert(e, n);
            n
        }
        size(self, e, limit.saturating_add(1), &mut FxHashMap::default()) > limit
    }

    /// The distinct operations (sums, products, powers, functions) `e` is built of, each
    /// shared subexpression once.
    pub fn operation_count(&self, e: ExprId) -> usize {
        let mut seen = FxHashSet::default();
        let mut stack = vec![e];
        let mut count = 0;
        while let Some(x) = stack.pop() {
            if !seen.insert(x) {
                continue;
            }
            let before = stack.len();
            self.for_each_child(x, |c| stack.push(c));
            if stack.len() > before {
                count += 1;
            }
        }
        count
    }

    /// How a symbol is shown: `theta''` is `θ̈` in Unicode and `\ddot{\theta}` in LaTeX.
    pub fn symbol_text(&self, s: SymId, style: Style) -> String {
        let symbol = self.symbol(s);
        if style == Style::Ascii {
            return symbol.name.clone();
        }
        // A symbol that is no coordinate's derivative may still be a rate (`KE'`, the rate of
        // the kinetic energy): its primes count too.
        let order = match symbol.kind {
            SymbolKind::Coordinate { order, .. } => order,
            _ => (symbol.name.len() - symbol.base_name().len()) as u8,
        };
        let (base, sub) = split_subscript(symbol.base_name());
        let greek = GREEK.iter().find(|(w, _, _)| *w == base);
        match style {
            Style::Unicode => {
                let glyph =
                    greek.map(|(_, c, _)| c.to_string()).unwrap_or_else(|| base.to_string());
                let single = glyph.chars().count() == 1;
                let marked = match (order, single) {
                    (0, _) => glyph,
                    (1, true) => format!("{glyph}\u{307}"),
                    (2, true) => format!("{glyph}\u{308}"),
                    (3, true) => format!("{glyph}\u{20db}"),
                    (n, _) => format!("{glyph}{}", "′".repeat(n as usize)),
                };
                if sub.is_empty() {
                    marked
                } else {
                    format!("{marked}{}", unicode_subscript(sub))
                }
            }
            _ => {
                let glyph = match greek {
                    Some((_, _, tex)) => tex.to_string(),
                    None if base.chars().count() == 1 => base.to_string(),
                    None => format!("\\mathrm{{{base}}}"),
                };
                let marked = match order {
                    0 => glyph,
                    1 => format!("\\dot{{{glyph}}}"),
                    2 => format!("\\ddot{{{glyph}}}"),
                    3 => format!("\\dddot{{{glyph}}}"),
                    n => format!("{glyph}^{{({n})}}"),
                };
                if sub.is_empty() {
                    marked
                } else {
                    format!("{marked}_{{{sub}}}")
                }
            }
        }
    }

    fn rational_text(&self, q: &Rational, style: Style) -> String {
        let minus = if q.is_negative() { minus(style) } else { "" };
        let a = q.abs();
        if a.is_integer() {
            return format!("{minus}{}", a.numer());
        }
        match style {
            Style::Unicode => match vulgar(&a) {
                Some(v) => format!("{minus}{v}"),
                None => format!("{minus}{}/{}", a.numer(), a.denom()),
            },
            Style::Ascii => format!("{minus}{}/{}", a.numer(), a.denom()),
            Style::Latex => format!("{minus}\\frac{{{}}}{{{}}}", a.numer(), a.denom()),
        }
    }

    fn fmt(&self, e: ExprId, style: Style) -> (String, Prec) {
        match self.node(e) {
            Node::Num(q) => {
                let prec = if q.is_negative() || !q.is_integer() { Prec::Sum } else { Prec::Atom };
                let prec =
                    if style == Style::Latex && !q.is_negative() { Prec::Atom } else { prec };
                (self.rational_text(q, style), prec)
            }
            Node::Sym(s) => (self.symbol_text(*s, style), Prec::Atom),
            Node::Pi => (
                match style {
                    Style::Unicode => "π",
                    Style::Ascii => "pi",
                    Style::Latex => "\\pi",
                }
                .to_string(),
                Prec::Atom,
            ),
            Node::Add(c, terms) => {
                let parts = self.in_term_order(terms);
                let mut out = String::new();
                // A constant reads first in a sum of positions (1 + 3 sin²θ), last in an
                // equation with rates in it.
                let constant_first = !c.is_zero() && self.max_order(e) == 0;
                if constant_first {
                    let text = self.rational_text(&c.abs(), style);
                    push_term(&mut out, &text, c.is_negative(), true, style);
                }
                for (i, (t, k)) in parts.iter().enumerate() {
                    let text = self.fmt_scaled(*t, &k.abs(), style);
                    push_term(&mut out, &text, k.is_negative(), i == 0 && !constant_first, style);
                }
                if !c.is_zero() && !constant_first {
                    let text = self.rational_text(&c.abs(), style);
                    push_term(&mut out, &text, c.is_negative(), parts.is_empty(), style);
                }
                (out, Prec::Sum)
            }
            Node::Mul(c, factors) => {
                let text = self.fmt_product(&c.abs(), factors, style);
                if c.is_negative() {
                    (format!("{}{text}", minus(style)), Prec::Sum)
                } else {
                    (text, Prec::Product)
                }
            }
            Node::Pow(b, x) => {
                let base = self.fmt_at(*b, Prec::Atom, style);
                let exp = self.fmt_at(*x, Prec::Atom, style);
                let text = match style {
                    Style::Latex => format!("{base}^{{{}}}", self.print(*x, style)),
                    _ => format!("{base}^{exp}"),
                };
                (text, Prec::Power)
            }
            Node::Func(f, a) => {
                let arg = self.print(*a, style);
                (self.call_text(f.name(), &arg, None, style), Prec::Atom)
            }
            Node::Atan2(y, x) => {
                let (y, x) = (self.print(*y, style), self.print(*x, style));
                let text = match style {
                    Style::Latex => format!("\\operatorname{{atan2}}\\left({y}, {x}\\right)"),
                    _ => format!("atan2({y}, {x})"),
                };
                (text, Prec::Atom)
            }
        }
    }

    fn call_text(&self, name: &str, arg: &str, power: Option<&str>, style: Style) -> String {
        // |u| reads as the bars a reader writes; scene syntax keeps `abs(u)`, which parses.
        let bars = match style {
            Style::Latex => Some(format!("\\left|{arg}\\right|")),
            Style::Unicode => Some(format!("|{arg}|")),
            Style::Ascii => None,
        };
        if let (Some(bars), "abs") = (bars, name) {
            return match (power, style) {
                (Some(p), Style::Latex) => format!("{bars}^{{{p}}}"),
                (Some(p), _) => format!("{bars}{}", superscript(p)),
                (None, _) => bars,
            };
        }
        match style {
            Style::Latex => {
                let head = match name {
                    "sin" | "cos" | "tan" | "sinh" | "cosh" | "tanh" | "exp" | "ln" => {
                        format!("\\{name}")
                    }
                    "asin" => "\\arcsin".to_string(),
                    "acos" => "\\arccos".to_string(),
                    "atan" => "\\arctan".to_string(),
                    "sign" => "\\operatorname{sgn}".to_string(),
                    other => format!("\\operatorname{{{other}}}"),
                };
                match power {
                    Some(p) => format!("{head}^{{{p}}}\\left({arg}\\right)"),
                    None => format!("{head}\\left({arg}\\right)"),
                }
            }
            Style::Unicode => match power {
                Some(p) => format!("{name}{}({arg})", superscript(p)),
                None => format!("{name}({arg})"),
            },
            Style::Ascii => match power {
                Some(p) => format!("{name}({arg})^{p}"),
                None => format!("{name}({arg})"),
            },
        }
    }

    fn fmt_at(&self, e: ExprId, min: Prec, style: Style) -> String {
        let (text, prec) = self.fmt(e, style);
        if prec < min {
            match style {
                Style::Latex => format!("\\left({text}\\right)"),
                _ => format!("({text})"),
            }
        } else {
            text
        }
    }

    /// `k·t` for a positive rational `k`, printed as one product.
    fn fmt_scaled(&self, t: ExprId, k: &Rational, style: Style) -> String {
        match self.node(t) {
            Node::Mul(c, factors) => self.fmt_product(&(c * k), factors, style),
            _ if k.is_one() => self.fmt_at(t, Prec::Product, style),
            _ => self.fmt_product(k, &[(t, Rational::one())], style),
        }
    }

    /// A product with a positive coefficient: numerator factors, then a denominator.
    fn fmt_product(&self, coef: &Rational, factors: &[(ExprId, Rational)], style: Style) -> String {
        let mut factors: Vec<(ExprId, Rational)> = factors.to_vec();
        factors.sort_by(|a, b| self.factor_order(a.0, b.0));
        let mut upper = Vec::new();
        let mut lower = Vec::new();
        for (b, x) in &factors {
            if x.is_negative() {
                lower.push(self.fmt_power(*b, &-x, style));
            } else {
                upper.push(self.fmt_power(*b, x, style));
            }
        }
        let sep = match style {
            Style::Unicode => "·",
            Style::Ascii => "*",
            Style::Latex => " ",
        };
        if style == Style::Latex && !lower.is_empty() {
            let mut top = Vec::new();
            if !coef.numer().is_one() || upper.is_empty() {
                top.push(coef.numer().to_string());
            }
            top.extend(upper);
            let mut bottom = Vec::new();
            if !coef.denom().is_one() {
                bottom.push(coef.denom().to_string());
            }
            bottom.extend(lower);
            if bottom.is_empty() {
                return top.join(sep);
            }
            return format!("\\frac{{{}}}{{{}}}", top.join(sep), bottom.join(sep));
        }
        // π/6 and L/4 read better than ⅙·π and ¼·L; ½·m·ẋ² keeps its fraction in front.
        if coef.numer().is_one()
            && !coef.is_integer()
            && factors.len() == 1
            && lower.is_empty()
            && factors[0].1.is_one()
        {
            let atom = self.fmt_at(factors[0].0, Prec::Power, style);
            return format!("{atom}/{}", coef.denom());
        }
        let mut head = Vec::new();
        if !coef.is_one() || upper.is_empty() {
            head.push(self.rational_text(coef, style));
        }
        head.extend(upper);
        let mut text = head.join(sep);
        if !lower.is_empty() {
            text.push('/');
            if lower.len() == 1 {
                text.push_str(&lower[0]);
            } else {
                text.push_str(&format!("({})", lower.join(sep)));
            }
        }
        text
    }

    /// `b^x` for a positive rational exponent, as a factor of a product.
    fn fmt_power(&self, b: ExprId, x: &Rational, style: Style) -> String {
        if x.is_one() {
            return self.fmt_at(b, Prec::Power, style);
        }
        // Compared by parts: building ½ as a rational (a gcd and divisions) at every power
        // printed cost more than printing it.
        let half = x.numer().is_one() && x.denom().to_u8() == Some(2);
        if half {
            let inner = self.print(b, style);
            return match style {
                Style::Unicode => {
                    let (_, prec) = self.fmt(b, style);
                    if prec == Prec::Atom {
                        format!("√{inner}")
                    } else {
                        format!("√({inner})")
                    }
                }
                Style::Ascii => format!("sqrt({inner})"),
                Style::Latex => format!("\\sqrt{{{inner}}}"),
            };
        }
        let exp = if x.is_integer() {
            x.numer().to_string()
        } else {
            format!("{}/{}", x.numer(), x.denom())
        };
        if let (Node::Func(f, a), true) = (self.node(b), x.is_integer()) {
            if style != Style::Ascii {
                return self.call_text(f.name(), &self.print(*a, style), Some(&exp), style);
            }
        }
        let base = self.fmt_at(b, Prec::Atom, style);
        match style {
            Style::Unicode if x.is_integer() => format!("{base}{}", superscript(&exp)),
            Style::Latex => format!("{base}^{{{exp}}}"),
            _ if x.is_integer() => format!("{base}^{exp}"),
            _ => format!("{base}^({exp})"),
        }
    }

    /// The terms of a sum in printing order (`term_order_with`), each term's order and
    /// leading symbols found once rather than at every comparison.
    fn in_term_order(&self, terms: &[(ExprId, Rational)]) -> Vec<(ExprId, Rational)> {
        let keys: Vec<(u8, Vec<SymId>)> = terms
            .iter()
            .map(|(t, _)| {
                let order = self.max_order(*t);
                (order, self.leading_symbols(*t, order))
            })
            .collect();
        let mut index: Vec<usize> = (0..terms.len()).collect();
        index.sort_by(|&i, &j| self.term_order_with(terms[i].0, &keys[i], terms[j].0, &keys[j]));
        index.into_iter().map(|i| terms[i].clone()).collect()
    }

    /// Terms of a sum: accelerations first, then velocities, then the rest; ties broken by
    /// the factors, compared in printing order. Each term comes with its order and its
    /// leading symbols of that order.
    fn term_order_with(
        &self,
        a: ExprId,
        (oa, la): &(u8, Vec<SymId>),
        b: ExprId,
        (ob, lb): &(u8, Vec<SymId>),
    ) -> Ordering {
        ob.cmp(oa)
            .then_with(|| {
                // Among terms of the same order, follow the coordinates' declaration order
                // (the ẍ term before the s̈ term).
                // Compared as whole sequences (a prefix first): stopping at the shorter one
                // would make the order intransitive, which sorting must not meet.
                let mut pairs = la.iter().zip(lb.iter());
                pairs
                    .find_map(|(x, y)| {
                        let o = self.symbol_order(*x, *y);
                        (o != Ordering::Equal).then_some(o)
                    })
                    .unwrap_or_else(|| la.len().cmp(&lb.len()))
            })
            .then_with(|| self.structural_order(a, b))
    }

    /// The symbols of the given derivative order in `e`, in declaration order.
    fn leading_symbols(&self, e: ExprId, order: u8) -> Vec<SymId> {
        let mut out = Vec::new();
        let mut stack = vec![e];
        while let Some(x) = stack.pop() {
            match self.node(x) {
                Node::Sym(s) if self.symbol(*s).order() == order && order > 0 => out.push(*s),
                _ => stack.extend(self.children(x)),
            }
        }
        out.sort_by(|a, b| self.symbol_order(*a, *b));
        out.dedup();
        out
    }

    /// Factors of a product: numbers, π, parameters in declaration order, sums, functions,
    /// then coordinates, velocities and accelerations.
    fn factor_order(&self, a: ExprId, b: ExprId) -> Ordering {
        self.factor_rank(a).cmp(&self.factor_rank(b)).then_with(|| self.structural_order(a, b))
    }

    fn factor_rank(&self, e: ExprId) -> u8 {
        match self.node(e) {
            Node::Num(_) => 0,
            Node::Pi => 1,
            Node::Sym(s) => match self.symbol(*s).kind {
                SymbolKind::Param | SymbolKind::Time => 2,
                SymbolKind::Coordinate { order, .. } => 5 + order,
            },
            Node::Add(..) => 3,
            _ => 4,
        }
    }

    fn max_order(&self, e: ExprId) -> u8 {
        match self.node(e) {
            Node::Sym(s) => self.symbol(*s).order(),
            _ => self.children(e).into_iter().map(|c| self.max_order(c)).max().unwrap_or(0),
        }
    }

    /// A total order on expressions that depends only on their structure and on symbol
    /// declaration order, never on when a node happened to be created.
    pub fn structural_order(&self, a: ExprId, b: ExprId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        let kind = |n: &Node| match n {
            Node::Num(_) => 0,
            Node::Pi => 1,
            Node::Sym(_) => 2,
            Node::Func(..) => 3,
            Node::Atan2(..) => 4,
            Node::Pow(..) => 5,
            Node::Mul(..) => 6,
            Node::Add(..) => 7,
        };
        let (na, nb) = (self.node(a), self.node(b));
        kind(na).cmp(&kind(nb)).then_with(|| match (na, nb) {
            (Node::Num(x), Node::Num(y)) => x.cmp(y),
            (Node::Sym(x), Node::Sym(y)) => self.symbol_order(*x, *y),
            (Node::Func(f, x), Node::Func(g, y)) => {
                f.cmp(g).then_with(|| self.structural_order(*x, *y))
            }
            (Node::Atan2(a1, a2), Node::Atan2(b1, b2)) | (Node::Pow(a1, a2), Node::Pow(b1, b2)) => {
                self.structural_order(*a1, *b1).then_with(|| self.structural_order(*a2, *b2))
            }
            (Node::Mul(c1, f1), Node::Mul(c2, f2)) => {
                self.pairs_order(f1, f2, true).then_with(|| c1.cmp(c2))
            }
            (Node::Add(c1, t1), Node::Add(c2, t2)) => {
                self.pairs_order(t1, t2, false).then_with(|| c1.cmp(c2))
            }
            _ => Ordering::Equal,
        })
    }

    fn pairs_order(
        &self,
        a: &[(ExprId, Rational)],
        b: &[(ExprId, Rational)],
        factors: bool,
    ) -> Ordering {
        let sorted = |v: &[(ExprId, Rational)]| {
            let mut v = v.to_vec();
            if factors {
                v.sort_by(|x, y| self.factor_order(x.0, y.0));
            } else {
                v.sort_by(|x, y| self.structural_order(x.0, y.0));
            }
            v
        };
        let (a, b) = (sorted(a), sorted(b));
        for ((xa, ka), (xb, kb)) in a.iter().zip(b.iter()) {
            let o = self.structural_order(*xa, *xb).then_with(|| ka.cmp(kb));
            if o != Ordering::Equal {
                return o;
            }
        }
        a.len().cmp(&b.len())
    }

    fn symbol_order(&self, a: SymId, b: SymId) -> Ordering {
        // Parameters in declaration order, then time (w·t, not t·w), then coordinates.
        let key = |s: SymId| match self.symbol(s).kind {
            SymbolKind::Coordinate { base, order } => (order, base.index()),
            SymbolKind::Time => (0, usize::MAX),
            SymbolKind::Param => (0, s.index()),
        };
        key(a).cmp(&key(b))
    }
}

fn minus(style: Style) -> &'static str {
    match style {
        Style::Unicode => "−",
        _ => "-",
    }
}

fn push_term(out: &mut String, text: &str, negative: bool, first: bool, style: Style) {
    match (first, negative) {
        (true, false) => out.push_str(text),
        (true, true) => {
            out.push_str(minus(style));
            out.push_str(text);
        }
        (false, false) => {
            out.push_str(" + ");
            out.push_str(text);
        }
        (false, true) => {
            out.push(' ');
            out.push_str(minus(style));
            out.push(' ');
            out.push_str(text);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::number;

    #[test]
    fn rod_equation_prints_like_the_solution() {
        let mut p = Pool::new();
        let g = p.param("g");
        let g = p.sym(g);
        let l = p.param("L");
        let l = p.sym(l);
        let th = p.coordinate("theta");
        let thd = p.rate(th).unwrap();
        let th = p.sym(th);
        let thd = p.sym(thd);
        let gl = p.div(g, l);
        let e = p.scale(gl, &number::ratio(12, 7));
        assert_eq!(p.print(e, Style::Unicode), "12/7·g/L");
        assert_eq!(p.print(e, Style::Ascii), "12/7*g/L");
        assert_eq!(p.print(e, Style::Latex), "\\frac{12 g}{7 L}");
        let s = p.sin(th);
        let s2 = p.powi(s, 2);
        let v2 = p.powi(thd, 2);
        let t = p.mul(&[s2, v2]);
        let t = p.scale(t, &number::ratio(1, 2));
        assert_eq!(p.print(t, Style::Unicode), "½·sin²(θ)·θ̇²");
        assert_eq!(p.print(t, Style::Ascii), "1/2*sin(theta)^2*theta'^2");
        assert_eq!(
            p.print(t, Style::Latex),
            "\\frac{1}{2} \\sin^{2}\\left(\\theta\\right) \\dot{\\theta}^{2}"
        );
    }
}
