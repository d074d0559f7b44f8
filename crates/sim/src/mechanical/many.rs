//! Right-hand sides at many states at once, for callers that evaluate a field of states
//! rather than follow one trajectory (a phase portrait, a batch from Python, a test of many
//! starts): M and f come from the batch tape, eight states a pass of the dynamics program,
//! and the eight systems are solved side by side by the operations [`Problem::rhs`] does for
//! one (or alone, where that solve does not serve), so the numbers are the same bits as one
//! state at a time. The lockstep ensemble's solve is the same (`solve_lanes`).

use numeric::{BatchTape, Program, LANES};

use crate::linalg::{self, Lanes};

use super::Mechanical;
use crate::{check_finite, rate, FaultKind, Problem};

/// The batch tape of the dynamics program, [`LANES`] states a pass, and the lanes of the solve
/// side by side.
#[derive(Clone)]
pub(super) struct Many {
    tape: BatchTape,
    mass: Vec<Lanes>,
    accelerations: Vec<Lanes>,
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
        if self.recursive() {
            return self.rhs_many_recursive(times, states, dys);
        }
        let n = self.layout.coordinates;
        let mut many = self.many.take().unwrap_or_else(|| Many {
            tape: BatchTape::new(self.dynamics.program().clone()),
            mass: vec![[0.0; LANES]; n * n],
            accelerations: vec![[0.0; LANES]; n],
        });
        // Compiled for the widest vectors at hand, as the lockstep's trials are.
        let chunks = Chunks { problem: self, many: &mut many, times, states, dys };
        let solved = pulp::Arch::new().dispatch(chunks);
        self.many = Some(many);
        // `dyn_out` no longer holds the outputs at the dynamics program's inputs.
        self.solved = None;
        solved
    }

    /// [`Mechanical::rhs_many`] by the recursive form's program on the batch tape, q̈ of
    /// [`LANES`] states a pass: the same operations as one state's, so the same bits. A state
    /// whose q̈ is not finite is solved alone, which says why.
    fn rhs_many_recursive(
        &mut self,
        times: &[f64],
        states: &[f64],
        dys: &mut [f64],
    ) -> Result<(), (usize, FaultKind)> {
        let n = self.layout.coordinates;
        let width = 2 * n;
        if !self.signals.is_empty() {
            // Parameters that follow a series take its value at each state's time.
            let rows = states.chunks_exact(width).zip(dys.chunks_exact_mut(width));
            for (row, ((state, dy), &t)) in rows.zip(times).enumerate() {
                self.rhs(t, state, dy).map_err(|kind| (row, kind))?;
            }
            return Ok(());
        }
        let program = self.chain.as_ref().expect("a recursive form").program().clone();
        let tape = self.chain_many.get_or_insert_with(|| BatchTape::new(program));
        let mut inputs = Vec::with_capacity(times.len() * tape.program().inputs);
        for (state, &t) in states.chunks_exact(width).zip(times) {
            inputs.push(t);
            inputs.extend_from_slice(state);
            inputs.extend_from_slice(&self.parameters);
        }
        let mut accelerations = vec![0.0; times.len() * n];
        tape.eval_many(&inputs, &mut accelerations);
        let rows = states.chunks_exact(width).zip(dys.chunks_exact_mut(width));
        for (row, ((state, dy), a)) in rows.zip(accelerations.chunks_exact(n)).enumerate() {
            dy[..n].copy_from_slice(&state[n..]);
            dy[n..].copy_from_slice(a);
            if !dy.iter().all(|x| x.is_finite()) {
                self.rhs(times[row], state, dy).map_err(|kind| (row, kind))?;
            }
        }
        Ok(())
    }

    /// [`Mechanical::rhs_many`] a pass of [`LANES`] states at a time: the dynamics program on
    /// the batch tape, M q̈ = f solved side by side where there are no kept multipliers, and
    /// a state that solve does not serve solved alone.
    #[inline(always)]
    fn rhs_chunks(
        &mut self,
        many: &mut Many,
        times: &[f64],
        states: &[f64],
        dys: &mut [f64],
    ) -> Result<(), (usize, FaultKind)> {
        let (n, width) = (self.layout.coordinates, self.dim());
        let outputs = self.layout.dynamics_outputs();
        for first in (0..times.len()).step_by(LANES) {
            let count = LANES.min(times.len() - first);
            for lane in 0..LANES {
                // Spare lanes repeat the last state; their results are dropped.
                let row = first + lane.min(count - 1);
                // A parameter that follows a time series takes its value at this state's time.
                self.follow_signals(times[row]);
                let inputs = many.tape.input_lanes_mut();
                inputs[0][lane] = times[row];
                let values = states[row * width..(row + 1) * width].iter().chain(&self.parameters);
                for (slot, value) in inputs[1..].iter_mut().zip(values) {
                    slot[lane] = *value;
                }
            }
            many.tape.run_lanes();
            let solved = if self.layout.multipliers == 0 {
                solve_lanes(self.layout, &many.tape, &mut many.mass, &mut many.accelerations)
            } else {
                [false; LANES]
            };
            for lane in 0..count {
                let row = first + lane;
                let fail = |fault| (row, fault);
                let (y, dy) = (&states[row * width..], &mut dys[row * width..(row + 1) * width]);
                dy[..n].copy_from_slice(&y[n..width]);
                if solved[lane] {
                    for (d, a) in dy[n..].iter_mut().zip(&many.accelerations) {
                        *d = a[lane];
                    }
                } else {
                    for (o, out) in self.dyn_out.iter_mut().enumerate().take(outputs) {
                        *out = many.tape.output_lanes(o)[lane];
                    }
                    check_finite(&self.dyn_out, |i| self.layout.dynamics_entry(i)).map_err(fail)?;
                    self.solve_dynamics().map_err(fail)?;
                    dy[n..].copy_from_slice(&self.solution[..n]);
                }
                check_finite(dy, rate).map_err(fail)?;
            }
        }
        Ok(())
    }
}

