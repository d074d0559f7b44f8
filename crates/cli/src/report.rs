//! The `derive` report in three formats: text for people, LaTeX for papers, JSON for programs.

use cas::number::Signed;
use cas::{ExprId, Pool, Rational, Style, SymId};
use engine::derived::Derived;
use mechanics::{Derivation, Equation};
use model::Value;
use serde_json::{json, Map, Value as Json};
use verify::{NumericValue, ShownAtStart};

/// A terminating decimal for rationals like 981/100, so parameter values read as written.
fn decimal(q: &Rational) -> Option<String> {
    let mut d = q.denom().clone();
    let mut places = 0u32;
    let (two, five) = (2.into(), 5.into());
    let zero = 0.into();
    while &d % &two == zero || &d % &five == zero {
        if &d % &two == zero {
            d /= &two;
        }
        if &d % &five == zero {
            d /= &five;
        }
        places += 1;
        // Values pasted from elsewhere carry up to 17 digits; a float's binary fraction, more.
        if places > 17 {
            return None;
        }
    }
    if d != 1.into() {
        return None;
    }
    let scaled = q * num_ten_pow(places);
    let digits = scaled.to_integer().abs().to_string();
    let sign = if q.is_negative() { "-" } else { "" };
    if places == 0 {
        return Some(format!("{sign}{digits}"));
    }
    let padded = format!("{digits:0>width$}", width = places as usize + 1);
    let (whole, frac) = padded.split_at(padded.len() - places as usize);
    Some(format!("{sign}{whole}.{frac}"))
}

fn num_ten_pow(n: u32) -> cas::number::Rational {
    let mut r = Rational::from_integer(1.into());
    for _ in 0..n {
        r *= Rational::from_integer(10.into());
    }
    r
}

/// `= value` of a start position, or `≈ value` where it was solved in numbers (a decimal
/// whose last digits are the solve's rounding).
/// Once positions were solved, the rates solved at them are exact only in those decimals, and
/// read better as numbers too.
fn start_value_text(d: &Derivation, s: cas::SymId, e: ExprId, style: Style) -> String {
    let pool = &d.model.pool;
    let rate = pool.symbol(s).order() > 0;
    let numeric = d.solved_start_positions.contains(&s)
        || (rate && !d.solved_start_positions.is_empty() && pool.as_num(e).is_none());
    let values = if numeric { verify::parameter_values(d).ok() } else { None };
    match values {
        Some(params) => {
            let mut at = vec![f64::NAN; pool.symbol_count()];
            for (p, v) in params {
                at[p.index()] = v;
            }
            let sign = if style == Style::Latex { "\\approx" } else { "≈" };
            format!("{sign} {}", significant(numeric::eval(pool, e, &at), 12, style))
        }
        None => format!("= {}", value_text(pool, e, style)),
    }
}

pub(crate) fn value_text(pool: &Pool, e: ExprId, style: Style) -> String {
    match pool.as_num(e).and_then(decimal) {
        // The minus sign every other printed number has.
        Some(d) if style == Style::Unicode => d.replacen('-', "−", 1),
        Some(d) if style != Style::Latex => d,
        _ => pool.print(e, style),
    }
}

fn unit_text(unit: &lang::Unit, style: Style) -> String {
    let power = |p: i32| match style {
        Style::Unicode => cas::print::superscript(&p.to_string()),
        Style::Ascii => format!("^{p}"),
        Style::Latex => format!("^{{{p}}}"),
    };
    let mut up = Vec::new();
    let mut down = Vec::new();
    for (name, p) in &unit.factors {
        let part =
            |q: i32| if q == 1 { name.name.clone() } else { format!("{}{}", name.name, power(q)) };
        if *p >= 0 {
            up.push(part(*p));
        } else {
            down.push(part(-*p));
        }
    }
    let sep = if style == Style::Unicode { "·" } else { "*" };
    let mut text = if up.is_empty() { "1".to_string() } else { up.join(sep) };
    // Every denominator factor gets its own `/`: `kg/m*s` would read back as kg·s/m.
    for d in down {
        text.push('/');
        text.push_str(&d);
    }
    text
}

/// Display width in terminal columns: combining marks (the dots of θ̇) take none.
pub(crate) fn width(s: &str) -> usize {
    unicode_width::UnicodeWidthStr::width(s)
}

fn pad(s: &str, w: usize) -> String {
    format!("{s}{}", " ".repeat(w.saturating_sub(width(s))))
}

/// A matrix or column with tall brackets, each line prefixed (the first with `label`).
pub(crate) fn bracketed(rows: &[Vec<String>], label: &str) -> Vec<String> {
    let cols = rows.first().map_or(0, |r| r.len());
    let widths: Vec<usize> =
        (0..cols).map(|j| rows.iter().map(|r| width(&r[j])).max().unwrap_or(0)).collect();
    let n = rows.len();
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            let (l, rt) = match (n, i) {
                (1, _) => ('[', ']'),
                (_, 0) => ('⎡', '⎤'),
                (_, i) if i == n - 1 => ('⎣', '⎦'),
                _ => ('⎢', '⎥'),
            };
            let cells: Vec<String> = r.iter().zip(&widths).map(|(c, w)| pad(c, *w)).collect();
            let prefix = if i == 0 { label.to_string() } else { " ".repeat(width(label)) };
            format!("{prefix}{l} {} {rt}", cells.join("   "))
        })
        .collect()
}

