//! Rust source for programs: one function per program, plus the helpers they call. The
//! result needs only `std`.

use std::fmt::Write;

use cas::Func;

use crate::source::{self, Call, Dialect};
use numeric::Program;

/// A literal that reads back as exactly `v`.
pub fn literal(v: f64) -> String {
    if v.is_nan() {
        "f64::NAN".to_string()
    } else if v.is_infinite() {
        if v > 0.0 { "f64::INFINITY" } else { "f64::NEG_INFINITY" }.to_string()
    } else {
        // `{:?}` prints the shortest text that parses back to the same bits.
        let text = format!("{v:?}");
        if v < 0.0 {
            format!("({text}_f64)")
        } else {
            format!("{text}_f64")
        }
    }
}

/// The source of `pub fn NAME(input: &[f64; N], out: &mut [f64; K])`, computing the program's
/// outputs from its inputs with the same operations, in the same order, as the tape.
pub fn function(program: &Program, name: &str, doc: &str) -> String {
    source::function(program, name, doc, &Rust)
}

/// Rust's spelling of a straight-line function.
struct Rust;

impl Dialect for Rust {
    fn literal(&self, v: f64) -> String {
        literal(v)
    }

    fn open(&self, name: &str, doc: &str, inputs: usize, reads: usize, outputs: usize) -> String {
        let mut s = String::new();
        for line in doc.lines() {
            let _ = writeln!(s, "/// {line}");
        }
        // A program whose outputs are constants (a scene's partials in a coordinate nothing
        // depends on) reads no input: its parameter is named unused, as rustc asks.
        let input = if reads == 0 { "_input" } else { "input" };
        let _ =
            writeln!(s, "pub fn {name}({input}: &[f64; {inputs}], out: &mut [f64; {outputs}]) {{");
        s
    }

    fn define(&self, reg: usize, value: &str) -> String {
        format!("    let r{reg} = {value};\n")
    }

    fn call(&self, operation: Call, operands: &[String]) -> String {
        let a = &operands[0];
        match operation {
            Call::Sqrt => format!("{a}.sqrt()"),
            Call::PowF => format!("{a}.powf({})", operands[1]),
            Call::PowInt(n) => format!("pow_int({a}, {n})"),
            Call::Func(Func::Sign) => format!("sign({a})"),
            Call::Func(Func::Ln) => format!("{a}.ln()"),
            Call::Func(f) => format!("{a}.{}()", f.name()),
            Call::Atan2 => format!("{a}.atan2({})", operands[1]),
        }
    }
}

/// Helpers the generated functions call: integer powers as the tape computes them, and a
/// dense solver (Gaussian elimination with partial pivoting) for `a·x = b`.
pub const HELPERS: &str = r#"/// −1, 0 or 1 by the sign of `x`, as the tape computes it (`f64::signum` gives 1 at 0).
pub fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        x * 0.0
    }
}

/// `x^n` by binary powering, as the tape computes it.
pub fn pow_int(x: f64, n: i32) -> f64 {
    let mut base = x;
    let mut k = n.unsigned_abs();
    let mut acc = 1.0;
    while k > 0 {
        if k & 1 == 1 {
            acc *= base;
        }
        base *= base;
        k >>= 1;
    }
    if n < 0 {
        1.0 / acc
    } else {
        acc
    }
}

/// Solves `a·x = b` in place (`a` row-major, n×n; the solution replaces `b`) by Gaussian
/// elimination with partial pivoting. Returns false when a pivot vanishes.
pub fn solve_in_place(n: usize, a: &mut [f64], b: &mut [f64]) -> bool {
    for k in 0..n {
        let mut pivot = k;
        for i in k + 1..n {
            if a[i * n + k].abs() > a[pivot * n + k].abs() {
                pivot = i;
            }
        }
        if a[pivot * n + k] == 0.0 || !a[pivot * n + k].is_finite() {
            return false;
        }
        if pivot != k {
            for j in 0..n {
                a.swap(k * n + j, pivot * n + j);
            }
            b.swap(k, pivot);
        }
        for i in k + 1..n {
            let factor = a[i * n + k] / a[k * n + k];
            for j in k..n {
                a[i * n + j] -= factor * a[k * n + j];
            }
            b[i] -= factor * b[k];
        }
    }
    for k in (0..n).rev() {
        let mut v = b[k];
        for j in k + 1..n {
            v -= a[k * n + j] * b[j];
        }
        b[k] = v / a[k * n + k];
    }
    true
}
"#;
