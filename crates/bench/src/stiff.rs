//! The stiffness ladder: the pendulum hung from a spring of stiffness k and damping ratio 5
//! (`examples/classics/stiff_spring_pendulum.lag`, to t = 10 s at tolerance 1e-8), for k from
//! 1e4 to 1e12 N/m, integrated by dop853, auto and radau and, with `--peer`, by SciPy's Radau and BDF
//! with the exact Jacobian written by hand (`tests/sympy/stiff_peer.py`) in the same run: steps,
//! rejections, right-hand sides, Jacobians, LU factorizations, the wall time of one run and
//! the error of the state at t = 10 against a reference, radau itself at tolerance 1e-12
//! (checked against dop853 at 1e-13 where dop853 can afford it). An explicit method's steps
//! grow as √k; radau's should not.

use std::path::Path;
use std::process::Command;

use engine::input::Assignment;
use simulation::{simulate, Options, Outcome};

use crate::{median, seconds};

const SCENE: &str = "examples/classics/stiff_spring_pendulum.lag";
const PEER: &str = "tests/sympy/stiff_peer.py";
const EXPONENTS: [i32; 5] = [4, 6, 8, 10, 12];
const TOLERANCE: f64 = 1e-8;
const STATE: &str = "r, theta, r', theta'";

/// One integration of the ladder: ours or the peer's.
struct Row {
    k: f64,
    method: String,
    steps: usize,
    rejected: Option<usize>,
    evaluations: usize,
    jacobians: usize,
    factorizations: usize,
    seconds: f64,
    error: f64,
}

fn run_once(source: &str, method: &str, k: f64, tolerance: f64) -> Outcome {
    let options = Options {
        method: Some(method.into()),
        tolerance: Some(tolerance),
        set: vec![format!("k={k:e}").parse::<Assignment>().expect("k=… is an assignment")],
        output: vec![STATE.into()],
        samples: 2,
        ..Options::default()
    };
    simulate(source, &options).expect("the scene runs")
}

/// (r, θ, ṙ, θ̇) at the end: the columns asked for, before what the run records after them
/// (its energies).
fn final_state(outcome: &Outcome) -> Vec<f64> {
    let last = outcome.run.trajectory.rows.last().cloned().unwrap_or_default();
    last.into_iter().take(outcome.shown).collect()
}

fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// `largest`: the stiffest k to run dop853 at (it takes minutes at 1e12); `peer`: run SciPy
/// in the same run.
pub fn run(largest: f64, peer: bool) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let source = std::fs::read_to_string(root.join(SCENE)).expect("scene");
    let ks: Vec<f64> = EXPONENTS.iter().map(|&e| numeric::pow_int(10.0, e)).collect();

    let references: Vec<Vec<f64>> =
        ks.iter().map(|&k| final_state(&run_once(&source, "radau", k, 1e-12))).collect();
    // The reference is radau's own; dop853 at 1e-13 is independent of it where it is cheap.
    let check = final_state(&run_once(&source, "dop853", ks[0], 1e-13));
    let agreement = largest_difference(&check, &references[0]);

    let mut rows = Vec::new();
    for (k, reference) in ks.iter().zip(&references) {
        for method in ["dop853", "auto", "radau"] {
            if method == "dop853" && *k > largest {
                continue;
            }
            rows.push(ours(&source, method, *k, TOLERANCE, reference));
        }
        // radau's error at a tolerance is larger than SciPy's Radau's (it holds its estimate
        // to tol^(4/5), as dop853's error calls for, where SciPy holds it to the tolerance): a
        // hundredth of the tolerance matches SciPy's error.
        rows.push(ours(&source, "radau", *k, TOLERANCE / 100.0, reference));
    }
    let peer_rows = if peer { scipy(&root, &ks, &references) } else { Ok(Vec::new()) };

    outln!("## Stiffness: a pendulum on a spring of stiffness k, damping ratio 5\n");
    outln!(
        "To t = 10 s at tolerance {TOLERANCE:e}. Error: the largest difference of (r, θ, ṙ, θ̇) \
         at t = 10 from radau at 1e-12 (which dop853 at 1e-13 meets to {agreement:.1e} at \
         k = 1e4). Time: one run's integration, the median of several for runs under a second \
         (radau's includes lowering the partials its exact Jacobian is made of)."
    );
    if largest < 1e12 {
        outln!("dop853 was run up to k = {largest:e} (`--largest`).");
    }
    outln!();
    outln!(
        "| k (N/m) | method | steps | rejected | F evaluations | Jacobians | LUs | time | error |"
    );
    outln!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    let mut all: Vec<&Row> = rows.iter().collect();
    if let Ok(peer_rows) = &peer_rows {
        all.extend(peer_rows.iter());
    }
    all.sort_by(|a, b| a.k.total_cmp(&b.k));
    for row in &all {
        outln!(
            "| {:.0e} | {} | {} | {} | {} | {} | {} | {} | {:.1e} |",
            row.k,
            row.method,
            row.steps,
            row.rejected.map_or("".into(), |r| r.to_string()),
            row.evaluations,
            row.jacobians,
            row.factorizations,
            seconds(row.seconds),
            row.error
        );
    }
    outln!();
    summary(&rows, &peer_rows);
}

