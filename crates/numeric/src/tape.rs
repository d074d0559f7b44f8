//! The tape evaluator: runs a [`Program`] over a register file allocated once, interpreted,
//! or as machine code once it has run often (`native`).

use cas::Func;

mod native;

use native::{Native, Outputs};

use crate::elementary::{apply, atan2, pow, pow_int, sin_cos};
use crate::lower::{Instr, Program, Reg};

/// A program with its registers. Evaluation allocates nothing; the elementary functions are
/// those of [`crate::elementary`], so the same inputs give the same bits on every machine.
#[derive(Clone, Debug)]
pub struct Tape {
    program: Program,
    /// The program's code as the evaluator runs it, each op with the register it writes: the
    /// same operations in the same order, with the sine and cosine of one register fused.
    ops: Vec<(Reg, Op)>,
    registers: Vec<f64>,
    fixed: Option<Fixed>,
    /// `ops` as machine code.
    native: Native,
}

/// Inputs that change seldom, such as parameters ([`Tape::with_fixed_inputs`]), and the ops
/// that depend on the other inputs: while the fixed inputs keep their bits, only those run,
/// and the registers of the rest keep the values the same operations gave them before.
///
/// Runs of the whole program and of its slices share the registers, so they share the count
/// of the fixed inputs' changes: between two changes an op on them alone gives the same bits
/// whoever runs it, and a run (whole or a slice) that ran its own since the last change may
/// leave them out.
#[derive(Clone, Debug)]
struct Fixed {
    inputs: std::ops::Range<usize>,
    /// Their values at the last run of any kind; `None` before the first.
    seen: Option<Vec<f64>>,
    /// How many times a run found them changed.
    epoch: u64,
    /// The epoch in which a run of the whole program last ran every op.
    whole: Option<u64>,
    varying: Vec<(Reg, Op)>,
    /// `varying` as machine code.
    native: Native,
}

impl Fixed {
    /// The epoch of the fixed inputs in `registers`, counting a change since the last run.
    fn epoch(&mut self, registers: &[f64]) -> u64 {
        let now = &registers[self.inputs.clone()];
        let same = self
            .seen
            .as_ref()
            .is_some_and(|seen| seen.iter().zip(now).all(|(a, b)| a.to_bits() == b.to_bits()));
        if !same {
            self.seen = Some(now.to_vec());
            self.epoch += 1;
        }
        self.epoch
    }
}

/// An instruction of [`Program::code`] as the tape (and the batch tape) runs it: the k-th
/// writes register `inputs + constants + k`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Op {
    Plain(Instr),
    /// The sine and cosine of `arg` at once (the same bits as each alone, at the cost of
    /// one): this op's register gets the one its instruction asked for, `other` the other.
    SinCos {
        arg: Reg,
        sine_here: bool,
        other: Reg,
    },
    /// The value was written by an earlier [`Op::SinCos`].
    Written,
}

/// The program's code with each sine and cosine of the same register fused into the first
/// of the two; `base` is the register the first instruction writes.
pub(crate) fn fuse_sin_cos(code: &[Instr], base: usize) -> Vec<Op> {
    let mut ops: Vec<Op> = code.iter().map(|i| Op::Plain(*i)).collect();
    let mut first: std::collections::HashMap<(Reg, bool), usize> = Default::default();
    for (k, instr) in code.iter().enumerate() {
        let (sine, arg) = match *instr {
            Instr::Func(Func::Sin, a) => (true, a),
            Instr::Func(Func::Cos, a) => (false, a),
            _ => continue,
        };
        if let Some(earlier) = first.remove(&(arg, !sine)) {
            let other = Reg::try_from(base + k).expect("registers fit a Reg");
            ops[earlier] = Op::SinCos { arg, sine_here: !sine, other };
            ops[k] = Op::Written;
        } else {
            first.entry((arg, sine)).or_insert(k);
        }
    }
    ops
}

