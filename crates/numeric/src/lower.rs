//! From expressions to a straight-line program: one walk of the DAG in id order, with value
//! numbering of the instructions it emits.

use std::collections::HashMap;
use std::fmt;

use cas::number::{One, Rational, ToPrimitive};
use cas::{ExprId, Func, Node, Pool, SymId};

use crate::elementary::to_f64;

/// A register index. Registers are laid out as inputs, then constants, then one register per
/// instruction, in order: the program is in static single-assignment form.
pub type Reg = u32;

/// One operation of a [`Program`]; it writes the register after the previous instruction's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Instr {
    Add(Reg, Reg),
    Sub(Reg, Reg),
    Mul(Reg, Reg),
    Div(Reg, Reg),
    Neg(Reg),
    /// An integer power by binary powering ([`crate::pow_int`]).
    PowInt(Reg, i32),
    Sqrt(Reg),
    /// A real power `base^exponent`.
    PowF(Reg, Reg),
    Func(Func, Reg),
    Atan2(Reg, Reg),
}

impl Instr {
    /// The same operation on renamed registers.
    pub fn map_registers(self, mut f: impl FnMut(Reg) -> Reg) -> Instr {
        match self {
            Instr::Add(a, b) => Instr::Add(f(a), f(b)),
            Instr::Sub(a, b) => Instr::Sub(f(a), f(b)),
            Instr::Mul(a, b) => Instr::Mul(f(a), f(b)),
            Instr::Div(a, b) => Instr::Div(f(a), f(b)),
            Instr::Neg(a) => Instr::Neg(f(a)),
            Instr::PowInt(a, n) => Instr::PowInt(f(a), n),
            Instr::Sqrt(a) => Instr::Sqrt(f(a)),
            Instr::PowF(a, b) => Instr::PowF(f(a), f(b)),
            Instr::Func(func, a) => Instr::Func(func, f(a)),
            Instr::Atan2(a, b) => Instr::Atan2(f(a), f(b)),
        }
    }
}

/// A straight-line program: `inputs` values in, `outputs` values out.
#[derive(Clone, Debug)]
pub struct Program {
    pub inputs: usize,
    /// Values of the constant registers, which follow the inputs.
    pub constants: Vec<f64>,
    pub code: Vec<Instr>,
    /// The register holding each output.
    pub outputs: Vec<Reg>,
}

/// How many operations of each kind a program performs per evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCounts {
    /// Additions, subtractions and negations.
    pub add: usize,
    pub mul: usize,
    pub div: usize,
    /// Integer powers, square roots and real powers.
    pub pow: usize,
    /// Elementary functions and atan2.
    pub func: usize,
}

impl OpCounts {
    pub fn total(&self) -> usize {
        self.add + self.mul + self.div + self.pow + self.func
    }
}

impl fmt::Display for OpCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} operations: {} add/sub, {} mul, {} div, {} powers, {} functions",
            self.total(),
            self.add,
            self.mul,
            self.div,
            self.pow,
            self.func
        )
    }
}

impl Program {
    /// The total number of registers an evaluation needs.
    pub fn registers(&self) -> usize {
        self.inputs + self.constants.len() + self.code.len()
    }

    pub fn op_counts(&self) -> OpCounts {
        let mut c = OpCounts::default();
        for i in &self.code {
            match i {
                Instr::Add(..) | Instr::Sub(..) | Instr::Neg(..) => c.add += 1,
                Instr::Mul(..) => c.mul += 1,
                Instr::Div(..) => c.div += 1,
                Instr::PowInt(..) | Instr::Sqrt(..) | Instr::PowF(..) => c.pow += 1,
                Instr::Func(..) | Instr::Atan2(..) => c.func += 1,
            }
        }
        c
    }
}

/// Why an expression could not be lowered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LowerError {
    /// The expression mentions a symbol that has no input slot.
    UnboundSymbol(SymId),
}

/// Lowers `outputs` to one program whose input `i` is the value of `inputs[i]`.
/// Only the nodes the outputs reach are lowered, each once.
pub fn lower(pool: &Pool, inputs: &[SymId], outputs: &[ExprId]) -> Result<Program, LowerError> {
    let slots: HashMap<SymId, Reg> =
        inputs.iter().enumerate().map(|(i, s)| (*s, i as Reg)).collect();
    build(pool, &reachable(pool, outputs), inputs.len(), &slots, outputs)
}

