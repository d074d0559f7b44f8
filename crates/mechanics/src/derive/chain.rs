//! The recursive form of the equations of motion, for scenes whose bodies hang from one
//! another in a tree: each point's velocity is its parent's base velocity plus terms in its
//! own coordinates' rates. The numbers then solve M·q̈ = f in O(n) by an articulated-body
//! sweep (`sim`'s `Chain`), without forming M, whose n² entries and n³/6 factorization are
//! what the dense route costs on a long chain.
//!
//! The structure is found, not declared. A point of the scene's dimension (a particle, a
//! body's centre) depends on a set of coordinates; each set is a node, its parent the largest
//! set inside it, and its own coordinates those its parent lacks. The sets inside a set must
//! lie on one way up from it (a chain of parents), and every coordinate must be owned by one
//! node: then sets meet only in what the nodes above both own, as siblings meet in their
//! parent's set. A point's column for a coordinate its node does not own must be the same for
//! every point below that coordinate's child node: that common column is the child's base,
//! so the base's velocity is its parent's base velocity plus the base columns times the
//! parent's own rates. Rotation (a planar angle, a body turning in space) and any other
//! kinetic term may depend only on one node's own coordinates. An n-link chain in absolute
//! angles has this form; one in relative angles does not (a point's column for the first
//! angle depends on every later one), and keeps the dense route, as does every scene with
//! kept constraints, contacts, a position or turning prescribed in time, or kinetic energy
//! off the structural route.
//!
//! For a node with own rates q̇ₒ (k of them) in a scene of dimension d, with base
//! acceleration a, its points' accelerations are a + Eₚ·q̈ₒ + cₚ, and its Euler–Lagrange rows
//! read Σ Eₚᵀ·Fₚ + (children's) + D_own·q̈ₒ = Q − (own bias), each F a point's force m·a. The
//! lowered program gives per node the parts that need no other node: Σm, D = Σ m·EᵀE + the
//! rotational inertia, U = Σ m·E, Σ m·c, u = Q − Σ m·Eᵀc − the rotational bias, and its base
//! columns B and base bias c in its parent; the sweep adds the children's articulated
//! inertias to them.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId, SymbolKind};

use super::equations::Structure;
use super::structural::{acceleration_without_q2, angular_momentum_rate, InertialTerm};
use super::Derivation;

/// The recursive form: nodes in an order where a parent comes before its children.
#[derive(Clone, Debug)]
pub struct ChainForm {
    /// d: the points' velocities have this many components (2 in the plane, 3 in space).
    pub dimension: usize,
    pub nodes: Vec<ChainNode>,
}

/// One node of the tree: its own coordinates and the expressions of the state the sweep
/// starts from (row-major matrices).
#[derive(Clone, Debug)]
pub struct ChainNode {
    pub parent: Option<usize>,
    /// Indices into the derivation's remaining coordinates.
    pub coordinates: Vec<usize>,
    /// Σ m over the node's points.
    pub mass: ExprId,
    /// D, k×k: Σ m·EᵀE plus the rotational inertia of the own coordinates.
    pub inertia: Vec<ExprId>,
    /// U, d×k: Σ m·E.
    pub coupling: Vec<ExprId>,
    /// Σ m·c, d.
    pub bias: Vec<ExprId>,
    /// u, k: Q − Σ m·Eᵀc − the rotational bias.
    pub force: Vec<ExprId>,
    /// B, d×k of the parent: the base's columns in the parent's own rates; empty at a root.
    pub base: Vec<ExprId>,
    /// The base's acceleration with the parent's q̈ zero, relative to the parent's base, d;
    /// empty at a root.
    pub base_bias: Vec<ExprId>,
}

impl ChainForm {
    /// Every node's expressions in one list, in the layout `sim::Chain` reads: per node Σm,
    /// D, U, Σ m·c, u, then B and its bias unless it is a root.
    pub fn outputs(&self) -> Vec<ExprId> {
        let mut v = Vec::new();
        for node in &self.nodes {
            v.push(node.mass);
            v.extend(&node.inertia);
            v.extend(&node.coupling);
            v.extend(&node.bias);
            v.extend(&node.force);
            v.extend(&node.base);
            v.extend(&node.base_bias);
        }
        v
    }
}

