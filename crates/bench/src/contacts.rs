//! One-sided contacts: the bouncing ball (`examples/contacts/bouncing_ball.lag`, e = 0.8,
//! h0 = 1, to t = 5 s) and Housner's rocking block (`examples/contacts/rocking_block.lag`,
//! gripping corners, plastic landings, to t = 2 s), run by dop853 at tolerances 1e-6, 1e-9 and
//! 1e-12 on a scene loaded once ([`Compiled`]).
//!
//! Accuracy against the closed forms: the ball's impact times t₁·(1 + 2·(e + … + e^(k−1)))
//! and the time it settles against the accumulation point t₁·(1 + e)/(1 − e); the block's
//! impact times (its energy integral by quadrature, [`rocking_block_impacts`]) and its rate
//! ratio per impact 1 − 3/2·sin²α, α = atan(b/h), read off the rows before and after each
//! jump. The worst relative error over every impact of five starts (h0 or θ₀ from a small
//! grid), with steps, right-hand sides and impacts of the middle start.
//!
//! Cost: the wall time of one run on the loaded scene and per impact, the medians over the
//! repeats of every start of the grid (the start changes from run to run, so no run finds the
//! previous one's numbers waiting), the thread's CPU time of a run beside it, and the one-time
//! load (parsing, deriving, lowering) apart.
//!
//! With `--peer`, SciPy in the same run (`tests/sympy/contacts_peer.py`): `solve_ivp`'s DOP853
//! with a terminal event at the gap and the impulse applied by hand, restarting after each
//! impact, on models derived by hand (the block reduced to its tilt), at the rtol = atol whose
//! worst impact-time error over the same starts is at most ours and as close to it as the
//! peer's search gets ("at equal error"). The ball's impacts accumulate (and the block's, from
//! the lower starts), which an event loop cannot pass: the peer stops once the next flight
//! would be shorter than the one at which ours settled the contact, so both make the same
//! impacts.

use std::path::Path;

use std::time::Instant;

use bench::reference::{
    bouncing_ball_accumulation, bouncing_ball_impacts, housner_ratio, rocking_block_impacts,
};
use engine::input::Assignment;
use sim::{ModeChange, ModeEvent};
use simulation::{Compiled, Options, Outcome, Settings};

use crate::{median, seconds};

const PEER: &str = "tests/sympy/contacts_peer.py";
const TOLERANCES: [f64; 3] = [1e-6, 1e-9, 1e-12];

/// The ball's and the block's numbers, as their scene files set them.
const G: f64 = 9.81;
const E: f64 = 0.8;
const B: f64 = 0.1;
const H: f64 = 0.3;

/// A contact scene and what it is measured against.
struct Scene {
    name: &'static str,
    file: &'static str,
    /// The rate whose ratio across an impact is measured.
    rate: &'static str,
    /// The parameter the starts vary, and its grid (the middle one is the scene's own).
    start: &'static str,
    starts: [f64; 5],
    until: f64,
    /// The exact ratio of `rate` after an impact to before.
    ratio: f64,
    /// How much shorter each flight is than the one before as the impacts accumulate.
    shrink: f64,
}

impl Scene {
    /// The exact impact times at `start` (at least `count` for the ball, whose impacts go on
    /// for ever).
    fn references(&self, start: f64, count: usize) -> Vec<f64> {
        match self.name {
            "ball" => bouncing_ball_impacts(G, E, start, count),
            _ => rocking_block_impacts(G, B, H, start, self.until),
        }
    }

    /// The exact impact times at `start` against a run that made `count` impacts: where it
    /// `settled` the contact, the series cut at the impact it settled at.
    fn exact(&self, start: f64, count: usize, settled: bool) -> Vec<f64> {
        let mut exact = self.references(start, count);
        if settled {
            exact.truncate(count);
        }
        exact
    }

    /// The peer's parameters.
    fn params(&self) -> serde_json::Value {
        match self.name {
            "ball" => serde_json::json!({ "g": G, "e": E }),
            _ => serde_json::json!({ "g": G, "b": B, "h": H }),
        }
    }
}

