//! What a run asks of a method: the stepper and its dense output (the traits every method
//! implements), the cubic Hermite interpolant of the fixed-step methods, the fixed step that
//! lands on the end, and the error norms and the overflow fault the adaptive methods share.

use crate::{FaultKind, Problem};

/// The dense output of the last accepted step: what a run asks of its method between steps
/// (to locate events and record samples), apart from stepping.
pub(crate) trait Dense {
    /// The state at time `t` inside the last accepted step.
    fn interpolate(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64]);
    /// The right-hand side jumped where the last step ended (a held input was sampled, or the
    /// problem's mode jumped, its state with it, where a run cut the step): what
    /// the method carries from step to step (a derivative, a dense output, predicted stages)
    /// belongs to the old one and is dropped; the step size is kept.
    fn after_jump(&mut self) {}
    /// The problem's mode jumped where a run cut the last step (a contact opened, closed or
    /// landed): as [`Dense::after_jump`], and what depends on the equations themselves (an
    /// implicit method's Jacobian and factors) is dropped too, since the mode changed them.
    fn after_switch(&mut self) {
        self.after_jump();
    }
}

/// Advances one accepted step at a time and interpolates inside the last one.
pub(crate) trait Stepper: Dense {
    /// Advances from `t` (with `y` its state, updated in place) by one accepted step that does
    /// not pass `t_end`; returns the new time.
    fn advance(
        &mut self,
        p: &mut dyn Problem,
        t: f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<f64, FaultKind>;
    fn evaluations(&self) -> usize;
    /// Steps rejected by the error control (adaptive methods only).
    fn rejected(&self) -> usize {
        0
    }
    /// Accepted steps whose size was set by stability rather than accuracy (adaptive methods
    /// only): see [`crate::erk::Adaptive::stiff`].
    fn stiff_steps(&self) -> usize {
        0
    }
    /// Jacobians evaluated (adaptive implicit methods only).
    fn jacobians(&self) -> usize {
        0
    }
    /// LU factorizations of the iteration matrices (adaptive implicit methods only).
    fn factorizations(&self) -> usize {
        0
    }
    /// The times at which the method switched sides (`auto` only).
    fn switches(&self) -> &[f64] {
        &[]
    }
}

/// The cubic Hermite interpolant from the end values and derivatives of a step: third order,
/// enough to locate events of fixed-step methods. Its buffers are reused from step to step.
#[derive(Default)]
pub(crate) struct Hermite {
    pub t0: f64,
    pub t1: f64,
    pub y0: Vec<f64>,
    pub y1: Vec<f64>,
    pub f0: Vec<f64>,
    pub f1: Vec<f64>,
    /// Whether `f1` holds the derivative at the end of the current step.
    f1_known: bool,
}

impl Hermite {
    /// Records the start of a step: the state and its derivative there.
    pub fn begin(&mut self, t: f64, y: &[f64], f: &[f64]) {
        self.t0 = t;
        refill(&mut self.y0, y);
        refill(&mut self.f0, f);
    }

    /// Records the end of a step of size `h` from `t` and returns its time, landing exactly on
    /// `t_end` when within rounding of it; the end derivative is computed only if needed.
    pub fn end(&mut self, t: f64, h: f64, t_end: f64, y: &[f64]) -> f64 {
        let t1 = if t_end - (t + h) <= 1e-12 * h.abs() { t_end } else { t + h };
        self.t1 = t1;
        refill(&mut self.y1, y);
        self.f1_known = false;
        t1
    }

    /// Evaluates, computing the end derivative on demand (counted in `evals`).
    pub fn eval(&mut self, p: &mut dyn Problem, t: f64, out: &mut [f64], evals: &mut usize) {
        let d = self.y0.len();
        if !self.f1_known {
            self.f1.resize(d, 0.0);
            // A fault here already showed up when the step was taken.
            let _ = p.rhs(self.t1, &self.y1, &mut self.f1);
            *evals += 1;
            self.f1_known = true;
        }
        let h = self.t1 - self.t0;
        let s = (t - self.t0) / h;
        let (f0, f1) = (&self.f0, &self.f1);
        let h00 = (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s);
        let h10 = s * (1.0 - s) * (1.0 - s);
        let h01 = s * s * (3.0 - 2.0 * s);
        let h11 = s * s * (s - 1.0);
        for i in 0..d {
            out[i] = h00 * self.y0[i] + h10 * h * f0[i] + h01 * self.y1[i] + h11 * h * f1[i];
        }
    }
}

/// Makes `buffer` a copy of `values`, in the memory it already has once it is large enough.
fn refill(buffer: &mut Vec<f64>, values: &[f64]) {
    buffer.clear();
    buffer.extend_from_slice(values);
}

/// A fixed step that lands exactly on `t_end` instead of leaving a sliver before it.
pub(crate) fn fixed_step(step: f64, t: f64, t_end: f64) -> f64 {
    let left = t_end - t;
    if left <= step * (1.0 + 1e-9) {
        left
    } else {
        step
    }
}

/// The fault of rates `f` whose norm weighted by `scale` overflows: the component that
/// weighs the most. Every step's error is measured in that norm, so it would overflow too, and
/// the step shrink to nothing: the run stops here and says why.
pub(crate) fn rates_overflow(f: &[f64], scale: &[f64]) -> FaultKind {
    let weighed = |i: usize| f[i].abs() / scale[i];
    let component = (0..f.len()).max_by(|&a, &b| weighed(a).total_cmp(&weighed(b))).unwrap_or(0);
    FaultKind::RatesOverflow { component, rate: f.get(component).copied().unwrap_or(f64::NAN) }
}

/// The root mean square of the values.
pub(crate) fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x * x;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        (s / n as f64).sqrt()
    }
}
