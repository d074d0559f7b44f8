//! Exact Jacobians of the first-order problems, from the partials of their equations lowered
//! beside them. The accelerations solve r = M q̈ − Jᵀλ − f = 0 together with the (stabilised)
//! constraint rows, so along the state [M −Jᵀ; J 0]·∂(q̈, λ) = −∂(r, c): one LU of the matrix
//! the accelerations were solved with, and a solve per state component, give the exact
//! ∂q̈/∂(q, q̇) with no step size to choose. On a long chain's recursive route the columns
//! solve with the sweep's own factors instead, O(n) each, M never formed.

use super::{Canonical, ChainFactored, Layout, Mechanical, Stabilisation, SLICES};
use numeric::Tape;

use crate::{check_finite, linalg, FaultKind, NonFiniteAt};

/// How many of the Jacobian's (and the sensitivities') columns are solved side by side.
pub(super) const COLUMNS: usize = 8;

impl Mechanical {
    /// Whether the problem has its exact Jacobian ([`Mechanical::with_partials`]).
    pub fn has_partials(&self) -> bool {
        self.partials.is_some()
    }

    /// The raw partials ∂(r, c, Φ, Φ̇)/∂(q, q̇) at the state `y` = (q, q̇) and time `t`, with
    /// the accelerations and multipliers held at `unknowns` = (q̈ (n), λ (m)), in the layout of
    /// the partials program ([`Layout`]): row-major, n + 3m rows of 2n (r, then c, Φ and Φ̇ of
    /// each multiplier; in each row the partials in q, then in q̇). `None` without a partials
    /// program. This is what a method integrating the constraints as they are (index 3, with
    /// q̈ and λ among its unknowns) needs besides M and J.
    pub fn partials_at(
        &mut self,
        t: f64,
        y: &[f64],
        unknowns: &[f64],
    ) -> Result<Option<&[f64]>, FaultKind> {
        let Layout { coordinates: n, multipliers: m, parameters: k } = self.layout;
        self.follow_signals(t);
        let Some(tape) = self.partials.as_mut() else { return Ok(None) };
        assert_eq!(y.len(), 2 * n, "state length");
        assert_eq!(unknowns.len(), n + m, "accelerations and multipliers");
        let input = &mut self.obs_input;
        input[0] = t;
        input[1..1 + 2 * n].copy_from_slice(y);
        input[1 + 2 * n..1 + 3 * n + m].copy_from_slice(unknowns);
        input[1 + 3 * n + m..1 + 3 * n + m + k].copy_from_slice(&self.parameters);
        tape.eval(input, &mut self.partials_out);
        check_finite(&self.partials_out, |_| NonFiniteAt::Partials)?;
        Ok(Some(&self.partials_out))
    }

