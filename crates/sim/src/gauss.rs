//! Gauss–Legendre collocation: implicit, symmetric and symplectic Runge–Kutta methods. One
//! stage is the implicit midpoint rule (order 2), two stages give order 4. Applied to a
//! Hamiltonian system in canonical variables they conserve a modified energy, so the energy
//! error stays bounded over long runs instead of drifting.
//!
//! The stage equations Z = h (A ⊗ I) F(y + Z) are solved by simplified Newton iterations with
//! the Jacobian of F at the start of each step (the problem's exact one where it has it, forward
//! differences otherwise), until the update stops shrinking at round-off level: symplecticity
//! holds only for the converged solution.

use nalgebra::DMatrix;

use crate::stepper::{fixed_step, Dense, Hermite, Stepper};
use crate::{linalg, FaultKind, Problem};

const SQRT3_6: f64 = 0.288_675_134_594_812_9; // √3/6

pub(crate) struct Gauss {
    stages: usize,
    a: [[f64; 2]; 2],
    b: [f64; 2],
    c: [f64; 2],
    step: f64,
    evals: usize,
    pub newton_iterations: usize,
    last: Hermite,
    jac: DMatrix<f64>,
    /// The problem's exact Jacobian, row-major, before it is copied into `jac`.
    exact: Vec<f64>,
    iteration: DMatrix<f64>,
    pivots: Vec<usize>,
    /// The last Jacobian was the problem's exact one, not differences.
    exact_jacobian: bool,
}

impl Gauss {
    pub fn new(stages: usize, dim: usize, step: f64) -> Self {
        let (a, b, c) = if stages == 1 {
            ([[0.5, 0.0], [0.0, 0.0]], [1.0, 0.0], [0.5, 0.0])
        } else {
            (
                [[0.25, 0.25 - SQRT3_6], [0.25 + SQRT3_6, 0.25]],
                [0.5, 0.5],
                [0.5 - SQRT3_6, 0.5 + SQRT3_6],
            )
        };
        Gauss {
            stages,
            a,
            b,
            c,
            step,
            evals: 0,
            newton_iterations: 0,
            last: Hermite::default(),
            jac: DMatrix::zeros(dim, dim),
            exact: vec![0.0; dim * dim],
            iteration: DMatrix::zeros(stages * dim, stages * dim),
            pivots: vec![0; stages * dim],
            exact_jacobian: false,
        }
    }

    fn jacobian(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &[f64],
        f0: &[f64],
    ) -> Result<(), FaultKind> {
        let d = y.len();
        // A partial can be undefined where F is not (a square root at zero): differences then.
        self.exact_jacobian = p.jacobian(t, y, &mut self.exact).unwrap_or(false);
        if self.exact_jacobian {
            for i in 0..d {
                for j in 0..d {
                    self.jac[(i, j)] = self.exact[i * d + j];
                }
            }
            return Ok(());
        }
        let mut yp = y.to_vec();
        let mut fp = vec![0.0; d];
        for j in 0..d {
            let dy = f64::EPSILON.sqrt() * y[j].abs().max(1.0);
            yp[j] = y[j] + dy;
            p.rhs(t, &yp, &mut fp)?;
            self.evals += 1;
            for i in 0..d {
                self.jac[(i, j)] = (fp[i] - f0[i]) / dy;
            }
            yp[j] = y[j];
        }
        Ok(())
    }
}

impl Dense for Gauss {
    fn interpolate(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64]) {
        self.last.eval(p, t, out, &mut self.evals);
    }
}

impl Stepper for Gauss {
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let h = fixed_step(self.step, t, t_end);
        let (d, s) = (y.len(), self.stages);
        let mut f0 = vec![0.0; d];
        p.rhs(t, y, &mut f0)?;
        self.evals += 1;
        self.jacobian(p, t, y, &f0)?;
        // I − h (A ⊗ J), factored once per step.
        for bi in 0..s {
            for bj in 0..s {
                for i in 0..d {
                    for j in 0..d {
                        let id = if bi == bj && i == j { 1.0 } else { 0.0 };
                        self.iteration[(bi * d + i, bj * d + j)] =
                            id - h * self.a[bi][bj] * self.jac[(i, j)];
                    }
                }
            }
        }
        linalg::lu_in_place(&mut self.iteration, &mut self.pivots)?;

        let mut z: Vec<f64> = (0..s * d).map(|k| self.c[k / d] * h * f0[k % d]).collect();
        let mut f = vec![vec![0.0; d]; s];
        let mut stage = vec![0.0; d];
        let mut residual = vec![0.0; s * d];
        let mut previous = f64::INFINITY;
        let scale = y.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        let mut converged = false;
        let mut contraction = f64::NAN;
        for _ in 0..50 {
            for (i, fi) in f.iter_mut().enumerate() {
                for k in 0..d {
                    stage[k] = y[k] + z[i * d + k];
                }
                p.rhs(t + self.c[i] * h, &stage, fi)?;
                self.evals += 1;
            }
            for i in 0..s {
                for k in 0..d {
                    let mut acc = 0.0;
                    for (j, fj) in f.iter().enumerate() {
                        acc += self.a[i][j] * fj[k];
                    }
                    residual[i * d + k] = h * acc - z[i * d + k];
                }
            }
            linalg::lu_solve(&self.iteration, &self.pivots, &mut residual);
            let norm = residual.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if previous.is_finite() {
                contraction = norm / previous;
            }
            for (zk, dk) in z.iter_mut().zip(&residual) {
                *zk += dk;
            }
            self.newton_iterations += 1;
            // Stop at round-off: when the update is tiny, or stops shrinking near it.
            if norm <= 1e-16 * scale || (norm >= previous && norm <= 1e-10 * scale) {
                converged = true;
                break;
            }
            previous = norm;
        }
        if !converged {
            return Err(FaultKind::NewtonFailed {
                step: h,
                contraction,
                exact_jacobian: self.exact_jacobian,
            });
        }
        for (i, fi) in f.iter_mut().enumerate() {
            for k in 0..d {
                stage[k] = y[k] + z[i * d + k];
            }
            p.rhs(t + self.c[i] * h, &stage, fi)?;
            self.evals += 1;
        }
        self.last.begin(t, y, &f0);
        for k in 0..d {
            let mut acc = 0.0;
            for (i, fi) in f.iter().enumerate() {
                acc += self.b[i] * fi[k];
            }
            y[k] += h * acc;
        }
        Ok(self.last.end(t, h, t_end, y))
    }

    fn evaluations(&self) -> usize {
        self.evals
    }
}
