//! The values a front end's options carry, typed: `name=value` ([`Assignment`]), `p=a:b:n`
//! ([`SweepRange`]) and an ensemble's varied parameter ([`Vary`]). Each is parsed here once,
//! for the command line's value parsers, the benchmarks and the Python package alike; the
//! errors say what form was wanted and leave naming the option to the front end.

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

/// A time a front end was given as text for `setting` (`until`, `hold`, `step`), as the scene's
/// `simulate` block writes it: `10`, `1/4`, `2*pi`, `20 ms`, `1/4 min`; in seconds. A plain
/// decimal is read as Rust reads it, so `10` has the bits it always had, and its sign is
/// checked with the other settings; anything else as the block reads its value (positive).
/// On failure, the diagnostics, with spans into `text`.
pub fn time(setting: Setting, text: &str) -> Result<f64, Vec<lang::Diagnostic>> {
    match text.trim().parse::<f64>() {
        Ok(seconds) => Ok(seconds),
        Err(_) => model::time_setting(setting.name(), text),
    }
}

/// A pure number a front end was given as text for `setting` (`tolerance`), as the scene
/// writes one: `1e-10`, `10^-12`; a plain decimal read as Rust reads it. A unit is refused.
/// On failure, the diagnostics, with spans into `text`.
pub fn ratio(setting: Setting, text: &str) -> Result<f64, Vec<lang::Diagnostic>> {
    if let Ok(value) = text.trim().parse::<f64>() {
        return Ok(value);
    }
    match model::constant_value(text)? {
        (value, false) => Ok(value),
        (_, true) => {
            let key = setting.name();
            let d = lang::Diagnostic::error(
                lang::Span::new(0, text.len()),
                format!("`{key}` takes no unit"),
            )
            .with_label("a unit")
            .with_hint(format!("`{key}` is a pure number, such as 1e-10"));
            Err(vec![d])
        }
    }
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

/// `NAME=A:B:N`, `NAME=normal(MU, SIGMA)` or `NAME=uniform(A, B)`: how an ensemble varies a
/// parameter, over a grid axis or by random draws.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    pub parameter: String,
    pub spread: Spread,
    /// The numbers of the spread written with a unit (`10 cm`), as written: converted to SI
    /// in `spread`, their dimension checked against the parameter's when the scene is loaded.
    pub with_units: Vec<String>,
}

/// The values a varied parameter takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    /// `values` evenly spaced from `from` to `to`, both included.
    Grid { from: f64, to: f64, values: usize },
    /// Drawn from the normal distribution of this mean and standard deviation (positive).
    Normal { mean: f64, deviation: f64 },
    /// Drawn evenly from `[low, high)`, `low < high`.
    Uniform { low: f64, high: f64 },
}

impl Spread {
    /// The `k`th of a grid axis's values, the last exactly its end.
    pub fn grid_value(&self, k: usize) -> f64 {
        match *self {
            Spread::Grid { to, values, .. } if k + 1 == values => to,
            Spread::Grid { from, to, values } => {
                from + (to - from) * k as f64 / (values - 1) as f64
            }
            _ => f64::NAN,
        }
    }

    /// Whether the values are random draws rather than a grid axis.
    pub fn is_random(&self) -> bool {
        !matches!(self, Spread::Grid { .. })
    }
}

const VARY_FORMS: &str = "the forms are NAME=A:B:N (a grid of N values from A to B), \
                          NAME=normal(MU, SIGMA) and NAME=uniform(A, B)";

impl Vary {
    /// Reads `text`; a mistake is a diagnostic whose span points into `text`, with a hint
    /// that shows the forms.
    pub fn parse(text: &str) -> Result<Vary, lang::Diagnostic> {
        let at = |start: usize, end: usize, message: &str, label: &str| {
            let end = end.max(start + 1).min(text.len().max(start + 1));
            lang::Diagnostic::error(lang::Span::new(start, end), message)
                .with_label(label)
                .with_hint(VARY_FORMS)
        };
        let Some(equals) = text.find('=') else {
            return Err(at(0, text.len(), "no `=` in what to vary", "expected NAME=…"));
        };
        let parameter = text[..equals].trim();
        if parameter.is_empty() {
            return Err(at(0, equals + 1, "no parameter named before `=`", "expected NAME"));
        }
        let spec_start = equals + 1;
        let spec = &text[spec_start..];
        let mut with_units = Vec::new();
        let spread = if let Some(open) = spec.find('(') {
            distribution(text, spec_start, open, &at, &mut with_units)?
        } else {
            grid(text, spec_start, &at, &mut with_units)?
        };
        Ok(Vary { parameter: parameter.to_string(), spread, with_units })
    }
}

/// The pieces of `text[start..end]` between `separator`s, each trimmed, with its span.
fn pieces(text: &str, start: usize, end: usize, separator: char) -> Vec<(usize, usize, &str)> {
    let mut found = Vec::new();
    let mut from = start;
    for (i, c) in text[start..end].char_indices() {
        if c == separator {
            found.push(trimmed(text, from, start + i));
            from = start + i + 1;
        }
    }
    found.push(trimmed(text, from, end));
    found
}

