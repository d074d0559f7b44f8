//! The equations of a scene as source code that needs nothing of lagrange: a Rust module (only
//! `std`, [`codegen`]) or a C99 header and source (only libm, [`c`]). Both print the same
//! lowered programs, gathered once here: the mass matrix, the forcing, the constraint rows,
//! the partials that give the exact Jacobian of the first-order system, the energies, the
//! reactions, the scene's outputs and the start, each a straight-line function lowered like
//! the tape. Parameters and inputs are separate arguments of the functions a caller uses.

use cas::ExprId;

use engine::numbers::{prepare, Prepared};
use engine::{Error, Options};

mod c;
pub mod impact;
mod rust;

pub use c::{c, identifier, parameter_fields, CModule};
pub use rust::{codegen, codegen_with, Module};

/// How many of each thing the generated functions handle.
#[derive(Clone, Copy, Debug)]
pub struct Sizes {
    /// Coordinates n; the state is (q, q̇), 2n values.
    pub coordinates: usize,
    /// Constraints kept with multipliers, m.
    pub constraints: usize,
    /// The scene's parameters (without the inputs): the slots the programs read.
    pub parameters: usize,
    /// The free parameters, the ones a caller gives; the derived ones follow them.
    pub free_parameters: usize,
    pub inputs: usize,
    /// The scene's contacts: their rows are among the m multipliers, as a run lays them out.
    pub contacts: usize,
}

impl Sizes {
    /// `[t, q, q̇, parameters, inputs]`: the input of M, f, the constraints, the energies and
    /// the outputs.
    pub fn dynamics_inputs(&self) -> usize {
        1 + 2 * self.coordinates + self.parameters + self.inputs
    }
}

/// The programs both languages print, gathered once from a scene.
pub struct Equations {
    pub prepared: Prepared,
    /// The values of the parameters' slots: the scene's parameters, then the inputs' declared
    /// values.
    pub values: Vec<f64>,
    pub sizes: Sizes,
    /// (function name, program), in the order the module prints them.
    pub programs: Vec<(String, numeric::Program)>,
    /// The reactions' names, in the order of the `reactions` program's outputs.
    pub reactions: Vec<String>,
    /// The scene's `output` names, in the order of the `outputs` program's outputs.
    pub outputs: Vec<String>,
    /// `[t, parameters, inputs]` → the start (q, q̇): the scene's initial values, which may
    /// depend on the parameters.
    pub start: numeric::Program,
    /// The scene's title, or the path when it has none.
    pub title: String,
    /// The free parameters' indices, in declaration order: the fields a caller sets.
    pub free: Vec<usize>,
    /// Each derived parameter's index with its value as a program of `[parameters, inputs]`
    /// (one output), in declaration order: computed from the slots before it, as
    /// `model::ParameterValues` computes it, so the generated code has its bits.
    pub derived: Vec<(usize, numeric::Program)>,
}

