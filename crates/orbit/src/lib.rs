//! Periodic orbits of a scene: what `lagrange orbit` finds and judges. This crate owns the
//! return map (over a fixed period, to a section where an expression crosses zero, or to a
//! contact's landing), the symmetry a return is mapped by before it is compared with its start
//! ([`Symmetry`]), Newton's method on the map in the chart of its section, and the Floquet
//! multipliers and the verdict at the fixed point, as an [`Orbit`] a front end renders.
//! Newton is inexact: each run's tolerance is matched to the residual its step should leave
//! (`Accuracy`), and only a run at the tolerance asked for ends a search.
//!
//! The map's Jacobian is the variational run's (`sim::variational`): the state transition
//! matrix integrated on the run's own steps from the exact Jacobian, carried across the jumps
//! by their saltation matrices, and ended with the section's event time varied with the start.
//! Newton and the multipliers work in the chart of the section within the manifold the kept
//! constraints hold the state on ([`chart::section`]): the directions across it (the flow's
//! own, and those Baumgarte's terms decide) are the trivial multipliers, left out. A scene is
//! loaded once for many searches ([`Search`]), and [`sweep`] continues an orbit in a
//! parameter and locates where a multiplier crosses the unit circle.
//! It loads the scene as `simulation` does for a run, and prints nothing.

pub mod chart;
mod map;
pub mod sweep;

use nalgebra::{Complex, DMatrix, DVector};
use numeric::Tape;
use sim::variational::{self, End, Guard, Refusal};
use sim::{Mechanical, Watched};

use engine::input::Assignment;
use engine::Error;
pub use map::Symmetry;

/// Where the return map ends.
#[derive(Clone, Debug, PartialEq)]
pub enum Section {
    /// A fixed period, an expression of the parameters in seconds (a driven scene's).
    Period(String),
    /// Where an expression of the state crosses zero (`lhs = rhs`: their difference) in the
    /// direction given.
    Crossing { expression: String, rising: bool },
    /// Just after a contact lands (any contact's landing with `None`).
    Landing { contact: Option<String> },
}

impl Section {
    /// The section in words, as a report heads itself with.
    pub fn words(&self) -> String {
        match self {
            Section::Period(text) => format!("period {text}"),
            Section::Crossing { expression, rising } => {
                format!("section {expression}, {}", if *rising { "rising" } else { "falling" })
            }
            Section::Landing { contact: None } => "section impact".into(),
            Section::Landing { contact: Some(name) } => format!("section impact:{name}"),
        }
    }

    /// `impact`, `impact:NAME`, or an expression (`lhs = rhs` allowed) crossing zero.
    pub fn parse(text: &str, rising: bool) -> Section {
        let text = text.trim();
        if text == "impact" {
            return Section::Landing { contact: None };
        }
        if let Some(name) = text.strip_prefix("impact:") {
            return Section::Landing { contact: Some(name.trim().to_string()) };
        }
        let expression = match text.split_once('=') {
            Some((l, r)) => format!("({}) - ({})", l.trim(), r.trim()),
            None => text.to_string(),
        };
        Section::Crossing { expression, rising }
    }
}

/// What `orbit` is asked.
#[derive(Clone, Debug)]
pub struct Options {
    /// The run's settings as `simulate` takes them: `until` is the longest a return may take.
    pub run: simulation::Options,
    pub section: Section,
    pub swaps: Vec<Assignment>,
    pub shifts: Vec<Assignment>,
    /// Coordinates left out of the comparison (cyclic ones, whose value a return need not
    /// repeat: with them in, the orbit would be one of a family, with a multiplier at 1).
    pub ignore: Vec<String>,
    /// The most Newton iterations.
    pub iterations: usize,
}

/// One Newton iteration: the residual in the chart before its step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iteration {
    pub residual: f64,
    pub steps: usize,
    /// The tolerance its run was integrated at: matched to Newton's residual, loose far from
    /// the orbit.
    pub tolerance: f64,
}

/// A periodic orbit found, judged by its multipliers.
#[derive(Clone, Debug)]
pub struct Orbit {
    pub state_names: Vec<String>,
    /// The fixed point of the map (q, q̇), on the section.
    pub fixed_point: Vec<f64>,
    /// The time the map takes there.
    pub period: f64,
    /// The eigenvalues of the map's Jacobian in the chart, largest modulus first.
    pub multipliers: Vec<Complex<f64>>,
    /// The map's Jacobian on the whole state (row-major), the symmetry applied.
    pub monodromy: Vec<f64>,
    /// How many directions the chart leaves out (the flow's and the constraints' normals),
    /// whose multipliers are trivial.
    pub trivial: usize,
    pub jumps: usize,
    pub iterations: Vec<Iteration>,
    /// Where the last iteration's step was taken without a run to check it (its residual
    /// already small enough that Newton's quadratic rate, measured on the iterations before,
    /// leaves nothing after it): the residual it is expected to leave. The fixed point is then
    /// that step's end, and the multipliers, the monodromy and the period are the last run's,
    /// a step away at most the run's tolerance in relative terms.
    pub last_step: Option<f64>,
    /// Whether every multiplier lies inside the unit circle (the verdict is `Stable`).
    pub stable: bool,
    pub verdict: Verdict,
}

