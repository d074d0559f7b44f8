//! Explicit Runge–Kutta methods: fixed-step RK4, and the adaptive pairs (Bogacki–Shampine 3(2),
//! Dormand–Prince 5(4) and 8(5,3), DOP853) with error control and dense output, whose
//! coefficients and step-control facts are in `coefficients`. The Dormand–Prince coefficients
//! are those of Hairer, Nørsett and Wanner, "Solving Ordinary Differential Equations I", and
//! Shampine (1986) for the quartic dense output of the 5(4) pair.

use nalgebra::Complex;
use numeric::elementary::pow;

use crate::stepper::{fixed_step, rates_overflow, rms, Dense, Hermite, Stepper};
use crate::{FaultKind, Problem};

mod coefficients;
mod lanes;
mod tableau;
pub(crate) use coefficients::Pair;
use coefficients::{DOP853_A, DOP853_BHH, DOP853_C, DOP853_D, DOP853_E5};
pub(crate) use lanes::{Lanes, Stages};
pub use tableau::{dop853_tableau, Dop853Tableau};

/// The classic fourth-order Runge–Kutta method with a fixed step.
pub(crate) struct Rk4 {
    step: f64,
    k: [Vec<f64>; 4],
    tmp: Vec<f64>,
    evals: usize,
    last: Hermite,
}

impl Rk4 {
    pub fn new(dim: usize, step: f64) -> Self {
        Rk4 {
            step,
            k: std::array::from_fn(|_| vec![0.0; dim]),
            tmp: vec![0.0; dim],
            evals: 0,
            last: Hermite::default(),
        }
    }
}

impl Dense for Rk4 {
    fn interpolate(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64]) {
        self.last.eval(p, t, out, &mut self.evals);
    }
}

impl Stepper for Rk4 {
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let h = fixed_step(self.step, t, t_end);
        let d = y.len();
        let [k1, k2, k3, k4] = &mut self.k;
        p.rhs(t, y, k1)?;
        for i in 0..d {
            self.tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        p.rhs(t + 0.5 * h, &self.tmp, k2)?;
        for i in 0..d {
            self.tmp[i] = y[i] + 0.5 * h * k2[i];
        }
        p.rhs(t + 0.5 * h, &self.tmp, k3)?;
        for i in 0..d {
            self.tmp[i] = y[i] + h * k3[i];
        }
        p.rhs(t + h, &self.tmp, k4)?;
        self.evals += 4;
        self.last.begin(t, y, k1);
        for i in 0..d {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        Ok(self.last.end(t, h, t_end, y))
    }

    fn evaluations(&self) -> usize {
        self.evals
    }
}

/// An adaptive explicit pair with local extrapolation (the higher order propagates).
pub(crate) struct Adaptive {
    pair: Pair,
    rtol: f64,
    atol: f64,
    /// The step to try next; 0 until the first step is chosen.
    h: f64,
    /// Stages: 7 for the 5(4) pair, 16 (12 + the final derivative + 3 dense-output stages)
    /// for DOP853.
    k: Vec<Vec<f64>>,
    tmp: Vec<f64>,
    /// The stages' sums of a trial, and DOP853's second error estimate's.
    sum: Vec<f64>,
    sum3: Vec<f64>,
    y_new: Vec<f64>,
    y_old: Vec<f64>,
    t_old: f64,
    h_last: f64,
    /// F(t, y) at the current point (first-same-as-last).
    f: Option<Vec<f64>>,
    evals: usize,
    /// Dense-output coefficients of the last step, computed on first use (`dense_ready`),
    /// in buffers kept from step to step.
    dense: Vec<Vec<f64>>,
    dense_ready: bool,
    pub rejected: usize,
    /// Accepted steps at the edge of the method's stability region. Hairer's test: with the
    /// last stage and the end point both at t + h, ρ = h·‖F(y₁) − F(ŷ)‖ / ‖y₁ − ŷ‖ estimates
    /// h·|λ| of the dominant eigenvalue; past the boundary of the stability region along the
    /// negative axis (3.25 for DOPRI5, 6.1 for DOP853) the step is limited by stability, not
    /// accuracy: the system is stiff for this method.
    pub stiff: usize,
}

const SAFETY: f64 = 0.9;
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 10.0;

impl Adaptive {
    /// The pair for a run at `tolerance`, relative and absolute, held at its
    /// [`Pair::error_target`].
    pub fn for_tolerance(pair: Pair, dim: usize, tolerance: f64) -> Self {
        let rtol = pair.error_target(tolerance);
        let atol = rtol;
        let stages = pair.kept_stages();
        Adaptive {
            pair,
            rtol,
            atol,
            h: 0.0,
            k: vec![vec![0.0; dim]; stages],
            tmp: vec![0.0; dim],
            sum: vec![0.0; dim],
            sum3: vec![0.0; dim],
            y_new: vec![0.0; dim],
            y_old: vec![0.0; dim],
            t_old: 0.0,
            h_last: 0.0,
            f: None,
            evals: 0,
            dense: Vec::new(),
            dense_ready: false,
            rejected: 0,
            stiff: 0,
        }
    }

