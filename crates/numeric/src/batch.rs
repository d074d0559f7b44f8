//! The tape run over many points at once: each register holds [`LANES`] values, one per
//! point, so an instruction is decoded once for all of them and its arithmetic is a loop over
//! lanes that the compiler turns into vector instructions. Every lane computes exactly what
//! [`crate::Tape`] computes at its point (the same operations in the same order, the same
//! elementary functions), so a batch gives the same bits as the points one at a time. As on
//! the tape, the sine and cosine of one register are one op; here it computes eight lanes at
//! once in vector instructions ([`sin_cos_lanes`], libm's bits).

use crate::elementary::{apply, atan2, pow, pow_int, sin_cos_lanes, LANES};
use crate::lower::{Instr, Program};
use crate::tape::{fuse_sin_cos, Op};

type Lanes = [f64; LANES];

/// A program with registers [`LANES`] wide, allocated once.
#[derive(Clone, Debug)]
pub struct BatchTape {
    program: Program,
    /// The program's code with sines and cosines fused, as the tape runs it: the k-th op
    /// writes register `inputs + constants + k`.
    ops: Vec<Op>,
    registers: Vec<Lanes>,
}

impl BatchTape {
    pub fn new(program: Program) -> BatchTape {
        let mut registers = vec![[0.0; LANES]; program.registers()];
        for (slot, c) in registers[program.inputs..].iter_mut().zip(&program.constants) {
            *slot = [*c; LANES];
        }
        let ops = fuse_sin_cos(&program.code, program.inputs + program.constants.len());
        BatchTape { program, ops, registers }
    }

    pub fn program(&self) -> &Program {
        &self.program
    }

    /// Evaluates the program at every point of `inputs` (row-major: a point's inputs a row)
    /// and writes each point's outputs as a row of `out`. A last chunk shorter than
    /// [`LANES`] fills its spare lanes with its last point, whose results are dropped.
    ///
    /// # Panics
    /// When the lengths do not make whole rows of the same number of points: a caller's bug,
    /// not bad data.
    pub fn eval_many(&mut self, inputs: &[f64], out: &mut [f64]) {
        let (width, outputs) = (self.program.inputs, self.program.outputs.len());
        assert!(width > 0 || inputs.is_empty(), "batch tape without inputs");
        // A program without inputs has as many points as `out` has rows.
        let points = inputs.len().checked_div(width).unwrap_or_else(|| out.len() / outputs.max(1));
        assert_eq!(inputs.len(), points * width, "batch tape inputs");
        assert_eq!(out.len(), points * outputs, "batch tape outputs");
        for first in (0..points).step_by(LANES) {
            let count = LANES.min(points - first);
            for slot in 0..width {
                let lanes = &mut self.registers[slot];
                for (lane, value) in lanes.iter_mut().enumerate() {
                    *value = inputs[(first + lane.min(count - 1)) * width + slot];
                }
            }
            self.run();
            for (o, reg) in self.program.outputs.iter().enumerate() {
                let lanes = &self.registers[*reg as usize];
                for (lane, value) in lanes.iter().enumerate().take(count) {
                    out[(first + lane) * outputs + o] = *value;
                }
            }
        }
    }

    /// The input registers, each [`LANES`] wide (lane `l` of register `i` is input `i` of
    /// point `l`): a caller that keeps its points lane by lane fills them in place, then
    /// calls [`BatchTape::run_lanes`].
    pub fn input_lanes_mut(&mut self) -> &mut [Lanes] {
        &mut self.registers[..self.program.inputs]
    }

    /// Evaluates the program at the points in [`BatchTape::input_lanes_mut`]; output `o` of
    /// each point is then in [`BatchTape::output_lanes`]`(o)`.
    #[inline(always)]
    pub fn run_lanes(&mut self) {
        self.run();
    }

    /// Output `o` of each point of the last [`BatchTape::run_lanes`], lane by lane.
    pub fn output_lanes(&self, o: usize) -> &Lanes {
        &self.registers[self.program.outputs[o] as usize]
    }

    /// One pass of the code over the registers as they stand.
    #[inline(always)]
    fn run(&mut self) {
        let p = &self.program;
        let r = &mut self.registers;
        let base = p.inputs + p.constants.len();
        for (k, op) in self.ops.iter().enumerate() {
            let instr = match *op {
                Op::Plain(instr) => instr,
                Op::SinCos { arg, sine_here, other } => {
                    // Written in place: `other` is the register of a later instruction, the
                    // fused partner, so it lies past this op's.
                    let x = r[arg as usize];
                    let (before, after) = r.split_at_mut(base + k + 1);
                    let here = &mut before[base + k];
                    let there = &mut after[other as usize - base - k - 1];
                    let (s, c) = if sine_here { (here, there) } else { (there, here) };
                    sin_cos_lanes(&x, s, c);
                    continue;
                }
                Op::Written => continue,
            };
            let v = match instr {
                Instr::Add(a, b) => zip(&r[a as usize], &r[b as usize], |x, y| x + y),
                Instr::Sub(a, b) => zip(&r[a as usize], &r[b as usize], |x, y| x - y),
                Instr::Mul(a, b) => zip(&r[a as usize], &r[b as usize], |x, y| x * y),
                Instr::Div(a, b) => zip(&r[a as usize], &r[b as usize], |x, y| x / y),
                Instr::Neg(a) => each(&r[a as usize], |x| -x),
                Instr::PowInt(a, n) => each(&r[a as usize], |x| pow_int(x, n)),
                Instr::Sqrt(a) => each(&r[a as usize], f64::sqrt),
                Instr::PowF(a, b) => zip(&r[a as usize], &r[b as usize], pow),
                Instr::Func(f, a) => each(&r[a as usize], |x| apply(f, x)),
                Instr::Atan2(y, x) => zip(&r[y as usize], &r[x as usize], atan2),
            };
            r[base + k] = v;
        }
    }
}

#[inline(always)]
fn each(a: &Lanes, f: impl Fn(f64) -> f64) -> Lanes {
    let mut v = [0.0; LANES];
    for (out, x) in v.iter_mut().zip(a) {
        *out = f(*x);
    }
    v
}

#[inline(always)]
fn zip(a: &Lanes, b: &Lanes, f: impl Fn(f64, f64) -> f64) -> Lanes {
    let mut v = [0.0; LANES];
    for ((out, x), y) in v.iter_mut().zip(a).zip(b) {
        *out = f(*x, *y);
    }
    v
}
