//! The articulated-body sweep: q̈ of a tree-structured scene from its recursive form
//! (`mechanics::ChainForm`) in O(n), without forming M, written as straight-line code after
//! the form's own program, so that one program gives q̈ from the state. Whatever runs a
//! program then runs it: the tape and its compiled code, the batch tape's lanes, the
//! generated Rust and C.
//!
//! Each node has k own coordinates and a base point whose acceleration a is its parent's base
//! acceleration plus B·q̈ (the parent's own) plus c. Its rows read D·q̈ₒ = u − Uᵀ·a once the
//! children are folded in, and the force its subtree needs at its base is Iᴬ·a + p. From the
//! leaves to the roots, each node folds its children's Iᴬ and p into its own parts (Ĩ += Iᴬ,
//! U += Iᴬ·B, D += Bᵀ·Iᴬ·B, Σm·c += Iᴬ·c + p, u −= Bᵀ·(Iᴬ·c + p)), factors D (LDLᵀ) and
//! passes Iᴬ = Ĩ − U·D⁻¹·Uᵀ and p = Σm·c + U·D⁻¹·u to its parent. From the roots (whose base
//! is fixed, a = 0) to the leaves, q̈ₒ = D⁻¹·u − D⁻¹·Uᵀ·a. This is Featherstone's
//! articulated-body algorithm with translations for the joints' motion: the scene's own
//! kinematics give B, E and the bias terms exactly, the sweep only adds and solves.
//!
//! The same sweep with no bias terms and other right-hand sides for u solves M·x = b: a
//! second program gives the sweep's factors beside q̈ (per node 1/Δ, L, D⁻¹·Uᵀ and B), and
//! [`Chain::solve_columns`] solves blocks of columns with them in O(n) each, which the exact
//! Jacobian, the sensitivities and the variational runs take on a long chain.
//!
//! A D that vanishes (a coordinate that has lost its inertia) makes q̈ infinite or NaN; the
//! problem that runs the program then solves by the dense route, which says why.

use numeric::{Instr, Program, Reg};

/// A value of the sweep: a register, or `None` where it is exactly zero (a root's base
/// acceleration, a term the form's program gives as the constant 0), so that no operation is
/// spent on it.
type Value = Option<Reg>;

/// The recursive form's shape: each node's parent (before it) and own coordinates.
#[derive(Clone, Debug)]
pub struct Chain {
    dimension: usize,
    nodes: Vec<(Option<usize>, Vec<usize>)>,
    /// Where each node's factors start among the factored program's outputs after q̈, and
    /// (last) how many there are.
    factor_starts: Vec<usize>,
    /// Where every node owns one coordinate (a chain of hinges, the common case): per node
    /// its coordinate, and its parent with the parent's coordinate.
    hinges: Option<Vec<Hinge>>,
}

/// A node of one coordinate, for the solves' lean loop.
#[derive(Clone, Copy, Debug)]
struct Hinge {
    coordinate: usize,
    parent: Option<(usize, usize)>,
}

impl Chain {
    /// The shape of nodes given parents first, in a scene of `dimension` (2 or 3).
    pub fn new(dimension: usize, nodes: &[(Option<usize>, Vec<usize>)]) -> Chain {
        for (x, (parent, _)) in nodes.iter().enumerate() {
            assert!(parent.is_none_or(|p| p < x), "a parent comes before its children");
        }
        assert!(dimension <= 3, "a scene of two or three dimensions");
        let hinges = nodes.iter().all(|(_, own)| own.len() == 1).then(|| {
            let hinge = |(parent, own): &(Option<usize>, Vec<usize>)| Hinge {
                coordinate: own[0],
                parent: parent.map(|p| (p, nodes[p].1[0])),
            };
            nodes.iter().map(hinge).collect()
        });
        let mut chain = Chain { dimension, nodes: nodes.to_vec(), factor_starts: vec![0], hinges };
        for x in 0..nodes.len() {
            let next = chain.factor_starts[x] + chain.factor_terms(x);
            chain.factor_starts.push(next);
        }
        chain
    }

