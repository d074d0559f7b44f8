//! `abs` and `sign`: their exact values at numbers, their derivatives almost everywhere, and
//! how they print.

use cas::{Func, Pool, Style};

#[test]
fn abs_and_sign_of_numbers_and_multiples_of_pi_are_exact() {
    let mut p = Pool::new();
    let ascii = |p: &Pool, e| p.print(e, Style::Ascii);
    let minus_three_halves = p.ratio(-3, 2);
    let a = p.func(Func::Abs, minus_three_halves);
    assert_eq!(ascii(&p, a), "3/2");
    let s = p.func(Func::Sign, minus_three_halves);
    assert_eq!(ascii(&p, s), "-1");
    let zero = p.zero();
    let s0 = p.func(Func::Sign, zero);
    assert_eq!(ascii(&p, s0), "0");
    let pi = p.pi();
    let minus_two_pi = p.scale(pi, &cas::number::int(-2));
    let a = p.func(Func::Abs, minus_two_pi);
    assert_eq!(ascii(&p, a), "2*pi");
    let s = p.func(Func::Sign, minus_two_pi);
    assert_eq!(ascii(&p, s), "-1");
}

#[test]
fn abs_is_even_sign_is_odd_and_abs_of_abs_is_abs() {
    let mut p = Pool::new();
    let x = p.coordinate("x");
    let x = p.sym(x);
    let minus_x = p.neg(x);
    let (a, b) = (p.func(Func::Abs, x), p.func(Func::Abs, minus_x));
    assert_eq!(a, b);
    let (s, t) = (p.func(Func::Sign, x), p.func(Func::Sign, minus_x));
    assert_eq!(p.neg(s), t);
    assert_eq!(p.func(Func::Abs, a), a);
}

#[test]
fn the_derivative_of_abs_is_sign_and_of_sign_is_zero() {
    let mut p = Pool::new();
    let xs = p.coordinate("x");
    let x = p.sym(xs);
    let x2 = p.powi(x, 2);
    let one = p.one();
    let u = p.sub(x2, one);
    let a = p.func(Func::Abs, u);
    let d = p.diff(a, xs);
    assert_eq!(p.print(d, Style::Ascii), "2*sign(-1 + x^2)*x");
    let s = p.func(Func::Sign, u);
    let d = p.diff(s, xs);
    assert_eq!(d, p.zero());
}

#[test]
fn abs_prints_as_bars_except_in_scene_syntax() {
    let mut p = Pool::new();
    let xs = p.coordinate("theta");
    let x = p.sym(xs);
    let a = p.func(Func::Abs, x);
    let a2 = p.powi(a, 2);
    let s = p.func(Func::Sign, x);
    assert_eq!(p.print(a, Style::Ascii), "abs(theta)");
    assert_eq!(p.print(a, Style::Unicode), "|θ|");
    assert_eq!(p.print(a, Style::Latex), "\\left|\\theta\\right|");
    assert_eq!(p.print(a2, Style::Unicode), "|θ|²");
    assert_eq!(p.print(a2, Style::Latex), "\\left|\\theta\\right|^{2}");
    assert_eq!(p.print(s, Style::Ascii), "sign(theta)");
    assert_eq!(p.print(s, Style::Latex), "\\operatorname{sgn}\\left(\\theta\\right)");
}
