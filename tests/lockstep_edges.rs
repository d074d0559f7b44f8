//! The lockstep's edges, each against the same runs one at a time: faults met inside a trial
//! (a value not finite, a mass matrix that is not positive definite or singular, a step too
//! small, too many steps), kept constraints solved lane by lane, stops and events located on
//! the dense output, recorded samples, a last step cut short a rounding away from its end,
//! runs that end at their start, a lockstep broken off, and an ensemble's runs picked,
//! interrupted or driven by inputs. Every run must be the same bits in a lane as alone, and
//! each test checks that the case it is about did happen.

use std::ops::ControlFlow;

use ::ensemble::{Ensemble, Options, Table};
use cas::Func;
use engine::input::Vary;
use engine::numbers::prepare;
use numeric::elementary::{apply, sin_cos};
use numeric::Tape;
use sim::{integrate, Event, FaultKind, Job, Lockstep, Mechanical, Method, Run, Settings};

/// A scene's problem observing `observed` (accelerations among them, which the lanes observe
/// from their last stage), with its parameter values and start.
fn problem(source: &str, observed: &[&str]) -> (Mechanical, Vec<f64>, Vec<f64>) {
    let extra: Vec<String> = observed.iter().map(|s| s.to_string()).collect();
    let mut prepared = prepare(source, &extra, engine::Options::default()).expect("loads");
    let parameters = prepared.parameter_values(&[]).expect("parameter values");
    let y0 = prepared.initial_state(&parameters, &[]).expect("a start");
    let dynamics_exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs).expect("lowers");
    let observation =
        prepared.lower(&prepared.observation_inputs(), &prepared.extra).expect("lowers");
    let problem = Mechanical::new(
        prepared.layout,
        Tape::new(dynamics),
        Tape::new(observation),
        parameters.clone(),
    )
    .with_kinds(prepared.stabilisation());
    (problem, parameters, y0)
}

fn settings(method: Method, until: f64, samples: usize, max_steps: usize) -> Settings {
    Settings { method, start: 0.0, until, tolerance: 1e-8, step: 0.01, max_steps, samples }
}

/// Everything a run gives, bit for bit: its floats as bits (NaN's too), and the rest (events,
/// stops, fault kinds, counts, segments, interruption) as printed.
fn fingerprint(run: &Run) -> (Vec<u64>, String) {
    let mut all: Vec<f64> = Vec::new();
    all.extend(&run.trajectory.times);
    run.trajectory.rows.iter().for_each(|r| all.extend(r));
    all.extend(&run.final_state);
    all.push(run.final_time);
    all.extend(&run.peaks);
    run.extremes.iter().for_each(|(a, b)| all.extend([a, b]));
    if let Some(fault) = &run.fault {
        all.push(fault.time);
        all.extend(&fault.state);
    }
    (all.iter().map(|v| v.to_bits()).collect(), format!("{run:?}"))
}

/// The runs of `jobs` in lockstep, by id (`None`: not given back), with `go_on` asked before
/// every trial; and how many jobs it never took.
fn in_lockstep(
    problem: &Mechanical,
    settings: &Settings,
    jobs: &[Job],
    events: &[Event],
    go_on: &mut dyn FnMut() -> ControlFlow<()>,
) -> (Vec<Option<Run>>, usize) {
    let mut lockstep = Lockstep::new(problem, settings).expect("a plain problem runs in lockstep");
    let mut queue = jobs.iter().map(|j| Job {
        id: j.id,
        parameters: j.parameters.clone(),
        state: j.state.clone(),
    });
    let mut runs: Vec<Option<Run>> = vec![None; jobs.len()];
    let mut gave_none = false;
    lockstep.run(
        &mut || {
            assert!(!gave_none, "jobs asked for again after it gave none");
            let job = queue.next();
            gave_none = job.is_none();
            job
        },
        events,
        &mut |id, run| {
            assert!(runs[id].is_none(), "run {id} given twice");
            runs[id] = Some(run);
        },
        go_on,
    );
    (runs, queue.count())
}

fn alone(problem: &Mechanical, settings: &Settings, job: &Job, events: &[Event]) -> Run {
    let mut problem = problem.clone();
    problem.set_parameters(&job.parameters);
    integrate(&mut problem, &job.state, settings, events, &mut |_| ControlFlow::Continue(()))
}

