//! Small motions about a reference, for a front end: the options read (`--about`, `--set`,
//! `--sweep`), the scene loaded with the command line's reference resolved against its model
//! (no scene text is edited: its spans point into the argument), the `linear` stage run at
//! the parameters' values and over the sweep, and the result assembled as a [`Linearized`].
//! The linearization itself, exact and in numbers, is the `linear` crate's.

use cas::{ExprId, Rational};
use lang::Diagnostic;
use mechanics::Derivation;

use crate::numbers::{prepare_resolved_for, Prepared};
use crate::{Error, Piece, Setting};

pub use linear::{
    Analysis, Case, CaseNumbers, Change, Component, ExactStateSpace, Linearization, Numbers,
    OutputRow, Rank, Row, Stability, StateSpace, Sweep, RANK_TOLERANCE, RELATIVE_TOLERANCE,
};

/// Past this many sweep values the table stops being a table.
const MAX_SWEEP_VALUES: usize = 100_000;

/// What a front end asks for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `theta=0, phi'=2`: items that override or extend the scene's `linearize about` line.
    pub about: Option<String>,
    /// `name=value` pairs for parameters.
    pub set: Vec<String>,
    /// `p=a:b:n`: n values of parameter p from a to b.
    pub sweep: Option<String>,
    /// Skip the dimension check.
    pub no_units: bool,
    /// Leave the positions of cyclic coordinates out of the state (by default the state is
    /// (q, q̇) of every coordinate).
    pub drop_cyclic: bool,
}

/// Everything `linearize` reports.
pub struct Linearized {
    pub derivation: Derivation,
    pub linearization: Linearization,
    /// M, C, K in the forms a report shows.
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    /// The names of the state x of ẋ = A·x: positions (`theta`, or `z1` along the null space
    /// of kept constraints), then rates (`theta'`).
    pub state: Vec<String>,
    /// Whether the algebra showed the accelerations zero at the reference for every value of
    /// the parameters (else numbers showed it at each value used).
    pub exact_reference: bool,
    /// A and B exactly, where the algebra gives them (see [`linear::exact_state_space`]).
    pub exact: Option<ExactStateSpace>,
    /// The inputs' names, the columns of B and D.
    pub inputs: Vec<String>,
    /// The outputs' names, the rows of C and D.
    pub outputs: Vec<String>,
    pub at: Numbers,
    pub sweep: Option<Sweep>,
}

fn bad(message: impl Into<String>) -> Error {
    Error::Input(message.into())
}

/// `p=a:b:n`, checked.
fn parse_sweep(text: &str) -> Result<(String, f64, f64, usize), Error> {
    let form = || {
        let rest = format!(" `{text}` is not of the form p=a:b:n (like w=0:100:201)");
        Error::setting(Setting::Sweep, rest)
    };
    let (name, range) = text.split_once('=').ok_or_else(form)?;
    let parts: Vec<&str> = range.split(':').map(str::trim).collect();
    let [a, b, n] = parts[..] else { return Err(form()) };
    let (Ok(a), Ok(b), Ok(n)) = (a.parse::<f64>(), b.parse::<f64>(), n.parse::<usize>()) else {
        return Err(form());
    };
    if !(a.is_finite() && b.is_finite()) || a == b {
        let rest = ": the ends must be two different finite numbers";
        return Err(Error::given(Setting::Sweep, text, rest));
    }
    if !(2..=MAX_SWEEP_VALUES).contains(&n) {
        let rest = format!(": the number of values must be from 2 to {MAX_SWEEP_VALUES}");
        return Err(Error::given(Setting::Sweep, text, rest));
    }
    Ok((name.trim().to_string(), a, b, n))
}

/// `name=value` pairs, split.
fn parse_sets(sets: &[String]) -> Result<Vec<(String, String)>, Error> {
    let pair = |s: &String| match s.split_once('=') {
        Some((name, value)) => Ok((name.trim().to_string(), value.trim().to_string())),
        None => Err(Error::setting(Setting::Set, format!(" `{s}` is not of the form name=value"))),
    };
    sets.iter().map(pair).collect()
}