    /// Starts afresh at a point another method reached, trying the step `h` first: the
    /// derivative there and the dense output are computed anew.
    pub fn restart(&mut self, h: f64) {
        self.f = None;
        self.dense_ready = false;
        self.h = h;
    }

    /// The step the last accepted one was.
    pub fn last_step(&self) -> f64 {
        self.h_last
    }

    fn order(&self) -> f64 {
        self.pair.estimate_order()
    }

    /// Hairer's starting step: from the sizes of y, F and a trial Euler step.
    fn initial_step(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &[f64],
        f0: &[f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        let scale: Vec<f64> = y.iter().map(|v| self.atol + v.abs() * self.rtol).collect();
        let norm = |v: &[f64]| rms(v.iter().zip(&scale).map(|(a, s)| a / s));
        let (d0, d1) = (norm(y), norm(f0));
        if !d1.is_finite() {
            return Err(rates_overflow(f0, &scale));
        }
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        let h0 = h0.min((t_end - t).abs());
        for i in 0..y.len() {
            self.tmp[i] = y[i] + h0 * f0[i];
        }
        let mut f1 = vec![0.0; y.len()];
        p.rhs(t + h0, &self.tmp, &mut f1)?;
        self.evals += 1;
        let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
        let d2 = norm(&diff) / h0;
        let h1 = if d1 <= 1e-15 && d2 <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            pow(0.01 / d1.max(d2), 1.0 / (self.order() + 1.0))
        };
        Ok((100.0 * h0).min(h1))
    }

    /// One trial step of size h from (t, y): fills the stages and `y_new`, returns the error
    /// norm (accept when ≤ 1).
    fn trial(&mut self, p: &mut dyn Problem, t: f64, y: &[f64], h: f64) -> Result<f64, FaultKind> {
        let d = y.len();
        let stages = self.pair.stage_count();
        for s in 1..stages {
            stage_sum(self.pair.a(s), &self.k, &mut self.sum);
            for ((out, y), acc) in self.tmp.iter_mut().zip(y).zip(&self.sum) {
                *out = y + h * acc;
            }
            let c = self.pair.c(s);
            p.rhs(t + c * h, &self.tmp, &mut self.k[s])?;
            self.evals += 1;
        }
        stage_sum(self.pair.b(), &self.k, &mut self.sum);
        for ((out, y), acc) in self.y_new.iter_mut().zip(y).zip(&self.sum) {
            *out = y + h * acc;
        }
        p.rhs(t + h, &self.y_new, &mut self.k[stages])?;
        self.evals += 1;
        let k = &self.k;
        // The components the step control weighs (all, but for a problem that carries some).
        let d = p.controlled().min(d);
        let scale = |i: usize| self.atol + y[i].abs().max(self.y_new[i].abs()) * self.rtol;
        Ok(match self.pair.error_weights() {
            Some(weights) => {
                let e = (0..d).map(|i| {
                    let mut acc = 0.0;
                    for (j, ej) in weights.iter().enumerate() {
                        acc += ej * k[j][i];
                    }
                    h * acc / scale(i)
                });
                rms(e)
            }
            None => {
                let (mut e5, mut e3) = (0.0, 0.0);
                stage_sum(&DOP853_E5, &k[..12], &mut self.sum);
                stage_sum(&DOP853_E3, &k[..12], &mut self.sum3);
                for i in 0..d {
                    let (a5, a3) = (self.sum[i], self.sum3[i]);
                    // Squares as products: the bits `powi(2)` gave, without its unspecified
                    // precision.
                    let (r5, r3) = (a5 / scale(i), a3 / scale(i));
                    e5 += r5 * r5;
                    e3 += r3 * r3;
                }
                let denom = e5 + 0.01 * e3;
                if denom == 0.0 {
                    0.0
                } else {
                    h.abs() * e5 / (denom * d as f64).sqrt()
                }
            }
        })
    }

