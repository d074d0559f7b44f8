//! Runs of a scene, above `engine`'s prepared scene: settings from the scene's `simulate { … }`
//! block and the front end's options, read into typed [`Settings`] and checked, from the one
//! resolution the scene is loaded from ([`Resolved`]); the outputs, stop conditions, events and
//! `--set` values resolved as expressions in the scene's scope; the inputs' laws put in place
//! ([`drive`](drive_signals)); the problem a method integrates ([`Integrand`]), lowered once
//! for run after run ([`Compiled`]); the run, its rows handed to a front end's [`Sink`] as they
//! are made; the words of a fault; the figures of an animation ([`animate`]); and the
//! measurement of integrators against a reference that `lagrange bench` prints ([`bench`]).
//! Writing the results is the front end's.

use std::ops::ControlFlow;
use std::time::Instant;

use sim::{integrate, FaultKind, Mechanical, Method, NonFiniteAt, Run};

pub mod along;
pub mod animate;
pub mod bench;
mod compiled;
mod drive;
mod fault;
mod integrand;
mod on_demand;
mod rows;

pub use compiled::Compiled;
pub use drive::{hold as drive_hold, signals as drive_signals};
pub use fault::FastestMode;
pub use integrand::{frictions, restitutions, run_settings, watched, Integrand};
pub use rows::{Sink, Totals};

use crate::animate::Animation;
use engine::input::Assignment;
use engine::numbers::{prepare_resolved, Prepared};
use lang::Diagnostic;

use engine::{Error, Piece, Setting};

/// What a front end asks for; `None` leaves the scene's setting or the default.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub until: Option<f64>,
    pub method: Option<String>,
    pub tolerance: Option<f64>,
    pub step: Option<f64>,
    /// Values in place of the scene's.
    pub set: Vec<Assignment>,
    /// Inputs driven by expressions of t, the state and the parameters (`F=-20*x - 5*x'`).
    pub input: Vec<Assignment>,
    /// Inputs given as time series (read from files by the front end), by name.
    pub input_series: Vec<(String, sim::Series)>,
    /// Sample the inputs driven by laws every this many seconds and hold each sample (a
    /// zero-order hold), rather than apply the laws continuously.
    pub hold: Option<f64>,
    /// Quantities to record, comma-separated lists.
    pub output: Vec<String>,
    /// Expressions whose zero (or `lhs = rhs`) ends the run.
    pub stop_when: Vec<String>,
    /// Expressions whose zero crossings are recorded.
    pub events: Vec<String>,
    /// Skip the dimension check.
    pub no_units: bool,
    /// Evenly spaced times to record at (0: every accepted step).
    pub samples: usize,
    /// Also evaluate the scene's figures at every recorded time ([`Outcome::animation`]).
    pub animate: bool,
}

/// The settings of a run: the scene's `simulate` block overridden by the [`Options`], checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The end time, in seconds; positive.
    pub until: f64,
    pub method: Method,
    /// The tolerance of the adaptive methods; positive.
    pub tolerance: f64,
    /// The step of the fixed-step methods; positive.
    pub step: f64,
    /// Quantities to record, as scene expressions; none: every remaining coordinate.
    pub outputs: Vec<String>,
    /// Expressions whose zero ends the run.
    pub stops: Vec<String>,
    /// Expressions whose zero crossings are recorded.
    pub events: Vec<String>,
    /// `--set` values, each a scene expression.
    pub sets: Vec<Assignment>,
    /// The inputs driven, each by a scene expression of t, the state and the parameters.
    pub drives: Vec<Assignment>,
    /// The inputs given as time series, by name.
    pub series: Vec<(String, sim::Series)>,
    /// The period of the zero-order hold of the driven inputs' laws (positive); none: the laws
    /// act continuously.
    pub hold: Option<f64>,
    /// Evenly spaced times to record at (0: every accepted step).
    pub samples: usize,
    /// Check dimensions when loading.
    pub units: bool,
    /// Evaluate the scene's figures at every recorded time.
    pub animate: bool,
}

/// How far a run has got, for a front end that shows it; `()` shows nothing.
pub trait Progress {
    /// The integration starts (after loading and lowering) and will run to `until`.
    fn start(&mut self, _until: f64) {}
    /// The integration has reached `t`.
    fn update(&mut self, _t: f64) {}
    /// The integration is over.
    fn finish(&mut self) {}
    /// Whether the front end wants the run to stop now (its user pressed Ctrl-C). Asked after
    /// every accepted step, so it is cheap or throttled; a run stopped so ends where it is,
    /// [`sim::Run::interrupted`].
    fn interrupted(&mut self) -> bool {
        false
    }
}

impl Progress for () {}

