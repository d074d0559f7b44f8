//! The harmonic oscillator, whose solution is known in closed form, shared by the integrators'
//! tests.

use sim::{FaultKind, Problem};

/// y'' = −y from y = 1, y' = 0; observations: y, and y − 0.5 (for events).
pub struct Oscillator;

impl Problem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    }
    fn observations(&self) -> usize {
        2
    }
    fn observe(&mut self, _t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        out[0] = y[0];
        out[1] = y[0] - 0.5;
        Ok(())
    }
}