    /// The gradients in (q, q̇) of what the rows kept now hold at zero: Φ and Φ̇ of a position
    /// row, A·q̇ + b of a velocity row. They are the normals of the manifold a run moves on,
    /// along which Baumgarte's terms, not the motion, decide the Jacobian; a map of the state
    /// is charted on their null space. `None` without a partials program.
    pub fn manifold_normals(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<Vec<Vec<f64>>>, FaultKind> {
        let Layout { coordinates: n, multipliers: m, .. } = self.layout;
        // Φ and Φ̇ do not depend on q̈ and λ, which the program takes all the same.
        let held = vec![0.0; n + m];
        let kept = self.kept.clone();
        let kinds = self.stabilisation.clone();
        let Some(out) = self.partials_at(t, y, &held)? else { return Ok(None) };
        let width = 2 * n;
        let row = |block: usize, c: usize| out[(n + block * m + c) * width..][..width].to_vec();
        let mut normals = Vec::new();
        for c in (0..m).filter(|&c| kept[c]) {
            normals.push(row(1, c));
            if kinds[c] == Stabilisation::Position {
                normals.push(row(2, c));
            }
        }
        Ok(Some(normals))
    }

    /// [`Mechanical::partials_at`] into `partials_out` for what the exact Jacobian reads: the
    /// rows of r and the kept rows' (an open contact's rows are not read), from a slice of the
    /// partials program for the rows kept now; the other rows keep older values. A rimless
    /// wheel on one of its eight spokes had evaluated its sixteen contact rows' partials at
    /// every stage, most of the program. A contact slipping in space reads the rates of rows
    /// it does not keep: there, the whole program runs.
    fn kept_partials_at(&mut self, t: f64, y: &[f64], unknowns: &[f64]) -> Result<(), FaultKind> {
        if self.bends.iter().any(|b| b.cone.is_some()) {
            return self.partials_at(t, y, unknowns).map(|_| ());
        }
        let Layout { coordinates: n, multipliers: m, parameters: k } = self.layout;
        self.follow_signals(t);
        let Some(tape) = self.partials.as_mut() else { return Ok(()) };
        let kept = &self.kept;
        // Compared entry by entry inline: `==` on the two vectors called the C library's
        // memcmp, a sixth of a small fit's time in that call alone.
        let same =
            |rows: &[bool]| rows.len() == kept.len() && rows.iter().zip(kept).all(|(a, b)| a == b);
        let index = match self.partial_slices.iter().position(|(rows, _)| same(rows)) {
            Some(index) => index,
            None => {
                let width = 2 * n;
                let rows = (0..n).chain(
                    (0..m).filter(|&c| kept[c]).flat_map(|c| (0..3).map(move |b| n + b * m + c)),
                );
                let slice = tape.slice(rows.flat_map(|r| r * width..(r + 1) * width));
                // The modes a run meets are few; a problem that meets ever more starts over.
                if self.partial_slices.len() >= SLICES {
                    self.partial_slices.clear();
                }
                self.partial_slices.push((kept.clone(), slice));
                self.partial_slices.len() - 1
            }
        };
        let input = tape.inputs_mut();
        input[0] = t;
        input[1..1 + 2 * n].copy_from_slice(y);
        input[1 + 2 * n..1 + 3 * n + m].copy_from_slice(unknowns);
        input[1 + 3 * n + m..1 + 3 * n + m + k].copy_from_slice(&self.parameters);
        let slice = &mut self.partial_slices[index].1;
        tape.run_slice(slice, &mut self.partials_out);
        // 0·x is NaN for a non-finite x (see `all_finite`): no branch per output, and four
        // sums side by side rather than one chain of additions.
        let out = &self.partials_out;
        let mut lanes = [0.0; 4];
        let chunks = slice.outputs().chunks_exact(4);
        let rest = chunks.remainder().iter().fold(0.0, |sum, &o| sum + 0.0 * out[o]);
        for chunk in chunks {
            for (lane, &o) in lanes.iter_mut().zip(chunk) {
                *lane += 0.0 * out[o];
            }
        }
        if !lanes.iter().fold(rest, |sum, lane| sum + lane).is_finite() {
            return Err(FaultKind::NonFinite { at: NonFiniteAt::Partials });
        }
        Ok(())
    }

    /// ∂(q̇, q̈)/∂(q, q̇), row-major, into `jac`; false without a partials program.
    pub(super) fn exact_jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, FaultKind> {
        if self.partials.is_none() {
            return Ok(false);
        }
        if self.chain_jacobian(t, y, jac)? {
            return Ok(true);
        }
        let n = self.layout.coordinates;
        self.dense_accelerations(t, y)?;
        let solution = std::mem::take(&mut self.solution);
        let evaluated = self.kept_partials_at(t, y, &solution);
        if let Err(fault) = evaluated {
            self.solution = solution;
            return Err(fault);
        }
        let out = std::mem::take(&mut self.partials_out);
        let width = 2 * n;
        jac.fill(0.0);
        for i in 0..n {
            jac[i * width + n + i] = 1.0;
        }
        if self.mass_factored && self.small.is_none() {
            // M alone past the stack's order, factored by LDLᵀ as the accelerations were solved
            // at this state: those factors serve every column (a 32-link chain's LU for them
            // had been a quarter of its Jacobian). Smaller systems keep `solve_partials`' LU,
            // whose columns are the bits `linear`'s solves give (a linearization along a run
            // at an equilibrium is the one about it, exactly).
            let system = &self.system;
            negated_in_blocks(
                n,
                width,
                &mut self.kept_factors.block,
                |i, c| out[i * width + c],
                |block| linalg::ldl_solve_columns(system, block),
                |i, first, row| {
                    let at = (n + i) * width + first;
                    jac[at..at + row.len()].copy_from_slice(row);
                },
            );
            self.partials_out = out;
            self.solution = solution;
            check_finite(jac, |_| NonFiniteAt::Jacobian)?;
            return Ok(true);
        }
        let solved = self.solve_partials(&out, width, &solution, |k, column| {
            for i in 0..n {
                jac[(n + i) * width + k] = column[i];
            }
        });
        self.partials_out = out;
        self.solution = solution;
        solved?;
        check_finite(jac, |_| NonFiniteAt::Jacobian)?;
        Ok(true)
    }

    /// [`Mechanical::exact_jacobian`] on the recursive route, past the stack's order: q̈ and
    /// the sweep's factors from one run of the factored program, then −M⁻¹ times the partials
    /// solved by the sweep a block of columns at a time, O(n) a column. The dense route had
    /// formed M (n² entries), factored it (n³/6) and solved each column in O(n²): at 32 links
    /// most of the Jacobian. False where the sweep gives no number: the dense route then
    /// solves, or says why it cannot.
    fn chain_jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        let Some(mut factored) = self.recursive_factors(t, y) else { return Ok(false) };
        let n = self.layout.coordinates;
        let solution = std::mem::take(&mut self.solution);
        let evaluated = self.kept_partials_at(t, y, &solution);
        self.solution = solution;
        if let Err(fault) = evaluated {
            self.chain_factored = Some(factored);
            return Err(fault);
        }
        let width = 2 * n;
        // q̇'s rows; q̈'s are every one written below.
        jac[..n * width].fill(0.0);
        for i in 0..n {
            jac[i * width + n + i] = 1.0;
        }
        let out = &self.partials_out;
        let block = &mut self.kept_factors.block;
        factored.solve_negated(
            n,
            width,
            block,
            |i, c| out[i * width + c],
            |i, first, row| {
                let at = (n + i) * width + first;
                jac[at..at + row.len()].copy_from_slice(row);
            },
        );
        self.chain_factored = Some(factored);
        check_finite(jac, |_| NonFiniteAt::Jacobian)?;
        Ok(true)
    }

