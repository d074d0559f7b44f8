//! A program printed as straight-line source: one walk over the instructions, shared by every
//! language, with a [`Dialect`] saying how each language spells a function, a register, an
//! operation and a literal. The printed function computes the program's outputs from its
//! inputs with the same operations, in the same order, as the tape.

pub mod c;
pub mod rust;

use cas::Func;
use numeric::{Instr, Program, Reg};

/// How one language spells the pieces of a straight-line function.
pub trait Dialect {
    /// A literal that reads back as exactly `v` (negative ones in parentheses, so that any
    /// operand may follow an operator).
    fn literal(&self, v: f64) -> String;
    /// The function's documentation and opening line, for `inputs` values in (`reads` of
    /// them read) and `outputs` values out.
    fn open(&self, name: &str, doc: &str, inputs: usize, reads: usize, outputs: usize) -> String;
    /// A statement defining register `reg` as `value`.
    fn define(&self, reg: usize, value: &str) -> String;
    /// The statement storing `value` as output `slot`; both languages write `out[slot] = value;`.
    fn store(&self, slot: usize, value: &str) -> String {
        format!("    out[{slot}] = {value};\n")
    }
    /// The function's closing line.
    fn close(&self) -> String {
        "}\n".to_string()
    }
    /// A square root, a real power, an elementary function, atan2 and the helpers the
    /// language's generated code defines (`sign`, `pow_int`).
    fn call(&self, operation: Call, operands: &[String]) -> String;
}

/// The operations a dialect spells as calls rather than operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    Sqrt,
    PowF,
    /// An integer power by binary powering (the helper `pow_int`).
    PowInt(i32),
    /// One of the scene's functions; `Sign` is the helper `sign`.
    Func(Func),
    Atan2,
}

/// The source of a function computing `program`'s outputs from its inputs, in `dialect`:
/// the inputs it reads, then a definition per instruction whose value is used, then the
/// outputs.
pub fn function(program: &Program, name: &str, doc: &str, dialect: &dyn Dialect) -> String {
    let inputs = program.inputs;
    let base = inputs + program.constants.len();
    let used = used_registers(program);
    let operand = |r: Reg| -> String {
        let r = r as usize;
        if (inputs..base).contains(&r) {
            dialect.literal(program.constants[r - inputs])
        } else {
            format!("r{r}")
        }
    };
    let reads = used[..inputs].iter().filter(|u| **u).count();
    let mut s = dialect.open(name, doc, inputs, reads, program.outputs.len());
    for (i, _) in used.iter().enumerate().take(inputs).filter(|(_, u)| **u) {
        s.push_str(&dialect.define(i, &format!("input[{i}]")));
    }
    for (k, instr) in program.code.iter().enumerate() {
        let reg = base + k;
        if !used[reg] {
            continue;
        }
        let value = match *instr {
            Instr::Add(a, b) => format!("{} + {}", operand(a), operand(b)),
            Instr::Sub(a, b) => format!("{} - {}", operand(a), operand(b)),
            Instr::Mul(a, b) => format!("{} * {}", operand(a), operand(b)),
            Instr::Div(a, b) => format!("{} / {}", operand(a), operand(b)),
            Instr::Neg(a) => format!("-{}", operand(a)),
            Instr::PowInt(a, n) => dialect.call(Call::PowInt(n), &[operand(a)]),
            Instr::Sqrt(a) => dialect.call(Call::Sqrt, &[operand(a)]),
            Instr::PowF(a, b) => dialect.call(Call::PowF, &[operand(a), operand(b)]),
            Instr::Func(f, a) => dialect.call(Call::Func(f), &[operand(a)]),
            Instr::Atan2(y, x) => dialect.call(Call::Atan2, &[operand(y), operand(x)]),
        };
        s.push_str(&dialect.define(reg, &value));
    }
    for (i, &r) in program.outputs.iter().enumerate() {
        s.push_str(&dialect.store(i, &operand(r)));
    }
    s.push_str(&dialect.close());
    s
}

/// Which registers an instruction or an output reads: only those are defined.
fn used_registers(program: &Program) -> Vec<bool> {
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
    used
}

/// Whether any of `programs` calls `f` (a language defines a helper only where it is called:
/// C refuses an unused static function under `-Wall -Werror`).
pub fn calls(programs: &[&Program], f: impl Fn(&Instr) -> bool) -> bool {
    programs.iter().any(|p| p.code.iter().any(&f))
}
