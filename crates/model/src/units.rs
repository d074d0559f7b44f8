//! Units and dimensions: the SI units a scene may write after a value, and the inference that
//! every sum, equation and energy term in the scene has one dimension.
//!
//! Dimensions are exponents of the SI base quantities. Names without a unit get an unknown
//! dimension that is inferred from how they are used (a linear system over the exponents), so
//! a scene needs units on only a few parameters for every term to be checked. The resolver
//! states the facts (this equals that, this is dimensionless, this is an energy) as it
//! resolves each expression; [`Inference::solve`] then solves them in the file's order.

use std::collections::{BTreeMap, HashMap, HashSet};

use cas::number::{One, Signed, Zero};
use cas::Rational;
use lang::{Diagnostic, Span, Unit};

/// The SI base quantities tracked: mass, length, time, current, temperature.
const BASES: [&str; 5] = ["kg", "m", "s", "A", "K"];

/// A dimension: the exponent of each base quantity.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Dim([Rational; 5]);

impl Dim {
    pub(crate) fn base(i: usize) -> Dim {
        let mut d = Dim::default();
        d.0[i] = Rational::one();
        d
    }

    fn of(exps: [i64; 5]) -> Dim {
        Dim(exps.map(|e| Rational::from_integer(e.into())))
    }

    fn is_dimensionless(&self) -> bool {
        self.0.iter().all(|e| e.is_zero())
    }

    fn add(&self, other: &Dim) -> Dim {
        Dim(std::array::from_fn(|i| cas::number::plus(&self.0[i], &other.0[i])))
    }

    fn scale(&self, k: &Rational) -> Dim {
        // Through cas's integer fast path: the inference scales dimensions by small integers
        // all the time.
        Dim(std::array::from_fn(|i| cas::number::times(&self.0[i], k)))
    }

    /// The exponents of kg, m, s, A and K, when all are integers (a front end that names
    /// units by their SI base, as an FMU's unit definitions do).
    pub fn integer_exponents(&self) -> Option<[i32; 5]> {
        let mut out = [0; 5];
        for (e, o) in self.0.iter().zip(&mut out) {
            if !e.is_integer() {
                return None;
            }
            *o = i32::try_from(e.to_integer()).ok()?;
        }
        Some(out)
    }

    /// `kg·m²/s²`, or `1` for a dimensionless quantity.
    pub fn text(&self) -> String {
        let power = |e: &Rational| -> String {
            if e.is_one() {
                String::new()
            } else if e.is_integer() {
                cas::print::superscript(&e.to_string())
            } else {
                format!("^({e})")
            }
        };
        let up: Vec<String> = (0..5)
            .filter(|&i| self.0[i].is_positive())
            .map(|i| format!("{}{}", BASES[i], power(&self.0[i])))
            .collect();
        let down: Vec<String> = (0..5)
            .filter(|&i| self.0[i].is_negative())
            .map(|i| format!("{}{}", BASES[i], power(&-self.0[i].clone())))
            .collect();
        match (up.is_empty(), down.is_empty()) {
            (true, true) => "1 (dimensionless)".to_string(),
            (false, true) => up.join("·"),
            (true, false) => format!("1/{}", down.join("·")),
            (false, false) => format!("{}/{}", up.join("·"), down.join("·")),
        }
    }
}

/// The factor that turns a value in a unit into SI: `rational · π^pi_power`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scale {
    pub rational: Rational,
    pub pi_power: i32,
}

impl Scale {
    pub fn is_one(&self) -> bool {
        self.rational.is_one() && self.pi_power == 0
    }
}

