//! The `derive` report in three formats: text for people, LaTeX for papers, JSON for programs.

use cas::number::Signed;
use cas::{ExprId, Pool, Rational, Style, SymId};
use engine::derived::{Derivation, Derived, Equation, NumericValue, ShownAtStart};
use model::Value;
use results::Data;
use serde_json::{json, Map, Value as Json};

mod json;
mod latex;
mod text;

pub use json::json;
pub use latex::latex;
pub use text::text_with;

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
    let values = if numeric { engine::derived::parameter_values(d).ok() } else { None };
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
    /// The inputs with their values when nothing drives them, and the outputs.
    Signals {
        inputs: &'a [model::Input],
        outputs: &'a [model::Output],
    },
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
    /// Each contact: its gap and law, its two modes, its impact law.
    Contacts(&'a [engine::derived::DerivedContact]),
    Energies {
        kinetic: ExprId,
        potential: ExprId,
        lagrangian: Option<ExprId>,
    },
    Equations(&'a [Equation]),
    MassMatrix {
        mass: &'a [Vec<ExprId>],
        forcing: &'a [ExprId],
        multipliers: &'a [engine::derived::Multiplier],
    },
    Independent(&'a engine::derived::IndependentForm),
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
        Section::Signals { inputs: &d.model.inputs, outputs: &d.model.outputs },
        Section::Coordinates { declared: &d.model.coords, generalized: &d.coords },
        Section::Constraints {
            constraints: &d.model.constraints,
            sides: &derived.constraint_sides,
            left_out: &derived.left_out,
        },
        Section::Contacts(&derived.contacts),
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

/// A result's data as JSON: a complex number as `[re, im]`, a matrix as its rows, an exact
/// expression as its scene-syntax text; a number that is not finite as null.
pub(crate) fn data_json(data: &Data) -> Json {
    let rows = |rows: &[Vec<f64>]| {
        let row = |r: &Vec<f64>| Json::Array(r.iter().map(|v| json_number(*v)).collect());
        Json::Array(rows.iter().map(row).collect())
    };
    match data {
        Data::Null => Json::Null,
        Data::Bool(b) => json!(b),
        Data::Int(n) => json!(n),
        Data::Float(v) => json_number(*v),
        Data::Text(s) => json!(s),
        Data::List(items) | Data::Array(items) => {
            Json::Array(items.iter().map(data_json).collect())
        }
        Data::Map(entries) => {
            Json::Object(entries.iter().map(|(k, v)| (k.clone(), data_json(v))).collect())
        }
        Data::Complex(re, im) => json!([json_number(*re), json_number(*im)]),
        Data::Matrix { rows: values, .. } => rows(values),
        Data::Exact(e) => json!(e.text),
        Data::ExactMatrix(m) => Json::Array(
            m.iter().map(|r| Json::Array(r.iter().map(|e| json!(e.text)).collect())).collect(),
        ),
    }
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
