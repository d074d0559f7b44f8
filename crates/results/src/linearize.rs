//! `linearize`'s result as data: [`report`], the object the command writes as JSON
//! (expressions as scene-syntax text beside their trees, numbers as numbers), and [`python`],
//! the dict the Python package returns (exact matrices, NumPy arrays, complex eigenvalues).
//! The two shapes differ for their readers' sake (the report names its rows, Python's dict
//! keeps A, B, C, D at the top); both are built here from the same pieces.

use cas::{ExprId, Pool, Style, SymId};
use engine::linearize::{CaseNumbers, Linearized, Rank, Sweep};

use crate::{Data, Exact, MapBuilder};

fn exact(pool: &Pool, rows: &[Vec<ExprId>]) -> Data {
    Data::ExactMatrix(Exact::rows(pool, rows))
}

/// Eigenvalues as `[re, im]` pairs in a list (the report) or complex numbers.
fn eigenvalues(values: &[(f64, f64)]) -> Vec<Data> {
    values.iter().map(|(re, im)| Data::Complex(*re, *im)).collect()
}

fn rank(r: Rank) -> Data {
    let mut out = MapBuilder::default();
    out.put("rank", Data::count(r.rank));
    out.put("of", Data::count(r.full));
    out.put("tolerance", Data::Float(r.tolerance));
    out.put("smallest_counted", Data::Float(r.smallest_counted));
    out.put("largest_left_out", Data::Float(r.largest_left_out));
    out.put("doubtful", Data::Bool(r.doubtful()));
    out.done()
}

/// The report of `lagrange linearize --json`: one `linearization` object.
pub fn report(l: &Linearized) -> Data {
    let d = &l.derivation;
    let pool = &d.model.pool;
    let lin = &l.linearization;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let names =
        |s: &mut dyn Iterator<Item = SymId>| Data::List(s.map(|s| Data::text(name(s))).collect());
    let about = lin.reference().into_iter().map(|(q, rate, value)| {
        let key = if rate { format!("{}'", name(q)) } else { name(q) };
        (key, Data::text(pool.print(value, Style::Ascii)))
    });
    let parameters =
        d.model.params.iter().zip(&l.at.parameters).map(|(p, v)| (p.name.clone(), Data::Float(*v)));
    let matrix = |e: &[Vec<ExprId>], v: &[Vec<f64>]| {
        Data::Map(vec![("exact".into(), exact(pool, e)), ("value".into(), Data::matrix(v))])
    };
    let constraints: Vec<Data> = lin
        .constraints()
        .iter()
        .zip(&l.at.multipliers)
        .map(|(c, v)| {
            let mut out = MapBuilder::default();
            out.put("name", Data::text(&d.model.constraints[c.constraint].name));
            out.put("multiplier", Data::text(name(c.lambda)));
            out.put("multiplier_value", Data::Float(*v));
            let jacobian = c.jacobian.iter().map(|e| Data::Exact(Exact::of(pool, *e))).collect();
            out.put("jacobian", Data::List(jacobian));
            out.done()
        })
        .collect();
    let mut out = MapBuilder::default();
    out.put("coordinates", names(&mut lin.coords.iter().copied()));
    let cyclic = lin.coords.iter().zip(&lin.cyclic).filter(|(_, c)| **c).map(|(q, _)| *q);
    out.put("cyclic", names(&mut cyclic.into_iter()));
    out.put("about", Data::Map(about.collect()));
    out.put("exact_reference", Data::Bool(l.exact_reference));
    out.put("parameters", Data::Map(parameters.collect()));
    out.put("accelerations", Data::floats(&l.at.accelerations));
    out.put("M", matrix(&l.mass, &l.at.mass));
    out.put("C", matrix(&l.damping, &l.at.damping));
    out.put("K", matrix(&l.stiffness, &l.at.stiffness));
    if !constraints.is_empty() {
        out.put("constraints", Data::List(constraints));
    }
    if let CaseNumbers::Holonomic { basis: Some(basis) } = &l.at.case {
        out.put("basis", Data::matrix(basis));
    }
    if let (Some(r), CaseNumbers::InRates { kinematics: g }) = (lin.in_rates(), &l.at.case) {
        out.put("independent_rates", names(&mut r.rates.iter().copied()));
        out.put("positions_kept", names(&mut r.kept.iter().map(|&i| lin.coords[i])));
        out.put("G", matrix(&r.kinematics, g));
    }
    out.put("state", Data::texts(&l.state));
    out.put("A", Data::matrix(&l.at.first_order.a));
    out.put("first_order", first_order(l));
    out.put("cyclic_zeros", Data::count(l.at.cyclic_zeros));
    out.put("first_integrals", Data::count(l.at.first_integrals));
    out.put("eigenvalues", Data::List(eigenvalues(&l.at.eigenvalues)));
    out.put("bounds", Data::floats(&l.at.bounds));
    out.put("stability", Data::text(l.at.stability.name()));
    out.put("tolerance", Data::Float(l.at.tolerance));
    if let Some(sweep) = &l.sweep {
        out.put("sweep_parameter", Data::text(&sweep.parameter));
        out.put("sweep", Data::List(sweep_rows(sweep, Data::List)));
        out.put("changes", Data::List(changes(sweep, true)));
    }
    Data::Map(vec![("linearization".into(), out.done())])
}

