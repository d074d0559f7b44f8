//! A run: steps of one method from the start to the end time, the observations recorded at
//! each accepted step, and events located on the dense output.

use std::ops::ControlFlow;

use crate::stepper::Dense;
use crate::{Fault, FaultKind, Method, ModeEvent, Problem};

#[derive(Clone, Debug)]
pub struct Settings {
    pub method: Method,
    pub start: f64,
    pub until: f64,
    /// Relative and absolute tolerance of the adaptive methods: one accuracy whichever of
    /// them runs, each holding its local error estimate to the level that makes its final
    /// error follow the tolerance alike ([`Radau::new`], `Pair::error_target`).
    pub tolerance: f64,
    /// The step of the fixed-step methods.
    pub step: f64,
    pub max_steps: usize,
    /// Record at this many evenly spaced times from the start to the end, both included (from
    /// the dense output), rather than at every accepted step; 0 records at every step. Events
    /// and the end are recorded either way.
    pub samples: usize,
}

/// A zero crossing to watch: of observation `column`; `stop` ends the run there.
#[derive(Clone, Copy, Debug)]
pub struct Event {
    pub column: usize,
    pub stop: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EventHit {
    /// Index into the events of the run.
    pub event: usize,
    pub time: f64,
}

/// The observations of a run, one row per recorded time.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    pub times: Vec<f64>,
    pub rows: Vec<Vec<f64>>,
}

/// Where a run's recorded rows go, each as it is made, in time order: a run that hands them
/// on ([`integrate_into`]) keeps none, so its memory does not grow with the samples.
pub trait Rows {
    /// The observations `row` recorded at time `t`.
    fn row(&mut self, t: f64, row: &[f64]);
}

/// The rows kept: what [`integrate`] records.
impl Rows for Trajectory {
    fn row(&mut self, t: f64, row: &[f64]) {
        self.times.push(t);
        self.rows.push(row.to_vec());
    }
}

#[derive(Clone, Debug)]
pub struct Run {
    pub trajectory: Trajectory,
    pub steps: usize,
    pub rejected: usize,
    pub evaluations: usize,
    /// Accepted steps whose size stability, not accuracy, decided (adaptive methods): many
    /// of them mean the system is stiff for an explicit method.
    pub stiff_steps: usize,
    /// Jacobians evaluated and LU factorizations of iteration matrices (radau).
    pub jacobians: usize,
    pub factorizations: usize,
    /// The largest |value| of each observation at the start and the accepted steps: the
    /// integrator's own points, where a recorded sample may come from the dense output.
    pub peaks: Vec<f64>,
    /// The least and the greatest value of each observation over the run: at the start, the
    /// accepted steps before the end, and the end (a stop's point, not the step past it).
    pub extremes: Vec<(f64, f64)>,
    pub events: Vec<EventHit>,
    /// The jumps of the problem's modes, in time order: contacts landing, settling, closing
    /// and lifting off ([`Problem::jump`]). A jump's time has two recorded rows, the one
    /// before it and the one after.
    pub modes: Vec<ModeEvent>,
    /// The stop event that ended the run, if one did.
    pub stopped_by: Option<usize>,
    pub fault: Option<Fault>,
    /// The final state in physical variables (q, q̇).
    pub final_state: Vec<f64>,
    pub final_time: f64,
    /// Which method ran over which span of time, in order: one segment, unless `auto`
    /// switched.
    pub segments: Vec<Segment>,
    /// The progress callback asked the run to stop (a front end's Ctrl-C): it ended at
    /// `final_time`, with what was computed up to there.
    pub interrupted: bool,
}

/// A span of a run integrated by one method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub method: Method,
    pub start: f64,
    pub end: f64,
}

