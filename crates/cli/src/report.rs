//! The `derive` report in three formats: text for people, LaTeX for papers, JSON for programs.

use cas::number::Signed;
use cas::{ExprId, Pool, Rational, Style, SymId};
use mechanics::Derivation;
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

/// The report for people; `full` prints every entry whole (see [`TEXT_ENTRY_LIMIT`]).
pub fn text_with(d: &mut Derivation, full: bool) -> String {
    let derived = engine::derived::collect(d);
    let pool = &d.model.pool;
    let u = Style::Unicode;
    let print = |e: ExprId| entry(pool, e, full);
    let mut out = Vec::new();
    if let Some(title) = &d.model.title {
        out.push(title.clone());
        out.push("═".repeat(width(title)));
        out.push(String::new());
    }
    if !d.model.params.is_empty() {
        out.push("Parameters".into());
        for p in &d.model.params {
            let mut line = format!("  {}", sym_text(pool, p.sym, u));
            if let Some(v) = p.value {
                line.push_str(&format!(" = {}", value_text(pool, v, u)));
            }
            if let Some(unit) = &p.unit {
                line.push_str(&format!(" {}", unit_text(unit, u)));
            }
            out.push(line);
        }
    }
    out.push("Coordinates".into());
    for c in &d.model.coords {
        let name = sym_text(pool, c.sym, u);
        if let Some(e) = d.eliminated.iter().find(|e| e.coord == c.sym) {
            let cname = &d.model.constraints[e.constraint].name;
            out.push(format!("  {name} = {}   (eliminated by {cname})", print(e.solution)));
        } else {
            let rate_symbol = pool.lookup_symbol(&format!("{}'", c.name));
            let rate = rate_symbol.map(|r| sym_text(pool, r, u)).unwrap_or_default();
            let solved = if d.solved_start_positions.contains(&c.sym) {
                ", solved from the constraints"
            } else {
                ""
            };
            out.push(format!(
                "  {name}   (from {name} {}, {rate} {}{solved})",
                start_value_text(d, c.sym, c.initial, u),
                start_value_text(d, rate_symbol.unwrap_or(c.sym), c.initial_rate, u)
            ));
        }
    }
    if !d.model.constraints.is_empty() {
        out.push("Constraints".into());
        for (i, c) in d.model.constraints.iter().enumerate() {
            let (lhs, rhs) = derived.constraint_sides[i];
            out.push(format!("  {}: {} = {}", c.name, print(lhs), print(rhs)));
            let force = sym_text(pool, c.force_symbol, u);
            if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                let what = if c.force_requested {
                    format!("; its reaction {force} is derived below")
                } else {
                    String::new()
                };
                if let Some(phi) = e.integrated {
                    out.push(format!("    integrates to {} = 0", print(phi)));
                }
                out.push(format!("    solved for {}{what}", sym_text(pool, e.coord, u)));
            } else if let Some(why) = &derived.left_out[i] {
                out.push(format!("    left out, as it restrains nothing more: {why}"));
            } else if c.kind == model::ConstraintKind::Velocity {
                out.push(format!(
                    "    a velocity constraint, kept with the multiplier {force} (generalized force {force}·∂Φ/∂q̇)"
                ));
            } else {
                out.push(format!(
                    "    kept with the multiplier {force} (generalized force {force}·∂Φ/∂q)"
                ));
            }
        }
    }
    out.push("Energies".into());
    out.push(format!("  T = {}", print(derived.kinetic)));
    out.push(format!("  V = {}", print(derived.potential)));
    if let Some(l) = derived.lagrangian {
        out.push(format!("  L = {}", print(l)));
    }
    out.push("Equations of motion".into());
    for eq in &derived.equations {
        out.push(format!("  {} = {}", print(eq.lhs), print(eq.rhs)));
    }
    let q: Vec<String> = d.coords.iter().map(|s| sym_text(pool, *s, u)).collect();
    let extra = if d.multipliers.is_empty() { "" } else { " + Jᵀ·λ" };
    out.push(format!("Mass-matrix form  M(q)·q̈ = f(q, q̇){extra},  q = ({})", q.join(", ")));
    out.extend(bracketed(&cells(pool, &derived.mass_matrix, full), "  M = "));
    let f_rows: Vec<Vec<ExprId>> = derived.forcing.iter().map(|e| vec![*e]).collect();
    out.extend(bracketed(&cells(pool, &f_rows, full), "  f = "));
    for m in &d.multipliers {
        let name = sym_text(pool, m.lambda, u);
        let row = cells(pool, std::slice::from_ref(&m.jacobian), full);
        out.extend(bracketed(&row, &format!("  J({name}) = ")));
        out.push(format!("  γ({name}) = {}", print(m.bias)));
    }
    if let Some(form) = &derived.independent {
        let names = |s: &[SymId]| s.iter().map(|r| sym_text(pool, *r, u)).collect::<Vec<_>>();
        let dependent: Vec<SymId> = form.dependent.iter().map(|(d, _)| *d).collect();
        out.push(format!(
            "In the independent rates  ({}; the constraints give {})",
            names(&form.independent).join(", "),
            names(&dependent).join(", ")
        ));
        for (d, e) in &form.dependent {
            out.push(format!("  {} = {}", sym_text(pool, *d, u), print(*e)));
        }
        for e in &form.equations {
            out.push(format!("  {} = 0", print(*e)));
        }
    }
    if !derived.reactions.is_empty() {
        out.push("Reactions".into());
        for ((s, e), (_, explicit)) in derived.reactions.iter().zip(&derived.reactions_of_state) {
            let mut line = format!("  {} = {}", sym_text(pool, *s, u), print(*e));
            if explicit != e {
                line.push_str(&format!("\n    = {}", print(*explicit)));
            }
            out.push(line);
        }
    }
    if !derived.shown.is_empty() {
        out.push("Shown".into());
        for (show, v) in &derived.shown {
            let label = d.show_label(show, u);
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
                out.push(format!(
                    "  {label}: a multiplier of the equations above; {unknowns} unknowns are too many to solve for it symbolically (`lagrange simulate --output {}` gives its values)",
                    show.label
                ));
                continue;
            }
            out.extend(value_lines(pool, full, &format!("  {label} = "), v));
        }
    }
    let start_heading = || {
        let state: Vec<String> = derived
            .start_state
            .iter()
            .map(|(s, e)| format!("{} {}", sym_text(pool, *s, u), start_value_text(d, *s, *e, u)))
            .collect();
        format!("At the start  ({})", state.join(", "))
    };
    match &derived.at_start {
        ShownAtStart::Exact(items) if !items.is_empty() => {
            out.push(start_heading());
            for (show, v) in items {
                let label = d.show_label(show, u);
                out.extend(value_lines(pool, full, &format!("  {label} = "), v));
            }
        }
        ShownAtStart::Exact(_) => {}
        ShownAtStart::Numeric { items, unknowns, digits, params, because } => {
            out.push(start_heading());
            let at: Vec<String> = params
                .iter()
                .map(|(s, v)| format!("{} = {}", sym_text(pool, *s, u), significant(*v, 15, u)))
                .collect();
            out.push(format!(
                "  solved numerically: {}; at {}, to about {digits} significant digits",
                because.words(*unknowns),
                at.join(", ")
            ));
            for (show, v) in items {
                let label = d.show_label(show, u);
                out.push(format!("  {label} ≈ {}", numeric_text(v, *digits, u)));
            }
        }
        ShownAtStart::Unvalued { unknowns, missing } => out.push(format!(
            "At the start: {unknowns} unknowns are too many to solve for exactly, and solving numerically needs a value for {}",
            missing.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")
        )),
        ShownAtStart::Singular => {
            out.push("At the start: the mass matrix is singular; nothing can be shown".into())
        }
    }
    let mut text = out.join("\n");
    text.push('\n');
    text
}