    /// Where the recursive route solves this problem's columns (past the stack's order, the
    /// sweep giving numbers at this state): q̈ into `solution` from one run of the factored
    /// program, and the sweep's factors, taken out of the problem for the caller to solve with
    /// and put back. `None`: the dense route solves.
    fn recursive_factors(&mut self, t: f64, y: &[f64]) -> Option<ChainFactored> {
        if self.small.is_some() {
            return None;
        }
        let mut factored = self.chain_factored.take()?;
        let n = self.layout.coordinates;
        self.begin_recursive(t, y);
        super::fill_inputs(factored.tape.inputs_mut(), t, y, &self.parameters);
        factored.tape.run(&mut factored.out);
        if !crate::all_finite(&factored.out) {
            self.chain_factored = Some(factored);
            return None;
        }
        self.solution[..n].copy_from_slice(&factored.out[..n]);
        self.solved = Some(self.baumgarte.to_bits());
        Some(factored)
    }

    /// Gives the problem the partials of its equations by `columns` parameters: `program`
    /// takes the observation inputs and gives ∂(r, c, Φ, Φ̇)/∂p with the state, q̈ and λ held,
    /// row-major with the rows of the partials program ([`Layout`]) and a column per
    /// parameter. Each column is a parameter a caller varies (one set by a user, with the
    /// slots that follow it moved along: the program carries the chain rule), so `columns`
    /// need not be the number of slots.
    pub fn set_sensitivities(&mut self, program: Tape, columns: usize) {
        assert_eq!(program.inputs(), self.layout.observation_inputs());
        assert_eq!(program.outputs(), self.layout.sensitivity_outputs(columns));
        self.sensitivities_out = vec![0.0; program.outputs()];
        self.sensitivities = Some((program, columns));
    }

    /// Whether a contact has Coulomb friction, whose μ the problem holds as a number.
    pub(crate) fn has_friction(&self) -> bool {
        self.contacts.iter().any(|c| c.friction.is_some())
    }

    /// Whether laws are held in parameter slots between samples.
    pub(crate) fn has_hold(&self) -> bool {
        self.hold.is_some()
    }

    /// How many parameters the sensitivity program differentiates by; `None` without one.
    pub fn sensitivity_columns(&self) -> Option<usize> {
        self.sensitivities.as_ref().map(|(_, columns)| *columns)
    }

    /// The sensitivity program's outputs at (t, y) with q̈ and λ held at `solution`, into
    /// `sensitivities_out`; a fault where one is not finite.
    fn sensitivities_at(&mut self, t: f64, y: &[f64], solution: &[f64]) -> Result<(), FaultKind> {
        let Layout { coordinates: n, multipliers: m, parameters: k } = self.layout;
        let input = &mut self.obs_input;
        input[0] = t;
        input[1..1 + 2 * n].copy_from_slice(y);
        input[1 + 2 * n..1 + 3 * n + m].copy_from_slice(solution);
        input[1 + 3 * n + m..1 + 3 * n + m + k].copy_from_slice(&self.parameters);
        if let Some((tape, _)) = self.sensitivities.as_mut() {
            tape.eval(input, &mut self.sensitivities_out);
        }
        check_finite(&self.sensitivities_out, |_| NonFiniteAt::Partials)
    }

