//! Straight-line register programs compiled to machine code with Cranelift.
//!
//! A program here is a list of operations on one array of `f64` registers, each writing the
//! register it names: what `numeric`'s tape runs, handed down as [`Op`]s. [`compile`] turns it
//! into native code ([`Kernel`]) that does the same operations in the same order, so the same
//! registers in give the same bits out: addition, subtraction, multiplication, division,
//! negation and the square root are the IEEE operations themselves (Cranelift fuses no multiply
//! and add into one: it emits an `fma` only where one is asked for, and none is here), an
//! integer power is the multiplications of binary powering in their order, and every other
//! function is a call of the very function the caller hands over. The caller keeps the
//! portable interpreter for a host Cranelift has no backend for ([`available`] says), or when
//! the environment says `LAGRANGE_JIT=off`.
//!
//! Machine code is not what this project is about; Cranelift (the code generator of Wasmtime)
//! is well kept and compiles fast, which matters since programs are compiled as they are
//! loaded. Running generated code takes `unsafe`, which the rest of the workspace forbids: it is
//! all in the `kernel` module, whose doc says why it is sound.

use std::collections::HashMap;
use std::fmt;
use std::sync::OnceLock;

use cranelift_codegen::ir::{
    types, AbiParam, InstBuilder, MemFlagsData, Signature, StackSlotData, StackSlotKind,
    UserFuncName, Value,
};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_codegen::Context;
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, Linkage, Module};

// The one module allowed `unsafe`: see its doc.
#[allow(unsafe_code)]
mod kernel;

pub use kernel::Kernel;

/// A register's index in the array a [`Kernel`] runs on.
pub type Reg = u32;

/// A function of one value that generated code calls, such as `libm`'s sine.
pub type Unary = extern "C" fn(f64) -> f64;
/// A function of two values that generated code calls, such as a real power.
pub type Binary = extern "C" fn(f64, f64) -> f64;
/// A function of one value with two results, written to `out`, such as a sine and cosine at
/// once.
pub type Pair = extern "C" fn(f64, &mut [f64; 2]);

/// One operation: what it computes from the registers it reads.
#[derive(Clone, Copy, Debug)]
pub enum Op {
    Add(Reg, Reg),
    Sub(Reg, Reg),
    Mul(Reg, Reg),
    Div(Reg, Reg),
    Neg(Reg),
    Sqrt(Reg),
    /// `x^n` by binary powering from an accumulator of 1: for each bit of |n| from the lowest,
    /// the accumulator times the base where the bit is set, then the base squared; for n < 0,
    /// one over the accumulator. (The same multiplications in the same order as
    /// `numeric::pow_int`.)
    PowInt(Reg, i32),
    Unary(Unary, Reg),
    Binary(Binary, Reg, Reg),
    /// The function's two results: the first to this operation's register, the second to
    /// `second`.
    Pair(Pair, Reg, Reg),
}

impl Op {
    fn reads(self) -> [Option<Reg>; 2] {
        match self {
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) => [Some(a), Some(b)],
            Op::Binary(_, a, b) => [Some(a), Some(b)],
            Op::Neg(a) | Op::Sqrt(a) | Op::PowInt(a, _) | Op::Unary(_, a) => [Some(a), None],
            // The second result's register is written, not read, but must lie in the array
            // all the same.
            Op::Pair(_, a, second) => [Some(a), Some(second)],
        }
    }
}

/// Why a program was not compiled.
#[derive(Debug)]
pub enum Error {
    /// An operation names a register past the array's end (an output's register: `op` the
    /// code's length).
    Register { op: usize, register: Reg },
    /// An output is gathered into a slot past the outputs' end.
    Output { slot: usize, outputs: usize },
    /// Cranelift has no backend for this machine.
    Host(&'static str),
    /// Cranelift refused the code or could not map it executable.
    Codegen(Box<dyn std::error::Error + Send + Sync>),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Register { op, register } => {
                write!(f, "operation {op} names register {register}, past the array")
            }
            Error::Output { slot, outputs } => {
                write!(f, "output slot {slot} lies past the {outputs} outputs")
            }
            Error::Host(why) => write!(f, "no code generator for this machine: {why}"),
            Error::Codegen(e) => write!(f, "code generation failed: {e}"),
        }
    }
}

