//! The `linearize` report: M, C, K exactly and at the parameters' values, the first-order
//! matrix, the eigenvalues and the verdict, a sweep's table and its changes of stability, as
//! text, or as JSON rendered from `results::linearize`. The sweep's figure is
//! [`crate::plot::sweep`].

use cas::{ExprId, Pool, Style, SymId};
use engine::linearize::{CaseNumbers, Linearized, Numbers, Sweep};

use crate::report::{bracketed, data_json, significant, value_text, width};

/// Digits of the numbers in the text report.
const DIGITS: u32 = 10;

fn number(v: f64) -> String {
    if v == 0.0 {
        // −0 and 0 read the same to a person.
        return "0".into();
    }
    significant(v, DIGITS, Style::Unicode)
}

/// `re ± im·i`, with the digits a table has room for.
fn complex(re: f64, im: f64, digits: u32) -> String {
    let re_text = if re == 0.0 { "0".to_string() } else { significant(re, digits, Style::Unicode) };
    if im == 0.0 {
        return re_text;
    }
    let sign = if im < 0.0 { "−" } else { "+" };
    let im_text = significant(im.abs(), digits, Style::Unicode);
    if re == 0.0 {
        // Purely imaginary: ±ωi, as a hand derivation writes an oscillation.
        return format!("{}{im_text}i", if im < 0.0 { "−" } else { "" });
    }
    format!("{re_text} {sign} {im_text}i")
}

fn exact_rows(pool: &Pool, m: &[Vec<ExprId>]) -> Vec<Vec<String>> {
    m.iter().map(|r| r.iter().map(|e| pool.print(*e, Style::Unicode)).collect()).collect()
}

fn number_rows(m: &[Vec<f64>]) -> Vec<Vec<String>> {
    m.iter().map(|r| r.iter().map(|v| number(*v)).collect()).collect()
}

/// `θ = 0, ẋ = 0, θ̇ = 0`: the reference as the scene's terms.
fn reference_text(pool: &Pool, reference: &[(SymId, bool, ExprId)], style: Style) -> Vec<String> {
    reference
        .iter()
        .map(|(q, rate, value)| {
            let name = if *rate {
                let r = pool.symbol(*q).name.clone() + "'";
                pool.lookup_symbol(&r).map(|s| pool.symbol_text(s, style)).unwrap_or(r)
            } else {
                pool.symbol_text(*q, style)
            };
            format!("{name} = {}", value_text(pool, *value, style))
        })
        .collect()
}

fn verdict_text(numbers: &Numbers) -> String {
    // Each real part is judged against its own bound on rounding; the largest is given.
    let bound = format!(
        "its own bound on rounding (the largest {})",
        significant(numbers.tolerance, 2, Style::Unicode)
    );
    let verdict = match numbers.stability {
        engine::linearize::Stability::Stable => {
            format!("Stable: every real part is below minus {bound}")
        }
        engine::linearize::Stability::MarginallyStable => format!(
            "Marginally stable: no real part is above {bound}, and some are within it of zero"
        ),
        engine::linearize::Stability::Unstable => {
            format!("Unstable: some real part is above {bound}")
        }
    };
    let verdict = match numbers.first_integrals {
        0 => verdict,
        1 => format!(
            "{verdict}, apart from one zero: a first integral's, which leads to neighbouring \
             steady motions"
        ),
        k => format!(
            "{verdict}, apart from {k} zeros: first integrals', which lead to neighbouring \
             steady motions"
        ),
    };
    match numbers.cyclic_zeros {
        0 => verdict,
        1 => format!(
            "{verdict}; apart from one zero: a cyclic coordinate's position, which drifts with \
             its rate"
        ),
        k => format!(
            "{verdict}; apart from {k} zeros: cyclic coordinates' positions, which drift with \
             their rates"
        ),
    }
}

/// The report for people: the reference, the exact equations, the numbers, the first-order
/// form and its eigenvalues, and the sweep.
pub fn text(l: &Linearized) -> String {
    let mut out = reference_lines(l);
    out.extend(exact_lines(l));
    out.extend(exact_first_order_lines(l));
    out.extend(number_lines(l));
    out.extend(first_order_lines(l));
    if let Some(sweep) = &l.sweep {
        out.push(String::new());
        out.extend(sweep_lines(&l.derivation.model.pool, sweep));
    }
    let mut text = out.join("\n");
    text.push('\n');
    text
}

