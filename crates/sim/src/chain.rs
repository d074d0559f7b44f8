//! The articulated-body sweep: q̈ from the recursive form of a tree-structured scene
//! (`mechanics::ChainForm`) in O(n), without forming M.
//!
//! Each node has k own coordinates and a base point whose acceleration a is its parent's base
//! acceleration plus B·q̈ (the parent's own) plus c. Its rows read D·q̈ₒ = u − Uᵀ·a once the
//! children are folded in, and the force the node's subtree needs at its base is
//! Iᴬ·a + p. From the leaves to the roots, each node folds its children's Iᴬ and p into its
//! own parts (Ĩ += Iᴬ, U += Iᴬ·B, D += Bᵀ·Iᴬ·B, Σm·c += Iᴬ·c + p, u −= Bᵀ·(Iᴬ·c + p)), factors
//! D and passes Iᴬ = Ĩ − U·D⁻¹·Uᵀ and p = Σm·c + U·D⁻¹·u to its parent. From the roots (whose
//! base is fixed, a = 0) to the leaves, q̈ₒ = D⁻¹·u − D⁻¹·Uᵀ·a. This is Featherstone's
//! articulated-body algorithm with translations for the joints' motion: the scene's own
//! kinematics give B, E and the bias terms exactly, the sweep only adds and solves.

use crate::FaultKind;

/// One node's shape and where its parts are, in the program's outputs and in the scratch.
#[derive(Clone, Debug)]
struct Node {
    parent: Option<usize>,
    coordinates: Vec<usize>,
    /// The offset of its Σm in the outputs; D, U, Σm·c and u follow, then B and c.
    out: usize,
    /// Its offsets in the scratch arrays of d×d, d×k (and k×d), k×k, d and k values.
    square: usize,
    wide: usize,
    small: usize,
    vector: usize,
    own: usize,
}

/// A tree's sweep and its scratch; one per problem (a clone is another's).
#[derive(Clone, Debug)]
pub struct Chain {
    dimension: usize,
    nodes: Vec<Node>,
    outputs: usize,
    /// Ĩ and then Iᴬ per node (d×d).
    inertia: Vec<f64>,
    /// U per node (d×k, row-major), then D⁻¹·Uᵀ (k×d, row-major) in the same place's twin.
    coupling: Vec<f64>,
    solved_coupling: Vec<f64>,
    /// D per node (k×k), then its Cholesky factor.
    joint: Vec<f64>,
    /// Σm·c and then p per node (d), and the base acceleration (d).
    bias: Vec<f64>,
    acceleration: Vec<f64>,
    /// u per node (k), then D⁻¹·u.
    force: Vec<f64>,
    /// Whether every node has one own coordinate, the common case, swept by
    /// [`Chain::solve_single`] in fixed-size arrays.
    single: bool,
    /// That sweep's scratch: per node Ĩ then Iᴬ, U then D⁻¹·U, Σm·c then p, and the base
    /// acceleration (each padded to 3), D and u then D⁻¹·u.
    unit: Vec<Unit>,
}

/// One node of [`Chain::solve_single`]'s sweep.
#[derive(Clone, Copy, Debug, Default)]
struct Unit {
    inertia: [[f64; 3]; 3],
    coupling: [f64; 3],
    bias: [f64; 3],
    acceleration: [f64; 3],
    joint: f64,
    force: f64,
}