    /// ∂q̈/∂p at (t, y), row-major n × k, into `out`: the accelerations' derivative by each of
    /// the sensitivity program's parameters with the state held, from the same augmented
    /// system (its factors where the accelerations left them) and the same stabilisation as
    /// the exact Jacobian, [M −Jᵀ; J 0]·∂(q̈, λ)/∂p = −∂(r, c̃)/∂p. False without a sensitivity
    /// program.
    pub fn parameter_derivative(
        &mut self,
        t: f64,
        y: &[f64],
        out: &mut [f64],
    ) -> Result<bool, FaultKind> {
        let Some(columns) = self.sensitivity_columns() else { return Ok(false) };
        let n = self.layout.coordinates;
        assert_eq!(y.len(), 2 * n, "state length");
        assert_eq!(out.len(), n * columns, "∂q̈/∂p's length");
        if let Some(mut factored) = self.recursive_factors(t, y) {
            let solution = std::mem::take(&mut self.solution);
            let evaluated = self.sensitivities_at(t, y, &solution);
            self.solution = solution;
            if evaluated.is_ok() {
                let partials = &self.sensitivities_out;
                let read = |i: usize, c: usize| partials[i * columns + c];
                factored.solve_negated(
                    n,
                    columns,
                    &mut self.kept_factors.block,
                    read,
                    |i, c, row| {
                        out[i * columns + c..i * columns + c + row.len()].copy_from_slice(row);
                    },
                );
            }
            self.chain_factored = Some(factored);
            evaluated?;
            check_finite(out, |_| NonFiniteAt::Jacobian)?;
            return Ok(true);
        }
        self.dense_accelerations(t, y)?;
        let solution = std::mem::take(&mut self.solution);
        if let Err(fault) = self.sensitivities_at(t, y, &solution) {
            self.solution = solution;
            return Err(fault);
        }
        let partials = std::mem::take(&mut self.sensitivities_out);
        let solved = self.solve_partials(&partials, columns, &solution, |j, column| {
            for i in 0..n {
                out[i * columns + j] = column[i];
            }
        });
        self.sensitivities_out = partials;
        self.solution = solution;
        solved?;
        check_finite(out, |_| NonFiniteAt::Jacobian)?;
        Ok(true)
    }

