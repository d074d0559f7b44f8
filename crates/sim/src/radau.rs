//! Radau IIA of order 5 (three stages), adaptive, for stiff systems and for the
//! differential–algebraic systems M·y' = F(t, y) with M = diag(I, 0) of index up to 3; after
//! Hairer & Wanner, "Solving Ordinary Differential Equations II", sections IV.8 and VII.8.
//!
//! The stage increments Z solve (I⊗M)·Z = h·(A⊗I)·F(y₀ + Z). Simplified Newton iterations
//! run in the coordinates W = (T⁻¹⊗I)·Z that diagonalise A⁻¹ = T·Λ·T⁻¹ into one real eigenvalue
//! γ and a complex pair α ± iβ, so each iteration solves one real and one complex system of
//! the problem's size, (γ/h·M − J) and ((α + iβ)/h·M − J), instead of one three times as
//! large. The Jacobian J and the factors are kept across steps while Newton converges fast
//! and the step stays put; the embedded third-order estimate is filtered through
//! (γ/h·M − J)⁻¹ so that stiff components do not inflate it; the step follows Gustafsson's
//! predictive controller; the collocation polynomial is the dense output.

use nalgebra::{Complex, DMatrix};
use numeric::elementary::pow;

use crate::stepper::{rates_overflow, rms, Dense, Stepper};
use crate::{linalg, Components, FaultKind, Problem};

/// The nodes (4 ∓ √6)/10 and 1.
#[allow(clippy::excessive_precision)]
const C: [f64; 3] = [0.155_051_025_721_682_190_18, 0.644_948_974_278_317_809_82, 1.0];
/// The real eigenvalue of A⁻¹ and the complex pair α ± iβ.
#[allow(clippy::excessive_precision)]
const GAMMA: f64 = 3.637_834_252_744_495_732_2;
#[allow(clippy::excessive_precision)]
const ALPHA: f64 = 2.681_082_873_627_752_133_9;
#[allow(clippy::excessive_precision)]
const BETA: f64 = 3.050_430_199_247_410_569_4;
/// A⁻¹·T = T·Λ with Λ = [[γ, 0, 0], [0, α, −β], [0, β, α]].
#[allow(clippy::excessive_precision)]
const T: [[f64; 3]; 3] = [
    [0.094_438_762_488_975_241_487, -0.141_255_295_020_954_208_43, -0.030_029_194_105_147_424_492],
    [0.250_213_122_965_333_311_38, 0.204_129_352_293_799_932, 0.382_942_112_757_261_937_8],
    [1.0, 1.0, 0.0],
];
#[allow(clippy::excessive_precision)]
const T_INV: [[f64; 3]; 3] = [
    [4.178_718_591_551_904_727_3, 0.327_682_820_761_062_387_08, 0.523_376_445_499_449_548_04],
    [-4.178_718_591_551_904_727_3, -0.327_682_820_761_062_387_08, 0.476_623_554_500_550_451_96],
    [-0.502_872_634_945_786_875_95, 2.571_926_949_855_605_429_2, -0.596_039_204_828_224_924_97],
];
/// The embedded method ŷ₁ = y₀ + h·(γ₀·F(y₀) + Σ b̂ᵢ·F(Yᵢ)) of order 3, γ₀ = 1/γ, differs from
/// y₁ by γ₀·(h·F(y₀) + Σ Eᵢ·Zᵢ); these are the Eᵢ.
#[allow(clippy::excessive_precision)]
const E: [f64; 3] = [-10.048_809_399_827_415_562, 1.382_142_733_160_748_895_8, -1.0 / 3.0];