/// Integrates `problem` from `y0` at `settings.start` to `settings.until`, recording the
/// observations at every accepted step (and at located events). A problem that samples held
/// inputs ([`Problem::next_sample`]) is sampled at the start and at each sample time, where a
/// step ends and the method restarts. A problem with guards ([`Problem::guards`]: one-sided
/// contacts) decides its mode at the start ([`Problem::begin_modes`]); where a guard reaches
/// zero inside a step, the step is cut there, the rows before and after the jump
/// ([`Problem::jump`]) are recorded at its time, and the method restarts ([`Run::modes`]). A fault ends the run early: what was computed up to it
/// is kept, and the fault says when and where. `progress` is told the time after every
/// accepted step and may end the run there ([`Run::interrupted`]); it is the one hook a front
/// end has into the loop, so a check it makes should be cheap or throttled.
pub fn integrate(
    problem: &mut dyn Problem,
    y0: &[f64],
    settings: &Settings,
    events: &[Event],
    progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
) -> Run {
    integrate_to(problem, y0, settings, events, progress, None)
}

/// [`integrate`], handing each recorded row to `rows` as it is made rather than keeping it:
/// the run's [`Trajectory`] is left empty, and the rows are the ones [`integrate`] would
/// have kept, in the same order, with the same bits.
pub fn integrate_into(
    problem: &mut dyn Problem,
    y0: &[f64],
    settings: &Settings,
    events: &[Event],
    progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
    rows: &mut dyn Rows,
) -> Run {
    integrate_to(problem, y0, settings, events, progress, Some(rows))
}

fn integrate_to(
    problem: &mut dyn Problem,
    y0: &[f64],
    settings: &Settings,
    events: &[Event],
    progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
    rows: Option<&mut dyn Rows>,
) -> Run {
    let mut stepper = settings.method.stepper(settings, problem);
    let mut course = match Course::begin(problem, y0, settings) {
        Ok(course) => course,
        Err(run) => return *run,
    };
    course.send_to(rows);
    while course.t < settings.until {
        if course.run.steps >= settings.max_steps {
            course.fail(problem, FaultKind::TooManySteps { limit: settings.max_steps });
            break;
        }
        let t0 = course.t;
        let t_end = course.step_end(settings);
        match stepper.advance(problem, course.t, &mut course.y, t_end) {
            Ok(t1) => course.t = t1,
            Err(kind) => {
                course.fail(problem, kind);
                break;
            }
        }
        if course.after_step(problem, stepper.as_mut(), events, t0, progress).is_break() {
            break;
        }
    }
    let counts = Counts {
        evaluations: stepper.evaluations(),
        rejected: stepper.rejected(),
        stiff_steps: stepper.stiff_steps(),
        jacobians: stepper.jacobians(),
        factorizations: stepper.factorizations(),
    };
    let segments = segments(settings, stepper.switches(), course.t);
    course.finish(problem, counts, segments)
}

/// What a method counted over a run.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Counts {
    pub evaluations: usize,
    pub rejected: usize,
    pub stiff_steps: usize,
    pub jacobians: usize,
    pub factorizations: usize,
}

/// A run under way: its time and state, and what it has recorded, between the steps of its
/// method. [`integrate`] takes its steps one after another; the lockstep ensemble takes the
/// steps of several runs at once and hands each of them here alike.
pub(crate) struct Course<'r> {
    pub run: Run,
    /// Where the rows go when they are not kept in the run's trajectory.
    sink: Option<&'r mut dyn Rows>,
    pub t: f64,
    pub y: Vec<f64>,
    row: Vec<f64>,
    previous_row: Vec<f64>,
    next_sample: Option<f64>,
    sampler: Sampler,
    until: f64,
    samples: usize,
    /// The problem's guards at the current time and state ([`Problem::guards`]).
    guards: Vec<f64>,
    /// The time of the last jump, and how many jumps in a row were at that time.
    jumped: (f64, usize),
    /// The guards at a step's end, a located guard's values and the state at a probe: kept
    /// from step to step (allocated at every step, they were a fifth of a walker's mallocs).
    scratch: [Vec<f64>; 3],
}

/// The most jumps in a row at one time before a run says its modes chatter there.
const CHATTER: usize = 64;