/// A finished (or faulted) simulation, ready to be written.
pub struct Outcome {
    pub columns: Vec<String>,
    /// The run; its trajectory is empty where the rows went to a [`Sink`] as they were made.
    pub run: Run,
    /// The figures of every row the summary gives, whether the rows were kept or not.
    pub totals: Totals,
    /// Which trajectory columns are the recorded outputs (the rest are internal).
    pub shown: usize,
    /// Trajectory columns of KE and PE.
    pub energy_columns: (usize, usize),
    pub constraint_columns: Vec<usize>,
    pub event_names: Vec<String>,
    pub stop_names: usize,
    pub method: Method,
    pub wall_seconds: f64,
    pub state_names: Vec<String>,
    /// The constraints kept with multipliers, in the order of the numbers' slots.
    pub constraint_names: Vec<String>,
    /// The contacts, in the order written: the run's mode events ([`sim::Run::modes`]) index
    /// them.
    pub contact_names: Vec<String>,
    /// Which contacts are rough contacts in space (`slip (V1, V2)`): their slips have a
    /// direction, not a sign.
    pub contacts_in_space: Vec<bool>,
    /// The parameter slots' names (the inputs' after the parameters'), for a fault in a held
    /// law.
    pub parameter_names: Vec<String>,
    /// Bodies in space oriented by angles (not Euler parameters), whose angle sets have
    /// singular configurations where the mass matrix loses rank.
    pub angle_oriented_bodies: Vec<String>,
    /// Whether the scene's energy should be conserved (no forces, dissipation or explicit t).
    pub conservative: bool,
    /// The scene's figures at every recorded time, when the settings asked for them.
    pub animation: Option<Animation>,
    /// The mode an explicit method's step could not follow, when that is what ended the run.
    pub fastest_mode: Option<FastestMode>,
    /// An input driven continuously by a law is in the Lagrangian: the symplectic methods
    /// refuse the run ([`DRIVEN_IN_LAGRANGIAN`]).
    pub lagrangian_driven: bool,
}

/// What happened to a contact, in one word, as every front end names it (the summary, the
/// events table, Python's `contact_events`, the animation's page).
pub fn mode_word(kind: sim::ModeChange) -> &'static str {
    match kind {
        sim::ModeChange::Impact => "impact",
        sim::ModeChange::Settled => "settled",
        sim::ModeChange::Closed => "closed",
        sim::ModeChange::LiftOff => "lift-off",
        sim::ModeChange::Struck => "struck",
        sim::ModeChange::Sticks => "sticks",
        sim::ModeChange::Slips => "slips",
    }
}

/// Why a method that [`Method::handles_multipliers`] says no to cannot run a scene with such
/// constraints; shared by `simulate`'s error and `bench`'s list of methods left out.
pub const NO_MULTIPLIERS: &str =
    "works in canonical variables and does not handle constraints kept with multipliers";

/// Why a symplectic method cannot run a scene whose Lagrangian holds an input driven by a
/// law; shared by `simulate`'s error and `bench`'s list of methods left out.
pub const DRIVEN_IN_LAGRANGIAN: &str =
    "works from the Lagrangian, and an input driven by a law must not be in it (through a \
     potential)";

fn bad(message: impl Into<String>) -> Error {
    Error::Input(message.into())
}

/// Splits at commas outside parentheses and brackets.
pub fn split_list(text: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let (mut depth, mut current) = (0i32, String::new());
    for c in text.chars() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(current.trim().to_string());
                current.clear();
                continue;
            }
            _ => {}
        }
        current.push(c);
    }
    if !current.trim().is_empty() {
        parts.push(current.trim().to_string());
    }
    parts
}

/// `lhs = rhs` as `(lhs) - (rhs)`; an expression without `=` as itself.
fn zero_of(text: &str) -> String {
    match text.split_once('=') {
        Some((l, r)) => format!("({}) - ({})", l.trim(), r.trim()),
        None => text.trim().to_string(),
    }
}

/// Refuses a front end's tolerance for a fixed-step method and its step for an adaptive one:
/// the run would not use it, and would give the same bits as without it.
fn check_applies(method: Method, options: &Options) -> Result<(), Error> {
    let (unused, used) = match (method.is_adaptive(), options.step, options.tolerance) {
        (true, Some(_), _) => (Setting::Step, Setting::Tolerance),
        (false, _, Some(_)) => (Setting::Tolerance, Setting::Step),
        _ => return Ok(()),
    };
    let kind = if method.is_adaptive() { "an adaptive" } else { "a fixed-step" };
    Err(Error::Setting(vec![
        Piece::Setting(unused),
        Piece::Text(format!(" is not used by {}, {kind} method: it takes ", method.name())),
        Piece::Setting(used),
        Piece::Text(format!(
            " (the adaptive methods {} take a tolerance, the fixed-step {} a step)",
            engine::block::methods_taking(true),
            engine::block::methods_taking(false)
        )),
    ]))
}

/// The settings of a run of `source`: its `simulate` block, as its model has read it (before
/// the scene is derived; a scene that does not resolve has none, and loading it reports why),
/// then the options.
pub fn settings(source: &str, options: &Options) -> Result<Settings, Error> {
    Resolved::new(source, options).settings(options)
}

/// A scene resolved once for a run: its settings are read from it and then it is loaded, so
/// that a command resolves its scene one time (a resolution is most of a short run's
/// set-up, and two could disagree). A scene that does not resolve keeps its error for the
/// load to report, and has the default settings meanwhile.
pub struct Resolved<'a> {
    source: &'a str,
    model: Result<(model::Model, Vec<Diagnostic>), Error>,
}