/// Runs `jobs` in lockstep and one at a time; asserts each is the same bits both ways and
/// gives the runs.
fn same_as_alone(
    what: &str,
    problem: &Mechanical,
    settings: &Settings,
    jobs: &[Job],
    events: &[Event],
) -> Vec<Run> {
    let (side_by_side, left) =
        in_lockstep(problem, settings, jobs, events, &mut || ControlFlow::Continue(()));
    assert_eq!(left, 0, "{what}: jobs left untaken");
    jobs.iter()
        .zip(side_by_side)
        .map(|(job, lane)| {
            let lane = lane.unwrap_or_else(|| panic!("{what}: run {} lost", job.id));
            let alone = alone(problem, settings, job, events);
            let (a, b) = (fingerprint(&lane), fingerprint(&alone));
            assert!(a.1 == b.1, "{what}, run {}:\nlockstep {}\nalone    {}", job.id, a.1, b.1);
            assert!(a.0 == b.0, "{what}, run {}: the bits differ", job.id);
            alone
        })
        .collect()
}

/// Jobs at the scene's start with the parameters `values` gives per run.
fn jobs_from(y0: &[f64], values: Vec<Vec<f64>>) -> Vec<Job> {
    values
        .into_iter()
        .enumerate()
        .map(|(id, parameters)| Job { id, parameters, state: y0.to_vec() })
        .collect()
}

/// A particle in the plane: an anti-spring that throws x off to infinity in finite time (k),
/// and a push that stops being a number at t = c.
const FAULTS: &str = "scene \"Faults\"\n\
    param m = 1 kg, g = 1 m/s^2, k = 0 N/m^3, c = 10 s, F = 1/2 N\n\
    coord x = 1 m, x' = 0, y = 0\n\
    particle bob { mass m; position (x, y) }\n\
    potential -k/4*x^4\n\
    force push on bob: (0, F*sqrt(1 - t/c))\n\
    gravity g\n";

fn fault_name(run: &Run) -> &'static str {
    match run.fault.as_ref().map(|f| &f.kind) {
        None => "none",
        Some(FaultKind::NonFinite { .. }) => "non-finite",
        Some(FaultKind::SingularMass { .. }) => "singular mass",
        Some(FaultKind::StepTooSmall { .. }) => "step too small",
        Some(FaultKind::TooManySteps { .. }) => "too many steps",
        Some(_) => "other",
    }
}

#[test]
fn faults_inside_a_trial_and_at_the_start_are_the_lanes_own() {
    let (problem, base, y0) = problem(FAULTS, &["x", "y''", "y'"]);
    // m, g, k, c, F: the masses' sign picks the solve (LDLᵀ over the lanes, or LU lane by
    // lane), k the blow-up, c when the push fails.
    let mut values = Vec::new();
    for (r, m) in [1.0, -1.0, 2.5, 0.0, f64::NAN, 1.5].into_iter().enumerate() {
        for (s, (k, c)) in
            [(0.0, 10.0), (6.0, 10.0), (0.0, 0.7), (1.5, 1.3)].into_iter().enumerate()
        {
            let nudge = 1.0 + 0.01 * (r * 4 + s) as f64;
            values.push(vec![m, base[1] * nudge, k * nudge, c * nudge, base[4]]);
        }
    }
    let jobs = jobs_from(&y0, values);
    let events = [Event { column: 0, stop: false }];
    let mut seen = std::collections::BTreeMap::new();
    for method in [Method::Dop853, Method::Dopri5] {
        for max_steps in [20_000, 60] {
            let settings = settings(method, 2.0, 0, max_steps);
            let what = format!("{} to {max_steps} steps", method.name());
            for (job, run) in
                jobs.iter().zip(same_as_alone(&what, &problem, &settings, &jobs, &events))
            {
                let mid_run = run.final_time > 0.0;
                *seen.entry((fault_name(&run), mid_run, job.parameters[0] < 0.0)).or_insert(0) += 1;
            }
        }
    }
    for case in [
        ("non-finite", true, false),     // the push at t > c
        ("step too small", true, false), // the blow-up
        ("too many steps", true, false),
        ("singular mass", false, false), // m = 0
        ("non-finite", false, false),    // m = NaN
        ("none", true, true),            // a negative mass, solved by LU
        ("non-finite", true, true),
    ] {
        assert!(seen.contains_key(&case), "no run met {case:?}: {seen:?}");
    }
}