impl Derivation {
    /// The recursive form of the equations, where the scene has one (see the module's doc);
    /// `None` sends it the dense route. It builds new expressions, so it is computed only when
    /// a caller asks for it.
    pub fn chain_form(&mut self) -> Option<ChainForm> {
        if !self.multipliers.is_empty() || !self.contacts.is_empty() {
            return None;
        }
        let structure = self.structure.take()?;
        let dimension = self.model.dimension();
        let form = build(&mut self.model.pool, dimension, &self.coords, &structure);
        self.structure = Some(structure);
        form
    }
}

/// A point of the scene's dimension: its mass and its nonzero columns, by coordinate.
struct Point {
    mass: ExprId,
    columns: Vec<(usize, Vec<ExprId>)>,
}

/// A kinetic term of a single node's own coordinates.
enum Own<'a> {
    /// ½·m·|ẋ|² of a position that is not a point of the scene's dimension (a planar angle).
    Moving { mass: ExprId, position: &'a [ExprId], columns: Vec<(usize, Vec<ExprId>)> },
    /// ½·ωᵀ·I·ω, its columns ∂ω/∂q̇.
    Turning { inertia: [[ExprId; 3]; 3], omega: [ExprId; 3], columns: Vec<(usize, Vec<ExprId>)> },
}

impl Own<'_> {
    fn columns(&self) -> &[(usize, Vec<ExprId>)] {
        match self {
            Own::Moving { columns, .. } | Own::Turning { columns, .. } => columns,
        }
    }
}

fn build(
    pool: &mut Pool,
    dimension: usize,
    coords: &[SymId],
    structure: &Structure,
) -> Option<ChainForm> {
    if structure.rest_has_mass {
        return None;
    }
    let n = coords.len();
    let index: HashMap<SymId, usize> = coords.iter().enumerate().map(|(i, q)| (*q, i)).collect();
    let rates: HashMap<SymId, usize> = coords
        .iter()
        .enumerate()
        .map(|(i, q)| (pool.rate(*q).expect("coordinates have rates"), i))
        .collect();
    let mut points = Vec::new();
    let mut owns = Vec::new();
    for term in &structure.terms {
        match term {
            InertialTerm::Moving(term) => {
                let timed = term.position.iter().any(|x| {
                    pool.free_symbols(*x).iter().any(|s| pool.symbol(*s).kind == SymbolKind::Time)
                });
                if timed {
                    return None;
                }
                let columns = columns(pool, &term.position, &index);
                if columns.is_empty() {
                    continue;
                }
                if term.position.len() == dimension {
                    points.push(Point { mass: term.mass, columns });
                } else {
                    owns.push(Own::Moving { mass: term.mass, position: &term.position, columns });
                }
            }
            InertialTerm::Turning(turn) => {
                if turn.driven {
                    return None;
                }
                let columns = columns(pool, &turn.omega, &rates);
                if !columns.is_empty() {
                    owns.push(Own::Turning { inertia: turn.inertia, omega: turn.omega, columns });
                }
            }
        }
    }
    let tree = Tree::of(&points, n)?;
    let mut own_terms: Vec<Vec<usize>> = vec![Vec::new(); tree.sets.len()];
    for (t, own) in owns.iter().enumerate() {
        let first = own.columns()[0].0;
        let node = (0..tree.sets.len()).find(|&x| tree.own[x].contains(&first))?;
        if !own.columns().iter().all(|(i, _)| tree.own[node].contains(i)) {
            return None;
        }
        own_terms[node].push(t);
    }
    // The base columns: for a node C and each coordinate its parent owns, the column every
    // point below C shares.
    let mut base: Vec<HashMap<usize, Vec<ExprId>>> = vec![HashMap::new(); tree.sets.len()];
    for (p, point) in points.iter().enumerate() {
        let mut child = tree.node_of[p];
        while let Some(parent) = tree.parent[child] {
            for &i in &tree.own[parent] {
                let column = &point.columns.iter().find(|(j, _)| *j == i)?.1;
                match base[child].get(&i) {
                    None => {
                        base[child].insert(i, column.clone());
                    }
                    Some(shared) => {
                        for (&a, &b) in shared.iter().zip(column) {
                            if a != b {
                                let difference = pool.sub(a, b);
                                if !pool.is_identically_zero(difference) {
                                    return None;
                                }
                            }
                        }
                    }
                }
            }
            child = parent;
        }
    }
    let mut nodes = Vec::with_capacity(tree.sets.len());
    for x in 0..tree.sets.len() {
        let own = &tree.own[x];
        let members: Vec<&Point> =
            (0..points.len()).filter(|&p| tree.node_of[p] == x).map(|p| &points[p]).collect();
        let own_of: Vec<&Own> = own_terms[x].iter().map(|&t| &owns[t]).collect();
        let mut node = node_expressions(pool, dimension, coords, own, &members, &own_of);
        node.force = node
            .force
            .iter()
            .zip(own)
            .map(|(u, &i)| {
                let q = pool.add(&structure.rest_forcing[i]);
                pool.add2(q, *u)
            })
            .collect();
        if let Some(parent) = tree.parent[x] {
            let parent_own = &tree.own[parent];
            let mut columns = vec![pool.zero(); dimension * parent_own.len()];
            let mut bias = Vec::with_capacity(dimension);
            for a in 0..dimension {
                let mut parts = Vec::new();
                for (j, i) in parent_own.iter().enumerate() {
                    let entry = base[x][i][a];
                    columns[a * parent_own.len() + j] = entry;
                    parts.push(rate_times_derivative(pool, entry, coords[*i]));
                }
                bias.push(pool.add(&parts));
            }
            node.base = columns;
            node.base_bias = bias;
        }
        node.parent = tree.parent[x];
        node.coordinates = own.clone();
        nodes.push(node);
    }
    Some(ChainForm { dimension, nodes })
}

