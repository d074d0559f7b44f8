//! `lagrange export --fmu`: the archive holds what FMI 2.0 asks for, the binary exports the
//! FMI functions, and a missing compiler is a clear error. FMPy's validation and the runs
//! against `simulate` are in tests/fmu/check_fmu.py, which CI runs.

use std::io::Read;

use export::fmu::{ExportOptions, Fmu};

fn scene(path: &str) -> String {
    std::fs::read_to_string(format!("{}/../{path}", env!("CARGO_MANIFEST_DIR"))).expect("reads")
}

/// The FMU of an example, as `lagrange export` makes it.
fn export(path: &str) -> Fmu {
    export::fmu::export(path, &scene(path), &ExportOptions::default()).expect("exports")
}

const PENDULUM: &str = "examples/classics/double_pendulum.lag";

#[test]
fn the_archive_holds_the_description_the_binary_the_sources_and_the_documentation() {
    let fmu = export(PENDULUM);
    let dir = tempfile_dir();
    let out = dir.join("double_pendulum.fmu");
    // The sources compile without a warning, as the C generator's do.
    let strict = format!("{} -Wall -Wextra -Werror -pedantic", cli::export::compiler());
    cli::export::export(&fmu, &strict, &out).expect("compiles and writes");
    let bytes = std::fs::read(&out).expect("written");
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("a zip archive");
    let names: Vec<String> = zip.file_names().map(String::from).collect();
    let (platform, extension) = Fmu::platform();
    for expected in [
        "modelDescription.xml".to_string(),
        format!("binaries/{platform}/double_pendulum.{extension}"),
        "sources/double_pendulum.c".into(),
        "sources/double_pendulum.h".into(),
        "sources/fmu.c".into(),
        "sources/fmi2.h".into(),
        "sources/dop853.c".into(),
        "sources/dop853_tableau.h".into(),
        "documentation/index.html".into(),
    ] {
        assert!(names.contains(&expected), "{expected} missing from {names:?}");
    }
    let mut description = String::new();
    zip.by_name("modelDescription.xml").expect("entry").read_to_string(&mut description).unwrap();
    assert!(description.contains("<ModelExchange modelIdentifier=\"double_pendulum\""));
    assert!(description.contains("<CoSimulation modelIdentifier=\"double_pendulum\""));
    assert!(description.contains("name=\"der(theta2')\""), "{description}");
    assert!(description.contains(&format!("guid=\"{}\"", guid_of(&fmu))));
    // g = 9.81 m/s^2: a tunable parameter in its SI unit, declared by its base.
    assert!(description.contains("<Unit name=\"m/s2\"><BaseUnit m=\"1\" s=\"-2\"/></Unit>"));
    assert!(description.contains("<Real start=\"9.81e0\" unit=\"m/s2\"/>"), "{description}");
    // Both angles start at π/2, as the scene puts them.
    let start = format!("<Real start=\"{:e}\"/>", std::f64::consts::FRAC_PI_2);
    assert_eq!(description.matches(&start).count(), 2, "{description}");
    // The DOP853 tableau printed into C reads back to the bits `sim` steps with.
    let tableau = &fmu.sources.iter().find(|s| s.0 == "dop853_tableau.h").unwrap().1;
    let t = sim::dop853_tableau();
    for x in t.a.iter().flat_map(|row| row.iter()).chain(t.b).chain(t.e5) {
        assert!(tableau.contains(&format!("{x:e}")), "{x:e} missing");
    }
    std::fs::remove_dir_all(&dir).ok();
}

fn guid_of(fmu: &Fmu) -> String {
    let header = &fmu.sources.iter().find(|s| s.0 == "fmu_model.h").expect("shim").1;
    let line = header.lines().find(|l| l.starts_with("#define MODEL_GUID")).expect("GUID");
    line.split('"').nth(1).expect("quoted").to_string()
}

#[test]
fn without_a_compiler_the_export_says_so_and_writes_nothing() {
    let fmu = export(PENDULUM);
    let dir = tempfile_dir();
    let out = dir.join("nothing.fmu");
    let error = cli::export::export(&fmu, "/nonexistent/cc", &out).expect_err("no compiler");
    let message = error.to_string();
    assert!(
        message.starts_with("no C compiler: `/nonexistent/cc` could not be started"),
        "{message}"
    );
    assert!(message.contains("CC environment variable"), "{message}");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// Corner scenes (derived without the dimension check): no parameter and no input; names C
/// reserves or spells otherwise, with an input and outputs.
const CORNERS: [(&str, &str); 2] = [
    ("nothing.lag", "coord x = 1/2\nparticle p { mass 1; position (x, 0) }\npotential x^2/2\n"),
    (
        "int.lag",
        "param double = 2, α = 3\ninput int = 1\ncoord x = double/10\n\
         particle p { mass double; position (x, 0) }\npotential α*x^2/2\n\
         force drive on p: (int, 0)\noutput doubled: 2*x*int\n",
    ),
];

#[test]
fn corner_scenes_compile_without_a_warning() {
    let dir = tempfile_dir();
    for (path, source) in CORNERS {
        let options = ExportOptions { no_units: true, ..Default::default() };
        let fmu = export::fmu::export(path, source, &options).expect("exports");
        let strict = format!("{} -Wall -Wextra -Werror -pedantic", cli::export::compiler());
        let out = dir.join(path).with_extension("fmu");
        cli::export::export(&fmu, &strict, &out).unwrap_or_else(|e| panic!("{path}: {e}"));
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_output_named_as_another_variable_is_refused() {
    for (name, other) in [("KE", "the kinetic energy"), ("m", "the parameter")] {
        let source = format!(
            "param m = 1 kg, g = 9.81 m/s^2\ncoord x\nparticle p {{ mass m; position (0, x) }}\n\
             gravity g\noutput {name}: x\n"
        );
        let Err(engine::Error::Input(message)) =
            export::fmu::export("scene.lag", &source, &ExportOptions::default())
        else {
            panic!("an output named as {other} is refused");
        };
        assert!(message.contains(&format!("would be named `{name}`")), "{message}");
    }
}

#[test]
fn an_export_is_reproducible() {
    let (a, b) = (export(PENDULUM), export(PENDULUM));
    assert_eq!(a.model_description, b.model_description);
    assert_eq!(a.sources, b.sources);
}

/// A fresh folder in the system's temporary space.
fn tempfile_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "lagrange-fmu-test-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}