/// [`Mechanical::rhs_many`]'s passes, for `pulp` to compile for the vector instructions at
/// hand.
struct Chunks<'a> {
    problem: &'a mut Mechanical,
    many: &'a mut Many,
    times: &'a [f64],
    states: &'a [f64],
    dys: &'a mut [f64],
}

impl pulp::WithSimd for Chunks<'_> {
    type Output = Result<(), (usize, FaultKind)>;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Self::Output {
        self.problem.rhs_chunks(self.many, self.times, self.states, self.dys)
    }
}

impl Mechanical {
    /// The dynamics program, for a caller that evaluates it over many states itself.
    pub(crate) fn dynamics_program(&self) -> &Program {
        self.dynamics.program()
    }

    /// The recursive form's program of q̈ (the dynamics program's inputs), where q̈ is solved
    /// by it ([`Mechanical::with_chain`]).
    pub(crate) fn recursive_program(&self) -> Option<&Program> {
        self.chain.as_ref().map(|tape| tape.program())
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
        self.dense = true;
        self.sliced = None;
        let layout = self.layout;
        check_finite(&self.dyn_out, |i| layout.dynamics_entry(i))?;
        self.solve_dynamics()?;
        dy[..n].copy_from_slice(&y[n..2 * n]);
        dy[n..].copy_from_slice(&self.solution[..n]);
        check_finite(dy, rate)
    }
}

/// M q̈ = f of a system without kept multipliers at each lane of `tape`'s last run: M's lower
/// triangle and f gathered into `mass` and `accelerations`, solved side by side, q̈ left in
/// `accelerations`. A lane whose flag is false (a dynamics output not finite, or a system the
/// LDLᵀ in lanes declines) is to be solved alone, as [`Problem::rhs`] solves it; a lane whose
/// flag is true holds its bits.
#[inline(always)]
pub(crate) fn solve_lanes(
    layout: super::Layout,
    tape: &BatchTape,
    mass: &mut [Lanes],
    accelerations: &mut [Lanes],
) -> [bool; LANES] {
    let n = layout.coordinates;
    debug_assert_eq!(layout.multipliers, 0);
    for i in 0..n {
        for j in 0..=i {
            mass[i * n + j] = *tape.output_lanes(j * n + i);
        }
        accelerations[i] = *tape.output_lanes(n * n + i);
    }
    let ok = linalg::solve_symmetric_lanes(n, mass, accelerations);
    let finite = finite_lanes((0..layout.dynamics_outputs()).map(|o| tape.output_lanes(o)));
    std::array::from_fn(|l| ok[l] && finite[l])
}

/// Whether each lane's values are all finite: v·0 is ±0 for a finite v and NaN otherwise, so
/// the sum of those is 0 exactly when they all are, a test the compiler vectorizes.
#[inline(always)]
pub(crate) fn finite_lanes<'a>(values: impl Iterator<Item = &'a Lanes>) -> [bool; LANES] {
    let mut excess = [0.0; LANES];
    for v in values {
        for l in 0..LANES {
            excess[l] += v[l] * 0.0;
        }
    }
    std::array::from_fn(|l| excess[l] == 0.0)
}