impl std::error::Error for Error {}

/// Whether programs are compiled here: Cranelift has a backend for this machine, and the
/// environment does not say `LAGRANGE_JIT=off`. Asked once a process.
pub fn available() -> bool {
    static AVAILABLE: OnceLock<bool> = OnceLock::new();
    *AVAILABLE.get_or_init(|| {
        let off = std::env::var_os("LAGRANGE_JIT").is_some_and(|v| v == "off");
        !off && cranelift_native::builder().is_ok()
    })
}

/// Operations a generated function holds at most: a program longer than this is compiled as
/// several functions run one after the other, which bounds the register allocator's work (it
/// grows faster than the code does: 2,048 operations a function compiled a third slower than
/// 512, with no faster code).
const CHUNK: usize = 512;

/// How many operations back a value is reused from where it was loaded or computed; an older
/// one is loaded from the registers again, as a spilled value would be. Longer reuse kept
/// more values alive, which cost the register allocator time and spills and gained nothing.
const REUSE: usize = 16;

/// Compiles `code` to run on an array of `registers` values: operation k writes register
/// `code[k].0` (and, for a [`Op::Pair`], its second register too) from the registers it reads,
/// in the order given; every other register is left as it was.
pub fn compile(registers: usize, code: &[(Reg, Op)]) -> Result<Kernel, Error> {
    compile_gathering(registers, code, &[], 0)
}

/// [`compile`], the code then copying register `gather[i].1` into entry `gather[i].0` of an
/// array of `outputs` values ([`Kernel::run_into`]): a program's outputs where its caller
/// reads them. Copied by the caller, output by output through two indices each checked, they
/// had cost a walker's search a tenth of its instructions, more than the code itself.
pub fn compile_gathering(
    registers: usize,
    code: &[(Reg, Op)],
    gather: &[(usize, Reg)],
    outputs: usize,
) -> Result<Kernel, Error> {
    for (k, (dst, op)) in code.iter().enumerate() {
        for r in std::iter::once(Some(*dst)).chain(op.reads()).flatten() {
            if r as usize >= registers {
                return Err(Error::Register { op: k, register: r });
            }
        }
    }
    for &(slot, r) in gather {
        if r as usize >= registers {
            return Err(Error::Register { op: code.len(), register: r });
        }
        if slot >= outputs {
            return Err(Error::Output { slot, outputs });
        }
    }
    let mut flags = settings::builder();
    let set = |flags: &mut settings::Builder, name, value| {
        flags.set(name, value).map_err(|e| Error::Codegen(Box::new(e)))
    };
    // The program comes optimized (shared terms computed once): Cranelift's optimizer found
    // nothing to gain in it and took a third of the compile time.
    set(&mut flags, "opt_level", "none")?;
    // The verifier checks Cranelift's input, which `emit` makes the same way for every
    // program: debug builds (the tests) run it, release builds do not pay its time.
    set(&mut flags, "enable_verifier", if cfg!(debug_assertions) { "true" } else { "false" })?;
    // As cranelift-jit requires: calls reach anywhere, code at any address.
    set(&mut flags, "use_colocated_libcalls", "false")?;
    set(&mut flags, "is_pic", "false")?;
    let isa = cranelift_native::builder()
        .map_err(Error::Host)?
        .finish(settings::Flags::new(flags))
        .map_err(|e| Error::Codegen(Box::new(e)))?;
    let mut module = JITModule::new(JITBuilder::with_isa(isa, default_libcall_names()));
    let mut ids = Vec::new();
    let mut ctx = module.make_context();
    let mut builder_ctx = FunctionBuilderContext::new();
    let pointer = module.target_config().pointer_type();
    // At least one function, which gathers the outputs after the last chunk's operations.
    let chunks: Vec<&[(Reg, Op)]> =
        if code.is_empty() { vec![&[]] } else { code.chunks(CHUNK).collect() };
    for (n, chunk) in chunks.iter().enumerate() {
        let mut signature = module.make_signature();
        signature.params.push(AbiParam::new(pointer));
        signature.params.push(AbiParam::new(pointer));
        let id = module
            .declare_function(&chunk_name(n), Linkage::Local, &signature)
            .map_err(|e| Error::Codegen(Box::new(e)))?;
        ctx.func.signature = signature;
        ctx.func.name = UserFuncName::user(0, id.as_u32());
        let gathered = if n + 1 == chunks.len() { gather } else { &[] };
        emit(&mut ctx, &mut builder_ctx, &module, chunk, gathered);
        module.define_function(id, &mut ctx).map_err(|e| Error::Codegen(Box::new(e)))?;
        module.clear_context(&mut ctx);
        ids.push(id);
    }
    module.finalize_definitions().map_err(|e| Error::Codegen(Box::new(e)))?;
    let entries = ids.iter().map(|id| module.get_finalized_function(*id)).collect();
    Ok(Kernel::new(module, entries, registers, outputs))
}

