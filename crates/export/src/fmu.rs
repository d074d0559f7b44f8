//! A scene as an FMI 2.0 functional mock-up unit, for Model Exchange and Co-Simulation in one
//! archive: its modelDescription.xml, the C sources (the scene's generated C, the FMI wrapper
//! and the DOP853 integrator with lagrange's tableau) and a documentation page. Building the
//! binary and writing the archive is a front end's work: this says what goes in it and how the
//! binary is compiled ([`Fmu::compile_units`]).

use std::fmt::Write;

use engine::{Error, Options};

mod description;

/// What an FMU export asks for; `None` leaves the scene's setting or the default.
#[derive(Clone, Debug, Default)]
pub struct ExportOptions {
    /// The Co-Simulation integrator's tolerance (relative and absolute) when the importer sets
    /// none; default: the scene's `simulate { tolerance … }`, else 1e-10.
    pub tolerance: Option<f64>,
    /// The default experiment's stop time; default: the scene's `simulate { until … }`, else 10.
    pub until: Option<f64>,
    /// Skip the dimension check.
    pub no_units: bool,
}

/// The contents of an FMU, but for its binary.
pub struct Fmu {
    /// The scene's name as a C identifier: the prefix of the generated C, the binary's name.
    pub model_identifier: String,
    /// `modelDescription.xml`.
    pub model_description: String,
    /// The files under `sources/`, by name.
    pub sources: Vec<(String, String)>,
    /// `documentation/index.html`.
    pub documentation: String,
}

/// An SI unit as the FMU declares it: its name (as the generated C's `NAME_parameter_units`
/// spells it) and its exponents of the base units, radians included.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct SiUnit {
    pub name: String,
    /// Exponents of kg, m, s, A, K.
    pub base: [i32; 5],
    pub radians: i32,
}

/// What a scene's FMU declares, read from the scene at its parameters' values.
pub(crate) struct Interface {
    pub title: String,
    pub identifier: String,
    pub guid: String,
    pub states: Vec<(String, f64)>,
    /// Name, SI unit, value.
    pub parameters: Vec<(String, Option<SiUnit>, f64)>,
    pub inputs: Vec<(String, Option<SiUnit>, f64)>,
    /// The scene's `output` lines, then KE and PE.
    pub outputs: Vec<String>,
    pub until: f64,
    pub tolerance: f64,
}

/// The FMU of the scene `source` read from `path`, whose stem names the model (as it names
/// the generated C).
pub fn export(path: &str, source: &str, options: &ExportOptions) -> Result<Fmu, Error> {
    let module = crate::codegen::c(path, source, Options { units: !options.no_units })?;
    // The wrapper integrates with every contact open and knows no impact: it would let the
    // bodies pass through each other.
    module.equations.prepared.refuse_contacts("export --fmu")?;
    let mut interface = interface(&module, options)?;
    interface.guid = guid(&[source, &module.header, &module.source]);
    let fields = crate::codegen::parameter_fields(&module.equations);
    let name = &module.name;
    let mut sources = vec![
        (format!("{name}.h"), module.header.clone()),
        (format!("{name}.c"), module.source.clone()),
        ("fmu_model.h".into(), model_header(&interface, &fields, module.equations.sizes)),
        ("dop853_tableau.h".into(), tableau_header()),
    ];
    for (file, text) in WRAPPER {
        sources.push((file.to_string(), text.to_string()));
    }
    let mut fmu = Fmu {
        model_identifier: module.name.clone(),
        documentation: description::documentation(&interface),
        model_description: String::new(),
        sources,
    };
    fmu.model_description = description::model_description(&interface, &fmu.compile_units());
    Ok(fmu)
}

/// The wrapper's sources, the same for every scene.
const WRAPPER: [(&str, &str); 4] = [
    ("fmi2.h", include_str!("fmu/c/fmi2.h")),
    ("dop853.h", include_str!("fmu/c/dop853.h")),
    ("dop853.c", include_str!("fmu/c/dop853.c")),
    ("fmu.c", include_str!("fmu/c/fmu.c")),
];

