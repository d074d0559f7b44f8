//! The Whipple bicycle (`examples/bicycle/whipple.lag`): the time to derive the full nonlinear
//! model and to linearize it at 5 m/s (each a whole run, once), the operations its lowered
//! equations take (whole, and M, f and the constraint rows each alone), and one right-hand side
//! on the tape at the start; then what an implicit method adds: the partials differentiated
//! and lowered (once), their operations, and one exact Jacobian.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use numeric::Tape;
use sim::{Mechanical, Problem};

use crate::seconds;

pub fn run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let source =
        std::fs::read_to_string(root.join("examples/bicycle/whipple.lag")).expect("the bicycle");
    outln!("## The Whipple bicycle\n");

    let bar = crate::progress::Bar::new("bicycle: deriving");
    let start = Instant::now();
    let scene = engine::load(&source).expect("the bicycle derives");
    let derive = start.elapsed().as_secs_f64();
    drop(bar);
    let n = scene.derivation.coords.len();
    let kept = scene.derivation.multipliers.len();
    drop(scene);

    let bar = crate::progress::Bar::new("bicycle: linearizing");
    let start = Instant::now();
    let options = engine::linearize::Options { set: vec!["v=5".into()], ..Default::default() };
    let linearized = engine::linearize::linearize(&source, &options).expect("linearizes");
    let linearize = start.elapsed().as_secs_f64();
    drop(bar);
    black_box(&linearized.at.eigenvalues);

    let mut prepared =
        engine::numbers::prepare(&source, &[], engine::Options::default()).expect("prepares");
    let exprs = prepared.dynamics_exprs();
    let inputs = prepared.dynamics_inputs();
    let start = Instant::now();
    let dynamics = prepared.lower(&inputs, &exprs).expect("lowers");
    let lowering = start.elapsed().as_secs_f64();
    let ops = dynamics.op_counts().total();
    // Each part lowered alone, so what they share is counted in each: they add up to more.
    // The slots as `dynamics_exprs` lays them out: M by columns, f, then the constraint rows.
    let part = |range: std::ops::Range<usize>| {
        let program = prepared.lower(&inputs, &exprs[range]).expect("lowers");
        program.op_counts().total()
    };
    let (mass_ops, forcing_ops, rows_ops) =
        (part(0..n * n), part(n * n..n * n + n), part(n * n + n..exprs.len()));
    let observation = prepared.lower(&prepared.observation_inputs(), &[]).expect("lowers");
    let parameters = prepared.parameter_values(&[]).expect("parameter values");
    let y = prepared.initial_state(&parameters, &[]).expect("a start");
    let stabilisation = prepared.stabilisation();
    let mut mech =
        Mechanical::new(prepared.layout, Tape::new(dynamics), Tape::new(observation), parameters)
            .with_kinds(stabilisation);
    let mut dy = vec![0.0; y.len()];
    let rhs = crate::per_call(|| {
        mech.rhs(0.0, black_box(&y), black_box(&mut dy)).expect("regular");
    });

    outln!("| coordinates | kept constraints | derive (whole load, once) | linearize at 5 m/s (with its derivation, once) | lowered operations: all (M alone, f alone, constraint rows alone) | lowering them (once) | one right-hand side |");
    outln!("|---|---|---|---|---|---|---|");
    outln!(
        "| {n} | {kept} | {} | {} | {ops} ({mass_ops}, {forcing_ops}, {rows_ops}) | {} | {} |",
        seconds(derive),
        seconds(linearize),
        seconds(lowering),
        seconds(rhs)
    );
    outln!();

    // Only implicit methods ask for the partials, so this is what they add to a run's start.
    let start = Instant::now();
    let exprs = prepared.partials_exprs();
    let differentiate = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let partials = prepared.lower(&prepared.observation_inputs(), &exprs).expect("lowers");
    let lower_partials = start.elapsed().as_secs_f64();
    let partial_ops = partials.op_counts().total();
    let mut mech = mech.with_partials(Tape::new(partials));
    let mut jac = vec![0.0; y.len() * y.len()];
    let jacobian = crate::per_call(|| {
        mech.jacobian(0.0, black_box(&y), black_box(&mut jac)).expect("regular");
    });
    outln!("| partials: differentiated (once) | lowered (once) | their operations | one exact Jacobian |");
    outln!("|---|---|---|---|");
    outln!(
        "| {} | {} | {partial_ops} | {} |",
        seconds(differentiate),
        seconds(lower_partials),
        seconds(jacobian)
    );
    outln!();
}