impl Chain {
    /// The sweep for nodes given parents first, each as (parent, its own coordinates), in a
    /// scene of `dimension`.
    pub fn new(dimension: usize, nodes: &[(Option<usize>, Vec<usize>)]) -> Chain {
        let d = dimension;
        let (mut out, mut square, mut wide, mut small, mut vector, mut own) = (0, 0, 0, 0, 0, 0);
        let mut shaped = Vec::with_capacity(nodes.len());
        for (x, (parent, coordinates)) in nodes.iter().enumerate() {
            assert!(parent.is_none_or(|p| p < x), "a parent comes before its children");
            let k = coordinates.len();
            shaped.push(Node {
                parent: *parent,
                coordinates: coordinates.clone(),
                out,
                square,
                wide,
                small,
                vector,
                own,
            });
            out += 1 + k * k + d * k + d + k;
            if let Some(p) = parent {
                out += d * nodes[*p].1.len() + d;
            }
            square += d * d;
            wide += d * k;
            small += k * k;
            vector += d;
            own += k;
        }
        Chain {
            dimension,
            nodes: shaped,
            outputs: out,
            inertia: vec![0.0; square],
            coupling: vec![0.0; wide],
            solved_coupling: vec![0.0; wide],
            joint: vec![0.0; small],
            bias: vec![0.0; vector],
            acceleration: vec![0.0; vector],
            force: vec![0.0; own],
            single: nodes.iter().all(|(_, c)| c.len() == 1) && (2..=3).contains(&dimension),
            unit: vec![Unit::default(); nodes.len()],
        }
    }

    /// How many values the recursive form's program gives.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// q̈ into `accelerations` (indexed by coordinate) from the program's outputs `out`.
    pub fn solve(&mut self, out: &[f64], accelerations: &mut [f64]) -> Result<(), FaultKind> {
        debug_assert_eq!(out.len(), self.outputs);
        match (self.single, self.dimension) {
            (true, 2) => return self.solve_single::<2>(out, accelerations),
            (true, 3) => return self.solve_single::<3>(out, accelerations),
            _ => {}
        }
        let d = self.dimension;
        for node in &self.nodes {
            let k = node.coordinates.len();
            let mut at = node.out;
            let mass = out[at];
            at += 1;
            let inertia = &mut self.inertia[node.square..node.square + d * d];
            inertia.fill(0.0);
            for a in 0..d {
                inertia[a * d + a] = mass;
            }
            self.joint[node.small..node.small + k * k].copy_from_slice(&out[at..at + k * k]);
            at += k * k;
            self.coupling[node.wide..node.wide + d * k].copy_from_slice(&out[at..at + d * k]);
            at += d * k;
            self.bias[node.vector..node.vector + d].copy_from_slice(&out[at..at + d]);
            at += d;
            self.force[node.own..node.own + k].copy_from_slice(&out[at..at + k]);
        }
        for x in (0..self.nodes.len()).rev() {
            self.fold(x, out)?;
        }
        for x in 0..self.nodes.len() {
            let node = &self.nodes[x];
            let k = node.coordinates.len();
            let mut a = [0.0; 3];
            if let Some(p) = node.parent {
                let parent = &self.nodes[p];
                let kp = parent.coordinates.len();
                let base = node.out + 1 + k * k + d * k + d + k;
                let (columns, bias) = (&out[base..base + d * kp], &out[base + d * kp..]);
                for (i, slot) in a.iter_mut().enumerate().take(d) {
                    let mut v = self.acceleration[parent.vector + i] + bias[i];
                    for (j, &q) in parent.coordinates.iter().enumerate() {
                        v += columns[i * kp + j] * accelerations[q];
                    }
                    *slot = v;
                }
            }
            self.acceleration[node.vector..node.vector + d].copy_from_slice(&a[..d]);
            let y = &self.solved_coupling[node.wide..node.wide + d * k];
            for (j, &q) in node.coordinates.iter().enumerate() {
                let mut v = self.force[node.own + j];
                for i in 0..d {
                    v -= y[j * d + i] * a[i];
                }
                accelerations[q] = v;
            }
        }
        Ok(())
    }

