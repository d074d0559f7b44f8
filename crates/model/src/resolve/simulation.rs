//! The `simulate { … }` block: each setting read into its type ([`Simulation`]), numbers
//! converted to SI, and every mistake reported where it is written, so that a run never meets
//! a setting it cannot read.

use lang::{Diagnostic, ExprKind, Ident, Setting};

use super::{closest, Resolver};
use crate::units::{parse_unit, Dim};
use crate::Number;

/// The settings a `simulate` block knows, in the order a hint lists them.
const SETTINGS: [&str; 9] =
    ["until", "method", "tolerance", "step", "output", "stop", "event", "input", "hold"];

/// What a number setting measures.
#[derive(Clone, Copy, PartialEq)]
enum Measure {
    /// In seconds unless written with another time unit.
    Time,
    /// A pure number, written without a unit.
    Ratio,
}

impl Measure {
    /// A setting of this measure, written well.
    fn example(self, key: &str) -> String {
        match self {
            Measure::Time => format!("`{key} 10 s`"),
            Measure::Ratio => format!("`{key} 1e-10`"),
        }
    }
}

/// A time given on its own, as a front end's setting is (`--until 1/4 min`, `--hold "20 ms"`):
/// read as the `simulate` block's setting `key` reads its value (a value that names nothing,
/// with an optional time unit), in seconds and positive. On failure, the diagnostics, with
/// spans into `text`.
pub fn time_setting(key: &str, text: &str) -> Result<f64, Vec<Diagnostic>> {
    let (value, unit) = lang::parse_quantity(text)?;
    let key = Ident { name: key.to_string(), span: lang::Span::new(0, text.len()) };
    let setting = Setting { key, target: None, values: vec![value], unit };
    let mut r = Resolver::new(text);
    let number = r.setting_number(&setting, Measure::Time);
    let mut errors = std::mem::take(&mut r.diagnostics.errors);
    // Nothing is declared here: the scene's hint to declare the name would mislead.
    for d in errors.iter_mut().filter(|d| d.message.starts_with("unknown name")) {
        d.hint = Some(format!(
            "a setting's time names no parameter: a number with a unit, like `{}`",
            Measure::Time.example(&setting.key.name).trim_matches('`')
        ));
    }
    match number {
        Some(number) if errors.is_empty() => Ok(number.value),
        _ => {
            if errors.is_empty() {
                errors.push(Diagnostic::error(setting.key.span, "cannot be read as a time"));
            }
            Err(errors)
        }
    }
}

/// A value given on its own that names nothing (an ensemble's bound, `--vary "L=10 cm:1 m:5"`):
/// an expression of numbers and constants with an optional unit, in SI, and whether it had a
/// unit (whose dimension the caller checks against what the value is for). On failure, the
/// diagnostics, with spans into `text`.
pub fn constant_value(text: &str) -> Result<(f64, bool), Vec<Diagnostic>> {
    let (value, unit) = lang::parse_quantity(text)?;
    let mut r = Resolver::new(text);
    let si = r.scalar(&value).and_then(|(written, _)| {
        if !r.model.pool.free_symbols(written).is_empty() {
            r.error(
                Diagnostic::error(value.span, "a bound must be a number")
                    .with_label("names a symbol")
                    .with_hint("write a number, with a unit if you like: `0.1`, `pi/2`, `10 cm`"),
            );
            return None;
        }
        r.in_si(written, unit.as_ref())
    });
    let mut errors = std::mem::take(&mut r.diagnostics.errors);
    for d in errors.iter_mut().filter(|d| d.message.starts_with("unknown name")) {
        d.hint = Some("a bound names no parameter: a number with a unit, like `10 cm`".into());
    }
    match si {
        Some(si) if errors.is_empty() => {
            Ok((numeric::eval(&r.model.pool, si, &[]), unit.is_some()))
        }
        _ => {
            if errors.is_empty() {
                errors.push(Diagnostic::error(value.span, "cannot be read as a number"));
            }
            Err(errors)
        }
    }
}

