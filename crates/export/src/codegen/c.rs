//! The equations as C99: a header `NAME.h` and a source `NAME.c` that need only libm. The
//! programs of [`Equations`] are `static` functions of a slot vector; what a caller uses are
//! the functions of the state (t, y) with the parameters in a struct of named fields and the
//! inputs in an array of their own, each returning 0, or 1 where a system it solves is
//! singular. The names and signatures are a contract (the FMU export builds on them): add,
//! do not change.

use std::fmt::Write;

use crate::source::c::{comment, function, helpers, literal};

use super::Equations;
use engine::{Error, Options};

mod functions;

/// A generated header and source, with the equations they were printed from.
pub struct CModule {
    /// The C identifier every exported name starts with (the scene file's stem).
    pub name: String,
    pub header: String,
    pub source: String,
    pub equations: Equations,
}

/// The C of the scene `source`, read from `path`: its exported names start with the file's
/// stem made an identifier.
pub fn c(path: &str, source: &str, options: Options) -> Result<CModule, Error> {
    let equations = Equations::gather(path, source, options)?;
    let stem = std::path::Path::new(path).file_stem().map(|s| s.to_string_lossy());
    let name = identifier(stem.as_deref().unwrap_or("scene"));
    let names = Names::of(&equations);
    let header = header(&equations, &name, path, &names);
    let source = implementation(&equations, &name, path, &names);
    Ok(CModule { name, header, source, equations })
}

/// `text` as a C identifier that is not a keyword and not reserved: letters, digits and `_`
/// kept, Greek letters spelled out, anything else as its code point; `scene_` in front of a
/// leading digit or underscore.
pub fn identifier(text: &str) -> String {
    let mut s = String::new();
    for ch in text.chars() {
        if ch.is_ascii_alphanumeric() || ch == '_' {
            s.push(ch);
        } else if let Some(name) = greek(ch) {
            s.push_str(name);
        } else {
            let _ = write!(s, "u{:x}", ch as u32);
        }
    }
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit() || c == '_') {
        s.insert_str(0, "scene_");
    }
    if KEYWORDS.contains(&s.as_str()) {
        s.push('_');
    }
    s
}

const KEYWORDS: [&str; 37] = [
    "auto",
    "break",
    "case",
    "char",
    "const",
    "continue",
    "default",
    "do",
    "double",
    "else",
    "enum",
    "extern",
    "float",
    "for",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "register",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "struct",
    "switch",
    "typedef",
    "union",
    "unsigned",
    "void",
    "volatile",
    "while",
    "_Bool",
    "_Complex",
    "_Imaginary",
];

fn greek(ch: char) -> Option<&'static str> {
    const LOWER: [&str; 25] = [
        "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
        "lambda", "mu", "nu", "xi", "omicron", "pi", "rho", "sigmaf", "sigma", "tau", "upsilon",
        "phi", "chi", "psi", "omega",
    ];
    const UPPER: [&str; 25] = [
        "Alpha", "Beta", "Gamma", "Delta", "Epsilon", "Zeta", "Eta", "Theta", "Iota", "Kappa",
        "Lambda", "Mu", "Nu", "Xi", "Omicron", "Pi", "Rho", "", "Sigma", "Tau", "Upsilon", "Phi",
        "Chi", "Psi", "Omega",
    ];
    let code = ch as u32;
    let name = match code {
        0x3b1..=0x3c9 => LOWER[(code - 0x3b1) as usize],
        0x391..=0x3a9 => UPPER[(code - 0x391) as usize],
        _ => "",
    };
    (!name.is_empty()).then_some(name)
}

/// `text` as a C string literal: printable ASCII as it is, every other byte (UTF-8 included)
/// as an octal escape, which cannot run into a following digit as a hex escape would.
fn string(text: &str) -> String {
    let mut s = String::from("\"");
    for b in text.bytes() {
        match b {
            // `?` escaped too: `??=` and the other trigraphs are read even in a string.
            b'"' | b'\\' | b'?' => {
                s.push('\\');
                s.push(b as char);
            }
            0x20..=0x7e => s.push(b as char),
            _ => {
                let _ = write!(s, "\\{b:03o}");
            }
        }
    }
    s.push('"');
    s
}