impl Tape {
    pub fn new(program: Program) -> Tape {
        let mut registers = vec![0.0; program.registers()];
        registers[program.inputs..program.inputs + program.constants.len()]
            .copy_from_slice(&program.constants);
        let base = program.inputs + program.constants.len();
        let ops = fuse_sin_cos(&program.code, base)
            .into_iter()
            .enumerate()
            .map(|(k, op)| (Reg::try_from(base + k).expect("registers fit a Reg"), op))
            .collect();
        Tape { program, ops, registers, fixed: None, native: Native::default() }
    }

    /// Declares the inputs in `inputs` fixed from run to run but for now and then (the
    /// parameters): the operations that depend on nothing else run again only when one of
    /// them changed its bits, which saves their work and changes no result.
    pub fn with_fixed_inputs(mut self, inputs: std::ops::Range<usize>) -> Tape {
        assert!(inputs.end <= self.program.inputs, "fixed inputs are inputs");
        let mut varies = vec![false; self.registers.len()];
        varies[..self.program.inputs].iter_mut().enumerate().for_each(|(i, v)| {
            *v = !inputs.contains(&i);
        });
        for (k, instr) in self.program.code.iter().enumerate() {
            let mut any = false;
            instr.map_registers(|r| {
                any |= varies[r as usize];
                r
            });
            varies[self.ops[k].0 as usize] = any;
        }
        let varying = self.ops.iter().filter(|(dst, _)| varies[*dst as usize]).copied().collect();
        self.fixed = Some(Fixed {
            inputs,
            seen: None,
            epoch: 0,
            whole: None,
            varying,
            native: Native::default(),
        });
        self
    }

    /// Compiles the program to machine code now, rather than once it has run often (the ops
    /// on the varying inputs alone too, with [`Tape::with_fixed_inputs`]): for a caller that
    /// knows it will run it often, or a test. Whether it is compiled: not where the machine
    /// has no code generator, or with `LAGRANGE_JIT=off`, where it stays interpreted.
    pub fn compile(&mut self) -> bool {
        let registers = self.registers.len();
        let gather = || gather_all(&self.program);
        let outputs = || Outputs { gather: &gather, outputs: self.program.outputs.len() };
        let full = self.native.compile(&self.ops, registers, outputs()).is_some();
        match &self.fixed {
            Some(fixed) => {
                full && fixed.native.compile(&fixed.varying, registers, outputs()).is_some()
            }
            None => full,
        }
    }

    /// Whether the program runs as machine code: [`Tape::compile`] said so, or it has run
    /// often enough.
    pub fn is_compiled(&self) -> bool {
        self.native.is_compiled()
    }

    /// How many operations a run takes while the fixed inputs keep their bits (all of them on
    /// a tape without fixed inputs).
    pub fn operations(&self) -> usize {
        self.fixed.as_ref().map_or(self.ops.len(), |fixed| fixed.varying.len())
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
        assert_eq!(inputs.len(), self.program.inputs, "tape inputs");
        self.inputs_mut().copy_from_slice(inputs);
        self.run(out);
    }

    /// The input registers, to be filled in place before [`Tape::run`]: a caller that builds
    /// its inputs anyway saves copying them in.
    pub fn inputs_mut(&mut self) -> &mut [f64] {
        &mut self.registers[..self.program.inputs]
    }

    /// Evaluates the program at the inputs in [`Tape::inputs_mut`], writing output `i` to
    /// `out[i]`.
    ///
    /// # Panics
    /// When `out` has the wrong length: a caller's bug, not bad data.
    pub fn run(&mut self, out: &mut [f64]) {
        let p = &self.program;
        assert_eq!(out.len(), p.outputs.len(), "tape outputs");
        let r = &mut self.registers;
        let (ops, native) = match &mut self.fixed {
            None => (&self.ops, &mut self.native),
            Some(fixed) => {
                let epoch = fixed.epoch(r);
                if fixed.whole == Some(epoch) {
                    (&fixed.varying, &mut fixed.native)
                } else {
                    fixed.whole = Some(epoch);
                    (&self.ops, &mut self.native)
                }
            }
        };
        let gather = || gather_all(p);
        match native.code(ops, r.len(), Outputs { gather: &gather, outputs: out.len() }) {
            Some(code) => code.run_into(r, out),
            None => {
                interpret(ops, r);
                for (o, reg) in out.iter_mut().zip(&p.outputs) {
                    *o = r[*reg as usize];
                }
            }
        }
    }
}