/// The report as a LaTeX fragment (amsmath).
pub fn latex(d: &mut Derivation) -> String {
    let derived = engine::derived::collect(d);
    let pool = &d.model.pool;
    let l = Style::Latex;
    let mut out = Vec::new();
    if let Some(title) = &d.model.title {
        out.push(format!("% {title}"));
    }
    out.push("% Energies".into());
    out.push("\\begin{align}".into());
    out.push(format!("  T &= {} \\\\", pool.print(derived.kinetic, l)));
    let last = derived.lagrangian.map(|e| format!("  L &= {}", pool.print(e, l)));
    match last {
        Some(lag) => {
            out.push(format!("  V &= {} \\\\", pool.print(derived.potential, l)));
            out.push(lag);
        }
        None => out.push(format!("  V &= {}", pool.print(derived.potential, l))),
    }
    out.push("\\end{align}".into());
    out.push("% Equations of motion".into());
    out.push("\\begin{align}".into());
    let n = derived.equations.len();
    for (i, eq) in derived.equations.iter().enumerate() {
        let end = if i + 1 < n { " \\\\" } else { "" };
        out.push(format!("  {} &= {}{end}", pool.print(eq.lhs, l), pool.print(eq.rhs, l)));
    }
    out.push("\\end{align}".into());
    out.push("% Mass-matrix form".into());
    let matrix = |rows: &[Vec<ExprId>]| {
        let body: Vec<String> = rows
            .iter()
            .map(|r| r.iter().map(|e| pool.print(*e, l)).collect::<Vec<_>>().join(" & "))
            .collect();
        format!("\\begin{{bmatrix}} {} \\end{{bmatrix}}", body.join(" \\\\ "))
    };
    let q: Vec<String> = d.accels.iter().map(|s| sym_text(pool, *s, l)).collect();
    let f_rows: Vec<Vec<ExprId>> = derived.forcing.iter().map(|e| vec![*e]).collect();
    out.push("\\begin{equation}".into());
    out.push(format!(
        "  {} \\begin{{bmatrix}} {} \\end{{bmatrix}} = {}",
        matrix(&derived.mass_matrix),
        q.join(" \\\\ "),
        matrix(&f_rows)
    ));
    out.push("\\end{equation}".into());
    if let Some(form) = &derived.independent {
        out.push("% In the independent rates".into());
        out.push("\\begin{align}".into());
        let mut lines: Vec<String> = form
            .dependent
            .iter()
            .map(|(r, e)| format!("  {} &= {}", sym_text(pool, *r, l), pool.print(*e, l)))
            .collect();
        lines.extend(form.equations.iter().map(|e| format!("  {} &= 0", pool.print(*e, l))));
        let n = lines.len();
        for (i, line) in lines.into_iter().enumerate() {
            out.push(if i + 1 < n { format!("{line} \\\\") } else { line });
        }
        out.push("\\end{align}".into());
    }
    let mut items: Vec<(String, String)> = Vec::new();
    for (s, e) in &derived.reactions {
        items.push((sym_text(pool, *s, l), pool.print(*e, l)));
    }
    for (show, v) in &derived.shown {
        items.push((d.show_label(show, l), value_latex(pool, v)));
    }
    match &derived.at_start {
        ShownAtStart::Exact(at_start) => {
            for (show, v) in at_start {
                items.push((
                    format!("\\left.{}\\right|_{{t=0}}", d.show_label(show, l)),
                    value_latex(pool, v),
                ));
            }
        }
        ShownAtStart::Numeric { items: at_start, digits, .. } => {
            for (show, v) in at_start {
                items.push((
                    format!("\\left.{}\\right|_{{t=0}}", d.show_label(show, l)),
                    format!("\\approx {}", numeric_text(v, *digits, l)),
                ));
            }
        }
        ShownAtStart::Unvalued { .. } | ShownAtStart::Singular => {}
    }
    if !items.is_empty() {
        out.push("% Reactions and shown quantities".into());
        out.push("\\begin{align}".into());
        let n = items.len();
        for (i, (a, b)) in items.iter().enumerate() {
            let end = if i + 1 < n { " \\\\" } else { "" };
            out.push(format!("  {a} &= {b}{end}"));
        }
        out.push("\\end{align}".into());
    }
    let mut text = out.join("\n");
    text.push('\n');
    text
}

