//! What an ensemble records per run: a scene expression at the end (or at the stop, where `t`
//! is the stop's time), or its least or greatest value over the run, `min(EXPR)` and
//! `max(EXPR)` (a one-argument call; with two arguments `min` and `max` are the scene's own).

use sim::Run;

use simulation::split_list;

/// Which value of an expression a column records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extreme {
    /// At the end of the run, or where a stop ended it.
    Final,
    /// The least value at the start, the integrator's accepted steps and the end.
    Least,
    /// The greatest value, likewise.
    Greatest,
}

/// A recorded column: its name as written, which value, and its expression's observation.
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    pub name: String,
    pub extreme: Extreme,
    /// The expression, as resolved in the scene's scope.
    pub expression: String,
    /// Its observation column.
    column: usize,
}

impl Recorded {
    /// The value this column records of a finished run.
    pub(super) fn value(&self, run: &Run) -> f64 {
        match self.extreme {
            Extreme::Final => run.trajectory.rows.last().map_or(f64::NAN, |row| row[self.column]),
            Extreme::Least => run.extremes.get(self.column).map_or(f64::NAN, |e| e.0),
            Extreme::Greatest => run.extremes.get(self.column).map_or(f64::NAN, |e| e.1),
        }
    }
}

/// The recorded columns of the lists given, each expression observed once however often it
/// is recorded.
pub(crate) fn parse(lists: &[String]) -> Vec<Recorded> {
    let mut expressions: Vec<String> = Vec::new();
    let mut recorded = Vec::new();
    for item in lists.iter().flat_map(|list| split_list(list)) {
        let (extreme, expression) = extreme_of(&item);
        let column = match expressions.iter().position(|e| *e == expression) {
            Some(c) => c,
            None => {
                expressions.push(expression.clone());
                expressions.len() - 1
            }
        };
        recorded.push(Recorded { name: item, extreme, expression, column });
    }
    recorded
}

/// The distinct expressions observed, in the order of their columns.
pub(super) fn expressions(recorded: &[Recorded]) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for r in recorded {
        if r.column == seen.len() {
            seen.push(r.expression.clone());
        }
    }
    seen
}

/// Each output at the end: what an ensemble records when asked for nothing.
pub(super) fn finals(outputs: &[String]) -> Vec<Recorded> {
    let final_of = |(column, name): (usize, &String)| Recorded {
        name: name.clone(),
        extreme: Extreme::Final,
        expression: name.clone(),
        column,
    };
    outputs.iter().enumerate().map(final_of).collect()
}

/// `max(EXPR)` and `min(EXPR)` as the extreme of EXPR; anything else as its final value.
fn extreme_of(item: &str) -> (Extreme, String) {
    for (name, extreme) in [("max", Extreme::Greatest), ("min", Extreme::Least)] {
        let Some(inner) = item.strip_prefix(name).map(str::trim_start) else { continue };
        let Some(inner) = inner.strip_prefix('(').and_then(|i| i.strip_suffix(')')) else {
            continue;
        };
        if encloses(inner) && split_list(inner).len() == 1 {
            return (extreme, inner.trim().to_string());
        }
    }
    (Extreme::Final, item.to_string())
}

/// Whether the brackets of `inner` balance without closing the call's own `(` early.
fn encloses(inner: &str) -> bool {
    let mut depth = 0i32;
    for c in inner.chars() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extremes_take_one_argument_and_share_columns() {
        let recorded = parse(&["t, max(theta1), min(theta1)".into(), "max(a, b)".into()]);
        let kinds: Vec<(Extreme, &str, usize)> =
            recorded.iter().map(|r| (r.extreme, r.expression.as_str(), r.column)).collect();
        assert_eq!(
            kinds,
            [
                (Extreme::Final, "t", 0),
                (Extreme::Greatest, "theta1", 1),
                (Extreme::Least, "theta1", 1),
                (Extreme::Final, "max(a, b)", 2),
            ]
        );
        assert_eq!(expressions(&recorded), ["t", "theta1", "max(a, b)"]);
        assert_eq!(extreme_of("max(x) + max(y)").0, Extreme::Final);
    }
}