fn scenes() -> [Scene; 2] {
    [
        Scene {
            name: "ball",
            file: "examples/contacts/bouncing_ball.lag",
            rate: "y'",
            start: "h0",
            starts: [0.9, 0.95, 1.0, 1.05, 1.1],
            until: 5.0,
            ratio: -E,
            shrink: E,
        },
        Scene {
            name: "block",
            file: "examples/contacts/rocking_block.lag",
            rate: "theta'",
            start: "theta0",
            starts: [0.08, 0.09, 0.1, 0.11, 0.12],
            until: 2.0,
            ratio: housner_ratio(B, H),
            // The flights of small swings are in proportion to the landing rate.
            shrink: housner_ratio(B, H),
        },
    ]
}

/// What one run at one start gave.
struct Measured {
    /// Impact times (settling included), in order.
    impacts: Vec<f64>,
    /// The worst relative error of the impact times; infinite if their count is wrong.
    error: f64,
    /// The worst relative error of the rate ratio across an impact.
    ratio_error: f64,
    /// When a contact settled, if one did.
    settled: Option<f64>,
    steps: usize,
    evaluations: usize,
}

/// One tolerance of one scene: accuracy over the starts, cost over the repeats.
struct Row {
    tolerance: f64,
    /// Each start's run (the first repeat's).
    measured: Vec<Measured>,
    error: f64,
    ratio_error: f64,
    /// The worst relative error of the settling time against the accumulation point.
    settled_error: Option<f64>,
    per_run: f64,
    per_impact: f64,
    /// The thread's CPU time of a run, the median: on a machine others share, what the run
    /// itself cost, without the time it waited for a core.
    cpu_per_run: f64,
    /// The share of a run spent integrating (the rest: resolving the start, making the
    /// problem, the summary's totals).
    integrating: f64,
    /// From each start, the flight below which the peer stops: between the flights after the
    /// impact at which ours settled the contact and after the one before (0 where ours did
    /// not settle it).
    floors: Vec<f64>,
}

/// The worst relative difference of `times` from `exact`, pairwise; infinite when their
/// counts differ.
fn worst_error(times: &[f64], exact: &[f64]) -> f64 {
    if times.len() != exact.len() {
        return f64::INFINITY;
    }
    times.iter().zip(exact).map(|(t, r)| ((t - r) / r).abs()).fold(0.0, f64::max)
}

/// The scene loaded once for runs of `scene` recording its rate at every step, and the load's
/// wall time.
fn load(root: &Path, scene: &Scene) -> (Settings, Compiled, f64) {
    let source = std::fs::read_to_string(root.join(scene.file)).expect("scene");
    let options = Options {
        method: Some("dop853".into()),
        output: vec![scene.rate.into()],
        ..Options::default()
    };
    let settings = simulation::settings(&source, &options).expect("the scene's settings");
    let started = Instant::now();
    let compiled = Compiled::new(&source, &settings).expect("the scene loads");
    let took = started.elapsed().as_secs_f64();
    (settings, compiled, took)
}

/// One run of the loaded scene from `start` at `tolerance`, its wall time and its thread's
/// CPU time.
fn once(
    scene: &Scene,
    compiled: &mut Compiled,
    settings: &Settings,
    start: f64,
    tolerance: f64,
) -> (Outcome, f64, f64) {
    let settings = Settings {
        tolerance,
        sets: vec![Assignment { name: scene.start.into(), value: format!("{start:e}") }],
        ..settings.clone()
    };
    let (started, cpu) = (Instant::now(), cpu_time::ThreadTime::now());
    let outcome = compiled.run(&settings, &mut ()).expect("the scene runs");
    let (took, cpu) = (started.elapsed().as_secs_f64(), cpu.elapsed().as_secs_f64());
    assert!(outcome.run.fault.is_none(), "{} faulted at {start}", scene.name);
    (outcome, took, cpu)
}