/// A named unit: its dimension and its size in SI.
fn unit(name: &str) -> Option<(Dim, Rational, i32)> {
    let r = |n: i64, d: i64| Rational::new(n.into(), d.into());
    let one = r(1, 1);
    Some(match name {
        "kg" => (Dim::of([1, 0, 0, 0, 0]), one, 0),
        "g" => (Dim::of([1, 0, 0, 0, 0]), r(1, 1000), 0),
        "m" => (Dim::of([0, 1, 0, 0, 0]), one, 0),
        "km" => (Dim::of([0, 1, 0, 0, 0]), r(1000, 1), 0),
        "cm" => (Dim::of([0, 1, 0, 0, 0]), r(1, 100), 0),
        "mm" => (Dim::of([0, 1, 0, 0, 0]), r(1, 1000), 0),
        "s" => (Dim::of([0, 0, 1, 0, 0]), one, 0),
        "ms" => (Dim::of([0, 0, 1, 0, 0]), r(1, 1000), 0),
        "min" => (Dim::of([0, 0, 1, 0, 0]), r(60, 1), 0),
        "h" => (Dim::of([0, 0, 1, 0, 0]), r(3600, 1), 0),
        "Hz" => (Dim::of([0, 0, -1, 0, 0]), one, 0),
        "N" => (Dim::of([1, 1, -2, 0, 0]), one, 0),
        "J" => (Dim::of([1, 2, -2, 0, 0]), one, 0),
        "W" => (Dim::of([1, 2, -3, 0, 0]), one, 0),
        "Pa" => (Dim::of([1, -1, -2, 0, 0]), one, 0),
        "A" => (Dim::of([0, 0, 0, 1, 0]), one, 0),
        "C" => (Dim::of([0, 0, 1, 1, 0]), one, 0),
        "V" => (Dim::of([1, 2, -3, -1, 0]), one, 0),
        "T" => (Dim::of([1, 0, -2, -1, 0]), one, 0),
        "K" => (Dim::of([0, 0, 0, 0, 1]), one, 0),
        "rad" => (Dim::default(), one, 0),
        "deg" => (Dim::default(), r(1, 180), 1),
        "rev" => (Dim::default(), r(2, 1), 1),
        "rpm" => (Dim::of([0, 0, -1, 0, 0]), r(1, 30), 1),
        _ => return None,
    })
}

/// The dimension and SI scale of a written unit, or an error naming the unknown part.
pub fn parse_unit(u: &Unit) -> Result<(Dim, Scale), Diagnostic> {
    let mut dim = Dim::default();
    let mut scale = Scale { rational: Rational::one(), pi_power: 0 };
    for (name, power) in &u.factors {
        let Some((d, r, p)) = unit(&name.name) else {
            let mut diag = Diagnostic::error(name.span, format!("unknown unit `{}`", name.name))
                .with_label("not a unit lagrange knows");
            let near = lang::UNIT_NAMES.iter().find(|n| n.eq_ignore_ascii_case(&name.name));
            diag = match near {
                Some(n) => diag.with_hint(format!("did you mean `{n}`?")),
                None => diag.with_hint(format!("the units are {}", lang::UNIT_NAMES.join(", "))),
            };
            return Err(diag);
        };
        let k = Rational::from_integer((*power).into());
        dim = dim.add(&d.scale(&k));
        scale.rational *= cas::number::pow_int(&r, k.numer()).unwrap_or_else(Rational::one);
        scale.pi_power += p * power;
    }
    Ok((dim, scale))
}

/// The SI unit a value written in `u` is held in, spelled as Modelica and FMI spell units
/// (`kg.m2/s2`, `rad/s`; `1` for a dimensionless value): values are converted to SI when
/// resolved, so this is the unit of the number, not the one written. An angle keeps `rad`.
pub fn si_text(u: &Unit) -> Result<String, Diagnostic> {
    let (dim, _) = parse_unit(u)?;
    let angle = u
        .factors
        .iter()
        .any(|(name, _)| matches!(name.name.as_str(), "rad" | "deg" | "rev" | "rpm"));
    let power = |e: &Rational| if e.is_one() { String::new() } else { e.to_string() };
    let mut up: Vec<String> = (0..5)
        .filter(|&i| dim.0[i].is_positive())
        .map(|i| format!("{}{}", BASES[i], power(&dim.0[i])))
        .collect();
    if angle {
        up.insert(0, "rad".to_string());
    }
    let down: Vec<String> = (0..5)
        .filter(|&i| dim.0[i].is_negative())
        .map(|i| format!("{}{}", BASES[i], power(&-dim.0[i].clone())))
        .collect();
    let up = if up.is_empty() { "1".to_string() } else { up.join(".") };
    Ok(match down.len() {
        0 => up,
        1 => format!("{up}/{}", down[0]),
        _ => format!("{up}/({})", down.join(".")),
    })
}

