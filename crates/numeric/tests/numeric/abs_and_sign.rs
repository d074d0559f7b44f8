//! `abs` and `sign` in numbers: sign is 0 at 0 (not `f64::signum`'s 1), on the tape and in
//! one-off evaluation alike.

use cas::{Func, Pool};

#[test]
fn sign_is_zero_at_zero_and_abs_is_the_magnitude() {
    use numeric::elementary::{apply, sign};
    assert_eq!(sign(0.0), 0.0);
    assert_eq!(sign(-0.25), -1.0);
    assert_eq!(sign(3.0), 1.0);
    assert!(sign(f64::NAN).is_nan());
    assert_eq!(apply(Func::Abs, -2.5), 2.5);
    let mut p = Pool::new();
    let xs = p.coordinate("x");
    let x = p.sym(xs);
    let s = p.func(Func::Sign, x);
    let a = p.func(Func::Abs, x);
    let e = p.mul2(s, a);
    let program = numeric::lower(&p, &[xs], &[e]).expect("lowers");
    let mut out = [0.0];
    for v in [-2.0, 0.0, 0.5] {
        numeric::Tape::new(program.clone()).eval(&[v], &mut out);
        assert_eq!(out[0], v, "sign(x)*|x| at {v}");
    }
}