fn value_lines(pool: &Pool, full: bool, label: &str, v: &Value) -> Vec<String> {
    match v {
        Value::Scalar(e) => vec![format!("{label}{}", entry(pool, *e, full))],
        // A vector is a column, as in a hand derivation.
        Value::Vector(xs) => {
            let rows: Vec<Vec<ExprId>> = xs.iter().map(|e| vec![*e]).collect();
            bracketed(&cells(pool, &rows, full), label)
        }
        Value::Matrix(m) => {
            let rows = cells(pool, m, full);
            bracketed(&rows, label)
        }
    }
}

fn sym_text(pool: &Pool, s: SymId, style: Style) -> String {
    pool.symbol_text(s, style)
}

/// The report for people.
pub fn text(d: &mut Derivation) -> String {
    text_with(d, false)
}

/// Past this many characters an entry of the text report is a wall no one reads (a bicycle's
/// equations run to 16,000): its size stands in its place unless the whole report is asked
/// for. Every example but the bicycle prints its entries in full well under it.
pub const TEXT_ENTRY_LIMIT: usize = 1_000;

/// An entry of the text report: in full, or past [`TEXT_ENTRY_LIMIT`] characters (unless
/// `full`) its size and how to see it, as an entry past the printer's own node limit shows
/// its operations.
fn entry(pool: &Pool, e: ExprId, full: bool) -> String {
    shortened(pool, e, pool.print(e, Style::Unicode), TEXT_ENTRY_LIMIT, full)
}

/// `printed` (of `e`), or its size when it runs past `limit` characters and not `full`.
fn shortened(pool: &Pool, e: ExprId, printed: String, limit: usize, full: bool) -> String {
    let characters = printed.chars().count();
    if full || characters <= limit {
        return printed;
    }
    let operations = pool.operation_count(e);
    format!("⟨{operations} operations, {characters} characters; --full prints it⟩")
}

/// The cells of a matrix in the text report. Its columns are as wide as their widest entry,
/// so a row runs past [`TEXT_ENTRY_LIMIT`] long before any one entry does: then an entry
/// wider than its share of the limit shows its size (unless `full`).
fn cells(pool: &Pool, rows: &[Vec<ExprId>], full: bool) -> Vec<Vec<String>> {
    let printed: Vec<Vec<String>> =
        rows.iter().map(|r| r.iter().map(|e| pool.print(*e, Style::Unicode)).collect()).collect();
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widest = |k: usize| printed.iter().filter_map(|r| r.get(k)).map(|c| width(c)).max();
    let line: usize = (0..columns).filter_map(widest).sum();
    if full || line <= TEXT_ENTRY_LIMIT {
        return printed;
    }
    let share = TEXT_ENTRY_LIMIT / columns.max(1);
    rows.iter()
        .zip(printed)
        .map(|(r, p)| r.iter().zip(p).map(|(e, c)| shortened(pool, *e, c, share, false)).collect())
        .collect()
}

