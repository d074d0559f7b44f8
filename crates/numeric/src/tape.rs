//! The tape evaluator: runs a [`Program`] over a register file allocated once.

use crate::elementary::{apply, atan2, pow, pow_int};
use crate::lower::{Instr, Program};

/// A program with its registers. Evaluation allocates nothing; the elementary functions are
/// those of [`crate::elementary`], so the same inputs give the same bits on every machine.
#[derive(Clone, Debug)]
pub struct Tape {
    program: Program,
    registers: Vec<f64>,
}

impl Tape {
    pub fn new(program: Program) -> Tape {
        let mut registers = vec![0.0; program.registers()];
        registers[program.inputs..program.inputs + program.constants.len()]
            .copy_from_slice(&program.constants);
        Tape { program, registers }
    }

    pub fn program(&self) -> &Program {
        &self.program
    }

    pub fn inputs(&self) -> usize {
        self.program.inputs
    }

    pub fn outputs(&self) -> usize {
        self.program.outputs.len()
    }

    /// Evaluates the program at `inputs`, writing output `i` to `out[i]`.
    ///
    /// # Panics
    /// When `inputs` or `out` have the wrong length: a caller's bug, not bad data.
    pub fn eval(&mut self, inputs: &[f64], out: &mut [f64]) {
        let p = &self.program;
        assert_eq!(inputs.len(), p.inputs, "tape inputs");
        assert_eq!(out.len(), p.outputs.len(), "tape outputs");
        let r = &mut self.registers;
        r[..p.inputs].copy_from_slice(inputs);
        let base = p.inputs + p.constants.len();
        for (k, instr) in p.code.iter().enumerate() {
            let v = match *instr {
                Instr::Add(a, b) => r[a as usize] + r[b as usize],
                Instr::Sub(a, b) => r[a as usize] - r[b as usize],
                Instr::Mul(a, b) => r[a as usize] * r[b as usize],
                Instr::Div(a, b) => r[a as usize] / r[b as usize],
                Instr::Neg(a) => -r[a as usize],
                Instr::PowInt(a, n) => pow_int(r[a as usize], n),
                Instr::Sqrt(a) => r[a as usize].sqrt(),
                Instr::PowF(a, b) => pow(r[a as usize], r[b as usize]),
                Instr::Func(f, a) => apply(f, r[a as usize]),
                Instr::Atan2(y, x) => atan2(r[y as usize], r[x as usize]),
            };
            r[base + k] = v;
        }
        for (o, reg) in out.iter_mut().zip(&p.outputs) {
            *o = r[*reg as usize];
        }
    }
}
