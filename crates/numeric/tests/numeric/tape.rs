//! The tape against a direct walk of the expression, the evaluator against the tape bit for
//! bit, and the sharing that lowering promises.

use cas::{ExprId, Func, Node, Pool};
use numeric::elementary::{apply, atan2, pow};
use numeric::{lower, to_f64, LowerError, Tape};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-13 * a.abs().max(b.abs()).max(1.0)
}

/// The value of `e` by a walk of the tree as written, none of lowering's rewrites (angle sums,
/// subtraction for negative terms, one division per product): the oracle the tape is held to.
fn reference(p: &Pool, e: ExprId, values: &[f64]) -> f64 {
    match p.node(e) {
        Node::Num(q) => to_f64(q),
        Node::Sym(s) => values[s.index()],
        Node::Pi => std::f64::consts::PI,
        Node::Add(c, terms) => {
            terms.iter().fold(to_f64(c), |acc, (t, k)| acc + to_f64(k) * reference(p, *t, values))
        }
        Node::Mul(c, factors) => factors
            .iter()
            .fold(to_f64(c), |acc, (b, x)| acc * pow(reference(p, *b, values), to_f64(x))),
        Node::Pow(b, x) => pow(reference(p, *b, values), reference(p, *x, values)),
        Node::Func(f, a) => apply(*f, reference(p, *a, values)),
        Node::Atan2(y, x) => atan2(reference(p, *y, values), reference(p, *x, values)),
    }
}

/// Sums with negative terms, roots, powers, a quotient, exp, atan2 and a constant in x, y
/// and t0: the symbols and the expressions.
fn assorted(p: &mut Pool) -> ([cas::SymId; 3], Vec<ExprId>) {
    let (x, y, t) = (p.coordinate("x"), p.coordinate("y"), p.param("t0"));
    let (xe, ye, te) = (p.sym(x), p.sym(y), p.sym(t));
    let sx = p.sin(xe);
    let cy = p.cos(ye);
    let xy = p.mul(&[sx, cy, te]);
    let half = cas::number::ratio(1, 2);
    let r = p.powq(xe, &half);
    let r3 = p.powq(ye, &cas::number::ratio(-3, 2));
    let inv = p.powi(ye, -2);
    let minus = p.neg(r3);
    let three = p.int(3);
    let lin = p.add(&[xy, r, minus, inv, three]);
    let e = p.func(Func::Exp, lin);
    let a2 = p.atan2(ye, xe);
    let pw = p.pow(xe, ye);
    let k = p.scale(pw, &cas::number::ratio(-7, 3));
    let quotient = p.div(sx, ye);
    ([x, y, t], vec![lin, e, a2, k, xe, three, quotient])
}

#[test]
fn tape_agrees_with_a_walk_of_the_tree() {
    let mut p = Pool::new();
    let ([x, y, t], outputs) = assorted(&mut p);
    let program = lower(&p, &[x, y, t], &outputs).unwrap();
    let mut tape = Tape::new(program);
    let mut out = vec![0.0; outputs.len()];
    for (xv, yv, tv) in [(0.3, 1.7, 2.0), (2.5, 0.4, -1.0), (1.0, 1.0, 0.0)] {
        tape.eval(&[xv, yv, tv], &mut out);
        let mut values = vec![f64::NAN; p.symbol_count()];
        values[x.index()] = xv;
        values[y.index()] = yv;
        values[t.index()] = tv;
        for (o, e) in out.iter().zip(&outputs) {
            let want = reference(&p, *e, &values);
            assert!(close(*o, want), "{o} vs {want}");
        }
    }
}

#[test]
fn shared_subexpressions_are_computed_once() {
    let mut p = Pool::new();
    let x = p.coordinate("x");
    let xe = p.sym(x);
    let s = p.sin(xe);
    let s2 = p.powi(s, 2);
    let a = p.add(&[s2, xe]);
    let b = p.mul(&[s2, xe]);
    let program = lower(&p, &[x], &[a, b, s2]).unwrap();
    let c = program.op_counts();
    assert_eq!(c.func, 1, "sin once");
    assert_eq!(c.mul, 2, "the square and the product");
    assert_eq!(c.add, 1);
}

#[test]
fn only_what_the_outputs_reach_is_lowered() {
    let mut p = Pool::new();
    let x = p.coordinate("x");
    let xe = p.sym(x);
    let _unused = p.cos(xe);
    let s = p.sin(xe);
    let program = lower(&p, &[x], &[s]).unwrap();
    assert_eq!(program.code.len(), 1);
}

#[test]
fn an_unbound_symbol_is_an_error() {
    let mut p = Pool::new();
    let (x, y) = (p.coordinate("x"), p.coordinate("y"));
    let (xe, ye) = (p.sym(x), p.sym(y));
    let e = p.add(&[xe, ye]);
    assert_eq!(lower(&p, &[x], &[e]).unwrap_err(), LowerError::UnboundSymbol(y));
}

#[test]
fn integer_powers_match_repeated_multiplication() {
    assert_eq!(numeric::pow_int(3.0, 4), 81.0);
    assert_eq!(numeric::pow_int(2.0, -3), 0.125);
    assert_eq!(numeric::pow_int(-2.0, 3), -8.0);
    assert_eq!(numeric::pow_int(5.0, 0), 1.0);
}