    /// How many values the recursive form's program gives: per node Σm, D (k×k), U (d×k),
    /// Σm·c (d), u (k), then B (d × the parent's k) and c (d) unless it is a root.
    pub fn outputs(&self) -> usize {
        (0..self.nodes.len()).map(|x| self.own_terms(x) + self.base_terms(x)).sum()
    }

    /// How many of node x's terms are its own: Σm, D, U, Σm·c and u.
    fn own_terms(&self, x: usize) -> usize {
        let (d, k) = (self.dimension, self.nodes[x].1.len());
        1 + k * k + d * k + d + k
    }

    /// How many of node x's terms place its base in its parent: B and c (none at a root).
    fn base_terms(&self, x: usize) -> usize {
        let d = self.dimension;
        self.nodes[x].0.map_or(0, |p| d * self.nodes[p].1.len() + d)
    }

    /// How many coordinates the nodes own.
    pub fn coordinates(&self) -> usize {
        self.nodes.iter().map(|(_, own)| own.len()).sum()
    }

    /// How many values the factored program gives after q̈ ([`Recursive::factored`]).
    pub fn factor_outputs(&self) -> usize {
        self.factor_starts[self.nodes.len()]
    }

    /// How many of the sweep's factors node x has: 1/Δ (k), L below its diagonal
    /// (k·(k − 1)/2, row by row), D⁻¹·Uᵀ (k×d), then B (d × the parent's k) unless it is a
    /// root.
    fn factor_terms(&self, x: usize) -> usize {
        let (d, k) = (self.dimension, self.nodes[x].1.len());
        let base = self.nodes[x].0.map_or(0, |p| d * self.nodes[p].1.len());
        k + k * (k - 1) / 2 + k * d + base
    }

    /// The sweep lowered after `terms`, the recursive form's program: q̈'s program (one output
    /// per coordinate, in the coordinates' order), and the same with the sweep's factors after
    /// q̈.
    pub fn lower(self, terms: Program) -> Recursive {
        let (builder, accelerations, factors) = self.sweep(terms);
        let mut both = accelerations.clone();
        both.extend(factors);
        let copy = Builder { program: builder.program.clone(), ..builder };
        Recursive {
            accelerations: copy.finish(&accelerations),
            factored: builder.finish(&both),
            chain: self,
        }
    }