/// The ops a subset of a tape's outputs depends on ([`Tape::slice`]), run on the tape's own
/// registers by [`Tape::run_slice`]: the same operations in the same order, those no wanted
/// output needs left out, so the wanted outputs get the bits a full run gives them.
#[derive(Clone, Debug)]
pub struct Slice {
    ops: Vec<(Reg, Op)>,
    /// The wanted outputs' indices.
    outputs: Vec<usize>,
    native: Native,
    /// Of a tape with fixed inputs: the ops among `ops` that depend on the other inputs, as
    /// ops and as machine code, and the epoch of the fixed inputs in which the slice last ran
    /// every op ([`Fixed`]).
    varying: Vec<(Reg, Op)>,
    varying_native: Native,
    whole: Option<u64>,
    /// Whether the tape has fixed inputs.
    of_fixed: bool,
}

impl Slice {
    /// The indices of the outputs it computes, increasing.
    pub fn outputs(&self) -> &[usize] {
        &self.outputs
    }

    /// How many operations a run of it takes while the fixed inputs keep their bits (all of
    /// them on a tape without fixed inputs): what it costs against [`Tape::operations`].
    pub fn operations(&self) -> usize {
        if self.of_fixed {
            self.varying.len()
        } else {
            self.ops.len()
        }
    }
}

impl Tape {
    /// The ops the outputs `wanted` (indices) depend on: for a caller that needs some outputs
    /// often and the rest seldom (the kept rows of a problem whose contacts are mostly open).
    pub fn slice(&self, wanted: impl IntoIterator<Item = usize>) -> Slice {
        let mut outputs: Vec<usize> = wanted.into_iter().collect();
        outputs.sort_unstable();
        outputs.dedup();
        let mut needed = vec![false; self.registers.len()];
        for &o in &outputs {
            needed[self.program.outputs[o] as usize] = true;
        }
        let mut kept = vec![false; self.ops.len()];
        for (k, &(dst, op)) in self.ops.iter().enumerate().rev() {
            match op {
                Op::Plain(instr) if needed[dst as usize] => {
                    kept[k] = true;
                    instr.map_registers(|r| {
                        needed[r as usize] = true;
                        r
                    });
                }
                Op::SinCos { arg, other, .. } if needed[dst as usize] || needed[other as usize] => {
                    kept[k] = true;
                    needed[arg as usize] = true;
                }
                _ => {}
            }
        }
        let ops: Vec<(Reg, Op)> =
            self.ops.iter().zip(&kept).filter(|(_, k)| **k).map(|(op, _)| *op).collect();
        let varying = match &self.fixed {
            Some(fixed) => {
                let mut varies = vec![false; self.registers.len()];
                for &(dst, _) in &fixed.varying {
                    varies[dst as usize] = true;
                }
                ops.iter().filter(|(dst, _)| varies[*dst as usize]).copied().collect()
            }
            None => Vec::new(),
        };
        Slice {
            ops,
            outputs,
            native: Native::default(),
            varying,
            varying_native: Native::default(),
            whole: None,
            of_fixed: self.fixed.is_some(),
        }
    }

    /// Evaluates the outputs of `slice` (made by [`Tape::slice`] of this tape) at the inputs
    /// in [`Tape::inputs_mut`], writing output `i` to `out[i]` for each of them; the other
    /// entries of `out` are left as they were.
    pub fn run_slice(&mut self, slice: &mut Slice, out: &mut [f64]) {
        assert_eq!(out.len(), self.program.outputs.len(), "tape outputs");
        let r = &mut self.registers;
        let (ops, native) = match &mut self.fixed {
            None => (&slice.ops, &mut slice.native),
            Some(fixed) => {
                let epoch = fixed.epoch(r);
                if slice.whole == Some(epoch) {
                    (&slice.varying, &mut slice.varying_native)
                } else {
                    slice.whole = Some(epoch);
                    (&slice.ops, &mut slice.native)
                }
            }
        };
        let outputs = &self.program.outputs;
        let gather = || slice.outputs.iter().map(|&o| (o, outputs[o])).collect();
        match native.code(ops, r.len(), Outputs { gather: &gather, outputs: out.len() }) {
            Some(code) => code.run_into(r, out),
            None => {
                interpret(ops, r);
                for &o in &slice.outputs {
                    out[o] = r[outputs[o] as usize];
                }
            }
        }
    }
}

