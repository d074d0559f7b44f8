//! Rust source for programs: one function per program, plus the helpers they call. The
//! result needs only `std`.

use std::fmt::Write;

use cas::Func;

use crate::lower::{Instr, Program, Reg};

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
    let inputs = program.inputs;
    let constants = program.constants.len();
    let base = inputs + constants;
    let mut used = vec![false; program.registers()];
    let mut mark = |r: Reg| used[r as usize] = true;
    for i in &program.code {
        match *i {
            Instr::Add(a, b)
            | Instr::Sub(a, b)
            | Instr::Mul(a, b)
            | Instr::Div(a, b)
            | Instr::PowF(a, b)
            | Instr::Atan2(a, b) => {
                mark(a);
                mark(b);
            }
            Instr::Neg(a) | Instr::PowInt(a, _) | Instr::Sqrt(a) | Instr::Func(_, a) => mark(a),
        }
    }
    program.outputs.iter().for_each(|&r| mark(r));

    let operand = |r: Reg| -> String {
        let r = r as usize;
        if (inputs..base).contains(&r) {
            literal(program.constants[r - inputs])
        } else {
            format!("r{r}")
        }
    };
    let mut s = String::new();
    for line in doc.lines() {
        let _ = writeln!(s, "/// {line}");
    }
    let _ = writeln!(
        s,
        "pub fn {name}(input: &[f64; {inputs}], out: &mut [f64; {}]) {{",
        program.outputs.len()
    );
    for (i, _) in used.iter().enumerate().take(inputs).filter(|(_, u)| **u) {
        let _ = writeln!(s, "    let r{i} = input[{i}];");
    }
    for (k, instr) in program.code.iter().enumerate() {
        let reg = base + k;
        if !used[reg] {
            continue;
        }
        let e = match *instr {
            Instr::Add(a, b) => format!("{} + {}", operand(a), operand(b)),
            Instr::Sub(a, b) => format!("{} - {}", operand(a), operand(b)),
            Instr::Mul(a, b) => format!("{} * {}", operand(a), operand(b)),
            Instr::Div(a, b) => format!("{} / {}", operand(a), operand(b)),
            Instr::Neg(a) => format!("-{}", operand(a)),
            Instr::PowInt(a, n) => format!("pow_int({}, {n})", operand(a)),
            Instr::Sqrt(a) => format!("{}.sqrt()", operand(a)),
            Instr::PowF(a, b) => format!("{}.powf({})", operand(a), operand(b)),
            Instr::Func(Func::Sign, a) => format!("sign({})", operand(a)),
            Instr::Func(f, a) => format!("{}.{}()", operand(a), method(f)),
            Instr::Atan2(y, x) => format!("{}.atan2({})", operand(y), operand(x)),
        };
        let _ = writeln!(s, "    let r{reg} = {e};");
    }
    for (i, &r) in program.outputs.iter().enumerate() {
        let _ = writeln!(s, "    out[{i}] = {};", operand(r));
    }
    s.push_str("}\n");
    s
}

fn method(f: Func) -> &'static str {
    match f {
        Func::Ln => "ln",
        other => other.name(),
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