/// One section of the `derive` report with its data, in the order the text report prints
/// them. The three formats walk this one list, each rendering a section its own way (or not
/// at all: LaTeX leaves out the parameters, only JSON carries the scene's primitive model).
enum Section<'a> {
    Title(Option<&'a str>),
    Parameters(&'a [model::Param]),
    /// As declared, and the generalized coordinates left after elimination.
    Coordinates {
        declared: &'a [model::Coord],
        generalized: &'a [SymId],
    },
    Constraints {
        constraints: &'a [model::Constraint],
        sides: &'a [(ExprId, ExprId)],
        left_out: &'a [Option<String>],
    },
    Energies {
        kinetic: ExprId,
        potential: ExprId,
        lagrangian: Option<ExprId>,
    },
    Equations(&'a [Equation]),
    MassMatrix {
        mass: &'a [Vec<ExprId>],
        forcing: &'a [ExprId],
        multipliers: &'a [mechanics::Multiplier],
    },
    Independent(&'a mechanics::IndependentForm),
    /// With the accelerations solved for, and as functions of the state.
    Reactions {
        reactions: &'a [(SymId, ExprId)],
        of_state: &'a [(SymId, ExprId)],
    },
    Shown(&'a [(model::Show, Value)]),
    AtStart {
        at_start: &'a ShownAtStart,
        state: &'a [(SymId, ExprId)],
    },
    Model,
}

/// The report's sections, built once from what `derive` computed.
fn sections<'a>(d: &'a Derivation, derived: &'a Derived) -> Vec<Section<'a>> {
    let mut sections = vec![
        Section::Title(d.model.title.as_deref()),
        Section::Parameters(&d.model.params),
        Section::Coordinates { declared: &d.model.coords, generalized: &d.coords },
        Section::Constraints {
            constraints: &d.model.constraints,
            sides: &derived.constraint_sides,
            left_out: &derived.left_out,
        },
        Section::Energies {
            kinetic: derived.kinetic,
            potential: derived.potential,
            lagrangian: derived.lagrangian,
        },
        Section::Equations(&derived.equations),
        Section::MassMatrix {
            mass: &derived.mass_matrix,
            forcing: &derived.forcing,
            multipliers: &d.multipliers,
        },
    ];
    sections.extend(derived.independent.as_ref().map(Section::Independent));
    sections.extend([
        Section::Reactions { reactions: &derived.reactions, of_state: &derived.reactions_of_state },
        Section::Shown(&derived.shown),
        Section::AtStart { at_start: &derived.at_start, state: &derived.start_state },
        Section::Model,
    ]);
    sections
}

/// A format of the report: it renders each section in turn, then gives its text.
trait Renderer {
    fn section(&mut self, section: &Section);
    fn finish(self) -> String;
}

/// Derives what the report shows and walks its sections with the renderer `make` builds.
fn render<'d, R: Renderer>(
    d: &'d mut Derivation,
    make: impl FnOnce(&'d Derivation) -> R,
) -> String {
    let derived = engine::derived::collect(d);
    let d: &'d Derivation = d;
    let mut renderer = make(d);
    for section in &sections(d, &derived) {
        renderer.section(section);
    }
    renderer.finish()
}

/// Lines joined, with a final newline.
fn lines_text(out: &[String]) -> String {
    let mut text = out.join("\n");
    text.push('\n');
    text
}

/// The report for people; `full` prints every entry whole (see [`TEXT_ENTRY_LIMIT`]).
pub fn text_with(d: &mut Derivation, full: bool) -> String {
    render(d, |d| Text { d, pool: &d.model.pool, full, out: Vec::new() })
}

/// The text report, a line at a time.
struct Text<'a> {
    d: &'a Derivation,
    pool: &'a Pool,
    full: bool,
    out: Vec<String>,
}

const U: Style = Style::Unicode;

impl Renderer for Text<'_> {
    fn section(&mut self, section: &Section) {
        match section {
            Section::Title(Some(title)) => {
                self.out.push(title.to_string());
                self.out.push("═".repeat(width(title)));
                self.out.push(String::new());
            }
            Section::Title(None) | Section::Model => {}
            Section::Parameters(params) => self.parameters(params),
            Section::Coordinates { declared, .. } => self.coordinates(declared),
            Section::Constraints { constraints, sides, left_out } => {
                self.constraints(constraints, sides, left_out)
            }
            Section::Energies { kinetic, potential, lagrangian } => {
                self.out.push("Energies".into());
                self.out.push(format!("  T = {}", self.print(*kinetic)));
                self.out.push(format!("  V = {}", self.print(*potential)));
                if let Some(l) = lagrangian {
                    self.out.push(format!("  L = {}", self.print(*l)));
                }
            }
            Section::Equations(equations) => {
                self.out.push("Equations of motion".into());
                for eq in *equations {
                    self.out.push(format!("  {} = {}", self.print(eq.lhs), self.print(eq.rhs)));
                }
            }
            Section::MassMatrix { mass, forcing, multipliers } => {
                self.mass_matrix(mass, forcing, multipliers)
            }
            Section::Independent(form) => self.independent(form),
            Section::Reactions { reactions, of_state } => self.reactions(reactions, of_state),
            Section::Shown(shown) => self.shown(shown),
            Section::AtStart { at_start, state } => self.at_start(at_start, state),
        }
    }

    fn finish(self) -> String {
        lines_text(&self.out)
    }
}

impl Text<'_> {
    fn print(&self, e: ExprId) -> String {
        entry(self.pool, e, self.full)
    }

    fn sym(&self, s: SymId) -> String {
        sym_text(self.pool, s, U)
    }

    fn parameters(&mut self, params: &[model::Param]) {
        if params.is_empty() {
            return;
        }
        self.out.push("Parameters".into());
        for p in params {
            let mut line = format!("  {}", self.sym(p.sym));
            if let Some(v) = p.value {
                line.push_str(&format!(" = {}", value_text(self.pool, v, U)));
            }
            if let Some(unit) = &p.unit {
                line.push_str(&format!(" {}", unit_text(unit, U)));
            }
            self.out.push(line);
        }
    }

    fn coordinates(&mut self, coords: &[model::Coord]) {
        let (d, pool) = (self.d, self.pool);
        self.out.push("Coordinates".into());
        for c in coords {
            let name = self.sym(c.sym);
            if let Some(e) = d.eliminated.iter().find(|e| e.coord == c.sym) {
                let cname = &d.model.constraints[e.constraint].name;
                let solution = self.print(e.solution);
                self.out.push(format!("  {name} = {solution}   (eliminated by {cname})"));
            } else {
                let rate_symbol = pool.lookup_symbol(&format!("{}'", c.name));
                let rate = rate_symbol.map(|r| self.sym(r)).unwrap_or_default();
                let solved = if d.solved_start_positions.contains(&c.sym) {
                    ", solved from the constraints"
                } else {
                    ""
                };
                self.out.push(format!(
                    "  {name}   (from {name} {}, {rate} {}{solved})",
                    start_value_text(d, c.sym, c.initial, U),
                    start_value_text(d, rate_symbol.unwrap_or(c.sym), c.initial_rate, U)
                ));
            }
        }
    }

    fn constraints(
        &mut self,
        constraints: &[model::Constraint],
        sides: &[(ExprId, ExprId)],
        left_out: &[Option<String>],
    ) {
        if constraints.is_empty() {
            return;
        }
        self.out.push("Constraints".into());
        for (i, c) in constraints.iter().enumerate() {
            let (lhs, rhs) = sides[i];
            self.out.push(format!("  {}: {} = {}", c.name, self.print(lhs), self.print(rhs)));
            let force = self.sym(c.force_symbol);
            if let Some(e) = self.d.eliminated.iter().find(|e| e.constraint == i) {
                let what = if c.force_requested {
                    format!("; its reaction {force} is derived below")
                } else {
                    String::new()
                };
                if let Some(phi) = e.integrated {
                    self.out.push(format!("    integrates to {} = 0", self.print(phi)));
                }
                self.out.push(format!("    solved for {}{what}", self.sym(e.coord)));
            } else if let Some(why) = &left_out[i] {
                self.out.push(format!("    left out, as it restrains nothing more: {why}"));
            } else if c.kind == model::ConstraintKind::Velocity {
                self.out.push(format!(
                    "    a velocity constraint, kept with the multiplier {force} (generalized force {force}·∂Φ/∂q̇)"
                ));
            } else {
                self.out.push(format!(
                    "    kept with the multiplier {force} (generalized force {force}·∂Φ/∂q)"
                ));
            }
        }
    }

    fn mass_matrix(
        &mut self,
        mass: &[Vec<ExprId>],
        forcing: &[ExprId],
        multipliers: &[mechanics::Multiplier],
    ) {
        let (pool, full) = (self.pool, self.full);
        let q: Vec<String> = self.d.coords.iter().map(|s| self.sym(*s)).collect();
        let extra = if multipliers.is_empty() { "" } else { " + Jᵀ·λ" };
        self.out
            .push(format!("Mass-matrix form  M(q)·q̈ = f(q, q̇){extra},  q = ({})", q.join(", ")));
        self.out.extend(bracketed(&cells(pool, mass, full), "  M = "));
        let f_rows: Vec<Vec<ExprId>> = forcing.iter().map(|e| vec![*e]).collect();
        self.out.extend(bracketed(&cells(pool, &f_rows, full), "  f = "));
        for m in multipliers {
            let name = self.sym(m.lambda);
            let row = cells(pool, std::slice::from_ref(&m.jacobian), full);
            self.out.extend(bracketed(&row, &format!("  J({name}) = ")));
            self.out.push(format!("  γ({name}) = {}", self.print(m.bias)));
        }
    }

    fn independent(&mut self, form: &mechanics::IndependentForm) {
        let names = |s: &[SymId]| s.iter().map(|r| self.sym(*r)).collect::<Vec<_>>();
        let dependent: Vec<SymId> = form.dependent.iter().map(|(d, _)| *d).collect();
        let heading = format!(
            "In the independent rates  ({}; the constraints give {})",
            names(&form.independent).join(", "),
            names(&dependent).join(", ")
        );
        self.out.push(heading);
        for (d, e) in &form.dependent {
            self.out.push(format!("  {} = {}", self.sym(*d), self.print(*e)));
        }
        for e in &form.equations {
            self.out.push(format!("  {} = 0", self.print(*e)));
        }
    }

    fn reactions(&mut self, reactions: &[(SymId, ExprId)], of_state: &[(SymId, ExprId)]) {
        if reactions.is_empty() {
            return;
        }
        self.out.push("Reactions".into());
        for ((s, e), (_, explicit)) in reactions.iter().zip(of_state) {
            let mut line = format!("  {} = {}", self.sym(*s), self.print(*e));
            if explicit != e {
                line.push_str(&format!("\n    = {}", self.print(*explicit)));
            }
            self.out.push(line);
        }
    }

    fn shown(&mut self, shown: &[(model::Show, Value)]) {
        if shown.is_empty() {
            return;
        }
        let (d, pool) = (self.d, self.pool);
        self.out.push("Shown".into());
        for (show, v) in shown {
            let label = d.show_label(show, U);
            let unsolved = match v {
                Value::Scalar(e) => {
                    pool.as_sym(*e).filter(|s| d.multipliers.iter().any(|m| m.lambda == *s))
                }
                _ => None,
            };
            if unsolved.is_some() {
                // Past the size where the symbolic solution stays readable, say so rather than
                // print `λ = λ`.
                let unknowns = d.coords.len() + d.multipliers.len();
                self.out.push(format!(
                    "  {label}: a multiplier of the equations above; {unknowns} unknowns are too many to solve for it symbolically (`lagrange simulate --output {}` gives its values)",
                    show.label
                ));
                continue;
            }
            self.out.extend(value_lines(pool, self.full, &format!("  {label} = "), v));
        }
    }

    fn at_start(&mut self, at_start: &ShownAtStart, state: &[(SymId, ExprId)]) {
        let (d, pool) = (self.d, self.pool);
        let state: Vec<String> = state
            .iter()
            .map(|(s, e)| format!("{} {}", self.sym(*s), start_value_text(d, *s, *e, U)))
            .collect();
        let start_heading = || format!("At the start  ({})", state.join(", "));
        match at_start {
            ShownAtStart::Exact(items) if !items.is_empty() => {
                self.out.push(start_heading());
                for (show, v) in items {
                    let label = d.show_label(show, U);
                    self.out.extend(value_lines(pool, self.full, &format!("  {label} = "), v));
                }
            }
            ShownAtStart::Exact(_) => {}
            ShownAtStart::Numeric { items, unknowns, digits, params, because } => {
                self.out.push(start_heading());
                let at: Vec<String> = params
                    .iter()
                    .map(|(s, v)| format!("{} = {}", self.sym(*s), significant(*v, 15, U)))
                    .collect();
                self.out.push(format!(
                    "  solved numerically: {}; at {}, to about {digits} significant digits",
                    because.words(*unknowns),
                    at.join(", ")
                ));
                for (show, v) in items {
                    let label = d.show_label(show, U);
                    self.out.push(format!("  {label} ≈ {}", numeric_text(v, *digits, U)));
                }
            }
            ShownAtStart::Unvalued { unknowns, missing } => self.out.push(format!(
                "At the start: {unknowns} unknowns are too many to solve for exactly, and solving numerically needs a value for {}",
                missing.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")
            )),
            ShownAtStart::Singular => self
                .out
                .push("At the start: the mass matrix is singular; nothing can be shown".into()),
        }
    }
}

/// The report as a LaTeX fragment (amsmath).
pub fn latex(d: &mut Derivation) -> String {
    render(d, |d| Latex { d, pool: &d.model.pool, out: Vec::new(), items: Vec::new() })
}

/// The LaTeX report: its reactions, shown quantities and those at the start share one
/// `align`, printed last.
struct Latex<'a> {
    d: &'a Derivation,
    pool: &'a Pool,
    out: Vec<String>,
    items: Vec<(String, String)>,
}

