//! "Model only what the scene requires": the falling rod lowered with and without its floor
//! reaction and energies asked for. Each variant is derived from the scene with its `show`
//! and `expect` lines removed (they would ask for the reaction), plus the extra quantities.

use std::hint::black_box;
use std::time::Instant;

use numeric::Tape;
use sim::{Mechanical, Problem};

pub fn run() {
    outln!("## Model only what the scene requires (falling rod)");
    let source = crate::precision::read("ps5/falling_rod.lag");
    let bare: String = source
        .lines()
        .filter(|l| !l.starts_with("show") && !l.starts_with("expect"))
        .map(|l| format!("{l}\n"))
        .collect();
    outln!(
        "{:<26} {:>10} {:>9} {:>10} {:>8} {:>8} {:>12} {:>12}",
        "asked for",
        "derive",
        "reactions",
        "pool nodes",
        "ops dyn",
        "ops obs",
        "rhs",
        "rhs+observe"
    );
    let variants: [&[&str]; 4] =
        [&[], &["KE", "PE"], &["floor.force"], &["floor.force", "KE", "PE"]];
    for extra in variants {
        let extra: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        let mut times = Vec::new();
        let mut prepared = None;
        for _ in 0..5 {
            let start = Instant::now();
            let p = engine::numbers::prepare(&bare, &extra, engine::Options::default())
                .expect("derives");
            times.push(start.elapsed().as_secs_f64());
            prepared = Some(p);
        }
        let mut prepared = prepared.expect("five runs");
        let exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
        let observation =
            prepared.lower(&prepared.observation_inputs(), &prepared.extra).expect("lowers");
        let (dyn_ops, obs_ops) = (dynamics.op_counts().total(), observation.op_counts().total());
        let parameters = prepared.parameter_values(&[]).expect("values");
        let outputs = observation.outputs.len();
        let mut mech = Mechanical::new(
            prepared.layout,
            Tape::new(dynamics),
            Tape::new(observation),
            parameters,
        );
        let y = [0.25, 0.6, 0.0, 1.3];
        let mut dy = [0.0; 4];
        let rhs = crate::per_call(|| mech.rhs(0.0, black_box(&y), black_box(&mut dy)).expect("ok"));
        let mut row = vec![0.0; outputs];
        let both = crate::per_call(|| {
            mech.rhs(0.0, black_box(&y), black_box(&mut dy)).expect("ok");
            mech.observe(0.0, black_box(&y), black_box(&mut row)).expect("ok");
        });
        let label = if extra.is_empty() { "nothing".to_string() } else { extra.join(", ") };
        outln!(
            "{:<26} {:>10} {:>9} {:>10} {:>8} {:>8} {:>12} {:>12}",
            label,
            crate::seconds(crate::median(&mut times)),
            prepared.derivation.reactions.len(),
            prepared.derivation.model.pool.len(),
            dyn_ops,
            obs_ops,
            crate::seconds(rhs),
            crate::seconds(both)
        );
    }
    outln!("(rhs+observe: a step's right-hand side plus the recording of the outputs)\n");
}