fn trimmed(text: &str, start: usize, end: usize) -> (usize, usize, &str) {
    let piece = &text[start..end];
    let lead = piece.len() - piece.trim_start().len();
    let body = piece.trim();
    (start + lead, start + lead + body.len(), body)
}

type Located<'a> = &'a dyn Fn(usize, usize, &str, &str) -> lang::Diagnostic;

/// A number of the spec, finite: a plain decimal, or as the scene writes a value, an
/// expression of numbers with an optional unit (`pi/2`, `10 cm`), in SI; a number written
/// with a unit is added to `with_units`.
fn number(
    piece: (usize, usize, &str),
    what: &str,
    at: Located,
    with_units: &mut Vec<String>,
) -> Result<f64, lang::Diagnostic> {
    let (start, end, body) = piece;
    if body.is_empty() {
        return Err(at(start, end, &format!("no {what}"), "a number goes here"));
    }
    let not_a_number = |label: &str| at(start, end, &format!("the {what} is not a number"), label);
    match body.parse::<f64>() {
        Ok(v) if v.is_finite() => return Ok(v),
        Ok(_) => return Err(not_a_number("not finite")),
        Err(_) => {}
    }
    match model::constant_value(body) {
        Ok((v, with_unit)) if v.is_finite() => {
            if with_unit {
                with_units.push(body.to_string());
            }
            Ok(v)
        }
        Ok(_) => Err(not_a_number("not finite")),
        Err(diagnostics) => {
            let why = diagnostics.first().map_or("not a number", |d| d.message.as_str());
            Err(not_a_number(why))
        }
    }
}

fn grid(
    text: &str,
    start: usize,
    at: Located,
    with_units: &mut Vec<String>,
) -> Result<Spread, lang::Diagnostic> {
    let parts = pieces(text, start, text.len(), ':');
    let [a, b, n] = parts[..] else {
        let label = format!("{} part(s), where a grid has three, A:B:N", parts.len());
        return Err(at(start, text.len(), "not a grid axis A:B:N nor a distribution", &label));
    };
    let from = number(a, "first value", at, with_units)?;
    let to = number(b, "last value", at, with_units)?;
    let values = match n.2.parse::<usize>() {
        Ok(values) if (2..=MAX_SWEEP_VALUES).contains(&values) => values,
        _ => {
            let label = format!("a whole number from 2 to {MAX_SWEEP_VALUES}");
            return Err(at(n.0, n.1, "the number of values is not a count", &label));
        }
    };
    if from == to {
        return Err(at(a.0, b.1, "a grid axis from a value to itself", "two different ends"));
    }
    Ok(Spread::Grid { from, to, values })
}

fn distribution(
    text: &str,
    start: usize,
    open: usize,
    at: Located,
    with_units: &mut Vec<String>,
) -> Result<Spread, lang::Diagnostic> {
    let (name_start, name_end, name) = trimmed(text, start, start + open);
    let args_start = start + open + 1;
    let Some(close) = text[args_start..].rfind(')').map(|i| args_start + i) else {
        return Err(at(start + open, text.len(), "no closing `)`", "this `(` is not closed"));
    };
    if !text[close + 1..].trim().is_empty() {
        return Err(at(close + 1, text.len(), "text after the distribution", "not expected"));
    }
    let args = pieces(text, args_start, close, ',');
    let [first, second] = args[..] else {
        let label = format!("{} argument(s), where it takes two", args.len());
        return Err(at(args_start, close, "a distribution takes two numbers", &label));
    };
    match name {
        "normal" => {
            let mean = number(first, "mean", at, with_units)?;
            let deviation = number(second, "standard deviation", at, with_units)?;
            if deviation <= 0.0 {
                let (s, e, _) = second;
                return Err(at(s, e, "the standard deviation must be positive", "not positive"));
            }
            Ok(Spread::Normal { mean, deviation })
        }
        "uniform" => {
            let low = number(first, "low end", at, with_units)?;
            let high = number(second, "high end", at, with_units)?;
            if low >= high {
                return Err(at(first.0, second.1, "uniform(A, B) needs A < B", "A is not below B"));
            }
            Ok(Spread::Uniform { low, high })
        }
        _ => {
            let label = match strsim_nearest(name) {
                Some(near) => format!("did you mean `{near}`?"),
                None => "not normal or uniform".to_string(),
            };
            Err(at(name_start, name_end, &format!("unknown distribution `{name}`"), &label))
        }
    }
}

/// The distribution a misspelt name was likely meant to be.
fn strsim_nearest(name: &str) -> Option<&'static str> {
    model::closest(name, ["normal", "uniform"])
}

/// As it is parsed back.
impl fmt::Display for Vary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = &self.parameter;
        match self.spread {
            Spread::Grid { from, to, values } => write!(f, "{name}={from}:{to}:{values}"),
            Spread::Normal { mean, deviation } => write!(f, "{name}=normal({mean}, {deviation})"),
            Spread::Uniform { low, high } => write!(f, "{name}=uniform({low}, {high})"),
        }
    }
}