/// What the multipliers say of an orbit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Every multiplier inside the unit circle: nearby motions come back to the orbit.
    Stable,
    /// None outside, but one on the unit circle to the accuracy the multipliers have: a
    /// family of orbits (a conservative scene's, one per energy), or the edge of stability,
    /// which the map's linear part cannot decide.
    Neutral,
    /// A multiplier outside the unit circle.
    Unstable,
}

impl Verdict {
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Stable => "stable",
            Verdict::Neutral => "neutral",
            Verdict::Unstable => "unstable",
        }
    }
}

/// How far from the unit circle a multiplier counts as on it: far above the multipliers'
/// error (the integration's, and the differences of a guard that is not a gap: about 1e-9),
/// far below any stability worth the name.
const NEUTRAL: f64 = 1e-6;

impl Orbit {
    /// The largest |μ|.
    pub fn spectral_radius(&self) -> f64 {
        self.multipliers.first().map_or(0.0, |m| m.norm())
    }

    /// det of the map's Jacobian on the whole state: for a fixed period, exp of the integral
    /// of the divergence (Liouville).
    pub fn determinant(&self) -> f64 {
        let size = self.fixed_point.len();
        nalgebra::DMatrix::from_row_slice(size, size, &self.monodromy).determinant()
    }
}

/// The residual, relative to the state's size, below which Newton has converged: the map is
/// computed to the rounding of its steps and event times, not to the integration's tolerance.
const CONVERGED: f64 = 1e-14;
/// Below this residual (relative), a step that no longer divides it by ten has met the map's
/// rounding: the iteration ends there too.
const STAGNANT: f64 = 1e-9;
/// The loosest tolerance a Newton run is integrated at, far from the orbit.
const LOOSEST: f64 = 1e-6;
/// A run's tolerance against the residual its step is expected to leave: the map's error at
/// that tolerance (the run's global error, some tens of tolerances) a small part of it.
const MATCHED: f64 = 1e-3;
/// How many tolerances the last step may change the map's Jacobian by (K·r, relative) and
/// still be taken unchecked: a run at a tolerance carries its own error of several
/// tolerances in the multipliers (1.5 to 5 measured at 10⁻¹⁰ on the wheel, the pendulum and
/// the walker), and a run to check a change of that order buys less than a digit of them.
const UNCHECKED_CHANGE: f64 = 10.0;

/// How accurately each Newton run is integrated: an inexact Newton's method. A step from a
/// residual r leaves about K·r² (Newton's quadratic rate K) plus the map's own error, so a
/// run far from the orbit needs the map no more accurately than that: its tolerance is
/// matched to the residual its step is expected to leave, between the loosest and the one
/// asked for, and never loosened again. Only a run at the tolerance asked for may end the
/// search, so the fixed point, the period and the multipliers are those the tolerance gives.
#[derive(Clone, Copy, Debug)]
struct Accuracy {
    /// The tolerance asked for.
    target: f64,
    /// The first run's.
    loosest: f64,
}

/// A Newton run as [`Accuracy`] reads it: its residual relative to the state's size, and its
/// tolerance.
#[derive(Clone, Copy, Debug)]
struct Run {
    residual: f64,
    tolerance: f64,
}

/// What a run's residual says of the search.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Finish {
    Continue,
    /// The residual is the map's rounding: the run's start is the fixed point.
    Converged,
    /// The step from this run is expected to leave this residual (relative), below
    /// [`CONVERGED`], and changes the map's Jacobian by less than [`UNCHECKED_CHANGE`]
    /// tolerances: take it and end.
    LastStep(f64),
}

impl Accuracy {
    fn of(target: f64, far: bool) -> Accuracy {
        Accuracy { target, loosest: if far { LOOSEST.max(target) } else { target } }
    }

    /// Newton's quadratic rate K (r₂ ≈ K·r₁²) from two runs in a row; 1 without them.
    fn rate(before: &Run, after: &Run) -> f64 {
        if before.residual > 0.0 {
            after.residual / (before.residual * before.residual)
        } else {
            1.0
        }
    }