    /// The sweep's instructions after `terms`: the builder, q̈ and the factors in the layout
    /// of [`Chain::factor_outputs`].
    fn sweep(&self, terms: Program) -> (Builder, Vec<Value>, Vec<Value>) {
        assert_eq!(terms.outputs.len(), self.outputs(), "the recursive form's program");
        let mut b = Builder::new(terms);
        let (d, count) = (self.dimension, self.nodes.len());
        // Where each node's terms start in the form's outputs.
        let mut starts = Vec::with_capacity(count);
        let mut at = 0;
        for x in 0..count {
            starts.push(at);
            at += self.own_terms(x) + self.base_terms(x);
        }
        let mut parts: Vec<Parts> = Vec::with_capacity(count);
        for (x, (_, own)) in self.nodes.iter().enumerate() {
            let k = own.len();
            let mut at = starts[x];
            let mass = b.term(at);
            at += 1;
            let mut next = |n: usize| {
                let values: Vec<Value> = (at..at + n).map(|i| b.term(i)).collect();
                at += n;
                values
            };
            let joint = next(k * k);
            let coupling = next(d * k);
            let bias = next(d);
            let force = next(k);
            let mut inertia = vec![None; d * d];
            for i in 0..d {
                inertia[i * d + i] = mass;
            }
            parts.push(Parts { inertia, coupling, joint, bias, force });
        }
        // The base columns B and bias c of each node, in its parent's own coordinates.
        let base = |b: &Builder, x: usize| -> (Vec<Value>, Vec<Value>) {
            let kp = self.nodes[self.nodes[x].0.expect("a child")].1.len();
            let at = starts[x] + self.own_terms(x);
            let columns = (at..at + d * kp).map(|i| b.term(i)).collect();
            let bias = (at + d * kp..at + d * kp + d).map(|i| b.term(i)).collect();
            (columns, bias)
        };
        // From the leaves: D⁻¹·Uᵀ (k×d) and D⁻¹·u per node, for the pass back.
        let mut solved: Vec<(Vec<Value>, Vec<Value>)> = vec![(Vec::new(), Vec::new()); count];
        let mut factor_values: Vec<Vec<Value>> = vec![Vec::new(); count];
        for x in (0..count).rev() {
            let k = self.nodes[x].1.len();
            let Parts { inertia, coupling, joint, bias, force } = parts[x].clone();
            let factors = b.ldl(&joint, k);
            let mut y = vec![None; k * d];
            for i in 0..d {
                let column: Vec<Value> = (0..k).map(|j| coupling[i * k + j]).collect();
                for (j, v) in b.ldl_solve(&factors, k, column).into_iter().enumerate() {
                    y[j * d + i] = v;
                }
            }
            let free = b.ldl_solve(&factors, k, force);
            let mut own_factors = factors.reciprocals.clone();
            for i in 0..k {
                own_factors.extend((0..i).map(|m| factors.lower[i * k + m]));
            }
            own_factors.extend(&y);
            let mut articulated = inertia;
            let mut pushed = bias;
            for i in 0..d {
                for l in 0..d {
                    let products: Vec<Value> =
                        (0..k).map(|j| b.mul(coupling[i * k + j], y[j * d + l])).collect();
                    let sum = b.sum(&products);
                    articulated[i * d + l] = b.sub(articulated[i * d + l], sum);
                }
                let products: Vec<Value> =
                    (0..k).map(|j| b.mul(coupling[i * k + j], free[j])).collect();
                let sum = b.sum(&products);
                pushed[i] = b.add(pushed[i], sum);
            }
            solved[x] = (y, free);
            let Some(p) = self.nodes[x].0 else {
                factor_values[x] = own_factors;
                continue;
            };
            let kp = self.nodes[p].1.len();
            let (columns, base_bias) = base(&b, x);
            own_factors.extend(&columns);
            factor_values[x] = own_factors;
            // z = Iᴬ·c + p: the force the subtree needs beyond Iᴬ times the parent's terms.
            let z: Vec<Value> = (0..d)
                .map(|i| {
                    let mut terms = vec![pushed[i]];
                    terms.extend((0..d).map(|l| b.mul(articulated[i * d + l], base_bias[l])));
                    b.sum(&terms)
                })
                .collect();
            let through: Vec<Value> = (0..d * kp)
                .map(|ij| {
                    let (i, j) = (ij / kp, ij % kp);
                    let terms: Vec<Value> = (0..d)
                        .map(|l| b.mul(articulated[i * d + l], columns[l * kp + j]))
                        .collect();
                    b.sum(&terms)
                })
                .collect();
            let parent = &mut parts[p];
            for i in 0..d {
                for l in 0..d {
                    parent.inertia[i * d + l] =
                        b.add(parent.inertia[i * d + l], articulated[i * d + l]);
                }
                parent.bias[i] = b.add(parent.bias[i], z[i]);
                for j in 0..kp {
                    parent.coupling[i * kp + j] =
                        b.add(parent.coupling[i * kp + j], through[i * kp + j]);
                }
            }
            for m in 0..kp {
                for j in 0..kp {
                    let terms: Vec<Value> =
                        (0..d).map(|i| b.mul(columns[i * kp + m], through[i * kp + j])).collect();
                    let sum = b.sum(&terms);
                    parent.joint[m * kp + j] = b.add(parent.joint[m * kp + j], sum);
                }
                let terms: Vec<Value> = (0..d).map(|i| b.mul(columns[i * kp + m], z[i])).collect();
                let sum = b.sum(&terms);
                parent.force[m] = b.sub(parent.force[m], sum);
            }
        }
        // From the roots: each base's acceleration, and q̈.
        let mut accelerations: Vec<Value> = vec![None; self.coordinates()];
        let mut base_accelerations: Vec<Vec<Value>> = vec![Vec::new(); count];
        for x in 0..count {
            let (parent, own) = &self.nodes[x];
            let a: Vec<Value> = match parent {
                None => vec![None; d],
                Some(p) => {
                    let kp = self.nodes[*p].1.len();
                    let (columns, base_bias) = base(&b, x);
                    (0..d)
                        .map(|i| {
                            let mut terms = vec![base_accelerations[*p][i]];
                            for (j, q) in self.nodes[*p].1.iter().enumerate() {
                                terms.push(b.mul(columns[i * kp + j], accelerations[*q]));
                            }
                            terms.push(base_bias[i]);
                            b.sum(&terms)
                        })
                        .collect()
                }
            };
            let (y, free) = &solved[x];
            for (j, q) in own.iter().enumerate() {
                let terms: Vec<Value> = (0..d).map(|i| b.mul(y[j * d + i], a[i])).collect();
                let sum = b.sum(&terms);
                accelerations[*q] = b.sub(free[j], sum);
            }
            base_accelerations[x] = a;
        }
        (b, accelerations, factor_values.concat())
    }
}

