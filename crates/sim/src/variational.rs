//! Sensitivities of a run: the state transition matrix Φ = ∂x(t)/∂x(t₀) integrated beside the
//! state x = (q, q̇) of a [`Mechanical`] problem, Φ̇ = A(t)·Φ with A = ∂F/∂x its exact Jacobian
//! (the partials program, through the augmented system where constraints are kept).
//!
//! Φ rides on the run's own steps: every stage of an explicit method advances x and Φ alike,
//! so Φ is the derivative of the steps taken with their sizes held (internal
//! differentiation), not a second solution with steps of its own, and a Newton iteration on a
//! map built of such runs converges as fast as Newton's method can. The step control weighs
//! Φ with x: weighing x alone would leave Φ to the state's absolute tolerance where the state
//! is small (a driven response of 10⁻⁴ rad had Φ's determinant off by 2·10⁻⁶ so, against
//! 10⁻¹⁰ weighed).
//!
//! Where a run jumps (a contact lands or lifts off) Φ is carried across by the saltation
//! matrix Ξ = G_x·P + f⁺·h_xᵀ/ḣ, with h the guard that fired, ḣ = h_x·f⁻ + h_t its rate,
//! P = I − f⁻·h_xᵀ/ḣ the projection onto the guard's surface along the flow, and G the jump.
//! G_x·P is the jump's derivative along the surface, the state first moved back onto the
//! manifold the mode before the jump holds it on and onto the surface along f⁻ (across the
//! manifold, G is taken of the state projected onto it). It is exact wherever the jump's
//! impulse is frictionless or none (`Mechanical::impact_derivative` and
//! `Mechanical::projection_derivative`: the partials program's rows through the impact law and
//! the projections); where Coulomb's law acts in an impact it is central differences of the
//! jump alone (never of a run), so that the jump sees the same touching contacts. h_x and h_t
//! are exact for a gap (its row of J) and central differences of any other guard.
//! A crossing with ḣ too small to locate the event by (grazing, where the map has a
//! square-root singularity) and two guards at once are refused, named.
//!
//! A run may end at a time, where an observation crosses zero in a given direction (a
//! section), or just after a contact lands: at the two events the matrix given is the
//! derivative of the state there with the event's time varied with the start (P·Φ, G_x·P·Φ),
//! the Jacobian of a return map.
//!
//! Beside Φ a run may carry S = ∂x(t)/∂p, the state's derivative by parameters
//! ([`transition_with`], [`Options::sensitivities`]): Ṡ = A·S + ∂F/∂p, with ∂F/∂p = (0, ∂q̈/∂p)
//! from the problem's sensitivity program through the same augmented system
//! ([`Mechanical::parameter_derivative`]), from S(0) = ∂x(0)/∂p, which the caller gives (the
//! start may depend on the parameters: `engine`'s `Prepared::start_sensitivity` gives it for a
//! start as a scene writes it). On the run's own steps too, S is the derivative of the steps
//! taken. Across a jump S would need the jump's and the guard's own derivatives by the
//! parameters (∂G/∂p, ∂h/∂p), and at a section's crossing the section's (∂h/∂p), which are not
//! taken: a run carrying S is refused at its first jump, and one ending at an event before it
//! starts ([`Refusal::SensitivitiesAcrossJump`], [`Refusal::SensitivitiesAtEvent`]); so is one
//! with Coulomb friction, whose μ acts in the problem's numbers, not in the sensitivity
//! program ([`Refusal::SensitivitiesWithFriction`]).

use std::cell::Cell;
use std::ops::ControlFlow;

use crate::linalg::identity;
use crate::{integrate_into, Fault, FaultKind, Form, Mechanical, ModeChange, ModeEvent, Problem};
use crate::{Rows, Settings};

/// Where a variational run ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// At the settings' end time.
    Time,
    /// Where observation `column` of the problem crosses zero, upward if `rising`, after
    /// having been clearly on the other side (a start on the section does not end the run).
    Crossing { column: usize, rising: bool },
    /// Just after contact `contact` (any, with `None`) lands with an impact.
    Landing { contact: Option<usize> },
}

/// How the jump maps' derivatives G_x are taken.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Saltation {
    /// G_x exact wherever the impulse is frictionless or none (the partials program's rows
    /// through the impact law and the projections), differenced where Coulomb's law acts in
    /// an impact; the guard's gradient exact where it is a gap, differenced otherwise.
    #[default]
    Exact,
    /// Central differences of the jump map, at every jump.
    Differences,
}

/// A guard of a variational run: one of the contacts' ([`crate::Watched`]), or the section's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Guard {
    Contacts(crate::Watched),
    Section,
}

