//! Derivation scaling: parse + resolve + derive, then lowering M and f to one program, for
//! n-link chains of growing n; expression size as pool nodes and lowered operations, and the
//! peak resident memory of each size.

use std::time::Instant;

use lang::generate::{n_link, Family};

pub const SIZES: [usize; 9] = [1, 2, 4, 8, 12, 16, 24, 32, 50];

/// One measurement: seconds to derive, seconds to derive and lower, pool nodes, operations,
/// and the peak resident memory of the process while deriving and lowering (where the system
/// tells it).
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    pub derive: f64,
    pub lowered: f64,
    pub nodes: usize,
    pub ops: usize,
    pub peak_bytes: Option<u64>,
}

fn once(family: Family, n: usize) -> Measured {
    let scene = n_link(family, n);
    crate::memory::reset_peak();
    let start = Instant::now();
    // `prepare` is parse, resolve (with the dimension check) and derive, plus collecting the
    // parameter slots: what every numeric command does before lowering.
    let mut prepared = engine::numbers::prepare(&scene, &[], engine::Options::default())
        .expect("generated scenes derive");
    let derive = start.elapsed().as_secs_f64();
    let exprs = prepared.dynamics_exprs();
    let program = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let lowered = start.elapsed().as_secs_f64();
    Measured {
        derive,
        lowered,
        nodes: prepared.derivation.model.pool.len(),
        ops: program.op_counts().total(),
        peak_bytes: crate::memory::peak_bytes(),
    }
}

/// Repeats until `repeats` runs are done, or one run is slow (then its noise is small).
pub fn measure(family: Family, n: usize, repeats: usize) -> Measured {
    let mut runs = vec![once(family, n)];
    while runs.len() < repeats && runs[0].lowered < 2.0 {
        runs.push(once(family, n));
    }
    let mut d: Vec<f64> = runs.iter().map(|r| r.derive).collect();
    let mut l: Vec<f64> = runs.iter().map(|r| r.lowered).collect();
    // The largest peak of the repeats: memory is not noise to be filtered out.
    let peak_bytes = runs.iter().filter_map(|r| r.peak_bytes).max();
    Measured {
        derive: crate::median(&mut d),
        lowered: crate::median(&mut l),
        peak_bytes,
        ..runs[0]
    }
}

/// One measurement of `family` at `n` as a line of JSON, for `tests/sympy/sympy_compare.py`.
pub fn json(family: Family, n: usize) {
    let m = measure(family, n, 5);
    let line = serde_json::json!({
        "n": n,
        "derive_s": m.derive,
        "lowered_s": m.lowered,
        "nodes": m.nodes,
        "ops": m.ops,
        "peak_rss_bytes": m.peak_bytes,
    });
    outln!("{line}");
}

// Timings extrapolated and growth exponents printed to two decimals: no last bit shows.
#[allow(clippy::disallowed_methods)]
pub fn run(budget: f64, max: usize) {
    outln!("## Derivation scaling (median of up to 5 runs; per-size budget {budget} s)");
    for family in [Family::Pendulum, Family::PendulumOnCart] {
        let name = Family::NAMES[family as usize];
        outln!("\n{name}");
        outln!(
            "{:>4} {:>12} {:>16} {:>10} {:>10} {:>8} {:>9} {:>10}",
            "n",
            "derive",
            "+ lower M, f",
            "pool nodes",
            "ops M, f",
            "ops/n²",
            "growth",
            "peak RSS"
        );
        let mut previous: Option<(usize, f64)> = None;
        for &n in SIZES.iter().filter(|&&n| n <= max) {
            if let Some((pn, pt)) = previous {
                // Skip a size whose run, extrapolated with cubic growth, would pass the budget.
                let predicted = pt * (n as f64 / pn as f64).powi(3);
                if predicted > budget {
                    outln!(
                        "{n:>4} skipped: about {predicted:.0} s expected from n = {pn}, over the \
                         {budget} s budget"
                    );
                    continue;
                }
            }
            let m = {
                let _bar = crate::progress::Bar::new(format!("scaling: {name}, n = {n}"));
                measure(family, n, 5)
            };
            let growth = match previous {
                Some((pn, pt)) if n > pn => {
                    format!("n^{:.2}", (m.lowered / pt).ln() / (n as f64 / pn as f64).ln())
                }
                _ => String::new(),
            };
            outln!(
                "{n:>4} {:>12} {:>16} {:>10} {:>10} {:>8.1} {:>9} {:>10}",
                crate::seconds(m.derive),
                crate::seconds(m.lowered),
                m.nodes,
                m.ops,
                m.ops as f64 / (n * n) as f64,
                growth,
                crate::memory::megabytes(m.peak_bytes)
            );
            previous = Some((n, m.lowered));
        }
    }
    outln!();
}
