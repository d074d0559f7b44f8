//! Evaluation at scale: the n-link pendulum (point masses on massless links, planar, the
//! scene `lang::generate` writes) at n = 2 … 64.
//!
//! In this process: the load (parse, derive, lower), the dynamics program's size, and where
//! one right-hand side's time goes: the tape's M and f (and M alone and f alone, each lowered
//! by itself), M copied into the solver's matrix, its LDLᵀ factorization, and the whole
//! `Mechanical::rhs` (the rest is the two triangular solves and the checks). Every figure cycles through distinct states: `Mechanical` returns
//! the accelerations it solved when a call is at the bits of the last, which would hide the
//! cost.
//!
//! With `--peer`, in one Python run (`tests/sympy/links_peer.py`): lagrange's `f(t, y)` of
//! `Scene.rhs()`, its `f.batch` per state, its `f.jac` at n = 32 and the load at n = 64,
//! against Pinocchio's articulated-body algorithm (`pinocchio.aba`, O(n)) on the same chain
//! built with Pinocchio's API, each called through Python with the state varied per call, and
//! the two q̈ held to each other first.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use lang::generate::{n_link, Family};
use nalgebra::DMatrix;
use numeric::Tape;
use sim::{Mechanical, Problem};

use crate::seconds;

const PEER: &str = "tests/sympy/links_peer.py";
const SIZES: [usize; 6] = [2, 4, 8, 16, 32, 64];
/// How many distinct states a timing cycles through: no call is at the state of the last, and
/// the states themselves are few enough to stay in cache.
const STATES: usize = 64;
/// The rows of the peer's `batch`.
const ROWS: usize = 1024;
/// Where the Jacobian is timed, and where the load.
const JACOBIAN_AT: usize = 32;
const LOAD_AT: usize = 64;
/// Calls before a timing of `Mechanical`, past the run on which its tapes compile themselves.
const WARM: usize = 1100;
/// The largest relative difference of the two q̈ that still counts as the same model.
const AGREEMENT: f64 = 1e-9;

/// `count` states of the n-link chain, angles and rates in (−1, 1), spread by the fractional
/// parts of multiples of irrational numbers: distinct, and the same from run to run.
fn states(n: usize, count: usize) -> Vec<Vec<f64>> {
    (0..count)
        .map(|k| {
            (0..2 * n)
                .map(|i| {
                    let x = (k * 2 * n + i + 1) as f64 * 0.618_033_988_749_895
                        + i as f64 * 0.414_213_562_373_095;
                    2.0 * (x % 1.0) - 1.0
                })
                .collect()
        })
        .collect()
}

/// What this process measured at one n.
struct Row {
    n: usize,
    load: f64,
    ops: usize,
    /// The dynamics program compiled to machine code (all of it, and the ops on the state
    /// alone), as `Tape::compile` does it; 0 where tapes are interpreted (`LAGRANGE_JIT=off`).
    compile: f64,
    tape: f64,
    /// M alone and f alone, each lowered by itself: what either costs without the other
    /// (their common terms counted in both).
    mass: (usize, f64),
    forcing: (usize, f64),
    form: f64,
    factor: f64,
    rhs: f64,
    /// At [`JACOBIAN_AT`]: the partials program's size, its compile time, its tape's time,
    /// and the whole exact Jacobian on each route: the dense one (the dense accelerations and
    /// M's LDLᵀ factors, the partials, and a solve with those factors per state component)
    /// and the recursive one (q̈ and the sweep's factors, the partials, and the columns solved
    /// by the sweep), which Python's `f.jac` takes.
    jacobian: Option<(usize, f64, f64, f64, f64)>,
    /// The recursive form: its program's size, the time to find and lower it, and the
    /// `rhs` that sweeps it.
    recursive: (usize, f64, f64),
}