/// Why a variational run gave no transition matrix.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// The problem was given no partials program: A would be differences.
    NoJacobian,
    /// The method is not an explicit one on (q, q̇): its steps could not carry Φ as theirs.
    Method(&'static str),
    /// The run faulted.
    Fault(Fault),
    /// `guard` reached zero with ḣ = `rate`, too slow against its scale (`relative`) to say
    /// when: the event's time is not differentiable there.
    Grazing { time: f64, guard: Guard, relative: f64 },
    /// Several guards fired at once: which jump happens first changes with the start.
    Simultaneous { time: f64, guards: Vec<Guard> },
    /// The run reached its end time before its section or landing.
    NotReached { until: f64 },
    /// S was asked for of a problem without a sensitivity program
    /// ([`Mechanical::set_sensitivities`]).
    NoSensitivities,
    /// S(0) has `given` entries where the problem's state and sensitivity program make
    /// `expected` (2n × k).
    SensitivityStart { expected: usize, given: usize },
    /// A time of [`Options::times`] outside the run's span, or not after the one before it.
    SampleTime { time: f64 },
    /// S was asked for of a run that ends at a section or a landing: the event's time moves
    /// with the parameters through the guard's own derivative by them, which is not taken.
    SensitivitiesAtEvent,
    /// A run carrying S met a jump at `time`, fired by `guard`: S across it would need the
    /// jump's and the guard's derivatives by the parameters, which are not taken.
    SensitivitiesAcrossJump { time: f64, guard: Guard },
    /// S was asked for of a problem with Coulomb friction: a slipping contact's force
    /// −μ·λ·J_Tᵀ holds μ as a number of the problem's, not a slot of the sensitivity program,
    /// so S by μ (and by what μ's value follows) would leave its share out.
    SensitivitiesWithFriction,
    /// S was asked for of a problem holding laws sampled into parameter slots
    /// ([`Mechanical::with_hold`]): the held values move with the parameters at each sample,
    /// a jump of the right-hand side S would need their derivatives at.
    SensitivitiesWithHold,
}

/// What a variational run's step control weighs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepControl {
    /// The state, Φ and S alike: each to the tolerance, as an orbit's multipliers want Φ.
    #[default]
    Everything,
    /// The state alone, Φ and S carried on its steps: the exact derivatives of the state those
    /// steps computed, which is what a fit's residuals need, at the state's cost in steps.
    State,
}

/// What a variational run carries besides Φ, and how.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// How the jumps' derivatives are taken.
    pub saltation: Saltation,
    /// What the step control weighs.
    pub step_control: StepControl,
    /// S(0) = ∂x(0)/∂p, row-major 2n × k for the k parameters of the problem's sensitivity
    /// program: with it the run carries S = ∂x(t)/∂p beside Φ ([`Transition::sensitivities`]).
    /// The start's own dependence on the parameters is the caller's to give (zeros for a start
    /// held fixed as they move); it is taken as the start's after its contacts' modes are
    /// decided, which may project a start on a closed contact.
    pub sensitivities: Option<Vec<f64>>,
    /// Times, increasing, within the run's span, at which the state, Φ and S (where carried)
    /// are recorded besides the end ([`Transition::samples`]): a fit's data times. They are
    /// read from the method's dense output, as a simulation's samples are, and end no step:
    /// the interpolant is linear in the stages, whose Φ and S are their states' derivatives,
    /// so what is recorded is still the exact derivative of what the run computed.
    pub times: Vec<f64>,
    /// D (row-major 2n × c): the run carries Φ·D, the state's derivative along D's columns,
    /// rather than Φ itself (D = I). With c = 0 it carries the state alone, its `surface` and
    /// its end all the same: a return map's first run onto its section needs no more.
    pub directions: Option<Vec<f64>>,
}

/// What a variational run recorded at one of [`Options::times`].
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub time: f64,
    /// (q, q̇).
    pub state: Vec<f64>,
    /// Φ, row-major 2n × 2n (Φ·D, 2n × c, where [`Options::directions`] gave D).
    pub matrix: Vec<f64>,
    /// S, row-major 2n × k, where [`Options::sensitivities`] asked for it.
    pub sensitivities: Option<Vec<f64>>,
}

/// A run's end and the derivative of its state there with respect to its start.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// The state the run began from, after the start's mode was decided (a contact closed
    /// there may project it), and F there.
    pub start: Vec<f64>,
    pub start_rate: Vec<f64>,
    /// The normals of the manifold the start moves on ([`Mechanical::manifold_normals`]), in
    /// the mode decided at the start.
    pub normals: Vec<Vec<f64>>,
    pub time: f64,
    /// (q, q̇) at the end, after the jump for a landing.
    pub state: Vec<f64>,
    /// ∂state/∂start, row-major, 2n × 2n; along D's columns (Φ·D, 2n × c) where
    /// [`Options::directions`] gave D.
    pub matrix: Vec<f64>,
    /// S = ∂state/∂p at the end, row-major 2n × k, when [`Options::sensitivities`] asked for it.
    pub sensitivities: Option<Vec<f64>>,
    /// The state, Φ and S at each of [`Options::times`] the run reached.
    pub samples: Vec<Sample>,
    /// The derivative of the state at the end along the surface it ended on, within the
    /// manifold the state moved on before it, row-major: P·Q at a crossing, G_x·P·Q at a
    /// landing, Q at a time, with Q the orthogonal projection onto that manifold's tangent.
    /// Its range is the tangent of the section there, the directions a state on it can move in.
    pub surface: Vec<f64>,
    /// The jumps crossed on the way (the landing that ends a run included).
    pub jumps: usize,
    /// How many of them had their G_x exact ([`Saltation::Exact`]), not differenced (their
    /// guard's gradient may still be differences: see [`Saltation::Exact`]).
    pub exact_jumps: usize,
    pub steps: usize,
    pub evaluations: usize,
}

