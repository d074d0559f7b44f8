//! The FMU's modelDescription.xml and documentation page, from its [`Interface`].
//!
//! Value references follow the wrapper's layout (fmu.c): the states, their derivatives, the
//! parameters, the inputs, the outputs (KE and PE last). The states start at the scene's values
//! (`initial="exact"`); the derivatives and outputs are computed (`initial="calculated"`), so
//! they are the initial unknowns.

use std::collections::BTreeSet;
use std::fmt::Write;

use super::{Interface, SiUnit};
use engine::Error;

/// SI base units in the order of `model::units`' exponents, as FMI's `BaseUnit` names them.
const BASES: [&str; 5] = ["kg", "m", "s", "A", "K"];

/// Refuses a scene whose variables would share a name in the FMU.
pub(crate) fn check_names(interface: &Interface) -> Result<(), Error> {
    let mut seen = BTreeSet::new();
    for name in variable_names(interface) {
        if !seen.insert(name.clone()) {
            return Err(Error::Input(format!(
                "two of the FMU's variables would be named `{name}`; rename the scene's \
                 `output` or parameter of that name"
            )));
        }
    }
    Ok(())
}

fn variable_names(interface: &Interface) -> Vec<String> {
    let mut names: Vec<String> = interface.states.iter().map(|s| s.0.clone()).collect();
    names.extend(interface.states.iter().map(|s| format!("der({})", s.0)));
    names.extend(interface.parameters.iter().map(|p| p.0.clone()));
    names.extend(interface.inputs.iter().map(|u| u.0.clone()));
    names.extend(interface.outputs.iter().cloned());
    names
}

/// Text as XML attribute content.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            // Kept through attribute-value normalisation, which would make them spaces.
            '\t' | '\n' | '\r' => {
                let _ = std::fmt::Write::write_fmt(&mut out, format_args!("&#{};", c as u32));
            }
            // No other control character may stand in XML 1.0, even as a reference.
            c if c.is_control() && (c as u32) < 0x20 => out.push('\u{FFFD}'),
            _ => out.push(c),
        }
    }
    out
}

/// A double as XML Schema's `xs:double` reads it back to the same bits.
fn number(x: f64) -> String {
    format!("{x:e}")
}

struct Variable<'a> {
    name: String,
    causality: &'a str,
    variability: &'a str,
    initial: Option<&'a str>,
    description: String,
    /// The `Real` element's attributes.
    real: String,
}

fn variables(interface: &Interface) -> Vec<Variable<'static>> {
    let n2 = interface.states.len();
    let n = n2 / 2;
    let mut out = Vec::new();
    for (i, (name, start)) in interface.states.iter().enumerate() {
        let what = if i < n { "coordinate" } else { "rate of a coordinate" };
        out.push(Variable {
            name: name.clone(),
            causality: "local",
            variability: "continuous",
            initial: Some("exact"),
            description: format!("state: {what}"),
            real: format!("start=\"{}\"", number(*start)),
        });
    }
    for (i, (name, _)) in interface.states.iter().enumerate() {
        out.push(Variable {
            name: format!("der({name})"),
            causality: "local",
            variability: "continuous",
            initial: Some("calculated"),
            description: format!("the time derivative of {name}"),
            // `derivative` is the state's index in ModelVariables, counted from 1.
            real: format!("derivative=\"{}\"", i + 1),
        });
    }
    let with_unit = |unit: &Option<SiUnit>, start: f64| match unit {
        Some(u) => format!("start=\"{}\" unit=\"{}\"", number(start), escape(&u.name)),
        None => format!("start=\"{}\"", number(start)),
    };
    for (name, unit, value) in &interface.parameters {
        out.push(Variable {
            name: name.clone(),
            causality: "parameter",
            variability: "tunable",
            initial: Some("exact"),
            description: "parameter of the scene".into(),
            real: with_unit(unit, *value),
        });
    }
    for (name, unit, value) in &interface.inputs {
        out.push(Variable {
            name: name.clone(),
            causality: "input",
            variability: "continuous",
            initial: None,
            description: "input of the scene, held over a Co-Simulation step".into(),
            real: with_unit(unit, *value),
        });
    }
    let scene_outputs = interface.outputs.len() - 2;
    for (i, name) in interface.outputs.iter().enumerate() {
        let description = match i.checked_sub(scene_outputs) {
            Some(0) => "kinetic energy".to_string(),
            Some(_) => "potential energy".to_string(),
            None => "output of the scene".to_string(),
        };
        out.push(Variable {
            name: name.clone(),
            causality: "output",
            variability: "continuous",
            initial: Some("calculated"),
            description,
            real: String::new(),
        });
    }
    out
}