fn measure(n: usize) -> Row {
    let scene = n_link(Family::Pendulum, n);
    let began = Instant::now();
    let mut prepared =
        engine::numbers::prepare(&scene, &[], engine::Options::default()).expect("derives");
    let exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let observation = prepared.lower(&prepared.observation_inputs(), &[]).expect("lowers");
    let load = began.elapsed().as_secs_f64();
    let ops = dynamics.op_counts().total();
    let inputs = prepared.dynamics_inputs();
    let part = |exprs: &[cas::ExprId]| prepared.lower(&inputs, exprs).expect("lowers");
    let (mass, forcing) = (part(&exprs[..n * n]), part(&exprs[n * n..]));
    let parameters = prepared.parameter_values(&[]).expect("the parameters' values");
    let layout = prepared.layout;
    let ys = states(n, STATES);

    // The tape as `Mechanical` runs it: the parameters fixed, the state's inputs written in.
    let fixed = 1 + 2 * n..layout.dynamics_inputs();
    let mut tape = Tape::new(dynamics.clone()).with_fixed_inputs(fixed.clone());
    tape.inputs_mut()[fixed].copy_from_slice(&parameters);
    let began = Instant::now();
    let compile = if tape.compile() { began.elapsed().as_secs_f64() } else { 0.0 };
    let mut out = vec![0.0; layout.dynamics_outputs()];
    let outputs: Vec<Vec<f64>> = ys
        .iter()
        .map(|y| {
            tape.inputs_mut()[1..1 + 2 * n].copy_from_slice(y);
            tape.run(&mut out);
            out.clone()
        })
        .collect();
    let mut k = 0;
    let tape = crate::per_call(|| {
        k = (k + 1) % STATES;
        tape.inputs_mut()[1..1 + 2 * n].copy_from_slice(black_box(&ys[k]));
        tape.run(black_box(&mut out));
    });

    let alone = |program: numeric::Program| {
        let ops = program.op_counts().total();
        let mut tape = Tape::new(program).with_fixed_inputs(1 + 2 * n..layout.dynamics_inputs());
        tape.inputs_mut()[1 + 2 * n..].copy_from_slice(&parameters);
        let mut out = vec![0.0; tape.outputs()];
        let mut k = 0;
        let time = crate::per_call(|| {
            k = (k + 1) % STATES;
            tape.inputs_mut()[1..1 + 2 * n].copy_from_slice(black_box(&ys[k]));
            tape.run(black_box(&mut out));
        });
        (ops, time)
    };
    let (mass, forcing) = (alone(mass), alone(forcing));

    // M copied into the solver's matrix as `Mechanical` loads it (M is column-major in the
    // outputs), then factored in place.
    let mut a = DMatrix::<f64>::zeros(n, n);
    let load_mass = |k: usize, a: &mut DMatrix<f64>| {
        let mass = &outputs[k][..n * n];
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] = mass[j * n + i];
            }
        }
    };
    let form = crate::per_call(|| {
        k = (k + 1) % STATES;
        load_mass(k, &mut a);
        black_box(&a);
    });
    let factor = crate::per_call(|| {
        k = (k + 1) % STATES;
        load_mass(k, &mut a);
        black_box(sim::linalg::ldl_in_place(&mut a)).expect("M is positive definite");
    }) - form;

    let mut mechanical = Mechanical::new(
        layout,
        Tape::new(dynamics.clone()),
        Tape::new(observation.clone()),
        parameters.clone(),
    );
    let mut dy = vec![0.0; 2 * n];
    // A tape compiles itself to machine code on its 1,000th run: the calls are timed after
    // that, as those of a run past its start are.
    for y in ys.iter().cycle().take(WARM) {
        mechanical.rhs(0.0, y, &mut dy).expect("regular");
    }
    let rhs = crate::per_call(|| {
        k = (k + 1) % STATES;
        mechanical.rhs(0.0, black_box(&ys[k]), black_box(&mut dy)).expect("regular");
    });
    let began = Instant::now();
    let program = prepared.recursive_from(1).expect("lowers").expect("a chain");
    let found = began.elapsed().as_secs_f64();
    let recursive_ops = program.accelerations.op_counts().total();
    let mut swept =
        Mechanical::new(layout, Tape::new(dynamics), Tape::new(observation), parameters)
            .with_chain(program);
    for y in ys.iter().cycle().take(WARM) {
        swept.rhs(0.0, y, &mut dy).expect("regular");
    }
    let swept_rhs = crate::per_call(|| {
        k = (k + 1) % STATES;
        swept.rhs(0.0, black_box(&ys[k]), black_box(&mut dy)).expect("regular");
    });
    let jacobian = (n == JACOBIAN_AT).then(|| {
        let exprs = prepared.partials_exprs();
        let program = prepared.lower(&prepared.observation_inputs(), &exprs).expect("lowers");
        let ops = program.op_counts().total();
        // The partials at the accelerations each state has, as the Jacobian evaluates them.
        let inputs: Vec<Vec<f64>> = ys
            .iter()
            .map(|y| {
                mechanical.rhs(0.0, y, &mut dy).expect("regular");
                let mut input = vec![0.0];
                input.extend(y);
                input.extend(&dy[n..]);
                input.extend(mechanical.parameters());
                input
            })
            .collect();
        let mut tape = Tape::new(program.clone());
        let began = Instant::now();
        let compile = if tape.compile() { began.elapsed().as_secs_f64() } else { 0.0 };
        let mut out = vec![0.0; tape.outputs()];
        let partials = crate::per_call(|| {
            k = (k + 1) % STATES;
            tape.eval(black_box(&inputs[k]), black_box(&mut out));
        });
        let mut jac = vec![0.0; 4 * n * n];
        let mut whole = |problem: &mut Mechanical| {
            problem.set_partials(Tape::new(program.clone()));
            for y in ys.iter().cycle().take(WARM) {
                problem.jacobian(0.0, y, &mut jac).expect("regular");
            }
            crate::per_call(|| {
                k = (k + 1) % STATES;
                let done = problem.jacobian(0.0, black_box(&ys[k]), black_box(&mut jac));
                assert!(done.expect("regular"), "the partials were given");
            })
        };
        let (dense, swept) = (whole(&mut mechanical), whole(&mut swept));
        (ops, compile, partials, dense, swept)
    });
    let recursive = (recursive_ops, found, swept_rhs);
    Row { n, load, ops, compile, tape, mass, forcing, form, factor, rhs, jacobian, recursive }
}