/// The recursive form lowered ([`Chain::lower`]).
#[derive(Clone)]
pub struct Recursive {
    /// q̈, one output per coordinate in the coordinates' order.
    pub accelerations: Program,
    /// The same q̈, then the sweep's factors ([`Chain::factor_outputs`]), with which
    /// [`Chain::solve_columns`] solves M·x = b for other right-hand sides.
    pub factored: Program,
    pub chain: Chain,
}

impl Chain {
    /// Solves M·x = b for `W` right-hand sides side by side (`block`, a row per coordinate, b
    /// in and x out) with the sweep's factors at a state (`factors`, the factored program's
    /// outputs after q̈), in O(n) per column where the dense route's solve is O(n²) and needs M
    /// formed and factored first. The equations are linear in q̈, the bias terms and the
    /// forces, so the sweep with no bias and b for u solves M·x = b: from the leaves each node
    /// takes D⁻¹ of its rows (its children's forces already taken out) and passes the force
    /// its subtree needs, z = U·D⁻¹·u plus its children's, to its parent; from the roots,
    /// x = D⁻¹·u − D⁻¹·Uᵀ·a with a = a(parent) + B·x(parent). `work` is scratch.
    pub fn solve_columns<const W: usize>(
        &self,
        factors: &[f64],
        block: &mut [[f64; W]],
        work: &mut Vec<[f64; W]>,
    ) {
        assert_eq!(factors.len(), self.factor_outputs(), "the sweep's factors");
        assert_eq!(block.len(), self.coordinates(), "a row per coordinate");
        // The dimension fixed at compile time keeps a node's d rows of columns in registers.
        match (self.dimension, &self.hinges) {
            (2, Some(hinges)) => self.solve_hinges::<W, 2>(hinges, factors, block, work),
            (_, Some(hinges)) => self.solve_hinges::<W, 3>(hinges, factors, block, work),
            (2, None) => self.solve_in::<W, 2>(factors, block, work),
            (_, None) => self.solve_in::<W, 3>(factors, block, work),
        }
    }