/// The title, the reference, whether it holds exactly, and the coordinates that leave the state.
fn reference_lines(l: &Linearized) -> Vec<String> {
    let d = &l.derivation;
    let pool = &d.model.pool;
    let lin = &l.linearization;
    let u = Style::Unicode;
    let mut out = Vec::new();
    let mut reference = lin.reference();
    // A dependent rate of kept constraints stays its own symbol: numbers solve it, below.
    reference.retain(|(q, rate, value)| {
        !*rate
            || lin
                .coords
                .iter()
                .position(|c| c == q)
                .is_none_or(|i| pool.as_sym(*value) != Some(d.rates[i]))
    });
    let about = reference_text(pool, &reference, u).join(", ");
    let title = match &d.model.title {
        Some(title) => format!("{title}: small motions"),
        None => "Small motions".to_string(),
    };
    out.push(title.clone());
    out.push("═".repeat(width(&title)));
    out.push(String::new());
    out.push(format!("About  {about}"));
    if l.exact_reference {
        out.push(
            "  the accelerations vanish there exactly, for every value of the parameters".into(),
        );
    } else {
        let largest = l.at.accelerations.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        out.push(format!(
            "  the accelerations vanish there at the parameters' values (the largest is {})",
            number(largest)
        ));
    }
    for (q, _) in lin.coords.iter().zip(&lin.cyclic).filter(|(_, c)| **c) {
        let name = pool.symbol_text(*q, u);
        let rate = pool
            .lookup_symbol(&format!("{}'", pool.symbol(*q).name))
            .map(|s| pool.symbol_text(s, u))
            .unwrap_or_default();
        out.push(if lin.in_rates().is_some() || lin.kept().is_some() {
            format!(
                "  {name} is ignorable (in neither the equations in u nor the rates of p): \
                 δ{name} leaves the state"
            )
        } else if lin.keep_cyclic {
            format!(
                "  {name} is cyclic (in neither M nor f): δ{name} stays in the state with a zero \
                 eigenvalue, set aside from the verdict (--drop-cyclic leaves it out)"
            )
        } else {
            format!(
                "  {name} is cyclic (in neither M nor f): δ{name} leaves the state, δ{rate} stays"
            )
        });
    }
    out
}

/// The linearized equations exactly, in the case's form, with each kept constraint's row.
fn exact_lines(l: &Linearized) -> Vec<String> {
    let pool = &l.derivation.model.pool;
    let lin = &l.linearization;
    let u = Style::Unicode;
    let names = |symbols: &mut dyn Iterator<Item = SymId>| -> String {
        symbols.map(|s| pool.symbol_text(s, u)).collect::<Vec<_>>().join(", ")
    };
    let mut out = Vec::new();
    if let Some(r) = lin.in_rates() {
        let rates = names(&mut r.rates.iter().copied());
        let kept = names(&mut r.kept.iter().map(|&i| lin.coords[i]));
        let dependent = names(&mut r.dependent.iter().map(|(d, _)| *d));
        out.push(format!(
            "Linearized equations in the independent rates  M·δu̇ + C·δu + K·δp = 0,  \
             u = ({rates}),  p = ({kept})"
        ));
        out.push(format!(
            "  (the velocity constraints give {dependent}; their multipliers cancel in this form)"
        ));
    } else {
        let q = names(&mut lin.coords.iter().copied());
        let rhs = if lin.constraints().is_empty() { "0" } else { "Jᵀ·δλ,  J·δq = 0" };
        out.push(format!("Linearized equations  M·δq̈ + C·δq̇ + K·δq = {rhs},  q = ({q})"));
    }
    out.extend(bracketed(&exact_rows(pool, &l.mass), "  M = "));
    out.extend(bracketed(&exact_rows(pool, &l.damping), "  C = "));
    out.extend(bracketed(&exact_rows(pool, &l.stiffness), "  K = "));
    if let Some(r) = lin.in_rates().filter(|r| !r.kept.is_empty()) {
        out.push("Kinematics  δṗ = G·(δp, δu)".into());
        out.extend(bracketed(&exact_rows(pool, &r.kinematics), "  G = "));
    }
    for c in lin.constraints() {
        let name = pool.symbol_text(c.lambda, u);
        let row: Vec<String> = c.jacobian.iter().map(|e| pool.print(*e, u)).collect();
        out.extend(bracketed(&[row], &format!("  J({name}) = ")));
    }
    out
}