/// The command line's reference, resolved against the scene's model as a `linearize about`
/// line after the scene's own, its spans laid after the scene's
/// ([`lang::render::argument_start`]) so that a diagnostic can point into either.
struct About {
    text: String,
    start: usize,
}

impl About {
    fn new(source: &str, text: &str) -> Result<About, Error> {
        if text.contains(['\n', '\r']) {
            return Err(Error::setting(Setting::About, " must be one line"));
        }
        Ok(About { text: text.to_string(), start: lang::render::argument_start(source) })
    }

    /// Resolves the items into `model`, the parameters named in `varying` (those `--set` or
    /// the sweep changes) left to be checked at their values in force; a mistake in the items
    /// points into the argument.
    fn resolve(
        &self,
        model: &mut model::Model,
        source: &str,
        varying: &[&str],
    ) -> Result<(), Error> {
        let shift = |s: lang::Span| lang::Span::new(s.start + self.start, s.end + self.start);
        // A parameter defined through one that changes changes with it (`w2 = 2*w`).
        let mut changing: Vec<cas::SymId> = Vec::new();
        for p in &model.params {
            let through = p
                .value
                .is_some_and(|v| model.pool.free_symbols(v).iter().any(|s| changing.contains(s)));
            if through || varying.contains(&p.name.as_str()) {
                changing.push(p.sym);
            }
        }
        let varying = changing;
        if let Err(mut diagnostics) = model.resolve_about_varying(&self.text, &varying) {
            for d in &mut diagnostics {
                d.span = shift(d.span);
                d.related.iter_mut().for_each(|(s, _)| *s = shift(*s));
            }
            return Err(self.error(source, diagnostics));
        }
        if let Some(line) = model.linearize.last_mut() {
            line.span = shift(line.span);
            line.items.iter_mut().for_each(|item| item.span = shift(item.span));
        }
        Ok(())
    }

    /// The diagnostics of a scene linearized about this reference as an error: with the
    /// argument if any of them points into it (those saying so in their labels), else the
    /// scene's alone.
    fn error(&self, source: &str, mut diagnostics: Vec<Diagnostic>) -> Error {
        let into = |s: &lang::Span| s.start >= self.start;
        if !diagnostics.iter().any(|d| into(&d.span) || d.related.iter().any(|(s, _)| into(s))) {
            return Error::Scene { diagnostics, source: source.to_string() };
        }
        for d in diagnostics.iter_mut().filter(|d| into(&d.span)) {
            d.label = format!("{} (from --about)", d.label);
        }
        Error::WithArgument {
            diagnostics,
            source: source.to_string(),
            setting: Setting::About,
            argument: self.text.clone(),
        }
    }
}

/// The diagnostics of the scene linearized, with the command line's reference if there is one.
fn scene_error(source: &str, about: Option<&About>, diagnostics: Vec<Diagnostic>) -> Error {
    match about {
        Some(about) => about.error(source, diagnostics),
        None => Error::Scene { diagnostics, source: source.to_string() },
    }
}

/// Loads `source`, linearizes it about its reference (with `--about` items after the scene's)
/// and analyses it at the parameters' values, and over the sweep if one is asked for.
pub fn linearize(source: &str, options: &Options) -> Result<Linearized, Error> {
    let sweep = options.sweep.as_deref().map(parse_sweep).transpose()?;
    let sets = parse_sets(&options.set)?;
    let about = options.about.as_deref().map(|text| About::new(source, text)).transpose()?;
    let (mut model, warnings) =
        crate::resolve_with(source, crate::Options { units: !options.no_units })?;
    if let Some(about) = &about {
        let mut varying: Vec<&str> = sets.iter().map(|(name, _)| name.as_str()).collect();
        varying.extend(sweep.iter().map(|(name, ..)| name.as_str()));
        about.resolve(&mut model, source, &varying)?;
    }
    let extra: Vec<(Option<&str>, String)> =
        sets.iter().map(|(name, v)| (Some(name.as_str()), v.clone())).collect();
    let prepared = prepare_resolved_for(source, model, warnings, &extra)?;
    let asked = Asked { about, sets, sweep, drop_cyclic: options.drop_cyclic };
    Ok(linearize_prepared(source, prepared, asked, &[])?.0)
}