    /// The tolerance of the next run, after `runs`.
    fn next(&self, runs: &[Run]) -> f64 {
        let Some(last) = runs.last() else { return self.loosest };
        let rate = match runs {
            [.., a, b] => Accuracy::rate(a, b),
            _ => 1.0,
        };
        // What the next run should see, and what its step should leave; never more than the
        // residual before (a rate measured on a map's error rather than on Newton's steps).
        let coming = (rate * last.residual * last.residual).min(last.residual);
        let after = (rate * coming * coming).min(coming);
        (MATCHED * after).clamp(self.target, last.tolerance)
    }

    /// Whether the search ends at `this` run, after `runs`.
    fn finish(&self, runs: &[Run], this: Run) -> Finish {
        if this.tolerance > self.target {
            return Finish::Continue;
        }
        if this.residual <= CONVERGED {
            return Finish::Converged;
        }
        let Some(previous) = runs.last() else { return Finish::Continue };
        let at_target = previous.tolerance <= self.target;
        if at_target && this.residual <= STAGNANT && this.residual > previous.residual / 10.0 {
            return Finish::Converged;
        }
        // The rate from a looser run before is, if anything, too large (its residual the
        // looser map's): the expectation errs towards another run.
        let rate = Accuracy::rate(previous, &this);
        let expected = rate * this.residual * this.residual;
        if expected <= CONVERGED && rate * this.residual <= UNCHECKED_CHANGE * self.target {
            return Finish::LastStep(expected);
        }
        Finish::Continue
    }
}

/// The scene loaded and lowered for variational runs, its start and its map.
struct Loaded {
    mechanical: Mechanical,
    start: Vec<f64>,
    end: End,
    until: f64,
    symmetry: Symmetry,
    run: sim::Settings,
    /// For a sweep's map, where the parameter swept is carried exactly: the period's
    /// derivative by it (the mechanical problem has its sensitivity program).
    swept: Option<f64>,
    state_names: Vec<String>,
    contact_names: Vec<String>,
    /// What a fault's words name besides the state and the contacts.
    constraint_names: Vec<String>,
    parameter_names: Vec<String>,
    angle_oriented_bodies: Vec<String>,
}

fn load(source: &str, options: &Options) -> Result<Loaded, Error> {
    load_for(source, options, None)
}