impl Fmu {
    /// The sources a compiler is given, the others being headers they include.
    pub fn compile_units(&self) -> Vec<&str> {
        self.sources.iter().map(|(name, _)| name.as_str()).filter(|n| n.ends_with(".c")).collect()
    }

    /// The archive's folder of binaries for the platform this runs on, as FMI 2.0 names it
    /// (`linux64`, `darwin64`, `win64`, …), and the binary's extension there.
    pub fn platform() -> (String, &'static str) {
        let bits = if cfg!(target_pointer_width = "64") { "64" } else { "32" };
        let (os, extension) = match std::env::consts::OS {
            "macos" => ("darwin", "dylib"),
            "windows" => ("win", "dll"),
            _ => ("linux", "so"),
        };
        (format!("{os}{bits}"), extension)
    }
}

fn interface(
    module: &crate::codegen::CModule,
    options: &ExportOptions,
) -> Result<Interface, Error> {
    let equations = &module.equations;
    let prepared = &equations.prepared;
    let model = &prepared.derivation.model;
    // The block as the scene's one resolution read it, not the text resolved again.
    let settings = simulation::settings_of(
        model.simulation.clone(),
        &simulation::Options {
            until: options.until,
            // The FMU integrates with its own DOP853 whatever the scene's method, so its
            // tolerance applies even to a scene run by a fixed-step method.
            method: Some(sim::Method::Dop853.name().to_string()),
            tolerance: options.tolerance,
            no_units: options.no_units,
            ..Default::default()
        },
    )?;
    let values = &equations.values;
    // The start as the generated C's `NAME_initial_state` computes it: from the same program.
    let mut tape = numeric::Tape::new(equations.start.clone());
    let mut y0 = vec![0.0; 2 * equations.sizes.coordinates];
    let slots: Vec<f64> = std::iter::once(0.0).chain(values.iter().copied()).collect();
    tape.eval(&slots, &mut y0);
    // The tunable parameters are the free ones; the derived ones follow them inside the
    // generated C, as they do in every run.
    let parameters: Vec<_> = equations
        .free
        .iter()
        .map(|i| (&model.params[*i], values[*i]))
        .map(|(p, v)| (p.name.clone(), si_unit(&p.unit), v))
        .collect();
    let inputs: Vec<_> = model
        .inputs
        .iter()
        .zip(&values[model.params.len()..])
        .map(|(u, v)| (u.name.clone(), si_unit(&u.unit), *v))
        .collect();
    let mut outputs = equations.outputs.clone();
    outputs.extend(["KE".to_string(), "PE".to_string()]);
    let states: Vec<(String, f64)> = prepared.state_names().into_iter().zip(y0).collect();
    let interface = Interface {
        title: equations.title.clone(),
        identifier: module.name.clone(),
        guid: String::new(),
        states,
        parameters,
        inputs,
        outputs,
        until: settings.until,
        tolerance: settings.tolerance,
    };
    description::check_names(&interface)?;
    Ok(interface)
}

/// The SI unit of a value written with `unit`: named as the generated C names it, with
/// `rad` where the written unit is an angle's.
fn si_unit(unit: &Option<lang::Unit>) -> Option<SiUnit> {
    let unit = unit.as_ref()?;
    let name = model::units::si_text(unit).ok()?;
    let (dim, _) = model::units::parse_unit(unit).ok()?;
    let radians = i32::from(name == "rad" || name.starts_with("rad.") || name.starts_with("rad/"));
    Some(SiUnit { name, base: dim.integer_exponents()?, radians })
}