    /// Hairer's stiffness test on the step just tried (see [`Adaptive::stiff`]); `tmp` still
    /// holds the argument of the last stage.
    fn at_stability_limit(&self, h: f64) -> bool {
        let last = self.pair.stage_count();
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..self.tmp.len() {
            let (dk, dy) = (self.k[last][i] - self.k[last - 1][i], self.y_new[i] - self.tmp[i]);
            num += dk * dk;
            den += dy * dy;
        }
        den > 0.0 && h.abs() * (num / den).sqrt() > self.pair.stiffness_bound()
    }

    /// Makes ready for a step from (t, y): the derivative there (first same as last after a
    /// step) and, before the first step, the starting step.
    pub(crate) fn prepare(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &[f64],
        t_end: f64,
    ) -> Result<(), FaultKind> {
        if self.f.is_none() {
            let mut f0 = vec![0.0; y.len()];
            p.rhs(t, y, &mut f0)?;
            self.evals += 1;
            self.f = Some(f0);
        }
        if self.h == 0.0 {
            let f0 = self.f.clone().expect("just set");
            self.h = self.initial_step(p, t, y, &f0, t_end)?;
        }
        Ok(())
    }

    /// The evaluations of the right-hand side counted so far.
    pub(crate) fn evaluations_counted(&self) -> usize {
        self.evals
    }

    /// The derivative at the point a step starts from (after [`Adaptive::prepare`]).
    pub(crate) fn start_derivative(&self) -> &[f64] {
        self.f.as_deref().expect("prepared")
    }

    /// The next trial from `t`: its step and where it ends, not past `t_end`; or the fault
    /// when the step has shrunk below what floating point resolves at `t`.
    pub(crate) fn trial_step(&self, t: f64, t_end: f64) -> Result<(f64, f64), FaultKind> {
        if self.h < min_step(t) {
            return Err(FaultKind::StepTooSmall { step: self.h });
        }
        let (mut h, mut t_new) = (self.h, t + self.h);
        if t_new >= t_end {
            t_new = t_end;
            h = t_end - t;
        }
        Ok((h, t_new))
    }

    /// The step control's verdict on a trial of step `h` from `t` (its error norm, or the
    /// fault an evaluation inside it met; `stiff`: whether it was at the stability limit):
    /// accepted (true) or to be tried again with the smaller step it sets (false). A failed
    /// evaluation inside the step (NaN, singular M) may be the step's fault: the step shrinks,
    /// and the fault is reported only when it cannot shrink further. `rejected_here` says
    /// whether this step was rejected before, which caps its growth once accepted.
    pub(crate) fn judge(
        &mut self,
        trial: Result<f64, FaultKind>,
        h: f64,
        t: f64,
        stiff: bool,
        rejected_here: &mut bool,
    ) -> Result<bool, FaultKind> {
        let (err, exponent) = (trial_error(&trial), self.error_exponent());
        self.judge_powered(trial, h, t, stiff, rejected_here, || trial_power(err, exponent))
    }

