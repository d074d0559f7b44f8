//! Fitting: `fit::fit` on the recordings of `examples/fitting` — the damped pendulum (free L
//! and c, the column theta) and the pushed cart with its pole (free b and I, the columns x and
//! theta, driven by the recorded push) — at tolerance 1e-12, from the scenes' own values, unit
//! weights. The time is a whole fit in-process (load, every run, the statistics), the median
//! of the repeats, at least `--repeats` of them and for at least three seconds (SciPy's
//! repeats take that long, and the machine's speed swings over seconds); nothing is kept from
//! one repeat to the next.
//!
//! With `--peer`, SciPy in the same run (`tests/sympy/fit_peer.py`): `least_squares` with its
//! defaults (trf, the Jacobian by 2-point differences of whole runs) on the residuals of
//! `solve_ivp` (DOP853 at rtol = atol = 1e-12) of a lambdified SymPy right-hand side, from the
//! same start values. The bench measures: how much faster ours is, the iterations of each, and
//! how far apart the estimates are; it says whether the goals (50× faster, the same
//! estimates to 1e-6) hold, and asserts nothing.

use std::path::Path;
use std::time::Instant;

use crate::{median, repeating, seconds, SPAN};

const PEER: &str = "tests/sympy/fit_peer.py";
const TOLERANCE: f64 = 1e-12;
/// The goals: ours this many times faster, the estimates this close (relative).
const FASTER: f64 = 50.0;
const AGREE: f64 = 1e-6;

/// A fitting problem: the scene, its recording, and what the peer is told of it.
struct Problem {
    name: &'static str,
    /// The peer's name for the scene it derives.
    kind: &'static str,
    file: &'static str,
    data: &'static str,
    /// A series input: its name and file.
    input: Option<(&'static str, &'static str)>,
    free: &'static [&'static str],
    columns: &'static [&'static str],
    /// The scene's fixed parameters, for the peer.
    params: serde_json::Value,
    /// The free parameters' start values and the state's start (the scene's own), for the peer.
    start: serde_json::Value,
}

fn problems() -> [Problem; 2] {
    [
        Problem {
            name: "damped pendulum",
            kind: "pendulum",
            file: "examples/fitting/damped_pendulum.lag",
            data: "examples/fitting/damped_pendulum.csv",
            input: None,
            free: &["L", "c"],
            columns: &["theta"],
            params: serde_json::json!({"m": 1.0, "g": 9.81}),
            start: serde_json::json!({"L": 0.8, "c": 0.1, "theta": 1.0}),
        },
        Problem {
            name: "cart and pole",
            kind: "cart",
            file: "examples/fitting/cart_pendulum.lag",
            data: "examples/fitting/cart_pendulum.csv",
            input: Some(("F", "examples/fitting/push.csv")),
            free: &["b", "I"],
            columns: &["x", "theta"],
            params: serde_json::json!({"M": 1.0, "m": 0.3, "L": 0.6, "g": 9.81}),
            start: serde_json::json!({"b": 0.5, "I": 0.005}),
        },
    ]
}

/// A series file of two columns, time and value, under a header row.
fn series(text: &str) -> sim::Series {
    let (times, values): (Vec<f64>, Vec<f64>) = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let (t, v) = l.split_once(',').expect("a time and a value");
            (t.trim().parse::<f64>().expect("a time"), v.trim().parse::<f64>().expect("a value"))
        })
        .unzip();
    sim::Series::new(times, values).expect("a series")
}

/// One of our fits, timed.
struct Ours {
    wall: f64,
    estimates: Vec<f64>,
    cost: f64,
    iterations: usize,
    runs: usize,
    steps: usize,
    converged: bool,
    /// The load alone, the median of as many.
    load: f64,
}

fn ours(root: &Path, problem: &Problem, repeats: usize) -> Ours {
    let source = std::fs::read_to_string(root.join(problem.file)).expect("the scene");
    let text = std::fs::read_to_string(root.join(problem.data)).expect("the data");
    let table = fit::data::read(&text).expect("a data table");
    let mut options = fit::Options {
        run: simulation::Options { tolerance: Some(TOLERANCE), ..Default::default() },
        free: fit::parse_free(&problem.free.join(",")).expect("free names"),
        ..Default::default()
    };
    if let Some((name, file)) = problem.input {
        let text = std::fs::read_to_string(root.join(file)).expect("the input's series");
        options.run.input_series.push((name.to_string(), series(&text)));
    }
    let mut times = Vec::new();
    let mut loads = Vec::new();
    let mut last = None;
    // SciPy's repeats span seconds on their own; ours are made to (`SPAN`).
    let since = Instant::now();
    while repeating(times.len(), repeats, since) {
        // The table is the fit's to own; copying it is not part of the time.
        let table = table.clone();
        let began = Instant::now();
        let found = fit::fit(&source, &options, table).expect("a fit");
        times.push(began.elapsed().as_secs_f64());
        last = Some(found);
        // The load alone (parse, derive, lower, the columns resolved): what SciPy's time
        // leaves out as its derivation and lambdify.
        let table = fit::data::read(&text).expect("a data table");
        let began = Instant::now();
        let loaded = fit::problem::Problem::load(&source, &options, table).expect("a load");
        loads.push(began.elapsed().as_secs_f64());
        drop(loaded);
    }
    let found = last.expect("a fit");
    Ours {
        wall: median(&mut times),
        load: median(&mut loads),
        estimates: found.estimates,
        cost: found.cost,
        iterations: found.iterations,
        runs: found.evaluations,
        steps: found.steps,
        converged: found.ending.converged(),
    }
}

