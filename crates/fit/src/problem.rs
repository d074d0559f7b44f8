//! The scene loaded for a fit: its free unknowns, its measured columns lowered with their
//! partials, and the residuals and their exact Jacobian at given values of the unknowns, from
//! one variational run per shot.

use cas::ExprId;
use lang::{Diagnostic, Span};
use numeric::Tape;
use sim::variational::{self, End, Refusal};
use sim::Mechanical;

use crate::data::Table;
use crate::{Error, Free, Options};

/// What a free unknown is.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A parameter, by its slot.
    Parameter(usize),
    /// A start value: the coordinate (its index among the scene's declared ones), its state
    /// slot, and whether it is the rate.
    Start { coordinate: usize, slot: usize, rate: bool },
}

/// A free unknown: its name as the user wrote it and what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Unknown {
    pub name: String,
    pub kind: Kind,
}

/// The residuals at some values of the unknowns and their derivatives.
pub struct Evaluation {
    /// Weighted residuals (model − data)/σ, column after column as [`Problem::residual_index`]
    /// orders them.
    pub residuals: Vec<f64>,
    /// ∂residuals/∂(θ, z), row-major, `residuals.len()` × [`Problem::width`].
    pub jacobian: Vec<f64>,
    /// The shots' continuity gaps x(T⁻) − z at each inner shot boundary (2n each).
    pub gaps: Vec<f64>,
    /// Their derivatives, row-major, `gaps.len()` × [`Problem::width`].
    pub gap_jacobian: Vec<f64>,
    /// The model's value of each measured column at each row of the table.
    pub model: Vec<Vec<f64>>,
    /// Integrator steps, over every shot.
    pub steps: usize,
}

pub struct Problem {
    mechanical: Mechanical,
    prepared: engine::numbers::Prepared,
    overrides: simulation::Overrides,
    run: sim::Settings,
    pub unknowns: Vec<Unknown>,
    /// The free parameters' slots, in the order of the sensitivity program's columns.
    free_slots: Vec<usize>,
    observation: Tape,
    /// Whether each column names an acceleration or a reaction, whose derivative comes from
    /// the accelerations' system at each row.
    unknown_columns: Vec<bool>,
    /// The series-driven inputs' slots and series, filled in at each data time.
    signals: Vec<(usize, sim::Series)>,
    pub table: Table,
    /// 1/σ per column.
    pub weights: Vec<f64>,
    /// The data rows each shot starts at (the first is 0).
    pub shot_starts: Vec<usize>,
    /// Whether the scene's start is solved by kept constraints, so that its derivative is
    /// taken by differences of that solve.
    start_solved: bool,
    pub state_names: Vec<String>,
    names: FaultContext,
}

/// What a fault's words name.
struct FaultContext {
    state: Vec<String>,
    constraints: Vec<String>,
    parameters: Vec<String>,
    angle_oriented_bodies: Vec<String>,
    contacts: Vec<String>,
}

/// The step of the central differences of the start's solve, relative to the unknown.
const START_DIFFERENCE: f64 = 1e-6;

