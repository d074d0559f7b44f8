//! The ensemble benchmark: the double pendulum's 60×60 flip-time map to t = 10
//! (`examples/classics/double_pendulum_flip.lag`, both start angles from −3 to 3, dop853 at
//! the default tolerance 1e-10, each run ended by the first flip), run on one thread and on
//! two: the wall time of each, whether the two tables are the same bits, and with `--peer`
//! SciPy's DOP853 on a right-hand side lambdified from SymPy (`tests/sympy/ensemble_peer.py`)
//! on a sample of the map's starts spread over both angles, one run at a time, against the
//! same starts here as an ensemble of their own on one thread (side by side in lockstep, and
//! one at a time).

use std::path::Path;
use std::time::Instant;

use ::ensemble::{Ensemble, Options, Table};
use engine::input::Vary;

use crate::{median, seconds};

const SCENE: &str = "examples/classics/double_pendulum_flip.lag";
const PEER: &str = "tests/sympy/ensemble_peer.py";
const SIDE: usize = 60;

/// `peer`: run SciPy on `sample` of the map's starts in the same run; `repeats`: how often
/// each thread count's map is timed (the median is shown).
pub fn run(peer: bool, sample: usize, repeats: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let source = std::fs::read_to_string(root.join(SCENE)).expect("scene");
    let axis = |name: &str| Vary::parse(&format!("{name}=-3:3:{SIDE}")).expect("a grid axis");
    let options = Options {
        vary: vec![axis("a1"), axis("a2")],
        record: vec!["t".into()],
        ..Options::default()
    };
    let started = Instant::now();
    let mut ensemble = Ensemble::new(&source, &options).expect("the ensemble loads");
    let setup = started.elapsed().as_secs_f64();
    let runs = ensemble.runs();

    // The wall time and the process's CPU time of the whole map, the median of the repeats.
    let timed = |threads: usize| -> ((f64, f64), Table) {
        let (mut walls, mut cpus) = (Vec::new(), Vec::new());
        let mut table = None;
        for _ in 0..repeats.max(1) {
            let bar = &mut crate::progress::Bar::new(format!("{runs} runs on {threads} thread(s)"));
            let (started, cpu) = (Instant::now(), cpu_time::ProcessTime::now());
            table = Some(ensemble.run(0..runs, threads, bar));
            walls.push(started.elapsed().as_secs_f64());
            cpus.push(cpu.elapsed().as_secs_f64());
        }
        ((median(&mut walls), median(&mut cpus)), table.expect("timed at least once"))
    };
    let ((one, one_cpu), table) = timed(1);
    let ((two, two_cpu), other) = timed(2);
    let same = bits(&table) == bits(&other);
    let failed = table.failures.iter().filter(|f| f.is_some()).count();
    let flipped = table.rows.iter().filter(|r| r[2] < 10.0).count();

    outln!("## Ensemble: the double pendulum's {SIDE}×{SIDE} flip-time map to t = 10\n");
    outln!(
        "{runs} runs of dop853 at tolerance 1e-10, each until the first flip (|θ| = π) or \
         t = 10; {flipped} flipped, {failed} failed. Loading, deriving, lowering and making \
         the starts took {} once. Time: the whole map, the median of {} timing(s); CPU: the \
         process's CPU time over the same run, and cores: CPU over wall time, how many cores \
         the run had on average.\n",
        seconds(setup),
        repeats.max(1)
    );
    outln!("| threads | wall time | per run | against 1 thread | CPU | cores |");
    outln!("|---:|---:|---:|---:|---:|---:|");
    for (threads, time, cpu) in [(1, one, one_cpu), (2, two, two_cpu)] {
        outln!(
            "| {threads} | {} | {} | {:.2} | {} | {:.2} |",
            seconds(time),
            seconds(time / runs as f64),
            time / one,
            seconds(cpu),
            cpu / time
        );
    }
    outln!();
    outln!(
        "The two tables are {} (the target: the same bits); 2 threads took {:.2} of 1 \
         thread's time (the target: at most 0.65).",
        if same { "the same bits" } else { "DIFFERENT" },
        two / one
    );
    if peer {
        scipy(&root, &mut ensemble, sample, one_cpu / runs as f64);
    }
    outln!();
}

/// Every number of the table as its bits, NaN included.
fn bits(table: &Table) -> Vec<u64> {
    table.rows.iter().flatten().map(|v| v.to_bits()).collect()
}

