//! `lagrange-bench`: the benchmarks of the speed/accuracy issue, printed as tables.
//!
//! - `scaling`: derivation time, expression size and peak memory of the n-link pendulum (and
//!   on a cart);
//! - `eval`: one evaluation of M and f, and one right-hand side, on the tape, in generated
//!   Rust compiled with `rustc -O`, and in a hand-written function (the floor);
//! - `precision`: work–precision of every integrator against exact references;
//! - `model`: what asking for reactions and energies costs in the lowered program;
//! - `space`: derivation time and lowered size of the scenes with bodies in space;
//! - `bicycle`: the Whipple bicycle's derivation and linearization, its lowered size and one
//!   right-hand side;
//! - `stiff [--largest K] [--peer]`: the stiffness ladder, dop853 and radau on a pendulum hung
//!   from a spring stiff up to k = 1e12 (dop853 only up to K, 1e12 by default: it takes
//!   minutes there), with `--peer` SciPy's Radau and BDF in the same run;
//! - `tolerance`: the final error of every adaptive method at tolerances 1e-6 … 1e-12, and
//!   their spread at each tolerance (one tolerance should mean one accuracy);
//! - `ensemble [--peer]`: the double pendulum's 60×60 flip-time map on one thread and on two,
//!   with `--peer` SciPy's DOP853 on a lambdified SymPy right-hand side on a sample of it;
//! - `contacts [--peer] [--repeats N]`: the bouncing ball and the rocking block: the worst
//!   error of their impact times (and rate ratios) against closed forms at tolerances 1e-6,
//!   1e-9 and 1e-12, and the wall time per run and per impact on the scene loaded once, with
//!   `--peer` a SciPy event loop (DOP853, the impulses applied by hand) at equal error;
//! - `orbit [--peer] [--repeats N]`: the rimless wheel's and the driven pendulum's periodic
//!   orbits found by `orbit`, their multipliers against closed forms and the wall time of a
//!   search, with `--peer` SciPy's shooting loop (finite-difference Jacobians of whole runs);
//! - `fit [--peer] [--repeats N]`: `fit::fit` on the damped pendulum's and the pushed cart's
//!   recordings at tolerance 1e-12, with `--peer` SciPy's `least_squares` (2-point
//!   differences of whole `solve_ivp` runs) from the same start, in the same run;
//! - `links [--peer]`: the n-link pendulum at n = 2 … 64, where a right-hand side's time goes
//!   (the tape, M copied, its factorization), and with `--peer` lagrange from Python (`rhs`,
//!   `batch`, `jac`, the load) against Pinocchio's articulated-body algorithm in one Python run,
//!   the state varied per call;
//! - `memory [--largest N]`: the peak memory of `lagrange simulate` and `lagrange ensemble`
//!   processes at 1e5, 1e6 … N samples and runs (1e7 by default), their tables streamed to a
//!   file (Linux: read from /proc);
//! - `derive FAMILY N`: one scaling measurement as JSON, for `tests/sympy/sympy_compare.py`.
//!
//! Benchmarks measure; the tests assert. Every timing is a median of repeats, and the
//! machine may be shared, so the figures are indicative.

/// `print!` to standard output, but a reader that stops reading (`| head`) ends the output
/// quietly instead of with a panic; other write errors are said on stderr.
macro_rules! out {
    ($($arg:tt)*) => {
        crate::emit(format_args!($($arg)*))
    };
}

