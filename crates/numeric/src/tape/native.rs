//! The tape's ops as machine code ([`jit`]), for a tape run often: the same operations in the
//! same order as the interpreter's, calling the same [`crate::elementary`] functions, so the
//! same bits.

use std::sync::{Arc, OnceLock};

use cas::Func;

use super::Op;
use crate::elementary::{apply, atan2, pow, sin_cos};
use crate::lower::{Instr, Reg};

/// Runs of one op list after which it is compiled. Compiling costs 3–8 µs an operation, and
/// a run as code saves about 3 ns an operation (the n-link pendulum's at n = 32: 3.8 ns
/// interpreted, 0.9 ns compiled), so compiling pays after some 1,000–2,700 runs: compiled on
/// the 1,000th, a tape run fewer times than that (a one-off value, a start's Newton
/// iteration, a short run) never pays for it, and one that runs on gains it soon after.
const COMPILE_AFTER: u32 = 1000;

/// One op list's native code, made on its [`COMPILE_AFTER`]-th run (or when asked) and
/// shared by the tape's clones.
#[derive(Clone, Debug, Default)]
pub(super) struct Native {
    runs: u32,
    /// `None` inside once compiling failed or is switched off: the interpreter runs.
    kernel: Arc<OnceLock<Option<jit::Kernel>>>,
}

/// Where a run's outputs go: output `gather[i].0` of `outputs` is register `gather[i].1`.
pub(super) struct Outputs<'a> {
    pub gather: &'a dyn Fn() -> Vec<(usize, Reg)>,
    pub outputs: usize,
}

impl Native {
    /// The code for `ops` on `registers` registers, gathering `outputs`, if it is compiled or
    /// now due.
    pub(super) fn code(
        &mut self,
        ops: &[(Reg, Op)],
        registers: usize,
        outputs: Outputs,
    ) -> Option<&jit::Kernel> {
        if self.kernel.get().is_none() {
            self.runs = self.runs.saturating_add(1);
            if self.runs < COMPILE_AFTER {
                return None;
            }
        }
        self.compile(ops, registers, outputs)
    }

    /// Compiles `ops` now if it is not yet.
    pub(super) fn compile(
        &self,
        ops: &[(Reg, Op)],
        registers: usize,
        outputs: Outputs,
    ) -> Option<&jit::Kernel> {
        self.kernel.get_or_init(|| compiled(ops, registers, outputs)).as_ref()
    }

    pub(super) fn is_compiled(&self) -> bool {
        self.kernel.get().is_some_and(Option::is_some)
    }
}

fn compiled(ops: &[(Reg, Op)], registers: usize, outputs: Outputs) -> Option<jit::Kernel> {
    if !jit::available() {
        return None;
    }
    let code: Vec<(jit::Reg, jit::Op)> = ops
        .iter()
        .filter_map(|&(dst, op)| match op {
            Op::Plain(instr) => Some((dst, plain(instr))),
            Op::SinCos { arg, sine_here: true, other } => {
                Some((dst, jit::Op::Pair(sine_and_cosine, arg, other)))
            }
            Op::SinCos { arg, sine_here: false, other } => {
                Some((other, jit::Op::Pair(sine_and_cosine, arg, dst)))
            }
            Op::Written => None,
        })
        .collect();
    // A program the code generator refuses still runs, interpreted.
    jit::compile_gathering(registers, &code, &(outputs.gather)(), outputs.outputs).ok()
}

fn plain(instr: Instr) -> jit::Op {
    match instr {
        Instr::Add(a, b) => jit::Op::Add(a, b),
        Instr::Sub(a, b) => jit::Op::Sub(a, b),
        Instr::Mul(a, b) => jit::Op::Mul(a, b),
        Instr::Div(a, b) => jit::Op::Div(a, b),
        Instr::Neg(a) => jit::Op::Neg(a),
        Instr::PowInt(a, n) => jit::Op::PowInt(a, n),
        Instr::Sqrt(a) => jit::Op::Sqrt(a),
        Instr::PowF(a, b) => jit::Op::Binary(power, a, b),
        Instr::Atan2(y, x) => jit::Op::Binary(arc_tangent2, y, x),
        Instr::Func(f, a) => jit::Op::Unary(function(f), a),
    }
}

extern "C" fn sine_and_cosine(x: f64, out: &mut [f64; 2]) {
    let (s, c) = sin_cos(x);
    *out = [s, c];
}

extern "C" fn power(base: f64, exponent: f64) -> f64 {
    pow(base, exponent)
}

extern "C" fn arc_tangent2(y: f64, x: f64) -> f64 {
    atan2(y, x)
}

/// The function generated code calls for `f`: [`apply`]'s, through a wrapper of the C
/// calling convention per function.
fn function(f: Func) -> jit::Unary {
    macro_rules! wrappers {
        ($($func:ident),*) => {
            match f {
                $(Func::$func => {
                    extern "C" fn wrapper(x: f64) -> f64 {
                        apply(Func::$func, x)
                    }
                    wrapper
                })*
            }
        };
    }
    wrappers!(Sin, Cos, Tan, Asin, Acos, Atan, Sinh, Cosh, Tanh, Exp, Ln, Abs, Sign)
}
