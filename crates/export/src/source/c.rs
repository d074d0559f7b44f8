//! C99 source for programs: one `static` function per program, plus the helpers they call.
//! The result needs only `<math.h>` (libm). Constants are hexadecimal float literals, which
//! C99 reads back exactly.

use std::fmt::Write;

use cas::Func;

use crate::source::{self, Call, Dialect};
use numeric::{Instr, Program};

/// A C99 literal that reads back as exactly `v`: a hexadecimal float such as `0x1.8p+1`
/// (3), in parentheses when negative; `NAN` and `INFINITY` from `<math.h>` otherwise.
pub fn literal(v: f64) -> String {
    if v.is_nan() {
        return "NAN".to_string();
    }
    let magnitude = if v.is_infinite() { "INFINITY".to_string() } else { hex(v.abs()) };
    if v.is_sign_negative() {
        format!("(-{magnitude})")
    } else {
        magnitude
    }
}

/// The hexadecimal form of a finite non-negative float: `0x1.<fraction>p<exponent>`, or
/// `0x0.<fraction>p-1022` below the normal range, trailing zero digits left out.
fn hex(v: f64) -> String {
    let bits = v.to_bits();
    let fraction = bits & ((1u64 << 52) - 1);
    let biased = (bits >> 52) as i64;
    if biased == 0 && fraction == 0 {
        return "0x0p+0".to_string();
    }
    let (lead, exponent) = if biased == 0 { (0, -1022) } else { (1, biased - 1023) };
    let digits = format!("{fraction:013x}");
    let digits = digits.trim_end_matches('0');
    let point = if digits.is_empty() { String::new() } else { format!(".{digits}") };
    format!("0x{lead}{point}p{exponent:+}")
}

/// The source of `static void NAME(const double *input, double *out)`, computing the
/// program's outputs from its inputs with the same operations, in the same order, as the
/// tape.
pub fn function(program: &Program, name: &str, doc: &str) -> String {
    source::function(program, name, doc, &C)
}

/// C's spelling of a straight-line function.
struct C;

impl Dialect for C {
    fn literal(&self, v: f64) -> String {
        literal(v)
    }

    fn open(&self, name: &str, doc: &str, inputs: usize, reads: usize, outputs: usize) -> String {
        let mut s = comment(doc, "");
        let _ = writeln!(s, "static void {name}(const double *input, double *out)\n{{");
        let _ = writeln!(s, "    /* {inputs} values in, {outputs} out. */");
        if reads == 0 {
            // A program of constants; `-Wextra` would warn of the argument it does not read.
            s.push_str("    (void)input;\n");
        }
        s
    }

    fn define(&self, reg: usize, value: &str) -> String {
        format!("    const double r{reg} = {value};\n")
    }

    fn call(&self, operation: Call, operands: &[String]) -> String {
        let a = &operands[0];
        match operation {
            Call::Sqrt => format!("sqrt({a})"),
            Call::PowF => format!("pow({a}, {})", operands[1]),
            Call::PowInt(n) => format!("pow_int({a}, {n})"),
            Call::Func(Func::Sign) => format!("sign({a})"),
            Call::Func(Func::Ln) => format!("log({a})"),
            Call::Func(Func::Abs) => format!("fabs({a})"),
            Call::Func(f) => format!("{}({a})", f.name()),
            Call::Atan2 => format!("atan2({a}, {})", operands[1]),
        }
    }
}

/// `text` as a C comment, each line indented by `indent`.
pub fn comment(text: &str, indent: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    match lines.as_slice() {
        [] => String::new(),
        [one] => format!("{indent}/* {one} */\n"),
        _ => {
            let mut s = format!("{indent}/*\n");
            for line in text.lines() {
                let _ = writeln!(s, "{}", format!("{indent} * {line}").trim_end());
            }
            s.push_str(&format!("{indent} */\n"));
            s
        }
    }
}