impl Problem {
    pub fn load(source: &str, options: &Options, table: Table) -> Result<Problem, Error> {
        let resolved = simulation::Resolved::new(source, &options.run);
        let mut settings = resolved.settings(&options.run)?;
        if settings.hold.is_some() {
            return Err(engine::Error::Input(
                "fit takes inputs driven continuously or by a time series, not held between \
                 samples (`hold`)"
                    .into(),
            )
            .into());
        }
        let method = settings.method;
        if !method.is_explicit() || method.is_symplectic() {
            return Err(engine::Error::Input(format!(
                "fit integrates the sensitivities on an explicit method's steps; {} is not one \
                 (use dop853, the default, or another of the explicit methods)",
                method.name()
            ))
            .into());
        }
        let last = *table.times.last().expect("a table has rows");
        if last <= 0.0 {
            let d = Diagnostic::error(
                table.rows[table.rows.len() - 1],
                "no measurement after the start",
            )
            .with_label("the last time")
            .with_hint("a fit compares a motion with measurements after t = 0");
            return Err(Error::Data(vec![d]));
        }
        if let Some(k) = table.times.iter().position(|t| *t < 0.0) {
            let d = Diagnostic::error(table.rows[k], "a time before the start of the run, t = 0")
                .with_label("negative")
                .with_hint("the scene's start is at t = 0: shift the times so that they begin there or after");
            return Err(Error::Data(vec![d]));
        }
        settings.until = last;
        settings.events.clear();
        settings.stops.clear();
        let simulation::Loaded { mut prepared, outputs, .. } = resolved.load(&settings)?;
        if !prepared.contacts.is_empty() {
            return Err(engine::Error::Input(format!(
                "fit does not take contacts yet: the scene has {} (the sensitivities are not \
                 carried across an impact)",
                prepared.contact_names().join(", ")
            ))
            .into());
        }
        let columns = column_expressions(&mut prepared, &table)?;
        let set_exprs = simulation::set_expressions(&mut prepared, &settings.sets)?;
        let overrides = simulation::overrides(&prepared, &settings.sets, &set_exprs)?;
        prepared.set_parameter_overrides(&overrides.params);
        let unknowns = unknowns(&prepared, &options.free)?;
        let free_slots: Vec<usize> = unknowns
            .iter()
            .filter_map(|u| match u.kind {
                Kind::Parameter(slot) => Some(slot),
                Kind::Start { .. } => None,
            })
            .collect();
        let (parameters, _) = simulation::start(&mut prepared, &overrides, &[])?;
        let dynamics_exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &dynamics_exprs)?;
        let observed =
            prepared.lower(&prepared.observation_inputs(), &prepared.extra[..outputs.len()])?;
        let partials = prepared.partials_program()?;
        let signals = simulation::drive_signals(&prepared, &settings)?;
        let mechanical =
            Mechanical::new(prepared.layout, Tape::new(dynamics), Tape::new(observed), parameters)
                .with_kinds(prepared.stabilisation())
                .with_signals(signals.clone());
        // A long chain's q̈ and its sensitivities' columns by the recursive form's sweep.
        let mechanical = match prepared.recursive()? {
            Some(recursive) => mechanical.with_chain(recursive),
            None => mechanical,
        };
        let integrand = simulation::Integrand::new(&mut prepared, mechanical, method)?;
        let simulation::Integrand::Mechanical(mut mechanical) = integrand else {
            unreachable!("an explicit method integrates (q, q̇)")
        };
        mechanical.set_partials(Tape::new(partials));
        if !free_slots.is_empty() {
            let program = prepared.sensitivity_program(&free_slots)?;
            mechanical.set_sensitivities(Tape::new(program), free_slots.len());
        }
        let observation = Tape::new(prepared.observation_partials(&columns, &free_slots)?);
        let unknown_columns = columns.iter().map(|e| prepared.names_unknowns(*e)).collect();
        let weights = weights(&table, &options.noise)?;
        let kept = prepared.layout.multipliers > 0;
        let shots = options.shots.max(1);
        let shot_starts = shot_starts(&table, shots)?;
        let start_solved = kept;
        let mut run = simulation::run_settings(&settings, 0);
        run.until = settings.until;
        let names = FaultContext {
            state: prepared.state_names(),
            constraints: prepared.kept_constraint_names(),
            parameters: prepared.parameter_slot_names(),
            angle_oriented_bodies: simulation::angle_oriented_bodies(&prepared.derivation.model),
            contacts: prepared.contact_names(),
        };
        Ok(Problem {
            mechanical,
            state_names: prepared.state_names(),
            prepared,
            overrides,
            run,
            unknowns,
            free_slots,
            observation,
            unknown_columns,
            signals,
            table,
            weights,
            shot_starts,
            start_solved,
            names,
        })
    }

    /// The number of the unknowns besides the shots' starts.
    pub fn free(&self) -> usize {
        self.unknowns.len()
    }

    /// The size of the state.
    pub fn size(&self) -> usize {
        2 * self.prepared.layout.coordinates
    }

    /// All the unknowns: the free ones, then each inner shot's start state.
    pub fn width(&self) -> usize {
        self.free() + self.size() * (self.shot_starts.len() - 1)
    }

    /// The free unknowns' values in the scene (with the run's `--set` values in place), or
    /// those `free` gives.
    pub fn initial(&mut self, free: &[Free]) -> Result<Vec<f64>, Error> {
        let (parameters, state) =
            simulation::start(&mut self.prepared, &self.overrides, &[]).map_err(Error::from)?;
        Ok(self
            .unknowns
            .iter()
            .zip(free)
            .map(|(u, f)| {
                f.start.unwrap_or(match u.kind {
                    Kind::Parameter(slot) => parameters[slot],
                    Kind::Start { slot, .. } => state[slot],
                })
            })
            .collect())
    }

    /// The parameters and the start at the free unknowns' values `theta`.
    fn start(&mut self, theta: &[f64]) -> Result<(Vec<f64>, Vec<f64>), engine::Error> {
        let mut given = Vec::new();
        let mut values = simulation::Overrides {
            params: self.overrides.params.clone(),
            coords: self.overrides.coords.clone(),
        };
        for (u, &v) in self.unknowns.iter().zip(theta) {
            match u.kind {
                Kind::Parameter(slot) => {
                    values.params.retain(|(i, _)| *i != slot);
                    given.push((slot, v));
                }
                Kind::Start { coordinate, rate, .. } => {
                    let pool = &mut self.prepared.derivation.model.pool;
                    let e = number(pool, v).ok_or_else(|| {
                        engine::Error::Input(format!("`{}` = {v} is not a finite number", u.name))
                    })?;
                    values.coords.retain(|(i, r, _)| !(*i == coordinate && *r == rate));
                    values.coords.push((coordinate, rate, e));
                }
            }
        }
        simulation::start(&mut self.prepared, &values, &given)
    }

    /// ∂x(0)/∂θ, row-major 2n × k: exact where the scene writes the start (the parameters'
    /// share through `start_sensitivity`, a start value's own column the unit vector), central
    /// differences of the start's solve where kept constraints solve it.
    fn start_derivative(&mut self, theta: &[f64], parameters: &[f64]) -> Result<Vec<f64>, Error> {
        let (size, k) = (self.size(), self.free());
        let mut out = vec![0.0; size * k];
        if self.start_solved {
            for j in 0..k {
                let h = START_DIFFERENCE * theta[j].abs().max(1.0);
                let mut at = theta.to_vec();
                at[j] = theta[j] + h;
                let (_, up) = self.start(&at)?;
                at[j] = theta[j] - h;
                let (_, down) = self.start(&at)?;
                for i in 0..size {
                    out[i * k + j] = (up[i] - down[i]) / (2.0 * h);
                }
            }
            return Ok(out);
        }
        if !self.free_slots.is_empty() {
            let mut coords = self.overrides.coords.clone();
            for u in &self.unknowns {
                if let Kind::Start { coordinate, rate, .. } = u.kind {
                    let pool = &mut self.prepared.derivation.model.pool;
                    coords.retain(|(i, r, _)| !(*i == coordinate && *r == rate));
                    // The start value is an unknown of its own: constant in the parameters.
                    coords.push((coordinate, rate, pool.zero()));
                }
            }
            let by_parameters =
                self.prepared.start_sensitivity(parameters, &coords, &self.free_slots)?;
            let kp = self.free_slots.len();
            let mut p = 0;
            for (j, u) in self.unknowns.iter().enumerate() {
                if let Kind::Parameter(_) = u.kind {
                    for i in 0..size {
                        out[i * k + j] = by_parameters[i * kp + p];
                    }
                    p += 1;
                }
            }
        }
        for (j, u) in self.unknowns.iter().enumerate() {
            if let Kind::Start { slot, .. } = u.kind {
                out[slot * k + j] = 1.0;
            }
        }
        Ok(out)
    }

    /// The residuals and their Jacobian at `unknowns` = (θ, z): the free unknowns, then each
    /// inner shot's start.
    pub fn evaluate(&mut self, unknowns: &[f64]) -> Result<Evaluation, Error> {
        let (size, k, width) = (self.size(), self.free(), self.width());
        let theta = &unknowns[..k];
        let (parameters, start) = self.start(theta)?;
        self.mechanical.set_parameters(&parameters);
        let x0 = self.start_derivative(theta, &parameters)?;
        let rows = self.table.times.len();
        let columns = self.table.columns.len();
        let mut model = vec![vec![0.0; rows]; columns];
        // Per row: the state and dx/d(θ, z) there, 2n × width.
        let mut states: Vec<(Vec<f64>, Vec<f64>)> = Vec::with_capacity(rows);
        let shots = self.shot_starts.len();
        let mut gaps = Vec::new();
        let mut gap_jacobian = Vec::new();
        let mut steps = 0;
        let kp = self.free_slots.len();
        for s in 0..shots {
            let first = self.shot_starts[s];
            let end_row = self.shot_starts.get(s + 1).copied().unwrap_or(rows);
            let t0 = if s == 0 { 0.0 } else { self.table.times[first] };
            let t1 =
                if s + 1 < shots { self.table.times[end_row] } else { self.table.times[rows - 1] };
            // The shot's start and its derivative by (θ, z), 2n × width.
            let (y0, d0) = if s == 0 {
                let mut d = vec![0.0; size * width];
                for i in 0..size {
                    d[i * width..i * width + k].copy_from_slice(&x0[i * k..(i + 1) * k]);
                }
                (start.clone(), d)
            } else {
                let at = k + (s - 1) * size;
                let mut d = vec![0.0; size * width];
                for i in 0..size {
                    d[i * width + at + i] = 1.0;
                }
                (unknowns[at..at + size].to_vec(), d)
            };
            // S carried by the run is the parameters' share from the shot's start; the start's
            // own (and z's) comes through Φ.
            let sensitivities = (kp > 0).then(|| vec![0.0; size * kp]);
            let mut times: Vec<f64> = self.table.times[first..end_row].to_vec();
            if s + 1 < shots {
                times.push(t1);
            }
            let mut run = self.run.clone();
            run.start = t0;
            run.until = t1.max(t0);
            // The residuals' derivatives are those of the runs' own steps: the step control
            // need not hold Φ and S to the tolerance too, only the state.
            let step_control = variational::StepControl::State;
            let options =
                variational::Options { sensitivities, times, step_control, ..Default::default() };
            let transition =
                variational::transition_with(&mut self.mechanical, &y0, &run, End::Time, &options)
                    .map_err(|r| self.refused(r))?;
            steps += transition.steps;
            for sample in &transition.samples {
                let mut d = mat_mul(&sample.matrix, &d0, size, size, width);
                if let Some(sp) = &sample.sensitivities {
                    let mut p = 0;
                    for (j, u) in self.unknowns.iter().enumerate() {
                        if let Kind::Parameter(_) = u.kind {
                            for i in 0..size {
                                d[i * width + j] += sp[i * kp + p];
                            }
                            p += 1;
                        }
                    }
                }
                states.push((sample.state.clone(), d));
            }
            if s + 1 < shots {
                let (end_state, d_end) = states.pop().expect("the shot's end was recorded");
                let at = k + s * size;
                for i in 0..size {
                    gaps.push(end_state[i] - unknowns[at + i]);
                    let mut row = d_end[i * width..(i + 1) * width].to_vec();
                    row[at + i] -= 1.0;
                    gap_jacobian.extend(row);
                }
            }
        }
        debug_assert_eq!(states.len(), rows);
        let n = self.prepared.layout.coordinates;
        let m = self.prepared.layout.multipliers;
        let unknowns_size = n + m;
        let outputs_per = 1 + size + unknowns_size + kp;
        let mut inputs = vec![0.0; 1 + 3 * n + m + parameters.len()];
        let mut out = vec![0.0; columns * outputs_per];
        let mut residuals = Vec::with_capacity(self.table.measured());
        let mut jacobian = Vec::with_capacity(self.table.measured() * width);
        let mut per_column: Vec<Vec<(f64, Vec<f64>)>> = vec![Vec::new(); columns];
        let wanted = self.unknown_columns.iter().any(|u| *u);
        // Which column of the sensitivity program each unknown's own parameter share is.
        let mut p = 0;
        let by_parameter: Vec<Option<usize>> = (0..width)
            .map(|j| match self.unknowns.get(j).map(|u| &u.kind) {
                Some(Kind::Parameter(_)) => {
                    p += 1;
                    Some(p - 1)
                }
                _ => None,
            })
            .collect();
        let mut solution = vec![0.0; unknowns_size];
        let mut solution_rate = vec![0.0; unknowns_size * width];
        for (r, (state, d)) in states.iter().enumerate() {
            let t = self.table.times[r];
            inputs[0] = t;
            inputs[1..1 + size].copy_from_slice(state);
            if wanted {
                let found = self
                    .mechanical
                    .solution_derivative(
                        t,
                        state,
                        d,
                        &by_parameter,
                        &mut solution,
                        &mut solution_rate,
                    )
                    .map_err(|kind| {
                        let fault = sim::Fault { time: t, state: state.clone(), kind };
                        self.refused(Refusal::Fault(fault))
                    })?;
                debug_assert!(found, "the problem has its partials and sensitivities");
                inputs[1 + size..1 + size + unknowns_size].copy_from_slice(&solution);
            }
            let slots = &mut inputs[1 + 3 * n + m..];
            slots.copy_from_slice(&parameters);
            for (slot, series) in &self.signals {
                slots[*slot] = series.at(t);
            }
            self.observation.eval(&inputs, &mut out);
            for c in 0..columns {
                let row = &out[c * outputs_per..(c + 1) * outputs_per];
                model[c][r] = row[0];
                let Some(measured) = self.table.values[c][r] else { continue };
                let w = self.weights[c];
                let mut grad = vec![0.0; width];
                for (i, dh) in row[1..1 + size].iter().enumerate() {
                    if *dh != 0.0 {
                        for (g, dx) in grad.iter_mut().zip(&d[i * width..(i + 1) * width]) {
                            *g += dh * dx;
                        }
                    }
                }
                if self.unknown_columns[c] {
                    let by_unknowns = &row[1 + size..1 + size + unknowns_size];
                    for (i, dh) in by_unknowns.iter().enumerate().filter(|(_, dh)| **dh != 0.0) {
                        let rates = &solution_rate[i * width..(i + 1) * width];
                        for (g, ds) in grad.iter_mut().zip(rates) {
                            *g += dh * ds;
                        }
                    }
                }
                for (j, p) in by_parameter.iter().enumerate() {
                    if let Some(p) = p {
                        grad[j] += row[1 + size + unknowns_size + p];
                    }
                }
                grad.iter_mut().for_each(|g| *g *= w);
                per_column[c].push((w * (row[0] - measured), grad));
            }
        }
        for column in per_column {
            for (residual, grad) in column {
                residuals.push(residual);
                jacobian.extend(grad);
            }
        }
        if let Some(bad) = residuals.iter().position(|r| !r.is_finite()) {
            return Err(engine::Error::Numeric(format!(
                "a residual is not a finite number (the {}th)",
                bad + 1
            ))
            .into());
        }
        Ok(Evaluation { residuals, jacobian, gaps, gap_jacobian, model, steps })
    }

    /// The inner shots' start states as the data give them where they measure every state
    /// component, else as a run from the scene's start at `theta` gives them.
    pub fn shot_guesses(&mut self, theta: &[f64]) -> Result<Vec<f64>, Error> {
        let size = self.size();
        if self.shot_starts.len() == 1 {
            return Ok(Vec::new());
        }
        let measured: Vec<Option<usize>> =
            self.state_names.iter().map(|name| self.table.column(name)).collect();
        let mut guesses = Vec::new();
        let single: Vec<f64> = {
            let mut at = theta.to_vec();
            at.extend(vec![0.0; size * (self.shot_starts.len() - 1)]);
            let starts = std::mem::replace(&mut self.shot_starts, vec![0]);
            let evaluated = self.evaluate_states(&at[..self.free()]);
            self.shot_starts = starts;
            evaluated?
        };
        let n = size / 2;
        for &row in &self.shot_starts[1..] {
            for (i, column) in measured.iter().enumerate() {
                let from_data = column.and_then(|c| self.table.values[c][row]);
                // A rate not measured, of a coordinate that is: the slope of the data there.
                let slope = (i >= n)
                    .then(|| measured[i - n])
                    .flatten()
                    .and_then(|c| slope(&self.table.times, &self.table.values[c], row));
                guesses.push(from_data.or(slope).unwrap_or(single[row * size + i]));
            }
        }
        Ok(guesses)
    }

    /// The state at every data row of one shot from the scene's start at `theta`, row after
    /// row; an unknown a run could not reach keeps the start's value.
    fn evaluate_states(&mut self, theta: &[f64]) -> Result<Vec<f64>, Error> {
        let size = self.size();
        let (parameters, start) = self.start(theta)?;
        self.mechanical.set_parameters(&parameters);
        let mut run = self.run.clone();
        run.start = 0.0;
        let times = self.table.times.clone();
        let options = variational::Options { times, ..Default::default() };
        let rows = self.table.times.len();
        match variational::transition_with(&mut self.mechanical, &start, &run, End::Time, &options)
        {
            Ok(t) => Ok(t.samples.iter().flat_map(|s| s.state.clone()).collect()),
            Err(_) => Ok(start.iter().copied().cycle().take(rows * size).collect()),
        }
    }

    /// A variational run's refusal in words.
    fn refused(&self, refusal: Refusal) -> Error {
        let names = &self.names;
        let e = match refusal {
            Refusal::Fault(f) => {
                let words = simulation::FaultNames {
                    method: self.run.method,
                    state: &names.state,
                    constraints: &names.constraints,
                    parameters: &names.parameters,
                    angle_oriented_bodies: &names.angle_oriented_bodies,
                    contacts: &names.contacts,
                };
                engine::Error::Numeric(words.report(&f, "a fit's run"))
            }
            Refusal::SensitivitiesWithFriction => engine::Error::Input(
                "fit does not take Coulomb friction yet: the sensitivities to μ are not carried"
                    .into(),
            ),
            other => engine::Error::Numeric(format!("the fit's run was refused: {other:?}")),
        };
        e.into()
    }
}