    /// What a variational run needs at one state, from one solve of the accelerations and
    /// one factorization of their matrix: the rates F = (q̇, q̈) into `rates`, ∂F/∂(q, q̇)
    /// into `jac` (row-major 2n × 2n) and, with `change`, ∂q̈/∂p (row-major n × k) into it.
    /// The same bits as [`Problem::rhs`], [`Problem::jacobian`] and
    /// [`Mechanical::parameter_derivative`] one after another, at a fraction of their cost on
    /// small scenes, where the three calls' handling (the accelerations' cache checked twice,
    /// the observation inputs copied twice, the columns' set-up done twice) outweighed the
    /// arithmetic. False without a partials program, or with `change` and no sensitivity
    /// program.
    pub(crate) fn variational_parts(
        &mut self,
        t: f64,
        y: &[f64],
        rates: &mut [f64],
        jac: &mut [f64],
        change: Option<&mut [f64]>,
    ) -> Result<bool, FaultKind> {
        let n = self.layout.coordinates;
        let columns = match (&change, &self.sensitivities) {
            (None, _) => 0,
            (Some(_), Some((_, columns))) => *columns,
            (Some(_), None) => return Ok(false),
        };
        if self.partials.is_none() {
            return Ok(false);
        }
        let recursive = self.recursive_factors(t, y);
        if recursive.is_none() {
            self.kept_accelerations(t, y)?;
        }
        rates[..n].copy_from_slice(&y[n..2 * n]);
        rates[n..].copy_from_slice(&self.solution[..n]);
        if let Err(fault) = check_finite(rates, crate::rate) {
            if recursive.is_some() {
                self.chain_factored = recursive;
            }
            return Err(fault);
        }
        let solution = std::mem::take(&mut self.solution);
        let evaluated = self.kept_partials_at(t, y, &solution).and_then(|()| {
            if columns == 0 {
                return Ok(());
            }
            self.sensitivities_at(t, y, &solution)
        });
        if let Err(fault) = evaluated {
            self.solution = solution;
            if recursive.is_some() {
                self.chain_factored = recursive;
            }
            return Err(fault);
        }
        let width = 2 * n;
        // [0 I] above; every entry below is written by the solve.
        jac[..n * width].fill(0.0);
        for i in 0..n {
            jac[i * width + n + i] = 1.0;
        }
        let mut change = change;
        if let Some(mut factored) = recursive {
            // The Jacobian's 2n columns, then the parameters' k, as one run of blocks.
            let (partials, sensitivities) = (&self.partials_out, &self.sensitivities_out);
            let read = |i: usize, c: usize| {
                if c < width {
                    partials[i * width + c]
                } else {
                    sensitivities[i * columns + c - width]
                }
            };
            let block = &mut self.kept_factors.block;
            factored.solve_negated(n, width + columns, block, read, |i, first, row| {
                for (c, v) in (first..).zip(row) {
                    if c < width {
                        jac[(n + i) * width + c] = *v;
                    } else if let Some(out) = change.as_deref_mut() {
                        out[i * columns + c - width] = *v;
                    }
                }
            });
            self.chain_factored = Some(factored);
            self.solution = solution;
            check_finite(jac, |_| NonFiniteAt::Jacobian)?;
            if let Some(out) = change {
                check_finite(out, |_| NonFiniteAt::Jacobian)?;
            }
            return Ok(true);
        }
        let partials = std::mem::take(&mut self.partials_out);
        // The Jacobian's columns alone, where nothing turns with the state, a row at a time.
        let by_rows = match columns {
            0 => self.solve_partials_rows(&partials, width, |i, first, row| {
                jac[(n + i) * width + first..][..row.len()].copy_from_slice(row);
            }),
            _ => Ok(false),
        };
        if !matches!(by_rows, Ok(false)) {
            self.solution = solution;
            self.partials_out = partials;
            by_rows?;
            check_finite(jac, |_| NonFiniteAt::Jacobian)?;
            return Ok(true);
        }
        let sensitivities = std::mem::take(&mut self.sensitivities_out);
        // The Jacobian's 2n columns, then the parameters' k, solved as one block of columns.
        let solved = self.solve_partials_of(
            width + columns,
            |row, c| {
                if c < width {
                    partials[row * width + c]
                } else {
                    sensitivities[row * columns + c - width]
                }
            },
            &solution,
            |c, column| {
                if c < width {
                    for i in 0..n {
                        jac[(n + i) * width + c] = column[i];
                    }
                } else if let Some(out) = change.as_deref_mut() {
                    for i in 0..n {
                        out[i * columns + c - width] = column[i];
                    }
                }
            },
        );
        self.solution = solution;
        self.partials_out = partials;
        self.sensitivities_out = sensitivities;
        solved?;
        check_finite(jac, |_| NonFiniteAt::Jacobian)?;
        if let Some(out) = change {
            check_finite(out, |_| NonFiniteAt::Jacobian)?;
        }
        Ok(true)
    }

    /// q̈ and λ at (t, y) into `solution` (n + m), and their derivatives along `directions`
    /// (row-major 2n × k: columns of dx/dθ) into `out` (row-major (n + m) × k), with
    /// column j's own parameter share where `parameters[j]` names a column of the sensitivity
    /// program: [M −Jᵀ; J 0]·d(q̈, λ) = −(∂(r, c̃)/∂x·D + ∂(r, c̃)/∂p). What a measured
    /// acceleration's or reaction's derivative by a fit's unknowns needs. False without a
    /// partials program, or where `parameters` names a column without a sensitivity program.
    pub fn solution_derivative(
        &mut self,
        t: f64,
        y: &[f64],
        directions: &[f64],
        parameters: &[Option<usize>],
        solution: &mut [f64],
        out: &mut [f64],
    ) -> Result<bool, FaultKind> {
        let Layout { coordinates: n, multipliers: m, parameters: slots } = self.layout;
        let k = parameters.len();
        assert_eq!(directions.len(), 2 * n * k, "directions' length");
        assert_eq!(out.len(), (n + m) * k, "the derivatives' length");
        let wants_parameters = parameters.iter().any(Option::is_some);
        if self.partials.is_none() || (wants_parameters && self.sensitivities.is_none()) {
            return Ok(false);
        }
        self.dense_accelerations(t, y)?;
        let held = std::mem::take(&mut self.solution);
        solution.copy_from_slice(&held);
        let evaluated = self.partials_at(t, y, &held).map(|_| ());
        if let Err(fault) = evaluated {
            self.solution = held;
            return Err(fault);
        }
        let rows = n + 3 * m;
        let width = 2 * n;
        let mut combined = vec![0.0; rows * k];
        for i in 0..rows {
            let row = &self.partials_out[i * width..(i + 1) * width];
            for (l, p) in row.iter().enumerate().filter(|(_, p)| **p != 0.0) {
                for j in 0..k {
                    combined[i * k + j] += p * directions[l * k + j];
                }
            }
        }
        if wants_parameters {
            let input = &mut self.obs_input;
            input[0] = t;
            input[1..1 + 2 * n].copy_from_slice(y);
            input[1 + 2 * n..1 + 3 * n + m].copy_from_slice(&held);
            input[1 + 3 * n + m..1 + 3 * n + m + slots].copy_from_slice(&self.parameters);
            let Some((tape, columns)) = self.sensitivities.as_mut() else {
                unreachable!("checked above")
            };
            let columns = *columns;
            tape.eval(input, &mut self.sensitivities_out);
            for i in 0..rows {
                for (j, p) in parameters.iter().enumerate() {
                    if let Some(p) = p {
                        combined[i * k + j] += self.sensitivities_out[i * columns + p];
                    }
                }
            }
        }
        let solved = check_finite(&combined, |_| NonFiniteAt::Partials).and_then(|()| {
            self.solve_partials(&combined, k, &held, |j, column| {
                for (i, v) in column.iter().enumerate() {
                    out[i * k + j] = *v;
                }
            })
        });
        self.solution = held;
        solved?;
        check_finite(out, |_| NonFiniteAt::Jacobian)?;
        Ok(true)
    }