/// The slope of a central difference: far above rounding, its truncation (∝ step²) below it.
const DIFFERENCE: f64 = 1e-6;
/// A crossing whose |ḣ| is below this fraction of ‖h_x‖·‖f⁻‖ + |h_t| is grazing.
const GRAZING: f64 = 1e-6;
/// The section arms once the state is this fraction of the section's length scale on the side
/// before it.
const ARMING: f64 = 1e-8;

/// Integrates `problem` from `y0` = (q, q̇) with Φ beside it until `end`.
pub fn transition(
    problem: &mut Mechanical,
    y0: &[f64],
    settings: &Settings,
    end: End,
) -> Result<Transition, Refusal> {
    transition_by(problem, y0, settings, end, Saltation::Exact)
}

/// [`transition`] with the jumps' derivatives taken as `saltation` says.
pub fn transition_by(
    problem: &mut Mechanical,
    y0: &[f64],
    settings: &Settings,
    end: End,
    saltation: Saltation,
) -> Result<Transition, Refusal> {
    let options = Options { saltation, ..Default::default() };
    transition_with(problem, y0, settings, end, &options)
}

/// [`transition`] with what `options` asks besides Φ: S = ∂x/∂p too, where S(0) is given.
pub fn transition_with(
    problem: &mut Mechanical,
    y0: &[f64],
    settings: &Settings,
    end: End,
    options: &Options,
) -> Result<Transition, Refusal> {
    if !problem.has_partials() {
        return Err(Refusal::NoJacobian);
    }
    let method = settings.method;
    if method.form() != Form::Physical || !method.is_explicit() {
        return Err(Refusal::Method(method.name()));
    }
    let size = problem.dim();
    assert_eq!(y0.len(), size, "state length");
    let columns = match &options.sensitivities {
        None => 0,
        Some(given) => {
            let Some(columns) = problem.sensitivity_columns() else {
                return Err(Refusal::NoSensitivities);
            };
            if given.len() != size * columns {
                let expected = size * columns;
                return Err(Refusal::SensitivityStart { expected, given: given.len() });
            }
            if end != End::Time {
                return Err(Refusal::SensitivitiesAtEvent);
            }
            if problem.has_friction() {
                return Err(Refusal::SensitivitiesWithFriction);
            }
            if problem.has_hold() {
                return Err(Refusal::SensitivitiesWithHold);
            }
            columns
        }
    };
    let mut previous = settings.start;
    for (k, &time) in options.times.iter().enumerate() {
        let ordered = if k == 0 { time >= previous } else { time > previous };
        if !(ordered && time <= settings.until && time.is_finite()) {
            return Err(Refusal::SampleTime { time });
        }
        previous = time;
    }
    let mut start = y0.to_vec();
    let directions = match &options.directions {
        None => {
            start.resize(size + size * size, 0.0);
            for i in 0..size {
                start[size + i * size + i] = 1.0;
            }
            size
        }
        // Φ(0) = I: Φ·D starts as D.
        Some(d) => {
            assert_eq!(d.len() % size, 0, "D's rows are the state's");
            start.extend(d);
            d.len() / size
        }
    };
    if let Some(given) = &options.sensitivities {
        start.extend(given);
    }
    let saltation = options.saltation;
    let stop = Cell::new(false);
    let mut variational = Variational {
        inner: problem,
        size,
        end,
        jac: vec![0.0; size * size],
        observed: Vec::new(),
        armed: false,
        length: 0.0,
        captured: None,
        refusal: None,
        jumps: 0,
        exact_jumps: 0,
        stop: &stop,
        begun: None,
        saltation,
        carries: options.sensitivities.is_some(),
        columns,
        change: vec![0.0; size / 2 * columns],
        times: &options.times,
        samples: Vec::new(),
        step_control: options.step_control,
        directions,
    };
    let mut halt =
        |_: f64| if stop.get() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) };
    let run = integrate_into(&mut variational, &start, settings, &[], &mut halt, &mut Discard);
    if let Some(refusal) = variational.refusal.take() {
        return Err(refusal);
    }
    let (jumps, exact_jumps) = (variational.jumps, variational.exact_jumps);
    let samples = std::mem::take(&mut variational.samples);
    let (begun, captured) = (variational.begun.take(), variational.captured.take());
    if let (None, Some(mut fault)) = (&captured, run.fault) {
        fault.state.truncate(size);
        return Err(Refusal::Fault(fault));
    }
    let mut sensitivities = None;
    let (time, state, matrix, surface) = match (captured, end) {
        (Some(c), _) => c,
        (None, End::Time) if run.final_time == settings.until => {
            let (t, y) = (run.final_time, &run.final_state);
            let within = manifold_projection(problem, t, &y[..size]).map_err(|kind| {
                Refusal::Fault(Fault { kind, time: t, state: y[..size].to_vec() })
            })?;
            let carried = size + size * directions;
            if options.sensitivities.is_some() {
                sensitivities = Some(y[carried..].to_vec());
            }
            (t, y[..size].to_vec(), y[size..carried].to_vec(), within)
        }
        (None, _) => return Err(Refusal::NotReached { until: settings.until }),
    };
    // A problem without guards has one mode, and no start to decide it at.
    let (begun, begun_rate, normals) = match begun {
        Some(b) => b,
        None => {
            let fail =
                |kind| Refusal::Fault(Fault { kind, time: settings.start, state: y0.to_vec() });
            let rate = rate_of(problem, settings.start, y0).map_err(fail)?;
            let normals = problem.manifold_normals(settings.start, y0).map_err(fail)?;
            (y0.to_vec(), rate, normals.unwrap_or_default())
        }
    };
    Ok(Transition {
        start: begun,
        start_rate: begun_rate,
        normals,
        time,
        state,
        matrix,
        sensitivities,
        samples,
        surface,
        jumps,
        exact_jumps,
        steps: run.steps,
        evaluations: run.evaluations,
    })
}