    /// The exponent of the error norm in the step-size factor, −1/(order + 1).
    pub(crate) fn error_exponent(&self) -> f64 {
        -1.0 / (self.order() + 1.0)
    }

    /// [`Adaptive::judge`] with the error norm raised to [`Adaptive::error_exponent`] given by
    /// `power`, asked at most once: a caller that raised many norms at once hands each its own.
    pub(crate) fn judge_powered(
        &mut self,
        trial: Result<f64, FaultKind>,
        h: f64,
        t: f64,
        stiff: bool,
        rejected_here: &mut bool,
        power: impl FnOnce() -> f64,
    ) -> Result<bool, FaultKind> {
        let err = match trial {
            Ok(err) => err,
            Err(FaultKind::NonFinite { .. })
            | Err(FaultKind::SingularMass { .. })
            | Err(FaultKind::SingularConstraints { .. })
                if h > 1e3 * min_step(t) =>
            {
                self.h = h * MIN_FACTOR;
                self.rejected += 1;
                *rejected_here = true;
                return Ok(false);
            }
            Err(fault) => return Err(fault),
        };
        if err <= 1.0 {
            if stiff {
                self.stiff += 1;
            }
            let mut factor = if err == 0.0 { MAX_FACTOR } else { MAX_FACTOR.min(SAFETY * power()) };
            if *rejected_here {
                factor = factor.min(1.0);
            }
            self.h = h * factor;
            return Ok(true);
        }
        self.h = h * MIN_FACTOR.max(SAFETY * power());
        self.rejected += 1;
        *rejected_here = true;
        Ok(false)
    }

    /// Takes the accepted step of size `h` from (t, `y`), whose end is in `y_new` and whose
    /// last stage holds the derivative there: the step's start is kept for the dense output.
    pub(crate) fn accepted(&mut self, t: f64, h: f64, y: &[f64]) {
        self.y_old.copy_from_slice(y);
        self.t_old = t;
        self.h_last = h;
        let last = self.pair.stage_count();
        self.f.as_mut().expect("prepared").copy_from_slice(&self.k[last]);
        self.dense_ready = false;
    }

