//! The state-transition matrix over a motion: Φ(t_end, t_0) with Φ̇ = A(t)·Φ, Φ(t_0) = I, so
//! that a small change δx(t_0) of the start becomes Φ·δx(t_0) at the end, the inputs held on
//! the motion.
//!
//! Everything that integrates Φ is [`state_transition`], so that the sensitivity integrator
//! of `lagrange orbit` (the variational equations lowered beside the run's own) can take its
//! place without its callers changing. Until then it is classical RK4 on Φ̇ = A(t)·Φ, each
//! interval between samples cut into substeps short enough that h·‖A‖∞ ≤ [`REACH`], in one of
//! two ways ([`Between`]):
//!
//! - [`Between::Model`], for a run of the scene: from each recorded sample the scene's own
//!   equations are integrated to the next together with Φ (the state and Φ in one RK4 step,
//!   A at each stage's state), the inputs linear between the samples. Φ is then the run's to
//!   RK4's order, however far apart the samples are.
//! - [`Between::Interpolated`], for a trajectory read from a file, which need not be a motion
//!   of the scene at all (a planner's reference, a measured motion): only A at the samples is
//!   known, and A(t) is taken linear between them, so Φ is second order in the samples'
//!   spacing.

use nalgebra::DMatrix;

use super::{Along, Linear, Motion};
use crate::Error;

/// The most of h·‖A‖∞ in one RK4 substep: its local error is about REACH⁵/120 relative
/// (3e-11), small beside what a run's tolerance leaves.
pub const REACH: f64 = 0.02;

/// Past this many substeps in one interval the motion is too fast for the samples: an error
/// rather than a long wait.
const MAX_SUBSTEPS: usize = 1_000_000;

/// How A(t) is known between the samples of a motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Between {
    /// The motion is the scene's: its equations are integrated from each sample to the next.
    Model,
    /// Only the samples are known: A(t) linear between them.
    Interpolated,
}

impl Between {
    /// How Φ was integrated, in a few words for a report.
    pub fn words(self) -> &'static str {
        match self {
            Between::Model => {
                "RK4 of the scene's equations and Φ together from each sample to the next"
            }
            Between::Interpolated => "RK4 of Φ with A(t) linear between the samples",
        }
    }

    /// A short name for programs: `model` or `interpolated`.
    pub fn name(self) -> &'static str {
        match self {
            Between::Model => "model",
            Between::Interpolated => "interpolated",
        }
    }
}

/// Φ(t_end, t_0) over `motion`, whose first-order forms at the samples are `samples`.
pub fn state_transition(
    along: &mut Along,
    motion: &Motion,
    samples: &[Linear],
    between: Between,
) -> Result<DMatrix<f64>, Error> {
    let size = 2 * along.coordinates().len();
    let mut phi = DMatrix::identity(size, size);
    for k in 0..motion.times.len().saturating_sub(1) {
        let (t0, t1) = (motion.times[k], motion.times[k + 1]);
        let (a0, a1) = (&samples[k].a, &samples[k + 1].a);
        let reach = (t1 - t0) * norm(a0).max(norm(a1));
        let substeps = (reach / REACH).ceil().max(1.0);
        if substeps.is_nan() || substeps > MAX_SUBSTEPS as f64 {
            return Err(Error::Numeric(format!(
                "between t = {t0} and t = {t1}, A(t) changes the state too fast for the \
                 samples (h·‖A‖ = {reach:.3e}): record the motion more densely"
            )));
        }
        let interval = match between {
            Between::Interpolated => interpolated(t0, t1, a0, a1, substeps as usize),
            Between::Model => riding(along, motion, k, substeps as usize)?,
        };
        phi = interval * phi;
    }
    Ok(phi)
}

/// The infinity norm: the largest absolute row sum.
fn norm(a: &DMatrix<f64>) -> f64 {
    a.row_iter().map(|r| r.iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max)
}