/// Seconds per call as wall time and as the calling thread's CPU time.
#[derive(Clone, Copy)]
struct Time {
    wall: f64,
    cpu: f64,
}

impl Time {
    fn ratio(self, other: Time) -> String {
        format!("{:.2} ({:.2})", self.wall / other.wall, self.cpu / other.cpu)
    }
}

impl std::fmt::Display for Time {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{} ({})", seconds(self.wall), seconds(self.cpu))
    }
}

/// What the peer measured at one n (`batch` per state).
struct Theirs {
    n: usize,
    agreement: f64,
    rhs: Time,
    rhs_same: Time,
    batch: Time,
    aba: Time,
    jac: Option<Time>,
    aba_derivatives: Option<Time>,
    loads: Option<f64>,
    rhs_load: Option<f64>,
    whole_load: Option<f64>,
    pinocchio: String,
}

fn peer(root: &Path) -> Result<Vec<Theirs>, String> {
    let mut input = String::new();
    for (i, n) in SIZES.into_iter().enumerate() {
        let request = serde_json::json!({
            "n": n, "scene": n_link(Family::Pendulum, n), "states": STATES, "rows": ROWS,
            "seed": i, "jac": n == JACOBIAN_AT, "load": n == LOAD_AT,
        });
        input += &(request.to_string() + "\n");
    }
    let text = crate::peer_lines(&root.join(PEER), &input)?;
    text.lines()
        .filter(|l| l.starts_with('{'))
        .map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            let number = |key: &str| v[key].as_f64();
            let time =
                |key: &str| Some(Time { wall: number(key)?, cpu: number(&format!("{key}_cpu"))? });
            let missing = |key: &str| format!("the peer gave no `{key}`");
            Ok(Theirs {
                n: v["n"].as_u64().ok_or(missing("n"))? as usize,
                agreement: number("agreement").ok_or(missing("agreement"))?,
                rhs: time("rhs").ok_or(missing("rhs"))?,
                rhs_same: time("rhs_same").ok_or(missing("rhs_same"))?,
                batch: time("batch").ok_or(missing("batch"))?,
                aba: time("aba").ok_or(missing("aba"))?,
                jac: time("jac"),
                aba_derivatives: time("aba_derivatives"),
                loads: number("loads"),
                rhs_load: number("rhs_load"),
                whole_load: number("whole_load"),
                pinocchio: v["pinocchio"].as_str().unwrap_or("?").to_string(),
            })
        })
        .collect()
}