impl Equations {
    /// The equations of the scene `source`; `path` names it when the scene has no title.
    pub fn gather(path: &str, source: &str, options: Options) -> Result<Equations, Error> {
        // Reactions the scene derives are part of the module; asking for KE and PE changes
        // nothing.
        let mut prepared = prepare(source, &["KE".into(), "PE".into()], options)?;
        // The generated code holds a contact's tangential row as a grip: Coulomb's modes are
        // the run's alone for now.
        prepared.refuse_friction("codegen")?;
        let values = prepared.parameter_values(&[])?;
        let d = &mut prepared.derivation;
        let mut reactions = Vec::new();
        let mut reaction_exprs = Vec::new();
        for r in d.reactions.clone() {
            reactions.push(d.model.pool.symbol(r.symbol).name.clone());
            reaction_exprs.push(d.expand_quantities(r.expr, false));
        }
        let outputs: Vec<String> = d.model.outputs.iter().map(|o| o.name.clone()).collect();
        let output_exprs: Vec<ExprId> =
            d.model.outputs.clone().iter().map(|o| d.expand_quantities(o.value, false)).collect();
        let sizes = Sizes {
            coordinates: prepared.layout.coordinates,
            constraints: prepared.layout.multipliers,
            parameters: d.model.params.len(),
            free_parameters: prepared.parameter_plan.free().len(),
            inputs: d.model.inputs.len(),
            contacts: prepared.contacts.len(),
        };
        let (n, m) = (sizes.coordinates, sizes.constraints);
        let dynamics = prepared.dynamics_exprs();
        let dyn_inputs = prepared.dynamics_inputs();
        let obs_inputs = prepared.observation_inputs();
        let mut programs = vec![
            ("mass_matrix".to_string(), prepared.lower(&dyn_inputs, &dynamics[..n * n])?),
            ("forcing".to_string(), prepared.lower(&dyn_inputs, &dynamics[n * n..n * n + n])?),
        ];
        if let Some(recursive) = prepared.recursive()? {
            // q̈ by the recursive form's sweep, O(n), which `rhs` takes where it gives numbers.
            programs.push(("accelerations".to_string(), recursive.accelerations));
        }
        if m > 0 {
            // J (m×n row-major) then γ, Φ, Φ̇ per constraint, as the dynamics layout has them.
            programs.push((
                "constraints".to_string(),
                prepared.lower(&dyn_inputs, &dynamics[n * n + n..])?,
            ));
        }
        // ∂(r, c, Φ, Φ̇)/∂(q, q̇): the right-hand side solves c stabilised by Φ and Φ̇, as a run
        // does, so its Jacobian needs their partials too.
        let partials = prepared.partials_exprs();
        programs.push((
            "partials".to_string(),
            prepared.lower(&obs_inputs, &partials[..(n + 3 * m) * 2 * n])?,
        ));
        programs.push(("energies".to_string(), prepared.lower(&dyn_inputs, &prepared.extra[..2])?));
        if !reaction_exprs.is_empty() {
            programs.push(("reactions".to_string(), prepared.lower(&obs_inputs, &reaction_exprs)?));
        }
        if !output_exprs.is_empty() {
            programs.push(("outputs".to_string(), prepared.lower(&dyn_inputs, &output_exprs)?));
        }
        if !prepared.contacts.is_empty() {
            // Each contact's coefficient of restitution, a constant of the parameters.
            let d = &prepared.derivation;
            let restitutions: Vec<ExprId> = d.contacts.iter().map(|c| c.restitution).collect();
            programs.push((
                "restitutions".to_string(),
                prepared.lower(&prepared.parameters, &restitutions)?,
            ));
        }
        let start = start_program(&prepared)?;
        let title = prepared.derivation.model.title.clone().unwrap_or_else(|| path.to_string());
        let free = prepared.parameter_plan.free();
        let mut derived = Vec::new();
        for i in prepared.parameter_plan.derived() {
            let Some(value) = prepared.derivation.model.params[i].value else { continue };
            derived.push((i, prepared.lower(&prepared.parameters, &[value])?));
        }
        Ok(Equations {
            prepared,
            values,
            sizes,
            programs,
            reactions,
            outputs,
            start,
            title,
            free,
            derived,
        })
    }

    /// The program named `name`, if the scene has it.
    pub fn program(&self, name: &str) -> Option<&numeric::Program> {
        self.programs.iter().find(|(n, _)| n == name).map(|(_, p)| p)
    }

    /// The multipliers' slots of the contacts' rows (each normal, then its grip), which the
    /// functions of the state hold open: λ = 0 there, as a run holds an open contact.
    pub fn contact_slots(&self) -> Vec<usize> {
        self.prepared
            .contacts
            .iter()
            .flat_map(|c| std::iter::once(c.normal).chain(c.grip))
            .collect()
    }

    /// The contacts' names, in the order written.
    pub fn contact_names(&self) -> Vec<String> {
        self.prepared.contact_names()
    }

    /// The rate the impact law takes of multiplier `slot`'s row, an index into the
    /// constraints program's outputs: Φ̇ of a position row (a contact's normal rate γ), Φ of
    /// a velocity row (a grip's tangential rate), as a run reads them.
    pub fn row_rate(&self, slot: usize) -> usize {
        let n = self.sizes.coordinates;
        let base = slot * (n + 3) + n;
        match self.prepared.stabilisation()[slot] {
            sim::Stabilisation::Position => base + 2,
            sim::Stabilisation::Velocity => base + 1,
        }
    }

