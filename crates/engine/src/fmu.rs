//! A scene as an FMI 2.0 functional mock-up unit, for Model Exchange and Co-Simulation in one
//! archive: its modelDescription.xml, the C sources (the scene's generated C, the FMI wrapper
//! and the DOP853 integrator with lagrange's tableau) and a documentation page. Building the
//! binary and writing the archive is a front end's work: this says what goes in it and how the
//! binary is compiled ([`Fmu::compile_units`]).

use std::fmt::Write;

use crate::numbers::{prepare, Prepared};
use crate::{Error, Options};

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
    pub tolerance: f64,
}

/// The scene's equations as C, which an FMU wraps: the header and source `lagrange codegen
/// --lang c` writes.
pub struct CModel {
    /// The C identifier that prefixes every name in them.
    pub name: String,
    /// (file name, text): the header `NAME.h` and the source `NAME.c`.
    pub files: Vec<(String, String)>,
}

/// What a scene's FMU declares, read from the scene at its parameters' values.
pub(crate) struct Interface {
    pub title: String,
    pub identifier: String,
    pub guid: String,
    pub states: Vec<(String, f64)>,
    /// Name, SI unit (exponents of kg, m, s, A, K), value.
    pub parameters: Vec<(String, Option<[i32; 5]>, f64)>,
    pub inputs: Vec<(String, Option<[i32; 5]>, f64)>,
    /// The scene's `output` lines, then KE and PE.
    pub outputs: Vec<String>,
    pub until: f64,
    pub tolerance: f64,
}

/// The FMU of the scene `source` read from `path` (whose stem names the model): its C
/// generated, then wrapped.
pub fn export(path: &str, source: &str, options: &ExportOptions) -> Result<Fmu, Error> {
    let c = c_model(path, source, options)?;
    fmu(c, source, options)
}

/// The scene's C, as `lagrange codegen --lang c` writes it.
fn c_model(path: &str, source: &str, options: &ExportOptions) -> Result<CModel, Error> {
    let _ = (path, source, options);
    Err(Error::Input("C code generation is not in this build yet".into()))
}

/// The FMU of the scene `source`, wrapping the C the scene generated (`c`).
pub fn fmu(c: CModel, source: &str, options: &ExportOptions) -> Result<Fmu, Error> {
    let prepared = prepare(source, &[], Options { units: !options.no_units })?;
    let mut interface = interface(&prepared, &c.name, source, options)?;
    interface.guid = guid(&[source, &c.files.iter().map(|f| f.1.as_str()).collect::<String>()]);
    let model_description = description::model_description(&interface);
    let mut sources = c.files;
    sources.push(("fmu_model.h".into(), model_header(&interface, &prepared)));
    sources.push(("dop853_tableau.h".into(), tableau_header()));
    for (name, text) in WRAPPER {
        sources.push((name.to_string(), text.to_string()));
    }
    Ok(Fmu {
        model_identifier: c.name,
        documentation: description::documentation(&interface),
        model_description,
        sources,
        tolerance: interface.tolerance,
    })
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
    prepared: &Prepared,
    identifier: &str,
    source: &str,
    options: &ExportOptions,
) -> Result<Interface, Error> {
    let model = &prepared.derivation.model;
    let settings = crate::simulate::settings(
        source,
        &crate::simulate::Options {
            until: options.until,
            tolerance: options.tolerance,
            no_units: options.no_units,
            ..Default::default()
        },
    )?;
    let values = prepared.parameter_values(&[])?;
    let y0 = prepared.initial_state(&values, &[])?;
    let si = |unit: &Option<lang::Unit>| {
        unit.as_ref()
            .and_then(|u| model::units::parse_unit(u).ok())
            .and_then(|(dim, _)| dim.integer_exponents())
    };
    let parameters: Vec<_> =
        model.params.iter().zip(&values).map(|(p, v)| (p.name.clone(), si(&p.unit), *v)).collect();
    let inputs: Vec<_> = model
        .inputs
        .iter()
        .zip(&values[model.params.len()..])
        .map(|(u, v)| (u.name.clone(), si(&u.unit), *v))
        .collect();
    let mut outputs: Vec<String> = model.outputs.iter().map(|o| o.name.clone()).collect();
    outputs.extend(["KE".to_string(), "PE".to_string()]);
    let states: Vec<(String, f64)> = prepared.state_names().into_iter().zip(y0).collect();
    let interface = Interface {
        title: model.title.clone().unwrap_or_else(|| identifier.to_string()),
        identifier: identifier.to_string(),
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

/// `fmu_model.h`: the generated C's names under the ones the wrapper uses, the parameters by
/// index, and what the export fixed (the GUID, the default tolerance).
fn model_header(interface: &Interface, prepared: &Prepared) -> String {
    let name = &interface.identifier;
    let mut s = String::new();
    let _ =
        writeln!(s, "/* The scene's C under the names fmu.c uses; written by lagrange export. */");
    let _ = writeln!(s, "#ifndef LAGRANGE_FMU_MODEL_H\n#define LAGRANGE_FMU_MODEL_H\n");
    let _ = writeln!(s, "#include <stddef.h>\n\n#include \"{name}.h\"\n");
    let _ = writeln!(s, "#define MODEL_GUID \"{}\"", interface.guid);
    let _ = writeln!(s, "#define MODEL_TOLERANCE {:e}", interface.tolerance);
    let _ = writeln!(s, "#define MODEL_STATES {}", 2 * prepared.layout.coordinates);
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
    let _ = writeln!(s, "    switch (i) {{");
    for (i, (param, _, _)) in interface.parameters.iter().enumerate() {
        let _ = writeln!(s, "    case {i}:\n        return &p->{param};");
    }
    let _ = writeln!(s, "    default:\n        return (double *)0;\n    }}\n}}\n");
    let _ = writeln!(s, "static double model_default_input(size_t i) {{");
    if interface.inputs.is_empty() {
        let _ = writeln!(s, "    (void)i;\n    return 0.0;\n}}\n");
    } else {
        let _ = writeln!(s, "    return {name}_default_inputs[i];\n}}\n");
    }
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