/// The measured columns as scene expressions, each resolved against the scene; a column that
/// names none, or names what a run's state does not give, is a diagnostic at its header.
fn column_expressions(
    prepared: &mut engine::numbers::Prepared,
    table: &Table,
) -> Result<Vec<ExprId>, Error> {
    let mut exprs = Vec::with_capacity(table.columns.len());
    let mut diagnostics = Vec::new();
    for column in &table.columns {
        let shift =
            |span: Span| Span::new(span.start + column.span.start, span.end + column.span.start);
        match prepared.derivation.model.resolve_expression(&column.name) {
            Ok(model::Value::Scalar(e)) => {
                let e = prepared.derivation.expand_quantities(e, false);
                let e = prepared.with_laws(e);
                exprs.push(e);
            }
            Ok(value) => diagnostics.push(
                Diagnostic::error(
                    column.span,
                    format!("the column `{}` is {}, not a number", column.name, value.kind_name()),
                )
                .with_label("not a scalar")
                .with_hint("measure one component a column: `bob.position[1]`"),
            ),
            Err(found) => {
                for mut d in found {
                    d.span = shift(d.span);
                    d.related = d.related.into_iter().map(|(s, l)| (shift(s), l)).collect();
                    if d.message.is_empty() {
                        d.message =
                            format!("the column `{}` names no scene expression", column.name);
                    }
                    diagnostics.push(d);
                }
            }
        }
    }
    if diagnostics.is_empty() {
        Ok(exprs)
    } else {
        Err(Error::Data(diagnostics))
    }
}