fn chunk_name(n: usize) -> String {
    format!("chunk{n}")
}

/// One function's body: each operation's operands loaded (or reused, where this function has
/// them in hand from a few operations back), the operation, its result stored; then each
/// register of `gather` stored into its output.
fn emit(
    ctx: &mut Context,
    builder_ctx: &mut FunctionBuilderContext,
    module: &JITModule,
    code: &[(Reg, Op)],
    gather: &[(usize, Reg)],
) {
    let call_conv = module.isa().default_call_conv();
    let pointer = module.target_config().pointer_type();
    let signature = |params: &[types::Type], returns: &[types::Type]| {
        let mut s = Signature::new(call_conv);
        s.params.extend(params.iter().map(|t| AbiParam::new(*t)));
        s.returns.extend(returns.iter().map(|t| AbiParam::new(*t)));
        s
    };
    let mut b = FunctionBuilder::new(&mut ctx.func, builder_ctx);
    let unary = b.import_signature(signature(&[types::F64], &[types::F64]));
    let binary = b.import_signature(signature(&[types::F64, types::F64], &[types::F64]));
    let pair = b.import_signature(signature(&[types::F64, pointer], &[]));
    let block = b.create_block();
    b.append_block_params_for_function_params(block);
    b.switch_to_block(block);
    b.seal_block(block);
    let base = b.block_params(block)[0];
    let outputs = b.block_params(block)[1];
    let out = b.create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, 16, 3));
    // The registers are the caller's alone for the call, aligned, and never trap.
    let flags = MemFlagsData::trusted();
    // Each register's value in hand, with the operation it was loaded or computed at.
    let mut known: HashMap<Reg, (Value, usize)> = HashMap::new();
    let mut at = 0;
    let value =
        |b: &mut FunctionBuilder, known: &mut HashMap<Reg, (Value, usize)>, r, at| match known
            .get(&r)
        {
            Some(&(v, when)) if at - when <= REUSE => v,
            _ => {
                let v = b.ins().load(types::F64, flags, base, offset(r));
                known.insert(r, (v, at));
                v
            }
        };
    let mut results: Vec<(Reg, Value)> = Vec::with_capacity(2);
    for &(dst, op) in code {
        at += 1;
        results.clear();
        let v = match op {
            Op::Add(a, c) => {
                let (x, y) = (value(&mut b, &mut known, a, at), value(&mut b, &mut known, c, at));
                b.ins().fadd(x, y)
            }
            Op::Sub(a, c) => {
                let (x, y) = (value(&mut b, &mut known, a, at), value(&mut b, &mut known, c, at));
                b.ins().fsub(x, y)
            }
            Op::Mul(a, c) => {
                let (x, y) = (value(&mut b, &mut known, a, at), value(&mut b, &mut known, c, at));
                b.ins().fmul(x, y)
            }
            Op::Div(a, c) => {
                let (x, y) = (value(&mut b, &mut known, a, at), value(&mut b, &mut known, c, at));
                b.ins().fdiv(x, y)
            }
            Op::Neg(a) => {
                let x = value(&mut b, &mut known, a, at);
                b.ins().fneg(x)
            }
            Op::Sqrt(a) => {
                let x = value(&mut b, &mut known, a, at);
                b.ins().sqrt(x)
            }
            Op::PowInt(a, n) => {
                let mut base = value(&mut b, &mut known, a, at);
                let mut acc = b.ins().f64const(1.0);
                let mut k = n.unsigned_abs();
                while k > 0 {
                    if k & 1 == 1 {
                        acc = b.ins().fmul(acc, base);
                    }
                    k >>= 1;
                    // The last squaring is never read: left out, it changes nothing.
                    if k > 0 {
                        base = b.ins().fmul(base, base);
                    }
                }
                if n < 0 {
                    let one = b.ins().f64const(1.0);
                    b.ins().fdiv(one, acc)
                } else {
                    acc
                }
            }
            Op::Unary(f, a) => {
                let x = value(&mut b, &mut known, a, at);
                let callee = b.ins().iconst(pointer, f as usize as i64);
                let call = b.ins().call_indirect(unary, callee, &[x]);
                b.inst_results(call)[0]
            }
            Op::Binary(f, a, c) => {
                let (x, y) = (value(&mut b, &mut known, a, at), value(&mut b, &mut known, c, at));
                let callee = b.ins().iconst(pointer, f as usize as i64);
                let call = b.ins().call_indirect(binary, callee, &[x, y]);
                b.inst_results(call)[0]
            }
            Op::Pair(f, a, second) => {
                let x = value(&mut b, &mut known, a, at);
                let callee = b.ins().iconst(pointer, f as usize as i64);
                let address = b.ins().stack_addr(pointer, out, 0);
                b.ins().call_indirect(pair, callee, &[x, address]);
                let there = b.ins().stack_load(pointer, types::F64, out, 8);
                results.push((second, there));
                b.ins().stack_load(pointer, types::F64, out, 0)
            }
        };
        results.push((dst, v));
        for &(r, v) in &results {
            b.ins().store(flags, v, base, offset(r));
            known.insert(r, (v, at));
        }
    }
    for &(slot, r) in gather {
        at += 1;
        let v = value(&mut b, &mut known, r, at);
        b.ins().store(flags, v, outputs, offset_of(slot));
    }
    b.ins().return_(&[]);
    b.finalize(module.target_config());
}