/// A scene's own linearization (its `linearize about` lines at its parameters' values) from
/// its derivation, with `sweeps` of its parameters about it, each a sweep's result or why it
/// could not be made: what `check` needs of its `expect linearized:` lines, from the
/// derivation it has already made rather than the scene resolved and derived again.
pub fn linearize_derived(
    source: &str,
    derivation: Derivation,
    sweeps: &[(String, f64, f64, usize)],
) -> Result<(Linearized, Vec<Result<linear::Sweep, Error>>), Error> {
    let prepared = Prepared::from_derivation(derivation, Vec::new());
    let asked = Asked { about: None, sets: Vec::new(), sweep: None, drop_cyclic: false };
    linearize_prepared(source, prepared, asked, sweeps)
}

/// What a linearization is asked for besides the scene: the command line's reference, `--set`
/// values, a sweep, and whether cyclic coordinates are dropped.
struct Asked {
    about: Option<About>,
    sets: Vec<(String, String)>,
    sweep: Option<(String, f64, f64, usize)>,
    drop_cyclic: bool,
}

fn linearize_prepared(
    source: &str,
    mut prepared: Prepared,
    asked: Asked,
    more_sweeps: &[(String, f64, f64, usize)],
) -> Result<(Linearized, Vec<Result<linear::Sweep, Error>>), Error> {
    // Small motions about a reference of a scene whose contacts open and close are not one
    // linear system.
    prepared.refuse_contacts("linearize")?;
    let Asked { about, sets, sweep, drop_cyclic } = asked;
    if prepared.derivation.model.linearize.is_empty() {
        return Err(Error::Setting(vec![
            Piece::Text(
                "the scene has no `linearize about` line: add one, or give the reference with "
                    .into(),
            ),
            Piece::Given(Setting::About, "theta=0".into()),
        ]));
    }
    let linearization = linear::linearize(&mut prepared.derivation, !drop_cyclic)
        .map_err(|diagnostics| scene_error(source, about.as_ref(), diagnostics))?;
    if linearization.coords.is_empty() {
        return Err(bad("the constraints fix every coordinate: nothing is left to linearize"));
    }
    let overrides = overrides(&prepared, &sets)?;
    let swept = match &sweep {
        Some((name, ..)) => Some(parameter_index(&prepared, name, Setting::Sweep)?),
        None => None,
    };
    let d = &prepared.derivation;
    let analysis = Analysis::new(d, &prepared.parameters, linearization)
        .map_err(|e| prepared.lower_error(e))?;
    let mut session = Session { prepared, analysis, overrides, swept, source, about };
    let at = session.analyse(None)?;
    let sweep = match sweep {
        Some((parameter, a, b, n)) => {
            Some(linear::sweep(parameter, (a, b, n), |v| session.analyse(Some(v)))?)
        }
        None => None,
    };
    let more = more_sweeps
        .iter()
        .map(|(name, a, b, n)| {
            session.swept = Some(parameter_index(&session.prepared, name, Setting::Sweep)?);
            linear::sweep(name.clone(), (*a, *b, *n), |v| session.analyse(Some(v)))
        })
        .collect();

    let Session { mut prepared, analysis, .. } = session;
    let linearization = analysis.into_linearization();
    let pool = &mut prepared.derivation.model.pool;
    let mut shown = |m: &[Vec<ExprId>]| -> Vec<Vec<ExprId>> {
        m.iter().map(|r| r.iter().map(|e| pool.factor_content(*e)).collect()).collect()
    };
    let (mass, damping, stiffness) = (
        shown(&linearization.mass),
        shown(&linearization.damping),
        shown(&linearization.stiffness),
    );
    let exact = linear::exact_state_space(pool, &linearization);
    let pool = &prepared.derivation.model.pool;
    let state = at.first_order.state.iter().map(|c| c.name(pool, &linearization.coords)).collect();
    let model = &prepared.derivation.model;
    let inputs = model.inputs.iter().map(|u| u.name.clone()).collect();
    let outputs = model.outputs.iter().map(|o| o.name.clone()).collect();
    let linearized = Linearized {
        exact,
        inputs,
        outputs,
        derivation: prepared.derivation,
        exact_reference: linearization.residual_is_zero,
        linearization,
        mass,
        damping,
        stiffness,
        state,
        at,
        sweep,
    };
    Ok((linearized, more))
}