impl<'a> Resolved<'a> {
    /// Resolves `source` as a run takes it (inputs may stand in constraints, the laws are put
    /// in place before deriving), with the options' unit check.
    pub fn new(source: &'a str, options: &Options) -> Resolved<'a> {
        let checks = model::Checks { units: !options.no_units, inputs_in_constraints: true };
        Resolved { source, model: engine::resolve_checked(source, checks) }
    }

    /// The scene's `simulate` block overridden by the options (see [`settings`]).
    pub fn settings(&self, options: &Options) -> Result<Settings, Error> {
        let simulation = match &self.model {
            Ok((model, _)) => model.simulation.clone(),
            Err(_) => model::Simulation::default(),
        };
        settings_from_block(self.source, simulation, options)
    }

    /// Every coordinate the scene declares and its rate (`theta`, `theta'`), in declaration
    /// order; none for a scene that does not resolve.
    pub fn declared_states(&self) -> Vec<String> {
        let Ok((model, _)) = &self.model else { return Vec::new() };
        let names = model.coords.iter().map(|c| c.name.clone());
        names.clone().chain(names.map(|n| format!("{n}'"))).collect()
    }

    /// The scene loaded with the settings' expressions and laws (see [`Loaded`]).
    pub fn load(self, settings: &Settings) -> Result<Loaded, Error> {
        let (model, warnings) = self.model?;
        load_model(self.source, model, warnings, settings)
    }
}

/// [`settings`] of a resolved scene's `simulate` block.
fn settings_from_block(
    source: &str,
    simulation: model::Simulation,
    options: &Options,
) -> Result<Settings, Error> {
    if let (None, Some(hold)) = (options.hold, simulation.hold) {
        // The block's laws all replaced by time series: the block's hold has nothing left to
        // hold, and it is the block's line that says so.
        let kept = simulation.drives.iter().any(|d| {
            !options.input_series.iter().any(|(name, _)| *name == d.input)
                || options.input.iter().any(|a| a.name == d.input)
        });
        if !kept && options.input.is_empty() {
            let d = Diagnostic::error(hold.span, "`hold` with no law left to hold")
                .with_label("holds nothing in this run")
                .with_hint(
                    "the time series given replace every law the block holds; a series is \
                     not sampled by `hold`",
                );
            return Err(Error::Scene { diagnostics: vec![d], source: source.to_string() });
        }
    }
    settings_of(simulation, options)
}

/// The settings of a run of a scene whose `simulate` block is `scene` (a loaded scene's
/// `model.simulation`, its method name checked), then the options: [`settings`] without
/// resolving the scene again.
pub fn settings_of(scene: model::Simulation, options: &Options) -> Result<Settings, Error> {
    let number = |n: Option<model::Number>| n.map(|n| n.value);
    let mut until = number(scene.until).unwrap_or(10.0);
    // `resolve_with` has checked the name.
    let mut method = engine::block::scene_method(&scene).ok().flatten().unwrap_or(Method::DEFAULT);
    let mut tolerance = number(scene.tolerance).unwrap_or(1e-10);
    let mut step = number(scene.step);
    let hold = options.hold.or(number(scene.hold));
    let (mut outputs, mut stops, mut events) = (scene.outputs, scene.stops, scene.events);
    // The scene's laws, each replaced by the front end's for the same input.
    let mut drives: Vec<Assignment> = scene
        .drives
        .into_iter()
        .filter(|d| !options.input.iter().any(|a| a.name == d.input))
        .filter(|d| !options.input_series.iter().any(|(name, _)| *name == d.input))
        .map(|d| Assignment { name: d.input, value: d.law })
        .collect();
    drives.extend(options.input.iter().cloned());
    if let Some(u) = options.until {
        until = u;
    }
    if let Some(name) = &options.method {
        method = Method::from_name(name).ok_or_else(|| {
            bad(format!("unknown method `{name}`; one of {}", Method::NAMES.join(", ")))
        })?;
    }
    check_applies(method, options)?;
    if let Some(t) = options.tolerance {
        tolerance = t;
    }
    if options.step.is_some() {
        step = options.step;
    }
    if !options.output.is_empty() {
        outputs = options.output.iter().flat_map(|o| split_list(o)).collect();
    }
    stops.extend(options.stop_when.iter().map(|s| zero_of(s)));
    events.extend(options.events.iter().map(|s| zero_of(s)));
    if !(until.is_finite() && until > 0.0) {
        return Err(Error::setting(
            Setting::Until,
            format!(" must be a positive time, not {until}"),
        ));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::setting(
            Setting::Tolerance,
            format!(" must be positive, not {tolerance}"),
        ));
    }
    let step = step.unwrap_or(until / 1000.0);
    if !(step.is_finite() && step > 0.0) {
        return Err(Error::setting(Setting::Step, format!(" must be positive, not {step}")));
    }
    drive::check_hold(hold, &drives)?;

    Ok(Settings {
        until,
        method,
        tolerance,
        step,
        outputs,
        stops,
        events,
        sets: options.set.clone(),
        drives,
        series: options.input_series.clone(),
        hold,
        samples: options.samples,
        units: !options.no_units,
        animate: options.animate,
    })
}

/// Reads the settings of `source` and runs it, showing nothing while it runs.
pub fn simulate(source: &str, options: &Options) -> Result<Outcome, Error> {
    simulate_with(source, options, &mut ())
}

/// [`simulate`], telling `progress` how far the integration has got.
pub fn simulate_with(
    source: &str,
    options: &Options,
    progress: &mut dyn Progress,
) -> Result<Outcome, Error> {
    let resolved = Resolved::new(source, options);
    let settings = resolved.settings(options)?;
    Compiled::from_resolved(resolved, &settings)?.run(&settings, progress)
}

/// [`simulate_with`], handing the rows to `sink` as they are made rather than keeping them:
/// the outcome's trajectory is empty, and its summary the same. An animation's figures need
/// every row: with `animate` the rows are kept, and handed to `sink` after the run.
pub fn simulate_into(
    source: &str,
    options: &Options,
    progress: &mut dyn Progress,
    sink: &mut dyn Sink,
) -> Result<Outcome, Error> {
    let settings = settings(source, options)?;
    Compiled::new(source, &settings)?.run_into(&settings, progress, sink)
}