/// Newton iterations allowed per step.
const MAX_NEWTON: usize = 7;
/// Once its iterate meets the tolerance, Newton contracting slower than this has reached
/// rounding noise (or converges more slowly than is worth waiting for): the iterate is kept.
const STALLED: f64 = 0.8;
/// On a differential–algebraic system Newton aims this far below its tolerance, and stops
/// short of it only where its updates stall (`STALLED`). Its tolerance is measured in the
/// norm that weighs index-2 and index-3 components by h and h²: an iterate that just meets it
/// may leave the velocities 1/h times the tolerance from the collocation solution, and that
/// error, not the method's, was what the run kept (Andrews' mechanism at tolerance 1e-8:
/// 5.3e-5 stopping at the tolerance, 3.5e-7 at a thousandth of it, where dop853 ends 3.3e-7
/// off; and the error followed the target, not the tolerance).
const DAE_NEWTON_TARGET: f64 = 1e-5;
/// Newton converging faster than this (the ratio of successive updates) keeps the Jacobian
/// for the next step.
const KEEP_JACOBIAN: f64 = 0.001;
/// A new step within this ratio of the old one keeps the old step, and so its factors.
const KEEP_STEP: (f64, f64) = (1.0, 1.2);
const SAFETY: f64 = 0.9;
/// The step may shrink by at most 5 and grow by at most 8 at once.
const MOST_SHRINK: f64 = 5.0;
const MOST_GROWTH: f64 = 8.0;

/// The last accepted step, whose collocation polynomial is the dense output and predicts the
/// next step's stages.
struct Collocation {
    t0: f64,
    h: f64,
    y0: Vec<f64>,
    z: [Vec<f64>; 3],
}

impl Collocation {
    /// u(t₀ + s·h) − y₀: the polynomial of degree 3 through 0 at s = 0 and Zᵢ at s = cᵢ.
    fn increment(&self, s: f64, i: usize) -> f64 {
        let mut acc = 0.0;
        for k in 0..3 {
            let mut weight = s / C[k];
            for j in 0..3 {
                if j != k {
                    weight *= (s - C[j]) / (C[k] - C[j]);
                }
            }
            acc += weight * self.z[k][i];
        }
        acc
    }
}

/// How one step's Newton iteration ended.
enum Newton {
    Converged {
        iterations: usize,
    },
    /// Retry with the step times `factor`.
    Failed {
        factor: f64,
    },
}

pub(crate) struct Radau {
    /// The tolerances the error estimate is held to (see [`Radau::new`]).
    rtol: f64,
    atol: f64,
    /// Newton stops when its predicted remaining error is below this, in tolerance units.
    newton_tolerance: f64,
    /// What Newton aims for while it converges fast: `newton_tolerance` for an ordinary
    /// equation, `DAE_NEWTON_TARGET` times it for a differential–algebraic one.
    newton_target: f64,
    components: Components,
    /// The step to try next; 0 until the first is chosen.
    h: f64,
    /// ∂F/∂y, row-major.
    jac: Vec<f64>,
    /// `jac` is at the current point.
    jac_fresh: bool,
    /// Recompute `jac` before the next attempt.
    jac_wanted: bool,
    /// `jac` is the problem's exact Jacobian, not differences.
    exact_jacobian: bool,
    real: DMatrix<f64>,
    real_pivots: Vec<usize>,
    complex: DMatrix<Complex<f64>>,
    complex_pivots: Vec<usize>,
    /// The step the factors are for; 0 when there are none.
    factored: f64,
    /// F at the current point.
    f0: Option<Vec<f64>>,
    z: [Vec<f64>; 3],
    w: [Vec<f64>; 3],
    f: [Vec<f64>; 3],
    /// Newton's update ΔW, and beside it scratch vectors of the problem's size.
    delta: [Vec<f64>; 3],
    scale: Vec<f64>,
    tmp: Vec<f64>,
    column: Vec<f64>,
    estimate: Vec<f64>,
    combined: Vec<f64>,
    solve: Vec<Complex<f64>>,
    last: Option<Collocation>,
    /// θ/(1 − θ) of the last Newton iteration, carried to predict the next step's first.
    eta: f64,
    /// The last contraction ratio θ of Newton's iteration.
    theta: f64,
    /// The last accepted step and its error, for the predictive controller.
    accepted: Option<(f64, f64)>,
    last_rejected: bool,
    /// The fault a failed evaluation inside a step gave, reported if the step cannot shrink.
    pending: Option<FaultKind>,
    /// The last step tried, for the report when none succeeds.
    tried: f64,
    evals: usize,
    rejected: usize,
    jacobians: usize,
    factorizations: usize,
}

