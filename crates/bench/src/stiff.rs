//! Stiffness: the pendulum hung from a spring of stiffness k and damping ratio 5
//! (`examples/classics/stiff_spring_pendulum.lag`, to t = 10 s at tolerance 1e-8), integrated by
//! dop853 and radau for k from 1e4 to 1e12 N/m: steps, rejections, right-hand sides,
//! Jacobians, LU factorizations, the wall time of one run, and θ(10). An explicit method's
//! steps grow as √k; radau's should not.

use std::path::Path;

use engine::input::Assignment;
use engine::simulate::{simulate, Options};

use crate::seconds;

const SCENE: &str = "examples/classics/stiff_spring_pendulum.lag";

/// `largest`: the stiffest k to run dop853 at (it takes minutes at 1e12).
pub fn run(largest: f64) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let source = std::fs::read_to_string(root.join(SCENE)).expect("scene");
    outln!("## Stiffness: a pendulum on a spring of stiffness k, damping ratio 5\n");
    outln!(
        "| k (N/m) | method | steps | rejected | F evaluations | Jacobians | LUs | time | θ(10) |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|");
    for exponent in [4, 6, 8, 10, 12] {
        let k = format!("1e{exponent}");
        for method in ["dop853", "radau"] {
            if method == "dop853" && numeric::pow_int(10.0, exponent) > largest {
                outln!("| {k} | {method} | (not run: `--largest` is {largest:e}) | | | | | | |");
                continue;
            }
            let options = Options {
                method: Some(method.into()),
                set: vec![Assignment { name: "k".into(), value: k.clone() }],
                ..Options::default()
            };
            let outcome = simulate(&source, &options).expect("the scene runs");
            let r = &outcome.run;
            let theta = r.trajectory.rows.last().map_or(f64::NAN, |row| row[1]);
            let ended = match &r.fault {
                Some(f) => format!(" (fault at t = {:.2})", f.time),
                None => String::new(),
            };
            outln!(
                "| {k} | {method} | {} | {} | {} | {} | {} | {}{ended} | {theta:.10} |",
                r.steps,
                r.rejected,
                r.evaluations,
                r.jacobians,
                r.factorizations,
                seconds(outcome.wall_seconds)
            );
        }
    }
    outln!();
}