/// The impacts, errors and counts of one run from `start`.
fn measure(scene: &Scene, outcome: &Outcome, start: f64) -> Measured {
    let run = &outcome.run;
    let (times, rows) = (&run.trajectory.times, &run.trajectory.rows);
    // The rate just before and just after a jump: the first and the last row at its time.
    let across = |time: f64| {
        let first = times.iter().position(|&t| t == time)?;
        let last = times.iter().rposition(|&t| t == time)?;
        Some((rows[first][0], rows[last][0]))
    };
    let impacts: Vec<&ModeEvent> = run
        .modes
        .iter()
        .filter(|m| matches!(m.kind, ModeChange::Impact | ModeChange::Settled))
        .collect();
    // Settled: a contact whose impacts accumulate, made plastic, or an impact that leaves the
    // body at rest (the block's last, where the corner it leaves separates too slowly to count
    // as leaving and stays closed): from there the series of impacts is cut.
    let at_rest = |m: &ModeEvent| {
        m.kind == ModeChange::Settled
            || across(m.time).is_some_and(|(before, after)| after.abs() <= 1e-9 * before.abs())
    };
    let settled = impacts.iter().find(|m| at_rest(m)).map(|m| m.time);
    let ratio_error = impacts
        .iter()
        .filter(|m| !at_rest(m))
        .filter_map(|m| across(m.time))
        .map(|(before, after)| ((after / before - scene.ratio) / scene.ratio).abs())
        .fold(0.0, f64::max);
    let impacts: Vec<f64> = impacts.iter().map(|m| m.time).collect();
    let exact = scene.exact(start, impacts.len(), settled.is_some());
    Measured {
        error: worst_error(&impacts, &exact),
        impacts,
        ratio_error,
        settled,
        steps: run.steps,
        evaluations: run.evaluations,
    }
}

fn row(
    scene: &Scene,
    compiled: &mut Compiled,
    settings: &Settings,
    tolerance: f64,
    repeats: usize,
) -> Row {
    let mut measured = Vec::new();
    let (mut runs, mut per_impact, mut integrating) = (Vec::new(), Vec::new(), Vec::new());
    let mut cpus = Vec::new();
    for repeat in 0..repeats.max(1) {
        for &start in &scene.starts {
            let (outcome, took, cpu) = once(scene, compiled, settings, start, tolerance);
            let impacts = outcome
                .run
                .modes
                .iter()
                .filter(|m| matches!(m.kind, ModeChange::Impact | ModeChange::Settled))
                .count();
            runs.push(took);
            cpus.push(cpu);
            per_impact.push(took / impacts.max(1) as f64);
            integrating.push(outcome.wall_seconds / took);
            // The references (the block's by quadrature) once a start.
            if repeat == 0 {
                measured.push(measure(scene, &outcome, start));
            }
        }
    }
    let worst = |f: &dyn Fn(&Measured) -> f64| measured.iter().map(f).fold(0.0, f64::max);
    let error = worst(&|m| m.error);
    let ratio_error = worst(&|m| m.ratio_error);
    let settled_error = (scene.name == "ball").then(|| {
        scene
            .starts
            .iter()
            .zip(&measured)
            .map(|(&start, m)| {
                let end = bouncing_ball_accumulation(G, E, start);
                m.settled.map_or(f64::INFINITY, |t| ((t - end) / end).abs())
            })
            .fold(0.0, f64::max)
    });
    // The flight the contact would have had after its settling (the Kth) impact,
    // t_(K+1) − t_K, and the one before it, longer by 1/shrink: the peer stops between the two.
    let floors = scene
        .starts
        .iter()
        .zip(&measured)
        .map(|(&start, m)| {
            let k = m.impacts.len();
            let exact = scene.references(start, k + 1);
            match m.settled {
                Some(_) if k >= 1 && exact.len() > k => {
                    (exact[k] - exact[k - 1]) / scene.shrink.sqrt()
                }
                _ => 0.0,
            }
        })
        .collect();
    Row {
        tolerance,
        measured,
        error,
        ratio_error,
        settled_error,
        per_run: median(&mut runs),
        per_impact: median(&mut per_impact),
        cpu_per_run: median(&mut cpus),
        integrating: median(&mut integrating),
        floors,
    }
}

impl Row {
    /// The run from the middle start, the scene's own.
    fn middle(&self) -> &Measured {
        &self.measured[self.measured.len() / 2]
    }
}

/// SciPy at equal error: what the peer reported for one of our rows.
struct Peer {
    rtol: f64,
    error: f64,
    impacts: usize,
    steps: usize,
    evaluations: usize,
    per_run: f64,
    per_impact: f64,
    cpu_per_run: f64,
    tried: usize,
}