    /// [`Mechanical::solve_partials_of`] for the partials program's own columns (`width` of
    /// them, row-major in `partials`), each solved block's coordinate rows handed to
    /// `put(row, first column, values)`: the blocks are filled and emptied a row at a time, as
    /// slices, rather than an entry at a time through a closure (the walker's bookkeeping had
    /// been a seventh of its search). The same operations on each entry, so the same bits.
    /// False, with nothing solved, where a slipping contact in space turns its force with the
    /// state: [`Mechanical::solve_partials_of`] adds that.
    fn solve_partials_rows(
        &mut self,
        partials: &[f64],
        width: usize,
        mut put: impl FnMut(usize, usize, &[f64]),
    ) -> Result<bool, FaultKind> {
        let Mechanical {
            kept_factors: factors,
            dyn_out,
            kept,
            bends,
            baumgarte,
            stabilisation,
            layout,
            ..
        } = self;
        if bends.iter().any(|b| b.cone.is_some()) {
            return Ok(false);
        }
        let Layout { coordinates: n, multipliers: m, .. } = *layout;
        factors.ready(dyn_out, n, kept, bends)?;
        let order = factors.order(n);
        let alpha = *baumgarte;
        let mut block = std::mem::take(&mut factors.block);
        block.resize(order, [0.0; COLUMNS]);
        for first in (0..width).step_by(COLUMNS) {
            let columns = (width - first).min(COLUMNS);
            let row = |r: usize| &partials[r * width + first..r * width + first + columns];
            for (i, out) in block[..n].iter_mut().enumerate() {
                for (o, v) in out.iter_mut().zip(row(i)) {
                    *o = -v;
                }
                out[columns..].fill(0.0);
            }
            for (out, &c) in block[n..].iter_mut().zip(factors.rows()) {
                let of = |b: usize| row(n + b * m + c);
                // The partials of the row the accelerations satisfy, stabilisation included.
                match stabilisation[c] {
                    Stabilisation::Position => {
                        // c̃'s partials, then Φ's and Φ̇'s.
                        let (value, position, rate) = (of(0), of(1), of(2));
                        for (k, o) in out[..columns].iter_mut().enumerate() {
                            *o = -(value[k] + 2.0 * alpha * rate[k] + alpha * alpha * position[k]);
                        }
                    }
                    Stabilisation::Velocity => {
                        // c̃'s partials, then the velocity row's residual's.
                        let (value, residual) = (of(0), of(1));
                        for (k, o) in out[..columns].iter_mut().enumerate() {
                            *o = -(value[k] + alpha * residual[k]);
                        }
                    }
                }
                out[columns..].fill(0.0);
            }
            factors.solve_columns(n, &mut block);
            for (i, solved) in block[..n].iter().enumerate() {
                put(i, first, &solved[..columns]);
            }
        }
        factors.block = block;
        Ok(true)
    }

    /// Solves [M −Jᵀ; J 0]·∂(q̈, λ) = −∂(r, c̃) for each column of `partials` (the rows of
    /// the partials program's layout, `width` columns each, row-major), c̃ the kept rows as
    /// the accelerations were solved with them, Baumgarte's terms included, and hands each
    /// column's ∂(q̈, λ) to `put` (n + m: a multiplier not kept has none, 0). `solution` holds
    /// q̈ and λ at the state the dynamics program was last evaluated at.
    fn solve_partials(
        &mut self,
        partials: &[f64],
        width: usize,
        solution: &[f64],
        put: impl FnMut(usize, &[f64]),
    ) -> Result<(), FaultKind> {
        self.solve_partials_of(width, |row, k| partials[row * width + k], solution, put)
    }