/// What the peer reported for a problem.
struct Theirs {
    wall: f64,
    load: f64,
    estimates: Vec<f64>,
    /// Σr², as ours (least_squares reports half of it).
    cost: f64,
    nfev: usize,
    njev: usize,
    runs: usize,
    rhs: usize,
    message: String,
}

fn scipy(root: &Path, problems: &[Problem], repeats: usize) -> Result<Vec<Theirs>, String> {
    let path = |p: &str| root.join(p).display().to_string();
    let mut input = String::new();
    for p in problems {
        let request = serde_json::json!({
            "scene": p.kind, "data": path(p.data), "input": p.input.map(|(_, f)| path(f)),
            "params": p.params, "start": p.start, "free": p.free, "columns": p.columns,
            "rtol": TOLERANCE, "repeats": repeats,
        });
        input += &(request.to_string() + "\n");
    }
    let text = crate::peer_lines(&root.join(PEER), &input)?;
    let count = |v: &serde_json::Value| v.as_u64().unwrap_or(0) as usize;
    text.lines()
        .filter(|l| l.starts_with('{'))
        .map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            Ok(Theirs {
                wall: v["wall"].as_f64().unwrap_or(f64::NAN),
                load: v["load"].as_f64().unwrap_or(f64::NAN),
                estimates: serde_json::from_value(v["estimates"].clone())
                    .map_err(|e| format!("the peer's estimates: {e}"))?,
                cost: 2.0 * v["cost"].as_f64().unwrap_or(f64::NAN),
                nfev: count(&v["nfev"]),
                njev: count(&v["njev"]),
                runs: count(&v["runs"]),
                rhs: count(&v["rhs"]),
                message: v["message"].as_str().unwrap_or("").to_string(),
            })
        })
        .collect()
}

/// The largest relative difference between two lists of estimates.
fn difference(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / x.abs().max(y.abs())).fold(0.0, f64::max)
}

fn yes(holds: bool) -> &'static str {
    if holds {
        "yes"
    } else {
        "NO"
    }
}

/// `peer`: also run SciPy's `least_squares`; `repeats`: how often each fit is timed.
pub fn run(peer: bool, repeats: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let problems = problems();
    outln!("## Fitting: Levenberg–Marquardt on exact sensitivities\n");
    outln!(
        "`fit::fit` at tolerance {TOLERANCE:e} from the scenes' values, unit weights; the \
         median of whole fits (load, runs, statistics) repeated at least {repeats} times and \
         for at least {SPAN} s, and of as many loads alone (parse, derive, lower).\n"
    );
    outln!("| problem | estimates | Σr² | iterations | runs | steps per run | fit | load |");
    outln!("|---|---|---:|---:|---:|---:|---:|---:|");
    let mut found = Vec::new();
    for p in &problems {
        let o = ours(&root, p, repeats);
        let estimates: Vec<String> =
            p.free.iter().zip(&o.estimates).map(|(n, v)| format!("{n} = {v:.9}")).collect();
        outln!(
            "| {} | {} | {:.6e} | {}{} | {} | {:.0} | {} | {} |",
            p.name,
            estimates.join(", "),
            o.cost,
            o.iterations,
            if o.converged { "" } else { " (not converged)" },
            o.runs,
            o.steps as f64 / o.runs.max(1) as f64,
            seconds(o.wall),
            seconds(o.load)
        );
        found.push(o);
    }
    outln!();
    if !peer {
        return;
    }
    let theirs = match scipy(&root, &problems, repeats) {
        Ok(t) if t.len() == problems.len() => t,
        Ok(t) => {
            outln!("SciPy not run: {} answers for {} problems\n", t.len(), problems.len());
            return;
        }
        Err(why) => {
            outln!("SciPy not run: {why}\n");
            return;
        }
    };
    outln!(
        "SciPy's least_squares (trf, 2-point differences) on solve_ivp (DOP853, rtol = atol = \
         {TOLERANCE:e}), the median of {repeats} fits, the load (derive, lambdify) apart:\n"
    );
    outln!(
        "| problem | lagrange: iterations (runs) | fit, load apart (whole) | SciPy: nfev / njev \
         (runs) | rhs per run | fit | ours faster, load apart (whole) | estimates apart | Σr² \
         apart |"
    );
    outln!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut verdicts = Vec::new();
    for ((p, o), t) in problems.iter().zip(&found).zip(&theirs) {
        // Like for like: SciPy's time leaves its load out, so ours is compared without ours.
        let search = (o.wall - o.load).max(f64::MIN_POSITIVE);
        let ratio = t.wall / search;
        let apart = difference(&o.estimates, &t.estimates);
        outln!(
            "| {} | {} ({}) | {} ({}) | {} / {} ({}) | {:.0} | {} | {:.1}× ({:.1}×) | {:.1e} | {:.1e} |",
            p.name,
            o.iterations,
            o.runs,
            seconds(search),
            seconds(o.wall),
            t.nfev,
            t.njev,
            t.runs,
            t.rhs as f64 / t.runs.max(1) as f64,
            seconds(t.wall),
            ratio,
            t.wall / o.wall,
            apart,
            difference(&[o.cost], &[t.cost])
        );
        verdicts.push((p.name, ratio, apart, o.iterations <= t.njev, t));
    }
    outln!();
    for (name, ratio, apart, fewer, t) in verdicts {
        outln!(
            "- {name}: {FASTER}× faster, the loads apart: {} ({ratio:.1}×); estimates within \
             {AGREE:e}: {} \
             ({apart:.1e}); no more Jacobians than SciPy: {}. SciPy's load {}; it ended: {}",
            yes(ratio >= FASTER),
            yes(apart <= AGREE),
            yes(fewer),
            seconds(t.load),
            t.message
        );
    }
    outln!();
}