/// [`load`], with the sensitivities by the parameter `swept` lowered too where the map is one
/// whose derivative by it S gives: a fixed period's, without contacts (S is not carried
/// across a jump), series-driven inputs or shifts (whose share in the parameter S leaves out).
fn load_for(source: &str, options: &Options, swept: Option<&str>) -> Result<Loaded, Error> {
    let mut run_options = options.run.clone();
    if let Section::Crossing { expression, .. } = &options.section {
        run_options.events.push(expression.clone());
    }
    let resolved = simulation::Resolved::new(source, &run_options);
    let mut settings = resolved.settings(&run_options)?;
    if settings.hold.is_some() {
        return Err(Error::Input(
            "orbit takes inputs driven continuously, not held between samples (`hold`)".into(),
        ));
    }
    let method = settings.method;
    if !method.is_explicit() || method.is_symplectic() {
        return Err(Error::Input(format!(
            "orbit integrates the sensitivities on an explicit method's steps; {} is not one \
             (use dop853, the default, or another of the explicit methods)",
            method.name()
        )));
    }
    // The section's expression is the one event watched.
    settings.events = run_options.events.clone();
    let simulation::Loaded { mut prepared, outputs, .. } = resolved.load(&settings)?;
    let set_exprs = simulation::set_expressions(&mut prepared, &settings.sets)?;
    let values = simulation::overrides(&prepared, &settings.sets, &set_exprs)?;
    prepared.set_parameter_overrides(&values.params);
    let (parameters, start) = simulation::start(&mut prepared, &values, &[])?;
    let columns = outputs.len() + settings.stops.len() + settings.events.len() + 2;
    let dynamics_exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs)?;
    let observation = prepared.lower(&prepared.observation_inputs(), &prepared.extra[..columns])?;
    let partials = prepared.partials_program()?;
    let signals = simulation::drive_signals(&prepared, &settings)?;
    let mechanical = Mechanical::new(
        prepared.layout,
        Tape::new(dynamics),
        Tape::new(observation),
        parameters.clone(),
    )
    .with_kinds(prepared.stabilisation())
    .with_signals(signals);
    // A long chain's q̈ and its variational columns by the recursive form's sweep.
    let mechanical = match prepared.recursive()? {
        Some(recursive) => mechanical.with_chain(recursive),
        None => mechanical,
    };
    let integrand = simulation::Integrand::new(&mut prepared, mechanical, method)?;
    let simulation::Integrand::Mechanical(mut mechanical) = integrand else {
        unreachable!("an explicit method integrates (q, q̇)")
    };
    mechanical.set_partials(Tape::new(partials));
    let end = match &options.section {
        Section::Period(_) => End::Time,
        Section::Crossing { rising, .. } => {
            End::Crossing { column: outputs.len() + settings.stops.len(), rising: *rising }
        }
        Section::Landing { contact: None } => {
            refuse_no_contacts(&prepared)?;
            End::Landing { contact: None }
        }
        Section::Landing { contact: Some(name) } => {
            let names = prepared.contact_names();
            let Some(k) = names.iter().position(|c| c == name) else {
                refuse_no_contacts(&prepared)?;
                return Err(Error::Input(format!(
                    "--section impact:{name}: the scene has no contact `{name}`; one of {}",
                    names.join(", ")
                )));
            };
            End::Landing { contact: Some(k) }
        }
    };
    let plan = &prepared.parameter_plan;
    let free = swept
        .and_then(|name| plan.names().position(|n| n == name))
        .filter(|i| !plan.is_derived(*i))
        .filter(|_| {
            prepared.contacts.is_empty() && options.shifts.is_empty() && settings.series.is_empty()
        });
    let (until, swept) = match &options.section {
        Section::Period(text) => period(&mut prepared, &parameters, text, free)?,
        _ => (settings.until, None),
    };
    if let (Some(i), Some(_)) = (free, swept) {
        let program = prepared.sensitivity_program(&[i])?;
        mechanical.set_sensitivities(Tape::new(program), 1);
    }
    let symmetry = Symmetry::new(
        &mut prepared,
        &parameters,
        &options.swaps,
        &options.shifts,
        &options.ignore,
    )?;
    let mut run = simulation::run_settings(&settings, 0);
    run.until = until;
    Ok(Loaded {
        mechanical,
        start,
        end,
        until,
        symmetry,
        run,
        swept,
        state_names: prepared.state_names(),
        contact_names: prepared.contact_names(),
        constraint_names: prepared.kept_constraint_names(),
        parameter_names: prepared.parameter_slot_names(),
        angle_oriented_bodies: simulation::angle_oriented_bodies(&prepared.derivation.model),
    })
}

fn refuse_no_contacts(prepared: &engine::numbers::Prepared) -> Result<(), Error> {
    if prepared.contact_names().is_empty() {
        return Err(Error::Input(
            "--section impact: the scene has no contact to land on; give an expression that \
             crosses zero, or --period for a driven scene"
                .into(),
        ));
    }
    Ok(())
}

/// The fixed period's value in seconds, from an expression of the parameters with an
/// optional unit, and its derivative by the free parameter `free` where one is given.
fn period(
    prepared: &mut engine::numbers::Prepared,
    parameters: &[f64],
    text: &str,
    free: Option<usize>,
) -> Result<(f64, Option<f64>), Error> {
    let model = &mut prepared.derivation.model;
    let value = model
        .resolve_value_for("t", text)
        .map_err(|diagnostics| Error::Expression { diagnostics, text: text.to_string() })?;
    let model::Value::Scalar(e) = value else {
        return Err(Error::Input(format!(
            "--period `{text}` is {}, not a time",
            value.kind_name()
        )));
    };
    let value = prepared.constant(e, parameters);
    if !(value.is_finite() && value > 0.0) {
        return Err(Error::Input(format!(
            "--period `{text}` is {value} at the parameters' values: a period is a positive \
             time, a constant of the parameters"
        )));
    }
    let rate = match free {
        Some(i) => Some(prepared.constant_sensitivity(e, parameters, &[i])?[0]),
        None => None,
    };
    Ok((value, rate))
}