/// Rows nobody keeps: a variational run's value is its end.
struct Discard;

impl Rows for Discard {
    fn row(&mut self, _: f64, _: &[f64]) {}
}

/// The end of a run at its event: the time, the state, ∂state/∂start and ∂state along the
/// event's surface.
type Captured = (f64, Vec<f64>, Vec<f64>, Vec<f64>);

/// A jump's G_x·P (row-major) and its mode events.
type Jumped = (Vec<f64>, Vec<ModeEvent>);

/// The start after its mode was decided, F there and the manifold's normals.
type Begun = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// A function of (t, x) that may fault: a guard, a section's expression.
type Scalar<'f> = dyn FnMut(f64, &[f64]) -> Result<f64, FaultKind> + 'f;

/// The state and Φ (row-major) as one problem.
struct Variational<'a> {
    inner: &'a mut Mechanical,
    size: usize,
    end: End,
    jac: Vec<f64>,
    observed: Vec<f64>,
    /// Whether a crossing of the section counts yet.
    armed: bool,
    /// The section's length scale: ‖h_x‖₁ times the size of the state at the start.
    length: f64,
    captured: Option<Captured>,
    refusal: Option<Refusal>,
    jumps: usize,
    exact_jumps: usize,
    stop: &'a Cell<bool>,
    /// The start after its mode was decided, F there and the manifold's normals.
    begun: Option<Begun>,
    saltation: Saltation,
    /// Whether S is carried, for how many parameters, and ∂q̈/∂p's buffer.
    carries: bool,
    columns: usize,
    change: Vec<f64>,
    /// The times to record at, and what was recorded.
    times: &'a [f64],
    samples: Vec<Sample>,
    step_control: StepControl,
    /// The columns of Φ·D carried (2n for Φ itself).
    directions: usize,
}

impl Variational<'_> {
    fn section(&mut self, t: f64, x: &[f64]) -> Result<f64, FaultKind> {
        let End::Crossing { column, .. } = self.end else { return Ok(0.0) };
        section_value(self.inner, &mut self.observed, column, t, x)
    }

    fn refuse(&mut self, refusal: Refusal) -> Result<Vec<ModeEvent>, FaultKind> {
        self.refusal = Some(refusal);
        self.stop.set(true);
        Ok(Vec::new())
    }

    fn capture(&mut self, t: f64, x: Vec<f64>, matrix: Vec<f64>, surface: Vec<f64>) {
        self.captured = Some((t, x, matrix, surface));
        self.stop.set(true);
    }
}

fn section_value(
    problem: &mut Mechanical,
    observed: &mut Vec<f64>,
    column: usize,
    t: f64,
    x: &[f64],
) -> Result<f64, FaultKind> {
    observed.resize(problem.observations(), 0.0);
    problem.observe(t, x, observed)?;
    Ok(observed[column])
}

fn rate_of(problem: &mut Mechanical, t: f64, x: &[f64]) -> Result<Vec<f64>, FaultKind> {
    let mut f = vec![0.0; x.len()];
    problem.rhs(t, x, &mut f)?;
    Ok(f)
}

/// Central differences of `h` in each component of x and in t: (h_x, h_t).
fn gradient(t: f64, x: &[f64], h: &mut Scalar<'_>) -> Result<(Vec<f64>, f64), FaultKind> {
    let mut probe = x.to_vec();
    let mut hx = vec![0.0; x.len()];
    for i in 0..x.len() {
        let step = DIFFERENCE * (1.0 + x[i].abs());
        probe[i] = x[i] + step;
        let up = h(t, &probe)?;
        probe[i] = x[i] - step;
        let down = h(t, &probe)?;
        probe[i] = x[i];
        hx[i] = (up - down) / (2.0 * step);
    }
    let step = DIFFERENCE * (1.0 + t.abs());
    let ht = (h(t + step, x)? - h(t - step, x)?) / (2.0 * step);
    Ok((hx, ht))
}