/// The double pendulum of examples/classics/double_pendulum_flip.lag, with a push that
/// depends on time.
const FLIP: &str = "scene \"Flip\"\n\
    param m1 = 1 kg, m2 = 1 kg, l1 = 1 m, l2 = 1 m, g = 9.81 m/s^2, T = 2 N, w = 3 rad/s\n\
    coord theta1 = 2, theta2 = 2\n\
    let x1 = l1*sin(theta1)\n\
    let y1 = -l1*cos(theta1)\n\
    particle bob1 { mass m1; position (x1, y1) }\n\
    particle bob2 { mass m2; position (x1 + l2*sin(theta2), y1 - l2*cos(theta2)) }\n\
    force drive on bob1: (T*sin(w*t), 0)\n\
    gravity g\n";

#[test]
fn stops_events_and_samples_on_the_dense_output_are_as_alone() {
    let (problem, base, _) = problem(
        FLIP,
        &["theta1 - pi", "theta2 + pi", "theta2 - 1", "theta1''", "theta2''", "KE + PE"],
    );
    let jobs: Vec<Job> = (0..21)
        .map(|k| {
            let (a1, a2) = (-3.0 + 0.29 * k as f64, 2.9 - 0.23 * k as f64);
            let mut parameters = base.clone();
            parameters[4] *= 1.0 + 0.02 * (k % 3) as f64;
            parameters[5] *= 1.0 + 0.05 * (k % 5) as f64;
            // A negative outer mass: M indefinite and full, solved by LU lane by lane.
            if k % 7 == 6 {
                parameters[1] = -0.4;
            }
            Job { id: k, parameters, state: vec![a1, a2, 0.0, 0.0] }
        })
        .collect();
    // Flips stop the run, a swing past 1 rad is an event on the way.
    let events = [
        Event { column: 0, stop: true },
        Event { column: 1, stop: true },
        Event { column: 2, stop: false },
    ];
    let (mut stopped, mut crossed, mut sampled, mut indefinite) = (0, 0, 0, 0);
    for (method, samples) in
        [(Method::Dop853, 0), (Method::Dop853, 40), (Method::Dopri5, 0), (Method::Dopri5, 17)]
    {
        let settings = settings(method, 2.9, samples, 20_000);
        let what = format!("{} at {samples} samples", method.name());
        for (job, run) in jobs.iter().zip(same_as_alone(&what, &problem, &settings, &jobs, &events))
        {
            indefinite += usize::from(job.parameters[1] < 0.0 && run.steps > 10);
            stopped += usize::from(run.stopped_by.is_some());
            crossed += run.events.iter().filter(|e| e.event == 2).count();
            sampled += usize::from(samples > 0 && run.trajectory.times.len() > samples / 2);
        }
    }
    assert!(stopped >= 8, "{stopped} runs stopped");
    assert!(crossed >= 8, "{crossed} events crossed");
    assert!(sampled >= 8, "{sampled} runs recorded their samples");
    assert!(indefinite >= 8, "{indefinite} runs with M indefinite went on");
}

/// A push that grows with time: one ulp of t moves the accelerations.
const DRIFT: &str = "scene \"Drift\"\n\
    param m = 1 kg, F = 1/1000 N, c = 1 s\n\
    coord x = 1 m, x' = 0, y = 0\n\
    particle bob { mass m; position (x, y) }\n\
    force push on bob: (F*t/c, F*(t/c)^3)\n";

