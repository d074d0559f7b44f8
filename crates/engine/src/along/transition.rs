//! The state-transition matrix over a motion known only at its samples: Φ(t_end, t_0) with
//! Φ̇ = A(t)·Φ, Φ(t_0) = I, so that a small change δx(t_0) of the start becomes Φ·δx(t_0) at
//! the end, the inputs held on the motion.
//!
//! Along a run of the scene Φ is not integrated here: `sim::variational` carries it beside
//! the run on the run's own steps, from the same exact Jacobian A is ([`Between::Model`]).
//! A trajectory read from a file need not be a motion of the scene at all (a planner's
//! reference, a measured motion), so no integrator can follow it with the scene's equations:
//! only A at the samples is known, and here A(t) is taken linear between them and Φ̇ = A(t)·Φ
//! integrated by classical RK4, each interval cut into substeps short enough that
//! h·‖A‖∞ ≤ [`REACH`] ([`Between::Interpolated`]). Φ is then second order in the samples'
//! spacing.

use nalgebra::DMatrix;

use super::Linear;
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
    /// The motion is a run of the scene: Φ is the variational run's, on the run's steps.
    Model,
    /// Only the samples are known: A(t) linear between them.
    Interpolated,
}

impl Between {
    /// How Φ was integrated, in a few words for a report.
    pub fn words(self) -> &'static str {
        match self {
            Between::Model => "the variational equations integrated beside the run on its steps",
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

/// Φ(t_end, t_0) over the samples at `times`, whose first-order forms are `samples`, A(t)
/// linear between them.
pub fn state_transition(times: &[f64], samples: &[Linear]) -> Result<DMatrix<f64>, Error> {
    let size = samples.first().map_or(0, |s| s.a.nrows());
    let mut phi = DMatrix::identity(size, size);
    for (k, pair) in times.windows(2).enumerate().take(samples.len().saturating_sub(1)) {
        let (t0, t1) = (pair[0], pair[1]);
        let (a0, a1) = (&samples[k].a, &samples[k + 1].a);
        let reach = (t1 - t0) * norm(a0).max(norm(a1));
        let substeps = (reach / REACH).ceil().max(1.0);
        if substeps.is_nan() || substeps > MAX_SUBSTEPS as f64 {
            return Err(Error::Numeric(format!(
                "between t = {t0} and t = {t1}, A(t) changes the state too fast for the \
                 samples (h·‖A‖ = {reach:.3e}): record the motion more densely"
            )));
        }
        phi = interpolated(t0, t1, a0, a1, substeps as usize) * phi;
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