impl Resolver<'_> {
    /// A `simulate { … }` block: its settings added to those of earlier blocks.
    pub(super) fn simulate_statement(&mut self, settings: &[Setting]) {
        for setting in settings {
            self.setting(setting);
        }
    }

    fn setting(&mut self, setting: &Setting) {
        if let (Some(target), false) = (&setting.target, setting.key.name == "input") {
            self.error(
                Diagnostic::error(target.span, format!("`{}` takes no name", setting.key.name))
                    .with_label("`NAME =` is for `input`")
                    .with_hint("only `input F = EXPR` names what it sets"),
            );
            return;
        }
        match setting.key.name.as_str() {
            "until" => {
                if let Some(n) = self.setting_number(setting, Measure::Time) {
                    self.model.simulation.until = Some(n);
                }
            }
            "step" => {
                if let Some(n) = self.setting_number(setting, Measure::Time) {
                    self.model.simulation.step = Some(n);
                }
            }
            "hold" => {
                if let Some(mut n) = self.setting_number(setting, Measure::Time) {
                    // The whole setting, `hold 20 ms`: what a diagnostic about the hold
                    // itself (not its value) points at.
                    let value = setting.values.first().map_or(n.span, |v| v.span);
                    let end = setting.unit.as_ref().map_or(value, |u| u.span);
                    n.span = setting.key.span.join(value).join(end);
                    self.model.simulation.hold = Some(n);
                }
            }
            "tolerance" => {
                if let Some(n) = self.setting_number(setting, Measure::Ratio) {
                    self.model.simulation.tolerance = Some(n);
                }
            }
            "method" => {
                if let Some(name) = self.setting_name(setting) {
                    self.model.simulation.method = Some(name);
                }
            }
            "output" => self.model.simulation.outputs = self.setting_texts(setting, "outputs"),
            "stop" => self.model.simulation.stops = self.setting_texts(setting, "stops"),
            "event" => self.model.simulation.events = self.setting_texts(setting, "events"),
            "input" => self.drive_setting(setting),
            other => {
                let d = Diagnostic::error(
                    setting.key.span,
                    format!("unknown setting `{other}` in the simulate block"),
                )
                .with_label("not a setting");
                let known = SETTINGS.join(", ");
                self.error(match closest(other, SETTINGS) {
                    Some(near) => d.with_hint(format!("did you mean `{near}`? (known: {known})")),
                    None => d.with_hint(format!("the settings are {known}")),
                });
            }
        }
    }

    /// A `hold` of the `simulate` blocks samples the laws their `input` lines give: with none,
    /// it would hold nothing (the run refuses it), so the scene is refused where it stands.
    pub(super) fn hold_needs_a_law(&mut self) {
        let simulation = &self.model.simulation;
        let Some(hold) = simulation.hold else { return };
        if !simulation.drives.is_empty() {
            return;
        }
        self.error(
            Diagnostic::error(hold.span, "`hold` with no law to hold")
                .with_label("holds nothing")
                .with_hint(
                    "`hold` samples the laws that drive inputs: add one to the block \
                     (`input F = -k*x`), or give the hold with the law to the run",
                ),
        );
    }

    /// The one number of an `until`, `step` or `tolerance` setting, in SI and positive.
    fn setting_number(&mut self, setting: &Setting, measure: Measure) -> Option<Number> {
        let key = &setting.key.name;
        let value = self.single_value(setting)?;
        let scale = match (&setting.unit, measure) {
            (None, _) => None,
            (Some(unit), Measure::Ratio) => {
                self.error(
                    Diagnostic::error(unit.span, format!("`{key}` takes no unit"))
                        .with_label("a unit")
                        .with_hint(format!("`{key}` is a pure number: {}", measure.example(key))),
                );
                return None;
            }
            (Some(unit), Measure::Time) => match parse_unit(unit) {
                Err(d) => {
                    self.error(d);
                    return None;
                }
                Ok((dim, _)) if dim != Dim::base(2) => {
                    self.error(
                        Diagnostic::error(
                            unit.span,
                            format!("`{key}` is a time, not in {}", self.text(unit.span)),
                        )
                        .with_label("not a time")
                        .with_hint(format!(
                            "write it in seconds (or ms, min, h): {}",
                            measure.example(key)
                        )),
                    );
                    return None;
                }
                Ok(_) => Some(unit),
            },
        };
        let (written, _) = self.scalar(value)?;
        if !self.model.pool.free_symbols(written).is_empty() {
            self.error(
                Diagnostic::error(value.span, format!("`{key}` must be a number"))
                    .with_label("names a symbol")
                    .with_hint(format!(
                        "settings take numbers, not parameters: {}",
                        measure.example(key)
                    )),
            );
            return None;
        }
        let si = self.in_si(written, scale)?;
        let number = numeric::eval(&self.model.pool, si, &[]);
        if !(number.is_finite() && number > 0.0) {
            self.error(
                Diagnostic::error(value.span, format!("`{key}` must be positive"))
                    .with_label(format!("= {number}"))
                    .with_hint(format!("for example {}", measure.example(key))),
            );
            return None;
        }
        Some(Number { value: number, span: value.span })
    }

    /// The method's name: one bare name, checked against the integrator's names by the front
    /// end that runs it.
    fn setting_name(&mut self, setting: &Setting) -> Option<Ident> {
        let value = self.single_value(setting)?;
        match (&value.kind, &setting.unit) {
            (ExprKind::Name { name, primes: 0 }, None) => {
                Some(Ident { name: name.clone(), span: value.span })
            }
            _ => {
                let span = setting.unit.as_ref().map_or(value.span, |u| u.span);
                self.error(
                    Diagnostic::error(span, "a method is a name")
                        .with_label("not a method's name")
                        .with_hint("for example `method dop853`"),
                );
                None
            }
        }
    }

    /// The expressions of an `output`, `stop` or `event` setting as written, added to those of
    /// earlier ones.
    fn setting_texts(&mut self, setting: &Setting, what: &str) -> Vec<String> {
        let mut texts = match setting.key.name.as_str() {
            "output" => std::mem::take(&mut self.model.simulation.outputs),
            "stop" => std::mem::take(&mut self.model.simulation.stops),
            _ => std::mem::take(&mut self.model.simulation.events),
        };
        if let Some(unit) = &setting.unit {
            self.error(
                Diagnostic::error(unit.span, format!("{what} take no unit"))
                    .with_label("a unit")
                    .with_hint("each is a scene expression, in SI like the scene's own"),
            );
        }
        texts.extend(setting.values.iter().map(|v| self.text(v.span)));
        texts
    }

    /// `input F = EXPR`: an input the scene declares, driven in a run by a law kept as
    /// written, which the run resolves.
    fn drive_setting(&mut self, setting: &Setting) {
        let form = "write `input NAME = EXPR`, such as `input F = -k*x`";
        let Some(target) = &setting.target else {
            self.error(
                Diagnostic::error(setting.key.span, "`input` needs the input it drives")
                    .with_label("no `NAME =`")
                    .with_hint(form),
            );
            return;
        };
        let name = super::normalize(&target.name);
        if !self.model.inputs.iter().any(|u| u.name == name) {
            let inputs: Vec<&str> = self.model.inputs.iter().map(|u| u.name.as_str()).collect();
            let d = Diagnostic::error(target.span, format!("no input `{}`", target.name))
                .with_label("not an input");
            let hint = match (closest(&name, inputs.iter().copied()), inputs.is_empty()) {
                (_, true) => "the scene declares no input: add `input NAME = VALUE UNIT`".into(),
                (Some(near), false) => format!("did you mean `{near}`?"),
                (None, false) => format!("the inputs are {}", inputs.join(", ")),
            };
            self.error(d.with_hint(hint));
            return;
        }
        let (Some(value), 1, None) = (setting.values.first(), setting.values.len(), &setting.unit)
        else {
            self.error(
                Diagnostic::error(setting.key.span, "`input` takes one law and no unit")
                    .with_label("here")
                    .with_hint(form),
            );
            return;
        };
        let law = self.text(value.span);
        let drives = &mut self.model.simulation.drives;
        drives.retain(|d| d.input != name);
        drives.push(crate::Drive { input: name, law });
    }

    /// The value of a setting that takes one.
    fn single_value<'s>(&mut self, setting: &'s Setting) -> Option<&'s lang::Expr> {
        let key = &setting.key.name;
        if let Some(second) = setting.values.get(1) {
            self.error(
                Diagnostic::error(second.span, format!("`{key}` takes one value"))
                    .with_label("a second value")
                    .with_hint(format!(
                        "give `{key}` once; only `output`, `stop` and `event` take lists"
                    )),
            );
            return None;
        }
        setting.values.first()
    }
}

