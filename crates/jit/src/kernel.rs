//! A compiled program as something safe to call: the only `unsafe` of the crate.
//!
//! What keeps it sound:
//! - The code reads and writes the registers it was compiled for and nothing else of the
//!   caller's: [`crate::compile`] refuses an operation naming a register at or past the
//!   array's length, and its code generation touches no memory but `registers[r]` for the
//!   registers the operations name, `outputs[slot]` for the outputs it gathers, and a stack
//!   slot of its own. [`crate::compile_gathering`] refuses a slot at or past the outputs'
//!   length. [`Kernel::run_into`] takes the registers and the outputs as two `&mut [f64]`
//!   (distinct, as two mutable borrows are) of exactly the lengths compiled for (anything
//!   else panics before the code runs), so the code has both arrays to itself for the call.
//! - The code calls only the functions its operations carry, as the safe `extern "C"` function
//!   pointers they are, with the arguments their types say (a [`crate::Pair`]'s output is
//!   the code's own 16-byte, 8-aligned stack slot); a panic inside one aborts (`extern "C"`),
//!   so none unwinds through generated frames.
//! - The code memory lives as long as the kernel: the module that owns it is kept inside and
//!   freed only when the kernel is dropped, which no running call can outlive since a call
//!   borrows the kernel. The code is never written again once finalized, so any number of
//!   threads may run it at once, each on its own registers.
//! - `Kernel::new` is private to the crate: only `compile` makes a kernel, from code it
//!   generated and checked.

use std::sync::Mutex;

use cranelift_jit::JITModule;

/// Native code for a program on an array of `f64` registers; [`Kernel::run`] runs it.
pub struct Kernel {
    /// The functions to run one after the other, each taking the registers' address and the
    /// outputs'.
    entries: Vec<unsafe extern "C" fn(*mut f64, *mut f64)>,
    registers: usize,
    outputs: usize,
    /// Owns the code memory. Behind a mutex only to be `Sync` (the module keeps a `RefCell` of
    /// its symbols, which nothing touches once finalized); it is never locked but to be freed.
    module: Mutex<Option<JITModule>>,
}

impl Kernel {
    /// A kernel for the finalized functions at `entries` of `module`, which `compile`
    /// generated for an array of `registers` values (the module doc's invariants).
    pub(crate) fn new(
        module: JITModule,
        entries: Vec<*const u8>,
        registers: usize,
        outputs: usize,
    ) -> Kernel {
        type Entry = unsafe extern "C" fn(*mut f64, *mut f64);
        let entries = entries
            .into_iter()
            .map(|code| {
                // SAFETY: `code` is the start of a function finalized in `module` with the
                // signature `fn(*mut f64, *mut f64)` in the host's C calling convention, which
                // is what `compile_gathering` declared for every chunk.
                unsafe { std::mem::transmute::<*const u8, Entry>(code) }
            })
            .collect();
        Kernel { entries, registers, outputs, module: Mutex::new(Some(module)) }
    }

    /// How many registers the code was compiled for.
    pub fn registers(&self) -> usize {
        self.registers
    }

    /// Runs the code on `registers`.
    ///
    /// # Panics
    /// When `registers` is not of the length the code was compiled for: a caller's bug.
    pub fn run(&self, registers: &mut [f64]) {
        assert_eq!(self.outputs, 0, "a kernel that gathers outputs runs with them");
        self.run_into(registers, &mut []);
    }

    /// Runs the code on `registers`, gathering the outputs it was compiled for into `outputs`.
    ///
    /// # Panics
    /// When `registers` or `outputs` is not of the length the code was compiled for: a
    /// caller's bug.
    pub fn run_into(&self, registers: &mut [f64], outputs: &mut [f64]) {
        assert_eq!(registers.len(), self.registers, "a kernel's registers");
        assert_eq!(outputs.len(), self.outputs, "a kernel's outputs");
        let (at, out) = (registers.as_mut_ptr(), outputs.as_mut_ptr());
        for entry in &self.entries {
            // SAFETY: both arrays are ours for the call and of the lengths the code was
            // compiled for, which touches nothing past them; the code is alive while `self`
            // is borrowed.
            unsafe { entry(at, out) };
        }
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let module = self.module.get_mut().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(module) = module {
            // SAFETY: dropping takes the kernel by `&mut`, so no call is running, and the
            // entries die with it: nothing can call the code after this.
            unsafe { module.free_memory() };
        }
    }
}

impl std::fmt::Debug for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kernel")
            .field("registers", &self.registers)
            .field("outputs", &self.outputs)
            .field("functions", &self.entries.len())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use crate::{available, compile, Op};

    #[test]
    fn registers_of_another_length_are_refused_before_the_code_runs() {
        if !available() {
            return;
        }
        let kernel = compile(3, &[(2, Op::Add(0, 1))]).expect("compiles");
        for len in [0, 2, 4, 1000] {
            let mut r = vec![1.0; len];
            let caught =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| kernel.run(&mut r)));
            assert!(caught.is_err(), "ran on {len} registers");
            assert!(r.iter().all(|x| *x == 1.0), "wrote to {len} registers");
        }
    }

    #[test]
    fn only_the_registers_written_change() {
        if !available() {
            return;
        }
        // Writes 1 and 3 of 5; the array sits inside a larger one whose ends must not move.
        let kernel = compile(5, &[(1, Op::Mul(0, 0)), (3, Op::Add(1, 4))]).expect("compiles");
        let mut outer = [7.0; 9];
        outer[2] = 3.0;
        outer[6] = 0.5;
        kernel.run(&mut outer[2..7]);
        assert_eq!(outer, [7.0, 7.0, 3.0, 9.0, 7.0, 9.5, 0.5, 7.0, 7.0]);
    }

    #[test]
    fn the_code_runs_on_many_threads_at_once_and_is_freed_with_the_kernel() {
        if !available() {
            return;
        }
        let kernel = std::sync::Arc::new(compile(2, &[(1, Op::Sqrt(0))]).expect("compiles"));
        let threads: Vec<_> = (0..4)
            .map(|t| {
                let kernel = kernel.clone();
                std::thread::spawn(move || {
                    (0..10_000).all(|i| {
                        let x = (t * 10_000 + i) as f64;
                        let mut r = [x, 0.0];
                        kernel.run(&mut r);
                        r[1] == x.sqrt()
                    })
                })
            })
            .collect();
        assert!(threads.into_iter().all(|t| t.join().expect("runs")));
        // Kernels made and dropped many times: each frees its code (a leak would be pages a
        // kernel, a few megabytes here, which this cannot see; it checks that freeing one
        // leaves the others' code alive).
        let kept = compile(2, &[(1, Op::Neg(0))]).expect("compiles");
        for _ in 0..200 {
            drop(compile(2, &[(1, Op::Neg(0))]).expect("compiles"));
        }
        let mut r = [2.0, 0.0];
        kept.run(&mut r);
        assert_eq!(r, [2.0, -2.0]);
    }
}