const L: Style = Style::Latex;

impl Renderer for Latex<'_> {
    fn section(&mut self, section: &Section) {
        let (d, pool) = (self.d, self.pool);
        match section {
            Section::Title(Some(title)) => self.out.push(format!("% {title}")),
            Section::Title(None)
            | Section::Parameters(_)
            | Section::Coordinates { .. }
            | Section::Constraints { .. }
            | Section::Model => {}
            Section::Energies { kinetic, potential, lagrangian } => {
                let mut lines = vec![
                    format!("  T &= {}", pool.print(*kinetic, L)),
                    format!("  V &= {}", pool.print(*potential, L)),
                ];
                lines.extend(lagrangian.map(|e| format!("  L &= {}", pool.print(e, L))));
                self.align("Energies", lines);
            }
            Section::Equations(equations) => {
                let lines = equations
                    .iter()
                    .map(|eq| format!("  {} &= {}", pool.print(eq.lhs, L), pool.print(eq.rhs, L)))
                    .collect();
                self.align("Equations of motion", lines);
            }
            Section::MassMatrix { mass, forcing, .. } => {
                let q: Vec<String> = d.accels.iter().map(|s| sym_text(pool, *s, L)).collect();
                self.out.push("% Mass-matrix form".into());
                self.out.push("\\begin{equation}".into());
                self.out.push(format!(
                    "  {} {} = {}",
                    bmatrix(&latex_rows(pool, mass)),
                    bmatrix(&q),
                    bmatrix(&forcing.iter().map(|e| pool.print(*e, L)).collect::<Vec<_>>())
                ));
                self.out.push("\\end{equation}".into());
            }
            Section::Independent(form) => {
                let mut lines: Vec<String> = form
                    .dependent
                    .iter()
                    .map(|(r, e)| format!("  {} &= {}", sym_text(pool, *r, L), pool.print(*e, L)))
                    .collect();
                lines
                    .extend(form.equations.iter().map(|e| format!("  {} &= 0", pool.print(*e, L))));
                self.align("In the independent rates", lines);
            }
            Section::Reactions { reactions, .. } => {
                for (s, e) in *reactions {
                    self.items.push((sym_text(pool, *s, L), pool.print(*e, L)));
                }
            }
            Section::Shown(shown) => {
                for (show, v) in *shown {
                    self.items.push((d.show_label(show, L), value_latex(pool, v)));
                }
            }
            Section::AtStart { at_start, .. } => self.at_start(at_start),
        }
    }

    fn finish(mut self) -> String {
        if !self.items.is_empty() {
            let lines = self.items.iter().map(|(a, b)| format!("  {a} &= {b}")).collect();
            self.align("Reactions and shown quantities", lines);
        }
        lines_text(&self.out)
    }
}