/// The state space, an object of its own: at the top level `C` is the damping's, so A, B, C
/// and D sit here with their rows named by `state` (the top-level `state` and `A` stay for
/// readers of both).
fn first_order(l: &Linearized) -> Data {
    let pool = &l.derivation.model.pool;
    let space = &l.at.first_order;
    let mut out = MapBuilder::default();
    out.put("state", Data::texts(&l.state));
    out.put("inputs", Data::texts(&l.inputs));
    out.put("outputs", Data::texts(&l.outputs));
    out.put("A", Data::matrix(&space.a));
    out.put("B", Data::matrix(&space.b));
    out.put("C", Data::matrix(&space.c));
    out.put("D", Data::matrix(&space.d));
    if let Some(e) = &l.exact {
        let coords = &l.linearization.coords;
        let names: Vec<String> = e.state.iter().map(|c| c.name(pool, coords)).collect();
        let mut exact_form = MapBuilder::default();
        exact_form.put("state", Data::texts(&names));
        exact_form.put("A", exact(pool, &e.a));
        exact_form.put("B", exact(pool, &e.b));
        out.put("exact", exact_form.done());
    }
    out.put("controllability", Data::or_null(space.controllability.map(rank)));
    out.put("observability", Data::or_null(space.observability.map(rank)));
    out.done()
}

/// A sweep's rows, their eigenvalues gathered by `eigenvalues_as` (a list or an array).
fn sweep_rows(sweep: &Sweep, eigenvalues_as: fn(Vec<Data>) -> Data) -> Vec<Data> {
    let row = |r: &engine::linearize::Row| {
        let mut out = MapBuilder::default();
        out.put("value", Data::Float(r.value));
        out.put("eigenvalues", eigenvalues_as(eigenvalues(&r.eigenvalues)));
        out.put("bounds", Data::floats(&r.bounds));
        out.put("stability", Data::text(r.stability.name()));
        out.done()
    };
    sweep.rows.iter().map(row).collect()
}

/// Where the verdict changes, with the bisection's bracket or without.
fn changes(sweep: &Sweep, bracket: bool) -> Vec<Data> {
    let change = |c: &engine::linearize::Change| {
        let mut out = MapBuilder::default();
        out.put("value", Data::Float(c.value));
        out.put("from", Data::text(c.from.name()));
        out.put("to", Data::text(c.to.name()));
        if bracket {
            out.put("bracket", Data::floats(&[c.bracket.0, c.bracket.1]));
        }
        out.done()
    };
    sweep.changes.iter().map(change).collect()
}