    /// Names of `syms`, joined by commas.
    fn names(&self, syms: &[cas::SymId]) -> String {
        let pool = &self.prepared.derivation.model.pool;
        syms.iter().map(|s| pool.symbol(*s).name.clone()).collect::<Vec<_>>().join(", ")
    }

    /// The coordinates whose start was solved in numbers when the scene was derived: their
    /// start is a number, the same whatever the parameters.
    pub fn fixed_start(&self) -> Vec<String> {
        let d = &self.prepared.derivation;
        let pool = &d.model.pool;
        d.solved_start_positions.iter().map(|s| pool.symbol(*s).name.clone()).collect()
    }
}

/// Each kept constraint's γ as the run stabilises it (Baumgarte at `sim::BAUMGARTE_RATE`), an
/// expression of `rows`, the constraints program's outputs (J, γ, Φ, Φ̇ per constraint), with
/// the run's operations in its order, (γ − 2α·Φ̇) − α²·Φ, so that the generated code has its
/// bits; `literal` writes a number in the language.
pub(crate) fn stabilised_gamma(e: &Equations, literal: &dyn Fn(f64) -> String) -> Vec<String> {
    let (n, alpha) = (e.sizes.coordinates, sim::BAUMGARTE_RATE);
    let kinds = e.prepared.stabilisation();
    kinds
        .iter()
        .enumerate()
        .map(|(c, kind)| {
            let base = c * (n + 3) + n;
            match kind {
                sim::Stabilisation::Position => format!(
                    "rows[{base}] - {} * rows[{}] - {} * rows[{}]",
                    literal(2.0 * alpha),
                    base + 2,
                    literal(alpha * alpha),
                    base + 1
                ),
                sim::Stabilisation::Velocity => {
                    format!("rows[{base}] - {} * rows[{}]", literal(alpha), base + 1)
                }
            }
        })
        .collect()
}

/// The statements that turn each kept constraint's row of partials `d` (column `col`) into
/// those of the stabilised row [`stabilised_gamma`] solves: ∂c + 2α·∂Φ̇ + α²·∂Φ, or ∂c + α·∂Φ
/// for a velocity constraint, as `sim`'s exact Jacobian forms them.
pub(crate) fn stabilised_partials(e: &Equations, literal: &dyn Fn(f64) -> String) -> Vec<String> {
    let (n, m, alpha) = (e.sizes.coordinates, e.sizes.constraints, sim::BAUMGARTE_RATE);
    let width = 2 * n;
    let kinds = e.prepared.stabilisation();
    kinds
        .iter()
        .enumerate()
        .map(|(c, kind)| {
            let row = |block: usize| format!("d[{} + col]", (n + block * m + c) * width);
            match kind {
                sim::Stabilisation::Position => format!(
                    "{} = {} + {} * {} + {} * {};",
                    row(0),
                    row(0),
                    literal(2.0 * alpha),
                    row(2),
                    literal(alpha * alpha),
                    row(1)
                ),
                sim::Stabilisation::Velocity => {
                    format!("{} = {} + {} * {};", row(0), row(0), literal(alpha), row(1))
                }
            }
        })
        .collect()
}

/// The start (q, then q̇, of the remaining coordinates) as a program of `[t, parameters,
/// inputs]`: the scene's initial values are expressions of the parameters.
fn start_program(prepared: &Prepared) -> Result<numeric::Program, Error> {
    let d = &prepared.derivation;
    let initial = |q: &cas::SymId, rate: bool| {
        let c = d.model.coords.iter().find(|c| c.sym == *q);
        c.map_or(d.model.pool.zero(), |c| if rate { c.initial_rate } else { c.initial })
    };
    let mut exprs: Vec<ExprId> = d.coords.iter().map(|q| initial(q, false)).collect();
    exprs.extend(d.coords.iter().map(|q| initial(q, true)));
    let mut inputs = vec![d.model.time];
    inputs.extend(&prepared.parameters);
    prepared.lower(&inputs, &exprs)
}