    /// [`Chain::solve`] where every node has one own coordinate, in a scene of dimension `D`:
    /// D is a number, and each node's parts fit in fixed arrays the compiler unrolls.
    fn solve_single<const D: usize>(
        &mut self,
        out: &[f64],
        accelerations: &mut [f64],
    ) -> Result<(), FaultKind> {
        // Per node: Σm, D, U (D), Σm·c (D), u, then B (D) and c (D) unless a root.
        for (node, unit) in self.nodes.iter().zip(self.unit.iter_mut()) {
            let o = &out[node.out..node.out + 3 + 2 * D];
            unit.inertia = [[0.0; 3]; 3];
            for i in 0..D {
                unit.inertia[i][i] = o[0];
                unit.coupling[i] = o[2 + i];
                unit.bias[i] = o[2 + D + i];
            }
            unit.joint = o[1];
            unit.force = o[2 + 2 * D];
        }
        for x in (0..self.nodes.len()).rev() {
            let node = &self.nodes[x];
            let here = self.unit[x];
            // What rounding alone could leave of a vanishing D is a few ulps of its parts.
            let scale = out[node.out + 1].abs() + (here.joint - out[node.out + 1]).abs();
            if here.joint.is_nan() || here.joint <= 1e-13 * scale {
                return Err(FaultKind::SingularMass {
                    coordinates: vec![node.coordinates[0]],
                    condition: f64::INFINITY,
                });
            }
            let inverse = 1.0 / here.joint;
            let mut solved = [0.0; 3];
            for i in 0..D {
                solved[i] = here.coupling[i] * inverse;
            }
            let free = here.force * inverse;
            let mut articulated = here.inertia;
            let mut bias = here.bias;
            for i in 0..D {
                for l in 0..D {
                    articulated[i][l] -= here.coupling[i] * solved[l];
                }
                bias[i] += here.coupling[i] * free;
            }
            let unit = &mut self.unit[x];
            unit.coupling = solved;
            unit.force = free;
            let Some(p) = node.parent else { continue };
            let b = &out[node.out + 3 + 2 * D..node.out + 3 + 4 * D];
            let (columns, base_bias) = b.split_at(D);
            let parent = &mut self.unit[p];
            let mut pushed = [0.0; 3];
            let mut through = [0.0; 3];
            for i in 0..D {
                let (mut z, mut ib) = (bias[i], 0.0);
                for l in 0..D {
                    z += articulated[i][l] * base_bias[l];
                    ib += articulated[i][l] * columns[l];
                    parent.inertia[i][l] += articulated[i][l];
                }
                pushed[i] = z;
                through[i] = ib;
            }
            let (mut joint, mut force) = (0.0, 0.0);
            for i in 0..D {
                parent.bias[i] += pushed[i];
                parent.coupling[i] += through[i];
                joint += columns[i] * through[i];
                force += columns[i] * pushed[i];
            }
            parent.joint += joint;
            parent.force -= force;
        }
        for x in 0..self.nodes.len() {
            let node = &self.nodes[x];
            let mut a = [0.0; 3];
            if let Some(p) = node.parent {
                let b = &out[node.out + 3 + 2 * D..node.out + 3 + 4 * D];
                let (columns, base_bias) = b.split_at(D);
                let q = accelerations[self.nodes[p].coordinates[0]];
                let above = self.unit[p].acceleration;
                for i in 0..D {
                    a[i] = above[i] + columns[i] * q + base_bias[i];
                }
            }
            let unit = &mut self.unit[x];
            unit.acceleration = a;
            let mut v = unit.force;
            for i in 0..D {
                v -= unit.coupling[i] * a[i];
            }
            accelerations[node.coordinates[0]] = v;
        }
        Ok(())
    }