/// Each output of `program` with the register it is read from, for compiled code to gather.
fn gather_all(program: &Program) -> Vec<(usize, Reg)> {
    program.outputs.iter().copied().enumerate().collect()
}

/// Runs `ops` on the registers `r`, one after the other.
fn interpret(ops: &[(Reg, Op)], r: &mut [f64]) {
    for &(dst, op) in ops {
        let instr = match op {
            Op::Plain(instr) => instr,
            Op::SinCos { arg, sine_here, other } => {
                let (sine, cosine) = sin_cos(r[arg as usize]);
                let (here, there) = if sine_here { (sine, cosine) } else { (cosine, sine) };
                r[other as usize] = there;
                r[dst as usize] = here;
                continue;
            }
            Op::Written => continue,
        };
        r[dst as usize] = match instr {
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elementary::apply;

    #[test]
    fn fused_sine_and_cosine_are_the_bits_of_each_alone() {
        let mut args = vec![0.0, -0.0, 1e-300, 1e-9, 2e-8, 7.45e-9, 0.5, 0.785, 1.0, 3.0, -2.5];
        args.extend([1e6, -3e8, 1e22, 1e300, f64::INFINITY, f64::NAN]);
        args.extend((0..20_000).map(|i| (i as f64 - 10_000.0) * 0.000_731_3));
        for x in args {
            let (s, c) = sin_cos(x);
            assert_eq!(s.to_bits(), apply(Func::Sin, x).to_bits(), "sin {x}");
            assert_eq!(c.to_bits(), apply(Func::Cos, x).to_bits(), "cos {x}");
        }
    }

    #[test]
    fn a_tape_with_fused_pairs_gives_what_the_instructions_say() {
        // cos x, x·x, sin x, sin y, cos y in that order, and x once more as an output.
        let program = Program {
            inputs: 2,
            constants: Vec::new(),
            code: vec![
                Instr::Func(Func::Cos, 0),
                Instr::Mul(0, 0),
                Instr::Func(Func::Sin, 0),
                Instr::Func(Func::Sin, 1),
                Instr::Func(Func::Cos, 1),
            ],
            outputs: vec![2, 3, 4, 5, 6, 0],
        };
        let mut tape = Tape::new(program);
        assert!(matches!(tape.ops[0].1, Op::SinCos { arg: 0, sine_here: false, other: 4 }));
        assert!(matches!(tape.ops[4].1, Op::Written));
        let (x, y) = (0.7, -4.1);
        let mut out = [0.0; 6];
        tape.eval(&[x, y], &mut out);
        let (sin, cos) = (|v| apply(Func::Sin, v), |v| apply(Func::Cos, v));
        let want = [cos(x), x * x, sin(x), sin(y), cos(y), x];
        for (got, want) in out.iter().zip(want) {
            assert_eq!(got.to_bits(), want.to_bits(), "{out:?}");
        }
    }

    #[test]
    fn a_slice_runs_what_its_outputs_need_and_gives_their_bits() {
        // cos x, x·x, sin x (fused with cos x), sin y, y·2 (a constant), x·x + y·2.
        let program = Program {
            inputs: 2,
            constants: vec![2.0],
            code: vec![
                Instr::Func(Func::Cos, 0),
                Instr::Mul(0, 0),
                Instr::Func(Func::Sin, 0),
                Instr::Func(Func::Sin, 1),
                Instr::Mul(1, 2),
                Instr::Add(4, 7),
            ],
            outputs: vec![3, 5, 6, 8],
        };
        let mut tape = Tape::new(program);
        // sin x needs the fused pair written at cos x's place; the sum, x·x and y·2.
        let mut slice = tape.slice([3, 1]);
        assert_eq!(slice.outputs(), &[1, 3]);
        assert_eq!(slice.ops.len(), 4);
        let (x, y) = (0.7, -4.1);
        let mut full = [0.0; 4];
        tape.eval(&[x, y], &mut full);
        let mut part = [f64::NAN; 4];
        tape.inputs_mut().copy_from_slice(&[x, y]);
        tape.run_slice(&mut slice, &mut part);
        assert_eq!(part[1].to_bits(), full[1].to_bits());
        assert_eq!(part[3].to_bits(), full[3].to_bits());
        assert!(part[0].is_nan() && part[2].is_nan(), "the rest left as they were: {part:?}");
    }

    #[test]
    fn ops_on_fixed_inputs_alone_run_again_when_those_change() {
        // p·p (fixed alone), x·(p·p), x + 1.
        let program = Program {
            inputs: 2,
            constants: vec![1.0],
            code: vec![Instr::Mul(1, 1), Instr::Mul(0, 3), Instr::Add(0, 2)],
            outputs: vec![3, 4, 5],
        };
        let mut plain = Tape::new(program.clone());
        let mut fixed = Tape::new(program).with_fixed_inputs(1..2);
        assert_eq!(fixed.fixed.as_ref().map(|f| f.varying.len()), Some(2));
        let mut want = [0.0; 3];
        let mut got = [0.0; 3];
        for input in [[2.0, 3.0], [5.0, 3.0], [5.0, -4.0], [0.5, -4.0], [0.5, f64::NAN], [1.0, 3.0]]
        {
            plain.eval(&input, &mut want);
            fixed.eval(&input, &mut got);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "at {input:?}");
        }
        assert_eq!(got, [9.0, 9.0, 2.0]);
    }

    /// A slice leaves out its ops on the fixed inputs alone only while they hold the bits its
    /// own last full run saw; whole runs and other slices in between, at other values or at
    /// the same, change nothing of what it gives.
    #[test]
    fn slices_share_the_fixed_inputs_epochs_with_whole_runs() {
        // p·p (fixed alone), x·(p·p), x + 1, p + 1 (fixed alone).
        let program = Program {
            inputs: 2,
            constants: vec![1.0],
            code: vec![Instr::Mul(1, 1), Instr::Mul(0, 3), Instr::Add(0, 2), Instr::Add(1, 2)],
            outputs: vec![3, 4, 5, 6],
        };
        let mut plain = Tape::new(program.clone());
        let mut fixed = Tape::new(program).with_fixed_inputs(1..2);
        let mut product = fixed.slice([1]);
        let mut other = fixed.slice([3]);
        assert_eq!((product.operations(), fixed.operations()), (1, 2));
        let mut want = [0.0; 4];
        let mut got = [0.0; 4];
        // Each state: a whole run or one of the two slices, at these inputs.
        let steps: [(u8, [f64; 2]); 8] = [
            (1, [2.0, 3.0]),
            (0, [2.0, 5.0]),
            (1, [4.0, 5.0]),
            (2, [4.0, 3.0]),
            (1, [1.0, 3.0]),
            (0, [1.0, 7.0]),
            (2, [1.0, 3.0]),
            (1, [6.0, 3.0]),
        ];
        for (run, input) in steps {
            plain.eval(&input, &mut want);
            fixed.inputs_mut().copy_from_slice(&input);
            match run {
                0 => fixed.run(&mut got),
                1 => fixed.run_slice(&mut product, &mut got),
                _ => fixed.run_slice(&mut other, &mut got),
            }
            let wanted = match run {
                0 => vec![0, 1, 2, 3],
                1 => vec![1],
                _ => vec![3],
            };
            for o in wanted {
                assert_eq!(got[o].to_bits(), want[o].to_bits(), "output {o} at {input:?}");
            }
        }
    }
}