/// Lowers `outputs` with every symbol they mention as an input: the program, and the symbol
/// each input stands for.
pub(crate) fn lower_free(pool: &Pool, outputs: &[ExprId]) -> (Program, Vec<SymId>) {
    let reachable = reachable(pool, outputs);
    let symbols: Vec<SymId> = reachable
        .iter()
        .filter_map(|e| match pool.node(*e) {
            Node::Sym(s) => Some(*s),
            _ => None,
        })
        .collect();
    let slots: HashMap<SymId, Reg> =
        symbols.iter().enumerate().map(|(i, s)| (*s, i as Reg)).collect();
    let program = build(pool, &reachable, symbols.len(), &slots, outputs)
        .expect("every symbol reached has an input");
    (program, symbols)
}

/// The nodes `outputs` reach, in dependency order: children have smaller ids than parents,
/// so sorted by id.
fn reachable(pool: &Pool, outputs: &[ExprId]) -> Vec<ExprId> {
    let mut reachable: Vec<ExprId> = Vec::new();
    let mut seen: std::collections::HashSet<ExprId> = std::collections::HashSet::new();
    let mut stack: Vec<ExprId> = outputs.to_vec();
    while let Some(e) = stack.pop() {
        if !seen.insert(e) {
            continue;
        }
        reachable.push(e);
        stack.extend(pool.children(e));
    }
    reachable.sort();
    reachable
}

fn build(
    pool: &Pool,
    reachable: &[ExprId],
    inputs: usize,
    slots: &HashMap<SymId, Reg>,
    outputs: &[ExprId],
) -> Result<Program, LowerError> {
    let mut b = Builder {
        inputs,
        constants: Vec::new(),
        constant_regs: HashMap::new(),
        code: Vec::new(),
        numbered: HashMap::new(),
    };
    let mut value: HashMap<ExprId, Reg> = HashMap::with_capacity(reachable.len());
    for &e in reachable {
        let reg = match pool.node(e) {
            Node::Num(q) => b.constant(to_f64(q)),
            Node::Pi => b.constant(std::f64::consts::PI),
            Node::Sym(s) => *slots.get(s).ok_or(LowerError::UnboundSymbol(*s))?,
            Node::Add(constant, terms) => {
                let terms: Vec<(Reg, &Rational)> =
                    terms.iter().map(|(t, k)| (value[t], k)).collect();
                b.sum(constant, &terms)
            }
            Node::Mul(coef, factors) => {
                let factors: Vec<(Reg, &Rational)> =
                    factors.iter().map(|(f, x)| (value[f], x)).collect();
                b.product(coef, &factors)
            }
            Node::Pow(base, exponent) => b.emit(Instr::PowF(value[base], value[exponent])),
            Node::Func(f @ (Func::Sin | Func::Cos), a) => match angle_pair(pool, *a) {
                Some(((x, sx), (y, sy))) => b.angle_sum(*f, (value[&x], sx), (value[&y], sy)),
                None => b.emit(Instr::Func(*f, value[a])),
            },
            Node::Func(f, a) => b.emit(Instr::Func(*f, value[a])),
            Node::Atan2(y, x) => b.emit(Instr::Atan2(value[y], value[x])),
        };
        value.insert(e, reg);
    }
    let outputs = outputs.iter().map(|e| value[e]).collect();
    let mut program = Program { inputs: b.inputs, constants: b.constants, code: b.code, outputs };
    finish(&mut program);
    remove_dead_code(&mut program);
    Ok(program)
}

/// `±x ± y` with unit coefficients: the argument of sin and cos that the angle-sum formulas
/// turn into products of sines and cosines of x and y, which a chain's many θᵢ − θⱼ share.
fn angle_pair(pool: &Pool, a: ExprId) -> Option<((ExprId, bool), (ExprId, bool))> {
    let Node::Add(constant, terms) = pool.node(a) else { return None };
    let zero = Rational::from_integer(0.into());
    if *constant != zero || terms.len() != 2 {
        return None;
    }
    let sign = |k: &Rational| {
        if k.is_one() {
            Some(false)
        } else if (-k).is_one() {
            Some(true)
        } else {
            None
        }
    };
    let (x, kx) = &terms[0];
    let (y, ky) = &terms[1];
    Some(((*x, sign(kx)?), (*y, sign(ky)?)))
}