/// A variational run's refusal in words.
fn refused(refusal: Refusal, loaded: &Loaded) -> Error {
    let contacts = &loaded.contact_names;
    let name = |k: usize| contacts.get(k).cloned().unwrap_or_default();
    let guard = |g: Guard| match g {
        Guard::Contacts(Watched::Contact(k)) => format!("contact `{}`", name(k)),
        Guard::Contacts(Watched::Friction(k)) => {
            format!("the stick or slip of contact `{}`", name(k))
        }
        Guard::Contacts(Watched::Solvability) => {
            "the solvability of the slipping contacts' forces".to_string()
        }
        Guard::Contacts(Watched::Arming(k)) => {
            format!("the arming condition of contact `{}`", name(k))
        }
        Guard::Section => "the section".to_string(),
    };
    let until = loaded.until;
    match refusal {
        Refusal::NoJacobian => Error::Numeric("the scene's partials were not lowered".into()),
        Refusal::Method(m) => Error::Input(format!("{m} cannot carry the sensitivities")),
        Refusal::Fault(f) => {
            let names = simulation::FaultNames {
                method: loaded.run.method,
                state: &loaded.state_names,
                constraints: &loaded.constraint_names,
                parameters: &loaded.parameter_names,
                angle_oriented_bodies: &loaded.angle_oriented_bodies,
                contacts,
            };
            Error::Numeric(names.report(&f, "a return"))
        }
        Refusal::Grazing { time, guard: g, relative } => Error::Numeric(format!(
            "grazing: {} is reached at t = {time} with a rate {relative:.1e} of its scale, too \
             slow to say when it is reached (the return map is not differentiable there)",
            guard(g)
        )),
        Refusal::Simultaneous { time, guards } => Error::Numeric(format!(
            "simultaneous events at t = {time}: {} at once, and which comes first changes with \
             the start",
            guards.into_iter().map(guard).collect::<Vec<_>>().join(" and ")
        )),
        Refusal::NotReached { .. } => Error::Numeric(format!(
            "no return within {until} s: the section is not reached again (raise --until, or \
             check the section and its direction)"
        )),
        Refusal::SampleTime { time } => {
            Error::Numeric(format!("{time} is no time to record at within a return's run"))
        }
        Refusal::NoSensitivities | Refusal::SensitivityStart { .. } => {
            Error::Numeric("the parameter sensitivities were not lowered for this run".into())
        }
        Refusal::SensitivitiesWithHold => Error::Input(
            "the sensitivities to the parameters are not carried with held inputs".into(),
        ),
        Refusal::SensitivitiesWithFriction => Error::Input(
            "the sensitivities to the parameters are not carried with Coulomb friction".into(),
        ),
        Refusal::SensitivitiesAtEvent => Error::Input(
            "the sensitivities to the parameters are carried to a fixed time only, not to a \
             section or a landing"
                .into(),
        ),
        Refusal::SensitivitiesAcrossJump { time, guard: g } => Error::Input(format!(
            "the sensitivities to the parameters are not carried across a jump, and {} fires \
             at t = {time}",
            guard(g)
        )),
    }
}

fn identity(size: usize) -> Vec<f64> {
    let mut m = vec![0.0; size * size];
    for i in 0..size {
        m[i * size + i] = 1.0;
    }
    m
}

/// A fixed period's map at a state: the return less its start, the Jacobian (row-major) and
/// the chart there.
pub type Evaluated = (Vec<f64>, Vec<f64>, DMatrix<f64>);

/// Finds the periodic orbit of `source` from its start.
pub fn orbit(source: &str, options: &Options) -> Result<Orbit, Error> {
    Search::new(source, options)?.find(options.iterations)
}

/// A scene loaded and lowered for orbit searches: what a search costs before its first run
/// (parsing, deriving, lowering) is paid once by [`Search::new`], and [`Search::find`] runs
/// Newton's method from the scene's start (the benchmarks time the two apart).
pub struct Search {
    loaded: Loaded,
    /// The problem the searches run on, kept from one to the next: what it makes for itself
    /// as it runs (the partials program's slices for the modes it meets, and their machine
    /// code once they have run often) serves every later search rather than one.
    working: Mechanical,
}

impl Search {
    pub fn new(source: &str, options: &Options) -> Result<Search, Error> {
        Ok(Search::of(load(source, options)?))
    }

    fn of(loaded: Loaded) -> Search {
        let working = loaded.mechanical.clone();
        Search { loaded, working }
    }

    /// [`Search::new`] for a sweep in `parameter`: where the map is a fixed period's, with no
    /// contacts, series-driven inputs or shifts, its variational runs carry S by the parameter
    /// too, and [`Search::evaluate_swept`] gives the map's derivative in it.
    pub(crate) fn for_sweep(
        source: &str,
        options: &Options,
        parameter: &str,
    ) -> Result<Search, Error> {
        Ok(Search::of(load_for(source, options, Some(parameter))?))
    }

    /// The orbit from the scene's start, in at most `iterations` Newton steps.
    pub fn find(&mut self, iterations: usize) -> Result<Orbit, Error> {
        find(&self.loaded, &mut self.working, None, iterations)
    }