/// The names a module exports, as the scene writes them, and the parameters' fields.
struct Names {
    parameters: Vec<String>,
    /// The parameters' fields in the struct: their names made identifiers, made unique.
    fields: Vec<String>,
    parameter_units: Vec<String>,
    states: Vec<String>,
    inputs: Vec<String>,
    input_units: Vec<String>,
}

impl Names {
    fn of(e: &Equations) -> Names {
        let model = &e.prepared.derivation.model;
        let unit = |u: &Option<lang::Unit>| {
            u.as_ref().and_then(|u| model::units::si_text(u).ok()).unwrap_or_default()
        };
        // A caller sets the free parameters; the derived ones follow them in `gather`.
        let parameters: Vec<String> =
            e.free.iter().map(|i| model.params[*i].name.clone()).collect();
        let mut fields: Vec<String> = Vec::new();
        for p in &parameters {
            let mut field = identifier(p);
            while fields.contains(&field) {
                field.push('_');
            }
            fields.push(field);
        }
        Names {
            parameters,
            fields,
            parameter_units: e.free.iter().map(|i| unit(&model.params[*i].unit)).collect(),
            states: e.prepared.state_names(),
            inputs: model.inputs.iter().map(|u| u.name.clone()).collect(),
            input_units: model.inputs.iter().map(|u| unit(&u.unit)).collect(),
        }
    }
}

/// The fields of `NAME_parameters`, in the parameters' order: what a wrapper (the FMU's)
/// addresses them by.
pub fn parameter_fields(e: &Equations) -> Vec<String> {
    Names::of(e).fields
}

/// The signature of a function of the state: `(t, y, p, u, out)`.
fn of_state(name: &str, function: &str, out: &str) -> String {
    format!(
        "int {name}_{function}(double t, const double *y, const {name}_parameters *p, \
         const double *u, double *{out})"
    )
}

