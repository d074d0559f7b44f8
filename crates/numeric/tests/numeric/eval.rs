//! The evaluator of parameter values, initial states and checks against the tape the
//! integrators run: the same bits, whatever the inputs' order or the other outputs lowered
//! with an expression.

use cas::{ExprId, Func, Pool, SymId};
use numeric::{lower, Evaluator, ScaledEvaluator, Tape};

/// A few expressions that exercise every instruction: angle sums, negative terms, integer,
/// half-integer and real powers, quotients, functions and atan2.
fn expressions(p: &mut Pool) -> (Vec<SymId>, Vec<ExprId>) {
    let (x, y, l) = (p.coordinate("x"), p.coordinate("y"), p.param("l"));
    let (xe, ye, le) = (p.sym(x), p.sym(y), p.sym(l));
    let d = p.sub(xe, ye);
    let sd = p.sin(d);
    let cd = p.cos(d);
    let y2 = p.powi(ye, 2);
    let cubic = p.mul(&[sd, cd, y2, le]);
    let root = p.powq(le, &cas::number::ratio(-3, 2));
    let seven = p.int(7);
    let sum = p.add(&[cubic, root, seven]);
    let k = p.scale(sum, &cas::number::ratio(-5, 3));
    let quotient = p.div(k, cd);
    let ex = p.func(Func::Exp, d);
    let lg = p.func(Func::Ln, le);
    let real = p.pow(le, xe);
    let angle = p.atan2(ye, xe);
    let tanh = p.func(Func::Tanh, xe);
    let t = p.func(Func::Tan, d);
    let mixed = p.add(&[ex, lg, real, angle, tanh, t]);
    (vec![x, y, l], vec![sum, quotient, mixed, cd])
}

fn by_symbol(p: &Pool, syms: &[SymId], point: &[f64]) -> Vec<f64> {
    let mut values = vec![f64::NAN; p.symbol_count()];
    for (s, v) in syms.iter().zip(point) {
        values[s.index()] = *v;
    }
    values
}

const POINTS: [[f64; 3]; 4] =
    [[0.3, 1.7, 2.0], [2.5, -0.4, 0.7], [-1.1, 0.9, 1.3], [1e-3, 1e3, 1e-6]];

#[test]
fn the_evaluator_and_the_tape_agree_bit_for_bit() {
    let mut p = Pool::new();
    let (syms, exprs) = expressions(&mut p);
    // The tape as a simulation lowers it: inputs in an order of its own choosing.
    let inputs = [syms[2], syms[0], syms[1]];
    let mut tape = Tape::new(lower(&p, &inputs, &exprs).unwrap());
    let mut evaluator = Evaluator::new(&p, &exprs);
    for point in POINTS {
        let mut out = vec![0.0; exprs.len()];
        tape.eval(&[point[2], point[0], point[1]], &mut out);
        let values = by_symbol(&p, &syms, &point);
        let evaluated = evaluator.eval(&values);
        for (i, (a, b)) in out.iter().zip(evaluated).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "expression {i} at {point:?}: {a} vs {b}");
        }
        for (i, e) in exprs.iter().enumerate() {
            let alone = numeric::eval(&p, *e, &values);
            assert_eq!(alone.to_bits(), out[i].to_bits(), "expression {i} alone at {point:?}");
        }
    }
}

#[test]
fn a_symbol_without_a_value_is_nan() {
    let mut p = Pool::new();
    let (syms, exprs) = expressions(&mut p);
    let values = by_symbol(&p, &syms[..2], &[0.3, 1.7]);
    assert!(numeric::eval(&p, exprs[0], &values).is_nan());
    // Past the end of the values, too.
    assert!(numeric::eval(&p, exprs[0], &[]).is_nan());
}

#[test]
fn the_size_of_a_sum_is_the_sum_of_its_terms_magnitudes() {
    let mut p = Pool::new();
    let (x, y) = (p.coordinate("x"), p.coordinate("y"));
    let (xe, ye) = (p.sym(x), p.sym(y));
    let three = p.int(3);
    let minus = p.scale(ye, &cas::number::ratio(-2, 1));
    let sum = p.add(&[xe, minus, three]);
    let values = by_symbol(&p, &[x, y], &[1.0, 2.0]);
    assert_eq!(numeric::value_and_scale(&p, sum, &values), (0.0, 8.0));
    let mut both = ScaledEvaluator::new(&p, &[sum, xe]);
    assert_eq!(both.eval(&values), vec![(0.0, 8.0), (1.0, 1.0)]);
}

/// The numbers only spare the zero test its algebra: with or without them, the answers agree.
#[test]
fn the_zero_test_answers_the_same_with_the_probe() {
    for probe in [false, true] {
        let mut p = Pool::new();
        if probe {
            p.set_zero_test(Box::new(numeric::GenericPoints));
        }
        let x = p.coordinate("x");
        let xe = p.sym(x);
        let (s, c) = (p.sin(xe), p.cos(xe));
        let (s2, c2) = (p.powi(s, 2), p.powi(c, 2));
        let one = p.one();
        let pythagoras = p.add(&[s2, c2]);
        let zero = p.sub(pythagoras, one);
        let nonzero = p.sub(s2, c2);
        assert!(p.is_identically_zero(zero), "probe {probe}");
        assert!(!p.is_identically_zero(nonzero), "probe {probe}");
    }
}