/// The time dimension, which each prime takes off.
pub(crate) fn time() -> Form {
    Form::known(Dim::base(2))
}

/// An unknown dimension. Unknowns are ordered by the statement they arise in, then by their
/// order there: the order decides which unknown a fact is solved for, and so the wording of
/// later messages, and it must follow the file, whatever order the statements are resolved in
/// (`show` and `expect` lines last).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Unknown {
    stmt: usize,
    seq: usize,
}

/// A dimension that may still depend on unknowns: `known + Σ coefficient · unknown`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Form {
    known: Dim,
    unknowns: BTreeMap<Unknown, Rational>,
}

impl Form {
    pub(crate) fn known(d: Dim) -> Form {
        Form { known: d, unknowns: BTreeMap::new() }
    }

    fn unknown(u: Unknown) -> Form {
        Form { known: Dim::default(), unknowns: [(u, Rational::one())].into_iter().collect() }
    }

    /// `self + k·other`.
    pub(crate) fn plus(&self, other: &Form, k: &Rational) -> Form {
        let mut out = self.clone();
        out.known = out.known.add(&other.known.scale(k));
        for (u, c) in &other.unknowns {
            let slot = out.unknowns.entry(*u).or_insert_with(Rational::zero);
            cas::number::add_to(slot, &cas::number::times(c, k));
        }
        out.unknowns.retain(|_, c| !c.is_zero());
        out
    }

    pub(crate) fn times(&self, k: &Rational) -> Form {
        Form::default().plus(self, k)
    }

    /// The dimension of `primes` time derivatives of this.
    pub(crate) fn rate(&self, primes: u8) -> Form {
        self.plus(&time(), &-Rational::from_integer(primes.into()))
    }
}

/// The dimensions of a scene's values: scalars, and the entries of vectors and matrices.
// Shapes live only while one expression is resolved; boxing the scalar would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub(crate) enum Shape {
    Scalar(Form),
    Many(Vec<Form>),
}

impl Shape {
    pub(crate) fn forms(self) -> Vec<Form> {
        match self {
            Shape::Scalar(f) => vec![f],
            Shape::Many(v) => v,
        }
    }

    /// The scalar, or the first entry.
    pub(crate) fn first(self) -> Form {
        match self {
            Shape::Scalar(f) => f,
            Shape::Many(v) => v.into_iter().next().unwrap_or_default(),
        }
    }
}

/// What the resolver states about dimensions, to be solved once the scene is resolved.
// Each is stored once and read once; boxing the forms would cost an allocation apiece.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Fact {
    /// `a` and `b` have one dimension.
    Same {
        a: Form,
        b: Form,
        spans: (Span, Span),
        what: String,
    },
    Dimensionless {
        form: Form,
        span: Span,
        what: String,
    },
    /// A term of the energy (or, times a time, of the power).
    Energy {
        form: Form,
        span: Span,
    },
    /// The terms of a sum have one dimension, and the sum has theirs: each of `results` is
    /// `left`'s entry, or, when the terms disagree, a fresh unknown so that one mistake does
    /// not cascade.
    Sum {
        left: Vec<Form>,
        right: Vec<Form>,
        results: Vec<Unknown>,
        spans: (Span, Span),
    },
}

/// The facts about dimensions gathered while a scene is resolved.
#[derive(Clone)]
pub(crate) struct Inference {
    /// The statement being resolved, counted from 1 in file order (0 is before the first).
    stmt: usize,
    next: usize,
    /// What each unknown stands for, for messages.
    names: HashMap<Unknown, String>,
    facts: Vec<(usize, Fact)>,
    energy: Unknown,
    /// The unknowns of parameters: the name, where it is declared, and the
    /// declaration a dimensionless value would have (`param ka = 1/4 rad`), for messages.
    declared: HashMap<Unknown, Declared>,
    /// Where each declared name is used, by statement: a name without a unit takes its
    /// dimension from a use, and a later mismatch names that use.
    uses: HashMap<Unknown, Vec<(usize, Span)>>,
}

/// A parameter, as the messages about its dimension name it.
#[derive(Clone, Debug)]
struct Declared {
    name: String,
    span: Span,
    dimensionless: Option<String>,
}