fn ours(source: &str, method: &str, k: f64, tolerance: f64, reference: &[f64]) -> Row {
    let first = run_once(source, method, k, tolerance);
    let mut times = vec![first.wall_seconds];
    // Short runs are timed again: one run of a millisecond is mostly noise on a shared machine.
    if first.wall_seconds < 1.0 {
        times.extend((0..6).map(|_| run_once(source, method, k, tolerance).wall_seconds));
    }
    let method = if tolerance == TOLERANCE {
        method.to_string()
    } else {
        format!("{method} at {tolerance:e}")
    };
    let r = &first.run;
    let error = match r.fault {
        Some(_) => f64::INFINITY,
        None => largest_difference(&final_state(&first), reference),
    };
    Row {
        k,
        method,
        steps: r.steps,
        rejected: Some(r.rejected),
        evaluations: r.evaluations,
        jacobians: r.jacobians,
        factorizations: r.factorizations,
        seconds: median(&mut times),
        error,
    }
}

/// SciPy's rows from the peer script, measured against our references; an error says why the
/// peer did not run (no python3, no network for its environment).
fn scipy(root: &Path, ks: &[f64], references: &[Vec<f64>]) -> Result<Vec<Row>, String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let reference_file = dir.path().join("references.jsonl");
    let lines: Vec<String> = ks
        .iter()
        .zip(references)
        .map(|(k, state)| {
            serde_json::json!({ "k": k, "reference": true, "state": state }).to_string()
        })
        .collect();
    std::fs::write(&reference_file, lines.join("\n") + "\n").map_err(|e| e.to_string())?;
    let ks_text: Vec<String> = ks.iter().map(|k| format!("{k:e}")).collect();
    let output = Command::new("python3")
        .arg(root.join(PEER))
        .args(["--json", "--tol", &format!("{TOLERANCE:e}"), "--ks", &ks_text.join(",")])
        .arg("--reference")
        .arg(&reference_file)
        .output()
        .map_err(|e| format!("python3: {e}"))?;
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).trim().to_string());
    }
    let text = String::from_utf8_lossy(&output.stdout);
    text.lines()
        .filter(|l| l.starts_with('{'))
        .map(|line| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            let count = |key: &str| v[key].as_u64().unwrap_or(0) as usize;
            Ok(Row {
                k: v["k"].as_f64().unwrap_or(f64::NAN),
                method: v["method"].as_str().unwrap_or("?").to_string(),
                steps: count("steps"),
                rejected: None,
                evaluations: count("evaluations"),
                jacobians: count("jacobians"),
                factorizations: count("lu"),
                seconds: v["seconds"].as_f64().unwrap_or(f64::NAN),
                error: v["error"].as_f64().unwrap_or(f64::NAN),
            })
        })
        .collect()
}

/// What the issue asks of radau, read off the table: its steps stay within a factor of two
/// over the ladder, its error within the tolerance's order, and its time against SciPy's
/// Radau at each k.
fn summary(rows: &[Row], peer: &Result<Vec<Row>, String>) {
    let radau: Vec<&Row> = rows.iter().filter(|r| r.method == "radau").collect();
    let matched: Vec<&Row> = rows.iter().filter(|r| r.method.starts_with("radau at")).collect();
    let steps = |f: fn(usize, usize) -> usize| radau.iter().map(|r| r.steps).reduce(f);
    if let (Some(least), Some(most)) = (steps(usize::min), steps(usize::max)) {
        outln!(
            "radau: {least}–{most} steps over the ladder (a factor of {:.2}); largest error {:.1e}.",
            most as f64 / least as f64,
            radau.iter().map(|r| r.error).fold(0.0, f64::max)
        );
    }
    match peer {
        Err(why) => outln!("SciPy not run: {why}"),
        Ok(peer) if peer.is_empty() => {}
        Ok(peer) => {
            let ratios: Vec<String> = radau
                .iter()
                .filter_map(|ours| {
                    let theirs =
                        peer.iter().find(|p| p.method == "scipy-radau" && p.k == ours.k)?;
                    Some(format!("{:.0}× at k = {:.0e}", theirs.seconds / ours.seconds, ours.k))
                })
                .collect();
            outln!("SciPy's Radau takes longer than radau: {}.", ratios.join(", "));
            let ratios: Vec<String> = matched
                .iter()
                .filter_map(|ours| {
                    let theirs =
                        peer.iter().find(|p| p.method == "scipy-radau" && p.k == ours.k)?;
                    Some(format!(
                        "{:.0}× at k = {:.0e} (errors {:.1e} and {:.1e})",
                        theirs.seconds / ours.seconds,
                        ours.k,
                        ours.error,
                        theirs.error
                    ))
                })
                .collect();
            outln!(
                "At about the same error (radau at a hundredth of the tolerance): {}.",
                ratios.join(", ")
            );
        }
    }
    outln!();
}