impl Radau {
    /// The method for a problem of these components at a run's `tolerance`, relative and
    /// absolute. The embedded estimate is of order 3 while the solution is of order 5: a step
    /// h whose estimate is held to ε goes as ε^(1/4) and leaves a global error of order
    /// h⁵ ∝ ε^(5/4). Holding the estimate to tol^(4/5) therefore makes the final error of an
    /// ordinary differential equation proportional to the tolerance, near dop853's at the same
    /// one (RADAU5's 0.1·tol^(2/3) gives tol^(5/6): near dop853's error at 1e-10, five to a
    /// hundred times above it at 1e-12). A differential–algebraic system's velocities and
    /// accelerations are weighed by h and h² in the estimate, and its final error, once
    /// Newton's iteration is not what limits it (`DAE_NEWTON_TARGET`), falls a little faster
    /// than the estimate's bound: it is held to the tolerance itself (`lagrange-bench
    /// tolerance` measures both against dop853; a third of it, which the Newton-limited error
    /// wanted, left radau twenty to seventy times more accurate than dop853 on the car axis
    /// at 1e-10 and 1e-12, at the cost of as many more steps).
    pub fn new(components: Components, tolerance: f64) -> Self {
        let n: usize = components.by_index.iter().sum();
        let algebraic = components.differential < n;
        let rtol = if algebraic { tolerance } else { pow(tolerance, 0.8) };
        let atol = rtol;
        let newton_tolerance = (10.0 * f64::EPSILON / rtol).max(0.03f64.min(rtol.sqrt()));
        let zeros = || std::array::from_fn(|_| vec![0.0; n]);
        let newton_target =
            if algebraic { DAE_NEWTON_TARGET * newton_tolerance } else { newton_tolerance };
        Radau {
            rtol,
            atol,
            newton_tolerance,
            newton_target,
            components,
            h: 0.0,
            jac: vec![0.0; n * n],
            jac_fresh: false,
            jac_wanted: true,
            exact_jacobian: false,
            real: DMatrix::zeros(n, n),
            real_pivots: vec![0; n],
            complex: DMatrix::from_element(n, n, Complex::new(0.0, 0.0)),
            complex_pivots: vec![0; n],
            factored: 0.0,
            f0: None,
            z: zeros(),
            w: zeros(),
            f: zeros(),
            delta: zeros(),
            scale: vec![0.0; n],
            tmp: vec![0.0; n],
            column: vec![0.0; n],
            estimate: vec![0.0; n],
            combined: vec![0.0; n],
            solve: vec![Complex::new(0.0, 0.0); n],
            last: None,
            eta: 1.0,
            theta: 1.0,
            accepted: None,
            last_rejected: false,
            pending: None,
            tried: 0.0,
            evals: 0,
            rejected: 0,
            jacobians: 0,
            factorizations: 0,
        }
    }

    /// Starts afresh at a point another method reached, trying the step `h` first: the
    /// Jacobian, the factors, the predicted stages and the controller's history are dropped.
    pub fn restart(&mut self, h: f64) {
        self.h = h;
        self.f0 = None;
        self.last = None;
        self.accepted = None;
        self.last_rejected = false;
        self.jac_fresh = false;
        self.jac_wanted = true;
        self.factored = 0.0;
        self.eta = 1.0;
        self.theta = 1.0;
        self.pending = None;
    }

    /// The last accepted step, if there was one since the start or restart.
    pub fn last_step(&self) -> Option<f64> {
        self.accepted.map(|(h, _)| h)
    }

    /// ∂F/∂y as last evaluated, row-major.
    pub fn jacobian_matrix(&self) -> &[f64] {
        &self.jac
    }

    /// M's diagonal entry for component i.
    fn mass(&self, i: usize) -> f64 {
        if i < self.components.differential {
            1.0
        } else {
            0.0
        }
    }

