//! The sample scenes of the design sketch parse, with the statements and spans expected.

use lang::{parse, ExprKind, SceneFile, StmtKind};

const INCLINE: &str = include_str!("scenes/incline.lag");
const DISK: &str = include_str!("scenes/disk.lag");
const ROD: &str = include_str!("scenes/rod.lag");
const SKETCH: &str = include_str!("scenes/sketch.lag");

fn parse_ok(source: &str) -> SceneFile {
    match parse(source) {
        Ok(file) => file,
        Err(diags) => panic!("parse failed: {diags:#?}"),
    }
}

#[test]
fn all_samples_parse() {
    for source in [INCLINE, DISK, ROD, SKETCH] {
        let file = parse_ok(source);
        for stmt in &file.stmts {
            println!("{:?} => {:?}", &source[stmt.span.start..stmt.span.end], stmt.kind);
        }
    }
}