/// The `--set` values by parameter index, each resolved against the scene (`prepared.extra`).
fn overrides(
    prepared: &Prepared,
    sets: &[(String, String)],
) -> Result<Vec<(usize, ExprId)>, Error> {
    let model = &prepared.derivation.model;
    let mut overrides = Vec::new();
    for ((name, _), expr) in sets.iter().zip(&prepared.extra) {
        let is_coordinate =
            model.coords.iter().any(|c| *name == c.name || *name == format!("{}'", c.name));
        if is_coordinate && !model.params.iter().any(|p| &p.name == name) {
            return Err(Error::Setting(vec![
                Piece::Given(Setting::Set, name.clone()),
                Piece::Text(": the reference is given by `linearize about` or ".into()),
                Piece::Setting(Setting::About),
                Piece::Text(", not ".into()),
                Piece::Setting(Setting::Set),
            ]));
        }
        overrides.push((parameter_index(prepared, name, Setting::Set)?, *expr));
    }
    Ok(overrides)
}

/// The index of the parameter `name`, or an error for `setting` listing those there are.
fn parameter_index(prepared: &Prepared, name: &str, setting: Setting) -> Result<usize, Error> {
    let params = &prepared.derivation.model.params;
    let i = params.iter().position(|p| p.name == name).ok_or_else(|| {
        let known: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
        let rest = format!(": no parameter of that name; one of {}", known.join(", "));
        Error::given(setting, name, rest)
    })?;
    if prepared.parameter_plan.is_derived(i) {
        return Err(crate::numbers::derived_error(&prepared.parameter_plan, setting, i));
    }
    Ok(i)
}

/// A linearization being analysed at one set of parameter values after another.
struct Session<'a> {
    prepared: Prepared,
    analysis: Analysis,
    /// `--set` values: parameter index → expression.
    overrides: Vec<(usize, ExprId)>,
    /// The swept parameter's index.
    swept: Option<usize>,
    /// The scene, and the command line's reference, for diagnostics.
    source: &'a str,
    about: Option<About>,
}

impl Session<'_> {
    /// The numbers at the parameters' values, with the swept parameter at `value` if given.
    fn analyse(&mut self, value: Option<f64>) -> Result<Numbers, Error> {
        let mut all = self.overrides.clone();
        if let (Some(i), Some(v)) = (self.swept, value) {
            let q = Rational::from_float(v).ok_or_else(|| bad(format!("{v} is not a number")))?;
            all.push((i, self.prepared.derivation.model.pool.num(q)));
        }
        let parameters = self.prepared.parameter_values(&all)?;
        if !all.is_empty() {
            // The scene's masses were checked with its own values; these may change their sign.
            self.prepared.masses_at(&parameters)?;
        }
        let model = &self.prepared.derivation.model;
        let at = match (self.swept, value) {
            (Some(i), Some(v)) => format!(" (at {} = {v})", model.params[i].name),
            _ => String::new(),
        };
        if let Some(d) = reference_outside_domain(model, &parameters, &at) {
            return Err(scene_error(self.source, self.about.as_ref(), vec![d]));
        }
        self.analysis.at(&parameters).map_err(|fault| {
            let span = self.analysis.linearization().span;
            let diagnostics = vec![fault.diagnostic(&self.prepared.derivation, span, &at)];
            scene_error(self.source, self.about.as_ref(), diagnostics)
        })
    }
}