#[test]
fn a_last_step_that_ends_a_rounding_away_from_t_plus_h_is_observed_alone() {
    // The motion is a polynomial of low degree: the steps grow tenfold each time, and the
    // last one, cut to end at `until`, starts before half of it, where t + (until − t) need
    // not be `until`.
    let (problem, base, y0) = problem(DRIFT, &["x''", "y''", "x", "t"]);
    let jobs: Vec<Job> = (0..24)
        .map(|k| {
            let nudge = 1.0 + 0.037 * k as f64;
            // Every fifth at rest with no push: its state is the same bits all along.
            let push = if k % 5 == 0 { 0.0 } else { base[1] / nudge };
            let parameters = vec![base[0] * nudge, push, base[2]];
            let (u, v) = if k % 5 == 0 { (0.0, 0.0) } else { (0.1 * nudge, 0.2 / nudge) };
            Job { id: k, parameters, state: vec![y0[0], y0[1], u, v] }
        })
        .collect();
    let mut cut_short = 0;
    for method in [Method::Dop853, Method::Dopri5] {
        let settings = settings(method, 2.9, 0, 20_000);
        for run in same_as_alone(method.name(), &problem, &settings, &jobs, &[]) {
            let times = &run.trajectory.times;
            let t = times[times.len() - 2];
            cut_short += usize::from(t + (settings.until - t) != settings.until);
        }
        // Samples inside a step of a run at rest: the state there is the step's end, bit for
        // bit, at another time.
        let settings = Settings { samples: 7, ..settings };
        let runs = same_as_alone(method.name(), &problem, &settings, &jobs, &[]);
        assert!(runs.iter().all(|r| r.trajectory.times.len() == 7));
    }
    assert!(cut_short >= 4, "{cut_short} runs ended a rounding away from t + h");
}

/// A particle whose mass matrix grows ill-conditioned as it moves along x: diag(m, m·e^(−2x/L))
/// at y = 0, past the condition limit once x > 15 L.
const STRETCH: &str = "scene \"Stretch\"\n\
    param m = 1 kg, L = 1 m\n\
    coord x = 0, x' = 1 m/s, y = 0\n\
    particle bob { mass m; position (x, y*exp(-x/L)) }\n";

#[test]
fn a_mass_matrix_ill_conditioned_on_the_way_is_the_lanes_own() {
    let (problem, base, y0) = problem(STRETCH, &["x", "y''"]);
    let jobs: Vec<Job> = (0..13)
        .map(|k| {
            let state = vec![y0[0], y0[1], 2.0 + 1.1 * k as f64, 0.0];
            Job { id: k, parameters: base.clone(), state }
        })
        .collect();
    let mut faulted = 0;
    for method in [Method::Dop853, Method::Dopri5] {
        let runs =
            same_as_alone(method.name(), &problem, &settings(method, 2.0, 0, 20_000), &jobs, &[]);
        for run in &runs {
            if let Some(fault) = &run.fault {
                assert!(matches!(fault.kind, FaultKind::SingularMass { .. }), "{fault:?}");
                assert!(fault.time > 0.5, "{fault:?}");
                faulted += 1;
            }
        }
    }
    assert!((4..=20).contains(&faulted), "{faulted} runs met the condition limit");
}

/// A push that grows exponentially: past t = 709 c it is no longer a float.
const GROWTH: &str = "scene \"Growth\"\n\
    param m = 1 kg, F = 1 N, c = 1 s\n\
    coord x = 0, x' = 0\n\
    particle bob { mass m; position (x, 0) }\n\
    force push on bob: (F*exp(t/c), 0)\n";

#[test]
fn accelerations_that_overflow_on_the_way_are_the_lanes_own() {
    // With m < 1, q̈ = F·e^(t/c)/m (and q̇ with it) passes the largest float while M and f are
    // still finite: the stage's own values must be found not finite.
    let (problem, base, _) = problem(GROWTH, &["x''", "x"]);
    let jobs: Vec<Job> = (0..11)
        .map(|k| {
            let (m, c) = (0.3 + 0.05 * k as f64, if k % 4 == 3 { 1.1 } else { 1.0 });
            // On the solution x = c²·e^(t/c)/m at t = 700 s, not at rest: from rest the first
            // step's estimate itself overflows.
            let rate = c * apply(Func::Exp, 700.0 / c) / m;
            Job { id: k, parameters: vec![m, base[1], c], state: vec![c * rate, rate] }
        })
        .collect();
    for method in [Method::Dop853, Method::Dopri5] {
        let settings = Settings { start: 700.0, ..settings(method, 712.0, 0, 20_000) };
        let runs = same_as_alone(method.name(), &problem, &settings, &jobs, &[]);
        let overflowed = runs.iter().filter(|r| {
            let fault = r.fault.as_ref().map(|f| &f.kind);
            r.final_time > 702.0 && matches!(fault, Some(FaultKind::NonFinite { .. }))
        });
        assert_eq!(overflowed.count(), 9, "{}", method.name());
    }
}