    /// [`Chain::solve_columns`] where every node has one coordinate: the same operations in
    /// the same order (the same bits), without the general loops' bookkeeping, which had cost
    /// more than the arithmetic.
    fn solve_hinges<const W: usize, const D: usize>(
        &self,
        hinges: &[Hinge],
        factors: &[f64],
        block: &mut [[f64; W]],
        work: &mut Vec<[f64; W]>,
    ) {
        let count = hinges.len();
        work.clear();
        work.resize(2 * D * count, [0.0; W]);
        let (pushed, bases) = work.split_at_mut(D * count);
        for (x, hinge) in hinges.iter().enumerate().rev() {
            let f = &factors[self.factor_starts[x]..self.factor_starts[x + 1]];
            let (reciprocal, through) = (f[0], &f[1..1 + D]);
            let u = block[hinge.coordinate];
            let mut z = [[0.0; W]; D];
            for i in 0..D {
                let (t, sum) = (through[i], pushed[x * D + i]);
                for c in 0..W {
                    z[i][c] = sum[c] + t * u[c];
                }
            }
            let row = &mut block[hinge.coordinate];
            for c in 0..W {
                row[c] *= reciprocal;
            }
            let Some((p, above)) = hinge.parent else { continue };
            let columns = &f[1 + D..1 + 2 * D];
            let mut row = block[above];
            for i in 0..D {
                let (b, sum) = (columns[i], &mut pushed[p * D + i]);
                for c in 0..W {
                    sum[c] += z[i][c];
                    row[c] -= b * z[i][c];
                }
            }
            block[above] = row;
        }
        for (x, hinge) in hinges.iter().enumerate() {
            let Some((p, above)) = hinge.parent else { continue };
            let f = &factors[self.factor_starts[x]..self.factor_starts[x + 1]];
            let (through, columns) = (&f[1..1 + D], &f[1 + D..1 + 2 * D]);
            let v = block[above];
            let mut row = block[hinge.coordinate];
            for i in 0..D {
                let (b, t) = (columns[i], through[i]);
                let mut a = bases[p * D + i];
                for c in 0..W {
                    a[c] += b * v[c];
                    row[c] -= t * a[c];
                }
                bases[x * D + i] = a;
            }
            block[hinge.coordinate] = row;
        }
    }

    /// Node x's factors: 1/Δ, L below the diagonal, D⁻¹·Uᵀ and B.
    #[inline(always)]
    fn factors_of<'a>(&self, factors: &'a [f64], x: usize) -> [&'a [f64]; 4] {
        let (d, k) = (self.dimension, self.nodes[x].1.len());
        let f = &factors[self.factor_starts[x]..self.factor_starts[x + 1]];
        let (reciprocals, rest) = f.split_at(k);
        let (lower, rest) = rest.split_at(k * (k - 1) / 2);
        let (through, columns) = rest.split_at(k * d);
        [reciprocals, lower, through, columns]
    }

    fn solve_in<const W: usize, const D: usize>(
        &self,
        factors: &[f64],
        block: &mut [[f64; W]],
        work: &mut Vec<[f64; W]>,
    ) {
        let count = self.nodes.len();
        work.clear();
        work.resize(2 * D * count, [0.0; W]);
        let (pushed, bases) = work.split_at_mut(D * count);
        for x in (0..count).rev() {
            let (parent, own) = &self.nodes[x];
            let k = own.len();
            let [reciprocals, lower, through, columns] = self.factors_of(factors, x);
            // z = the children's + U·D⁻¹·u, U·D⁻¹ being (D⁻¹·Uᵀ)ᵀ: from u, before D⁻¹.
            let mut z = [[0.0; W]; D];
            z.copy_from_slice(&pushed[x * D..x * D + D]);
            for (j, q) in own.iter().enumerate() {
                let u = block[*q];
                for (i, zi) in z.iter_mut().enumerate() {
                    let t = through[j * D + i];
                    for c in 0..W {
                        zi[c] += t * u[c];
                    }
                }
            }
            // D⁻¹ of the node's rows: L, Δ, then Lᵀ.
            for i in 0..k {
                for m in 0..i {
                    let (l, from) = (lower[i * (i - 1) / 2 + m], block[own[m]]);
                    let row = &mut block[own[i]];
                    for c in 0..W {
                        row[c] -= l * from[c];
                    }
                }
            }
            for (q, r) in own.iter().zip(reciprocals) {
                let row = &mut block[*q];
                for v in row.iter_mut() {
                    *v *= r;
                }
            }
            for i in (0..k).rev() {
                for m in i + 1..k {
                    let (l, from) = (lower[m * (m - 1) / 2 + i], block[own[m]]);
                    let row = &mut block[own[i]];
                    for c in 0..W {
                        row[c] -= l * from[c];
                    }
                }
            }
            let Some(p) = *parent else { continue };
            let parent_own = &self.nodes[p].1;
            let kp = parent_own.len();
            for (i, zi) in z.iter().enumerate() {
                let sum = &mut pushed[p * D + i];
                for c in 0..W {
                    sum[c] += zi[c];
                }
            }
            for (m, q) in parent_own.iter().enumerate() {
                let row = &mut block[*q];
                for (i, zi) in z.iter().enumerate() {
                    let b = columns[i * kp + m];
                    for c in 0..W {
                        row[c] -= b * zi[c];
                    }
                }
            }
        }
        for x in 0..count {
            let (parent, own) = &self.nodes[x];
            // A root's base is fixed: its rows are D⁻¹·u already.
            let Some(p) = *parent else { continue };
            let [_, _, through, columns] = self.factors_of(factors, x);
            let parent_own = &self.nodes[p].1;
            let kp = parent_own.len();
            let mut a = [[0.0; W]; D];
            a.copy_from_slice(&bases[p * D..p * D + D]);
            for (j, q) in parent_own.iter().enumerate() {
                let v = block[*q];
                for (i, ai) in a.iter_mut().enumerate() {
                    let b = columns[i * kp + j];
                    for c in 0..W {
                        ai[c] += b * v[c];
                    }
                }
            }
            bases[x * D..x * D + D].copy_from_slice(&a);
            for (j, q) in own.iter().enumerate() {
                let row = &mut block[*q];
                for (i, ai) in a.iter().enumerate() {
                    let t = through[j * D + i];
                    for c in 0..W {
                        row[c] -= t * ai[c];
                    }
                }
            }
        }
    }
}