    /// Factors node x's D, turns its parts into Iᴬ and p, and folds them into its parent's.
    fn fold(&mut self, x: usize, out: &[f64]) -> Result<(), FaultKind> {
        let d = self.dimension;
        let node = &self.nodes[x];
        let k = node.coordinates.len();
        let joint = &mut self.joint[node.small..node.small + k * k];
        cholesky(joint, k).map_err(|column| FaultKind::SingularMass {
            coordinates: vec![node.coordinates[column]],
            condition: f64::INFINITY,
        })?;
        // Y = D⁻¹·Uᵀ (k×d) and D⁻¹·u.
        let u = &self.coupling[node.wide..node.wide + d * k];
        let y = &mut self.solved_coupling[node.wide..node.wide + d * k];
        let mut column = [0.0; 8];
        let mut column_vec;
        let scratch: &mut [f64] = if k <= 8 {
            &mut column[..k]
        } else {
            column_vec = vec![0.0; k];
            &mut column_vec
        };
        for i in 0..d {
            for j in 0..k {
                scratch[j] = u[i * k + j];
            }
            cholesky_solve(joint, k, scratch);
            for j in 0..k {
                y[j * d + i] = scratch[j];
            }
        }
        cholesky_solve(joint, k, &mut self.force[node.own..node.own + k]);
        // Iᴬ = Ĩ − U·Y and p = Σm·c + U·D⁻¹·u, in place.
        let solved_force = &self.force[node.own..node.own + k];
        let inertia = &mut self.inertia[node.square..node.square + d * d];
        let bias = &mut self.bias[node.vector..node.vector + d];
        for i in 0..d {
            for l in 0..d {
                let mut v = inertia[i * d + l];
                for j in 0..k {
                    v -= u[i * k + j] * y[j * d + l];
                }
                inertia[i * d + l] = v;
            }
            let mut v = bias[i];
            for j in 0..k {
                v += u[i * k + j] * solved_force[j];
            }
            bias[i] = v;
        }
        let Some(p) = node.parent else { return Ok(()) };
        let parent = &self.nodes[p];
        let kp = parent.coordinates.len();
        let base = node.out + 1 + k * k + d * k + d + k;
        let (columns, base_bias) =
            (&out[base..base + d * kp], &out[base + d * kp..base + d * kp + d]);
        let mut articulated = [0.0; 9];
        articulated[..d * d].copy_from_slice(&self.inertia[node.square..node.square + d * d]);
        let mut pushed = [0.0; 3];
        // z = Iᴬ·c + p: the force the subtree needs beyond Iᴬ times the parent's terms.
        for i in 0..d {
            let mut v = self.bias[node.vector + i];
            for l in 0..d {
                v += articulated[i * d + l] * base_bias[l];
            }
            pushed[i] = v;
        }
        for i in 0..d {
            for l in 0..d {
                self.inertia[parent.square + i * d + l] += articulated[i * d + l];
            }
            self.bias[parent.vector + i] += pushed[i];
        }
        for j in 0..kp {
            // Iᴬ·B's column j, then its share of U and D.
            let mut ib = [0.0; 3];
            for i in 0..d {
                let mut v = 0.0;
                for l in 0..d {
                    v += articulated[i * d + l] * columns[l * kp + j];
                }
                ib[i] = v;
                self.coupling[parent.wide + i * kp + j] += v;
            }
            for m in 0..kp {
                let mut v = 0.0;
                for i in 0..d {
                    v += columns[i * kp + m] * ib[i];
                }
                self.joint[parent.small + m * kp + j] += v;
            }
            let mut v = 0.0;
            for i in 0..d {
                v += columns[i * kp + j] * pushed[i];
            }
            self.force[parent.own + j] -= v;
        }
        Ok(())
    }
}

/// The lower Cholesky factor of a symmetric k×k matrix, in place (row-major, lower triangle
/// used); the column whose pivot is not positive as the error.
fn cholesky(a: &mut [f64], k: usize) -> Result<(), usize> {
    for j in 0..k {
        let diagonal = a[j * k + j];
        let mut pivot = diagonal;
        for m in 0..j {
            pivot -= a[j * k + m] * a[j * k + m];
        }
        // What rounding alone could leave of a pivot that vanishes is a few ulps of the
        // diagonal it started from.
        if pivot.is_nan() || pivot <= 1e-13 * diagonal.abs() {
            return Err(j);
        }
        let root = pivot.sqrt();
        a[j * k + j] = root;
        for i in j + 1..k {
            let mut v = a[i * k + j];
            for m in 0..j {
                v -= a[i * k + m] * a[j * k + m];
            }
            a[i * k + j] = v / root;
        }
    }
    Ok(())
}

/// Solves L·Lᵀ·x = b in place with the factor of [`cholesky`].
fn cholesky_solve(l: &[f64], k: usize, b: &mut [f64]) {
    for i in 0..k {
        let mut v = b[i];
        for m in 0..i {
            v -= l[i * k + m] * b[m];
        }
        b[i] = v / l[i * k + i];
    }
    for i in (0..k).rev() {
        let mut v = b[i];
        for m in i + 1..k {
            v -= l[m * k + i] * b[m];
        }
        b[i] = v / l[i * k + i];
    }
}