/// Φ over [t0, t1] with A linear from `a0` to `a1`, in `substeps` RK4 steps.
fn interpolated(
    t0: f64,
    t1: f64,
    a0: &DMatrix<f64>,
    a1: &DMatrix<f64>,
    substeps: usize,
) -> DMatrix<f64> {
    let h = (t1 - t0) / substeps as f64;
    let at = |s: f64| a0 + (a1 - a0) * s;
    let mut phi = DMatrix::identity(a0.nrows(), a0.ncols());
    for j in 0..substeps {
        let s = |fraction: f64| (j as f64 + fraction) / substeps as f64;
        let (start, middle, end) = (at(s(0.0)), at(s(0.5)), at(s(1.0)));
        let k1 = &start * &phi;
        let k2 = &middle * (&phi + &k1 * (h / 2.0));
        let k3 = &middle * (&phi + &k2 * (h / 2.0));
        let k4 = &end * (&phi + &k3 * h);
        phi += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    }
    phi
}

/// Φ over the interval after sample `k`: the scene's equations and Φ integrated together from
/// the sample, in `substeps` RK4 steps, the inputs linear between the samples.
fn riding(
    along: &mut Along,
    motion: &Motion,
    k: usize,
    substeps: usize,
) -> Result<DMatrix<f64>, Error> {
    let (t0, t1) = (motion.times[k], motion.times[k + 1]);
    let (u0, u1) = (&motion.inputs[k], &motion.inputs[k + 1]);
    let inputs_at = |t: f64| -> Vec<f64> {
        let s = (t - t0) / (t1 - t0);
        u0.iter().zip(u1).map(|(a, b)| a + (b - a) * s).collect()
    };
    let h = (t1 - t0) / substeps as f64;
    let mut x = motion.states[k].clone();
    let size = x.len();
    let mut phi = DMatrix::identity(size, size);
    let mut stage = |t: f64, x: &[f64]| -> Result<(Vec<f64>, DMatrix<f64>), Error> {
        let u = inputs_at(t);
        let (linear, rate) = along.at_with_rate(t, x, &u)?;
        Ok((rate, linear.a))
    };
    let shifted = |x: &[f64], by: &[f64], h: f64| -> Vec<f64> {
        x.iter().zip(by).map(|(a, b)| a + b * h).collect()
    };
    for j in 0..substeps {
        let t = t0 + h * j as f64;
        let (f1, a1) = stage(t, &x)?;
        let k1 = &a1 * &phi;
        let (f2, a2) = stage(t + h / 2.0, &shifted(&x, &f1, h / 2.0))?;
        let k2 = &a2 * (&phi + &k1 * (h / 2.0));
        let (f3, a3) = stage(t + h / 2.0, &shifted(&x, &f2, h / 2.0))?;
        let k3 = &a3 * (&phi + &k2 * (h / 2.0));
        let (f4, a4) = stage(t + h, &shifted(&x, &f3, h))?;
        let k4 = &a4 * (&phi + &k3 * h);
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += h / 6.0 * (f1[i] + 2.0 * f2[i] + 2.0 * f3[i] + f4[i]);
        }
        phi += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    }
    Ok(phi)
}

#[cfg(test)]
// The exact answers are closed forms in the tests, far from a last bit.
#[allow(clippy::disallowed_methods)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_a_gives_its_exponential() {
        // ẋ = [0 1; -1 0]·x turns the state by the angle t: Φ = [cos t, sin t; −sin t, cos t].
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, 0.0]);
        let exact =
            DMatrix::from_row_slice(2, 2, &[1f64.cos(), 1f64.sin(), -1f64.sin(), 1f64.cos()]);
        // RK4: ten times the substeps, ten thousand times closer.
        let coarse = (interpolated(0.0, 1.0, &a, &a, 10) - &exact).amax();
        let fine = (interpolated(0.0, 1.0, &a, &a, 100) - &exact).amax();
        assert!(fine < 1e-9 && coarse / fine > 5e3, "{coarse:e} {fine:e}");
    }

    #[test]
    fn a_linear_a_is_followed_along_the_interval() {
        // ẋ = t·x: Φ(1, 0) = e^{1/2}, which A at the ends alone would miss.
        let (a0, a1) = (DMatrix::from_element(1, 1, 0.0), DMatrix::from_element(1, 1, 1.0));
        let phi = interpolated(0.0, 1.0, &a0, &a1, 100);
        assert!((phi[(0, 0)] - 0.5f64.exp()).abs() < 1e-10, "{phi}");
    }
}