fn header(e: &Equations, name: &str, path: &str, names: &Names) -> String {
    let sizes = e.sizes;
    let (n, m) = (sizes.coordinates, sizes.constraints);
    let guard = format!("{}_H", name.to_uppercase());
    // Each line made safe whole: the path is the user's too.
    let mut s = comment(
        &ascii_lines(&format!(
            "Equations of motion of \"{}\", generated by `lagrange codegen --lang c {}`.\n\
             C99; needs only libm. Do not edit: regenerate from the scene.\n\
             \n\
             y = (q, qdot) with q = ({}); M(q, t) qddot = f(q, qdot, u, t){}.\n\
             The functions returning int return 0, or 1 when a system they solve is singular.\n\
             u may be NULL when {name}_INPUTS is 0.{}",
            ascii(&e.title),
            ascii(path),
            ascii(&names.states[..n].join(", ")),
            if m > 0 {
                format!(
                    " + J^T lambda, J qddot = gamma,\nwith gamma Baumgarte-stabilised (rate {}/s) as \
                     lagrange simulate holds kept constraints",
                    sim::BAUMGARTE_RATE
                )
            } else {
                String::new()
            },
            if sizes.contacts > 0 {
                "\nThe contacts' rows are among the constraints'; rhs and the functions like it hold\n\
                 every contact open (lambda = 0 there). impact gives the rates after an impact."
            } else {
                ""
            },
        )),
        "",
    );
    let _ = writeln!(s, "#ifndef {guard}\n#define {guard}\n");
    s.push_str("#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n");
    let counts = [
        ("COORDINATES", n, "q"),
        ("STATES", 2 * n, "y = (q, qdot)"),
        ("CONSTRAINTS", m, "kept with multipliers"),
        ("PARAMETERS", sizes.free_parameters, "fields of the parameters"),
        ("INPUTS", sizes.inputs, "u"),
        ("OUTPUTS", e.outputs.len(), "the scene's `output` lines"),
        ("REACTIONS", e.reactions.len(), "the reactions the scene names"),
        ("CONTACTS", sizes.contacts, "one-sided contacts, their rows among the constraints"),
    ];
    for (what, count, doc) in counts {
        let _ = writeln!(s, "#define {name}_{what} {count} /* {doc} */");
    }
    s.push('\n');
    let derived = &e.prepared.derivation.model.params;
    let derived: Vec<String> = e.derived.iter().map(|(i, _)| derived[*i].name.clone()).collect();
    let about = if derived.is_empty() {
        "The scene's parameters, in SI units.".to_string()
    } else {
        format!(
            "The scene's free parameters, in SI units. The derived ones ({}) are not\n\
             fields: every function computes them from these, as the scene defines them.",
            ascii(&derived.join(", "))
        )
    };
    s.push_str(&comment(&about, ""));
    s.push_str("typedef struct {\n");
    if names.fields.is_empty() {
        s.push_str("    char none; /* the scene has no parameters; C has no empty struct */\n");
    }
    for ((field, scene), unit) in
        names.fields.iter().zip(&names.parameters).zip(&names.parameter_units)
    {
        let _ = writeln!(
            s,
            "    double {field}; /* {} */",
            ascii(&format!("{scene} {unit}")).trim_end()
        );
    }
    let _ = writeln!(s, "}} {name}_parameters;\n");
    let declarations = [
        ("const {name}_parameters {name}_default_parameters", "The scene's values."),
        (
            "const char *const {name}_parameter_names[]",
            "Each parameter's name in the scene (UTF-8), then NULL; and its SI unit as\nModelica writes units (\"\" where the scene gives none).",
        ),
        ("const char *const {name}_parameter_units[]", ""),
        ("const char *const {name}_state_names[]", "The coordinates, then their rates (x'), then NULL."),
        ("const char *const {name}_input_names[]", "The inputs' names, then NULL; and their SI units."),
        ("const char *const {name}_input_units[]", ""),
        ("const char *const {name}_output_names[]", "The outputs, then NULL."),
        ("const char *const {name}_reaction_names[]", "The reactions, then NULL."),
        ("const char *const {name}_contact_names[]", "The contacts, in the order written, then NULL."),
        (
            "const int {name}_contact_rows[]",
            "Per contact, its normal row's slot among the constraints, then its grip row's\n(-1 when it does not grip): 2 {name}_CONTACTS values (one unused -1 when there\nare none).",
        ),
        (
            "const double {name}_default_inputs[]",
            "The inputs' declared values ({name}_INPUTS of them; one unused 0 when there\nare none, as C has no empty array).",
        ),
    ];
    for (declaration, doc) in declarations {
        s.push_str(&comment(&doc.replace("{name}", name), ""));
        let _ = writeln!(s, "extern {};", declaration.replace("{name}", name));
    }
    s.push('\n');
    s.push_str(&function_declarations(e, name));
    s.push_str("#ifdef __cplusplus\n}\n#endif\n\n");
    let _ = writeln!(s, "#endif /* {guard} */");
    s
}