/// The lower rows of A·Φ (A row-major `s` × `s`, Φ row-major `s` × `c`) into `d`: row by
/// row of Φ, each entry's sum over k in its order from +0 (the same bits whatever the route),
/// a zero of A's left out: ±0 added to a sum that is never −0 changes nothing, for the finite
/// Φ a run carries.
fn lower_rows_of(a: &[f64], phi: &[f64], d: &mut [f64], n: usize, s: usize, c: usize) {
    for i in n..s {
        let row = &mut d[i * c..(i + 1) * c];
        row.fill(0.0);
        for (k, &a) in a[i * s..(i + 1) * s].iter().enumerate() {
            if a == 0.0 {
                continue;
            }
            for (out, p) in row.iter_mut().zip(&phi[k * c..(k + 1) * c]) {
                *out += a * p;
            }
        }
    }
}

/// [`lower_rows_of`] with `C` columns, a constant.
fn lower_rows<const C: usize>(a: &[f64], phi: &[f64], d: &mut [f64], n: usize, s: usize) {
    for i in n..s {
        let mut sums = [0.0f64; C];
        for (&a, p) in a[i * s..(i + 1) * s].iter().zip(phi.chunks_exact(C)) {
            if a == 0.0 {
                continue;
            }
            for (out, p) in sums.iter_mut().zip(p) {
                *out += a * p;
            }
        }
        d[i * C..(i + 1) * C].copy_from_slice(&sums);
    }
}

/// A·B of row-major squares.
fn product(a: &[f64], b: &[f64], size: usize) -> Vec<f64> {
    let mut out = vec![0.0; size * size];
    // Row slices rather than indices: each entry's sum in the same order, without a bounds
    // check per term.
    for (row, a) in out.chunks_exact_mut(size).zip(a.chunks_exact(size)) {
        for (aik, b) in a.iter().zip(b.chunks_exact(size)) {
            for (o, bkj) in row.iter_mut().zip(b) {
                *o += aik * bkj;
            }
        }
    }
    out
}

/// The orthogonal projection (row-major) onto the tangent of the manifold the problem's mode
/// holds the state on at (t, x): I less the projection onto its normals' span.
fn manifold_projection(problem: &mut Mechanical, t: f64, x: &[f64]) -> Result<Vec<f64>, FaultKind> {
    let size = x.len();
    let normals = problem.manifold_normals(t, x)?.unwrap_or_default();
    let mut out = identity(size);
    if normals.is_empty() {
        return Ok(out);
    }
    let rows = nalgebra::DMatrix::from_fn(normals.len(), size, |r, c| normals[r][c]);
    let svd = rows.svd(false, true);
    let Some(v_t) = svd.v_t else { return Ok(out) };
    let largest = svd.singular_values.iter().fold(0.0_f64, |m: f64, v: &f64| m.max(*v));
    for (k, sigma) in svd.singular_values.iter().enumerate() {
        // A row dependent on the others (a grip implied by a gap) adds no direction.
        if *sigma <= 1e-10 * largest {
            continue;
        }
        let v = v_t.row(k);
        for i in 0..size {
            for j in 0..size {
                out[i * size + j] -= v[i] * v[j];
            }
        }
    }
    Ok(out)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// The rate of a guard at a crossing, refused as grazing where it is too small to locate by.
fn crossing_rate(hx: &[f64], ht: f64, f: &[f64]) -> (f64, f64) {
    let rate = dot(hx, f) + ht;
    let scale = norm(hx) * norm(f) + ht.abs();
    (rate, if scale > 0.0 { rate.abs() / scale } else { 0.0 })
}

/// P·Φ = Φ − f·(h_xᵀ·Φ)/ḣ: Φ (row-major, `size` rows) with the event's time varied with the
/// start.
fn along_surface(phi: &[f64], f: &[f64], hx: &[f64], rate: f64, size: usize) -> Vec<f64> {
    let columns = phi.len() / size;
    let mut out = phi.to_vec();
    for j in 0..columns {
        let moved: f64 = (0..size).map(|k| hx[k] * phi[k * columns + j]).sum::<f64>() / rate;
        for i in 0..size {
            out[i * columns + j] -= f[i] * moved;
        }
    }
    out
}

/// Guard `k` of the problem at (t, x).
fn guard_value(problem: &mut Mechanical, k: usize, t: f64, x: &[f64]) -> Result<f64, FaultKind> {
    let mut out = vec![0.0; problem.guards()];
    problem.guard_values(t, x, &mut out)?;
    Ok(out[k])
}

impl Variational<'_> {
    /// The jump at contact `k`'s gap taken on `y`, and G_x·P of it, exact: the projection onto
    /// the manifold the mode before it holds the state on and onto the guard's surface along
    /// f⁻ (twice, as [`Variational::differenced_jump`] moves its probes), the impulse, and the
    /// projection onto the new mode's manifold, each by its own derivative. `None` (the jump
    /// taken all the same) where one of them has none: Coulomb's law in the impulse, or rows
    /// that depend on each other.
    fn exact_jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        k: usize,
        before: &[f64],
        hx: &[f64],
        rate: f64,
    ) -> Result<Option<Jumped>, FaultKind> {
        let s = self.size;
        let x = y[..s].to_vec();
        let Some(old) = self.inner.projection_derivative(t, &x)? else { return Ok(None) };
        let events = self.inner.jump(t, &mut y[..s], &[k])?;
        let Some(impulse) = self.inner.impact_derivative(t, &x)? else { return Ok(None) };
        let Some(new) = self.inner.projection_derivative(t, &y[..s])? else { return Ok(None) };
        let flow = along_surface(&identity(s), before, hx, rate, s);
        let settle = product(&flow, &old, s);
        let onto = product(&product(&settle, &settle, s), &flow, s);
        Ok(Some((product(&new, &product(&impulse, &onto, s), s), events)))
    }

    /// G_x·P of the jump at guard `k` from `x`, by central differences of the jump alone on
    /// the problem itself, its modes put back after each.
    fn differenced_jump(
        &mut self,
        t: f64,
        x: &[f64],
        k: usize,
        before: &[f64],
        hx: &[f64],
        rate: f64,
    ) -> Result<Vec<f64>, FaultKind> {
        let s = self.size;
        let h0 = guard_value(self.inner, k, t, x)?;
        let saved = self.inner.modes_state();
        let scale = 1.0 + x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut along = vec![0.0; s * s];
        for i in 0..s {
            // P·eᵢ, scaled to the difference's step.
            let mut d: Vec<f64> = before.iter().map(|f| -f * hx[i] / rate).collect();
            d[i] += 1.0;
            let size = d.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let step = DIFFERENCE * scale / size;
            let mut sides = [Vec::new(), Vec::new()];
            for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
                let mut probe: Vec<f64> =
                    x.iter().zip(&d).map(|(a, b)| a + sign * step * b).collect();
                let copy = &mut *self.inner;
                // Back onto the manifold the mode before the jump holds the state on, and onto
                // the guard's surface along f⁻: there the jump sees the contacts the located
                // one did (a closed contact's rate a difference's step off its manifold would
                // be far outside its band, and open it). Across that manifold, G_x is taken as
                // the jump of the state projected onto it, which is what the stabilisation
                // keeps a run's state within rounding of.
                for _ in 0..2 {
                    copy.project_positions(t, &mut probe)?;
                    copy.project_velocities(t, &mut probe)?;
                    let off = (guard_value(copy, k, t, &probe)? - h0) / rate;
                    for (p, f) in probe.iter_mut().zip(before) {
                        *p -= f * off;
                    }
                }
                let jumped = copy.jump(t, &mut probe, &[k]);
                copy.restore_modes(&saved);
                jumped?;
                *side = probe;
            }
            for r in 0..s {
                along[r * s + i] = (sides[0][r] - sides[1][r]) / (2.0 * step);
            }
        }
        Ok(along)
    }
}

