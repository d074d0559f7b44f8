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
//! - `derive FAMILY N`: one scaling measurement as JSON, for `bench/sympy_compare.py`.
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
mod eval;
mod hand;
mod memory;
mod model;
mod precision;
mod progress;
mod scaling;
mod space;
mod stiff;

use std::time::Instant;

const USAGE: &str = "usage: lagrange-bench [all | scaling [--budget SECONDS] [--max N] | eval | \
                     precision | model | space | bicycle | stiff [--largest K] [--peer] | \
                     derive n-link-pendulum[-on-cart] N]";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| -> Option<f64> {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|v| v.parse().ok())
    };
    let budget = flag("--budget").unwrap_or(20.0);
    let max = flag("--max").map(|v| v as usize).unwrap_or(50);
    match args.first().map(String::as_str).unwrap_or("all") {
        "all" => {
            scaling::run(budget, max);
            eval::run();
            precision::run();
            model::run();
            space::run();
            bicycle::run();
        }
        "space" => space::run(),
        "bicycle" => bicycle::run(),
        "stiff" => {
            stiff::run(flag("--largest").unwrap_or(1e12), args.iter().any(|a| a == "--peer"))
        }
        "scaling" => scaling::run(budget, max),
        "eval" => eval::run(),
        "precision" => {
            precision::run();
        }
        "model" => model::run(),
        "derive" => {
            let family = args.get(1).and_then(|f| engine::generate::Family::from_name(f));
            let n = args.get(2).and_then(|n| n.parse::<usize>().ok());
            let (Some(family), Some(n)) = (family, n) else {
                eprintln!("{USAGE}");
                std::process::exit(2);
            };
            scaling::json(family, n);
        }
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    }
}

/// The median of `v`.
pub fn median(v: &mut [f64]) -> f64 {
    engine::bench::median(v)
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

/// A duration with a unit that keeps three significant digits readable.
pub use engine::bench::seconds;

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
