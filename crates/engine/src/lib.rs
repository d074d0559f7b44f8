//! The prepared scene every front end and later stage starts from. It loads a scene (parse,
//! resolve once, derive, diagnose) into a [`Scene`], checks its `simulate` block's integrator
//! settings ([`block`]), picks the forms a report shows ([`derived`]), lays out slots, lowers
//! what a command needs and holds the one way to the parameters' values ([`numbers`]), types
//! the options' values ([`input`]), runs the `linear` stage on small motions about a
//! reference, the command line's reference resolved against the scene ([`linearize`]),
//! decides the scene's `expect linearized:` lines ([`expect_linearized`]), and gives the
//! generalized forces that make a given motion happen ([`inverse`]). What goes wrong comes
//! back as an [`Error`]. Above it: runs (`simulation`), ensembles of runs (`ensemble`),
//! generated code and FMUs (`export`), and results as plain data (`results`).
//!
//! It reads no files, writes nothing to a terminal and renders nothing: diagnostics come back
//! as `lang::Diagnostic`s with the text they refer to, and a front end (the `lagrange`
//! command, the benchmarks) shows them.

pub mod along;
pub mod block;
pub mod derived;
mod error;
pub mod expect_linearized;
pub mod input;
pub mod inverse;
pub mod linearize;
pub mod numbers;

pub use error::{line_col, Error, Piece, Setting};
/// What a [`Scene`] holds, for front ends that keep a copy of it ([`numbers::prepare_derived`])
/// without depending on `mechanics` themselves.
pub use mechanics::Derivation;

use lang::Diagnostic;

/// What the pipeline checks besides the grammar and the names.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Check that every sum, equation and energy term has one dimension.
    pub units: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { units: true }
    }
}

/// A loaded scene: its derivation, and the warnings met on the way.
pub struct Scene {
    pub derivation: Derivation,
    /// Warnings of resolving, then of deriving and diagnosing; spans into the loaded text.
    pub warnings: Vec<Diagnostic>,
}

/// Parses, resolves and derives one scene.
pub fn load(source: &str) -> Result<Scene, Error> {
    load_with(source, Options::default())
}

/// [`load`] with options.
pub fn load_with(source: &str, options: Options) -> Result<Scene, Error> {
    let (model, warnings) = resolve_with(source, options)?;
    derive_resolved(source, model, warnings)
}

/// Parses and resolves one scene: its model, for more expressions to be resolved against
/// ([`model::Model::resolve_expression`]) before it is derived, and its warnings.
pub fn resolve_with(
    source: &str,
    options: Options,
) -> Result<(model::Model, Vec<Diagnostic>), Error> {
    resolve_checked(source, model::Checks { units: options.units, inputs_in_constraints: false })
}

/// The scene resolved as a run takes it, with inputs let stand in constraints (a run puts
/// their laws in place before deriving): a front end that holds a scene for runs as well as
/// derivations accepts such a scene, and refuses only what needs the input as a symbol.
pub fn resolve_for_runs(
    source: &str,
    options: Options,
) -> Result<(model::Model, Vec<Diagnostic>), Error> {
    resolve_checked(source, model::Checks { units: options.units, inputs_in_constraints: true })
}

/// [`resolve_with`] with the model's checks given as they are.
pub fn resolve_checked(
    source: &str,
    checks: model::Checks,
) -> Result<(model::Model, Vec<Diagnostic>), Error> {
    let scene = |diagnostics| Error::Scene { diagnostics, source: source.to_string() };
    let ast = lang::parse(source).map_err(scene)?;
    let (model, warnings) = model::resolve_with(&ast, source, checks).map_err(scene)?;
    // The integrator's names are `sim`'s, which `model` does not know.
    block::scene_method(&model.simulation).map_err(|d| scene(vec![d]))?;
    block::scene_settings_apply(&model.simulation).map_err(|d| scene(vec![d]))?;
    Ok((model, warnings))
}

/// Derives and diagnoses a model resolved from `source`.
pub fn derive_resolved(
    source: &str,
    model: model::Model,
    mut warnings: Vec<Diagnostic>,
) -> Result<Scene, Error> {
    let scene = |diagnostics| Error::Scene { diagnostics, source: source.to_string() };
    let mut derivation = mechanics::derive(model).map_err(scene)?;
    verify::diagnose(&mut derivation).map_err(scene)?;
    // Copied, not moved: the derivation's own stay with it for its report to cite.
    warnings.extend(derivation.warnings.iter().cloned());
    Ok(Scene { derivation, warnings })
}