fn value_latex(pool: &Pool, v: &Value) -> String {
    match v {
        Value::Scalar(e) => pool.print(*e, Style::Latex),
        Value::Vector(xs) => {
            let parts: Vec<String> = xs.iter().map(|e| pool.print(*e, Style::Latex)).collect();
            format!("\\begin{{bmatrix}} {} \\end{{bmatrix}}", parts.join(" \\\\ "))
        }
        Value::Matrix(m) => {
            let rows: Vec<String> = m
                .iter()
                .map(|r| {
                    r.iter().map(|e| pool.print(*e, Style::Latex)).collect::<Vec<_>>().join(" & ")
                })
                .collect();
            format!("\\begin{{bmatrix}} {} \\end{{bmatrix}}", rows.join(" \\\\ "))
        }
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
    let derived = engine::derived::collect(d);
    let pool = &d.model.pool;
    let a = Style::Ascii;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let mut params = Map::new();
    for p in &d.model.params {
        let numeric = p.value.map(|v| numeric::eval(pool, v, &[])).filter(|x| x.is_finite());
        params.insert(
            p.name.clone(),
            json!({
                "value": p.value.map(|v| pool.print(v, a)),
                "numeric": numeric,
                "unit": p.unit.as_ref().map(|u| unit_text(u, a)),
            }),
        );
    }
    let constraints: Vec<Json> = d
        .model
        .constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let equation = format!("{} = {}", pool.print(c.lhs, a), pool.print(c.rhs, a));
            if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                json!({
                    "name": c.name,
                    "equation": equation,
                    "treatment": "eliminated",
                    "coordinate": name(e.coord),
                    "solution": pool.print(e.solution, a),
                })
            } else {
                let m = d.multipliers.iter().find(|m| m.constraint == i);
                json!({
                    "name": c.name,
                    "equation": equation,
                    "treatment": "multiplier",
                    "multiplier": name(c.force_symbol),
                    "jacobian": m.map(|m| m.jacobian.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>()),
                    "bias": m.map(|m| pool.print(m.bias, a)),
                })
            }
        })
        .collect();
    let mut reactions = Map::new();
    for (s, e) in &derived.reactions_of_state {
        reactions.insert(name(*s), json!(pool.print(*e, a)));
    }
    let mut reactions_with_accelerations = Map::new();
    for (s, e) in &derived.reactions {
        reactions_with_accelerations.insert(name(*s), json!(pool.print(*e, a)));
    }
    let mut shown = Map::new();
    for (show, v) in &derived.shown {
        shown.insert(show.label.clone(), value_json(pool, v));
    }
    let mut at_start = Map::new();
    let mut at_start_digits = None;
    match &derived.at_start {
        ShownAtStart::Exact(items) => {
            for (show, v) in items {
                at_start.insert(show.label.clone(), value_json(pool, v));
            }
        }
        ShownAtStart::Numeric { items, digits, .. } => {
            for (show, v) in items {
                at_start.insert(show.label.clone(), numeric_json(v));
            }
            at_start_digits = Some(*digits);
        }
        ShownAtStart::Unvalued { .. } | ShownAtStart::Singular => {}
    }
    let doc = json!({
        "scene": d.model.title,
        "coordinates": d.coords.iter().map(|s| name(*s)).collect::<Vec<_>>(),
        "parameters": params,
        "constraints": constraints,
        "kinetic_energy": pool.print(derived.kinetic, a),
        "potential_energy": pool.print(derived.potential, a),
        "equations": derived.equations.iter().map(|e| json!({"lhs": pool.print(e.lhs, a), "rhs": pool.print(e.rhs, a)})).collect::<Vec<_>>(),
        "mass_matrix": derived.mass_matrix.iter().map(|r| r.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "forcing": derived.forcing.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>(),
        "reactions": reactions,
        "reactions_with_accelerations": reactions_with_accelerations,
        "shown": shown,
        "at_start": at_start,
        "model": model_json(d),
    });
    let mut doc = doc;
    // Only scenes that keep a velocity constraint and ask for no contact force have this form.
    if let (Some(form), Json::Object(map)) = (&derived.independent, &mut doc) {
        let dependent: Map<String, Json> = form
            .dependent
            .iter()
            .map(|(r, e)| (name(*r), Json::String(pool.print(*e, a))))
            .collect();
        map.insert(
            "independent_rates".into(),
            json!({
                "independent": form.independent.iter().map(|r| name(*r)).collect::<Vec<_>>(),
                "dependent": dependent,
                "equations": form.equations.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>(),
            }),
        );
    }
    // Numbers rather than exact expressions: say how far to trust them.
    if let (Some(digits), Json::Object(map)) = (at_start_digits, &mut doc) {
        map.insert("at_start_significant_digits".into(), json!(digits));
    }
    let mut text = serde_json::to_string_pretty(&doc).unwrap_or_default();
    text.push('\n');
    text
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
