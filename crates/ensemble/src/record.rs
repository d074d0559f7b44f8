//! What an ensemble records per run: a scene expression at the end (or at the stop, where `t`
//! is the stop's time), or its least or greatest value over the run, `min(EXPR)` and
//! `max(EXPR)` (a one-argument call; with two arguments `min` and `max` are the scene's own);
//! or of a contact, `impacts(NAME)` (how many times it landed with an impact) and
//! `settled(NAME)` (when its impacts accumulated and it closed for good; NaN if they did not).

use engine::Error;
use sim::{ModeChange, Run};

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

/// A recorded column: its name as written, and what it records.
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    pub name: String,
    pub source: Source,
}

/// What a recorded column is of.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A value of a scene expression (as resolved in the scene's scope), observed in
    /// `column`.
    Expression { extreme: Extreme, expression: String, column: usize },
    /// Of a contact (named as written; its index among the scene's contacts once resolved,
    /// [`resolve_contacts`]).
    Contact { of: ContactRecord, contact: String, index: usize },
}

/// What a column records of a contact.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactRecord {
    /// How many impacts it took (landings by Newton's law, the settling one left out).
    Impacts,
    /// When it settled, NaN if it did not.
    Settled,
}

impl Recorded {
    /// The value this column records of a finished run.
    pub(super) fn value(&self, run: &Run) -> f64 {
        match &self.source {
            Source::Expression { extreme, column, .. } => match extreme {
                Extreme::Final => run.trajectory.rows.last().map_or(f64::NAN, |row| row[*column]),
                Extreme::Least => run.extremes.get(*column).map_or(f64::NAN, |e| e.0),
                Extreme::Greatest => run.extremes.get(*column).map_or(f64::NAN, |e| e.1),
            },
            Source::Contact { of, index, .. } => {
                let mut events = run.modes.iter().filter(|m| m.contact == *index);
                match of {
                    ContactRecord::Impacts => {
                        events.filter(|m| m.kind == ModeChange::Impact).count() as f64
                    }
                    ContactRecord::Settled => {
                        events.find(|m| m.kind == ModeChange::Settled).map_or(f64::NAN, |m| m.time)
                    }
                }
            }
        }
    }
}

/// Gives each contact column its contact's index among `contacts` (the scene's, in the order
/// written), or an error naming a contact the scene does not have.
pub(super) fn resolve_contacts(
    recorded: &mut [Recorded],
    contacts: &[String],
) -> Result<(), Error> {
    for r in recorded {
        if let Source::Contact { contact, index, .. } = &mut r.source {
            *index = contacts.iter().position(|c| c == contact).ok_or_else(|| {
                let known: Vec<String> = contacts.iter().map(|c| format!("`{c}`")).collect();
                Error::Input(format!(
                    "--record {}: the scene has no contact `{contact}` ({})",
                    r.name,
                    if known.is_empty() {
                        "it has no contacts".to_string()
                    } else {
                        format!("its contacts: {}", known.join(", "))
                    }
                ))
            })?;
        }
    }
    Ok(())
}

/// The recorded columns of the lists given, each expression observed once however often it
/// is recorded.
pub(crate) fn parse(lists: &[String]) -> Vec<Recorded> {
    let mut expressions: Vec<String> = Vec::new();
    let mut recorded = Vec::new();
    for item in lists.iter().flat_map(|list| split_list(list)) {
        if let Some((of, contact)) = contact_of(&item) {
            recorded
                .push(Recorded { name: item, source: Source::Contact { of, contact, index: 0 } });
            continue;
        }
        let (extreme, expression) = extreme_of(&item);
        let column = match expressions.iter().position(|e| *e == expression) {
            Some(c) => c,
            None => {
                expressions.push(expression.clone());
                expressions.len() - 1
            }
        };
        recorded.push(Recorded {
            name: item,
            source: Source::Expression { extreme, expression, column },
        });
    }
    recorded
}

/// The distinct expressions observed, in the order of their columns.
pub(super) fn expressions(recorded: &[Recorded]) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for r in recorded {
        if let Source::Expression { expression, column, .. } = &r.source {
            if *column == seen.len() {
                seen.push(expression.clone());
            }
        }
    }
    seen
}

/// Each output at the end: what an ensemble records when asked for nothing.
pub(super) fn finals(outputs: &[String]) -> Vec<Recorded> {
    let final_of = |(column, name): (usize, &String)| Recorded {
        name: name.clone(),
        source: Source::Expression { extreme: Extreme::Final, expression: name.clone(), column },
    };
    outputs.iter().enumerate().map(final_of).collect()
}

/// `impacts(NAME)` and `settled(NAME)` of a contact named by a plain name, if `item` is one.
fn contact_of(item: &str) -> Option<(ContactRecord, String)> {
    for (name, of) in [("impacts", ContactRecord::Impacts), ("settled", ContactRecord::Settled)] {
        let Some(inner) = item.trim().strip_prefix(name).map(str::trim_start) else { continue };
        let Some(inner) = inner.strip_prefix('(').and_then(|i| i.strip_suffix(')')) else {
            continue;
        };
        let inner = inner.trim();
        if !inner.is_empty() && inner.chars().all(|c| c.is_alphanumeric() || c == '_') {
            return Some((of, inner.to_string()));
        }
    }
    None
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
        let kinds: Vec<(Extreme, &str, usize)> = recorded
            .iter()
            .filter_map(|r| match &r.source {
                Source::Expression { extreme, expression, column } => {
                    Some((*extreme, expression.as_str(), *column))
                }
                Source::Contact { .. } => None,
            })
            .collect();
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

    #[test]
    fn a_contact_is_recorded_by_its_name_and_takes_no_column() {
        let mut recorded = parse(&["settled(floor), y, impacts( floor )".into()]);
        assert_eq!(expressions(&recorded), ["y"]);
        resolve_contacts(&mut recorded, &["wall".into(), "floor".into()]).unwrap();
        let of: Vec<_> = recorded
            .iter()
            .filter_map(|r| match &r.source {
                Source::Contact { of, index, .. } => Some((*of, *index)),
                Source::Expression { .. } => None,
            })
            .collect();
        assert_eq!(of, [(ContactRecord::Settled, 1), (ContactRecord::Impacts, 1)]);
        let e = resolve_contacts(&mut recorded, &[]).unwrap_err().to_string();
        assert!(e.contains("no contact `floor` (it has no contacts)"), "{e}");
        // A call of something else is an expression.
        assert!(matches!(parse(&["settled(a + b)".into()])[0].source, Source::Expression { .. }));
    }
}