impl Default for Inference {
    fn default() -> Self {
        let first = Unknown { stmt: 0, seq: 0 };
        let mut inference = Inference {
            stmt: 0,
            next: 1,
            names: HashMap::new(),
            facts: Vec::new(),
            energy: first,
            declared: HashMap::new(),
            uses: HashMap::new(),
        };
        inference.names.insert(first, "the energy".to_string());
        inference
    }
}

impl Inference {
    /// Facts and unknowns from here on belong to statement `index` (0-based) of the file.
    pub(crate) fn enter(&mut self, index: usize) {
        self.stmt = index + 1;
    }

    /// An unknown kept in reserve: named, and so used, only if its place needs it.
    pub(crate) fn reserve(&mut self) -> Unknown {
        self.next += 1;
        Unknown { stmt: self.stmt, seq: self.next }
    }

    pub(crate) fn named(&mut self, u: Unknown, what: &str) -> Form {
        self.names.insert(u, what.to_string());
        Form::unknown(u)
    }

    pub(crate) fn fresh(&mut self, what: &str) -> Form {
        let u = self.reserve();
        self.named(u, what)
    }

    /// The unknown dimension of a parameter declared at `span`; `dimensionless` is how its
    /// declaration would be written to make it dimensionless, if it can be. (A coordinate
    /// without a unit takes its dimension from a position as a matter of course; naming that
    /// use would be noise.)
    pub(crate) fn declared(
        &mut self,
        name: &str,
        span: Span,
        dimensionless: Option<String>,
    ) -> Form {
        let u = self.reserve();
        self.declared.insert(u, Declared { name: name.to_string(), span, dimensionless });
        self.named(u, name)
    }

    /// A use at `span` of a name whose dimension is `form`.
    pub(crate) fn used(&mut self, form: &Form, span: Span) {
        for u in form.unknowns.keys() {
            if self.declared.contains_key(u) {
                let uses = self.uses.entry(*u).or_default();
                if !uses.contains(&(self.stmt, span)) {
                    uses.push((self.stmt, span));
                }
            }
        }
    }

    /// The dimension of energy, whatever the scene's units make it.
    pub(crate) fn energy(&self) -> Form {
        Form::unknown(self.energy)
    }

    fn state(&mut self, fact: Fact) {
        self.facts.push((self.stmt, fact));
    }

    pub(crate) fn same(&mut self, a: &Form, b: &Form, span_a: Span, span_b: Span, what: &str) {
        let (a, b) = (a.clone(), b.clone());
        self.state(Fact::Same { a, b, spans: (span_a, span_b), what: what.to_string() });
    }

    pub(crate) fn dimensionless(&mut self, form: &Form, span: Span, what: &str) {
        self.state(Fact::Dimensionless { form: form.clone(), span, what: what.to_string() });
    }

    pub(crate) fn energy_term(&mut self, form: &Form, span: Span) {
        self.state(Fact::Energy { form: form.clone(), span });
    }

    /// The dimension of `l ± r`.
    pub(crate) fn sum(&mut self, l: Shape, r: Shape, span_l: Span, span_r: Span) -> Shape {
        let scalar = matches!(l, Shape::Scalar(_));
        let (left, right) = (l.forms(), r.forms());
        let results: Vec<Unknown> = left.iter().map(|_| self.reserve()).collect();
        let forms: Vec<Form> = results.iter().map(|u| self.named(*u, "a mismatched sum")).collect();
        self.state(Fact::Sum { left, right, results, spans: (span_l, span_r) });
        if scalar {
            Shape::Scalar(forms.into_iter().next().unwrap_or_default())
        } else {
            Shape::Many(forms)
        }
    }

    /// How far the facts go, to take back those of a walk that only looks.
    pub(crate) fn mark(&self) -> usize {
        self.facts.len()
    }

    pub(crate) fn rollback(&mut self, mark: usize) {
        self.facts.truncate(mark);
    }