/// The helpers `programs` call, and the dense solver (always: every module solves): C
/// refuses a static function it never calls under `-Wall -Werror`.
pub fn helpers(programs: &[&Program]) -> String {
    let mut s = String::new();
    if source::calls(programs, |i| matches!(i, Instr::Func(Func::Sign, _))) {
        s.push_str(SIGN);
    }
    if source::calls(programs, |i| matches!(i, Instr::PowInt(..))) {
        s.push_str(POW_INT);
    }
    s.push_str(SOLVE);
    s
}

const SIGN: &str = r#"/* -1, 0 or 1 by the sign of x, as the tape computes it (NaN stays NaN). */
static double sign(double x)
{
    if (x > 0.0) {
        return 1.0;
    }
    if (x < 0.0) {
        return -1.0;
    }
    return x * 0.0;
}

"#;

const POW_INT: &str = r#"/* x^n by binary powering, the same multiplications as the tape. */
static double pow_int(double x, int n)
{
    double base = x;
    double acc = 1.0;
    unsigned long k = n < 0 ? 0UL - (unsigned long)n : (unsigned long)n;
    while (k > 0) {
        if (k & 1UL) {
            acc *= base;
        }
        base *= base;
        k >>= 1;
    }
    return n < 0 ? 1.0 / acc : acc;
}

"#;

const SOLVE: &str = r#"/*
 * Solves a.x = b in place (a row-major, n by n; the solution replaces b) by Gaussian
 * elimination with partial pivoting. Returns 0, or 1 when a pivot vanishes.
 */
static int solve_in_place(int n, double *a, double *b)
{
    int i, j, k;
    for (k = 0; k < n; k++) {
        int pivot = k;
        double scale;
        for (i = k + 1; i < n; i++) {
            if (fabs(a[i * n + k]) > fabs(a[pivot * n + k])) {
                pivot = i;
            }
        }
        scale = a[pivot * n + k];
        if (scale == 0.0 || !isfinite(scale)) {
            return 1;
        }
        if (pivot != k) {
            double swap;
            for (j = 0; j < n; j++) {
                swap = a[k * n + j];
                a[k * n + j] = a[pivot * n + j];
                a[pivot * n + j] = swap;
            }
            swap = b[k];
            b[k] = b[pivot];
            b[pivot] = swap;
        }
        for (i = k + 1; i < n; i++) {
            double factor = a[i * n + k] / a[k * n + k];
            for (j = k; j < n; j++) {
                a[i * n + j] -= factor * a[k * n + j];
            }
            b[i] -= factor * b[k];
        }
    }
    for (k = n - 1; k >= 0; k--) {
        double v = b[k];
        for (j = k + 1; j < n; j++) {
            v -= a[k * n + j] * b[j];
        }
        b[k] = v / a[k * n + k];
    }
    return 0;
}
"#;

#[cfg(test)]
mod tests {
    use super::literal;

    #[test]
    fn literals_are_hexadecimal_and_exact() {
        assert_eq!(literal(3.0), "0x1.8p+1");
        assert_eq!(literal(1.0), "0x1p+0");
        assert_eq!(literal(0.5), "0x1p-1");
        assert_eq!(literal(-2.0), "(-0x1p+1)");
        assert_eq!(literal(0.0), "0x0p+0");
        assert_eq!(literal(-0.0), "(-0x0p+0)");
        assert_eq!(literal(0.1), "0x1.999999999999ap-4");
        assert_eq!(literal(f64::MIN_POSITIVE / 4.0), "0x0.4p-1022");
        assert_eq!(literal(f64::from_bits(1)), "0x0.0000000000001p-1022");
        assert_eq!(literal(f64::MAX), "0x1.fffffffffffffp+1023");
        assert_eq!(literal(f64::NEG_INFINITY), "(-INFINITY)");
        assert_eq!(literal(f64::NAN), "NAN");
    }
}
