//! Right-hand sides at many states at once, for callers that evaluate a field of states
//! rather than follow one trajectory (a phase portrait, a batch from Python, a test of many
//! starts): M and f come from the batch tape, eight states a pass of the dynamics program,
//! and each state's accelerations are solved as [`Problem::rhs`] solves them, so the numbers
//! are the same bits as one state at a time.

use numeric::{BatchTape, Program, LANES};

use super::Mechanical;
use crate::{check_finite, FaultKind, Problem};

/// The batch tape of the dynamics program and its input and output rows, [`LANES`] states.
#[derive(Clone)]
pub(super) struct Many {
    tape: BatchTape,
    inputs: Vec<f64>,
    outputs: Vec<f64>,
}

impl Mechanical {
    /// dy = (q̇, q̈) at each state of `states` (a state of 2n values a row) at its time in
    /// `times`, written as the rows of `dys`: what [`Problem::rhs`] gives at each, bit for bit.
    /// The first state where a value is not finite or the system is singular ends the call
    /// with its row and its fault; the rows before it are written.
    ///
    /// # Panics
    /// When `states` and `dys` are not rows of 2n values, one per time: a caller's bug.
    pub fn rhs_many(
        &mut self,
        times: &[f64],
        states: &[f64],
        dys: &mut [f64],
    ) -> Result<(), (usize, FaultKind)> {
        let width = self.dim();
        assert_eq!(states.len(), times.len() * width, "rhs_many: a state a time");
        assert_eq!(dys.len(), states.len(), "rhs_many: a derivative a state");
        let (inputs, outputs) = (self.layout.dynamics_inputs(), self.layout.dynamics_outputs());
        let mut many = self.many.take().unwrap_or_else(|| Many {
            tape: BatchTape::new(self.dynamics.program().clone()),
            inputs: vec![0.0; LANES * inputs],
            outputs: vec![0.0; LANES * outputs],
        });
        let solved = self.rhs_chunks(&mut many, times, states, dys);
        self.many = Some(many);
        // `dyn_out` no longer holds the outputs at the dynamics program's inputs.
        self.solved = None;
        solved
    }

    fn rhs_chunks(
        &mut self,
        many: &mut Many,
        times: &[f64],
        states: &[f64],
        dys: &mut [f64],
    ) -> Result<(), (usize, FaultKind)> {
        let (n, width) = (self.layout.coordinates, self.dim());
        let (inputs, outputs) = (self.layout.dynamics_inputs(), self.layout.dynamics_outputs());
        for first in (0..times.len()).step_by(LANES) {
            let count = LANES.min(times.len() - first);
            for lane in 0..count {
                let (row, t) = (first + lane, times[first + lane]);
                // A parameter that follows a time series takes its value at this state's time.
                self.follow_signals(t);
                let input = &mut many.inputs[lane * inputs..(lane + 1) * inputs];
                input[0] = t;
                input[1..1 + width].copy_from_slice(&states[row * width..(row + 1) * width]);
                input[1 + width..].copy_from_slice(&self.parameters);
            }
            many.tape
                .eval_many(&many.inputs[..count * inputs], &mut many.outputs[..count * outputs]);
            for lane in 0..count {
                let row = first + lane;
                let fail = |fault| (row, fault);
                self.dyn_out.copy_from_slice(&many.outputs[lane * outputs..(lane + 1) * outputs]);
                check_finite(&self.dyn_out).map_err(fail)?;
                self.solve_dynamics().map_err(fail)?;
                let (y, dy) = (&states[row * width..], &mut dys[row * width..(row + 1) * width]);
                dy[..n].copy_from_slice(&y[n..width]);
                dy[n..].copy_from_slice(&self.solution[..n]);
                check_finite(dy).map_err(fail)?;
            }
        }
        Ok(())
    }
}

impl Mechanical {
    /// The dynamics program, for a caller that evaluates it over many states itself.
    pub(crate) fn dynamics_program(&self) -> &Program {
        self.dynamics.program()
    }

    /// The observation program, for a caller that evaluates it over many states itself.
    pub(crate) fn observation_program(&self) -> &Program {
        self.observation.program()
    }

    /// Whether a run's right-hand side is the dynamics program at fixed parameters alone: no
    /// time series or held law changes a parameter slot during the run.
    pub(crate) fn has_fixed_parameters(&self) -> bool {
        self.signals.is_empty() && self.hold.is_none()
    }

    /// dy = (q̇, q̈) at (t, y) from `outputs`, the dynamics program's outputs there evaluated
    /// elsewhere (a batch tape, at this problem's parameters): what [`Problem::rhs`] gives,
    /// bit for bit. The state is kept as the last one solved, so that observing there solves
    /// nothing again.
    pub(crate) fn rhs_from_outputs(
        &mut self,
        t: f64,
        y: &[f64],
        outputs: impl Iterator<Item = f64>,
        dy: &mut [f64],
    ) -> Result<(), FaultKind> {
        let n = self.layout.coordinates;
        self.solved = None;
        let input = self.dynamics.inputs_mut();
        input[0] = t;
        input[1..1 + 2 * n].copy_from_slice(y);
        for (slot, value) in self.dyn_out.iter_mut().zip(outputs) {
            *slot = value;
        }
        check_finite(&self.dyn_out)?;
        self.solve_dynamics()?;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        dy[n..].copy_from_slice(&self.solution[..n]);
        check_finite(dy)
    }
}