/// A pendulum whose rod is kept with a multiplier: every lane is solved alone, and |Φ| is
/// observed.
const ROD: &str = "scene \"Rod\"\n\
    param m = 1 kg, L = 1 m, g = 9.81 m/s^2\n\
    coord x = 0, y = -L\n\
    particle bob { mass m; position (x, y) }\n\
    constraint rod: x^2 + y^2 = L^2\n\
    gravity g\n";

#[test]
fn kept_constraints_solved_lane_by_lane_are_as_alone() {
    let (problem, base, _) = problem(ROD, &["x", "y''"]);
    let jobs: Vec<Job> = (0..13)
        .map(|k| {
            let (a, l) = (0.25 * k as f64, if k == 5 { 0.0 } else { 1.0 + 0.1 * k as f64 });
            let mut parameters = base.clone();
            parameters[1] = l;
            let (sin, cos) = sin_cos(a);
            let (x, y) = (l * sin, -l * cos);
            Job { id: k, parameters, state: vec![x, y, 0.3 * y, -0.3 * x] }
        })
        .collect();
    // |Φ| is the last observation: its drift from 0 is an event.
    let events = [Event { column: 0, stop: false }, Event { column: 2, stop: false }];
    for method in [Method::Dop853, Method::Dopri5] {
        let runs = same_as_alone(
            method.name(),
            &problem,
            &settings(method, 1.5, 9, 20_000),
            &jobs,
            &events,
        );
        // The rod of length 0 has no gradient: that run cannot start, every other one ends.
        let faults: Vec<_> = runs.iter().map(|r| r.fault.as_ref().map(|f| f.time)).collect();
        let expected: Vec<_> = (0..jobs.len()).map(|k| (k == 5).then_some(0.0)).collect();
        assert_eq!(faults, expected);
        assert!(runs.iter().all(|r| r.fault.is_some() || r.final_time == 1.5));
    }
}