#[cfg(test)]
mod tests {
    use crate::{resolve, Simulation};

    const SCENE: &str = "param m = 1\ncoord x = 1\nparticle p { mass m; position (x, 0) }\n";

    fn simulation(block: &str) -> Result<Simulation, Vec<String>> {
        let source = format!("{SCENE}{block}\n");
        let ast = lang::parse(&source).expect("parses");
        match resolve(&ast, &source) {
            Ok((model, _)) => Ok(model.simulation),
            Err(errors) => Err(errors.into_iter().map(|d| d.message).collect()),
        }
    }

    #[test]
    fn settings_are_typed_and_in_si() {
        let s = simulation("simulate { until 2 min; step 5 ms; tolerance 1e-8; method rk4 }")
            .expect("resolves");
        assert_eq!(s.until.map(|n| n.value), Some(120.0));
        assert_eq!(s.step.map(|n| n.value), Some(0.005));
        assert_eq!(s.tolerance.map(|n| n.value), Some(1e-8));
        assert_eq!(s.method.map(|m| m.name), Some("rk4".to_string()));
    }

    #[test]
    fn later_blocks_override_numbers_and_add_to_lists() {
        let s = simulation(
            "simulate { until 1; output x }\nsimulate { until 3 s; output x', KE + PE }",
        )
        .expect("resolves");
        assert_eq!(s.until.map(|n| n.value), Some(3.0));
        assert_eq!(s.outputs, ["x", "x'", "KE + PE"]);
    }

    #[test]
    fn mistakes_are_reported_where_they_stand() {
        for (block, message) in [
            ("simulate { untill 2 }", "unknown setting `untill` in the simulate block"),
            ("simulate { until 2 m }", "`until` is a time, not in m"),
            ("simulate { until -1 }", "`until` must be positive"),
            ("simulate { until 1, 2 }", "`until` takes one value"),
            ("simulate { tolerance 1 s }", "`tolerance` takes no unit"),
            ("simulate { step m }", "`step` must be a number"),
            ("simulate { method 4 }", "a method is a name"),
            ("simulate { hold 20 ms }", "`hold` with no law to hold"),
        ] {
            assert_eq!(simulation(block).err(), Some(vec![message.to_string()]), "{block}");
        }
    }
}