impl Problem for Variational<'_> {
    fn dim(&self) -> usize {
        self.size + self.size * self.directions + self.size * self.columns
    }

    fn controlled(&self) -> usize {
        match self.step_control {
            StepControl::Everything => self.dim(),
            StepControl::State => self.size,
        }
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        let s = self.size;
        let n = s / 2;
        let (x, phi) = y.split_at(s);
        let c = self.directions;
        let (phi, sensitivities) = phi.split_at(s * c);
        let columns = self.columns;
        let (rates, d) = dy.split_at_mut(s);
        if c == 0 && columns == 0 {
            // The state alone: no Jacobian to form.
            return self.inner.kept_rates(t, x, rates);
        }
        let change = (columns > 0).then_some(&mut self.change[..]);
        if !self.inner.variational_parts(t, x, rates, &mut self.jac, change)? {
            return Err(FaultKind::NonFinite { at: crate::NonFiniteAt::Partials });
        }
        // A = [0 I; ∂q̈/∂q ∂q̈/∂q̇]: the upper rows of AΦ are the lower rows of Φ.
        d[..n * c].copy_from_slice(&phi[n * c..]);
        let jac = &self.jac;
        // The small widths with the width a constant, the sums in registers (a wheel's six
        // columns had cost ten instructions a product so).
        match c {
            2 => lower_rows::<2>(jac, phi, d, n, s),
            4 => lower_rows::<4>(jac, phi, d, n, s),
            6 => lower_rows::<6>(jac, phi, d, n, s),
            8 => lower_rows::<8>(jac, phi, d, n, s),
            _ => lower_rows_of(jac, phi, d, n, s, c),
        }
        if columns == 0 {
            return Ok(());
        }
        // Ṡ = A·S + (0, ∂q̈/∂p): the upper rows are S's lower rows, as for Φ.
        let d = &mut dy[s + s * c..];
        d[..n * columns].copy_from_slice(&sensitivities[n * columns..]);
        for i in n..s {
            let a = &self.jac[i * s..(i + 1) * s];
            for j in 0..columns {
                let mut acc = self.change[(i - n) * columns + j];
                for k in 0..s {
                    acc += a[k] * sensitivities[k * columns + j];
                }
                d[i * columns + j] = acc;
            }
        }
        Ok(())
    }

    fn observations(&self) -> usize {
        0
    }

    fn observe(&mut self, _: f64, _: &[f64], _: &mut [f64]) -> Result<(), FaultKind> {
        Ok(())
    }

    /// The problem's own next sample (a series' knot, where its slope changes, or a held
    /// law's): a step ends there. The times to record at are the dense output's
    /// ([`Problem::recorded_times`]), and end no step.
    fn next_sample(&self, t: f64) -> Option<f64> {
        self.inner.next_sample(t)
    }

    /// The problem's own sample (a held law's) changes its right-hand side, not the state: Φ
    /// and S go on through it.
    fn sample(&mut self, t: f64, y: &mut [f64]) -> Result<(), FaultKind> {
        self.inner.sample(t, &mut y[..self.size])
    }

    fn recorded_times(&self) -> &[f64] {
        self.times
    }

    /// x, Φ and S at a time to record at: from the dense output between steps, whose Φ and S
    /// are the derivatives of its x (the interpolant is linear in the stages, and the stages'
    /// Φ and S are their x's derivatives), or the exact state at the start and the end.
    fn record(&mut self, t: f64, y: &[f64]) {
        let (s, carried) = (self.size, self.size + self.size * self.directions);
        self.samples.push(Sample {
            time: t,
            state: y[..s].to_vec(),
            matrix: y[s..carried].to_vec(),
            sensitivities: self.carries.then(|| y[carried..].to_vec()),
        });
    }

    fn physical(&mut self, _: f64, y: &[f64]) -> Vec<f64> {
        y.to_vec()
    }

    fn guards(&self) -> usize {
        self.inner.guards() + usize::from(matches!(self.end, End::Crossing { .. }))
    }

    /// A contact's guard asked of the problem alone (an open contact's gap needs no solve);
    /// the section's as [`Problem::guard_values`] gives it.
    fn guard_value(
        &mut self,
        t: f64,
        y: &[f64],
        k: usize,
        scratch: &mut [f64],
    ) -> Result<f64, FaultKind> {
        let contacts = self.inner.guards();
        if k < contacts {
            return self.inner.guard_value(t, &y[..self.size], k, &mut scratch[..contacts]);
        }
        self.guard_values(t, y, scratch)?;
        Ok(scratch[k])
    }

    fn guard_values(&mut self, t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        let contacts = self.inner.guards();
        let x = &y[..self.size];
        self.inner.guard_values(t, x, &mut out[..contacts])?;
        if let End::Crossing { rising, .. } = self.end {
            let h = self.section(t, x)?;
            let ahead = if rising { -h } else { h };
            if !self.armed && ahead > ARMING * self.length {
                self.armed = true;
            }
            // Unarmed, the guard stays below zero: no crossing is seen.
            out[contacts] = if self.armed { ahead } else { -1.0 };
        }
        Ok(())
    }

    fn begin_modes(
        &mut self,
        t: f64,
        y: &mut [f64],
        tolerance: f64,
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let s = self.size;
        let events = self.inner.begin_modes_held(t, &mut y[..s], tolerance)?;
        let x = y[..s].to_vec();
        if let End::Crossing { column, .. } = self.end {
            let (inner, observed) = (&mut *self.inner, &mut self.observed);
            let (hx, _) =
                gradient(t, &x, &mut |t, x| section_value(inner, observed, column, t, x))?;
            let size = x.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
            self.length = hx.iter().map(|v| v.abs()).sum::<f64>() * size;
        }
        let rate = rate_of(self.inner, t, &x)?;
        let normals = self.inner.manifold_normals(t, &x)?.unwrap_or_default();
        self.begun = Some((x, rate, normals));
        Ok(events)
    }

    fn jump(
        &mut self,
        t: f64,
        y: &mut [f64],
        fired: &[usize],
    ) -> Result<Vec<ModeEvent>, FaultKind> {
        let s = self.size;
        let contacts = self.inner.guards();
        let guards: Vec<Guard> = fired
            .iter()
            .map(|&k| {
                if k < contacts {
                    Guard::Contacts(self.inner.watched_by(k))
                } else {
                    Guard::Section
                }
            })
            .collect();
        if guards.len() > 1 {
            return self.refuse(Refusal::Simultaneous { time: t, guards });
        }
        if self.columns > 0 {
            let guard = guards[0];
            return self.refuse(Refusal::SensitivitiesAcrossJump { time: t, guard });
        }
        let x = y[..s].to_vec();
        let c = self.directions;
        let landed = |end: End, e: &ModeEvent| {
            e.kind == ModeChange::Impact
                && matches!(end, End::Landing { contact } if contact.is_none_or(|c| c == e.contact))
        };
        // A run carrying the state alone needs no jump's derivative but that of the landing
        // that ends it (its surface): any other jump is taken as it is, without the guard's
        // gradient (differences of a reaction, eighteen solves) or G_x. A jump that turns out
        // to end the run is taken again from where it started, with its derivative.
        if c == 0 && matches!(guards[0], Guard::Contacts(_)) {
            let saved = self.inner.modes_state();
            let events = self.inner.jump(t, &mut y[..s], fired)?;
            if !events.iter().any(|e| landed(self.end, e)) {
                self.jumps += 1;
                return Ok(events);
            }
            y[..s].copy_from_slice(&x);
            self.inner.restore_modes(&saved);
        }
        let phi = y[s..s + s * c].to_vec();
        let before = rate_of(self.inner, t, &x)?;
        let Guard::Contacts(_) = guards[0] else {
            let End::Crossing { column, .. } = self.end else { unreachable!("a section fired") };
            let (inner, observed) = (&mut *self.inner, &mut self.observed);
            let (hx, ht) =
                gradient(t, &x, &mut |t, x| section_value(inner, observed, column, t, x))?;
            let (rate, relative) = crossing_rate(&hx, ht, &before);
            if relative < GRAZING {
                return self.refuse(Refusal::Grazing { time: t, guard: Guard::Section, relative });
            }
            let matrix = along_surface(&phi, &before, &hx, rate, s);
            let within = manifold_projection(self.inner, t, &x)?;
            let surface = product(&along_surface(&identity(s), &before, &hx, rate, s), &within, s);
            self.capture(t, x, matrix, surface);
            return Ok(Vec::new());
        };
        let k = fired[0];
        // The gradient of a gap is its normal row's, exact; any other guard's (a reaction, a
        // stick or a slip, an arming condition) is central differences of it.
        let exact_gradient = match self.saltation {
            Saltation::Exact => self.inner.gap_gradient(t, &x, k)?,
            Saltation::Differences => None,
        };
        let (hx, ht) = match exact_gradient.clone() {
            Some(gradient) => gradient,
            None => {
                let inner = &mut *self.inner;
                gradient(t, &x, &mut |t, x| guard_value(inner, k, t, x))?
            }
        };
        let (rate, relative) = crossing_rate(&hx, ht, &before);
        if relative < GRAZING {
            let guard = guards[0];
            return self.refuse(Refusal::Grazing { time: t, guard, relative });
        }
        let within = manifold_projection(self.inner, t, &x)?;
        let saved = self.inner.modes_state();
        // The jump itself is exact whatever its guard (a lift-off, a stick or a slip, an arming
        // moves no state: its impulse is none); the guard's gradient may be differences.
        let exact = match self.saltation {
            Saltation::Exact => self.exact_jump(t, y, k, &before, &hx, rate)?,
            Saltation::Differences => None,
        };
        let (along, events) = match exact {
            Some(done) => {
                self.exact_jumps += 1;
                done
            }
            None => {
                // Back to the state and the modes before the jump, to difference it there.
                y[..s].copy_from_slice(&x);
                self.inner.restore_modes(&saved);
                let along = self.differenced_jump(t, &x, k, &before, &hx, rate)?;
                (along, self.inner.jump(t, &mut y[..s], &[k])?)
            }
        };
        let after = rate_of(self.inner, t, &y[..s])?;
        self.jumps += 1;
        let mut carried = vec![0.0; s * c];
        for i in 0..s {
            for j in 0..c {
                carried[i * c + j] = (0..s).map(|r| along[i * s + r] * phi[r * c + j]).sum();
            }
        }
        if events.iter().any(|e| landed(self.end, e)) {
            self.capture(t, y[..s].to_vec(), carried, product(&along, &within, s));
            return Ok(events);
        }
        // Ξ·Φ = G_x·P·Φ + f⁺·(h_xᵀ·Φ)/ḣ.
        for j in 0..c {
            let moved: f64 = (0..s).map(|r| hx[r] * phi[r * c + j]).sum::<f64>() / rate;
            for i in 0..s {
                y[s + i * c + j] = carried[i * c + j] + after[i] * moved;
            }
        }
        Ok(events)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crossing_along_its_surface_is_grazing_and_across_it_is_not() {
        // h = x₀: the flow nearly along the surface, then across it.
        let (_, along) = crossing_rate(&[1.0, 0.0], 0.0, &[1e-9, 1.0]);
        assert!(along < GRAZING, "{along}");
        let (rate, across) = crossing_rate(&[1.0, 0.0], 0.0, &[-0.5, 0.5]);
        assert!(across > 0.5 && rate == -0.5, "{rate} {across}");
        // A moving surface: h = x₀ − t met at rest is no grazing.
        let (rate, moving) = crossing_rate(&[1.0, 0.0], -1.0, &[0.0, 0.0]);
        assert!(rate == -1.0 && moving == 1.0);
    }

    #[test]
    fn the_projection_along_the_flow_keeps_the_surface() {
        // P·Φ with Φ = I: h_x·P = 0, and P·f = 0.
        let (f, hx) = ([2.0, 1.0], [1.0, 3.0]);
        let rate = dot(&hx, &f);
        let p = along_surface(&identity(2), &f, &hx, rate, 2);
        for j in 0..2 {
            assert!((hx[0] * p[j] + hx[1] * p[2 + j]).abs() < 1e-15);
        }
        for i in 0..2 {
            assert!((p[i * 2] * f[0] + p[i * 2 + 1] * f[1]).abs() < 1e-15);
        }
    }
}