    /// A first step from the sizes of the differential components and their rates; errors of
    /// the first steps shrink it tenfold. Rates too large to weigh are a fault.
    fn initial_step(&self, t: f64, y: &[f64], f0: &[f64], t_end: f64) -> Result<f64, FaultKind> {
        let k = self.components.differential;
        let scale: Vec<f64> = y[..k].iter().map(|v| self.atol + self.rtol * v.abs()).collect();
        let norm = |v: &[f64]| rms(v[..k].iter().zip(&scale).map(|(a, s)| a / s));
        let (d0, d1) = (norm(y), norm(f0));
        if !d1.is_finite() {
            return Err(rates_overflow(&f0[..k], &scale));
        }
        let h = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        Ok(h.min(t_end - t))
    }

    /// ∂F/∂y at (t, y): the problem's own, or forward differences of F.
    fn jacobian(&mut self, p: &mut dyn Problem, t: f64, y: &[f64]) -> Result<(), FaultKind> {
        self.jacobians += 1;
        self.jac_fresh = true;
        self.jac_wanted = false;
        self.factored = 0.0;
        self.exact_jacobian = p.jacobian(t, y, &mut self.jac)?;
        if self.exact_jacobian {
            return Ok(());
        }
        let n = y.len();
        let f0 = self.f0.as_ref().expect("F at the point is known before its Jacobian");
        self.tmp.copy_from_slice(y);
        // The step is relative to |y| or to the size the tolerances call small (atol/rtol),
        // whichever is larger: F often sums large terms that cancel, and a step relative to a
        // |y| near zero would difference its rounding noise.
        let typical = self.atol / self.rtol;
        for j in 0..n {
            let delta = f64::EPSILON.sqrt() * y[j].abs().max(typical);
            self.tmp[j] = y[j] + delta;
            p.rhs(t, &self.tmp, &mut self.column)?;
            self.evals += 1;
            for i in 0..n {
                self.jac[i * n + j] = (self.column[i] - f0[i]) / delta;
            }
            self.tmp[j] = y[j];
        }
        Ok(())
    }

    /// Factors γ/h·M − J and (α + iβ)/h·M − J; `Err` if either is singular.
    fn factor(&mut self, h: f64) -> Result<(), usize> {
        let n = self.tmp.len();
        self.factorizations += 1;
        self.factored = 0.0;
        for i in 0..n {
            let m = self.mass(i);
            for j in 0..n {
                let jac = self.jac[i * n + j];
                let diagonal = if i == j { m } else { 0.0 };
                self.real[(i, j)] = GAMMA / h * diagonal - jac;
                self.complex[(i, j)] =
                    Complex::new(ALPHA / h * diagonal - jac, BETA / h * diagonal);
            }
        }
        linalg::lu_factor(&mut self.real, &mut self.real_pivots)?;
        linalg::lu_factor(&mut self.complex, &mut self.complex_pivots)?;
        self.factored = h;
        Ok(())
    }

    /// The weights of the norms at the start y of a step of size h: atol + rtol·|y|, and for
    /// index-2 and index-3 components that over h and h².
    fn set_scale(&mut self, y: &[f64], h: f64) {
        for (i, s) in self.scale.iter_mut().enumerate() {
            let base = self.atol + self.rtol * y[i].abs();
            *s = match self.components.index(i) {
                1 => base,
                2 => base / h,
                _ => base / (h * h),
            };
        }
    }

    fn norm(&self, v: &[f64]) -> f64 {
        rms(v.iter().zip(&self.scale).map(|(x, s)| x / s))
    }

    /// Newton's starting stages: the last step's collocation polynomial continued, or zero.
    fn start_values(&mut self, h: f64) {
        let n = self.tmp.len();
        match &self.last {
            Some(last) => {
                let ratio = h / last.h;
                for i in 0..n {
                    let end = last.increment(1.0, i);
                    for k in 0..3 {
                        self.z[k][i] = last.increment(1.0 + C[k] * ratio, i) - end;
                    }
                }
            }
            None => self.z.iter_mut().for_each(|z| z.fill(0.0)),
        }
        for i in 0..n {
            for k in 0..3 {
                self.w[k][i] = (0..3).map(|j| T_INV[k][j] * self.z[j][i]).sum();
            }
        }
    }