/// Loads `source` with the settings' outputs, stops, events and `--set` values resolved as
/// its expressions, and integrates it. A run that faults is an [`Outcome`] with its fault, and
/// what was computed before it.
pub fn run(
    source: &str,
    settings: &Settings,
    progress: &mut dyn Progress,
) -> Result<Outcome, Error> {
    Compiled::new(source, settings)?.run(settings, progress)
}

/// Where a run's quantities sit among the observed columns: the outputs, the stops, the
/// events, KE and PE, then the figures of an animation and the constraints' residuals.
pub struct Columns {
    pub outputs: usize,
    pub stops: usize,
    pub events: usize,
}

impl Columns {
    /// The column of KE; PE follows it.
    pub fn energies(&self) -> usize {
        self.outputs + self.stops + self.events
    }

    /// The first column after the energies.
    pub fn figures(&self) -> usize {
        self.energies() + 2
    }
}

/// A scene loaded for runs.
pub struct Loaded {
    /// With the run's expressions resolved in its scope, in [`Columns`] order, and the inputs
    /// driven continuously replaced by their laws.
    pub prepared: Prepared,
    /// The outputs' names: the remaining coordinates when the settings name none.
    pub outputs: Vec<String>,
    /// The laws of the inputs held between samples, each with its input.
    pub held: Vec<(cas::SymId, cas::ExprId)>,
    /// An input driven continuously is in the Lagrangian.
    pub lagrangian_driven: bool,
}

/// The scene loaded with the settings' expressions and laws (see [`Loaded`]).
pub fn load(source: &str, settings: &Settings) -> Result<Loaded, Error> {
    // An input in a constraint takes its law (or value) before anything is derived.
    let checks = model::Checks { units: settings.units, inputs_in_constraints: true };
    let (model, warnings) = engine::resolve_checked(source, checks)?;
    load_model(source, model, warnings, settings)
}

/// [`load`] of a scene already resolved as a run takes it.
fn load_model(
    source: &str,
    mut model: model::Model,
    warnings: Vec<Diagnostic>,
    settings: &Settings,
) -> Result<Loaded, Error> {
    let mut outputs = settings.outputs.clone();
    let mut extra: Vec<String> = Vec::new();
    extra.extend(outputs.iter().cloned());
    extra.extend(settings.stops.iter().cloned());
    extra.extend(settings.events.iter().cloned());
    extra.push("KE".into());
    extra.push("PE".into());
    let laws = drive::laws(&mut model, &settings.drives)?;
    drive::into_constraints(source, &mut model, &laws, settings)?;
    let mut prepared = prepare_resolved(source, model, warnings, &extra)?;
    let stops = outputs.len()..outputs.len() + settings.stops.len();
    let stop_exprs = prepared.extra[stops].to_vec();
    for (text, &stop) in settings.stops.iter().zip(&stop_exprs) {
        refuse_constant_stop(&mut prepared, text, stop)?;
    }
    // Held laws keep their inputs' slots; the others take their inputs' places.
    let (held, lagrangian_driven) = if settings.hold.is_some() {
        (laws, false)
    } else {
        prepared.drive(&laws);
        drive::check_method(&mut prepared, &laws, settings.method)?;
        (Vec::new(), drive::in_lagrangian(&mut prepared, &laws).is_some())
    };
    if outputs.is_empty() {
        // Default outputs: every remaining coordinate.
        outputs = prepared.coordinate_names();
        let coords = prepared.derivation.coords.clone();
        let pool = &mut prepared.derivation.model.pool;
        let exprs: Vec<cas::ExprId> = coords.iter().map(|q| pool.sym(*q)).collect();
        prepared.extra.splice(0..0, exprs);
    }
    Ok(Loaded { prepared, outputs, held, lagrangian_driven })
}

/// Refuses a stop condition that names nothing a run changes (`--stop-when 0`, `x = x`): it
/// is one value throughout, so it either stops the run at once or never, whatever the scene
/// does, which is not what anyone writing it meant.
fn refuse_constant_stop(
    prepared: &mut Prepared,
    text: &str,
    stop: cas::ExprId,
) -> Result<(), Error> {
    let d = &prepared.derivation;
    let mut changing: Vec<cas::SymId> = vec![d.model.time];
    changing.extend(d.coords.iter().chain(&d.rates).chain(&d.accels));
    changing.extend(d.multipliers.iter().map(|m| m.lambda));
    changing.extend(d.model.inputs.iter().map(|u| u.sym));
    let pool = &mut prepared.derivation.model.pool;
    let simplified = pool.simplify(stop);
    if pool.free_symbols(simplified).iter().any(|s| changing.contains(s)) {
        return Ok(());
    }
    Err(bad(format!(
        "the stop condition `{text}` names nothing that changes during a run (no coordinate, \
         rate, input or t), so it would stop the run at once or never: name what should \
         reach zero, such as `theta = pi/2`"
    )))
}

