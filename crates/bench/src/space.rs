//! Bodies in space: the time to load and derive the scenes of `examples/space` and the
//! spatial cross-check scenes (parse, resolve, derive and diagnose, as `derive` does before it
//! prints), and the operations their lowered equations take. Rotations are what stress the
//! simplifier; these are the figures to watch when it changes.

use std::path::Path;

use crate::{per_call, seconds};

/// The scenes measured, relative to the repository.
const SCENES: [&str; 6] = [
    "examples/space/heavy_top.lag",
    "examples/space/spherical_rod.lag",
    "examples/space/tennis_racket.lag",
    "examples/space/robot_arm.lag",
    "examples/space/gyroscope.lag",
    "tests/sympy/scenes/spatial_loads.lag",
];

pub fn run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    outln!("## Bodies in space: load and derive\n");
    outln!("| scene | coordinates | derive | lowered operations (M, f) |");
    outln!("|---|---|---|---|");
    for rel in SCENES {
        let source = std::fs::read_to_string(root.join(rel)).expect("scene");
        let scene = engine::load(&source).expect("the scene derives");
        let d = &scene.derivation;
        let n = d.coords.len();
        let time = per_call(|| {
            let s = engine::load(&source).expect("derives");
            std::hint::black_box(s);
        });
        let mut prepared =
            engine::numbers::prepare(&source, &[], engine::Options::default()).expect("prepares");
        let inputs = prepared.dynamics_inputs();
        let outputs = prepared.dynamics_exprs();
        let program = prepared.lower(&inputs, &outputs).expect("lowers");
        let name = rel.rsplit('/').next().unwrap_or(rel);
        outln!("| {name} | {n} | {} | {} |", seconds(time), program.op_counts().total());
    }
    outln!();
}