    /// The orbit from the state `from` (q, q̇) rather than the scene's start: a nearby orbit's
    /// fixed point, as a sweep continues one.
    pub fn find_from(&mut self, from: &[f64], iterations: usize) -> Result<Orbit, Error> {
        find(&self.loaded, &mut self.working, Some(from), iterations)
    }

    /// Whether the map is over a fixed period (whose start is any state, not one on a section).
    pub(crate) fn is_periodic_in_time(&self) -> bool {
        self.loaded.end == End::Time
    }

    /// A fixed period's map at `x`, for continuation: the return less its start, S(P(x)) − x,
    /// its Jacobian Π·Φ (row-major) and the chart at `x`. With no symmetry Π·Φ is the
    /// variational run's Φ over the period, which a linearization along a run gives too.
    pub fn evaluate(&self, x: &[f64]) -> Result<Evaluated, Error> {
        let loaded = &self.loaded;
        let mut mechanical = loaded.mechanical.clone();
        let fail = |r: Refusal| refused(r, loaded);
        let tr =
            variational::transition(&mut mechanical, x, &loaded.run, loaded.end).map_err(fail)?;
        let size = x.len();
        let ignored = loaded.symmetry.ignored_rows();
        let tangent = chart::section(&identity(size), &tr.normals, &ignored, size);
        let returned = loaded.symmetry.apply(&tr.state);
        let gap = returned.iter().zip(x).map(|(a, b)| a - b).collect();
        Ok((gap, loaded.symmetry.carry(&tr.matrix), tangent))
    }

    /// [`Search::evaluate`], with the map's derivative in the swept parameter p where
    /// [`Search::for_sweep`] could carry it: Π·(S(T) + F(x(T))·dT/dp), the start held
    /// (S(0) = 0) and the period moving with p; `None` where it could not.
    pub(crate) fn evaluate_swept(&self, x: &[f64]) -> Result<(Evaluated, Option<Vec<f64>>), Error> {
        let loaded = &self.loaded;
        let Some(period_rate) = loaded.swept else { return Ok((self.evaluate(x)?, None)) };
        let mut mechanical = loaded.mechanical.clone();
        let fail = |r: Refusal| refused(r, loaded);
        let size = x.len();
        let options =
            variational::Options { sensitivities: Some(vec![0.0; size]), ..Default::default() };
        let tr =
            variational::transition_with(&mut mechanical, x, &loaded.run, loaded.end, &options)
                .map_err(fail)?;
        let mut rate = vec![0.0; size];
        sim::Problem::rhs(&mut mechanical, tr.time, &tr.state, &mut rate).map_err(|kind| {
            fail(Refusal::Fault(sim::Fault { kind, time: tr.time, state: tr.state.clone() }))
        })?;
        let s = tr.sensitivities.clone().unwrap_or_default();
        let moved: Vec<f64> = s.iter().zip(&rate).map(|(s, f)| s + f * period_rate).collect();
        let ignored = loaded.symmetry.ignored_rows();
        let tangent = chart::section(&identity(size), &tr.normals, &ignored, size);
        let returned = loaded.symmetry.apply(&tr.state);
        let gap = returned.iter().zip(x).map(|(a, b)| a - b).collect();
        let evaluated = (gap, loaded.symmetry.carry(&tr.matrix), tangent);
        Ok((evaluated, Some(loaded.symmetry.permute(&moved))))
    }
}

fn find(
    loaded: &Loaded,
    mechanical: &mut Mechanical,
    from: Option<&[f64]>,
    iterations_allowed: usize,
) -> Result<Orbit, Error> {
    newton(loaded, mechanical, from, iterations_allowed).map(|(orbit, _)| orbit)
}

/// One Newton run from `x`, whose chart is built from `surface` (the surface of the return
/// `x` was reached from): the run, its chart, and the residual in it.
struct Measured {
    run: variational::Transition,
    tangent: DMatrix<f64>,
    residual: DVector<f64>,
}

fn measure(
    loaded: &Loaded,
    mechanical: &mut Mechanical,
    x: &[f64],
    surface: &[f64],
    tolerance: f64,
) -> Result<Measured, Error> {
    let settings = sim::Settings { tolerance, ..loaded.run.clone() };
    let symmetry = &loaded.symmetry;
    let size = x.len();
    let run = variational::transition(mechanical, x, &settings, loaded.end)
        .map_err(|r| refused(r, loaded))?;
    let ignored = symmetry.ignored_rows();
    let tangent = chart::section(&symmetry.carry(surface), &run.normals, &ignored, size);
    let returned = symmetry.apply(&run.state);
    let gap: Vec<f64> = returned.iter().zip(&run.start).map(|(a, b)| a - b).collect();
    let residual = tangent.transpose() * DVector::from_vec(gap);
    Ok(Measured { run, tangent, residual })
}