/// What the Python package's `linearize` returns.
pub fn python(l: &Linearized) -> Data {
    let pool = &l.derivation.model.pool;
    let space = &l.at.first_order;
    let mut out = MapBuilder::default();
    // An empty list has no shape for NumPy: each matrix carries its columns.
    let size = space.state.len();
    let inputs = l.inputs.len();
    let shaped = |rows: &[Vec<f64>], columns: usize| Data::Matrix { rows: rows.to_vec(), columns };
    out.put("state", Data::texts(&l.state));
    out.put("M", exact(pool, &l.mass));
    // `C` is the output matrix's key in this dict, where it follows M as the damping's would:
    // the damping is not handed to Python.
    out.put("C", shaped(&space.c, size));
    out.put("K", exact(pool, &l.stiffness));
    out.put("exact_reference", Data::Bool(l.exact_reference));
    out.put("A", shaped(&space.a, size));
    out.put("B", shaped(&space.b, inputs));
    out.put("D", shaped(&space.d, inputs));
    out.put("inputs", Data::texts(&l.inputs));
    out.put("outputs", Data::texts(&l.outputs));
    out.put("cyclic_zeros", Data::count(l.at.cyclic_zeros));
    if let Some(e) = &l.exact {
        let mut matrices = MapBuilder::default();
        matrices.put("A", exact(pool, &e.a));
        matrices.put("B", exact(pool, &e.b));
        matrices.put("C", exact(pool, &e.c));
        matrices.put("D", exact(pool, &e.d));
        out.put("exact", matrices.done());
    }
    for (key, r) in
        [("controllability", space.controllability), ("observability", space.observability)]
    {
        if let Some(r) = r {
            out.put(key, rank(r));
        }
    }
    out.put("eigenvalues", Data::Array(eigenvalues(&l.at.eigenvalues)));
    out.put("bounds", Data::floats(&l.at.bounds));
    out.put("stability", Data::text(l.at.stability.name()));
    out.put("tolerance", Data::Float(l.at.tolerance));
    if let Some(sweep) = &l.sweep {
        let mut item = MapBuilder::default();
        item.put("parameter", Data::text(&sweep.parameter));
        item.put("rows", Data::List(sweep_rows(sweep, Data::Array)));
        item.put("changes", Data::List(changes(sweep, false)));
        out.put("sweep", item.done());
    }
    out.done()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(data: &Data) -> Vec<&str> {
        match data {
            Data::Map(entries) => entries.iter().map(|(k, _)| k.as_str()).collect(),
            _ => panic!("not a map: {data:?}"),
        }
    }

    fn pendulum() -> Linearized {
        let source = include_str!("../../../examples/classics/simple_pendulum.lag");
        let options =
            engine::linearize::Options { about: Some("theta = 0".into()), ..Default::default() };
        engine::linearize::linearize(source, &options).expect("the pendulum linearizes")
    }

    #[test]
    fn each_key_appears_once_in_either_shape() {
        let l = pendulum();
        let python = python(&l);
        let mut seen = keys(&python);
        assert_eq!(&seen[..4], ["state", "M", "C", "K"]);
        seen.sort_unstable();
        let before = seen.len();
        seen.dedup();
        assert_eq!(seen.len(), before, "a key twice in {seen:?}");
        let Data::Map(report) = report(&l) else { panic!("the report is a map") };
        assert_eq!(report[0].0, "linearization");
        assert_eq!(keys(&report[0].1)[..3], ["coordinates", "cyclic", "about"]);
    }

    #[test]
    fn an_exact_stiffness_names_its_parameters_without_the_pool() {
        let l = pendulum();
        let Data::ExactMatrix(k) = &keys_value(&python(&l), "K") else { panic!("K is exact") };
        fn constants(t: &crate::Term, out: &mut Vec<String>) {
            match t {
                crate::Term::Constant(name) => out.push(name.clone()),
                crate::Term::Add(_, parts) | crate::Term::Mul(_, parts) => {
                    parts.iter().for_each(|(t, _)| constants(t, out))
                }
                crate::Term::Pow(a, b) | crate::Term::Atan2(a, b) => {
                    constants(a, out);
                    constants(b, out);
                }
                crate::Term::Func(_, a) => constants(a, out),
                _ => {}
            }
        }
        let mut names = Vec::new();
        constants(&k[0][0].term, &mut names);
        names.sort_unstable();
        assert_eq!(names, ["L", "g", "m"], "K = {}", k[0][0].text);
    }

    fn keys_value(data: &Data, key: &str) -> Data {
        let Data::Map(entries) = data else { panic!("not a map") };
        entries.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone()).expect("the key")
    }
}