/// The free unknowns by name: a parameter the scene declares (not a derived one), or a start
/// value `x(0)` or `x'(0)` of a remaining coordinate.
fn unknowns(prepared: &engine::numbers::Prepared, free: &[Free]) -> Result<Vec<Unknown>, Error> {
    let model = &prepared.derivation.model;
    let plan = &prepared.parameter_plan;
    let mut out: Vec<Unknown> = Vec::new();
    for f in free {
        let name = f.name.trim();
        let refuse = |message: String, hint: String| {
            let d =
                Diagnostic::error(f.span, message).with_label("not a free unknown").with_hint(hint);
            Error::Argument { flag: "--free", text: f.text.clone(), diagnostics: vec![d] }
        };
        if out.iter().any(|u| u.name == name) {
            return Err(refuse(
                format!("`{name}` is freed twice"),
                "name each unknown once".into(),
            ));
        }
        let options = || {
            let mut names: Vec<String> = plan
                .names()
                .enumerate()
                .filter(|(i, _)| !plan.is_derived(*i))
                .map(|(_, n)| n.to_string())
                .collect();
            for c in prepared.coordinate_names() {
                names.push(format!("{c}(0)"));
                names.push(format!("{c}'(0)"));
            }
            format!("free parameters and start values: {}", names.join(", "))
        };
        if let Some(base) = name.strip_suffix("(0)") {
            let (coord, rate) = match base.strip_suffix('\'') {
                Some(c) => (c.trim(), true),
                None => (base.trim(), false),
            };
            let Some(i) = model.coords.iter().position(|c| c.name == coord) else {
                return Err(refuse(
                    format!("`{coord}` is not a coordinate of the scene"),
                    options(),
                ));
            };
            let Some(slot) =
                prepared.derivation.coords.iter().position(|s| *s == model.coords[i].sym)
            else {
                return Err(refuse(
                    format!("`{coord}` is fixed by a constraint: its start follows the others'"),
                    options(),
                ));
            };
            let n = prepared.derivation.coords.len();
            let slot = if rate { n + slot } else { slot };
            out.push(Unknown {
                name: name.to_string(),
                kind: Kind::Start { coordinate: i, slot, rate },
            });
            continue;
        }
        match plan.names().position(|n| n == name) {
            Some(i) if plan.is_derived(i) => {
                return Err(refuse(
                    format!("`{name}` is derived from other parameters: {}", plan.derived_error(i)),
                    options(),
                ));
            }
            Some(i) if i < model.params.len() => {
                out.push(Unknown { name: name.to_string(), kind: Kind::Parameter(i) })
            }
            _ => {
                let hint = if model.coords.iter().any(|c| c.name == name.trim_end_matches('\'')) {
                    format!("a start value is written with (0): `{name}(0)`")
                } else {
                    options()
                };
                return Err(refuse(
                    format!("`{name}` is neither a parameter nor a start value of the scene"),
                    hint,
                ));
            }
        }
    }
    if out.is_empty() {
        return Err(
            engine::Error::Input("nothing is free: name an unknown with --free".into()).into()
        );
    }
    Ok(out)
}