impl Latex<'_> {
    /// An `align` under a `% heading` comment, each line but the last ended by `\\`.
    fn align(&mut self, heading: &str, lines: Vec<String>) {
        self.out.push(format!("% {heading}"));
        self.out.push("\\begin{align}".into());
        let n = lines.len();
        for (i, line) in lines.into_iter().enumerate() {
            self.out.push(if i + 1 < n { format!("{line} \\\\") } else { line });
        }
        self.out.push("\\end{align}".into());
    }

    /// The shown quantities at the start join the reactions' `align`.
    fn at_start(&mut self, at_start: &ShownAtStart) {
        let (d, pool) = (self.d, self.pool);
        let at_t0 = |show| format!("\\left.{}\\right|_{{t=0}}", d.show_label(show, L));
        match at_start {
            ShownAtStart::Exact(items) => {
                for (show, v) in items {
                    self.items.push((at_t0(show), value_latex(pool, v)));
                }
            }
            ShownAtStart::Numeric { items, digits, .. } => {
                for (show, v) in items {
                    let value = format!("\\approx {}", numeric_text(v, *digits, L));
                    self.items.push((at_t0(show), value));
                }
            }
            ShownAtStart::Unvalued { .. } | ShownAtStart::Singular => {}
        }
    }
}

/// The rows of a matrix in LaTeX, their entries separated by `&`.
fn latex_rows(pool: &Pool, rows: &[Vec<ExprId>]) -> Vec<String> {
    rows.iter()
        .map(|r| r.iter().map(|e| pool.print(*e, L)).collect::<Vec<_>>().join(" & "))
        .collect()
}