    /// Simplified Newton iterations on the transformed stage equations
    /// (h⁻¹Λ⊗M − I⊗J)·ΔW = (T⁻¹⊗I)·F(y + Z) − h⁻¹(Λ⊗M)·W, with Hairer's convergence test.
    fn newton(&mut self, p: &mut dyn Problem, t: f64, y: &[f64], h: f64) -> Newton {
        let n = y.len();
        self.eta = pow(self.eta.max(f64::EPSILON), 0.8);
        let mut previous = 0.0;
        let mut last_estimate = f64::INFINITY;
        for k in 0..MAX_NEWTON {
            for s in 0..3 {
                for i in 0..n {
                    self.tmp[i] = y[i] + self.z[s][i];
                }
                self.evals += 1;
                if let Err(fault) = p.rhs(t + C[s] * h, &self.tmp, &mut self.f[s]) {
                    self.pending = Some(fault);
                    return Newton::Failed { factor: 0.5 };
                }
            }
            for i in 0..n {
                let m = self.mass(i) / h;
                let g: [f64; 3] = std::array::from_fn(|r| {
                    T_INV[r][0] * self.f[0][i]
                        + T_INV[r][1] * self.f[1][i]
                        + T_INV[r][2] * self.f[2][i]
                });
                let (w1, w2, w3) = (self.w[0][i], self.w[1][i], self.w[2][i]);
                self.delta[0][i] = g[0] - m * GAMMA * w1;
                self.solve[i] = Complex::new(
                    g[1] - m * (ALPHA * w2 - BETA * w3),
                    g[2] - m * (BETA * w2 + ALPHA * w3),
                );
            }
            linalg::lu_factor_solve(&self.real, &self.real_pivots, &mut self.delta[0]);
            linalg::lu_factor_solve(&self.complex, &self.complex_pivots, &mut self.solve);
            for i in 0..n {
                self.delta[1][i] = self.solve[i].re;
                self.delta[2][i] = self.solve[i].im;
            }
            let norm =
                rms(self.delta.iter().flat_map(|d| d.iter().zip(&self.scale).map(|(x, s)| x / s)));
            if !norm.is_finite() {
                return Newton::Failed { factor: 0.5 };
            }
            if k > 0 {
                let theta = norm / previous;
                self.theta = theta;
                // Updates that stop shrinking fast once the last iterate met the tolerance
                // are rounding noise, or a slow convergence the tolerance does not need:
                // that iterate is kept.
                if theta > STALLED && last_estimate <= self.newton_tolerance {
                    return Newton::Converged { iterations: k };
                }
                if theta >= 0.99 {
                    return Newton::Failed { factor: 0.5 };
                }
                self.eta = theta / (1.0 - theta);
                // Would the iterations left reach the tolerance at this rate?
                let left = (MAX_NEWTON - 1 - k) as i32;
                let predicted = pow(theta, left as f64) / (1.0 - theta) * norm;
                if predicted > self.newton_tolerance {
                    let excess = (predicted / self.newton_tolerance).clamp(1e-4, 20.0);
                    return Newton::Failed {
                        factor: 0.8 * pow(excess, -1.0 / (4.0 + left as f64)),
                    };
                }
            }
            previous = norm.max(f64::MIN_POSITIVE);
            for i in 0..n {
                for r in 0..3 {
                    self.w[r][i] += self.delta[r][i];
                }
                for r in 0..3 {
                    self.z[r][i] =
                        T[r][0] * self.w[0][i] + T[r][1] * self.w[1][i] + T[r][2] * self.w[2][i];
                }
            }
            last_estimate = self.eta * norm;
            let stalling = (k > 0 && self.theta > STALLED) || k + 1 == MAX_NEWTON;
            if last_estimate <= self.newton_target
                || (last_estimate <= self.newton_tolerance && stalling)
            {
                return Newton::Converged { iterations: k + 1 };
            }
        }
        Newton::Failed { factor: 0.5 }
    }