/// The `--set` values resolved as expressions of the derived scene's parameters: after the
/// derivation, so that a scene derived once runs with value after value.
pub fn set_expressions(
    prepared: &mut Prepared,
    sets: &[Assignment],
) -> Result<Vec<cas::ExprId>, Error> {
    let mut exprs = Vec::with_capacity(sets.len());
    for set in sets {
        let text = &set.value;
        // A plain number is its exact value: no scope to look in, no dimensions to infer
        // again (which a batch of thousands of runs would pay for each).
        let (sign, digits) = match text.trim().strip_prefix('-') {
            Some(rest) => (-1, rest),
            None => (1, text.trim()),
        };
        if let Some(q) = cas::number::parse_decimal(digits) {
            exprs.push(prepared.derivation.model.pool.num(q * cas::number::int(sign)));
            continue;
        }
        let value = prepared
            .derivation
            .model
            .resolve_value_for(&set.name, text)
            .map_err(|diagnostics| Error::Expression { diagnostics, text: text.clone() })?;
        let model::Value::Scalar(e) = value else {
            return Err(Error::Input(format!(
                "`{text}` is {}, and only scalars can be recorded",
                value.kind_name()
            )));
        };
        exprs.push(prepared.derivation.expand_quantities(e, false));
    }
    Ok(exprs)
}

/// The `--set` values in place of the scene's: parameters by their index, and coordinates by
/// theirs with whether the rate is set.
pub struct Overrides {
    pub params: Vec<(usize, cas::ExprId)>,
    pub coords: Vec<(usize, bool, cas::ExprId)>,
}

/// Which parameter or coordinate each `--set` value replaces, or why it replaces none.
pub fn overrides(
    prepared: &Prepared,
    sets: &[Assignment],
    exprs: &[cas::ExprId],
) -> Result<Overrides, Error> {
    let model = &prepared.derivation.model;
    let coordinate_names = prepared.coordinate_names();
    let mut found = Overrides { params: Vec::new(), coords: Vec::new() };
    for (set, expr) in sets.iter().zip(exprs) {
        let (name, (base, primes)) = (&set.name, set.base());
        if let Some(i) = model.params.iter().position(|p| p.name == base && primes == 0) {
            found.params.push((i, *expr));
        } else if let Some(i) = model.coords.iter().position(|c| c.name == base && primes <= 1) {
            if !prepared.derivation.coords.contains(&model.coords[i].sym) {
                return Err(Error::given(
                    Setting::Set,
                    name,
                    format!(
                        ": `{base}` is fixed by a constraint; set the remaining coordinates ({}) \
                         instead",
                        coordinate_names.join(", ")
                    ),
                ));
            }
            found.coords.push((i, primes == 1, *expr));
        } else {
            let mut known: Vec<String> = model.params.iter().map(|p| p.name.clone()).collect();
            for c in &coordinate_names {
                known.push(c.clone());
                known.push(format!("{c}'"));
            }
            return Err(Error::given(
                Setting::Set,
                name,
                format!(": no parameter or coordinate of that name; one of {}", known.join(", ")),
            ));
        }
    }
    Ok(found)
}

/// The parameters' values and the initial state, with the `--set` values and the `given`
/// parameters' numbers (by index) in place and the start settled again on the kept
/// constraints where they moved it.
pub fn start(
    prepared: &mut Prepared,
    values: &Overrides,
    given: &[(usize, f64)],
) -> Result<(Vec<f64>, Vec<f64>), Error> {
    let parameters = prepared.parameter_values_given(&values.params, given)?;
    if !values.params.is_empty() || !given.is_empty() {
        // The scene's masses were checked with its own values; `--set` may change their sign.
        prepared.masses_at(&parameters)?;
    }
    let mut y0 = prepared.initial_state(&parameters, &values.coords)?;
    let set_in = |prepared: &Prepared, rates: bool| -> Vec<bool> {
        prepared
            .derivation
            .coords
            .iter()
            .map(|q| {
                let i = prepared.derivation.model.coords.iter().position(|c| c.sym == *q);
                values.coords.iter().any(|(j, rate, _)| Some(*j) == i && *rate == rates)
            })
            .collect()
    };
    let (set_positions, set_rates) = (set_in(prepared, false), set_in(prepared, true));
    // The scene's own start was settled when it was derived; `--set` values may break it.
    if !values.params.is_empty() || !values.coords.is_empty() || !given.is_empty() {
        prepared.settle_positions(&mut y0, &parameters, &set_positions)?;
        prepared.settle_rates(&mut y0, &parameters, &set_rates)?;
    }
    if let Some(bad_slot) = y0.iter().position(|v| !v.is_finite()) {
        return Err(bad(format!(
            "the initial value of `{}` is not a finite number",
            prepared.state_names()[bad_slot]
        )));
    }
    Ok((parameters, y0))
}