    /// [`Mechanical::solve_partials`] with column `k`'s entry in row `row` given by `entry`:
    /// columns from two programs solved in one pass.
    fn solve_partials_of(
        &mut self,
        width: usize,
        entry: impl Fn(usize, usize) -> f64,
        solution: &[f64],
        mut put: impl FnMut(usize, &[f64]),
    ) -> Result<(), FaultKind> {
        // The fields apart, borrowed side by side: taking the factors out and putting them
        // back moved their 192 bytes twice per stage.
        let Mechanical {
            kept_factors: factors,
            dyn_out,
            kept,
            bends,
            baumgarte,
            stabilisation,
            layout,
            ..
        } = self;
        let Layout { coordinates: n, multipliers: m, .. } = *layout;
        // One LU serves every column: the accelerations' own where they were solved by LU on
        // the heap at this state, else one made here (the exact Jacobian of M alone past the
        // stack's order solves with the accelerations' LDLᵀ factors instead, in
        // `exact_jacobian`). Only the kept rows are factored: an open contact's multiplier is
        // 0, and its identity row would only make the factorization larger (a rimless wheel on
        // one spoke: five rows rather than nineteen).
        factors.ready(dyn_out, n, kept, bends)?;
        let order = factors.order(n);
        let alpha = *baumgarte;
        // In space a slipping contact's factors f_i = −μ·γ_i/‖γ_T‖ move with the state too:
        // the force −J_iᵀ·f_i·λ adds −J_iᵀ·λ·∂f_i/∂x to ∂r/∂x, with ∂f_i/∂γ_j =
        // −μ·(δ_ij − d_i·d_j)/‖γ_T‖ and ∂γ_j/∂x the partials of the rows' rates. Within the band,
        // where the decided direction is held, the factors are constant.
        let mut turning: Vec<(usize, f64, [f64; 2], [usize; 2])> = Vec::new();
        for bend in bends.iter() {
            let Some(cone) = bend.cone else { continue };
            let (rate, d) = cone.aim(dyn_out, *layout);
            let size = crate::linalg::size2(rate[0], rate[1]);
            if size <= cone.band {
                continue;
            }
            let i = cone.which;
            let df = [0, 1].map(|j| -cone.mu * (f64::from(u8::from(i == j)) - d[i] * d[j]) / size);
            turning.push((bend.tangent, solution[n + bend.normal], df, cone.rates));
        }
        let (mut reduced, mut block, mut column) = (
            std::mem::take(&mut factors.reduced),
            std::mem::take(&mut factors.block),
            std::mem::take(&mut factors.column),
        );
        let rows = factors.rows();
        // Every entry of these is written before it is read, column by column: they are
        // resized, not cleared.
        reduced.resize(order, 0.0);
        // The columns are solved four at a time, side by side: the same bits as one by one (a
        // last block's unused columns are zeros, solved and dropped).
        block.resize(order, [0.0; COLUMNS]);
        column.resize(n + m, 0.0);
        for first in (0..width).step_by(COLUMNS) {
            let columns = (width - first).min(COLUMNS);
            for (c, k) in (first..first + columns).enumerate() {
                for i in 0..n {
                    reduced[i] = -entry(i, k);
                }
                for (r, &c) in rows.iter().enumerate() {
                    let row = |block: usize| entry(n + block * m + c, k);
                    // The partials of the row the accelerations satisfy, stabilisation included.
                    let stabilised = match stabilisation[c] {
                        Stabilisation::Position => {
                            row(0) + 2.0 * alpha * row(2) + alpha * alpha * row(1)
                        }
                        Stabilisation::Velocity => row(0) + alpha * row(1),
                    };
                    reduced[n + r] = -stabilised;
                }
                for &(tangent, lambda, df, rates) in &turning {
                    let rate = |r: usize| entry(n + m + rates[r], k);
                    let change = df[0] * rate(0) + df[1] * rate(1);
                    let base = n * n + n + tangent * (n + 3);
                    for i in 0..n {
                        reduced[i] += dyn_out[base + i] * lambda * change;
                    }
                }
                for (row, v) in block.iter_mut().zip(reduced.iter()) {
                    row[c] = *v;
                }
            }
            for row in block.iter_mut() {
                row[columns..].fill(0.0);
            }
            factors.solve_columns(n, &mut block);
            for (c, k) in (first..first + columns).enumerate() {
                for (i, v) in column[..n].iter_mut().enumerate() {
                    *v = block[i][c];
                }
                column[n..].fill(0.0);
                for (r, &kept) in rows.iter().enumerate() {
                    column[n + kept] = block[n + r][c];
                }
                put(k, &column);
            }
        }
        (factors.reduced, factors.block, factors.column) = (reduced, block, column);
        Ok(())
    }
}