/// A node's parts as the sweep folds them: Ĩ (d×d), U (d×k), D (k×k), Σm·c (d), u (k).
#[derive(Clone)]
struct Parts {
    inertia: Vec<Value>,
    coupling: Vec<Value>,
    joint: Vec<Value>,
    bias: Vec<Value>,
    force: Vec<Value>,
}

/// The factors of D = L·Δ·Lᵀ: L's entries below the diagonal (row-major k×k) and 1/Δ.
struct Factors {
    lower: Vec<Value>,
    reciprocals: Vec<Value>,
}

/// Appends instructions to a program.
struct Builder {
    program: Program,
    /// The registers of the constants 0 and 1.
    zero: Reg,
    one: Reg,
}

impl Builder {
    /// The builder of a program that extends `terms`, with the constants 0 and 1 among its
    /// registers (added after its own, its instructions' registers moved up to make room).
    fn new(mut terms: Program) -> Builder {
        let constant = |terms: &mut Program, value: f64| -> Reg {
            if let Some(i) = terms.constants.iter().position(|c| c.to_bits() == value.to_bits()) {
                return (terms.inputs + i) as Reg;
            }
            let slot = (terms.inputs + terms.constants.len()) as Reg;
            terms.constants.push(value);
            let moved = |r: Reg| if r >= slot { r + 1 } else { r };
            terms.code = terms.code.iter().map(|i| i.map_registers(moved)).collect();
            terms.outputs = terms.outputs.iter().map(|r| moved(*r)).collect();
            slot
        };
        let zero = constant(&mut terms, 0.0);
        let one = constant(&mut terms, 1.0);
        Builder { program: terms, zero, one }
    }

    /// Output `index` of the form's program, `None` where it is the constant 0.
    fn term(&self, index: usize) -> Value {
        let r = self.program.outputs[index];
        (r != self.zero).then_some(r)
    }

    fn push(&mut self, instr: Instr) -> Reg {
        let p = &mut self.program;
        let r = (p.inputs + p.constants.len() + p.code.len()) as Reg;
        p.code.push(instr);
        r
    }

    fn add(&mut self, a: Value, b: Value) -> Value {
        match (a, b) {
            (None, x) | (x, None) => x,
            (Some(a), Some(b)) => Some(self.push(Instr::Add(a, b))),
        }
    }