/// A bracketed matrix of `rows` (a column, when each is one entry).
fn bmatrix(rows: &[String]) -> String {
    format!("\\begin{{bmatrix}} {} \\end{{bmatrix}}", rows.join(" \\\\ "))
}

fn value_latex(pool: &Pool, v: &Value) -> String {
    match v {
        Value::Scalar(e) => pool.print(*e, L),
        Value::Vector(xs) => bmatrix(&xs.iter().map(|e| pool.print(*e, L)).collect::<Vec<_>>()),
        Value::Matrix(m) => bmatrix(&latex_rows(pool, m)),
    }
}

/// `v` to `digits` significant digits, plainly where that is short, in scientific notation
/// otherwise; a Unicode minus in the text style.
pub(crate) fn significant(v: f64, digits: u32, style: Style) -> String {
    let digits = digits.max(1) as i32;
    let text = if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else {
        let exponent = numeric::elementary::log10(v.abs()).floor() as i32;
        if (-4..15).contains(&exponent) {
            let decimals = (digits - 1 - exponent).max(0) as usize;
            let t = format!("{v:.decimals$}");
            if t.contains('.') {
                t.trim_end_matches('0').trim_end_matches('.').to_string()
            } else {
                t
            }
        } else {
            format!("{:.*e}", (digits - 1) as usize, v)
        }
    };
    if style == Style::Unicode {
        text.replace('-', "−")
    } else {
        text
    }
}

fn numeric_text(v: &NumericValue, digits: u32, style: Style) -> String {
    let one = |x: &f64| significant(*x, digits, style);
    match v {
        NumericValue::Scalar(x) => one(x),
        NumericValue::Vector(xs) => {
            format!("({})", xs.iter().map(one).collect::<Vec<_>>().join(", "))
        }
        NumericValue::Matrix(m) => format!(
            "[{}]",
            m.iter()
                .map(|r| r.iter().map(one).collect::<Vec<_>>().join(", "))
                .collect::<Vec<_>>()
                .join("; ")
        ),
    }
}

fn numeric_json(v: &NumericValue) -> Json {
    match v {
        NumericValue::Scalar(x) => json_number(*x),
        NumericValue::Vector(xs) => Json::Array(xs.iter().map(|x| json_number(*x)).collect()),
        NumericValue::Matrix(m) => Json::Array(
            m.iter().map(|r| Json::Array(r.iter().map(|x| json_number(*x)).collect())).collect(),
        ),
    }
}

pub(crate) fn json_number(v: f64) -> Json {
    serde_json::Number::from_f64(v).map(Json::Number).unwrap_or(Json::Null)
}

fn value_json(pool: &Pool, v: &Value) -> Json {
    match v {
        Value::Scalar(e) => json!(pool.print(*e, Style::Ascii)),
        Value::Vector(xs) => {
            Json::Array(xs.iter().map(|e| json!(pool.print(*e, Style::Ascii))).collect())
        }
        Value::Matrix(m) => Json::Array(
            m.iter()
                .map(|r| {
                    Json::Array(r.iter().map(|e| json!(pool.print(*e, Style::Ascii))).collect())
                })
                .collect(),
        ),
    }
}

/// The report as JSON; every expression is a string in the scene syntax.
pub fn json(d: &mut Derivation) -> String {
    render(d, |d| JsonReport { d, pool: &d.model.pool, fields: Map::new() })
}