/// The nonzero columns ∂x/∂s of a vector x, by coordinate index, for the symbols s that
/// `by` maps to one (the coordinates themselves, or their rates).
fn columns(pool: &mut Pool, x: &[ExprId], by: &HashMap<SymId, usize>) -> Vec<(usize, Vec<ExprId>)> {
    let mut moving: Vec<(usize, SymId)> = Vec::new();
    for &e in x {
        for s in pool.free_symbols(e).iter() {
            if let Some(&i) = by.get(s) {
                moving.push((i, *s));
            }
        }
    }
    moving.sort_unstable();
    moving.dedup();
    let mut out = Vec::new();
    for (i, s) in moving {
        let column: Vec<ExprId> = x.iter().map(|e| pool.diff(*e, s)).collect();
        if column.iter().any(|e| !pool.is_zero(*e)) {
            out.push((i, column));
        }
    }
    out
}

/// (d/dt e)·q̇ for an expression e of the coordinates: one term of a bias acceleration.
fn rate_times_derivative(pool: &mut Pool, e: ExprId, q: SymId) -> ExprId {
    let rate = pool.rate(q).expect("coordinates have rates");
    let rate = pool.sym(rate);
    let de = pool.time_derivative(e);
    pool.mul2(de, rate)
}

/// A node's own parts, its base and parent left for the caller.
fn node_expressions(
    pool: &mut Pool,
    d: usize,
    coords: &[SymId],
    own: &[usize],
    points: &[&Point],
    owns: &[&Own],
) -> ChainNode {
    let k = own.len();
    let zero = pool.zero();
    let mut mass = Vec::new();
    let mut inertia: Vec<Vec<ExprId>> = vec![Vec::new(); k * k];
    let mut coupling: Vec<Vec<ExprId>> = vec![Vec::new(); d * k];
    let mut bias: Vec<Vec<ExprId>> = vec![Vec::new(); d];
    let mut force: Vec<Vec<ExprId>> = vec![Vec::new(); k];
    for point in points {
        let m = point.mass;
        mass.push(m);
        // E, d×k, and c = Σⱼ (d/dt Eⱼ)·q̇ⱼ over the own coordinates.
        let e: Vec<Vec<ExprId>> = (0..d)
            .map(|a| {
                own.iter()
                    .map(|i| point.columns.iter().find(|(j, _)| j == i).map_or(zero, |(_, c)| c[a]))
                    .collect()
            })
            .collect();
        let c: Vec<ExprId> = (0..d)
            .map(|a| {
                let parts: Vec<ExprId> =
                    (0..k).map(|j| rate_times_derivative(pool, e[a][j], coords[own[j]])).collect();
                pool.add(&parts)
            })
            .collect();
        for a in 0..d {
            bias[a].push(pool.mul2(m, c[a]));
            for j in 0..k {
                coupling[a * k + j].push(pool.mul2(m, e[a][j]));
                let pushed = pool.mul(&[m, e[a][j], c[a]]);
                force[j].push(pool.neg(pushed));
                for l in 0..k {
                    inertia[j * k + l].push(pool.mul(&[m, e[a][j], e[a][l]]));
                }
            }
        }
    }
    for term in owns {
        let column = |i: usize| term.columns().iter().find(|(j, _)| *j == i).map(|(_, c)| c);
        match term {
            Own::Moving { mass: m, position, .. } => {
                for (a, x) in position.iter().enumerate() {
                    let velocity = pool.time_derivative(*x);
                    let a0 = acceleration_without_q2(pool, velocity);
                    for j in 0..k {
                        let Some(ej) = column(own[j]) else { continue };
                        let pushed = pool.mul(&[*m, ej[a], a0]);
                        force[j].push(pool.neg(pushed));
                        for l in 0..k {
                            let Some(el) = column(own[l]) else { continue };
                            inertia[j * k + l].push(pool.mul(&[*m, ej[a], el[a]]));
                        }
                    }
                }
            }
            Own::Turning { inertia: body, omega, .. } => {
                let rate = angular_momentum_rate(pool, body, omega);
                for j in 0..k {
                    let Some(wj) = column(own[j]) else { continue };
                    for a in 0..3 {
                        let pushed = pool.mul2(wj[a], rate[a]);
                        force[j].push(pool.neg(pushed));
                    }
                    for l in 0..k {
                        let Some(wl) = column(own[l]) else { continue };
                        for a in 0..3 {
                            for b in 0..3 {
                                if !pool.is_zero(body[a][b]) {
                                    let t = pool.mul(&[wj[a], body[a][b], wl[b]]);
                                    inertia[j * k + l].push(t);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    let sum = |pool: &mut Pool, parts: Vec<Vec<ExprId>>| -> Vec<ExprId> {
        parts.iter().map(|p| pool.add(p)).collect()
    };
    ChainNode {
        parent: None,
        coordinates: Vec::new(),
        mass: pool.add(&mass),
        inertia: sum(pool, inertia),
        coupling: sum(pool, coupling),
        bias: sum(pool, bias),
        force: sum(pool, force),
        base: Vec::new(),
        base_bias: Vec::new(),
    }
}

/// The tree the points' coordinate sets make, or `None` where they make none.
struct Tree {
    /// The distinct sets (sorted indices), smallest first: a parent before its children.
    sets: Vec<Vec<usize>>,
    parent: Vec<Option<usize>>,
    /// Each set's own coordinates: those its parent lacks.
    own: Vec<Vec<usize>>,
    /// The node of each point.
    node_of: Vec<usize>,
}

impl Tree {
    fn of(points: &[Point], n: usize) -> Option<Tree> {
        if points.is_empty() {
            return None;
        }
        let deps: Vec<Vec<usize>> =
            points.iter().map(|p| p.columns.iter().map(|(i, _)| *i).collect()).collect();
        let mut sets = deps.clone();
        sets.sort_by(|a, b| a.len().cmp(&b.len()).then_with(|| a.cmp(b)));
        sets.dedup();
        let subset = |a: &[usize], b: &[usize]| a.iter().all(|x| b.binary_search(x).is_ok());
        // Each set's parent is the largest set inside it (sorted by size, the last found).
        let mut parent = vec![None; sets.len()];
        for s in 0..sets.len() {
            for t in 0..s {
                if sets[t].len() < sets[s].len() && subset(&sets[t], &sets[s]) {
                    parent[s] = Some(t);
                }
            }
            // Every set inside this one lies inside its parent: the sets below form a chain,
            // as the sets on the way from a root to a node do.
            if let Some(p) = parent[s] {
                for t in 0..s {
                    if subset(&sets[t], &sets[s]) && !subset(&sets[t], &sets[p]) {
                        return None;
                    }
                }
            }
        }
        let own: Vec<Vec<usize>> = (0..sets.len())
            .map(|s| match parent[s] {
                None => sets[s].clone(),
                Some(p) => sets[s].iter().copied().filter(|x| !sets[p].contains(x)).collect(),
            })
            .collect();
        // Each coordinate owned by one node: then a set meets another only in what the nodes
        // on both their ways from a root own (siblings meet in their parent's set), and a
        // point's set is what the nodes on its way own.
        let mut owners = vec![0; n];
        for i in own.iter().flatten() {
            owners[*i] += 1;
        }
        if !owners.iter().all(|&c| c == 1) {
            return None;
        }
        let node_of =
            deps.iter().map(|d| sets.iter().position(|s| s == d).expect("a set")).collect();
        Some(Tree { sets, parent, own, node_of })
    }
}
