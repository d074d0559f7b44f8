//! The tape as machine code against the tape interpreted, bit for bit: random programs of
//! every instruction, with sines and cosines of one register fused, at many random inputs, and
//! with fixed inputs that change now and then.

use cas::Func;
use numeric::{Instr, Program, Reg, Tape};

/// A small deterministic generator: the same programs and inputs on every run.
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        // xorshift64*.
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// Mostly moderate values of either sign, now and then a zero, a huge or tiny one, an
    /// infinity or a NaN.
    fn value(&mut self) -> f64 {
        let u = (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        match self.below(40) {
            0 => 0.0,
            1 => -0.0,
            2 => 1e300 * (u - 0.5),
            3 => 1e-300 * (u - 0.5),
            4 => f64::INFINITY,
            5 => f64::NAN,
            _ => 8.0 * (u - 0.5),
        }
    }
}

const FUNCS: [Func; 13] = [
    Func::Sin,
    Func::Cos,
    Func::Tan,
    Func::Asin,
    Func::Acos,
    Func::Atan,
    Func::Sinh,
    Func::Cosh,
    Func::Tanh,
    Func::Exp,
    Func::Ln,
    Func::Abs,
    Func::Sign,
];

/// A program of `len` instructions on `inputs` inputs, each instruction reading registers
/// before it (recent ones more often, as lowered code does), with sines and cosines of shared
/// arguments for the tape to fuse.
fn program(rng: &mut Random, inputs: usize, len: usize) -> Program {
    let constants: Vec<f64> = (0..4).map(|_| rng.value()).collect();
    let base = inputs + constants.len();
    let mut code = Vec::with_capacity(len);
    for k in 0..len {
        let available = base + k;
        let pick = |rng: &mut Random| -> Reg {
            let r = if rng.below(3) == 0 {
                rng.below(available)
            } else {
                available - 1 - rng.below(available.min(12))
            };
            r as Reg
        };
        let (a, b) = (pick(rng), pick(rng));
        let instr = match rng.below(15) {
            0 | 1 => Instr::Add(a, b),
            2 => Instr::Sub(a, b),
            3 | 4 => Instr::Mul(a, b),
            5 => Instr::Div(a, b),
            6 => Instr::Neg(a),
            7 => Instr::PowInt(a, rng.below(19) as i32 - 9),
            8 => Instr::Sqrt(a),
            9 => Instr::PowF(a, b),
            10 => Instr::Atan2(a, b),
            // The other of a pair the tape fuses, where one is in reach.
            11 => match code.get(rng.below(k.max(1))) {
                Some(Instr::Func(Func::Sin, x)) => Instr::Func(Func::Cos, *x),
                Some(Instr::Func(Func::Cos, x)) => Instr::Func(Func::Sin, *x),
                _ => Instr::Func(Func::Sin, a),
            },
            12 => Instr::Func(Func::Cos, a),
            _ => Instr::Func(FUNCS[rng.below(FUNCS.len())], a),
        };
        code.push(instr);
    }
    let outputs = (0..8).map(|_| rng.below(base + len) as Reg).collect();
    Program { inputs, constants, code, outputs }
}

/// The bits of `v`, every NaN as one: which NaN an operation on two NaNs gives is the
/// processor's choice and no promise of Rust's either.
fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| if x.is_nan() { f64::NAN.to_bits() } else { x.to_bits() }).collect()
}