    /// Hairer's error estimate (γ/h·M − J)⁻¹·(F(y₀) + M·Σ Eᵢ·Zᵢ/h) in the scaled norm; after a
    /// rejection, or on the first step, a large one is tried again with F at y₀ + the error,
    /// which is sharper for stiff components.
    fn error(&mut self, p: &mut dyn Problem, t: f64, y: &[f64], h: f64) -> f64 {
        let n = y.len();
        let f0 = self.f0.as_ref().expect("F at the point is known");
        for i in 0..n {
            let sum = E[0] * self.z[0][i] + E[1] * self.z[1][i] + E[2] * self.z[2][i];
            self.combined[i] = self.mass(i) * sum / h;
            self.estimate[i] = f0[i] + self.combined[i];
        }
        linalg::lu_factor_solve(&self.real, &self.real_pivots, &mut self.estimate);
        let mut err = self.norm(&self.estimate).max(1e-10);
        if err >= 1.0 && (self.accepted.is_none() || self.last_rejected) {
            for i in 0..n {
                self.tmp[i] = y[i] + self.estimate[i];
            }
            self.evals += 1;
            if p.rhs(t, &self.tmp, &mut self.column).is_ok() {
                for i in 0..n {
                    self.estimate[i] = self.column[i] + self.combined[i];
                }
                linalg::lu_factor_solve(&self.real, &self.real_pivots, &mut self.estimate);
                err = self.norm(&self.estimate).max(1e-10);
            }
        }
        if err.is_finite() {
            err
        } else {
            1e10
        }
    }

    /// The step after one with error `err` that took `iterations` Newton iterations: the
    /// classical factor, made more cautious by slow Newton convergence, and Gustafsson's
    /// predictive factor from the last two accepted steps when the step is accepted.
    fn next_step(&self, h: f64, err: f64, iterations: usize) -> f64 {
        let most = (2 * MAX_NEWTON + 1) as f64;
        let safety = SAFETY.min(SAFETY * most / (iterations + 2 * MAX_NEWTON) as f64);
        let mut quotient = (pow(err, 0.25) / safety).clamp(1.0 / MOST_GROWTH, MOST_SHRINK);
        if err < 1.0 {
            if let Some((h_accepted, err_accepted)) = self.accepted {
                let predictive = h_accepted / h * pow(err * err / err_accepted, 0.25) / SAFETY;
                quotient = quotient.max(predictive.clamp(1.0 / MOST_GROWTH, MOST_SHRINK));
            }
        }
        h / quotient
    }

    /// The fault when the step cannot shrink further.
    fn stalled(&mut self, p: &mut dyn Problem, t: f64, y: &[f64], singular: bool) -> FaultKind {
        if let Some(fault) = self.pending.take() {
            return fault;
        }
        if singular {
            if let Some(fault) = p.explain_singular(t, y) {
                return fault;
            }
        }
        FaultKind::NewtonStalled {
            step: self.tried,
            contraction: self.theta,
            singular,
            exact_jacobian: self.exact_jacobian,
        }
    }
}

impl Dense for Radau {
    /// The Jacobian and its factors are kept (Newton's iteration needs only an approximate
    /// one, and asks for a fresh one if it fails); F and the predicted stages are not.
    fn after_jump(&mut self) {
        self.f0 = None;
        self.last = None;
        self.jac_fresh = false;
    }

    /// A new mode has other equations: a fresh Jacobian and factors for the next step.
    fn after_switch(&mut self) {
        self.after_jump();
        self.jac_wanted = true;
        self.factored = 0.0;
    }

    fn interpolate(&mut self, _p: &mut dyn Problem, t: f64, out: &mut [f64]) {
        let Some(last) = &self.last else { return };
        let s = (t - last.t0) / last.h;
        for (i, o) in out.iter_mut().enumerate() {
            *o = last.y0[i] + last.increment(s, i);
        }
    }
}