    /// Fills `dense` with the last step's dense-output coefficients.
    fn dense_coefficients(&mut self, p: &mut dyn Problem) {
        let d = self.y_old.len();
        let h = self.h_last;
        let mut f = std::mem::take(&mut self.dense);
        match self.pair.dense_weights() {
            Some(weights) => {
                f.resize_with(weights[0].len(), Vec::new);
                for (power, row) in f.iter_mut().enumerate() {
                    row.clear();
                    row.resize(d, 0.0);
                    for (j, w) in weights.iter().enumerate() {
                        for (v, k) in row.iter_mut().zip(&self.k[j]) {
                            *v += w[power] * k;
                        }
                    }
                    for v in row.iter_mut() {
                        *v *= h;
                    }
                }
            }
            None => {
                for s in 13..16 {
                    stage_sum(DOP853_A[s], &self.k, &mut self.sum);
                    for ((out, y), acc) in self.tmp.iter_mut().zip(&self.y_old).zip(&self.sum) {
                        *out = y + h * acc;
                    }
                    // A fault here already showed up when the step was taken.
                    let _ = p.rhs(self.t_old + DOP853_C[s] * h, &self.tmp, &mut self.k[s]);
                    self.evals += 1;
                }
                f.resize_with(7, Vec::new);
                for row in f.iter_mut() {
                    row.clear();
                    row.resize(d, 0.0);
                }
                let y1 = &self.y_new;
                for i in 0..d {
                    let dy = y1[i] - self.y_old[i];
                    f[0][i] = dy;
                    f[1][i] = h * self.k[0][i] - dy;
                    f[2][i] = 2.0 * dy - h * (self.k[12][i] + self.k[0][i]);
                }
                for r in 0..4 {
                    stage_sum(&DOP853_D[r], &self.k, &mut self.sum);
                    for (out, acc) in f[3 + r].iter_mut().zip(&self.sum) {
                        *out = h * acc;
                    }
                }
            }
        }
        self.dense = f;
        self.dense_ready = true;
    }
}

/// DOP853's weights of its third-order error estimate, b − b̂, as the sums had them.
const DOP853_E3: [f64; 12] = {
    let mut weights = [0.0; 12];
    let mut j = 0;
    while j < 12 {
        weights[j] = DOP853_A[12][j] - DOP853_BHH[j];
        j += 1;
    }
    weights
};

/// Σⱼ cⱼ·kⱼ into `sum`, each entry summed over the stages in their order, stage by stage so
/// that the entries' sums run side by side. A zero coefficient's term is left out: ±0 added
/// to a sum that starts at +0 and is never −0 (x + (−x) is +0) changes no bit, for the finite
/// stages an accepted step has (a stage that is not finite fails its evaluation).
fn stage_sum(coefficients: &[f64], k: &[Vec<f64>], sum: &mut [f64]) {
    sum.fill(0.0);
    for (c, kj) in coefficients.iter().zip(k) {
        if *c == 0.0 {
            continue;
        }
        for (acc, v) in sum.iter_mut().zip(kj) {
            *acc += c * v;
        }
    }
}

/// A trial's error norm, or NaN where an evaluation failed (its power is not asked for then).
fn trial_error(trial: &Result<f64, FaultKind>) -> f64 {
    trial.as_ref().map_or(f64::NAN, |err| *err)
}

/// The error norm raised to the step control's exponent: libm's `pow`, as the integrands use
/// it (the platform's `powf` may differ in the last bit, and a different step sequence moves
/// every result).
fn trial_power(err: f64, exponent: f64) -> f64 {
    pow(err, exponent)
}

/// The smallest step floating point resolves at `t`, with a margin.
fn min_step(t: f64) -> f64 {
    10.0 * (t.abs() * f64::EPSILON).max(f64::MIN_POSITIVE)
}

impl Dense for Adaptive {
    fn interpolate(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64]) {
        if !self.dense_ready {
            self.dense_coefficients(p);
        }
        let coef = &self.dense;
        let x = (t - self.t_old) / self.h_last;
        // Each component's sum in the same order as one component at a time, the rows outside
        // so that the components go side by side.
        out.fill(0.0);
        match self.pair.dense_weights() {
            Some(_) => {
                let mut xp = 1.0;
                for row in coef {
                    xp *= x;
                    for (v, c) in out.iter_mut().zip(row) {
                        *v += c * xp;
                    }
                }
            }
            None => {
                for (r, row) in coef.iter().rev().enumerate() {
                    let factor = if r % 2 == 0 { x } else { 1.0 - x };
                    for (v, c) in out.iter_mut().zip(row) {
                        *v = (*v + c) * factor;
                    }
                }
            }
        }
        for (v, y) in out.iter_mut().zip(&self.y_old) {
            *v += y;
        }
    }

    fn after_jump(&mut self) {
        self.restart(self.h);
    }
}

impl Stepper for Adaptive {
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind> {
        self.prepare(p, t, y, t_end)?;
        self.k[0].copy_from_slice(self.f.as_ref().expect("prepared"));
        let mut rejected_here = false;
        loop {
            let (h, t_new) = self.trial_step(t, t_end)?;
            let trial = self.trial(p, t, y, h);
            let stiff = matches!(trial, Ok(err) if err <= 1.0) && self.at_stability_limit(h);
            if self.judge(trial, h, t, stiff, &mut rejected_here)? {
                self.accepted(t, h, y);
                y.copy_from_slice(&self.y_new);
                return Ok(t_new);
            }
        }
    }

    fn evaluations(&self) -> usize {
        self.evals
    }

    fn rejected(&self) -> usize {
        self.rejected
    }

    fn stiff_steps(&self) -> usize {
        self.stiff
    }
}

/// An explicit tableau as its stability region is read from: A's rows and the weights b.
pub(crate) type Tableau = (&'static [&'static [f64]], &'static [f64]);

/// Classic RK4's tableau.
pub(crate) const RK4_TABLEAU: Tableau =
    (&[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]], &[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0]);