/// Integrates the lowered scene from `y0` with the settings' method, watching the stops and
/// events; the run and its wall time.
fn integrate_scene(
    prepared: &mut Prepared,
    mechanical: Mechanical,
    y0: &[f64],
    settings: &Settings,
    columns: &Columns,
    progress: &mut dyn Progress,
    rows: Option<&mut dyn sim::Rows>,
) -> Result<(Run, f64, Option<FastestMode>), Error> {
    let Settings { until, method, step, .. } = *settings;
    let mut run_settings = integrand::run_settings(settings, settings.samples);
    let most = most_rows(sim::Problem::observations(&mechanical));
    if settings.samples > most {
        return Err(Error::given(
            Setting::Samples,
            settings.samples.to_string(),
            format!(
                " would record more than {} GiB of rows; this run records at most {most}",
                MAX_RECORDED_BYTES >> 30
            ),
        ));
    }
    if settings.samples == 0 {
        // A row per step: the steps' cap keeps the rows within the memory allowed.
        run_settings.max_steps = run_settings.max_steps.min(most);
    }
    let watched = integrand::watched(columns);
    progress.start(until);
    let started = Instant::now();
    let mut fastest_mode = None;
    let run = {
        let mut update = |t: f64| {
            progress.update(t);
            if progress.interrupted() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        if method.jacobian() == sim::Jacobian::OnSwitch {
            // Not through `Integrand::new`: the contacts are given here.
            let mechanical = integrand::with_contacts(prepared, mechanical, method)?;
            let mut lazy = on_demand::OnDemand::new(mechanical, prepared);
            match rows {
                Some(rows) => {
                    sim::integrate_into(&mut lazy, y0, &run_settings, &watched, &mut update, rows)
                }
                None => integrate(&mut lazy, y0, &run_settings, &watched, &mut update),
            }
        } else {
            let mut integrand = Integrand::new(prepared, mechanical, method)?;
            let run = integrand.integrate_to(y0, &run_settings, &watched, &mut update, rows);
            if let Integrand::Mechanical(m) = &mut integrand {
                fastest_mode = fault::fastest_mode(m, prepared, (method, step), y0, &run);
            }
            run
        }
    };
    progress.finish();
    Ok((run, started.elapsed().as_secs_f64(), fastest_mode))
}

/// The most memory the rows a run records may take. Past it, a count of samples is refused
/// before the run, and a run recording every step ends in a fault naming `samples`, rather
/// than the process aborting when an allocation fails.
pub const MAX_RECORDED_BYTES: usize = 1 << 30;

/// The most rows of `observations` quantities a run records within [`MAX_RECORDED_BYTES`]: a
/// row is its numbers and the time, and a vector's header and the allocator's bookkeeping.
pub fn most_rows(observations: usize) -> usize {
    let row = 8 * (observations + 1) + 40;
    MAX_RECORDED_BYTES / row
}

/// The problem in (q, q̇) with the partials its exact Jacobian is made of, lowered only for
/// the methods that use one, so explicit runs lower nothing more.
pub(crate) fn with_partials(
    prepared: &mut Prepared,
    method: Method,
    mechanical: Mechanical,
) -> Result<Mechanical, Error> {
    if !method.uses_jacobian() {
        return Ok(mechanical);
    }
    Ok(mechanical.with_partials(on_demand::lower_partials(prepared)?))
}

/// Bodies in space oriented by angles (not Euler parameters).
pub fn angle_oriented_bodies(model: &model::Model) -> Vec<String> {
    let by_angles = |b: &&model::Body| {
        matches!(b.rotation, Some(model::Rotation::Spatial { euler_parameters: None, .. }))
    };
    model.bodies.iter().filter(by_angles).map(|b| b.name.clone()).collect()
}

/// Whether T + V should stay at its start value. It does not when loads act that no potential
/// accounts for, or when anything depends on time: T + V is then not a first integral even
/// where the equations do not mention t (a bead on a rod turned at a fixed rate has r̈ = ω²·r,
/// yet the motor feeds it energy). Time enters through the equations, a position or
/// orientation given in t, a coordinate eliminated by a constraint in t (a drive), a potential
/// or Lagrangian term in t, or a kept velocity constraint that moves the scene at rest.
fn conserves_energy(d: &mut mechanics::Derivation, dynamics: &[cas::ExprId]) -> bool {
    let model = &d.model;
    if !(model.forces.is_empty() && model.torques.is_empty() && model.dissipation.is_empty()) {
        return false;
    }
    // Coulomb friction takes energy out while a contact slips.
    if model.contacts.iter().any(|c| c.friction.is_some()) {
        return false;
    }
    let mut timed: Vec<cas::ExprId> = dynamics.to_vec();
    for body in &model.bodies {
        timed.extend(&body.position);
        match &body.rotation {
            Some(model::Rotation::Planar { angle, .. }) => timed.push(*angle),
            Some(model::Rotation::Spatial { orientation, .. }) => {
                timed.extend(orientation.iter().flatten())
            }
            None => {}
        }
    }
    timed.extend(d.eliminated.iter().map(|e| e.solution));
    timed.extend(model.potentials.iter().chain(&model.lagrangians).map(|term| term.expr));
    timed.push(d.potential);
    timed.push(d.lagrangian);
    let t = model.time;
    let pool = &mut d.model.pool;
    if timed.iter().any(|e| pool.depends_on(*e, t)) {
        return false;
    }
    !d.drives_through_velocity_constraints()
}

impl Outcome {
    /// A contact's name, by its index in the run's mode events.
    pub fn contact_name(&self, k: usize) -> String {
        self.contact_names.get(k).cloned().unwrap_or_else(|| format!("contact {k}"))
    }

    /// The total energy at each recorded time, of a run that kept its rows.
    pub fn energy(&self) -> Vec<f64> {
        let (k, p) = self.energy_columns;
        self.run.trajectory.rows.iter().map(|r| r[k] + r[p]).collect()
    }

    /// The largest |E(t) − E(0)|, and that relative to the energy scale.
    pub fn energy_drift(&self) -> (f64, f64) {
        self.totals.energy_drift()
    }

    /// The largest residual of a kept constraint over the recorded rows, where one is kept.
    pub fn constraint_drift(&self) -> Option<f64> {
        (!self.constraint_columns.is_empty()).then(|| self.totals.constraint_drift())
    }

    /// The largest |Φ| at the integrator's own steps, leaving out the samples interpolated
    /// between them: radau holds the constraints at its steps to Newton's tolerance, while its
    /// collocation polynomial between them keeps them only to its own accuracy.
    pub fn constraint_drift_at_steps(&self) -> Option<f64> {
        if self.constraint_columns.is_empty() {
            return None;
        }
        let peaks = &self.run.peaks;
        Some(
            self.constraint_columns
                .iter()
                .filter_map(|&c| peaks.get(c))
                .fold(0.0, |m, v| m.max(*v)),
        )
    }

    pub fn describe_fault(&self, f: &sim::Fault) -> String {
        let state: Vec<String> =
            self.state_names.iter().zip(&f.state).map(|(n, v)| format!("{n} = {v}")).collect();
        let names = FaultNames {
            method: self.method,
            state: &self.state_names,
            constraints: &self.constraint_names,
            parameters: &self.parameter_names,
            angle_oriented_bodies: &self.angle_oriented_bodies,
            contacts: &self.contact_names,
        };
        let (what, cause) = names.words(&f.kind);
        let cause = match &self.fastest_mode {
            Some(mode) => fault::stiffness_cause(mode, self.method, &self.state_names),
            None => cause,
        };
        format!(
            "numeric fault at t = {}: {what}\n  state: {}\n  likely cause: {cause}",
            f.time,
            state.join(", ")
        )
    }
}

/// What a fault's words name: the method, the state's and the kept constraints' names, and
/// the bodies oriented by angles.
pub struct FaultNames<'a> {
    pub method: Method,
    pub state: &'a [String],
    pub constraints: &'a [String],
    pub parameters: &'a [String],
    pub angle_oriented_bodies: &'a [String],
    /// The contacts, in the order written.
    pub contacts: &'a [String],
}