impl Stepper for Radau {
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let n = y.len();
        if self.f0.is_none() {
            let mut f0 = vec![0.0; n];
            p.rhs(t, y, &mut f0)?;
            self.evals += 1;
            if self.h == 0.0 {
                self.h = self.initial_step(t, y, &f0, t_end)?;
            }
            self.f0 = Some(f0);
        }
        let mut singular = false;
        loop {
            // Time's resolution over the run: a step below it is lost in rounding, and a
            // Newton failure at t = 0 must not halve the step down to underflow.
            let min_step = 10.0 * f64::EPSILON * t.abs().max(t_end.abs()).max(f64::MIN_POSITIVE);
            if self.h < min_step {
                return Err(self.stalled(p, t, y, singular));
            }
            let h = if t + 1.0001 * self.h >= t_end { t_end - t } else { self.h };
            self.tried = h;
            if self.jac_wanted {
                self.jacobian(p, t, y)?;
            }
            if self.factored != h && self.factor(h).is_err() {
                // Singular at this step; a smaller one moves the eigenvalues of the iteration
                // matrix away from J's.
                singular = true;
                self.h = 0.5 * h;
                self.rejected += 1;
                continue;
            }
            self.set_scale(y, h);
            self.start_values(h);
            let iterations = match self.newton(p, t, y, h) {
                Newton::Converged { iterations } => iterations,
                Newton::Failed { factor } => {
                    self.h = h * factor;
                    self.rejected += 1;
                    self.last_rejected = true;
                    if !self.jac_fresh {
                        self.jac_wanted = true;
                    }
                    continue;
                }
            };
            self.pending = None;
            let err = self.error(p, t, y, h);
            let h_new = self.next_step(h, err, iterations);
            if err >= 1.0 {
                self.rejected += 1;
                self.last_rejected = true;
                self.h = if self.accepted.is_none() { 0.1 * h } else { h_new };
                if !self.jac_fresh {
                    self.jac_wanted = true;
                }
                continue;
            }
            // Accepted, if F can be evaluated at the end (a NaN or a singular mass matrix
            // there may be the step's doing: a shorter one is tried first).
            let t_new = if h == t_end - t { t_end } else { t + h };
            for i in 0..n {
                self.tmp[i] = y[i] + self.z[2][i];
            }
            self.evals += 1;
            let projected = p.project(t_new, &mut self.tmp);
            if let Err(fault) = projected.and_then(|()| p.rhs(t_new, &self.tmp, &mut self.column)) {
                self.pending = Some(fault);
                self.h = 0.5 * h;
                self.rejected += 1;
                self.last_rejected = true;
                continue;
            }
            match &mut self.last {
                Some(last) => {
                    (last.t0, last.h) = (t, h);
                    last.y0.copy_from_slice(y);
                    for (kept, z) in last.z.iter_mut().zip(&self.z) {
                        kept.copy_from_slice(z);
                    }
                }
                None => {
                    self.last = Some(Collocation { t0: t, h, y0: y.to_vec(), z: self.z.clone() })
                }
            }
            y.copy_from_slice(&self.tmp);
            std::mem::swap(self.f0.as_mut().expect("set"), &mut self.column);
            self.accepted = Some((h, err.max(1e-2)));
            let h_new = if self.last_rejected { h_new.min(h) } else { h_new };
            self.last_rejected = false;
            self.jac_fresh = false;
            let fast = self.theta <= KEEP_JACOBIAN;
            let ratio = h_new / h;
            if !(fast && (KEEP_STEP.0..=KEEP_STEP.1).contains(&ratio)) {
                self.h = h_new;
            }
            self.jac_wanted = !fast;
            return Ok(t_new);
        }
    }

    fn evaluations(&self) -> usize {
        self.evals
    }

    fn rejected(&self) -> usize {
        self.rejected
    }

    fn jacobians(&self) -> usize {
        self.jacobians
    }

    fn factorizations(&self) -> usize {
        self.factorizations
    }
}