/// Varied parameters given as text by a front end without a parser of its own; the first
/// that cannot be read, as an [`Error::Expression`] pointing into it.
pub fn varies<S: AsRef<str>>(texts: &[S]) -> Result<Vec<Vary>, Error> {
    let read = |text: &S| {
        let text = text.as_ref();
        Vary::parse(text)
            .map_err(|d| Error::Expression { diagnostics: vec![d], text: text.to_string() })
    };
    texts.iter().map(read).collect()
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
    fn times_are_read_as_the_scene_writes_them() {
        let read = |text: &str| time(Setting::Until, text);
        assert_eq!(read("10").map(f64::to_bits), Ok(10f64.to_bits()));
        assert_eq!(read("0.1").map(f64::to_bits), Ok(0.1f64.to_bits()));
        assert_eq!(read("1/4"), Ok(0.25));
        assert_eq!(read("2*pi"), Ok(2.0 * std::f64::consts::PI));
        assert_eq!(read("20 ms"), Ok(0.02));
        assert_eq!(read("1/4 min"), Ok(15.0));
        for (text, message, culprit) in [
            ("2 m", "`until` is a time, not in m", "m"),
            ("-1 ms", "`until` must be positive", "-1"),
            ("g", "unknown name `g`", "g"),
            ("1/", "expected", ""),
        ] {
            let errors = read(text).expect_err(text);
            assert!(errors[0].message.contains(message), "{text}: {:?}", errors[0].message);
            let span = errors[0].span;
            if !culprit.is_empty() {
                assert_eq!(&text[span.start..span.end], culprit, "{text}");
            }
        }
    }

    #[test]
    fn ratios_are_read_as_the_scene_writes_them() {
        let read = |text: &str| ratio(Setting::Tolerance, text);
        assert_eq!(read("1e-10").map(f64::to_bits), Ok(1e-10f64.to_bits()));
        assert_eq!(read("10^-12"), Ok(1e-12));
        let errors = read("1e-9 s").expect_err("a unit");
        assert_eq!(errors[0].message, "`tolerance` takes no unit");
        assert!(read("x").is_err());
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

    #[test]
    fn varies_are_read_and_written_back() {
        for text in ["a=-3:3:60", "m=normal(1, 0.1)", "g=uniform(9.7, 9.9)"] {
            let vary = Vary::parse(text).expect(text);
            assert_eq!(Vary::parse(&vary.to_string()), Ok(vary.clone()), "{text}");
        }
        let grid = Vary::parse(" a = -3 : 3 : 60 ").expect("a grid");
        assert_eq!(grid.parameter, "a");
        assert_eq!(grid.spread, Spread::Grid { from: -3.0, to: 3.0, values: 60 });
        assert!(Vary::parse("m=normal(1, 0.1)").expect("normal").spread.is_random());
        // As the scene writes values: expressions, and units converted to SI.
        let written = Vary::parse("L=10 cm:pi/2:3").expect("a grid");
        assert_eq!(
            written.spread,
            Spread::Grid { from: 0.1, to: std::f64::consts::FRAC_PI_2, values: 3 }
        );
        assert_eq!(written.with_units, ["10 cm"]);
        let drawn = Vary::parse("L=normal(1 m, 5 cm)").expect("a draw");
        assert_eq!(drawn.spread, Spread::Normal { mean: 1.0, deviation: 0.05 });
        assert_eq!(drawn.with_units, ["1 m", "5 cm"]);
    }

    #[test]
    fn bad_varies_point_at_the_culprit() {
        for (text, message, culprit) in [
            ("a", "no `=` in what to vary", "a"),
            ("=1:2:3", "no parameter named before `=`", "="),
            ("a=1:2", "not a grid axis A:B:N nor a distribution", "1:2"),
            ("a=1:x:3", "the last value is not a number", "x"),
            ("a=1:2 qq:3", "the last value is not a number", "2 qq"),
            ("a=1:2:1", "the number of values is not a count", "1"),
            ("a=2:2:5", "a grid axis from a value to itself", "2:2"),
            ("m=normal(1, -2)", "the standard deviation must be positive", "-2"),
            ("m=normal(1)", "a distribution takes two numbers", "1"),
            ("m=gauss(0, 1)", "unknown distribution `gauss`", "gauss"),
            ("m=uniform(2, 1)", "uniform(A, B) needs A < B", "2, 1"),
            ("m=normal(1, 2", "no closing `)`", "(1, 2"),
        ] {
            let d = Vary::parse(text).expect_err(text);
            assert_eq!(d.message, message, "{text}");
            assert_eq!(&text[d.span.start..d.span.end], culprit, "{text}");
            assert!(d.hint.as_deref().is_some_and(|h| h.contains("NAME=A:B:N")), "{text}");
        }
        let error = varies(&["a=1:2:3", "b"]).expect_err("`b` has no spec");
        assert!(matches!(error, Error::Expression { text, .. } if text == "b"));
    }
}