/// 1/σ per column: the noise levels given (`--noise theta=0.01`), 1 for the others.
fn weights(table: &Table, noise: &[(String, f64)]) -> Result<Vec<f64>, Error> {
    let mut weights = vec![1.0; table.columns.len()];
    for (name, sigma) in noise {
        let Some(c) = table.column(name) else {
            let names: Vec<&str> = table.columns.iter().map(|c| c.name.as_str()).collect();
            return Err(engine::Error::Input(format!(
                "--noise {name}: the data have no column `{name}`; one of {}",
                names.join(", ")
            ))
            .into());
        };
        if !(sigma.is_finite() && *sigma > 0.0) {
            return Err(engine::Error::Input(format!(
                "--noise {name}={sigma}: a noise level is a positive number, in the column's unit"
            ))
            .into());
        }
        weights[c] = 1.0 / sigma;
    }
    Ok(weights)
}

/// The rows each of `shots` shots starts at: the table cut into spans of equal time, each
/// at the first row at or after its start time, each with a row of its own at least.
fn shot_starts(table: &Table, shots: usize) -> Result<Vec<usize>, Error> {
    let rows = table.times.len();
    let (first, last) = (0.0, table.times[rows - 1]);
    let mut starts = vec![0];
    for s in 1..shots {
        let at = first + (last - first) * s as f64 / shots as f64;
        let row = table.times.partition_point(|t| *t < at);
        if row > *starts.last().expect("one start") && row < rows - 1 {
            starts.push(row);
        }
    }
    if starts.len() < shots {
        return Err(engine::Error::Input(format!(
            "--shots {shots}: the data's {rows} rows cannot be cut into {shots} shots of a row \
             each and more"
        ))
        .into());
    }
    Ok(starts)
}