/// The machine's load average over the last minute, where the system says it (Linux).
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// `peer`: also run lagrange from Python against Pinocchio's ABA.
pub fn run(peer_too: bool) {
    outln!("## Evaluation at scale: the n-link pendulum\n");
    outln!(
        "Per call, cycling through {STATES} distinct states; the median of 7 batches of at \
         least 20 ms (load average {} at the start).\n",
        load_average()
    );
    outln!(
        "| n | load | ops | compile | tape M, f | M alone (ops) | f alone (ops) | M copied | LDLᵀ \
         | `rhs` | rest | recursive: found (ops) | `rhs` |"
    );
    outln!(
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: \
         | ---: |"
    );
    let mut jacobian = None;
    for n in SIZES {
        let r = measure(n);
        if let Some(j) = r.jacobian {
            jacobian = Some((r.n, r.recursive.2, j));
        }
        outln!(
            "| {} | {} | {} | {} | {} | {} ({}) | {} ({}) | {} | {} | {} | {} | {} ({}) | {} |",
            r.n,
            seconds(r.load),
            r.ops,
            seconds(r.compile),
            seconds(r.tape),
            seconds(r.mass.1),
            r.mass.0,
            seconds(r.forcing.1),
            r.forcing.0,
            seconds(r.form),
            seconds(r.factor),
            seconds(r.rhs),
            seconds(r.rhs - r.tape - r.form - r.factor),
            seconds(r.recursive.1),
            r.recursive.0,
            seconds(r.recursive.2)
        );
    }
    outln!();
    if let Some((n, rhs, (ops, compile, partials, dense, swept))) = jacobian {
        outln!(
            "The exact Jacobian at n = {n}: {} a call on the recursive route, {:.1}× its `rhs` \
             (q̈ and the sweep's factors, the partials, {} columns solved by the sweep); {} on \
             the dense route (M, f and M's LDLᵀ factors, the partials, {} solves with those \
             factors). The partials program is {ops} operations (compiled in {}), {} on the \
             tape.\n",
            seconds(swept),
            swept / rhs,
            2 * n,
            seconds(dense),
            2 * n,
            seconds(compile),
            seconds(partials),
        );
    }
    if !peer_too {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let before = load_average();
    let theirs = match peer(&root) {
        Ok(theirs) => theirs,
        Err(why) => {
            outln!("The peer did not run: {why}\n");
            return;
        }
    };
    let version = theirs.first().map_or("?", |t| t.pinocchio.as_str());
    outln!(
        "From Python, against Pinocchio {version}'s `aba` on the same chain, each cycling \
         through {STATES} distinct random states (load average {before} before, {} after):\n",
        load_average()
    );
    outln!(
        "| n | q̈ agree to | `rhs` | same state | ABA | `rhs`/ABA | `batch`, per state | \
         `batch`/ABA |"
    );
    outln!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    let mut disagree = Vec::new();
    for t in &theirs {
        if t.agreement.is_nan() || t.agreement > AGREEMENT {
            disagree.push(t.n);
        }
        outln!(
            "| {} | {:.0e} | {} | {} | {} | {} | {} | {} |",
            t.n,
            t.agreement,
            t.rhs,
            t.rhs_same,
            t.aba,
            t.rhs.ratio(t.aba),
            t.batch,
            t.batch.ratio(t.aba)
        );
    }
    outln!("\nEach figure is wall time (the thread's CPU time).\n");
    for t in &theirs {
        if let Some(jac) = t.jac {
            outln!("`jac` at n = {}: {jac} a call, {} the `rhs`.", t.n, jac.ratio(t.rhs));
            if let Some(theirs) = t.aba_derivatives {
                outln!(
                    "Pinocchio's `computeABADerivatives` (∂q̈/∂q and ∂q̈/∂v) on the same states: \
                     {theirs} a call, {} its `aba`; `jac` is {} of it.",
                    theirs.ratio(t.aba),
                    jac.ratio(theirs)
                );
            }
        }
        if let (Some(loads), Some(rhs), Some(whole)) = (t.loads, t.rhs_load, t.whole_load) {
            outln!(
                "Loading at n = {} from Python, text to a callable: {} (`lagrange.loads`: parse, \
                 resolve, derive {}; then `scene.rhs()`: lay out a copy of the derivation and \
                 lower it {}; medians of 3).",
                t.n,
                seconds(whole),
                seconds(loads),
                seconds(rhs)
            );
        }
    }
    if !disagree.is_empty() {
        outln!(
            "\nNOT THE SAME MODEL at n = {disagree:?}: the two q̈ differ by more than \
             {AGREEMENT:e} of their size, so those rows compare different things."
        );
    }
    outln!();
}