impl<'r> Course<'r> {
    /// Starts a run at `y0` (sampling a held input there): the start recorded, or the run
    /// ended by the fault met there.
    pub fn begin(
        problem: &mut dyn Problem,
        y0: &[f64],
        settings: &Settings,
    ) -> Result<Course<'r>, Box<Run>> {
        let t = settings.start;
        let mut run = Run {
            trajectory: Trajectory::default(),
            steps: 0,
            rejected: 0,
            evaluations: 0,
            stiff_steps: 0,
            jacobians: 0,
            factorizations: 0,
            peaks: Vec::new(),
            extremes: Vec::new(),
            events: Vec::new(),
            modes: Vec::new(),
            stopped_by: None,
            fault: None,
            final_state: Vec::new(),
            final_time: t,
            segments: Vec::new(),
            interrupted: false,
        };
        let mut y = y0.to_vec();
        let mut row = vec![0.0; problem.observations()];
        let mut guards = vec![0.0; problem.guards()];
        // A held input's first sample is at the start.
        let next_sample = problem.next_sample(t);
        // The modes are decided at the start: an impulse there (a contact landing at the
        // start) is an impact at the start, recorded with a row before it (the given state, in
        // the mode decided) and one after.
        let mut before = None;
        let started = problem.sample(t, &mut y).and_then(|()| {
            if !guards.is_empty() {
                let given = y.clone();
                run.modes = problem.begin_modes(t, &mut y, settings.tolerance)?;
                let struck =
                    |m: &ModeEvent| m.impulse != 0.0 || m.tangential.is_some_and(|l| l != 0.0);
                if run.modes.iter().any(struck) {
                    let mut open = vec![0.0; row.len()];
                    problem.observe(t, &given, &mut open)?;
                    before = Some(open);
                }
                problem.guard_values(t, &y, &mut guards)?;
            }
            problem.observe(t, &y, &mut row)
        });
        if let Err(kind) = started {
            run.fault = Some(fault(problem, kind, t, &y));
            run.final_state = problem.physical(t, &y);
            return Err(Box::new(run));
        }
        run.peaks = row.iter().map(|v| v.abs()).collect();
        run.extremes = row.iter().map(|v| (*v, *v)).collect();
        if let Some(open) = before {
            widen(&mut run.extremes, &open);
            for (peak, v) in run.peaks.iter_mut().zip(&open) {
                *peak = peak.max(v.abs());
            }
            run.trajectory.times.push(t);
            run.trajectory.rows.push(open);
        }
        run.trajectory.times.push(t);
        run.trajectory.rows.push(row.clone());
        let sampler = Sampler::new(settings, problem, t, &y);
        Ok(Course {
            run,
            sink: None,
            t,
            y,
            previous_row: row.clone(),
            row,
            next_sample,
            sampler,
            until: settings.until,
            samples: settings.samples,
            scratch: [vec![0.0; guards.len()], vec![0.0; guards.len()], vec![0.0; problem.dim()]],
            guards,
            jumped: (f64::NAN, 0),
        })
    }

    /// Hands the rows recorded so far (the start's) and every later one to `rows`, where
    /// given, rather than keeping them.
    fn send_to(&mut self, rows: Option<&'r mut dyn Rows>) {
        if let Some(rows) = rows {
            let kept = std::mem::take(&mut self.run.trajectory);
            for (t, row) in kept.times.iter().zip(&kept.rows) {
                rows.row(*t, row);
            }
            self.sink = Some(rows);
        }
    }

    /// Where the next step must end at the latest: the end of the run or the next sample of
    /// a held input.
    pub fn step_end(&self, settings: &Settings) -> f64 {
        self.next_sample.map_or(settings.until, |s| s.min(settings.until))
    }

    /// Ends the run with `kind` at the current time and state.
    pub fn fail(&mut self, problem: &mut dyn Problem, kind: FaultKind) {
        self.run.fault = Some(fault(problem, kind, self.t, &self.y));
    }

    /// Records the step just accepted from `t0` to the current time: observes there, locates
    /// the events the step crossed on `dense` and records the samples it covers. Breaks when
    /// the run ends here: at a stop, a fault, or when `progress` says so.
    pub fn after_step(
        &mut self,
        problem: &mut dyn Problem,
        dense: &mut dyn Dense,
        events: &[Event],
        t0: f64,
        progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let run = &mut self.run;
        run.steps += 1;
        let t = self.t;
        if let Err(kind) = problem.observe(t, &self.y, &mut self.row) {
            self.fail(problem, kind);
            return ControlFlow::Break(());
        }
        // A guard that reached zero: the step is cut at the first, where the mode jumps.
        let jump = match self.guard_crossing(problem, dense, t0) {
            Ok(jump) => jump,
            Err(kind) => {
                self.fail(problem, kind);
                return ControlFlow::Break(());
            }
        };
        let run = &mut self.run;
        let mut hits = crossings(problem, dense, events, (t0, &self.previous_row), (t, &self.row));
        match &jump {
            Some((at, _)) => hits.retain(|h| h.time <= *at),
            None => {
                for (peak, v) in run.peaks.iter_mut().zip(&self.row) {
                    *peak = peak.max(v.abs());
                }
            }
        }
        // The evenly spaced times this step covers, up to a stop or a jump if one comes.
        let cut = jump.as_ref().map_or(t, |(at, _)| *at);
        let end = hits.iter().find(|h| events[h.event].stop).map_or(cut, |h| h.time);
        let held_from = self.next_sample.filter(|s| *s == end);
        // A recorded time within rounding of a sample is the sample's: it shows the new held
        // value, recorded after the jump (k·T and the evenly spaced times may differ by an ulp).
        let before = held_from.map_or(end, |s| s - 4.0 * f64::EPSILON * s.abs().max(1.0));
        let rows = rows_of(&mut self.sink, &mut run.trajectory);
        self.sampler.record(problem, dense, before, rows);
        if let Some(stop) = hits.iter().position(|h| events[h.event].stop) {
            let hit = hits[stop];
            run.events.extend_from_slice(&hits[..=stop]);
            dense.interpolate(problem, hit.time, &mut self.y);
            self.t = hit.time;
            if let Err(kind) = problem.observe(self.t, &self.y, &mut self.row) {
                self.fail(problem, kind);
                return ControlFlow::Break(());
            }
            widen(&mut run.extremes, &self.row);
            rows_of(&mut self.sink, &mut run.trajectory).row(self.t, &self.row);
            run.stopped_by = Some(hit.event);
            return ControlFlow::Break(());
        }
        if let Some((at, fired)) = jump {
            run.events.extend(hits);
            return self.jump(problem, dense, at, &fired, progress);
        }
        widen(&mut run.extremes, &self.row);
        run.events.extend(hits);
        // The step ended on a sample: the held values change, and so the right-hand side;
        // the row recorded here shows the new ones, as the hold gives them from now on.
        if held_from.is_some() {
            let sampled = problem
                .sample(t, &mut self.y)
                .and_then(|()| problem.observe(t, &self.y, &mut self.row));
            if let Err(kind) = sampled {
                self.fail(problem, kind);
                return ControlFlow::Break(());
            }
            dense.after_jump();
            self.next_sample = problem.next_sample(t);
        }
        if self.samples == 0 || t >= self.until {
            rows_of(&mut self.sink, &mut self.run.trajectory).row(t, &self.row);
        }
        if t >= self.until {
            self.sampler.record_at_end(problem, t, &self.y);
        }
        std::mem::swap(&mut self.previous_row, &mut self.row);
        if progress(t).is_break() {
            self.run.interrupted = true;
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    /// The guards that went from > 0 to ≤ 0 over the step from `t0` to the current time, if
    /// any: the first time one reached zero, located on the dense output, with every guard
    /// that reached zero within rounding of it (they fire together). The time is the last
    /// one located at which the guard was still positive, so that after the jump the guards
    /// of the new mode start from where they hold. Without a jump the guards are kept at the
    /// step's end.
    fn guard_crossing(
        &mut self,
        problem: &mut dyn Problem,
        dense: &mut dyn Dense,
        t0: f64,
    ) -> Result<Option<(f64, Vec<usize>)>, FaultKind> {
        let count = self.guards.len();
        if count == 0 {
            return Ok(None);
        }
        let [now, values, y] = &mut self.scratch;
        problem.guard_values(self.t, &self.y, now)?;
        let mut found: Vec<(usize, f64)> = Vec::new();
        for k in 0..count {
            if self.guards[k] > 0.0 && now[k] <= 0.0 {
                let mut guard = |p: &mut dyn Problem, d: &mut dyn Dense, s: f64| {
                    d.interpolate(p, s, y);
                    p.guard_value(s, y, k, values).ok()
                };
                let ((a, _), _) =
                    bracket(problem, dense, &mut guard, (t0, self.guards[k]), (self.t, now[k]));
                found.push((k, a));
            }
        }
        let Some(first) = found.iter().map(|f| f.1).reduce(f64::min) else {
            std::mem::swap(&mut self.guards, now);
            return Ok(None);
        };
        let window = 16.0 * f64::EPSILON * first.abs().max(1.0);
        let fired = found.iter().filter(|f| f.1 <= first + window).map(|f| f.0).collect();
        Ok(Some((first, fired)))
    }

    /// Jumps at `at`, where the guards `fired` reached zero inside the last step: moves the
    /// state there, records the row before the jump, jumps, records the row after it (at the
    /// same time), and restarts the method.
    fn jump(
        &mut self,
        problem: &mut dyn Problem,
        dense: &mut dyn Dense,
        at: f64,
        fired: &[usize],
        progress: &mut dyn FnMut(f64) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        self.jumped = if self.jumped.0 == at { (at, self.jumped.1 + 1) } else { (at, 1) };
        if self.jumped.1 > CHATTER {
            let kind = FaultKind::ModesChatter { guards: fired.to_vec(), jumps: self.jumped.1 - 1 };
            self.fail(problem, kind);
            return ControlFlow::Break(());
        }
        dense.interpolate(problem, at, &mut self.y);
        self.t = at;
        let jumped = problem.observe(at, &self.y, &mut self.row).and_then(|()| {
            self.note_row();
            let modes = problem.jump(at, &mut self.y, fired)?;
            self.run.modes.extend(modes);
            // A held input's sample due at the same time is taken after the jump.
            if self.next_sample == Some(at) {
                problem.sample(at, &mut self.y)?;
                self.next_sample = problem.next_sample(at);
            }
            problem.observe(at, &self.y, &mut self.row)?;
            self.note_row();
            problem.guard_values(at, &self.y, &mut self.guards)
        });
        if let Err(kind) = jumped {
            self.fail(problem, kind);
            return ControlFlow::Break(());
        }
        dense.after_switch();
        self.previous_row.clone_from(&self.row);
        if progress(at).is_break() {
            self.run.interrupted = true;
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    /// Records the current row, always (a jump's rows are recorded whether or not the run
    /// samples), with its peaks and extremes.
    fn note_row(&mut self) {
        let run = &mut self.run;
        for (peak, v) in run.peaks.iter_mut().zip(&self.row) {
            *peak = peak.max(v.abs());
        }
        widen(&mut run.extremes, &self.row);
        rows_of(&mut self.sink, &mut run.trajectory).row(self.t, &self.row);
    }

    /// The run as it ended, with what its method counted and the spans of its methods.
    pub fn finish(
        mut self,
        problem: &mut dyn Problem,
        counts: Counts,
        segments: Vec<Segment>,
    ) -> Run {
        let run = &mut self.run;
        run.evaluations = counts.evaluations;
        run.rejected = counts.rejected;
        run.stiff_steps = counts.stiff_steps;
        run.jacobians = counts.jacobians;
        run.factorizations = counts.factorizations;
        run.final_time = self.t;
        run.final_state = problem.physical(self.t, &self.y);
        run.segments = segments;
        self.run
    }
}

/// Where a run's rows go: its sink, else its own trajectory.
fn rows_of<'a>(sink: &'a mut Option<&mut dyn Rows>, kept: &'a mut Trajectory) -> &'a mut dyn Rows {
    match sink {
        Some(rows) => &mut **rows,
        None => kept,
    }
}

/// Takes each observation's value in `row` into its least and greatest.
fn widen(extremes: &mut [(f64, f64)], row: &[f64]) {
    for ((least, greatest), v) in extremes.iter_mut().zip(row) {
        *least = least.min(*v);
        *greatest = greatest.max(*v);
    }
}

/// A fault at (t, y), with the state in the physical variables.
fn fault(problem: &mut dyn Problem, kind: FaultKind, t: f64, y: &[f64]) -> Fault {
    Fault { kind, time: t, state: problem.physical(t, y) }
}

/// The watched columns' sign changes over the step from `before` to `after` (each a time and
/// its recorded row), located on the dense output, in time order.
fn crossings(
    problem: &mut dyn Problem,
    stepper: &mut dyn Dense,
    events: &[Event],
    before: (f64, &[f64]),
    after: (f64, &[f64]),
) -> Vec<EventHit> {
    let width = problem.observations();
    let mut hits: Vec<EventHit> = Vec::new();
    for (k, e) in events.iter().enumerate() {
        let (mut start, mut end) = ((before.0, before.1[e.column]), (after.0, after.1[e.column]));
        // A function that leaves its domain within the step (√ of a negative) has no sign at
        // one end; it may have crossed zero before it did. The sign change is looked for up
        // to where it is still finite, as it would have been seen by a step ending there.
        match (start.1.is_finite(), end.1.is_finite()) {
            (true, false) => end = finite_edge(problem, stepper, e.column, start, end.0, width),
            (false, true) => start = finite_edge(problem, stepper, e.column, end, start.0, width),
            _ => {}
        }
        let (g0, g1) = (start.1, end.1);
        if g0 != 0.0 && g0 * g1 <= 0.0 {
            let mut y = vec![0.0; problem.dim()];
            let mut row = vec![0.0; width];
            let mut value = |p: &mut dyn Problem, d: &mut dyn Dense, s: f64| {
                d.interpolate(p, s, &mut y);
                p.observe(s, &y, &mut row).ok().map(|()| row[e.column])
            };
            let ((a, ga), (b, gb)) = bracket(problem, stepper, &mut value, start, end);
            let time = if gb == 0.0 || ga.abs() >= gb.abs() { b } else { a };
            hits.push(EventHit { event: k, time });
        }
    }
    hits.sort_by(|a, b| a.time.total_cmp(&b.time));
    hits
}

/// The evenly spaced times a run records from the dense output: `samples` of them from the
/// start to the end, both included, as numpy.linspace counts them (`samples − 1` intervals;
/// one sample is the start, and the end is recorded anyway). No samples: every step instead.
struct Sampler {
    start: f64,
    until: f64,
    intervals: usize,
    /// The next sample to record; past `intervals` when done or not sampling.
    next: usize,
    /// The problem's own times ([`Problem::recorded_times`]), and the next of them to record.
    own: Vec<f64>,
    next_own: usize,
    /// The dense output's state at one of them.
    scratch: Vec<f64>,
}

impl Sampler {
    /// The sampler of a run from (t, y), which records the problem's own times at t there.
    fn new(settings: &Settings, problem: &mut dyn Problem, t: f64, y: &[f64]) -> Self {
        let intervals = settings.samples.saturating_sub(1).max(1);
        let next = if settings.samples > 0 { 1 } else { usize::MAX };
        let own = problem.recorded_times().to_vec();
        let mut next_own = 0;
        while own.get(next_own).is_some_and(|s| *s <= t) {
            if own[next_own] == t {
                problem.record(t, y);
            }
            next_own += 1;
        }
        let scratch = if own.is_empty() { Vec::new() } else { vec![0.0; y.len()] };
        Sampler {
            start: settings.start,
            until: settings.until,
            intervals,
            next,
            own,
            next_own,
            scratch,
        }
    }

    /// Records the problem's own times up to `t` inclusive at the exact state `y` there: the
    /// run's end.
    fn record_at_end(&mut self, problem: &mut dyn Problem, t: f64, y: &[f64]) {
        while self.own.get(self.next_own).is_some_and(|s| *s <= t) {
            problem.record(self.own[self.next_own], y);
            self.next_own += 1;
        }
    }

    fn time(&self, k: usize) -> f64 {
        self.start + (self.until - self.start) * k as f64 / self.intervals as f64
    }

    /// Records the samples before `end` that the last step covered.
    fn record(
        &mut self,
        problem: &mut dyn Problem,
        stepper: &mut dyn Dense,
        end: f64,
        rows: &mut dyn Rows,
    ) {
        while self.own.get(self.next_own).is_some_and(|s| *s < end) {
            let s = self.own[self.next_own];
            stepper.interpolate(problem, s, &mut self.scratch);
            problem.record(s, &self.scratch);
            self.next_own += 1;
        }
        // Most steps cover no sample: they allocate nothing.
        if self.next > self.intervals || self.time(self.next) >= end {
            return;
        }
        let mut ys = vec![0.0; problem.dim()];
        let mut row = vec![0.0; problem.observations()];
        while self.next <= self.intervals && self.time(self.next) < end {
            let s = self.time(self.next);
            stepper.interpolate(problem, s, &mut ys);
            if problem.observe(s, &ys, &mut row).is_ok() {
                rows.row(s, &row);
            }
            self.next += 1;
        }
    }
}

/// The spans each method integrated: the whole run for one method; for one that switches
/// (`auto`), its first side and then its sides in turn at each switch.
pub(crate) fn segments(settings: &Settings, switches: &[f64], end: f64) -> Vec<Segment> {
    let sides = settings.method.sides();
    if sides.is_empty() {
        return vec![Segment { method: settings.method, start: settings.start, end }];
    }
    let mut segments = Vec::new();
    let mut start = settings.start;
    for (k, &switch) in switches.iter().enumerate() {
        segments.push(Segment { method: sides[k % sides.len()], start, end: switch });
        start = switch;
    }
    segments.push(Segment { method: sides[switches.len() % sides.len()], start, end });
    segments
}

/// The time nearest `other` on the dense output at which observation `column` is still
/// finite, with its value there, by bisection from `finite` (a time where it is finite) to
/// `other` (where it is not) to a few ulps of time.
fn finite_edge(
    problem: &mut dyn Problem,
    stepper: &mut dyn Dense,
    column: usize,
    mut finite: (f64, f64),
    mut other: f64,
    width: usize,
) -> (f64, f64) {
    let mut y = vec![0.0; problem.dim()];
    let mut row = vec![0.0; width];
    for _ in 0..200 {
        if (other - finite.0).abs() <= 4.0 * f64::EPSILON * finite.0.abs().max(other.abs()).max(1.0)
        {
            break;
        }
        let m = 0.5 * (finite.0 + other);
        stepper.interpolate(problem, m, &mut y);
        match problem.observe(m, &y, &mut row) {
            Ok(()) if row[column].is_finite() => finite = (m, row[column]),
            _ => other = m,
        }
    }
    finite
}

/// A value of the dense output at a time, or `None` where the problem could not give it.
type Value<'a> = dyn FnMut(&mut dyn Problem, &mut dyn Dense, f64) -> Option<f64> + 'a;

/// Narrows [a, b], over which `value` changes sign (or reaches zero at b), to a few ulps of
/// time by the Illinois variant of regula falsi on the dense output: the ends and their values
/// as it left them, a on the side of the value at the first a given, b of the other side (or
/// b where the value is zero).
fn bracket(
    problem: &mut dyn Problem,
    stepper: &mut dyn Dense,
    value: &mut Value<'_>,
    (mut a, mut ga): (f64, f64),
    (mut b, mut gb): (f64, f64),
) -> ((f64, f64), (f64, f64)) {
    let mut side = 0i8;
    for _ in 0..200 {
        if gb == 0.0 {
            break;
        }
        if (b - a).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()).max(1.0) {
            break;
        }
        let mut m = (a * gb - b * ga) / (gb - ga);
        if !(m > a.min(b) && m < a.max(b)) {
            m = 0.5 * (a + b);
        }
        let Some(gm) = value(problem, stepper, m) else {
            // Bisect towards the start, where the state was fine.
            b = m;
            continue;
        };
        if gm == 0.0 {
            // Exactly zero here: the crossing is at m, but the time returned is one where the
            // guard still holds, so the search goes on between a and m (a guard linear in t,
            // a block's slip rate, lands on zero exactly and would leave a at the step's start).
            b = m;
            gb = -ga.signum() * f64::MIN_POSITIVE;
            continue;
        }
        if (gm > 0.0) == (ga > 0.0) {
            a = m;
            ga = gm;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        } else {
            b = m;
            gb = gm;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        }
    }
    ((a, ga), (b, gb))
}