/// [`find`], and the surface of the last run's return (the chart at the fixed point).
fn newton(
    loaded: &Loaded,
    mechanical: &mut Mechanical,
    from: Option<&[f64]>,
    iterations_allowed: usize,
) -> Result<(Orbit, Vec<f64>), Error> {
    let end = loaded.end;
    let fail = |r: Refusal| refused(r, loaded);
    let symmetry = &loaded.symmetry;
    let size = loaded.start.len();
    let start = from.map_or_else(|| loaded.start.clone(), |x| x.to_vec());
    // From the scene's start the first step is a long one; from a nearby orbit's fixed point
    // (a sweep's prediction) it is short, and a loose run's error would be most of it.
    let accuracy = Accuracy::of(loaded.run.tolerance, from.is_none());
    // Onto the section first: the scene's start is anywhere on the orbit's way. The return is
    // mapped by the symmetry before it starts again, as every return is compared: a walker's
    // legs swap at the strike, and the state after it, its legs swapped, is where the next
    // step starts with its modes (the stance foot the one the coordinates now say). That run
    // carries no Φ: its surface, all the next run needs of it, is the jump's and the
    // section's. It is integrated at the tolerance asked for, though only Newton's start:
    // Newton's steps stay in the chart, along the manifold the constraints hold, so how far
    // its end lies off that manifold (the run's error) stays in every later start.
    let (mut x, mut surface) = match end {
        End::Time => (start, identity(size)),
        _ => {
            let options =
                variational::Options { directions: Some(Vec::new()), ..Default::default() };
            let tr = variational::transition_with(mechanical, &start, &loaded.run, end, &options)
                .map_err(fail)?;
            (symmetry.apply(&tr.state), tr.surface)
        }
    };
    let mut iterations: Vec<Iteration> = Vec::new();
    let mut runs: Vec<Run> = Vec::new();
    for _ in 0..iterations_allowed.max(1) {
        let tolerance = accuracy.next(&runs);
        let Measured { run: tr, tangent, residual } =
            measure(loaded, mechanical, &x, &surface, tolerance)?;
        let monodromy = symmetry.carry(&tr.matrix);
        let reduced = chart::reduced(&monodromy, &tangent);
        let size_of = tr.start.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let worst = residual.amax();
        let this = Run { residual: worst / size_of, tolerance };
        let finish = accuracy.finish(&runs, this);
        runs.push(this);
        iterations.push(Iteration { residual: worst, steps: tr.steps, tolerance });
        let next = match finish {
            Finish::Converged => None,
            Finish::Continue | Finish::LastStep(_) => {
                let Some(step) = chart::newton_step(&reduced, &residual, tolerance) else {
                    return Err(Error::Numeric(
                        "Newton's step is not finite: the map's Jacobian on the section is"
                            .to_string()
                            + " not a number there",
                    ));
                };
                let moved = &tangent * step;
                Some(tr.start.iter().zip(moved.iter()).map(|(a, d)| a + d).collect::<Vec<_>>())
            }
        };
        if finish == Finish::Continue {
            if let Some(next) = next {
                x = next;
                surface = tr.surface;
                continue;
            }
        }
        let last_step = match finish {
            Finish::LastStep(expected) => Some(expected * size_of),
            _ => None,
        };
        let multipliers = chart::multipliers_within(&reduced, &monodromy, size);
        let largest = multipliers.first().map_or(0.0, |m| m.norm());
        let verdict = if largest > 1.0 + NEUTRAL {
            Verdict::Unstable
        } else if largest >= 1.0 - NEUTRAL {
            Verdict::Neutral
        } else {
            Verdict::Stable
        };
        let stable = verdict == Verdict::Stable;
        let orbit = Orbit {
            state_names: loaded.state_names.clone(),
            fixed_point: next.unwrap_or_else(|| tr.start.clone()),
            period: tr.time - loaded.run.start,
            multipliers,
            monodromy,
            trivial: size - tangent.ncols(),
            jumps: tr.jumps,
            iterations,
            last_step,
            stable,
            verdict,
        };
        return Ok((orbit, tr.surface));
    }
    let last = iterations.last().map_or(f64::NAN, |i| i.residual);
    Err(Error::Numeric(format!(
        "Newton's method did not converge in {} iterations (residual {last:.3e} on the \
         section): start nearer the orbit (--set), or check the section and the symmetry (a \
         cyclic coordinate left in the comparison makes a family of orbits: --ignore it)",
        iterations.len()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHEEL: &str = include_str!("../../../examples/contacts/rimless_wheel.lag");

    fn run(residual: f64, tolerance: f64) -> Run {
        Run { residual, tolerance }
    }

    /// Far from the orbit the runs are loose; as the residual falls they tighten, never loosen,
    /// and reach the tolerance asked for once a step is expected to leave less than it can
    /// tell; a run looser than that never ends the search.
    #[test]
    fn the_runs_tighten_with_the_residual_and_only_a_tight_one_ends_the_search() {
        let accuracy = Accuracy::of(1e-10, true);
        assert_eq!(accuracy.next(&[]), LOOSEST);
        assert_eq!(Accuracy::of(1e-10, false).next(&[]), 1e-10);
        // From 10⁻¹ (rate 1 assumed): 10⁻² expected, then 10⁻⁴ after its step, matched by 10⁻⁷.
        let first = [run(1e-1, LOOSEST)];
        assert!((accuracy.next(&first) - 1e-7).abs() < 1e-20);
        // The rate measured (10⁻³/10⁻² = 10): 10⁻⁵ expected, 10⁻⁹ after, and 10⁻¹² is below
        // the tolerance asked for.
        let two = [run(1e-1, LOOSEST), run(1e-3, 1e-7)];
        assert_eq!(accuracy.next(&two), 1e-10);
        // A residual that grew (a rate read on a loose map's error) never loosens the runs.
        let grown = [run(1e-9, 1e-10), run(1e-6, 1e-10)];
        assert_eq!(accuracy.next(&grown), 1e-10);
        // A loose run's tiny residual is its map's error, not the orbit's: it goes on.
        assert_eq!(accuracy.finish(&[], run(1e-16, 1e-7)), Finish::Continue);
        assert_eq!(accuracy.finish(&[], run(1e-15, 1e-10)), Finish::Converged);
        // Quadratic from 10⁻⁶ to 10⁻¹²: the next step would leave about 10⁻²⁴, and moves the
        // state by less than the tolerance: taken unchecked.
        let near = [run(1e-6, 1e-10)];
        match accuracy.finish(&near, run(1e-12, 1e-10)) {
            Finish::LastStep(expected) => assert!((expected / 1e-24 - 1.0).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
        // The walker's: from 10⁻⁶ to 1.3·10⁻¹¹ (rate 13), the step changes the Jacobian by
        // 1.7·10⁻¹⁰, under ten tolerances: taken unchecked too.
        let walker = [run(1e-6, 1e-10)];
        assert!(matches!(accuracy.finish(&walker, run(1.3e-11, 1e-10)), Finish::LastStep(_)));
        // From 10⁻⁴ to 10⁻⁸ (rate 1): 10⁻¹⁶ expected, but the step moves the state by 10⁻⁸,
        // a hundred tolerances: checked by another run.
        assert_eq!(accuracy.finish(&[run(1e-4, 1e-10)], run(1e-8, 1e-10)), Finish::Continue);
        // A residual that no longer falls tenfold below 10⁻⁹ has met the map's rounding, but
        // only against a run at the same tolerance.
        assert_eq!(accuracy.finish(&[run(2e-10, 1e-10)], run(1e-10, 1e-10)), Finish::Converged);
        assert_eq!(accuracy.finish(&[run(2e-10, 1e-8)], run(1e-10, 1e-10)), Finish::Continue);
    }

    /// The wheel's last step is taken unchecked: a run from its end, on the chart the last run
    /// returned to, finds the residual at the map's rounding (the step had promised 10⁻²⁴),
    /// far below the 10⁻¹² the step started from.
    #[test]
    fn an_unchecked_last_step_leaves_the_residual_it_promised() {
        let options = Options {
            run: simulation::Options { tolerance: Some(1e-10), ..Default::default() },
            section: Section::Landing { contact: None },
            swaps: Vec::new(),
            shifts: vec![Assignment { name: "theta".into(), value: "pi/4".into() }],
            ignore: vec!["x".into()],
            iterations: 30,
        };
        let loaded = load(WHEEL, &options).expect("loads");
        let mut mechanical = loaded.mechanical.clone();
        let (orbit, surface) = newton(&loaded, &mut mechanical, None, 30).expect("an orbit");
        let promised = orbit.last_step.expect("taken unchecked");
        let before = orbit.iterations.last().expect("a run").residual;
        let measured =
            measure(&loaded, &mut mechanical, &orbit.fixed_point, &surface, 1e-10).expect("a run");
        let left = measured.residual.amax();
        assert!(promised < 1e-20 && left < 1e-14, "{left:e} left, {promised:e} promised");
        assert!(before > 1e2 * left, "{before:e} before the step, {left:e} after");
    }
}