/// The stability function R(z) of an explicit tableau: one step from y₀ = 1 of y' = λ·y with
/// z = h·λ, whose stages are g = z·(1 + A·g).
fn stability_function(a: &[&[f64]], b: &[f64], z: Complex<f64>) -> Complex<f64> {
    let mut g = [Complex::new(0.0, 0.0); 16];
    for (s, row) in a.iter().enumerate() {
        let sum: Complex<f64> = row.iter().zip(&g).map(|(a, g)| g * *a).sum();
        g[s] = z * (Complex::new(1.0, 0.0) + sum);
    }
    Complex::new(1.0, 0.0) + b.iter().zip(&g).map(|(b, g)| g * *b).sum::<Complex<f64>>()
}

/// How far from 0 along the ray z = r·`direction` (of modulus 1) the step stays stable,
/// |R(z)| ≤ 1: the
/// largest h·|λ| the method takes for an eigenvalue λ in that direction. The ray is walked out
/// in small steps to the first unstable point, then bisected; 0 where it leaves the region at
/// once (slightly unstable, as explicit methods are for some undamped modes).
pub(crate) fn stability_radius(tableau: (&[&[f64]], &[f64]), direction: Complex<f64>) -> f64 {
    let (a, b) = tableau;
    let stable = |r: f64| stability_function(a, b, direction * r).norm() <= 1.0 + 1e-12;
    let walk = 0.01;
    let mut inside = 0.0;
    while inside < 50.0 && stable(inside + walk) {
        inside += walk;
    }
    let mut outside = inside + walk;
    for _ in 0..50 {
        let middle = 0.5 * (inside + outside);
        if stable(middle) {
            inside = middle;
        } else {
            outside = middle;
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stability_intervals_on_the_negative_real_axis() {
        let radius = |tableau| stability_radius(tableau, Complex::new(-1.0, 0.0));
        // RK4: the real root of 1 + z + z²/2 + z³/6 + z⁴/24 = 1, near −2.7853.
        assert!((radius(RK4_TABLEAU) - 2.785_3).abs() < 1e-3, "{}", radius(RK4_TABLEAU));
        assert!(
            (radius(Pair::Dopri5.tableau()) - 3.31).abs() < 0.01,
            "{}",
            radius(Pair::Dopri5.tableau())
        );
        // Bogacki–Shampine's third-order polynomial, 1 + z + z²/2 + z³/6, near −2.5127.
        assert!(
            (radius(Pair::Bs3.tableau()) - 2.512_7).abs() < 1e-3,
            "{}",
            radius(Pair::Bs3.tableau())
        );
        // DOP853's reaches a little past the 6.1 its stiffness test counts from.
        assert!(
            (radius(Pair::Dop853.tableau()) - 6.394).abs() < 1e-3,
            "{}",
            radius(Pair::Dop853.tableau())
        );
    }

    #[test]
    fn the_stability_functions_agree_with_the_exponential_to_their_order() {
        // At z = −0.1, R(z) − e^z is of the size z^(p+1)/(p+1)!: 4e-6 for order 3, 8e-8 for
        // order 4, 1e-9 for order 5, 3e-15 for order 8.
        let z = Complex::new(-0.1, 0.0);
        let exact = numeric::elementary::pow(std::f64::consts::E, -0.1);
        for ((a, b), bound) in [
            (Pair::Bs3.tableau(), 1e-5),
            (RK4_TABLEAU, 1e-7),
            (Pair::Dopri5.tableau(), 1e-8),
            (Pair::Dop853.tableau(), 1e-14),
        ] {
            let error = (stability_function(a, b, z) - exact).norm();
            assert!(error < bound, "{error}");
        }
    }

    #[test]
    fn rk4_is_stable_on_the_imaginary_axis_up_to_twice_root_two() {
        let radius = stability_radius(RK4_TABLEAU, Complex::new(0.0, 1.0));
        assert!((radius - 2.0 * std::f64::consts::SQRT_2).abs() < 1e-6, "{radius}");
    }
}