/// The JSON report's keys, in the order it prints them.
const JSON_KEYS: [&str; 16] = [
    "scene",
    "coordinates",
    "parameters",
    "constraints",
    "kinetic_energy",
    "potential_energy",
    "equations",
    "mass_matrix",
    "forcing",
    "reactions",
    "reactions_with_accelerations",
    "shown",
    "at_start",
    "model",
    // Only scenes that keep a velocity constraint and ask for no contact force have this form.
    "independent_rates",
    // Numbers rather than exact expressions: how far to trust them.
    "at_start_significant_digits",
];

/// The JSON report: each section sets its keys, printed in the order of [`JSON_KEYS`].
struct JsonReport<'a> {
    d: &'a Derivation,
    pool: &'a Pool,
    fields: Map<String, Json>,
}

const A: Style = Style::Ascii;

impl Renderer for JsonReport<'_> {
    fn section(&mut self, section: &Section) {
        let (d, pool) = (self.d, self.pool);
        let name = |s: SymId| pool.symbol(s).name.clone();
        let prints = |es: &[ExprId]| es.iter().map(|e| pool.print(*e, A)).collect::<Vec<_>>();
        let names = |ss: &[(SymId, ExprId)]| -> Map<String, Json> {
            ss.iter().map(|(s, e)| (name(*s), json!(pool.print(*e, A)))).collect()
        };
        let mut set = |key: &str, value: Json| {
            self.fields.insert(key.into(), value);
        };
        match section {
            Section::Title(title) => set("scene", json!(title)),
            Section::Parameters(params) => set("parameters", json_parameters(pool, params)),
            Section::Coordinates { generalized, .. } => {
                set("coordinates", json!(generalized.iter().map(|s| name(*s)).collect::<Vec<_>>()))
            }
            Section::Constraints { constraints, .. } => {
                set("constraints", json_constraints(d, constraints))
            }
            Section::Energies { kinetic, potential, .. } => {
                set("kinetic_energy", json!(pool.print(*kinetic, A)));
                set("potential_energy", json!(pool.print(*potential, A)));
            }
            Section::Equations(equations) => set(
                "equations",
                equations
                    .iter()
                    .map(|e| json!({"lhs": pool.print(e.lhs, A), "rhs": pool.print(e.rhs, A)}))
                    .collect(),
            ),
            Section::MassMatrix { mass, forcing, .. } => {
                set("mass_matrix", json!(mass.iter().map(|r| prints(r)).collect::<Vec<_>>()));
                set("forcing", json!(prints(forcing)));
            }
            Section::Independent(form) => {
                let dependent: Map<String, Json> = form
                    .dependent
                    .iter()
                    .map(|(r, e)| (name(*r), Json::String(pool.print(*e, A))))
                    .collect();
                set(
                    "independent_rates",
                    json!({
                        "independent": form.independent.iter().map(|r| name(*r)).collect::<Vec<_>>(),
                        "dependent": dependent,
                        "equations": prints(&form.equations),
                    }),
                );
            }
            Section::Reactions { reactions, of_state } => {
                set("reactions", Json::Object(names(of_state)));
                set("reactions_with_accelerations", Json::Object(names(reactions)));
            }
            Section::Shown(shown) => {
                let shown: Map<String, Json> = shown
                    .iter()
                    .map(|(show, v)| (show.label.clone(), value_json(pool, v)))
                    .collect();
                set("shown", Json::Object(shown));
            }
            Section::AtStart { at_start, .. } => {
                let label = |show: &model::Show| show.label.clone();
                let values: Map<String, Json> = match at_start {
                    ShownAtStart::Exact(items) => {
                        items.iter().map(|(show, v)| (label(show), value_json(pool, v))).collect()
                    }
                    ShownAtStart::Numeric { items, digits, .. } => {
                        set("at_start_significant_digits", json!(digits));
                        items.iter().map(|(show, v)| (label(show), numeric_json(v))).collect()
                    }
                    ShownAtStart::Unvalued { .. } | ShownAtStart::Singular => Map::new(),
                };
                set("at_start", Json::Object(values));
            }
            Section::Model => set("model", model_json(d)),
        }
    }

    fn finish(mut self) -> String {
        let mut doc = Map::new();
        for key in JSON_KEYS {
            if let Some(value) = self.fields.remove(key) {
                doc.insert(key.into(), value);
            }
        }
        debug_assert!(self.fields.is_empty(), "a JSON key missing from JSON_KEYS");
        let mut text = serde_json::to_string_pretty(&Json::Object(doc)).unwrap_or_default();
        text.push('\n');
        text
    }
}

/// The parameters, each with its value as written and in numbers, and its unit.
fn json_parameters(pool: &Pool, params: &[model::Param]) -> Json {
    let mut out = Map::new();
    for p in params {
        let numeric = p.value.map(|v| numeric::eval(pool, v, &[])).filter(|x| x.is_finite());
        out.insert(
            p.name.clone(),
            json!({
                "value": p.value.map(|v| pool.print(v, A)),
                "numeric": numeric,
                "unit": p.unit.as_ref().map(|u| unit_text(u, A)),
            }),
        );
    }
    Json::Object(out)
}