    /// Solves the facts in the order of the statements they come from; returns the mismatches.
    pub(crate) fn solve(&self) -> Vec<Diagnostic> {
        let mut facts: Vec<&(usize, Fact)> = self.facts.iter().collect();
        facts.sort_by_key(|(stmt, _)| *stmt);
        let mut solver = Solver {
            names: &self.names,
            declared: &self.declared,
            uses: &self.uses,
            stmt: 0,
            origin: HashMap::new(),
            energy: self.energy,
            solved: HashMap::new(),
            void: HashSet::new(),
            energy_span: None,
            errors: Vec::new(),
        };
        for (stmt, fact) in facts {
            solver.stmt = *stmt;
            solver.fact(fact);
        }
        solver.errors
    }
}

struct Solver<'a> {
    names: &'a HashMap<Unknown, String>,
    declared: &'a HashMap<Unknown, Declared>,
    uses: &'a HashMap<Unknown, Vec<(usize, Span)>>,
    /// The statement of the fact being solved.
    stmt: usize,
    /// Where each declared name's dimension became known: the statement and the spans of
    /// the fact that decided it.
    origin: HashMap<Unknown, (usize, Span, Span)>,
    energy: Unknown,
    /// Solved unknowns, in terms of the others.
    solved: HashMap<Unknown, Form>,
    /// Entries of a vector sum whose terms disagreed: the sum became one fresh unknown, and
    /// nothing is checked against its other entries.
    void: HashSet<Unknown>,
    /// The first energy term, to point at when another disagrees with it.
    energy_span: Option<Span>,
    errors: Vec<Diagnostic>,
}