impl FaultNames<'_> {
    /// A fault of a run as a command that runs the scene many times reports it: when, in
    /// which run (`during`, "a return"), what went wrong, the state and the likely cause.
    pub fn report(&self, fault: &sim::Fault, during: &str) -> String {
        let (what, cause) = self.words(&fault.kind);
        let state: Vec<String> =
            self.state.iter().zip(&fault.state).map(|(n, v)| format!("{n} = {v}")).collect();
        format!(
            "numeric fault at t = {} of {during}: {what}\n  state: {}\n  likely cause: {cause}",
            fault.time,
            state.join(", ")
        )
    }

    /// Contacts by index, in words: "`floor`, `wall`".
    fn contacts(&self, indices: &[usize]) -> String {
        let named: Vec<String> = indices
            .iter()
            .map(|&k| self.contacts.get(k).map_or(format!("contact {k}"), |n| format!("`{n}`")))
            .collect();
        named.join(", ")
    }

    /// The value that came out NaN or infinite, in words.
    fn non_finite(&self, at: &NonFiniteAt) -> String {
        let coordinate =
            |i: usize| self.state.get(i).map_or(format!("coordinate {i}"), |s| format!("`{s}`"));
        match *at {
            NonFiniteAt::Mass { row, column } => {
                format!("the mass matrix's entry ({}, {})", coordinate(row), coordinate(column))
            }
            NonFiniteAt::Force { coordinate: c } => {
                format!("the force side f of {}'s equation (M·q̈ = f)", coordinate(c))
            }
            NonFiniteAt::Momentum { coordinate: c } => {
                format!("the momentum conjugate to {}", coordinate(c))
            }
            NonFiniteAt::Constraint { constraint } => format!(
                "the kept constraint {}'s Jacobian or drift",
                self.constraints
                    .get(constraint)
                    .map_or(format!("{constraint}"), |s| format!("`{s}`"))
            ),
            NonFiniteAt::Rate { component } => match self.state.get(component) {
                Some(name) => format!("the rate `{name}'`"),
                None => format!("the rate of state component {component}"),
            },
            NonFiniteAt::MomentumRate { coordinate: c } => {
                format!("the rate of the momentum conjugate to {}", coordinate(c))
            }
            NonFiniteAt::Residual { coordinate: c } => {
                format!("the residual of {}'s equation", coordinate(c))
            }
            NonFiniteAt::HeldLaw { slot } => format!(
                "the held law of {}",
                self.parameters.get(slot).map_or("an input".into(), |s| format!("`{s}`"))
            ),
            NonFiniteAt::Partials => "a partial derivative of the equations".into(),
            NonFiniteAt::Jacobian => "the Jacobian of the equations".into(),
            NonFiniteAt::System => "the matrix the accelerations are solved with".into(),
        }
    }

    /// What went wrong, and its likely cause.
    pub fn words(&self, kind: &FaultKind) -> (String, String) {
        let coords = |idx: &[usize]| -> String {
            idx.iter()
                .filter_map(|i| self.state.get(*i))
                .map(|s| format!("`{s}`"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match kind {
            FaultKind::SingularMass { coordinates, condition }
                if !self.angle_oriented_bodies.is_empty() =>
            {
                let bodies: Vec<String> =
                    self.angle_oriented_bodies.iter().map(|b| format!("`{b}`")).collect();
                (
                    format!(
                        "the orientation angles are singular here: the mass matrix loses rank \
                         (condition ≈ {condition:.1e}) along {}",
                        if coordinates.is_empty() {
                            "some coordinate".into()
                        } else {
                            coords(coordinates)
                        }
                    ),
                    format!(
                        "the angle set orienting {} has a singular configuration here (as θ = 0 \
                         is for 3-1-3 Euler angles); start away from it, choose angles regular \
                         here, or orient by quaternion(e0, e1, e2, e3)",
                        bodies.join(", ")
                    ),
                )
            }
            FaultKind::SingularMass { coordinates, condition } => (
                format!(
                    "the mass matrix is singular or ill-conditioned (condition ≈ {condition:.1e})"
                ),
                format!(
                    "the inertia along {} vanishes here (a degenerate configuration, or a \
                     coordinate that stops moving any mass)",
                    if coordinates.is_empty() {
                        "some coordinate".into()
                    } else {
                        coords(coordinates)
                    }
                ),
            ),
            FaultKind::SingularConstraints { constraints } => {
                let names: Vec<String> = constraints
                    .iter()
                    .filter_map(|i| self.constraints.get(*i))
                    .map(|s| format!("`{s}`"))
                    .collect();
                (
                    "the constraints' Jacobian lost rank (the mass matrix is fine)".to_string(),
                    if names.len() == 1 && constraints == &[0] {
                        format!(
                            "the gradient of {} vanishes here: a cusp of the constraint, or a \
                             constraint written as a square",
                            names[0]
                        )
                    } else if names.is_empty() {
                        "the constraints' gradients became dependent here: a dead point of the \
                         mechanism, or constraints that coincide here"
                            .to_string()
                    } else {
                        format!(
                            "the gradient of {} became a combination of the earlier constraints' \
                             here: a dead point of the mechanism, or constraints that coincide here",
                            names.join(", ")
                        )
                    },
                )
            }
            FaultKind::NonFinite { at: NonFiniteAt::HeldLaw { slot } } => {
                let input =
                    self.parameters.get(*slot).map_or("an input".into(), |s| format!("`{s}`"));
                (
                    format!("the held law driving {input} gave NaN or infinity"),
                    format!(
                        "the law of {input} is undefined at the state sampled (a division by \
                         zero or a function outside its domain), or the motion blew up"
                    ),
                )
            }
            FaultKind::NonFinite { at } => (
                format!("{} became NaN or infinite", self.non_finite(at)),
                "a division by zero or a function outside its domain; or the motion blew up".into(),
            ),
            FaultKind::RatesOverflow { component, rate } => (
                format!(
                    "the rate of {} is {rate:.1e}: too large for the step control to weigh \
                     against the tolerance",
                    self.state.get(*component).map_or("the state".into(), |s| format!("`{s}`"))
                ),
                "a force or an input beyond floating point's range (an exponential of a large \
                 argument?), or units far from the scene's scale"
                    .into(),
            ),
            FaultKind::StepTooSmall { step } => (
                format!("the step size fell to {step:.1e}"),
                "a singularity ahead (the solution blows up) or a very stiff system".into(),
            ),
            FaultKind::NewtonFailed { step, contraction, exact_jacobian } => {
                fault::newton_failed(self.method, *step, *contraction, *exact_jacobian)
            }
            FaultKind::NewtonStalled { step, contraction, singular, exact_jacobian } => {
                fault::newton_stalled(*step, *contraction, *singular, *exact_jacobian)
            }
            FaultKind::TooManySteps { limit } if *limit < integrand::MAX_STEPS => (
                format!("more than {limit} steps, each recorded"),
                format!(
                    "a row a step would take more than {} GiB: give `samples` to record evenly \
                     spaced times instead (the run may then take {} steps)",
                    MAX_RECORDED_BYTES >> 30,
                    integrand::MAX_STEPS
                ),
            ),
            FaultKind::TooManySteps { limit } => (
                format!("more than {limit} steps"),
                "the tolerance is too tight or the step too small for the time span".into(),
            ),
            FaultKind::ModesChatter { guards, jumps } => (
                format!("{} switched {jumps} times at the same instant", self.contacts(guards)),
                "a contact at the edge of opening and closing (a reaction that stays at zero): \
                 a smaller tolerance, or a scene that decides it"
                    .into(),
            ),
            FaultKind::Penetrating { contact, gap } => (
                format!("{} starts penetrating (its gap is {gap:.3e})", self.contacts(&[*contact])),
                "start with every contact's gap ≥ 0".into(),
            ),
            FaultKind::ContactsUnsolved { contacts, impact, why } => (
                format!(
                    "the {} of {} could not be solved: {why}",
                    if *impact { "impact" } else { "reactions" },
                    self.contacts(contacts)
                ),
                "a smaller tolerance, or fewer contacts touching at once".into(),
            ),
            FaultKind::Painleve { contacts, case, impact } => {
                let at = if *impact { "impact" } else { "forces" };
                let what = match case {
                    sim::PainleveCase::Inconsistent => format!(
                        "Painlevé's inconsistent case: no {at} of {} obey Coulomb's law and \
                         the contacts' (friction presses them in harder than any force can \
                         hold them out)",
                        self.contacts(contacts)
                    ),
                    sim::PainleveCase::Indeterminate => format!(
                        "Painlevé's indeterminate case: the {at} of {} have several solutions \
                         that move differently (it may lift off or slip pressed on)",
                        self.contacts(contacts)
                    ),
                    sim::PainleveCase::Jam => format!(
                        "Painlevé's jam: the normal force of {} grows without bound while it \
                         slips (its coefficient w·M⁻¹·(w − μ·s·t) reached zero)",
                        self.contacts(contacts)
                    ),
                };
                (
                    what,
                    "rigid bodies with Coulomb friction have no motion here: a smaller \
                     coefficient of friction, or a compliant contact, decides it"
                        .into(),
                )
            }
            FaultKind::ContactsInconsistent { contacts, impact } => (
                format!(
                    "the {} of {} has no solution",
                    if *impact { "impact" } else { "reactions" },
                    self.contacts(contacts)
                ),
                "the contacts' gradients conflict with each other or with the two-sided \
                 constraints here"
                    .into(),
            ),
        }
    }
}