/// Each constraint with how it was treated.
fn json_constraints(d: &Derivation, constraints: &[model::Constraint]) -> Json {
    let pool = &d.model.pool;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let constraints: Vec<Json> = constraints
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let equation = format!("{} = {}", pool.print(c.lhs, A), pool.print(c.rhs, A));
                if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                    json!({
                        "name": c.name,
                        "equation": equation,
                        "treatment": "eliminated",
                        "coordinate": name(e.coord),
                        "solution": pool.print(e.solution, A),
                    })
                } else {
                    let m = d.multipliers.iter().find(|m| m.constraint == i);
                    json!({
                        "name": c.name,
                        "equation": equation,
                        "treatment": "multiplier",
                        "multiplier": name(c.force_symbol),
                        "jacobian": m.map(|m| m.jacobian.iter().map(|e| pool.print(*e, A)).collect::<Vec<_>>()),
                        "bias": m.map(|m| pool.print(m.bias, A)),
                    })
                }
            })
            .collect();
    Json::Array(constraints)
}

/// The scene's primitive data (before any derivation), so that an independent tool can derive
/// the equations from the same system: every declared coordinate, the bodies, gravity, the
/// energy and dissipation terms, the loads, and each constraint with how it was treated.
fn model_json(d: &Derivation) -> Json {
    let m = &d.model;
    let pool = &m.pool;
    let a = Style::Ascii;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let print = |e: ExprId| pool.print(e, a);
    let prints = |es: &[ExprId]| es.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>();
    let bodies: Vec<Json> = m
        .bodies
        .iter()
        .map(|b| {
            let matrix = |m: &[[ExprId; 3]; 3]| -> Vec<Vec<String>> {
                m.iter().map(|r| prints(r)).collect()
            };
            match &b.rotation {
                // A planar body is "rigid" in the JSON that the SymPy cross-check reads.
                None | Some(model::Rotation::Planar { .. }) => json!({
                    "name": b.name,
                    "kind": if b.rotation.is_some() { "rigid" } else { "particle" },
                    "mass": print(b.mass),
                    "inertia": b.planar_inertia().map(print),
                    "position": prints(&b.position),
                    "angle": b.angle().map(print),
                }),
                Some(model::Rotation::Spatial { inertia, orientation, euler_parameters }) => {
                    let mut o = json!({
                        "name": b.name,
                        "kind": "spatial",
                        "mass": print(b.mass),
                        "inertia": matrix(inertia),
                        "position": prints(&b.position),
                        "orientation": matrix(orientation),
                    });
                    if let Some(e) = euler_parameters {
                        o["euler_parameters"] = json!(prints(e));
                    }
                    o
                }
            }
        })
        .collect();
    let gravity = m.gravity.as_ref().map(|g| {
        json!({
            "strength": print(g.strength),
            // As written; null means the default, straight down (−y in 2D, −z in 3D).
            "direction": g.direction.as_ref().map(|v| prints(v)),
        })
    });
    let terms = |ts: &[model::Term]| ts.iter().map(|t| print(t.expr)).collect::<Vec<_>>();
    let loads = |ls: &[model::Load], key: &str| -> Vec<Json> {
        ls.iter()
            .map(|l| {
                let mut o = Map::new();
                o.insert("name".into(), json!(l.name));
                o.insert("body".into(), json!(m.bodies[l.body].name));
                let v = match &l.value {
                    Value::Scalar(e) => json!(print(*e)),
                    other => json!(prints(&other.entries())),
                };
                o.insert(key.into(), v);
                if let Some(at) = &l.at {
                    o.insert("at".into(), json!(prints(at)));
                }
                Json::Object(o)
            })
            .collect()
    };
    let constraints: Vec<Json> = m
        .constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut o = Map::new();
            o.insert("name".into(), json!(c.name));
            o.insert("phi".into(), json!(print(c.phi)));
            if c.kind == model::ConstraintKind::Velocity {
                o.insert("kind".into(), json!("velocity"));
            }
            o.insert("reaction".into(), json!(name(c.force_symbol)));
            if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                o.insert("treatment".into(), json!("eliminated"));
                o.insert("coordinate".into(), json!(name(e.coord)));
                o.insert("solution".into(), json!(print(e.solution)));
            } else if let Some(k) = d.multipliers.iter().find(|k| k.constraint == i) {
                o.insert("treatment".into(), json!("multiplier"));
                o.insert("multiplier".into(), json!(name(k.lambda)));
            }
            Json::Object(o)
        })
        .collect();
    json!({
        "time": name(m.time),
        "coordinates": m.coords.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "bodies": bodies,
        "gravity": gravity,
        "potentials": terms(&m.potentials),
        "dissipation": terms(&m.dissipation),
        "lagrangian": terms(&m.lagrangians),
        "forces": loads(&m.forces, "vector"),
        "torques": loads(&m.torques, "torque"),
        "constraints": constraints,
    })
}
