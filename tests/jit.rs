//! Tapes compiled to machine code (`jit`) against the same tapes interpreted, bit for bit: every
//! program of every example's generated module (the right-hand side, the partials, the
//! observations, the inverse dynamics, …), at many states around the example's own.

use numeric::{Program, Tape};

/// A small deterministic generator: the same inputs on every run.
struct Random(u64);

impl Random {
    /// A value in (−3, 3), now and then a large or tiny one.
    fn value(&mut self) -> f64 {
        // xorshift64*.
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let u = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        match (self.0 >> 7) % 50 {
            0 => 1e12 * (u - 0.5),
            1 => 1e-12 * (u - 0.5),
            _ => 6.0 * (u - 0.5),
        }
    }
}

/// The bits of `v`, every NaN as one: which NaN an operation on two NaNs gives is the
/// processor's choice (a square root of a negative number, say, in a rough state).
fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| if x.is_nan() { f64::NAN.to_bits() } else { x.to_bits() }).collect()
}

/// Holds `program` compiled to the interpreter's bits at `runs` random inputs; false where this
/// machine compiles nothing.
fn compiled_matches(name: &str, program: &Program, rng: &mut Random, runs: usize) -> bool {
    let mut compiled = Tape::new(program.clone());
    if !compiled.compile() {
        return false;
    }
    let mut interpreted = Tape::new(program.clone());
    let (mut want, mut got) = (vec![0.0; program.outputs.len()], vec![0.0; program.outputs.len()]);
    for run in 0..runs {
        let x: Vec<f64> = (0..program.inputs).map(|_| rng.value()).collect();
        interpreted.eval(&x, &mut want);
        compiled.eval(&x, &mut got);
        assert_eq!(bits(&got), bits(&want), "{name}, run {run}, at {x:?}");
    }
    assert!(!interpreted.is_compiled(), "{name}: the oracle compiled itself");
    true
}

#[test]
fn every_examples_programs_compiled_give_the_interpreters_bits() {
    let mut rng = Random(0x9e37_79b9_7f4a_7c15);
    let mut checked = 0;
    let scenes =
        lagrange_tests::examples().into_iter().filter(|(_, s)| !lagrange_tests::has_friction(s));
    for (rel, source) in scenes {
        let module =
            export::codegen::codegen(&rel, &source).unwrap_or_else(|e| panic!("{rel}: {e}"));
        for (name, program) in &module.programs {
            if !compiled_matches(&format!("{rel}: {name}"), program, &mut rng, 200) {
                assert!(!jit::available(), "{rel}: {name} did not compile");
                return;
            }
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} programs");
}

/// The largest scene's right-hand side and partials (tens of thousands of operations, many
/// functions of a time compiled one after the other).
#[test]
fn the_bicycles_programs_compiled_give_the_interpreters_bits() {
    let source = lagrange_tests::example("examples/bicycle/whipple.lag");
    let mut prepared =
        engine::numbers::prepare(&source, &[], engine::Options::default()).expect("derives");
    let exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let partials = prepared.partials_program().expect("lowers");
    let mut rng = Random(17);
    for (name, program) in [("dynamics", dynamics), ("partials", partials)] {
        if !compiled_matches(name, &program, &mut rng, 50) {
            assert!(!jit::available(), "{name} did not compile");
        }
    }
}