/// `fmu_model.h`: the generated C's names under the ones the wrapper uses, the parameters by
/// index, and what the export fixed (the GUID, the default tolerance).
fn model_header(interface: &Interface, fields: &[String], sizes: crate::codegen::Sizes) -> String {
    let name = &interface.identifier;
    let mut s = String::new();
    let _ =
        writeln!(s, "/* The scene's C under the names fmu.c uses; written by lagrange export. */");
    let _ = writeln!(s, "#ifndef LAGRANGE_FMU_MODEL_H\n#define LAGRANGE_FMU_MODEL_H\n");
    let _ = writeln!(s, "#include <stddef.h>\n\n#include \"{name}.h\"\n");
    let _ = writeln!(s, "#define MODEL_GUID \"{}\"", interface.guid);
    let _ = writeln!(s, "#define MODEL_TOLERANCE {:e}", interface.tolerance);
    let _ = writeln!(s, "#define MODEL_STATES {}", 2 * sizes.coordinates);
    let _ = writeln!(s, "#define MODEL_PARAMETERS {}", interface.parameters.len());
    let _ = writeln!(s, "#define MODEL_INPUTS {}", interface.inputs.len());
    // KE and PE are not among the generated C's outputs.
    let _ = writeln!(s, "#define MODEL_OUTPUTS {}\n", interface.outputs.len() - 2);
    let _ = writeln!(s, "typedef {name}_parameters model_parameters;");
    let _ = writeln!(s, "#define model_default_parameters {name}_default_parameters");
    for f in ["initial_state", "rhs", "outputs", "energies"] {
        let _ = writeln!(s, "#define model_{f} {name}_{f}");
    }
    let _ = writeln!(s, "\nstatic double *model_parameter(model_parameters *p, size_t i) {{");
    if fields.is_empty() {
        let _ = writeln!(s, "    (void)p;");
    }
    let _ = writeln!(s, "    switch (i) {{");
    for (i, field) in fields.iter().enumerate() {
        let _ = writeln!(s, "    case {i}:\n        return &p->{field};");
    }
    let _ = writeln!(s, "    default:\n        return (double *)0;\n    }}\n}}\n");
    let _ = writeln!(s, "static double model_default_input(size_t i) {{");
    let _ = writeln!(s, "    return {name}_default_inputs[i];\n}}\n");
    let _ = writeln!(s, "#endif");
    s
}

/// `dop853_tableau.h`: the coefficients `sim` steps DOP853 with, printed to round-trip.
fn tableau_header() -> String {
    let t = sim::dop853_tableau();
    let row = |v: &[f64], width: usize| -> String {
        let mut cells: Vec<String> = v.iter().map(|x| c_double(*x)).collect();
        cells.resize(width, "0.0".into());
        format!("{{{}}}", cells.join(", "))
    };
    let stages = t.c.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "/* The DOP853 tableau of lagrange's integrator; written by lagrange export. */"
    );
    let _ = writeln!(s, "#define DOP853_STAGES {stages}\n#define DOP853_ORDER 7.0");
    let _ = writeln!(s, "#define DOP853_SAFETY {}", c_double(t.safety));
    let _ = writeln!(s, "#define DOP853_MIN_FACTOR {}", c_double(t.min_factor));
    let _ = writeln!(s, "#define DOP853_MAX_FACTOR {}\n", c_double(t.max_factor));
    let _ = writeln!(s, "static const double dop853_c[{stages}] = {};", row(t.c, stages));
    let _ = writeln!(s, "static const double dop853_a[{stages}][{stages}] = {{");
    for a in t.a {
        let _ = writeln!(s, "    {},", row(a, stages));
    }
    let _ = writeln!(s, "}};");
    for (name, v) in [("b", t.b), ("bhh", t.bhh), ("e5", t.e5)] {
        let _ = writeln!(s, "static const double dop853_{name}[{stages}] = {};", row(v, stages));
    }
    s
}

/// A double as C reads it back to the same bits (Rust's shortest round-trip form, which C99's
/// `strtod` parses).
fn c_double(x: f64) -> String {
    format!("{x:e}")
}

/// A deterministic GUID of what the FMU is made from: FNV-1a over the texts, as 128 bits in
/// the 8-4-4-4-12 form.
fn guid(parts: &[&str]) -> String {
    let mut hashes = [0xcbf2_9ce4_8422_2325_u64, 0x6c62_272e_07bb_0142_u64];
    for (k, h) in hashes.iter_mut().enumerate() {
        for part in parts {
            for b in part.bytes().chain([0xff_u8.wrapping_sub(k as u8)]) {
                *h ^= u64::from(b);
                *h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    let hex = format!("{:016x}{:016x}", hashes[0], hashes[1]);
    format!("{{{}-{}-{}-{}-{}}}", &hex[0..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..32])
}