/// Drops instructions no output depends on (the sums an angle-sum rewrite no longer reads),
/// renumbering the registers after them.
fn remove_dead_code(p: &mut Program) {
    let first = (p.inputs + p.constants.len()) as Reg;
    let mut live = vec![false; p.code.len()];
    let mark = |r: Reg, live: &mut Vec<bool>| {
        if r >= first {
            live[(r - first) as usize] = true;
        }
    };
    for &o in &p.outputs {
        mark(o, &mut live);
    }
    for i in (0..p.code.len()).rev() {
        if !live[i] {
            continue;
        }
        // Mark every register the instruction reads.
        p.code[i].map_registers(|r| {
            mark(r, &mut live);
            r
        });
    }
    let mut renumber = vec![0 as Reg; p.code.len()];
    let mut next = first;
    for (i, l) in live.iter().enumerate() {
        if *l {
            renumber[i] = next;
            next += 1;
        }
    }
    let fix = |r: Reg| if r >= first { renumber[(r - first) as usize] } else { r };
    let code = std::mem::take(&mut p.code);
    p.code =
        code.into_iter().zip(live).filter(|(_, l)| *l).map(|(i, _)| i.map_registers(fix)).collect();
    for o in p.outputs.iter_mut() {
        *o = fix(*o);
    }
}

struct Builder {
    inputs: usize,
    constants: Vec<f64>,
    constant_regs: HashMap<u64, Reg>,
    code: Vec<Instr>,
    numbered: HashMap<Instr, Reg>,
}

/// Instructions are numbered after every constant, whose count is only known at the end; until
/// then constants and instructions get tagged provisional registers, fixed up by [`finish`].
impl Builder {
    fn constant(&mut self, v: f64) -> Reg {
        if let Some(&r) = self.constant_regs.get(&v.to_bits()) {
            return r;
        }
        let r = self.placeholder_constant(self.constants.len());
        self.constants.push(v);
        self.constant_regs.insert(v.to_bits(), r);
        r
    }

    fn placeholder_constant(&self, index: usize) -> Reg {
        CONSTANT_TAG | (index as Reg)
    }

    fn emit(&mut self, i: Instr) -> Reg {
        if let Some(&r) = self.numbered.get(&i) {
            return r;
        }
        let r = INSTR_TAG | (self.code.len() as Reg);
        self.code.push(i);
        self.numbered.insert(i, r);
        r
    }

    /// sin or cos of `±x ± y` from the sines and cosines of x and y (shared by value
    /// numbering): sin(x + y) = sin x cos y + cos x sin y, cos(x + y) = cos x cos y − sin x sin y,
    /// with sin(−x) = −sin x and cos(−x) = cos x.
    fn angle_sum(
        &mut self,
        f: Func,
        (x, negate_x): (Reg, bool),
        (y, negate_y): (Reg, bool),
    ) -> Reg {
        let (sx, cx) = (self.emit(Instr::Func(Func::Sin, x)), self.emit(Instr::Func(Func::Cos, x)));
        let (sy, cy) = (self.emit(Instr::Func(Func::Sin, y)), self.emit(Instr::Func(Func::Cos, y)));
        // With a sign on x or y, sin picks up a minus: sin(−x) = −sin x.
        let flip =
            |b: &mut Self, r: Reg, negate: bool| if negate { b.emit(Instr::Neg(r)) } else { r };
        let sx = flip(self, sx, negate_x);
        let sy = flip(self, sy, negate_y);
        let (a1, a2) = match f {
            Func::Sin => (self.emit(Instr::Mul(sx, cy)), self.emit(Instr::Mul(cx, sy))),
            _ => (self.emit(Instr::Mul(cx, cy)), self.emit(Instr::Mul(sx, sy))),
        };
        match f {
            Func::Sin => self.emit(Instr::Add(a1, a2)),
            _ => self.emit(Instr::Sub(a1, a2)),
        }
    }