/// The first item of the reference (the later lines' overriding the earlier) that is not a
/// real number at the parameters' values in force, as a diagnostic at the item: its domain
/// was checked at the scene's values only where those stay in force.
fn reference_outside_domain(
    model: &model::Model,
    parameters: &[f64],
    at: &str,
) -> Option<Diagnostic> {
    let pool = &model.pool;
    let mut values = vec![f64::NAN; pool.symbol_count()];
    for (p, v) in model.params.iter().zip(parameters) {
        values[p.sym.index()] = *v;
    }
    let items: Vec<&model::About> = model.linearize.iter().flat_map(|l| &l.items).collect();
    let in_force = |i: usize| {
        let (item, later) = (items[i], &items[i + 1..]);
        !later.iter().any(|o| o.coord == item.coord && o.rate == item.rate)
    };
    let (item, value) = (0..items.len()).filter(|&i| in_force(i)).find_map(|i| {
        let value = numeric::eval(pool, items[i].value, &values);
        (!value.is_finite()).then_some((items[i], value))
    })?;
    let name = pool.symbol_text(item.coord, cas::Style::Unicode);
    let what = if item.rate { format!("{name}'") } else { name };
    Some(
        Diagnostic::error(item.span, format!("this reference is not a real number{at}"))
            .with_label(format!("{what} = {value} at the parameters' values in force"))
            .with_hint(
                "a function outside its domain (acos of more than 1, say) or a division by \
                 zero at these values: choose values where the reference exists",
            ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const PENDULUM: &str = "
param m = 1 kg, L = 2 m, g = 9.81 m/s^2
coord theta
particle bob { mass m; position (L*sin(theta), -L*cos(theta)) }
gravity g
";

    fn about(source: &str, about: &str) -> Result<Linearized, Error> {
        linearize(source, &Options { about: Some(about.into()), ..Default::default() })
    }

    #[test]
    fn the_command_lines_reference_is_resolved_against_the_scene() {
        // The scene's names, units and constants: θ = π standing, in degrees.
        let l = about(PENDULUM, "theta = 180 deg").expect("linearizes");
        assert_eq!(l.at.stability, Stability::Unstable);
        assert_eq!(l.derivation.model.linearize.len(), 1);
    }

    #[test]
    fn a_mistake_in_the_command_lines_reference_points_into_it() {
        let Err(Error::WithArgument { diagnostics, source, setting, argument }) =
            about(PENDULUM, "theta = 0, thta' = 0")
        else {
            panic!("a mistake in --about")
        };
        // The scene is not edited: its text is the file's, and the argument has its own.
        assert_eq!(
            (source.as_str(), setting, argument.as_str()),
            (PENDULUM, Setting::About, "theta = 0, thta' = 0")
        );
        let start = lang::render::argument_start(PENDULUM);
        let span = diagnostics[0].span;
        assert_eq!(&argument[span.start - start..span.end - start], "thta");
        assert!(diagnostics[0].label.ends_with("(from --about)"), "{diagnostics:?}");
        let error = about(PENDULUM, "theta = 0, thta' = 0").err().expect("refused").to_string();
        assert!(error.contains("(column 12 of `about`)"), "{error}");
        // Found by the stage, not the resolver: the reference that is not at rest.
        let Err(Error::WithArgument { diagnostics, .. }) = about(PENDULUM, "theta = 1") else {
            panic!("not an equilibrium")
        };
        assert_eq!(diagnostics[0].span, lang::Span::new(start, start + "theta = 1".len()));
    }

    #[test]
    fn a_mistake_in_the_scenes_own_line_stays_the_scenes() {
        let scene = format!("{PENDULUM}linearize about theta = 0, theta' = 1\n");
        let Err(Error::Scene { diagnostics, source }) = about(&scene, "theta = 0") else {
            panic!("θ is not cyclic")
        };
        assert_eq!(source, scene);
        let at = diagnostics[0].span;
        assert_eq!(&scene[at.start..at.end], "theta' = 1");
    }

    #[test]
    fn sweeps_are_parsed_and_checked() {
        assert_eq!(parse_sweep("w=0:100:11").ok(), Some(("w".to_string(), 0.0, 100.0, 11)));
        assert!(parse_sweep("w=0:100").is_err());
        assert!(parse_sweep("w=1:1:5").is_err());
        assert!(parse_sweep("w=0:1:1").is_err());
        assert!(parse_sweep("w=0:x:3").is_err());
    }
}