/// sin and cos of θ₁ − θ₂ and θ₂ − θ₃ come from one sine and one cosine per angle, and the
/// differences themselves, no longer read, are not computed.
#[test]
fn angle_differences_share_one_sine_and_cosine_per_angle() {
    let mut p = Pool::new();
    let q: Vec<_> = (1..=3).map(|i| p.coordinate(&format!("q{i}"))).collect();
    let e: Vec<_> = q.iter().map(|s| p.sym(*s)).collect();
    let d12 = p.sub(e[0], e[1]);
    let d23 = p.sub(e[1], e[2]);
    let outputs = [p.sin(d12), p.cos(d12), p.sin(d23), p.cos(d23)];
    let program = lower(&p, &q, &outputs).unwrap();
    let functions = program.code.iter().filter(|i| matches!(i, numeric::Instr::Func(..))).count();
    assert_eq!(functions, 6, "{:?}", program.code);
    let values = [0.3, -1.1, 2.0];
    let mut out = vec![0.0; outputs.len()];
    Tape::new(program).eval(&values, &mut out);
    let (a, b) = (0.3f64 + 1.1, -1.1f64 - 2.0);
    let expected =
        [apply(Func::Sin, a), apply(Func::Cos, a), apply(Func::Sin, b), apply(Func::Cos, b)];
    for (a, b) in out.iter().zip(expected) {
        assert!(close(*a, b), "{a} vs {b}");
    }
}

#[test]
fn a_batch_gives_the_bits_of_the_points_one_at_a_time() {
    let mut p = Pool::new();
    let ([x, y, t], outputs) = assorted(&mut p);
    let program = lower(&p, &[x, y, t], &outputs).unwrap();
    // Two whole chunks and a part of one; x < 0 makes NaN roots, y = 0 infinite powers.
    let points = 2 * numeric::LANES + 5;
    let inputs: Vec<f64> = (0..points)
        .flat_map(|i| {
            let i = i as f64;
            [(i * 0.37 % 4.0) - 2.0, (i * 0.61 % 3.0) * (i % 5.0), i * 0.25 - 1.0]
        })
        .collect();
    for (_, one, many) in tape_and_batch(program, &inputs) {
        for (a, b) in one.iter().zip(&many) {
            assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()), "{a} vs {b}");
        }
    }
}

/// Each point of `inputs` (a row each) with the program's outputs there on the tape and on
/// the batch tape.
fn tape_and_batch(program: numeric::Program, inputs: &[f64]) -> Vec<(&[f64], Vec<f64>, Vec<f64>)> {
    let (width, outputs) = (program.inputs, program.outputs.len());
    let mut tape = Tape::new(program.clone());
    let mut many = vec![0.0; inputs.len() / width * outputs];
    numeric::BatchTape::new(program).eval_many(inputs, &mut many);
    let rows = inputs.chunks(width).zip(many.chunks(outputs));
    rows.map(|(point, batch)| {
        let mut one = vec![0.0; outputs];
        tape.eval(point, &mut one);
        (point, one, batch.to_vec())
    })
    .collect()
}

/// Sines and cosines of one register, which both tapes fuse (the batch tape computing eight
/// lanes at once), beside a lone sine and a lone cosine, at angles, huge arguments, NaN and
/// infinities mixed in every chunk: the batch gives the tape's bits.
#[test]
fn a_batch_with_fused_sines_and_cosines_gives_the_tapes_bits() {
    let mut p = Pool::new();
    let (x, y, z) = (p.coordinate("x"), p.coordinate("y"), p.coordinate("z"));
    let (xe, ye, ze) = (p.sym(x), p.sym(y), p.sym(z));
    let difference = p.sub(xe, ye);
    let (sd, cd) = (p.sin(difference), p.cos(difference));
    let (sx, cx) = (p.sin(xe), p.cos(xe));
    let lone_sine = p.sin(ze);
    let product = p.mul(&[sx, cx]);
    let lone_cosine = p.cos(product);
    let outputs = [sd, cd, product, lone_sine, lone_cosine, cx];
    let program = lower(&p, &[x, y, z], &outputs).unwrap();
    // sin x, cos x, sin y and cos y (the angle difference's by the angle-sum formulas) and the
    // lone sin z: two pairs to fuse.
    let sines = program.code.iter().filter(|i| matches!(i, numeric::Instr::Func(Func::Sin, _)));
    assert_eq!(sines.count(), 3, "the program's sines");
    let odd = [0.0, -0.0, 1e-9, 1e6, -3e8, 1e300, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
    let points = 40 * numeric::LANES + 3;
    let inputs: Vec<f64> = (0..points)
        .flat_map(|i| {
            let angle = |k: usize| ((k as f64 * 0.618_033_988_749_895) % 1.0) * 20.0 - 10.0;
            let x = if i % 7 == 3 { odd[i % odd.len()] } else { angle(3 * i) };
            [x, angle(3 * i + 1), if i % 5 == 1 { odd[i % odd.len()] } else { angle(3 * i + 2) }]
        })
        .collect();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (point, one, many) in tape_and_batch(program, &inputs) {
        assert_eq!(bits(&many), bits(&one), "at {point:?}");
    }
}