/// The functions' declarations in the header, each with what it computes.
fn function_declarations(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let fixed = e.fixed_start();
    let start_doc = if fixed.is_empty() {
        "The scene's start y = (q, qdot) at the parameters p.".to_string()
    } else {
        format!(
            "The scene's start y = (q, qdot) at the parameters p. The start of {} was solved\n\
             numerically from the kept constraints at the scene's values, so it is a fixed number\n\
             here whatever p holds.",
            ascii(&fixed.join(", "))
        )
    };
    let mut s = comment(&start_doc, "");
    let _ = writeln!(s, "void {name}_initial_state(const {name}_parameters *p, double *y);");
    let state = [
        ("mass_matrix", "M", format!("The mass matrix M, {n} by {n}, column-major.")),
        ("forcing", "f", "The forcing f.".to_string()),
        (
            "constraints",
            "rows",
            format!(
                "Per kept constraint, {} values: its row of J ({n}), then gamma, Phi and\nd(Phi)/dt.",
                n + 3
            ),
        ),
        (
            "rhs",
            "dy",
            "dy = (qdot, qddot), solving M qddot = f (with kept constraints, the system\n[M -J^T; J 0] (qddot, lambda) = (f, gamma), not stabilised).".to_string(),
        ),
        (
            "jacobian",
            "jac",
            format!("The exact Jacobian of rhs, d(dy)/dy, {0} by {0}, row-major.", 2 * n),
        ),
        ("outputs", "out", "The scene's outputs, in order.".to_string()),
        ("energies", "ke_pe", "The kinetic energy, then the potential energy.".to_string()),
        (
            "reactions",
            "out",
            "The reactions, in order, at the accelerations rhs solves for.".to_string(),
        ),
    ];
    for (function, out, doc) in state {
        if function == "constraints" && m == 0 {
            s.push_str(&comment("The scene keeps no constraint: writes nothing.", ""));
        } else {
            s.push_str(&comment(&doc, ""));
        }
        let _ = writeln!(s, "{};", of_state(name, function, out));
    }
    s.push_str(&comment(
        "Inverse dynamics: the generalized forces tau = M qddot - f that make the motion\n\
         (q, qd, qdd) happen when added to f; with kept constraints, the one least in\n\
         tau^T M^-1 tau.",
        "",
    ));
    let _ = writeln!(
        s,
        "int {name}_inverse_dynamics(double t, const double *q, const double *qd, \
         const double *qdd, const {name}_parameters *p, const double *u, double *tau);\n"
    );
    if e.sizes.contacts > 0 {
        s.push_str(&comment(
            &format!(
                "Per contact, its gap g (open where g > 0), then its normal rate gamma = dg/dq qd +\n\
                 dg/dt: 2 {name}_CONTACTS values. rhs, jacobian, reactions and inverse_dynamics\n\
                 hold every contact open (lambda = 0 at its rows, as a run holds an open contact):\n\
                 integrate a flight with them, watch the gaps, and call impact where some reach 0\n\
                 closing."
            ),
            "",
        ));
        let _ = writeln!(
            s,
            "void {name}_gaps(double t, const double *q, const double *qd, \
             const {name}_parameters *p, const double *u, double *out);\n"
        );
        s.push_str(&comment(
            &format!(
                "{}\ntouching has {name}_CONTACTS flags (nonzero: touching), qd_plus {n} values, impulses\n{name}_CONSTRAINTS.",
                super::impact::contract(&[
                    ("(solved)", 0),
                    ("(the two-sided constraints' system is singular)", 1),
                    ("(no active set holds: no solution)", 2),
                    ("(more than 20 contacts touch)", 3),
                ])
            ),
            "",
        ));
        let _ = writeln!(
            s,
            "int {name}_impact(double t, const double *q, const double *qd_minus, \
             const {name}_parameters *p, const double *u, const int *touching, double *qd_plus, \
             double *impulses);\n"
        );
    }
    s
}

/// Text for a C comment: printable ASCII, the rest as `?`. A comment must not end early
/// (`*/`), nor open another (`/*`, which `-Wall` refuses), nor hold a trigraph (`??/` and the
/// others, which C99 reads even in a comment): `??` is kept apart as `? ?`.
fn ascii(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        let c = if matches!(c, ' '..='~') { c } else { '?' };
        // `*/` and `/*` are broken at their second character, `??` likewise.
        if matches!((s.chars().last(), c), (Some('*'), '/') | (Some('/'), '*') | (Some('?'), '?')) {
            s.push(' ');
        }
        s.push(c);
    }
    s
}