#[test]
fn compiled_tapes_give_the_interpreters_bits() {
    let mut rng = Random(0x9e37_79b9_7f4a_7c15);
    for case in 0..60 {
        let (inputs, len) = (1 + rng.below(6), 1 + rng.below(400));
        let program = program(&mut rng, inputs, len);
        let mut interpreted = Tape::new(program.clone());
        let mut compiled = Tape::new(program.clone());
        if !compiled.compile() {
            // No code generator here (or LAGRANGE_JIT=off): nothing to compare.
            assert!(!jit::available());
            return;
        }
        assert!(compiled.is_compiled() && !interpreted.is_compiled());
        let (mut want, mut got) = (vec![0.0; 8], vec![0.0; 8]);
        // Fewer runs than the interpreted tape takes to compile itself: it stays the oracle.
        for _ in 0..300 {
            let x: Vec<f64> = (0..inputs).map(|_| rng.value()).collect();
            interpreted.eval(&x, &mut want);
            compiled.eval(&x, &mut got);
            assert_eq!(bits(&got), bits(&want), "case {case} at {x:?}: {program:?}");
        }
        assert!(!interpreted.is_compiled(), "case {case}: compiled within 300 runs");
    }
}

#[test]
fn compiled_tapes_with_fixed_inputs_give_the_interpreters_bits() {
    let mut rng = Random(0x2545_f491_4f6c_dd1d);
    for case in 0..30 {
        let (inputs, len) = (2 + rng.below(6), 1 + rng.below(400));
        let fixed = 1 + rng.below(inputs - 1)..inputs;
        let program = program(&mut rng, inputs, len);
        let mut interpreted = Tape::new(program.clone());
        let mut compiled = Tape::new(program.clone()).with_fixed_inputs(fixed.clone());
        // Runs of an interpreted tape made anew each time, which never compiles itself.
        let mut interpreted = move |x: &[f64], out: &mut [f64]| {
            interpreted = Tape::new(interpreted.program().clone());
            interpreted.eval(x, out)
        };
        if !compiled.compile() {
            assert!(!jit::available());
            return;
        }
        let (mut want, mut got) = (vec![0.0; 8], vec![0.0; 8]);
        let mut x: Vec<f64> = (0..inputs).map(|_| rng.value()).collect();
        for run in 0..300 {
            // The fixed inputs change on one run in ten.
            for (i, x) in x.iter_mut().enumerate() {
                if !fixed.contains(&i) || run % 10 == 0 {
                    *x = rng.value();
                }
            }
            interpreted(&x, &mut want);
            compiled.eval(&x, &mut got);
            assert_eq!(bits(&got), bits(&want), "case {case}, run {run} at {x:?}: {program:?}");
        }
    }
}

#[test]
fn a_tape_run_often_compiles_itself_and_keeps_its_bits() {
    let mut rng = Random(7);
    let program = program(&mut rng, 3, 300);
    let mut interpreted = Tape::new(program.clone());
    let mut tape = Tape::new(program);
    let (mut want, mut got) = (vec![0.0; 8], vec![0.0; 8]);
    for _ in 0..1500 {
        let x: Vec<f64> = (0..3).map(|_| rng.value()).collect();
        interpreted.eval(&x, &mut want);
        tape.eval(&x, &mut got);
        assert_eq!(bits(&got), bits(&want), "at {x:?}");
    }
    assert_eq!(tape.is_compiled(), jit::available());
}

/// A slice run often compiles itself too, its code gathering only its own outputs: the
/// others keep what the caller left there.
#[test]
fn a_slice_run_often_compiles_itself_and_gathers_its_outputs_alone() {
    let mut rng = Random(11);
    let program = program(&mut rng, 3, 300);
    let mut whole = Tape::new(program.clone());
    let mut tape = Tape::new(program);
    let mut slice = tape.slice([1, 4, 6]);
    let (mut want, mut got) = (vec![0.0; 8], vec![0.0; 8]);
    for _ in 0..1500 {
        let x: Vec<f64> = (0..3).map(|_| rng.value()).collect();
        whole.eval(&x, &mut want);
        got.fill(f64::INFINITY);
        tape.inputs_mut().copy_from_slice(&x);
        tape.run_slice(&mut slice, &mut got);
        for o in 0..8 {
            let kept = [1, 4, 6].contains(&o);
            let expected = if kept { want[o] } else { f64::INFINITY };
            assert_eq!(bits(&[got[o]]), bits(&[expected]), "output {o} at {x:?}");
        }
    }
}