/// `peer`: also run SciPy at equal error; `repeats`: how often every start is timed.
pub fn run(peer: bool, repeats: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    outln!("## Contacts: impacts located, and their cost\n");
    outln!(
        "dop853 on the scene loaded once, one run per start of a grid of five (the middle one \
         the scene's own), every start run {} time(s). Error: the worst relative error over \
         every impact of the five starts against the closed forms; steps, right-hand sides and \
         impacts: the middle start's run. Time: one run on the loaded scene (resolving the \
         start, integrating, the summary), the median of every run; per impact: the median of \
         each run's time over its impacts; integrating: the median share of a run inside the \
         integrator.\n",
        repeats.max(1)
    );
    for scene in scenes() {
        let (settings, mut compiled, load) = load(&root, &scene);
        let rows: Vec<Row> = TOLERANCES
            .iter()
            .map(|&tol| row(&scene, &mut compiled, &settings, tol, repeats))
            .collect();
        table(&scene, &rows, load);
        if peer {
            match scipy(&root, &scene, &rows, repeats) {
                Ok(theirs) => peer_table(&scene, &rows, &theirs),
                Err(why) => outln!("SciPy not run: {why}\n"),
            }
        }
    }
}

fn table(scene: &Scene, rows: &[Row], load: f64) {
    let ball = scene.name == "ball";
    if ball {
        outln!(
            "### The bouncing ball: e = {E}, h0 from {} to {} m, to t = {} s\n",
            scene.starts[0],
            scene.starts[4],
            scene.until
        );
        outln!(
            "Impact times against t₁·(1 + 2·(e + … + e^(k−1))), t₁ = √(2·h0/g); the settling \
             time against the accumulation point t₁·(1 + e)/(1 − e); the ratio y'⁺/y'⁻ against \
             −e. Loading the scene (parsing, deriving, lowering) took {} once.\n",
            seconds(load)
        );
    } else {
        outln!(
            "### The rocking block: b/h = {B}/{H}, gripping corners, plastic, θ₀ from {} to {}, \
             to t = {} s\n",
            scene.starts[0],
            scene.starts[4],
            scene.until
        );
        outln!(
            "Impact times against the energy integral by quadrature; the ratio θ'⁺/θ'⁻ against \
             Housner's 1 − 3/2·sin²α = {:.4}. Loading the scene took {} once.\n",
            scene.ratio,
            seconds(load)
        );
    }
    let settled = if ball { " settling time error |" } else { "" };
    outln!(
        "| tolerance | impacts | impact-time error |{settled} ratio error | steps | \
         right-hand sides | per run | per impact | integrating |"
    );
    outln!("|---:|---:|---:|{}---:|---:|---:|---:|---:|---:|", if ball { "---:|" } else { "" });
    for row in rows {
        let settled = match row.settled_error {
            Some(e) => format!(" {e:.1e} |"),
            None => String::new(),
        };
        outln!(
            "| {:.0e} | {} | {:.1e} |{settled} {:.1e} | {} | {} | {} | {} | {:.0}% |",
            row.tolerance,
            row.middle().impacts.len(),
            row.error,
            row.ratio_error,
            row.middle().steps,
            row.middle().evaluations,
            seconds(row.per_run),
            seconds(row.per_impact),
            100.0 * row.integrating
        );
    }
    outln!();
}