impl Solver<'_> {
    fn fact(&mut self, fact: &Fact) {
        match fact {
            Fact::Same { a, b, spans, what } => {
                if !self.is_void(a) && !self.is_void(b) {
                    self.same(a, b, spans.0, spans.1, what);
                }
            }
            Fact::Dimensionless { form, span, what } => {
                if !self.is_void(form) {
                    self.dimensionless(form, *span, what);
                }
            }
            Fact::Energy { form, span } => {
                if !self.is_void(form) {
                    let e = Form::unknown(self.energy);
                    let first = *self.energy_span.get_or_insert(*span);
                    self.same(form, &e, *span, first, "between energy terms");
                }
            }
            Fact::Sum { left, right, results, spans } => {
                let mut ok = true;
                for (a, b) in left.iter().zip(right) {
                    if !self.is_void(a) && !self.is_void(b) {
                        ok &= self.same(a, b, spans.0, spans.1, "between the terms of this sum");
                    }
                }
                for (i, (u, l)) in results.iter().zip(left).enumerate() {
                    if !ok {
                        // The sum is one unknown: its first entry stays free.
                        if i > 0 {
                            self.void.insert(*u);
                        }
                    } else if self.is_void(l) {
                        self.void.insert(*u);
                    } else {
                        let value = self.reduce(l);
                        self.solved.insert(*u, value);
                    }
                }
            }
        }
    }

    fn is_void(&self, f: &Form) -> bool {
        !self.void.is_empty() && f.unknowns.keys().any(|u| self.void.contains(u))
    }

    /// Substitutes every solved unknown.
    fn reduce(&self, f: &Form) -> Form {
        let mut out = Form::known(f.known.clone());
        for (u, k) in &f.unknowns {
            match self.solved.get(u) {
                Some(s) => out = out.plus(s, k),
                None => out = out.plus(&Form::unknown(*u), k),
            }
        }
        out
    }

    fn describe(&self, f: &Form) -> String {
        let f = self.reduce(f);
        if f.unknowns.is_empty() {
            return f.known.text();
        }
        let mut parts: Vec<String> = Vec::new();
        if !f.known.is_dimensionless() {
            parts.push(f.known.text());
        }
        for (u, k) in &f.unknowns {
            let name = self.names.get(u).map_or("?", String::as_str);
            parts.push(if k.is_one() { format!("[{name}]") } else { format!("[{name}]^({k})") });
        }
        parts.join("·")
    }

    /// Records that `a` and `b` have one dimension; on a contradiction, reports both spans.
    /// Returns whether they can be one.
    fn same(&mut self, a: &Form, b: &Form, span_a: Span, span_b: Span, what: &str) -> bool {
        let diff = self.reduce(&a.plus(b, &-Rational::one()));
        if let Some((&u, k)) = diff.unknowns.iter().next() {
            // Solve diff = 0 for u, and fold it into every earlier solution.
            let mut rest = diff.clone();
            rest.unknowns.remove(&u);
            let value = rest.times(&-(Rational::one() / k));
            let mut decided = Vec::new();
            for (v, s) in self.solved.iter_mut() {
                if let Some(c) = s.unknowns.remove(&u) {
                    *s = s.plus(&value, &c);
                    if s.unknowns.is_empty() {
                        decided.push(*v);
                    }
                }
            }
            if value.unknowns.is_empty() {
                decided.push(u);
            }
            for v in decided {
                if self.declared.contains_key(&v) {
                    self.origin.entry(v).or_insert((self.stmt, span_a, span_b));
                }
            }
            self.solved.insert(u, value);
            return true;
        }
        if diff.known.is_dimensionless() {
            return true;
        }
        let (da, db) = (self.describe(a), self.describe(b));
        let mut d = Diagnostic::error(
            span_a,
            format!("dimensions do not match {what}: {da} here, {db} there"),
        )
        .with_label(da.clone());
        if span_b != span_a {
            d = d.with_related(span_b, db);
        }
        let hint = "every term added or equated must have one dimension; `--no-units` turns this check off";
        let d = match self.inferred(a, b) {
            Some((related, why)) => related
                .into_iter()
                .fold(d, |d, (span, label)| d.with_related(span, label))
                .with_hint(why),
            None => d.with_hint(hint),
        };
        self.errors.push(d);
        false
    }

    /// A mismatch that may come from a name without a unit, which took its dimension from a
    /// use elsewhere: that use and the declaration, for `d`, and the hint that goes with them.
    /// The use that decided the dimension may be the mistake rather than the place the
    /// mismatch shows, which the file's order alone decides.
    fn inferred(&self, a: &Form, b: &Form) -> Option<(Vec<(Span, String)>, String)> {
        let mut names: Vec<Unknown> = a.unknowns.keys().chain(b.unknowns.keys()).copied().collect();
        names.sort();
        names.dedup();
        let mut related = Vec::new();
        let mut hints = Vec::new();
        for u in names {
            let (Some(declared), Some(&(stmt, span_a, span_b))) =
                (self.declared.get(&u), self.origin.get(&u))
            else {
                continue;
            };
            let dim = self.reduce(&Form::unknown(u));
            if stmt == u.stmt || !dim.unknowns.is_empty() || dim.known.is_dimensionless() {
                continue;
            }
            let (from, to) = (span_a.start.min(span_b.start), span_a.end.max(span_b.end));
            let uses = self.uses.get(&u).map_or(&[][..], Vec::as_slice);
            let at = uses
                .iter()
                .find(|(s, span)| *s == stmt && span.start >= from && span.end <= to)
                .or_else(|| uses.iter().find(|(s, _)| *s == stmt))
                .map_or(span_a, |(_, span)| *span);
            let name = &declared.name;
            let text = dim.known.text();
            related.push((at, format!("`{name}` takes {text} from this use")));
            related.push((declared.span, format!("`{name}` is declared here without a unit")));
            hints.push(match &declared.dimensionless {
                Some(example) => format!(
                    "`{name}` has no unit, so it took {text} from its first use; if that use is \
                     the mistake and `{name}` is dimensionless, declare `{example}` (`rad` marks \
                     a value dimensionless), and the error moves to that use"
                ),
                None => format!(
                    "`{name}` has no unit, so it took {text} from its first use; if that use is \
                     the mistake, give `{name}` its unit where it is declared, and the error \
                     moves to that use"
                ),
            });
        }
        if related.is_empty() {
            return None;
        }
        Some((related, hints.join("; ")))
    }

    fn dimensionless(&mut self, f: &Form, span: Span, what: &str) {
        let diff = self.reduce(f);
        if diff.unknowns.is_empty() && !diff.known.is_dimensionless() {
            let d = Diagnostic::error(span, format!("{what} must be dimensionless, but this is {}", diff.known.text()))
                .with_label(diff.known.text())
                .with_hint("divide by a quantity of the same dimension, e.g. sin(x/L); a name without a unit takes its dimension from its uses, its initial value and rate among them (write `phi' = 1 rad/s`, not `phi' = 1`)");
            self.errors.push(d);
        } else {
            self.same(f, &Form::default(), span, span, what);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    // The inference is checked through the walk that states its facts.
    use crate::dimension_errors as check;

    fn errors(source: &str) -> Vec<String> {
        let file = lang::parse(source).expect("parses");
        check(&file).into_iter().map(|d| d.message).collect()
    }

    #[test]
    fn si_units_are_spelled_as_modelica_spells_them() {
        let source = "param a = 1 N, b = 2 kg/s^2, c = 30 deg, d = 60 rpm, e = 1 J/kg, f = 3 \
                      cm/ms, g = 1 T, h = 1/2 rad, i = 1/2\ncoord x\nparticle p { mass 1; position (x, 0) }\n";
        let file = lang::parse(source).expect("parses");
        let (model, _) = crate::resolve(&file, source).expect("resolves");
        let units: Vec<String> = model
            .params
            .iter()
            .map(|p| p.unit.as_ref().map(|u| si_text(u).expect("a unit")).unwrap_or_default())
            .collect();
        let expected = ["kg.m/s2", "kg/s2", "rad", "rad/s", "m2/s2", "m/s", "kg/(s2.A)", "rad", ""];
        assert_eq!(units, expected);
    }

    #[test]
    fn consistent_scenes_pass() {
        let rod = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord x = L/4, y, theta = pi/6\nbody rod { mass m; inertia m*L^2/12; position (x, y); angle theta }\nconstraint floor: y = L/2*cos(theta)\ngravity g\nexpect x'' = 0\nexpect at start: theta'' = 12/7*g/L\n";
        assert_eq!(errors(rod), Vec::<String>::new());
    }

    #[test]
    fn an_angle_where_a_length_is_needed_is_caught() {
        let bad = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord theta = pi/6\nparticle p { mass m; position (L*sin(theta), -L*cos(theta)) }\npotential m*g*theta\n";
        let e = errors(bad);
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].contains("kg·m/s²") && e[0].contains("kg·m²/s²"), "{e:?}");
    }

    #[test]
    fn function_arguments_must_be_dimensionless() {
        let bad = "param L = 2 m\ncoord x = 1 m\nparticle p { mass 1; position (sin(x), 0) }\n";
        let e = errors(bad);
        assert!(e.iter().any(|m| m.contains("argument of sin")), "{e:?}");
    }

    const CHARGE: &str = "param m = 1 kg, q = 1 C, B = 2 T\ncoord x = 1 m, x' = 0\ncoord y = 0, y' = 1 m/s\nlagrangian m/2*(x'^2 + y'^2) + q*B/2*(x*y' - y*x')\n";

    #[test]
    fn zero_has_every_dimension() {
        let matrix = format!("{CHARGE}expect [m, 0; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
        assert_eq!(errors(&matrix), Vec::<String>::new());
        for zero in ["0", "-0.0", "0*pi", "(1/2 - 0.5)", "sin(pi)", "(sqrt(4) - 2)"] {
            let m = format!("{CHARGE}expect [m, {zero}; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
            assert_eq!(errors(&m), Vec::<String>::new(), "{zero}");
            let product = format!("{CHARGE}expect m*x'' + {zero}*y'' = q*B*y'\n");
            assert_eq!(errors(&product), Vec::<String>::new(), "{zero}");
        }
        // A number that is not zero still makes a product keep the other factor's dimension.
        let wrong = format!("{CHARGE}expect [m, 1; 0, m] * [x''; y''] = [q*B*y'; -q*B*x']\n");
        let e = errors(&wrong);
        assert!(e.len() == 1 && e[0].contains("matrix product"), "{e:?}");
    }

    #[test]
    fn number_only_expressions_take_the_dimension_their_place_needs() {
        let pendulum = "param m = 1 kg, L = 1 m, g = 9.81 m/s^2\ncoord theta = 0, theta' = RATE\nparticle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\ngravity g\n";
        for rate in ["0.866", "1/2*sqrt(3)", "sqrt(3)/2", "2*pi", "1/3", "-1/2", "-(1/2)"] {
            assert_eq!(errors(&pendulum.replace("RATE", rate)), Vec::<String>::new(), "{rate}");
        }
        let sum =
            "param L = 1 m\ncoord x = 1 m\nparticle p { mass 1; position (x + sqrt(2)/2, 2*pi) }\n";
        assert_eq!(errors(sum), Vec::<String>::new());
        // A name is not a number: a `let` name for a number is dimensionless like any other.
        let named = "let c = 2\ncoord x = 1 m\nparticle p { mass 1; position (x + c, 0) }\n";
        assert_eq!(errors(named).len(), 1);
    }

    #[test]
    fn units_after_expressions_and_denominators_only() {
        let ok = "param m = 1 kg, L = 1 m, k = 1/2 1/m, c = sqrt(2) N/m\ncoord x = 0 m\nparticle p { mass m; position (x, 0) }\npotential c/2*x^2 + c*k*x^3\n";
        assert_eq!(errors(ok), Vec::<String>::new());
        // `0 m` keeps its unit: x is a length, and so x + t is refused.
        let zero_with_unit = "coord x = 0 m\nparticle p { mass 1; position (x + t, 0) }\n";
        assert_eq!(errors(zero_with_unit).len(), 1);
        let inverse_length = "param k = 1/2 1/m, L = 1 m\ncoord x = 1 m\nparticle p { mass 1; position (x + k, 0) }\n";
        let e = errors(inverse_length);
        assert!(e.len() == 1 && e[0].contains("1/m"), "{e:?}");
    }

    #[test]
    fn inconsistent_scenes_still_fail() {
        let sum = "param L = 1 m\ncoord x = 1 s\nparticle p { mass 1; position (x + L, 0) }\n";
        assert_eq!(errors(sum).len(), 1);
        let expect = "param m = 1 kg\ncoord x = 1 m\nparticle p { mass m; position (x, 0) }\nexpect m*x'' = x\n";
        let e = errors(expect);
        assert!(e.len() == 1 && e[0].contains("expectation"), "{e:?}");
    }

    #[test]
    fn a_parameter_without_a_unit_names_the_use_that_gave_it_one() {
        let scene = |ka: &str| {
            format!(
                "param m = 1 kg, L = 1 m, ka = {ka}\ncoord theta = 0.3\nlet r = L*sin(theta) + ka\n\
                 body rod {{ mass m; inertia ka*m*L^2; position (r, -L*cos(theta)); angle theta }}\n"
            )
        };
        let source = scene("1/4");
        let at = |text: &str, n: usize| {
            let start = source.match_indices(text).nth(n).expect("in the scene").0;
            Span::new(start, start + text.len())
        };
        let file = lang::parse(&source).expect("parses");
        let e = check(&file);
        assert_eq!(e.len(), 1, "{e:?}");
        assert_eq!(e[0].span, at("ka*m*L^2", 0));
        let related: Vec<(Span, &str)> =
            e[0].related.iter().map(|(s, l)| (*s, l.as_str())).collect();
        assert!(related.contains(&(at("ka", 1), "`ka` takes m from this use")), "{related:?}");
        assert!(related.contains(&(at("ka", 0), "`ka` is declared here without a unit")));
        assert!(e[0]
            .hint
            .as_deref()
            .is_some_and(|h| h.contains("(`rad` marks a value dimensionless)")));
        // Marked dimensionless, `ka` is blamed where it is used as a length.
        let source = scene("1/4 rad");
        let e = check(&lang::parse(&source).expect("parses"));
        let sum = source.find("L*sin(theta) + ka").expect("the let");
        assert!(e.len() == 1 && e[0].span.start == sum && e[0].related.len() == 1, "{e:?}");
    }

    #[test]
    fn the_parser_knows_every_unit() {
        for name in lang::UNIT_NAMES {
            assert!(unit(name).is_some(), "{name}");
        }
    }

    #[test]
    fn units_scale_to_si() {
        let file = lang::parse("param a = 30 deg, b = 10 cm\n").expect("parses");
        let lang::StmtKind::Param(ps) = &file.stmts[0].kind else { panic!() };
        let (_, s) = parse_unit(ps[0].unit.as_ref().expect("unit")).expect("known");
        assert_eq!((s.rational, s.pi_power), (Rational::new(1.into(), 180.into()), 1));
        let (d, s) = parse_unit(ps[1].unit.as_ref().expect("unit")).expect("known");
        assert_eq!(d, Dim::base(1));
        assert_eq!(s.rational, Rational::new(1.into(), 100.into()));
    }
}