    fn sum(&mut self, constant: &Rational, terms: &[(Reg, &Rational)]) -> Reg {
        // Positive terms first, so that a sum with a negative term starts from a value and
        // subtracts, rather than negating.
        let mut acc: Option<Reg> = None;
        let mut negatives = Vec::new();
        for &(t, k) in terms {
            if k.is_one() {
                acc = Some(match acc {
                    Some(a) => self.emit(Instr::Add(a, t)),
                    None => t,
                });
            } else if (-k).is_one() {
                negatives.push(t);
            } else if k > &Rational::from_integer(0.into()) {
                let c = self.constant(to_f64(k));
                let kt = self.emit(Instr::Mul(c, t));
                acc = Some(match acc {
                    Some(a) => self.emit(Instr::Add(a, kt)),
                    None => kt,
                });
            } else {
                let c = self.constant(to_f64(&-k));
                negatives.push(self.emit(Instr::Mul(c, t)));
            }
        }
        let zero = Rational::from_integer(0.into());
        if *constant != zero || acc.is_none() && negatives.is_empty() {
            let c = self.constant(to_f64(constant));
            acc = Some(match acc {
                Some(a) => self.emit(Instr::Add(a, c)),
                None => c,
            });
        }
        for n in negatives {
            acc = Some(match acc {
                Some(a) => self.emit(Instr::Sub(a, n)),
                None => self.emit(Instr::Neg(n)),
            });
        }
        acc.expect("a sum has at least one part")
    }

    fn product(&mut self, coef: &Rational, factors: &[(Reg, &Rational)]) -> Reg {
        let mut numerator: Option<Reg> = None;
        let mut denominator: Option<Reg> = None;
        let two = Rational::from_integer(2.into());
        for &(base, x) in factors {
            let (magnitude, negative) = if x.is_integer() {
                match x.numer().to_i32() {
                    Some(n) => (self.int_power(base, n.unsigned_abs()), n < 0),
                    None => (self.real_power(base, x), false),
                }
            } else if *x.denom() == *two.numer() {
                match x.numer().to_i32() {
                    Some(n) => {
                        let root = self.emit(Instr::Sqrt(base));
                        (self.int_power(root, n.unsigned_abs()), n < 0)
                    }
                    None => (self.real_power(base, x), false),
                }
            } else {
                (self.real_power(base, x), false)
            };
            let side = if negative { &mut denominator } else { &mut numerator };
            *side = Some(match *side {
                Some(a) => self.emit(Instr::Mul(a, magnitude)),
                None => magnitude,
            });
        }
        let negative = coef < &Rational::from_integer(0.into());
        let magnitude = if negative { -coef } else { coef.clone() };
        let mut acc = numerator;
        if !magnitude.is_one() || acc.is_none() {
            let c = self.constant(to_f64(&magnitude));
            acc = Some(match acc {
                Some(a) => self.emit(Instr::Mul(c, a)),
                None => c,
            });
        }
        let mut acc = acc.expect("set above");
        if let Some(d) = denominator {
            acc = self.emit(Instr::Div(acc, d));
        }
        if negative {
            acc = self.emit(Instr::Neg(acc));
        }
        acc
    }

    fn int_power(&mut self, base: Reg, n: u32) -> Reg {
        match n {
            1 => base,
            2 => self.emit(Instr::Mul(base, base)),
            _ => self.emit(Instr::PowInt(base, n as i32)),
        }
    }

    fn real_power(&mut self, base: Reg, x: &Rational) -> Reg {
        let c = self.constant(to_f64(x));
        self.emit(Instr::PowF(base, c))
    }
}

const CONSTANT_TAG: Reg = 1 << 31;
const INSTR_TAG: Reg = 1 << 30;

/// Replaces the provisional register numbers of constants and instructions by their places in
/// the final layout.
fn finish(p: &mut Program) {
    let inputs = p.inputs as Reg;
    let constants = p.constants.len() as Reg;
    let fix = |r: Reg| -> Reg {
        if r & CONSTANT_TAG != 0 {
            inputs + (r & !CONSTANT_TAG)
        } else if r & INSTR_TAG != 0 {
            inputs + constants + (r & !INSTR_TAG)
        } else {
            r
        }
    };
    for i in p.code.iter_mut() {
        *i = i.map_registers(fix);
    }
    for o in p.outputs.iter_mut() {
        *o = fix(*o);
    }
}