#[test]
fn runs_that_end_at_their_start_and_a_lockstep_broken_off() {
    let (faults, base, y0) = problem(FAULTS, &["x", "y''"]);
    let values = (0..11).map(|k| {
        let mut parameters = base.clone();
        parameters[0] = if k % 4 == 3 { 0.0 } else { 1.0 + 0.1 * k as f64 };
        parameters
    });
    let jobs = jobs_from(&y0, values.collect());
    // An end at the start: every run ends there, the lanes take them all.
    let runs = same_as_alone(
        "until the start",
        &faults,
        &settings(Method::Dop853, 0.0, 0, 10),
        &jobs,
        &[],
    );
    assert!(runs.iter().all(|r| r.steps == 0 && r.final_time == 0.0));
    assert_eq!(runs.iter().filter(|r| r.trajectory.times == [0.0]).count(), 9);
    // Broken off after a few trials: the runs that ended are as alone (flips and starts
    // that are not numbers), those under way are not given, the jobs not taken are left.
    let (problem, base, _) = problem(FLIP, &["theta1 - pi", "theta1''"]);
    let jobs: Vec<Job> = (0..14)
        .map(|k| {
            // Swung towards the top: the first flips at once.
            let a1 = if k % 5 == 4 { f64::NAN } else { 3.1 - 0.1 * k as f64 };
            Job { id: k, parameters: base.clone(), state: vec![a1, 0.5, 1.0, 0.0] }
        })
        .collect();
    let settings = settings(Method::Dop853, 2.0, 0, 20_000);
    let events = [Event { column: 0, stop: true }];
    let mut trials = 0;
    let (runs, left) = in_lockstep(&problem, &settings, &jobs, &events, &mut || {
        trials += 1;
        if trials > 20 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let given: Vec<_> = runs.iter().flatten().collect();
    assert_eq!(given.iter().filter(|r| r.stopped_by.is_some()).count(), 1);
    assert_eq!(given.iter().filter(|r| r.steps == 0).count(), 2);
    // Every lane is under way when it breaks, and the jobs past them were never taken.
    assert!(left > 0);
    assert_eq!(given.len() + numeric::LANES + left, jobs.len());
    for (job, run) in jobs.iter().zip(&runs) {
        if let Some(run) = run {
            assert_eq!(fingerprint(run), fingerprint(&alone(&problem, &settings, job, &events)));
        }
    }
}

fn table_bits(table: &Table) -> Vec<Vec<u64>> {
    table.rows.iter().map(|row| row.iter().map(|v| v.to_bits()).collect()).collect()
}

/// Interrupts an ensemble once it has heard of `after` runs done.
struct InterruptAfter {
    after: f64,
    done: f64,
}

impl simulation::Progress for InterruptAfter {
    fn update(&mut self, done: f64) {
        self.done = done;
    }
    fn interrupted(&mut self) -> bool {
        self.done >= self.after
    }
}

fn options(method: &str, vary: &[&str], record: &str, input: &[&str]) -> Options {
    Options {
        simulate: simulation::Options {
            until: Some(2.5),
            method: Some(method.to_string()),
            input: input.iter().map(|i| i.parse().expect("an input law")).collect(),
            ..Default::default()
        },
        vary: vary.iter().map(|v| Vary::parse(v).expect("an axis")).collect(),
        record: vec![record.to_string()],
        ..Default::default()
    }
}

#[test]
fn an_ensemble_picked_interrupted_or_driven_is_its_runs_one_at_a_time() {
    let flip = lagrange_tests::example("classics/double_pendulum_flip.lag");
    let mut ensemble =
        Ensemble::new(&flip, &options("dop853", &["a1=-3:3:7", "a2=-3:3:4"], "t, theta1''", &[]))
            .expect("loads");
    let side_by_side = ensemble.run(0..ensemble.runs(), 1, &mut ());
    let picked = [27, 3, 9, 3, 14, 20, 26, 99, 0];
    let picked_side_by_side = ensemble.run_picked(&picked, 1, &mut ());
    let interrupted =
        ensemble.run(0..ensemble.runs(), 1, &mut InterruptAfter { after: 9.0, done: 0.0 });
    ensemble.set_lockstep(false);
    let alone = ensemble.run(0..ensemble.runs(), 1, &mut ());
    assert_eq!(table_bits(&side_by_side), table_bits(&alone));
    // The picks in order, once each, those past the ensemble left out.
    let rows: Vec<_> =
        [0, 3, 9, 14, 20, 26, 27].iter().map(|k| table_bits(&alone)[*k].clone()).collect();
    assert_eq!(table_bits(&picked_side_by_side), rows);
    assert_eq!(table_bits(&ensemble.run_picked(&picked, 1, &mut ())), rows);
    // Interrupted: each row is the row of its values alone.
    // The runs under way then are dropped, not run to their ends (eight lanes' worth): only
    // one that ends in the same step as the ninth could join it.
    let rows = table_bits(&interrupted);
    assert!((9..=10).contains(&rows.len()), "{} rows", rows.len());
    for row in rows {
        assert!(table_bits(&alone).contains(&row), "{row:?}");
    }

    // Inputs: one left at its constant value, one driven by a law of time and the state.
    let cart = "scene \"Cart\"\n\
        param m = 1 kg, k = 4 N/m, A = 3/10 N, w = 2 rad/s, c = 1/10 N*s/m\n\
        input F = 1/2 N, G = 0 N\n\
        coord x = 1/10 m\n\
        particle cart { mass m; position (x, 0) }\n\
        spring wall between (0, 0) and cart: k\n\
        force push on cart: (F + G, 0)\n";
    for (method, input) in [("dopri5", &[][..]), ("dop853", &["G=A*sin(w*t) - c*x'"][..])] {
        let mut ensemble = Ensemble::new(
            cart,
            &options(method, &["m=0.5:2:6", "k=1:5:3"], "x, x'', max(x')", input),
        )
        .expect("loads");
        let side_by_side = ensemble.run(0..ensemble.runs(), 2, &mut ());
        ensemble.set_lockstep(false);
        let alone = ensemble.run(0..ensemble.runs(), 1, &mut ());
        assert_eq!(table_bits(&side_by_side), table_bits(&alone), "{input:?}");
        assert!(alone.failures.iter().all(Option::is_none));
    }
}
