//! The LaTeX report (amsmath): equations in `align`, matrices in `bmatrix`.

use super::*;

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
            | Section::Signals { .. }
            | Section::Coordinates { .. }
            | Section::Constraints { .. }
            | Section::Model => {}
            Section::Contacts(contacts) => {
                let rates: Vec<String> = d.rates.iter().map(|s| sym_text(pool, *s, L)).collect();
                for c in *contacts {
                    let Some(law) = &c.impact else { continue };
                    let mut lines = vec![format!("  \\Lambda &= {}", pool.print(law.impulse, L))];
                    for (r, after) in rates.iter().zip(&law.rates_after) {
                        lines.push(format!("  {r}^+ &= {}", pool.print(*after, L)));
                    }
                    self.align(&format!("Impact at {}", c.name), lines);
                }
            }
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