/// The matrices at the parameters' values (reduced in numbers where the case is), and the
/// multipliers.
fn number_lines(l: &Linearized) -> Vec<String> {
    let d = &l.derivation;
    let pool = &d.model.pool;
    let lin = &l.linearization;
    let u = Style::Unicode;
    let mut out = Vec::new();
    let at: Vec<String> = d
        .model
        .params
        .iter()
        .zip(&l.at.parameters)
        .map(|(p, v)| format!("{} = {}", pool.symbol_text(p.sym, u), number(*v)))
        .collect();
    out.push(if at.is_empty() {
        "In numbers".to_string()
    } else {
        format!("At {}", at.join(", "))
    });
    if let (Some(kept), CaseNumbers::Kept(r)) = (lin.kept(), &l.at.case) {
        let names = |is: &mut dyn Iterator<Item = SymId>| -> String {
            is.map(|s| pool.symbol_text(s, u)).collect::<Vec<_>>().join(", ")
        };
        let values: Vec<String> = kept
            .dependent
            .iter()
            .zip(&r.dependent_rates)
            .map(|(&i, v)| format!("{} = {}", pool.symbol_text(d.rates[i], u), number(*v)))
            .collect();
        out.push(format!("  the kept constraints give {}", values.join(", ")));
        out.push(format!(
            "  reduced in numbers: M·δu̇ + C·δu + K·δp = 0,  δṗ = G·(δp, δu),  u = ({}),  p = ({})",
            names(&mut r.rates.iter().map(|&i| d.rates[i])),
            names(&mut r.positions.iter().map(|&i| lin.coords[i]))
        ));
    }
    out.extend(bracketed(&number_rows(&l.at.mass), "  M = "));
    out.extend(bracketed(&number_rows(&l.at.damping), "  C = "));
    out.extend(bracketed(&number_rows(&l.at.stiffness), "  K = "));
    let kinematics = match &l.at.case {
        CaseNumbers::InRates { kinematics } => Some(kinematics),
        CaseNumbers::Kept(r) => Some(&r.kinematics),
        CaseNumbers::Holonomic { .. } => None,
    };
    if let Some(g) = kinematics.filter(|g| !g.is_empty()) {
        out.extend(bracketed(&number_rows(g), "  G = "));
    }
    for (c, v) in lin.constraints().iter().zip(&l.at.multipliers) {
        out.push(format!("  {} = {}", pool.symbol_text(c.lambda, u), number(*v)));
    }
    out
}

/// ẋ = A·x, its eigenvalues and the verdict.
fn first_order_lines(l: &Linearized) -> Vec<String> {
    let pool = &l.derivation.model.pool;
    let mut out = Vec::new();
    let state: Vec<String> = l.state.iter().map(|s| format!("δ{}", state_text(pool, s))).collect();
    // Not x: a scene's coordinate is as likely as not to be called that.
    out.push(format!("First-order form  {},  u = ({})", form_text(l), state.join(", ")));
    if let CaseNumbers::Holonomic { basis: Some(basis) } = &l.at.case {
        out.extend(bracketed(&number_rows(basis), "  δq = N·z,  N = "));
    }
    let space = &l.at.first_order;
    out.extend(bracketed(&number_rows(&space.a), "  A = "));
    if !l.inputs.is_empty() {
        out.extend(bracketed(&number_rows(&space.b), "  B = "));
    }
    if !l.outputs.is_empty() {
        out.push(format!("Outputs  y = C·u + D·w,  y = ({})", l.outputs.join(", ")));
        out.extend(bracketed(&number_rows(&space.c), "  C = "));
        if !l.inputs.is_empty() {
            out.extend(bracketed(&number_rows(&space.d), "  D = "));
        }
    }
    out.extend(rank_line("Controllable", "[B, AB, …]", space.controllability));
    out.extend(rank_line("Observable", "[C; CA; …]", space.observability));
    out.push("Eigenvalues of A".into());
    // A part within the eigenvalue's bound of zero is rounding: it prints as 0.
    for (&(re, im), &bound) in l.at.eigenvalues.iter().zip(&l.at.bounds) {
        let clean = |x: f64| if x.abs() <= bound { 0.0 } else { x };
        out.push(format!("  {}", complex(clean(re), clean(im), DIGITS)));
    }
    out.push(verdict_text(&l.at));
    out
}

/// The rank of the controllability or observability matrix in words, with the tolerance and
/// how far the singular values are from it.
fn rank_line(what: &str, matrix: &str, rank: Option<engine::linearize::Rank>) -> Option<String> {
    let r = rank?;
    let verdict =
        if r.rank == r.full { what.to_string() } else { format!("Not {}", what.to_lowercase()) };
    let s = |v: f64| significant(v, 2, Style::Unicode);
    let mut line = format!(
        "{verdict}: {matrix} has rank {} of {} (columns scaled to length 1; singular values \
         below {} × the largest count as zero; the smallest counted is {} of the largest",
        r.rank,
        r.full,
        s(r.tolerance),
        s(r.smallest_counted)
    );
    if r.rank < r.full {
        line.push_str(&format!(", the largest left out {}", s(r.largest_left_out)));
    }
    line.push(')');
    if r.doubtful() {
        line.push_str(" — doubtful: a singular value lies within a factor 1000 of the tolerance");
    }
    Some(line)
}

