//! The values a front end's options carry, typed: `name=value` ([`Assignment`]) and
//! `p=a:b:n` ([`SweepRange`]). Each is parsed here once, by [`FromStr`], for the command
//! line's value parsers, the benchmarks and the Python package alike; the errors say what
//! form was wanted and leave naming the option to the front end.

use std::fmt;
use std::str::FromStr;

use crate::{Error, Setting};

/// The most values a sweep may take.
pub const MAX_SWEEP_VALUES: usize = 100_000;

/// Why an option's text could not be read: what form it should have had.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidInput(String);

impl fmt::Display for InvalidInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InvalidInput {}

/// `name=value`: a parameter, a coordinate or (primed, `theta'`) a rate given a value in place
/// of the scene's. The value is a scene expression, resolved when the scene is loaded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    /// As written, primes included.
    pub name: String,
    pub value: String,
}

impl Assignment {
    /// The name without its primes, and how many it had.
    pub fn base(&self) -> (&str, usize) {
        let base = self.name.trim_end_matches('\'');
        (base, self.name.len() - base.len())
    }
}

impl FromStr for Assignment {
    type Err = InvalidInput;

    fn from_str(text: &str) -> Result<Self, InvalidInput> {
        let Some((name, value)) = text.split_once('=') else {
            return Err(InvalidInput("not of the form name=value (like g=1.62)".into()));
        };
        let (name, value) = (name.trim(), value.trim());
        if name.is_empty() {
            return Err(InvalidInput("no name before `=` (like g=1.62)".into()));
        }
        if value.is_empty() {
            return Err(InvalidInput(format!("no value after `{name}=` (like {name}=1.62)")));
        }
        Ok(Assignment { name: name.to_string(), value: value.to_string() })
    }
}

/// As it is parsed back: `name=value`.
impl fmt::Display for Assignment {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}", self.name, self.value)
    }
}

/// Assignments given as text by a front end without a parser of its own (Python's strings),
/// each read as [`Assignment::from_str`] reads it; the first that cannot be, as an
/// [`Error::Setting`] naming it.
pub fn assignments<S: AsRef<str>>(texts: &[S]) -> Result<Vec<Assignment>, Error> {
    assignments_of(Setting::Set, texts)
}

/// [`assignments`] given for `setting` (`set`, or `input` for the inputs a run drives).
pub fn assignments_of<S: AsRef<str>>(
    setting: Setting,
    texts: &[S],
) -> Result<Vec<Assignment>, Error> {
    let read = |text: &S| {
        let text = text.as_ref();
        text.parse().map_err(|e| Error::setting(setting, format!(" `{text}`: {e}")))
    };
    texts.iter().map(read).collect()
}

/// `p=a:b:n`: n evenly spaced values of parameter p from a to b, both included.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRange {
    pub parameter: String,
    /// The first and last values: finite and different.
    pub from: f64,
    pub to: f64,
    /// From 2 to [`MAX_SWEEP_VALUES`].
    pub values: usize,
}

impl FromStr for SweepRange {
    type Err = InvalidInput;

    fn from_str(text: &str) -> Result<Self, InvalidInput> {
        let form = || InvalidInput("not of the form p=a:b:n (like w=0:100:201)".into());
        let (name, range) = text.split_once('=').ok_or_else(form)?;
        let parts: Vec<&str> = range.split(':').map(str::trim).collect();
        let [a, b, n] = parts[..] else { return Err(form()) };
        let (Ok(from), Ok(to), Ok(values)) = (a.parse::<f64>(), b.parse::<f64>(), n.parse()) else {
            return Err(form());
        };
        let parameter = name.trim().to_string();
        if parameter.is_empty() {
            return Err(form());
        }
        if !(from.is_finite() && to.is_finite()) || from == to {
            return Err(InvalidInput("the ends must be two different finite numbers".into()));
        }
        if !(2..=MAX_SWEEP_VALUES).contains(&values) {
            let message = format!("the number of values must be from 2 to {MAX_SWEEP_VALUES}");
            return Err(InvalidInput(message));
        }
        Ok(SweepRange { parameter, from, to, values })
    }
}

/// As it is parsed back: `p=a:b:n`, the ends in their shortest exact form.
impl fmt::Display for SweepRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}:{}:{}", self.parameter, self.from, self.to, self.values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assignments_are_read_and_written_back() {
        let a: Assignment = " theta' = pi/3 ".parse().expect("an assignment");
        assert_eq!((a.name.as_str(), a.value.as_str()), ("theta'", "pi/3"));
        assert_eq!(a.base(), ("theta", 1));
        assert_eq!(a.to_string().parse::<Assignment>(), Ok(a));
        for (text, error) in [
            ("g", "not of the form name=value (like g=1.62)"),
            ("=1", "no name before `=` (like g=1.62)"),
            ("g=", "no value after `g=` (like g=1.62)"),
        ] {
            assert_eq!(text.parse::<Assignment>().map_err(|e| e.to_string()), Err(error.into()));
        }
    }

    #[test]
    fn text_assignments_fail_naming_the_setting() {
        assert_eq!(assignments(&["g=1.62"]).map(|a| a.len()), Ok(1));
        let error = assignments(&["g=1", "h"]).expect_err("`h` has no value");
        assert_eq!(error.to_string(), "error: `set` `h`: not of the form name=value (like g=1.62)");
    }

    #[test]
    fn sweeps_are_read_checked_and_written_back() {
        let s: SweepRange = "w=0:100:11".parse().expect("a sweep");
        assert_eq!(s, SweepRange { parameter: "w".into(), from: 0.0, to: 100.0, values: 11 });
        let odd: SweepRange = "v=0.1:1e-3:7".parse().expect("a sweep");
        assert_eq!(odd.to_string().parse::<SweepRange>(), Ok(odd));
        for text in ["w=0:100", "w=0:x:3", "=0:1:3", "w"] {
            let error = text.parse::<SweepRange>().expect_err(text).to_string();
            assert!(error.starts_with("not of the form p=a:b:n"), "{text}: {error}");
        }
        assert!(matches!("w=1:1:5".parse::<SweepRange>(), Err(e) if e.0.contains("different")));
        assert!(matches!("w=0:1:1".parse::<SweepRange>(), Err(e) if e.0.contains("from 2")));
    }
}