fn offset(r: Reg) -> i32 {
    offset_of(r as usize)
}

fn offset_of(index: usize) -> i32 {
    i32::try_from(index * std::mem::size_of::<f64>()).expect("an entry's offset fits i32")
}

#[cfg(test)]
mod tests {
    use super::*;

    extern "C" fn twice(x: f64) -> f64 {
        2.0 * x
    }

    extern "C" fn hypot(x: f64, y: f64) -> f64 {
        (x * x + y * y).sqrt()
    }

    extern "C" fn halves(x: f64, out: &mut [f64; 2]) {
        *out = [x / 2.0, -x / 2.0];
    }

    fn pow_int(x: f64, n: i32) -> f64 {
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

    #[test]
    fn every_operation_gives_what_it_says() {
        if !available() {
            return;
        }
        let code = [
            (2, Op::Add(0, 1)),
            (3, Op::Sub(0, 1)),
            (4, Op::Mul(0, 1)),
            (5, Op::Div(0, 1)),
            (6, Op::Neg(0)),
            (7, Op::Sqrt(0)),
            (8, Op::PowInt(1, 7)),
            (9, Op::PowInt(1, -6)),
            (10, Op::PowInt(1, 0)),
            (11, Op::Unary(twice, 0)),
            (12, Op::Binary(hypot, 0, 1)),
            (13, Op::Pair(halves, 1, 15)),
            (14, Op::Mul(13, 15)),
        ];
        let kernel = compile(16, &code).expect("compiles");
        for (x, y) in [(2.0, 3.0), (0.1, -1.7), (1e300, 1e-300), (-0.0, f64::INFINITY)] {
            let mut r = [0.0; 16];
            r[0] = x;
            r[1] = y;
            kernel.run(&mut r);
            let want = [
                x,
                y,
                x + y,
                x - y,
                x * y,
                x / y,
                -x,
                x.sqrt(),
                pow_int(y, 7),
                pow_int(y, -6),
                1.0,
                twice(x),
                hypot(x, y),
                y / 2.0,
                (y / 2.0) * (-y / 2.0),
                -y / 2.0,
            ];
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&r), bits(&want), "at ({x}, {y}): {r:?}");
        }
    }

    #[test]
    fn outputs_are_gathered_where_they_are_asked_and_nowhere_else() {
        if !available() {
            return;
        }
        // An input, a result, and a result gathered twice; slot 1 is nobody's.
        let gather = [(0, 2), (2, 0), (3, 3), (4, 2)];
        let kernel =
            compile_gathering(4, &[(2, Op::Mul(0, 1)), (3, Op::Neg(2))], &gather, 5).expect("ok");
        let mut r = [3.0, 2.0, 0.0, 0.0];
        let mut out = [9.0; 5];
        kernel.run_into(&mut r, &mut out);
        assert_eq!(out, [6.0, 9.0, 3.0, -6.0, 6.0]);
        assert_eq!(r, [3.0, 2.0, 6.0, -6.0]);
        // The outputs' length is checked before the code runs.
        let mut short = [9.0; 4];
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            kernel.run_into(&mut r, &mut short)
        }));
        assert!(caught.is_err() && short == [9.0; 4]);
        // A program with no operations still gathers.
        let kernel = compile_gathering(2, &[], &[(0, 1)], 1).expect("ok");
        let mut out = [0.0];
        kernel.run_into(&mut [4.0, 5.0], &mut out);
        assert_eq!(out, [5.0]);
    }

    #[test]
    fn an_output_past_the_outputs_or_from_past_the_registers_is_refused() {
        let e = compile_gathering(3, &[(2, Op::Add(0, 1))], &[(3, 2)], 3);
        assert!(matches!(e, Err(Error::Output { slot: 3, outputs: 3 })), "{e:?}");
        let e = compile_gathering(3, &[(2, Op::Add(0, 1))], &[(0, 3)], 3);
        assert!(matches!(e, Err(Error::Register { op: 1, register: 3 })), "{e:?}");
    }

    #[test]
    fn a_register_past_the_array_is_refused() {
        let e = compile(3, &[(2, Op::Add(0, 1)), (3, Op::Neg(0))]);
        assert!(matches!(e, Err(Error::Register { op: 1, register: 3 })), "{e:?}");
        let e = compile(3, &[(2, Op::Pair(halves, 0, 7))]);
        assert!(matches!(e, Err(Error::Register { op: 0, register: 7 })), "{e:?}");
    }

    #[test]
    fn a_long_program_runs_as_chunks_in_order() {
        if !available() {
            return;
        }
        // r[k] = r[k-1] + r[k-2], a chain across every chunk boundary.
        let n = 3 * CHUNK + 17;
        let code: Vec<(Reg, Op)> = (2..n as Reg).map(|k| (k, Op::Add(k - 1, k - 2))).collect();
        let kernel = compile(n, &code).expect("compiles");
        let mut r = vec![0.0; n];
        r[0] = 1e-300;
        r[1] = 1e-300;
        kernel.run(&mut r);
        let mut want = vec![1e-300; n];
        for k in 2..n {
            want[k] = want[k - 1] + want[k - 2];
        }
        assert_eq!(r, want);
    }
}
