//! The `simulate` block's integrator settings checked when a scene is resolved: the method it
//! names is one of `sim`'s, and the block gives that method a setting it uses (a tolerance to
//! an adaptive method, a step to a fixed-step one). The runs themselves are the `simulation`
//! crate's; these checks are here so that every command refuses such a block alike.

use lang::Diagnostic;
use sim::Method;

/// The method a scene's `simulate` block names, or why the integrator has none of that name.
pub fn scene_method(simulation: &model::Simulation) -> Result<Option<Method>, Diagnostic> {
    let Some(name) = &simulation.method else { return Ok(None) };
    let method = Method::from_name(&name.name);
    method.map(Some).ok_or_else(|| {
        let d = Diagnostic::error(name.span, format!("unknown method `{}`", name.name))
            .with_label("not a method");
        let known = Method::NAMES.join(", ");
        match model::closest(&name.name, Method::NAMES) {
            Some(near) => d.with_hint(format!("did you mean `{near}`? (known: {known})")),
            None => d.with_hint(format!("the methods are {known}")),
        }
    })
}

/// The methods as the settings they take: the adaptive ones a tolerance, the fixed-step ones
/// a step.
pub fn methods_taking(adaptive: bool) -> String {
    let names: Vec<&str> =
        Method::all().filter(|m| m.is_adaptive() == adaptive).map(Method::name).collect();
    names.join(", ")
}

/// The diagnostic of a `simulate` block that names a method and a `step` or `tolerance` that
/// method does not use (a block without a method runs the default, dop853).
pub fn scene_settings_apply(simulation: &model::Simulation) -> Result<(), Diagnostic> {
    let method = scene_method(simulation)?.unwrap_or(Method::DEFAULT);
    let (unused, key, takes) = match (method.is_adaptive(), simulation.step, simulation.tolerance) {
        (true, Some(step), _) => (step, "step", "tolerance"),
        (false, _, Some(tolerance)) => (tolerance, "tolerance", "step"),
        _ => return Ok(()),
    };
    let kind = if method.is_adaptive() { "an adaptive" } else { "a fixed-step" };
    let named = match &simulation.method {
        Some(_) => format!("`{}`", method.name()),
        None => format!("`{}` (the default)", method.name()),
    };
    Err(Diagnostic::error(unused.span, format!("`{key}` is not used by {named}, {kind} method"))
        .with_label(format!("{} takes `{takes}`", method.name()))
        .with_hint(format!(
            "the adaptive methods ({}) take `tolerance`, the fixed-step ones ({}) `step`",
            methods_taking(true),
            methods_taking(false)
        )))
}