/// `u̇ = A·u`, or `u̇ = A·u + B·w, w = (F)` with inputs.
fn form_text(l: &Linearized) -> String {
    match l.inputs.is_empty() {
        true => "u̇ = A·u".into(),
        false => format!("u̇ = A·u + B·w,  w = ({})", l.inputs.join(", ")),
    }
}

/// The first-order form exactly, where the algebra gives it.
fn exact_first_order_lines(l: &Linearized) -> Vec<String> {
    let Some(exact) = &l.exact else { return Vec::new() };
    let pool = &l.derivation.model.pool;
    let coords = &l.linearization.coords;
    let state: Vec<String> = exact
        .state
        .iter()
        .map(|c| format!("δ{}", state_text(pool, &c.name(pool, coords))))
        .collect();
    let form = form_text(l);
    let mut out = vec![format!("First-order form exactly  {form},  u = ({})", state.join(", "))];
    out.extend(bracketed(&exact_rows(pool, &exact.a), "  A = "));
    if !l.inputs.is_empty() {
        out.extend(bracketed(&exact_rows(pool, &exact.b), "  B = "));
    }
    out
}

/// A state name (`theta'`, `z1'`) as the report prints names (θ̇, ż1).
fn state_text(pool: &Pool, name: &str) -> String {
    if let Some(s) = pool.lookup_symbol(name) {
        return pool.symbol_text(s, Style::Unicode);
    }
    // A coordinate along the constraints' null space has no symbol: its rate gets its dot here.
    match name.strip_suffix('\'') {
        Some(base) => {
            let mut chars = base.chars();
            let first = chars.next().map(String::from).unwrap_or_default();
            format!("{first}\u{307}{}", chars.as_str())
        }
        None => name.to_string(),
    }
}

fn sweep_lines(pool: &Pool, sweep: &Sweep) -> Vec<String> {
    let mut out = Vec::new();
    let name = pool
        .lookup_symbol(&sweep.parameter)
        .map_or(sweep.parameter.clone(), |s| pool.symbol_text(s, Style::Unicode));
    let (first, last) = match (sweep.rows.first(), sweep.rows.last()) {
        (Some(a), Some(b)) => (a.value, b.value),
        _ => return out,
    };
    out.push(format!(
        "Sweep of {name} from {} to {} ({} values): eigenvalues",
        number(first),
        number(last),
        sweep.rows.len()
    ));
    let rows: Vec<Vec<String>> = sweep
        .rows
        .iter()
        .map(|r| {
            let mut cells = vec![number(r.value), r.stability.name().to_string()];
            // Parts within their eigenvalue's bound of zero print as 0.
            cells.extend(r.eigenvalues.iter().zip(&r.bounds).map(|(&(re, im), &bound)| {
                let clean = |x: f64| if x.abs() <= bound { 0.0 } else { x };
                complex(clean(re), clean(im), 6)
            }));
            cells
        })
        .collect();
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let mut header = vec![name.clone(), "verdict".into()];
    header.extend((1..columns.saturating_sub(1)).map(|k| format!("λ{k}")));
    let widths: Vec<usize> = (0..columns)
        .map(|j| {
            let cells = std::iter::once(&header).chain(&rows).filter_map(|r| r.get(j));
            cells.map(|c| width(c)).max().unwrap_or(0)
        })
        .collect();
    for row in std::iter::once(&header).chain(&rows) {
        let cells: Vec<String> = row
            .iter()
            .zip(&widths)
            .map(|(c, w)| format!("{c}{}", " ".repeat(w.saturating_sub(width(c)))))
            .collect();
        out.push(format!("  {}", cells.join("   ").trim_end()));
    }
    if sweep.changes.is_empty() {
        out.push(format!(
            "Stability does not change between {name} = {} and {}",
            number(first),
            number(last)
        ));
    } else {
        out.push("Stability changes".into());
        for c in &sweep.changes {
            out.push(format!(
                "  {name} = {}: {} → {}  (bracketed by bisection: [{}, {}])",
                significant(c.value, 12, Style::Unicode),
                c.from.name(),
                c.to.name(),
                significant(c.bracket.0.min(c.bracket.1), 14, Style::Unicode),
                significant(c.bracket.0.max(c.bracket.1), 14, Style::Unicode),
            ));
        }
    }
    out
}

/// The report as JSON: one `linearization` object; expressions are strings in the scene
/// syntax, numbers are numbers. Its shape is `results::linearize::report`'s.
pub fn json(l: &Linearized) -> String {
    let mut text = serde_json::to_string_pretty(&data_json(&results::linearize::report(l)))
        .unwrap_or_default();
    text.push('\n');
    text
}