/// SciPy on `sample` starts spread evenly over the map, against our runs of the same starts,
/// each timed alone on one thread.
fn scipy(root: &Path, ensemble: &mut Ensemble, sample: usize, map_per_run: f64) {
    let runs = ensemble.runs();
    let picked = spread(runs, sample.clamp(1, runs));
    let rows = ensemble.run_picked(&picked, 1, &mut ()).rows;
    // The sample as an ensemble of its own on this thread, whose CPU time is the runs':
    // side by side in lockstep, as `lagrange ensemble` runs them, and one at a time.
    let per_run = |ensemble: &mut Ensemble, lockstep: bool| {
        ensemble.set_lockstep(lockstep);
        let (mut walls, mut cpus): (Vec<f64>, Vec<f64>) = (0..5)
            .map(|_| {
                let (started, cpu) = (Instant::now(), cpu_time::ThreadTime::now());
                ensemble.run_picked(&picked, 1, &mut ());
                (started.elapsed().as_secs_f64(), cpu.elapsed().as_secs_f64())
            })
            .unzip();
        let count = picked.len() as f64;
        Timing { wall: median(&mut walls) / count, cpu: median(&mut cpus) / count }
    };
    let alone = per_run(ensemble, false);
    let ours = per_run(ensemble, true);
    let input: String = rows
        .iter()
        .map(|r| serde_json::json!({ "a1": r[0], "a2": r[1] }).to_string() + "\n")
        .collect();
    let theirs = match peer(root, &input) {
        Ok(theirs) => theirs,
        Err(why) => {
            outln!("SciPy not run: {why}");
            return;
        }
    };
    let agree = rows
        .iter()
        .zip(&theirs)
        // A start near the edge of a flip basin may flip on one side and not the other.
        .filter(|(row, (t, _))| (row[2] - t).abs() <= 1e-6 * t.max(1.0))
        .count();
    let mean = |v: &mut dyn Iterator<Item = f64>| {
        let (sum, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
        sum / n.max(1) as f64
    };
    let (their_wall, their_cpu) =
        (mean(&mut theirs.iter().map(|p| p.1.wall)), mean(&mut theirs.iter().map(|p| p.1.cpu)));
    outln!(
        "SciPy's DOP853 (rtol = atol = 1e-10) on a SymPy right-hand side lambdified to Python, \
         on {} starts spread over the map, one at a time, against the same starts here as an \
         ensemble on one thread (the median of five timings): {} of CPU per run against {} \
         here, **{:.0}×** (wall time {} against {}, {:.0}×; the target: at least 100×). The \
         same runs one at a time here, not side by side: {} of CPU per run, {:.0}×. The whole \
         map on one thread above: {} of CPU per run, {:.0}× SciPy's per run on the sample. \
         The first flip's time agrees to 1e-6 at {agree} of the {} starts.",
        theirs.len(),
        seconds(their_cpu),
        seconds(ours.cpu),
        their_cpu / ours.cpu,
        seconds(their_wall),
        seconds(ours.wall),
        their_wall / ours.wall,
        seconds(alone.cpu),
        their_cpu / alone.cpu,
        seconds(map_per_run),
        their_cpu / map_per_run,
        theirs.len()
    );
}

/// A run's wall time and CPU time.
struct Timing {
    wall: f64,
    cpu: f64,
}

/// `sample` run indices spread over both axes of the map: steps of the golden ratio's share
/// of the runs (made prime to their number), so that neither axis is sampled at one value.
fn spread(runs: usize, sample: usize) -> Vec<usize> {
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut stride = ((runs as f64) * 0.5 * (5f64.sqrt() - 1.0)).round() as usize;
    while gcd(stride.max(1), runs) != 1 {
        stride += 1;
    }
    let mut picked: Vec<usize> = (0..sample).map(|i| i * stride % runs).collect();
    picked.sort_unstable();
    picked
}

/// The peer's first flip and timing for each start of `input`, or why it did not run.
fn peer(root: &Path, input: &str) -> Result<Vec<(f64, Timing)>, String> {
    crate::peer_lines(&root.join(PEER), input)?
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            let number = |key: &str| v[key].as_f64().unwrap_or(f64::NAN);
            Ok((number("t"), Timing { wall: number("seconds"), cpu: number("cpu_seconds") }))
        })
        .collect()
}