/// modelDescription.xml.
/// `compile_units`: the sources under `sources/` a compiler is given.
pub(crate) fn model_description(interface: &Interface, compile_units: &[&str]) -> String {
    let vars = variables(interface);
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    let _ = writeln!(
        s,
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"{}\" \
         description=\"{}\" generationTool=\"lagrange {}\" variableNamingConvention=\"flat\" \
         numberOfEventIndicators=\"0\">",
        escape(&interface.title),
        interface.guid,
        escape(&format!("{}: equations of motion derived by lagrange", interface.title)),
        env!("CARGO_PKG_VERSION"),
    );
    let id = &interface.identifier;
    // The sources to compile, for an importer that builds the binary for its own platform.
    let files: String =
        compile_units.iter().map(|f| format!("      <File name=\"{}\"/>\n", escape(f))).collect();
    let sources = format!("    <SourceFiles>\n{files}    </SourceFiles>\n");
    let _ = writeln!(
        s,
        "  <ModelExchange modelIdentifier=\"{id}\" canNotUseMemoryManagementFunctions=\"false\">\n\
         {sources}  </ModelExchange>"
    );
    let _ = writeln!(
        s,
        "  <CoSimulation modelIdentifier=\"{id}\" canHandleVariableCommunicationStepSize=\"true\" \
         canNotUseMemoryManagementFunctions=\"false\">\n{sources}  </CoSimulation>"
    );
    let units: BTreeSet<&SiUnit> = interface
        .parameters
        .iter()
        .chain(&interface.inputs)
        .filter_map(|(_, unit, _)| unit.as_ref())
        .collect();
    if !units.is_empty() {
        let _ = writeln!(s, "  <UnitDefinitions>");
        for u in &units {
            let mut base: Vec<String> = (0..5)
                .filter(|&i| u.base[i] != 0)
                .map(|i| format!(" {}=\"{}\"", BASES[i], u.base[i]))
                .collect();
            if u.radians != 0 {
                base.push(format!(" rad=\"{}\"", u.radians));
            }
            let _ = writeln!(
                s,
                "    <Unit name=\"{}\"><BaseUnit{}/></Unit>",
                escape(&u.name),
                base.concat()
            );
        }
        let _ = writeln!(s, "  </UnitDefinitions>");
    }
    let _ = writeln!(
        s,
        "  <DefaultExperiment startTime=\"0\" stopTime=\"{}\" tolerance=\"{}\"/>",
        number(interface.until),
        number(interface.tolerance)
    );
    let _ = writeln!(s, "  <ModelVariables>");
    for (vr, v) in vars.iter().enumerate() {
        let initial = v.initial.map(|i| format!(" initial=\"{i}\"")).unwrap_or_default();
        let _ = writeln!(
            s,
            "    <!-- index {} -->\n    <ScalarVariable name=\"{}\" valueReference=\"{vr}\" \
             description=\"{}\" causality=\"{}\" variability=\"{}\"{initial}>",
            vr + 1,
            escape(&v.name),
            escape(&v.description),
            v.causality,
            v.variability,
        );
        let real = if v.real.is_empty() { String::new() } else { format!(" {}", v.real) };
        let _ = writeln!(s, "      <Real{real}/>\n    </ScalarVariable>");
    }
    let _ = writeln!(s, "  </ModelVariables>");
    let _ = writeln!(s, "{}", model_structure(interface, &vars));
    let _ = writeln!(s, "</fmiModelDescription>");
    s
}

/// Outputs, Derivatives and InitialUnknowns, by index in ModelVariables (from 1). No
/// dependencies are listed: each unknown may depend on every known.
fn model_structure(interface: &Interface, vars: &[Variable]) -> String {
    let n2 = interface.states.len();
    let outputs: Vec<usize> =
        (0..vars.len()).filter(|&i| vars[i].causality == "output").map(|i| i + 1).collect();
    let derivatives: Vec<usize> = (n2..2 * n2).map(|i| i + 1).collect();
    let mut initial: Vec<usize> = derivatives.iter().chain(&outputs).copied().collect();
    initial.sort_unstable();
    let list = |tag: &str, indices: &[usize]| -> String {
        let mut s = format!("    <{tag}>\n");
        for i in indices {
            let _ = writeln!(s, "      <Unknown index=\"{i}\"/>");
        }
        let _ = write!(s, "    </{tag}>");
        s
    };
    format!(
        "  <ModelStructure>\n{}\n{}\n{}\n  </ModelStructure>",
        list("Outputs", &outputs),
        list("Derivatives", &derivatives),
        list("InitialUnknowns", &initial)
    )
}

/// documentation/index.html: what the FMU holds and how it behaves.
pub(crate) fn documentation(interface: &Interface) -> String {
    let names = |v: &mut dyn Iterator<Item = &String>| -> String {
        let all: Vec<String> = v.map(|n| format!("<code>{}</code>", escape(n))).collect();
        if all.is_empty() {
            "none".into()
        } else {
            all.join(", ")
        }
    };
    let states = names(&mut interface.states.iter().map(|s| &s.0));
    let parameters = names(&mut interface.parameters.iter().map(|p| &p.0));
    let inputs = names(&mut interface.inputs.iter().map(|u| &u.0));
    let outputs = names(&mut interface.outputs.iter());
    let title = escape(&interface.title);
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{title}</title></head><body>\n\
         <h1>{title}</h1>\n\
         <p>An FMI 2.0 FMU for Model Exchange and Co-Simulation, exported by lagrange {version} \
         from a scene whose equations of motion it derived symbolically.</p>\n\
         <ul>\n<li>States: {states} (the coordinates, then their rates), with their \
         derivatives <code>der(&hellip;)</code>. A state not set before initialization \
         starts where the scene puts it for the parameters' values.</li>\n\
         <li>Parameters (tunable): {parameters}.</li>\n<li>Inputs: {inputs}.</li>\n\
         <li>Outputs: {outputs}.</li>\n</ul>\n\
         <p>Co-Simulation integrates with DOP853, the adaptive explicit Runge&ndash;Kutta pair \
         of <code>lagrange simulate</code>, at the tolerance of <code>fmi2SetupExperiment</code> \
         (relative and absolute), else {tolerance:e}; inputs are held over a communication \
         step. Model Exchange gives the derivatives to the importer's solver. The model has \
         no events and no event indicators. Saving and restoring the FMU's state and \
         directional derivatives are not offered.</p>\n\
         <p>The sources are in <code>sources/</code>: C99 that needs only the C library and \
         libm.</p>\n</body></html>\n",
        version = env!("CARGO_PKG_VERSION"),
        tolerance = interface.tolerance,
    )
}