/// The peer's rows for ours, or why it did not run.
fn scipy(root: &Path, scene: &Scene, rows: &[Row], repeats: usize) -> Result<Vec<Peer>, String> {
    let mut input = String::new();
    for row in rows {
        // The references as far as ours went: the impacts it made from each start.
        let references: Vec<Vec<f64>> = scene
            .starts
            .iter()
            .zip(&row.measured)
            .map(|(&s, m)| scene.exact(s, m.impacts.len(), m.settled.is_some()))
            .collect();
        let request = serde_json::json!({
            "label": row.tolerance,
            "scene": scene.name,
            "params": scene.params(),
            "until": scene.until,
            "starts": scene.starts,
            "references": references,
            "floors": row.floors,
            "target": row.error,
            "repeats": repeats.max(1),
        });
        input += &(request.to_string() + "\n");
    }
    let text = crate::peer_lines(&root.join(PEER), &input)?;
    // One line per request, in their order.
    text.lines()
        .filter(|l| l.starts_with('{'))
        .zip(rows)
        .map(|(line, row)| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            let number = |key: &str| v[key].as_f64().unwrap_or(f64::NAN);
            let count = |key: &str| v[key].as_u64().unwrap_or(0) as usize;
            // Their error measured here, against the same references as ours.
            let times: Vec<Vec<f64>> = serde_json::from_value(v["times"].clone())
                .map_err(|e| format!("the peer's times: {e}"))?;
            let error = scene
                .starts
                .iter()
                .zip(&times)
                .zip(&row.measured)
                .map(|((&s, t), m)| {
                    worst_error(t, &scene.exact(s, m.impacts.len(), m.settled.is_some()))
                })
                .fold(0.0, f64::max);
            Ok(Peer {
                rtol: number("rtol"),
                error,
                impacts: count("impacts"),
                steps: count("steps"),
                evaluations: count("evaluations"),
                per_run: number("seconds"),
                per_impact: number("seconds_per_impact"),
                cpu_per_run: number("cpu_seconds"),
                tried: count("tried"),
            })
        })
        .collect()
}

fn peer_table(scene: &Scene, rows: &[Row], theirs: &[Peer]) {
    outln!(
        "SciPy {} at equal error: solve_ivp's DOP853 with a terminal event at the gap, the \
         impulse applied by hand and a new solve_ivp after each impact, at the rtol = atol \
         whose worst impact-time error over the same five starts is at most ours (the peer's \
         search: a ladder of four tolerances a decade, then bisection; rtol tried). {}\n",
        scene.name,
        if scene.name == "ball" {
            "It cannot pass the accumulation point: it stops once the next flight would be \
             shorter than the one at which ours settles the ball, and the ball rests from \
             there (the rest of the span is not integrated)."
        } else {
            "Its model is the block reduced to its tilt θ, pivoting about one corner, \
             θ'' = −(3g/4R)·sin(±α − θ), with θ' ← (1 − 3/2·sin²α)·θ' and the pivot switched \
             at θ = 0: its ratio is exact by construction."
        }
    );
    outln!(
        "| tolerance | our error | SciPy rtol = atol | SciPy error | rtols tried | SciPy impacts | \
         SciPy steps | SciPy right-hand sides | ours per run | SciPy per run | ours per impact | \
         SciPy per impact | SciPy / ours | CPU: ours | CPU: SciPy | CPU: SciPy / ours |"
    );
    outln!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (ours, theirs) in rows.iter().zip(theirs) {
        outln!(
            "| {:.0e} | {:.1e} | {:.2e} | {:.1e} | {} | {} | {} | {} | {} | {} | {} | {} | \
             **{:.0}×** | {} | {} | {:.0}× |",
            ours.tolerance,
            ours.error,
            theirs.rtol,
            theirs.error,
            theirs.tried,
            theirs.impacts,
            theirs.steps,
            theirs.evaluations,
            seconds(ours.per_run),
            seconds(theirs.per_run),
            seconds(ours.per_impact),
            seconds(theirs.per_impact),
            theirs.per_run / ours.per_run,
            seconds(ours.cpu_per_run),
            seconds(theirs.cpu_per_run),
            theirs.cpu_per_run / ours.cpu_per_run
        );
    }
    outln!();
    let least = |f: &dyn Fn(&Row, &Peer) -> f64| {
        rows.iter().zip(theirs).map(|(o, t)| f(o, t)).fold(f64::INFINITY, f64::min)
    };
    let wall = least(&|o, t| t.per_run / o.per_run);
    let cpu = least(&|o, t| t.cpu_per_run / o.cpu_per_run);
    outln!(
        "The target: ours at least 50× faster per run at equal error; here {wall:.0}× at the \
         least in wall time, {}, and {cpu:.0}× at the least in CPU time (the medians of the \
         runs' own threads, which a shared machine's waits for a core do not count).\n",
        if wall >= 50.0 { "met" } else { "NOT met" }
    );
}