/// `println!` as [`out!`] prints.
macro_rules! outln {
    () => {
        crate::emit(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        crate::emit(format_args!("{}\n", format_args!($($arg)*)))
    };
}

mod bicycle;
mod contacts;
mod ensemble;
mod eval;
mod fit;
mod hand;
mod links;
mod memory;
mod model;
mod orbit;
mod precision;
mod progress;
mod scaling;
mod space;
mod stiff;
mod tolerance;

use std::time::Instant;

use clap::{Args, Parser, Subcommand};
use lang::generate::Family;

/// The benchmarks of the speed/accuracy issue, printed as tables.
#[derive(Parser)]
#[command(name = "lagrange-bench")]
struct Cli {
    /// Which benchmark to run; all of them but `derive` when none is named.
    #[command(subcommand)]
    benchmark: Option<Benchmark>,
}

#[derive(Subcommand)]
enum Benchmark {
    /// Every benchmark but `derive`, in turn.
    All(Limits),
    /// Derivation time, expression size and peak memory of the n-link chains.
    Scaling(Limits),
    /// One evaluation on the tape, in generated Rust and by hand.
    Eval,
    /// Work–precision of every integrator against exact references.
    Precision,
    /// What asking for reactions and energies costs in the lowered program.
    Model,
    /// The scenes with bodies in space.
    Space,
    /// The Whipple bicycle.
    Bicycle,
    /// The stiffness ladder: dop853 and radau on a pendulum hung from a spring of growing
    /// stiffness, against a tight reference.
    Stiff {
        /// The stiffest spring dop853 is run on (it takes minutes at 1e12).
        #[arg(long, value_name = "K", default_value_t = 1e12)]
        largest: f64,
        /// Also run SciPy's Radau and BDF with the exact Jacobian (tests/sympy/stiff_peer.py,
        /// which makes its own Python environment) in the same run.
        #[arg(long)]
        peer: bool,
    },
    /// The final error of every adaptive method at tolerances 1e-6 … 1e-12, and their
    /// spread at each tolerance.
    Tolerance,
    /// The double pendulum's 60×60 flip-time map on one thread and on two.
    Ensemble {
        /// Also run SciPy's DOP853 on a lambdified SymPy right-hand side
        /// (tests/sympy/ensemble_peer.py, which makes its own Python environment) on a sample
        /// of the map's starts, in the same run.
        #[arg(long)]
        peer: bool,
        /// How many of the map's starts the peer runs (a tenth of the map by default: enough
        /// runs that the lanes of ours seldom wait for the last few).
        #[arg(long, default_value_t = 360)]
        sample: usize,
        /// How often each thread count's map is timed.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// The bouncing ball and the rocking block: impacts against closed forms, and the cost of
    /// a run and of an impact.
    Contacts {
        /// Also run a SciPy event loop (tests/sympy/contacts_peer.py, which makes its own
        /// Python environment) at equal error, in the same run.
        #[arg(long)]
        peer: bool,
        /// How often each start of the grid is run and timed.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
    },
    /// The rimless wheel's and the driven pendulum's periodic orbits: multipliers against
    /// closed forms, and the cost of a search.
    Orbit {
        /// Also run SciPy's shooting loop with finite-difference Jacobians
        /// (tests/sympy/orbit_peer.py, which makes its own Python environment), in the same run.
        #[arg(long)]
        peer: bool,
        /// How often each search is timed.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
    },
    /// Parameters fitted to the recordings of examples/fitting: the time of a fit, its
    /// iterations and runs.
    Fit {
        /// Also run SciPy's least_squares on solve_ivp runs of a lambdified SymPy right-hand
        /// side (tests/sympy/fit_peer.py, which makes its own Python environment), in the same
        /// run.
        #[arg(long)]
        peer: bool,
        /// How often each fit is timed (SciPy's too).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
    },
    /// The n-link pendulum at n = 2 … 64: the load, and where a right-hand side's time goes.
    Links {
        /// Also time lagrange from Python against Pinocchio's articulated-body algorithm
        /// (tests/sympy/links_peer.py, which makes its own Python environment and installs
        /// this checkout's package into it), in one Python run.
        #[arg(long)]
        peer: bool,
    },
    /// The peak memory of `lagrange simulate` and `lagrange ensemble` as their tables grow
    /// (Linux).
    Memory {
        /// The most samples and runs (from 1e5, tenfold each time).
        #[arg(long, default_value_t = 10_000_000)]
        largest: usize,
    },
    /// One scaling measurement as JSON, for `tests/sympy/sympy_compare.py`.
    Derive {
        #[arg(value_parser = family)]
        family: Family,
        n: usize,
    },
}

/// How far `scaling` goes.
#[derive(Args)]
struct Limits {
    /// The time each size may take (s): past it, the chain grows no longer.
    #[arg(long, value_name = "SECONDS", default_value_t = Limits::DEFAULT.budget)]
    budget: f64,
    /// The largest n.
    #[arg(long, default_value_t = Limits::DEFAULT.max)]
    max: usize,
}

impl Limits {
    const DEFAULT: Limits = Limits { budget: 20.0, max: 50 };
}

/// A family of generated scenes by its name.
fn family(name: &str) -> Result<Family, String> {
    Family::from_name(name).ok_or_else(|| format!("one of {}", Family::NAMES.join(", ")))
}

fn main() {
    let benchmark = Cli::parse().benchmark;
    match benchmark.unwrap_or(Benchmark::All(Limits::DEFAULT)) {
        Benchmark::All(Limits { budget, max }) => {
            scaling::run(budget, max);
            eval::run();
            precision::run();
            model::run();
            space::run();
            bicycle::run();
        }
        Benchmark::Space => space::run(),
        Benchmark::Bicycle => bicycle::run(),
        Benchmark::Stiff { largest, peer } => stiff::run(largest, peer),
        Benchmark::Tolerance => tolerance::run(),
        Benchmark::Ensemble { peer, sample, repeats } => ensemble::run(peer, sample, repeats),
        Benchmark::Scaling(Limits { budget, max }) => scaling::run(budget, max),
        Benchmark::Eval => eval::run(),
        Benchmark::Precision => {
            precision::run();
        }
        Benchmark::Model => model::run(),
        Benchmark::Contacts { peer, repeats } => contacts::run(peer, repeats),
        Benchmark::Orbit { peer, repeats } => orbit::run(peer, repeats),
        Benchmark::Fit { peer, repeats } => fit::run(peer, repeats),
        Benchmark::Links { peer } => links::run(peer),
        Benchmark::Memory { largest } => memory::run(largest),
        Benchmark::Derive { family, n } => scaling::json(family, n),
    }
}

/// The least time, in seconds, that each side's repeats of a short measurement span. This
/// machine's speed swings by up to 2× in phases of seconds (a fit of ours took 16 to 30 ms in
/// one steady loop): repeats of a few milliseconds would meet one phase, a peer's of a second
/// each meet them all in their proportions. Spanning as long, the two medians sample the same
/// machine.
pub const SPAN: f64 = 3.0;

/// Whether a measurement repeated `done` times since `since` goes on: until it has at least
/// `repeats` and spans [`SPAN`].
pub fn repeating(done: usize, repeats: usize, since: std::time::Instant) -> bool {
    done < repeats.max(1) || since.elapsed().as_secs_f64() < SPAN
}

/// The median of `v`.
pub fn median(v: &mut [f64]) -> f64 {
    simulation::bench::median(v)
}

/// Seconds per call of `f`: batches sized to last about 20 ms, seven of them, the median.
/// Short batches would measure the clock; one long batch would let a neighbour's burst on a
/// shared machine decide the figure.
pub fn per_call(mut f: impl FnMut()) -> f64 {
    let mut iterations = 1usize;
    loop {
        let start = Instant::now();
        for _ in 0..iterations {
            f();
        }
        let took = start.elapsed().as_secs_f64();
        if took > 0.02 || iterations > 1 << 30 {
            break;
        }
        iterations *= if took < 0.002 { 10 } else { 2 };
    }
    let mut times: Vec<f64> = (0..7)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..iterations {
                f();
            }
            start.elapsed().as_secs_f64() / iterations as f64
        })
        .collect();
    median(&mut times)
}

/// What a Python peer `script` prints given `input` on its standard input (one request a
/// line), or why it did not run: no python3, or the script failed (its standard error).
pub fn peer_lines(script: &std::path::Path, input: &str) -> Result<String, String> {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new("python3")
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("python3: {e}"))?;
    child
        .stdin
        .take()
        .ok_or("no standard input")?
        .write_all(input.as_bytes())
        .map_err(|e| e.to_string())?;
    let output = child.wait_with_output().map_err(|e| e.to_string())?;
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).trim().to_string());
    }
    Ok(String::from_utf8_lossy(&output.stdout).into_owned())
}

/// A duration with a unit that keeps three significant digits readable.
pub use simulation::bench::seconds;

/// Writes to standard output for [`out!`] and [`outln!`].
fn emit(args: std::fmt::Arguments) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.flush()) {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("error: cannot write the output: {e}");
        }
    }
}