/// `v` as an exact number of the pool: the shortest decimal that gives its bits back.
fn number(pool: &mut cas::Pool, v: f64) -> Option<ExprId> {
    if !v.is_finite() {
        return None;
    }
    let digits = format!("{}", v.abs());
    let q = cas::number::parse_decimal(&digits)?;
    let q = if v < 0.0 { -q } else { q };
    Some(pool.num(q))
}

/// The slope at row `at` of a least-squares parabola through the measured values within
/// three rows either side: a rate the data imply, to start a shot from.
fn slope(times: &[f64], values: &[Option<f64>], at: usize) -> Option<f64> {
    let from = at.saturating_sub(3);
    let to = (at + 4).min(times.len());
    let points: Vec<(f64, f64)> =
        (from..to).filter_map(|r| values[r].map(|v| (times[r] - times[at], v))).collect();
    if points.len() < 3 {
        return None;
    }
    // Normal equations of v ≈ a + b·τ + c·τ², τ = t − t_at: the slope is b.
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = nalgebra::Vector3::<f64>::zeros();
    for (tau, v) in points {
        let basis = nalgebra::Vector3::new(1.0, tau, tau * tau);
        m += basis * basis.transpose();
        rhs += basis * v;
    }
    m.lu().solve(&rhs).map(|c| c[1]).filter(|b| b.is_finite())
}

/// a (r × inner) · b (inner × c), row-major.
fn mat_mul(a: &[f64], b: &[f64], r: usize, inner: usize, c: usize) -> Vec<f64> {
    let mut out = vec![0.0; r * c];
    for i in 0..r {
        for l in 0..inner {
            let x = a[i * inner + l];
            if x != 0.0 {
                for j in 0..c {
                    out[i * c + j] += x * b[l * c + j];
                }
            }
        }
    }
    out
}