    fn sub(&mut self, a: Value, b: Value) -> Value {
        match (a, b) {
            (x, None) => x,
            (None, Some(b)) => Some(self.push(Instr::Neg(b))),
            (Some(a), Some(b)) => Some(self.push(Instr::Sub(a, b))),
        }
    }

    fn mul(&mut self, a: Value, b: Value) -> Value {
        match (a, b) {
            (Some(a), Some(b)) => Some(self.push(Instr::Mul(a, b))),
            _ => None,
        }
    }

    /// The terms added left to right.
    fn sum(&mut self, terms: &[Value]) -> Value {
        terms.iter().fold(None, |sum, t| self.add(sum, *t))
    }

    /// 1/a; a zero gives what dividing by zero gives (an infinity the caller sees).
    fn reciprocal(&mut self, a: Value) -> Value {
        let a = a.unwrap_or(self.zero);
        Some(self.push(Instr::Div(self.one, a)))
    }

    /// D = L·Δ·Lᵀ of a symmetric k×k D (row-major), without square roots.
    fn ldl(&mut self, joint: &[Value], k: usize) -> Factors {
        let mut lower = vec![None; k * k];
        let mut pivots = vec![None; k];
        let mut reciprocals = vec![None; k];
        for j in 0..k {
            let mut pivot = joint[j * k + j];
            for m in 0..j {
                let t = self.mul(lower[j * k + m], lower[j * k + m]);
                let t = self.mul(t, pivots[m]);
                pivot = self.sub(pivot, t);
            }
            pivots[j] = pivot;
            reciprocals[j] = self.reciprocal(pivot);
            for i in j + 1..k {
                let mut v = joint[i * k + j];
                for m in 0..j {
                    let t = self.mul(lower[i * k + m], lower[j * k + m]);
                    let t = self.mul(t, pivots[m]);
                    v = self.sub(v, t);
                }
                lower[i * k + j] = self.mul(v, reciprocals[j]);
            }
        }
        Factors { lower, reciprocals }
    }

    /// x with L·Δ·Lᵀ·x = b.
    fn ldl_solve(&mut self, f: &Factors, k: usize, mut b: Vec<Value>) -> Vec<Value> {
        for i in 0..k {
            for m in 0..i {
                let t = self.mul(f.lower[i * k + m], b[m]);
                b[i] = self.sub(b[i], t);
            }
        }
        for i in 0..k {
            b[i] = self.mul(b[i], f.reciprocals[i]);
        }
        for i in (0..k).rev() {
            for m in i + 1..k {
                let t = self.mul(f.lower[m * k + i], b[m]);
                b[i] = self.sub(b[i], t);
            }
        }
        b
    }

    /// The program with `outputs` its outputs (a zero one the constant 0), without the
    /// instructions no output needs (a root's articulated inertia, a form's term the sweep
    /// skips): generated code must not compute a value it never reads.
    fn finish(mut self, outputs: &[Value]) -> Program {
        let p = &mut self.program;
        p.outputs = outputs.iter().map(|v| v.unwrap_or(self.zero)).collect();
        let base = p.inputs + p.constants.len();
        let mut live = vec![false; p.code.len()];
        for r in &p.outputs {
            if let Some(i) = (*r as usize).checked_sub(base) {
                live[i] = true;
            }
        }
        for i in (0..p.code.len()).rev() {
            if live[i] {
                p.code[i].map_registers(|r| {
                    if let Some(j) = (r as usize).checked_sub(base) {
                        live[j] = true;
                    }
                    r
                });
            }
        }
        let mut renamed = vec![0; p.code.len()];
        let mut code = Vec::with_capacity(p.code.len());
        let rename = |r: Reg, renamed: &[Reg]| match (r as usize).checked_sub(base) {
            Some(i) => renamed[i],
            None => r,
        };
        for (i, instr) in p.code.iter().enumerate() {
            if live[i] {
                renamed[i] = (base + code.len()) as Reg;
                code.push(instr.map_registers(|r| rename(r, &renamed)));
            }
        }
        p.code = code;
        p.outputs = p.outputs.iter().map(|r| rename(*r, &renamed)).collect();
        self.program
    }
}