/// The source file: the data, the helpers, the programs and the functions of the state.
fn implementation(e: &Equations, name: &str, path: &str, names: &Names) -> String {
    let mut doc = format!(
        "Equations of motion of \"{}\", generated by `lagrange codegen --lang c {}`.\n\
         Operation counts per call:\n",
        ascii(&e.title),
        ascii(path)
    );
    for (program, p) in &e.programs {
        let _ = writeln!(doc, "  {program}: {}", p.op_counts());
    }
    let mut s = comment(&ascii_lines(&doc), "");
    let _ = writeln!(s, "#include <math.h>\n#include <stddef.h>\n\n#include \"{name}.h\"\n");
    s.push_str(&data(e, name, names));
    let programs: Vec<&numeric::Program> = e
        .programs
        .iter()
        .map(|(_, p)| p)
        .chain([&e.start])
        .chain(e.derived.iter().map(|(_, p)| p))
        .collect();
    s.push_str(&helpers(&programs));
    if e.sizes.contacts > 0 {
        s.push('\n');
        s.push_str(&super::impact::c_solver(e.contact_slots().len()));
    }
    for (program, p) in &e.programs {
        s.push('\n');
        s.push_str(&function(p, &format!("eval_{program}"), &program_doc(program)));
    }
    s.push('\n');
    s.push_str(&function(&e.start, "eval_start", "The start from [t, parameters, inputs]."));
    s.push('\n');
    let params = &e.prepared.derivation.model.params;
    for (i, program) in &e.derived {
        let doc = format!("The derived parameter {} from [parameters, inputs].", params[*i].name);
        s.push_str(&function(program, &format!("eval_derived_{i}"), &ascii(&doc)));
        s.push('\n');
    }
    s.push_str(&gather(e, name, names));
    s.push_str(&functions::all(e, name));
    s
}

fn ascii_lines(text: &str) -> String {
    text.lines().map(ascii).collect::<Vec<_>>().join("\n")
}

fn program_doc(program: &str) -> String {
    match program {
        "mass_matrix" => "M, column-major, from [t, q, qdot, parameters, inputs].",
        "forcing" => "f, from [t, q, qdot, parameters, inputs].",
        "accelerations" => {
            "qddot by the articulated-body sweep of the scene's tree of bodies, O(n), from\n\
             [t, q, qdot, parameters, inputs]: what rhs gives without forming M where every\n\
             value is finite."
        }
        "constraints" => "Per kept constraint: J's row, gamma, Phi, d(Phi)/dt.",
        "partials" => {
            "With qddot and lambda held: d/dq then d/dqdot of r = M qddot - J^T lambda - f\n\
             (a row per coordinate), then of c = J qddot - gamma (a row per kept constraint),\n\
             from [t, q, qdot, qddot, lambda, parameters, inputs]."
        }
        "energies" => "KE and PE, from [t, q, qdot, parameters, inputs].",
        "restitutions" => "Each contact's coefficient of restitution, from [parameters, inputs].",
        "reactions" => "The reactions, from [t, q, qdot, qddot, lambda, parameters, inputs].",
        _ => "The outputs, from [t, q, qdot, parameters, inputs].",
    }
    .to_string()
}

/// The definitions of the exported data.
fn data(e: &Equations, name: &str, names: &Names) -> String {
    let k = e.sizes.parameters;
    let free = e.free.len();
    let mut s = format!("const {name}_parameters {name}_default_parameters = {{\n");
    if free == 0 {
        s.push_str("    0\n");
    }
    let values = e.free.iter().map(|i| e.values[*i]);
    for (i, (value, scene)) in values.zip(&names.parameters).enumerate() {
        let comma = if i + 1 < free { "," } else { "" };
        let _ = writeln!(s, "    {}{comma} /* {} = {value:?} */", literal(value), ascii(scene));
    }
    s.push_str("};\n\n");
    let lists = [
        ("parameter_names", &names.parameters),
        ("parameter_units", &names.parameter_units),
        ("state_names", &names.states),
        ("input_names", &names.inputs),
        ("input_units", &names.input_units),
        ("output_names", &e.outputs),
        ("reaction_names", &e.reactions),
        ("contact_names", &e.contact_names()),
    ];
    for (list, items) in lists {
        let mut entries: Vec<String> = items.iter().map(|t| string(t)).collect();
        entries.push("NULL".to_string());
        let _ = writeln!(s, "const char *const {name}_{list}[] = {{ {} }};", entries.join(", "));
    }
    let mut slots: Vec<String> = Vec::new();
    for c in &e.prepared.contacts {
        slots.push(c.normal.to_string());
        slots.push(c.grip.map_or(-1, |g| g as i64).to_string());
    }
    if slots.is_empty() {
        slots.push("-1".to_string());
    }
    let _ = writeln!(s, "const int {name}_contact_rows[] = {{ {} }};", slots.join(", "));
    let inputs: Vec<String> = e.values[k..].iter().map(|v| literal(*v)).collect();
    let inputs =
        if inputs.is_empty() { "0.0 /* no inputs */".to_string() } else { inputs.join(", ") };
    let _ = writeln!(s, "const double {name}_default_inputs[] = {{ {inputs} }};\n");
    s
}