impl Canonical {
    /// ∂(q̇, ṗ)/∂(q, p), row-major, into `jac`; false without a partials program.
    ///
    /// With q̇ = v(q, p) solving p = M(q)·v + b(q) and ṗ = g(q, v): ∂v/∂p = M⁻¹,
    /// ∂v/∂q = −M⁻¹·∂p/∂q (v held), and the chain rule through v for ṗ.
    pub(super) fn exact_jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        jac: &mut [f64],
    ) -> Result<bool, FaultKind> {
        let n = self.inner.layout.coordinates;
        if self.partials.is_none() {
            return Ok(false);
        }
        self.velocities(t, y)?;
        let rates = std::mem::take(&mut self.rates);
        self.set_input(t, &y[..n], Some(&rates));
        self.rates = rates;
        if let Some(tape) = self.partials.as_mut() {
            tape.eval(&self.input, &mut self.partials_out);
        }
        check_finite(&self.partials_out, |_| NonFiniteAt::Partials)?;
        let inner = &mut self.inner;
        inner.system.copy_from(&inner.backup);
        linalg::lu_in_place(&mut inner.system, &mut inner.pivots)?;
        let (momentum_q, force_q, force_v) = (
            &self.partials_out[..n * n],
            &self.partials_out[n * n..2 * n * n],
            &self.partials_out[2 * n * n..],
        );
        let width = 2 * n;
        // The top rows: ∂v/∂(q, p) = M⁻¹·[−∂p/∂q | I], a column at a time.
        let mut column = vec![0.0; n];
        for k in 0..width {
            for (i, slot) in column.iter_mut().enumerate() {
                *slot =
                    if k < n { -momentum_q[i * n + k] } else { f64::from(u8::from(i + n == k)) };
            }
            linalg::lu_solve(&inner.system, &inner.pivots, &mut column);
            for i in 0..n {
                jac[i * width + k] = column[i];
            }
        }
        for i in 0..n {
            for k in 0..width {
                let mut acc = if k < n { force_q[i * n + k] } else { 0.0 };
                for j in 0..n {
                    acc += force_v[i * n + j] * jac[j * width + k];
                }
                jac[(n + i) * width + k] = acc;
            }
        }
        check_finite(jac, |_| NonFiniteAt::Jacobian)?;
        Ok(true)
    }
}

impl ChainFactored {
    /// −M⁻¹ times `count` columns (`read(row, column)`, a row per coordinate) by the sweep at
    /// the state the factors were run at ([`negated_in_blocks`]).
    fn solve_negated(
        &mut self,
        n: usize,
        count: usize,
        block: &mut Vec<[f64; COLUMNS]>,
        read: impl Fn(usize, usize) -> f64,
        put: impl FnMut(usize, usize, &[f64]),
    ) {
        let (chain, factors, work) = (&self.chain, &self.out[n..], &mut self.work);
        negated_in_blocks(n, count, block, read, |b| chain.solve_columns(factors, b, work), put);
    }
}

/// Solves M·x = −b for `count` columns b (`read(row, column)`, a row per coordinate)
/// [`COLUMNS`] side by side with `solve` (a block in, its solution out), each block's solved
/// rows going to `put(row, first column, values)`: the partials are read and the results
/// written a row of a block at a time rather than a column at a time (strided both ways, a
/// fifth of a 32-link chain's Jacobian).
fn negated_in_blocks(
    n: usize,
    count: usize,
    block: &mut Vec<[f64; COLUMNS]>,
    read: impl Fn(usize, usize) -> f64,
    mut solve: impl FnMut(&mut [[f64; COLUMNS]]),
    mut put: impl FnMut(usize, usize, &[f64]),
) {
    block.resize(n, [0.0; COLUMNS]);
    for first in (0..count).step_by(COLUMNS) {
        let columns = (count - first).min(COLUMNS);
        for (i, row) in block.iter_mut().enumerate() {
            for (c, v) in row[..columns].iter_mut().enumerate() {
                *v = -read(i, first + c);
            }
            row[columns..].fill(0.0);
        }
        solve(block);
        for (i, row) in block.iter().enumerate() {
            put(i, first, &row[..columns]);
        }
    }
}
