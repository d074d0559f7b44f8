//! `check`'s result as data: each `expect` line with its verdict, and for one that fails the
//! diagnostic the command renders and what Python is handed (the residual exactly, a state
//! where it is not zero).

use cas::Style;
use engine::expect_linearized::LinearVerdict;
use engine::line_col;
use lang::Diagnostic;
use mechanics::Derivation;
use verify::Verdict;

use crate::{Data, Exact, MapBuilder};

/// One expectation checked.
pub struct Checked {
    /// The line it is written on, from 1.
    pub line: usize,
    /// The line as written.
    pub text: String,
    pub held: bool,
    /// How it held, or why not, in a few words.
    pub how: String,
    /// A failed equation's residual and where it is not zero.
    pub failure: Option<Failure>,
    /// What the command reports when it does not hold.
    pub diagnostic: Option<Diagnostic>,
}

/// lhs − rhs of an equation that does not hold.
pub struct Failure {
    pub residual: Exact,
    /// A state where the residual is not zero: each symbol's name and value.
    pub state: Vec<(String, f64)>,
    /// Which entry of a vector or matrix equation, if it has several.
    pub component: Option<usize>,
}

/// The scene's `expect` lines checked (its `expect linearized:` lines are [`linearized`]'s).
pub fn expectations(source: &str, d: &mut Derivation) -> Vec<Checked> {
    let verdicts = verify::check_all(d);
    let pool = &d.model.pool;
    let mut out = Vec::new();
    for (expect, verdict) in d.model.expects.iter().zip(&verdicts) {
        let (line, _) = line_col(source, expect.span.start);
        let (mut failure, mut diagnostic) = (None, None);
        match verdict {
            Verdict::Fails(f) => {
                let which = f.component.map(|k| format!(" (entry {})", k + 1)).unwrap_or_default();
                let state: Vec<String> = f
                    .state
                    .iter()
                    .map(|(s, v)| format!("{} = {v:.6}", pool.symbol_text(*s, Style::Unicode)))
                    .collect();
                let mut diag = Diagnostic::error(
                    expect.span,
                    format!("this expectation does not hold{which}"),
                )
                .with_label(format!("lhs − rhs = {}", pool.print(f.residual, Style::Unicode)));
                diag.hint = Some(if state.is_empty() {
                    format!("the residual is {:.6}, not 0", f.value)
                } else {
                    format!("at {}, lhs − rhs = {:.6}", state.join(", "), f.value)
                });
                diagnostic = Some(diag);
                failure = Some(Failure {
                    residual: Exact::of(pool, f.residual),
                    state: f
                        .state
                        .iter()
                        .map(|(s, v)| (pool.symbol(*s).name.clone(), *v))
                        .collect(),
                    component: f.component,
                });
            }
            Verdict::Undecided { reason } => {
                diagnostic = Some(
                    Diagnostic::error(expect.span, "this expectation could not be decided")
                        .with_label(reason.clone()),
                );
            }
            _ => {}
        }
        out.push(Checked {
            line,
            text: expect.text.clone(),
            held: verdict.holds(),
            how: verdict.how(),
            failure,
            diagnostic,
        });
    }
    out
}

/// The scene's `expect linearized:` lines with their verdicts.
pub fn linearized(source: &str, d: &Derivation, verdicts: &[LinearVerdict]) -> Vec<Checked> {
    let mut out = Vec::new();
    for (expect, verdict) in d.model.linear_expects.iter().zip(verdicts) {
        let (line, _) = line_col(source, expect.span.start);
        let how = match verdict {
            LinearVerdict::Holds(how)
            | LinearVerdict::Fails(how)
            | LinearVerdict::Undecided(how) => how.clone(),
        };
        let message = match verdict {
            LinearVerdict::Holds(_) => None,
            LinearVerdict::Undecided(_) => Some("this expectation could not be decided"),
            LinearVerdict::Fails(_) => Some("this expectation does not hold"),
        };
        out.push(Checked {
            line,
            text: expect.text.clone(),
            held: verdict.holds(),
            diagnostic: message.map(|m| Diagnostic::error(expect.span, m).with_label(how.clone())),
            how,
            failure: None,
        });
    }
    out
}

/// What the Python package's `check` returns: a dict per expectation.
pub fn python(checked: &[Checked]) -> Data {
    let item = |c: &Checked| {
        let mut out = MapBuilder::default();
        out.put("line", Data::count(c.line));
        out.put("text", Data::text(&c.text));
        out.put("held", Data::Bool(c.held));
        out.put("how", Data::text(&c.how));
        if let Some(f) = &c.failure {
            out.put("residual", Data::Exact(f.residual.clone()));
            let state = f.state.iter().map(|(name, v)| (name.clone(), Data::Float(*v)));
            out.put("state", Data::Map(state.collect()));
            out.put("component", Data::or_null(f.component.map(Data::count)));
        }
        out.done()
    };
    Data::List(checked.iter().map(item).collect())
}