/// `gather`: the slot vector [t, q, qdot, parameters, inputs] the programs read.
fn gather(e: &Equations, name: &str, names: &Names) -> String {
    let sizes = e.sizes;
    let n = sizes.coordinates;
    let mut s = comment("[t, q, qdot, parameters, inputs], the slots the programs read.", "");
    let _ = writeln!(
        s,
        "static void gather(double t, const double *q, const double *qd, \
         const {name}_parameters *p, const double *u, double *input)\n{{"
    );
    s.push_str("    int i;\n");
    // Without parameters or inputs, `-Wextra` would warn of the argument not read.
    if sizes.free_parameters == 0 {
        s.push_str("    (void)p;\n");
    }
    if sizes.inputs == 0 {
        s.push_str("    (void)u;\n");
    }
    s.push_str("    input[0] = t;\n");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {n}; i++) {{\n        input[1 + i] = q[i];\n        input[{} + i] = qd[i];\n    }}",
        1 + n
    );
    for (i, field) in e.free.iter().zip(&names.fields) {
        let _ = writeln!(s, "    input[{}] = p->{field};", 1 + 2 * n + i);
    }
    for i in 0..sizes.inputs {
        let _ = writeln!(s, "    input[{}] = u[{i}];", 1 + 2 * n + sizes.parameters + i);
    }
    // Each derived parameter from the slots before it, in declaration order.
    for (i, _) in &e.derived {
        let slot = 1 + 2 * n;
        let _ = writeln!(s, "    eval_derived_{i}(input + {slot}, input + {});", slot + i);
    }
    s.push_str("}\n\n");
    s
}

#[cfg(test)]
mod tests {
    use super::{identifier, string};

    #[test]
    fn names_become_identifiers_c_accepts() {
        assert_eq!(identifier("double_pendulum"), "double_pendulum");
        assert_eq!(identifier("θ"), "theta");
        assert_eq!(identifier("Ω₁"), "Omegau2081");
        assert_eq!(identifier("int"), "int_");
        assert_eq!(identifier("_hidden"), "scene__hidden");
        assert_eq!(identifier("5-link"), "scene_5u2dlink");
        assert_eq!(identifier(""), "scene_");
    }

    #[test]
    fn strings_escape_what_is_not_printable_ascii() {
        assert_eq!(string("x'"), "\"x'\"");
        assert_eq!(string("a\"b\\"), "\"a\\\"b\\\\\"");
        assert_eq!(string("θ1"), "\"\\316\\2701\"");
        assert_eq!(string("??="), "\"\\?\\?=\"");
    }

    #[test]
    fn comments_neither_end_nor_open_nor_hold_a_trigraph() {
        assert_eq!(super::ascii("a */ b /* c"), "a * / b / * c");
        assert_eq!(super::ascii("*/*/"), "* / * /");
        assert_eq!(super::ascii("θ̇ ??/"), "? ? ? ?/");
        assert_eq!(super::ascii("line\nbreak"), "line?break");
    }
}
