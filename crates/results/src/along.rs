//! The result of a linearization along a motion, as one tree for every front end: the names
//! of the state, inputs and outputs, the samples' times, A, B, C and D per sample (each an
//! array over the samples, which NumPy stacks into one array of shape samples × rows ×
//! columns) and the state-transition matrix over the motion with how it was integrated.

use engine::along::Linearized;
use nalgebra::DMatrix;

use crate::{Data, MapBuilder};

/// The tree of `lagrange linearize --along --format json` and of Python's
/// `Scene.linearize_along`.
pub fn report(l: &Linearized) -> Data {
    let mut out = MapBuilder::default();
    out.put("state", Data::texts(&l.state));
    out.put("inputs", Data::texts(&l.inputs));
    out.put("outputs", Data::texts(&l.outputs));
    out.put("t", Data::Array(l.times.iter().map(|t| Data::Float(*t)).collect()));
    let per_sample = |pick: fn(&engine::along::Linear) -> &DMatrix<f64>| {
        Data::Array(l.samples.iter().map(|s| matrix(pick(s))).collect())
    };
    out.put("A", per_sample(|s| &s.a));
    out.put("B", per_sample(|s| &s.b));
    out.put("C", per_sample(|s| &s.c));
    out.put("D", per_sample(|s| &s.d));
    let mut transition = MapBuilder::default();
    let (first, last) = (l.times.first(), l.times.last());
    transition.put("from", Data::Float(first.copied().unwrap_or(f64::NAN)));
    transition.put("to", Data::Float(last.copied().unwrap_or(f64::NAN)));
    transition.put("method", Data::text(l.between.name()));
    transition.put("matrix", matrix(&l.transition));
    out.put("transition", transition.done());
    out.done()
}

/// A matrix with its shape, empty or not.
pub fn matrix(m: &DMatrix<f64>) -> Data {
    let rows = (0..m.nrows()).map(|i| m.row(i).iter().copied().collect()).collect();
    Data::Matrix { rows, columns: m.ncols() }
}
