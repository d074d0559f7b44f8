//! The `lagrange` binary end to end: output, exit codes, and files written whole; the
//! settings of a run as the scene writes them (`cli/settings.rs`) and what written files
//! replace (`cli/writes.rs`), one test binary with the helpers they share.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lagrange(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lagrange")).args(args).output().expect("the binary runs")
}

fn example(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

#[path = "cli/settings.rs"]
mod settings;
#[path = "cli/writes.rs"]
mod writes;

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A temporary folder for one test, removed when the test ends (and emptied when it starts, in
/// case an earlier run of the same process id left it).
struct Scratch(PathBuf);

impl Scratch {
    fn new(test: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("lagrange-cli-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Scratch(dir)
    }

    fn file(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn path(&self, name: &str) -> String {
        self.file(name).to_string_lossy().into_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn derive_prints_the_rod_exactly() {
    let out = lagrange(&["derive", &example("ps5/falling_rod.lag")]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("(1 + 3·sin²(θ))·θ̈ + 3·sin(θ)·cos(θ)·θ̇² = 6·g·sin(θ)/L"), "{text}");
    assert!(text.contains("θ̈ = 12/7·g/L"), "{text}");
    assert!(text.contains("floor.force = 4/7·m·g"), "{text}");
}

#[test]
fn check_exit_codes() {
    let ok = lagrange(&["check", &example("ps5/falling_rod.lag"), &example("ps5/wedge.lag")]);
    assert_eq!(ok.status.code(), Some(0), "{}", String::from_utf8_lossy(&ok.stdout));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("7 passed, 0 failed"));

    let scratch = Scratch::new("exit-codes");
    let wrong = scratch.file("wrong.lag");
    std::fs::write(
        &wrong,
        "param m, g\ncoord x\nparticle p { mass m; position (0, x) }\ngravity g\nexpect x'' = g\n",
    )
    .expect("write");
    let fail = lagrange(&["check", wrong.to_str().expect("path")]);
    assert_eq!(fail.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&fail.stdout).contains("wrong.lag:5"));

    let bad = scratch.file("bad.lag");
    std::fs::write(&bad, "param m\ncoord x\nparticle p { mass m; position (x, 0) \n")
        .expect("write");
    let broken = lagrange(&["check", bad.to_str().expect("path")]);
    assert_eq!(broken.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&broken.stderr).contains("bad.lag:"));

    let missing = lagrange(&["derive", "no/such/file.lag"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("cannot read"));
}

#[test]
fn derive_out_writes_the_whole_file() {
    let scratch = Scratch::new("out");
    let target = scratch.file("rod.json");
    let out = lagrange(&[
        "derive",
        &example("ps5/falling_rod.lag"),
        "--format",
        "json",
        "--out",
        target.to_str().expect("path"),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let written = std::fs::read_to_string(&target).expect("written");
    let parsed: serde_json::Value = serde_json::from_str(&written).expect("whole JSON");
    assert_eq!(parsed["at_start"]["floor.force"], "4/7*m*g");
    let leftovers: Vec<_> = std::fs::read_dir(target.parent().expect("dir"))
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

#[test]
fn every_bad_scene_exits_2_from_derive_check_and_simulate() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/bad exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    for file in &files {
        let path = file.to_str().expect("path");
        let name = file.file_name().expect("name").to_string_lossy().into_owned();
        for command in ["derive", "check", "simulate"] {
            let out = lagrange(
                &[command, path, "--until", "0.01"][..if command == "simulate" { 4 } else { 2 }],
            );
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{command} {name}:\n{stderr}");
            assert!(
                stderr.contains(&format!("{name}:")),
                "{command} {name}: no location in\n{stderr}"
            );
        }
    }
}

#[test]
fn a_file_that_is_not_utf8_gets_the_line_and_column_of_its_first_bad_byte() {
    let scratch = Scratch::new("latin1");
    let file = scratch.file("bad.lag");
    // `é` in Latin-1 (0xE9), in a comment on line 4.
    let mut bytes =
        b"param m = 1 kg\ncoord x\nparticle p { mass m; position (x, 0) }\n# caf".to_vec();
    bytes.extend([0xE9, b'\n']);
    std::fs::write(&file, &bytes).expect("write");
    let path = file.to_str().expect("path");
    for command in ["derive", "check", "simulate"] {
        let out = lagrange(&[command, path]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}:\n{stderr}");
        assert!(stderr.contains("error: the file is not valid UTF-8"), "{command}:\n{stderr}");
        assert!(stderr.contains("bad.lag:4:6"), "{command}:\n{stderr}");
        assert!(stderr.contains("^ byte 0xE9 is not UTF-8"), "{command}:\n{stderr}");
        assert!(stderr.contains("in Latin-1, byte 0xE9 is `é`"), "{command}:\n{stderr}");
    }
    // Columns count characters, not bytes, up to the bad one.
    let rendered =
        cli::decode("θ.lag", b"coord \xCE\xB8 = \xFF\n".to_vec()).expect_err("not UTF-8");
    assert!(rendered.contains("θ.lag:1:11"), "{rendered}");
    assert_eq!(cli::decode("ok.lag", "coord θ\n".into()).as_deref(), Ok("coord θ\n"));
}

#[test]
fn set_cannot_make_a_mass_negative() {
    let pendulum = example("classics/simple_pendulum.lag");
    let out = lagrange(&["simulate", &pendulum, "--until", "0.01", "--set", "m=-1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`bob` has a mass of -1 kg; a mass must be positive"), "{stderr}");
    let out = lagrange(&["simulate", &pendulum, "--until", "0.01", "--set", "m=2"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

/// The engine names settings abstractly; the command line words them as its flags.
#[test]
fn settings_are_named_by_their_flags() {
    let pendulum = example("classics/simple_pendulum.lag");
    for (args, said) in [
        (&["--until=-1"][..], "error: --until must be a positive time, not -1"),
        (&["--set", "gg=1"][..], "error: --set gg: no parameter or coordinate of that name"),
        (&["--set", "m=-1"][..], "error: with the values of --set, `bob` has a mass of -1 kg"),
        (&["--set", "m"][..], "'--set <NAME=VALUE>': not of the form name=value (like g=1.62)"),
    ] {
        let out = lagrange(&[&["simulate", pendulum.as_str()][..], args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(said), "{args:?}: {stderr}");
    }
    let out = lagrange(&["linearize", &pendulum, "--sweep", "w=0:1:3"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("give the reference with --about theta=0"), "{stderr}");
    let cart = example("classics/inverted_pendulum_on_cart.lag");
    let out = lagrange(&["linearize", &cart, "--sweep", "w=0:1:3"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("error: --sweep w: no parameter of that name"), "{stderr}");
}

#[test]
fn bench_runs_what_it_can_on_a_scene_with_a_multiplier() {
    let scratch = Scratch::new("bench-multiplier");
    let plot = scratch.file("wp.svg");
    let out = lagrange(&[
        "bench",
        &example("classics/pendulum_cartesian.lag"),
        "--until",
        "0.1",
        "--repeats",
        "1",
        "--plot",
        plot.to_str().expect("path"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    for method in ["rk4", "dopri5", "dop853"] {
        let rows = stdout.lines().filter(|l| l.starts_with(method)).count();
        assert!(rows >= 8, "{method} has {rows} rows:\n{stdout}");
        assert!(!stdout.contains(&format!("{method} not applicable")), "{stdout}");
    }
    for method in ["midpoint", "gauss"] {
        let rows: Vec<&str> = stdout.lines().filter(|l| l.starts_with(method)).collect();
        assert_eq!(rows.len(), 1, "{stdout}");
        assert!(rows[0].contains("not applicable: works in canonical variables"), "{stdout}");
    }
    let svg = std::fs::read_to_string(&plot).expect("the plot is written");
    assert!(svg.contains(">not applicable:<"), "{svg}");
    assert!(svg.contains(">midpoint<title>") && svg.contains(">gauss<title>"), "{svg}");
}

#[test]
fn linearize_prints_exits_and_plots() {
    let pendulum = example("classics/simple_pendulum.lag");
    let out = lagrange(&["linearize", &pendulum, "--about", "theta=pi"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("K = [ −m·L·g ]") && text.contains("Unstable"), "{text}");

    let out = lagrange(&["linearize", &pendulum, "--about", "theta=1"]);
    assert_eq!(out.status.code(), Some(2));
    let errors = String::from_utf8(out.stderr).expect("utf-8");
    assert!(errors.contains("not an equilibrium") && errors.contains("θ̈ = "), "{errors}");

    let scratch = Scratch::new("linearize");
    let plot = scratch.file("top.svg");
    let plot_arg = plot.to_string_lossy().into_owned();
    let top = example("space/sleeping_top.lag");
    let args =
        ["linearize", &top, "--sweep", "w=0:100:21", "--plot", &plot_arg, "--format", "json"];
    let out = lagrange(&args);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["linearization"]["sweep"].as_array().map(Vec::len), Some(21));
    let svg = std::fs::read_to_string(&plot).expect("the plot is written");
    assert!(svg.starts_with("<svg") && svg.contains("stroke-dasharray"));

    // A plot needs a sweep to draw.
    let out = lagrange(&["linearize", &top, "--plot", &plot_arg]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn simulate_animates_into_a_page() {
    let scratch = Scratch::new("animate");
    let page = scratch.file("rod.html");
    let csv = scratch.file("rod.csv");
    let rod = example("ps5/falling_rod.lag");
    let (csv_arg, page_arg) = (csv.to_str().expect("path"), page.to_str().expect("path"));
    let out = lagrange(&["simulate", &rod, "--out", csv_arg, "--animate", page_arg]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let html = std::fs::read_to_string(&page).expect("the page is written");
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    assert!(html.contains("<title>Rod falls with its end on a frictionless floor</title>"));
    // 1000 frames by default with --animate, up to where the rod lies flat.
    let frames = std::fs::read_to_string(&csv).expect("csv").lines().count() - 1;
    assert!(frames > 300, "{frames} frames");

    // Only .html is an animation; nothing is written for another name.
    let wrong = scratch.file("rod.svg");
    let out = lagrange(&["simulate", &rod, "--animate", wrong.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("use .html"));
    assert!(!wrong.exists());
}

/// A reader that stops reading (`lagrange simulate … | head -1`) ends the output, not the
/// command with a panic: the exit code stays the command's own.
#[test]
fn a_reader_that_stops_reading_is_not_a_panic() {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_lagrange"))
        .args(["simulate", &example("classics/double_pendulum.lag"), "--until", "50"])
        .args(["--samples", "200000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let mut stdout = child.stdout.take().expect("piped");
    let mut first = [0u8; 16];
    stdout.read_exact(&mut first).expect("the header comes first");
    drop(stdout);
    let output = child.wait_with_output().expect("it ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(output.status.code(), Some(0), "{stderr}");
}

#[test]
fn inverse_dynamics_reads_a_simulate_table_and_writes_the_forces() {
    let scratch = Scratch::new("inverse");
    let (run, forces) = (scratch.file("run.csv"), scratch.file("tau.csv"));
    let flywheel = example("classics/driven_flywheel.lag");
    let out = lagrange(&[
        "simulate",
        &flywheel,
        "--until",
        "2",
        "--samples",
        "11",
        "--output",
        "KE, theta, theta', theta''",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // With the motor off in the scene, the force the motion takes is the motor's, 2 N·m.
    let args = ["inverse-dynamics", &flywheel, "--trajectory", run.to_str().unwrap()];
    let out =
        lagrange(&[&args[..], &["--set", "tau=0", "--out", forces.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stdout.is_empty() && out.stderr.is_empty());
    let table = std::fs::read_to_string(&forces).unwrap();
    let mut lines = table.lines();
    assert_eq!(lines.next(), Some("t,tau_theta"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 11);
    for row in rows {
        let tau: f64 = row.split(',').nth(1).unwrap().parse().unwrap();
        assert!((tau - 2.0).abs() < 1e-9, "{row}");
    }

    std::fs::write(&run, "t,theta,theta',theta''\n0,0,0,4\n0.1,0.02,0.4,four\n").unwrap();
    let out = lagrange(&args);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.ends_with("run.csv:3:4: `four` in the column `theta''` is not a finite number\n"),
        "{stderr}"
    );
    let out = lagrange(&[&args[..], &["--set", "J=1"]].concat());
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8(out.stderr).unwrap(),
        "error: --set J: no parameter of that name; one of I, tau, b\n"
    );
}

#[test]
fn auto_says_where_each_method_ran_and_a_stiff_rk4_run_says_why_it_failed() {
    let stiff = example("classics/stiff_spring_pendulum.lag");
    let scratch = Scratch::new("auto");
    let json = scratch.file("auto.json");
    let json_arg = json.to_string_lossy().into_owned();
    let out =
        lagrange(&["simulate", &stiff, "--set", "k=1e10", "--method", "auto", "--out", &json_arg]);
    let errors = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(out.status.code(), Some(0), "{errors}");
    let line = errors.lines().find(|l| l.starts_with("auto: dop853 ")).expect(&errors);
    assert!(line.contains(", radau ") && line.ends_with("–10 s (1 switch)"), "{line}");
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("written")).expect("json");
    let segments = value["summary"]["segments"].as_array().expect("segments");
    assert_eq!(segments.len(), 2, "{segments:?}");
    assert_eq!(
        (segments[0]["method"].as_str(), segments[1]["method"].as_str()),
        (Some("dop853"), Some("radau"))
    );
    assert_eq!(segments[0]["end"], segments[1]["start"]);
    assert_eq!(segments[1]["end"].as_f64(), Some(10.0));

    let out =
        lagrange(&["simulate", &stiff, "--set", "k=1e12", "--method", "rk4", "--step", "1e-3"]);
    let errors = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(out.status.code(), Some(1), "{errors}");
    assert!(errors.contains("numeric fault at t = 0.001: the mass matrix is singular"), "{errors}");
    assert!(
        errors.contains(
            "likely cause: the step, past rk4's stability limit: the fastest mode at t = 0 has \
             eigenvalue λ ≈ -9.90e6/s (time scale 1.0e-7 s), moving `r` (100%); rk4 is stable \
             along it for steps up to 2.8e-7 s, and its step was 1.0e-3 s, 3.6e3 times that."
        ),
        "{errors}"
    );
}

#[test]
fn ensemble_pictures_are_written_as_svg_and_png() {
    let scratch = Scratch::new("ensemble-plot");
    let scene = example("classics/simple_pendulum.lag");
    for (name, grid) in [
        ("line", vec!["--vary", "L=0.5:2:4"]),
        ("heat", vec!["--vary", "L=0.5:2:3", "--vary", "m=1:2:2"]),
    ] {
        for ext in ["svg", "png"] {
            let plot = scratch.file(&format!("{name}.{ext}"));
            let mut args =
                vec!["ensemble", &scene, "--until", "1", "--plot", plot.to_str().expect("path")];
            args.extend(grid.iter().copied());
            let out = lagrange(&args);
            assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
            let bytes = std::fs::read(&plot).expect("the picture is written");
            if ext == "svg" {
                let svg = String::from_utf8(bytes).expect("text");
                assert!(svg.starts_with("<svg") && svg.contains("</svg>"), "{svg}");
                continue;
            }
            let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
            let mut reader = decoder.read_info().expect("a PNG");
            let mut pixels = vec![0; reader.output_buffer_size()];
            let frame = reader.next_frame(&mut pixels).expect("its pixels");
            assert_eq!((frame.width, frame.height), (760, 600));
            assert_eq!(frame.color_type, png::ColorType::Rgb);
            // Drawn on, not blank: white, black text and axes, and the plot's colours.
            let colours: std::collections::HashSet<&[u8]> = pixels.chunks(3).collect();
            assert!(colours.len() > 20, "{name}: {} colours", colours.len());
        }
    }
}

#[test]
fn linearize_along_reads_a_simulate_table_and_refuses_what_it_cannot_take() {
    let scratch = Scratch::new("along");
    let run = scratch.file("run.csv");
    let pendulum = example("classics/simple_pendulum.lag");
    let out = lagrange(&[
        "simulate",
        &pendulum,
        "--until",
        "1",
        "--samples",
        "11",
        "--output",
        "KE, theta, theta'",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let along = ["linearize", &pendulum, "--along", run.to_str().unwrap()];
    let out = lagrange(&[&along[..], &["--format", "csv"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let table = stdout(&out);
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(
        lines[0],
        "t,\"A[theta,theta]\",\"A[theta,theta']\",\"A[theta',theta]\",\"A[theta',theta']\""
    );
    assert_eq!(lines.len(), 12);
    // θ'' = −g/L·sin θ: the entry below the diagonal is −g/L·cos θ, at the start θ = 1/2.
    let first: Vec<f64> = lines[1].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(first[..3], [0.0, 0.0, 1.0]);
    let expected = -9.81 * 0.8775825618903728;
    assert!((first[3] - expected).abs() < 1e-14, "{}", lines[1]);
    let out = lagrange(&along);
    assert!(stdout(&out).contains("11 samples from t = 0 to t = 1"), "{}", stdout(&out));

    // A missing column, times out of order, flags of the other kind of linearization.
    std::fs::write(&run, "t,theta,omega\n0,0.5,0\n0.1,0.45,-0.9\n").unwrap();
    let out = lagrange(&along);
    assert_eq!(out.status.code(), Some(2));
    let message = stderr(&out);
    assert!(message.contains("run.csv has no column `theta'`"), "{message}");
    assert!(message.contains("the columns nothing reads: omega"), "{message}");
    std::fs::write(&run, "t,theta,theta'\n0,0.5,0\n0.2,0.45,-0.9\n0.1,0.4,-1\n").unwrap();
    let out = lagrange(&along);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("run.csv:4: `t` = 0.1 does not come after 0.2"),
        "{}",
        stderr(&out)
    );
    let out = lagrange(&[&along[..], &["--about", "theta=0"]].concat());
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).starts_with("error: --about is about an equilibrium"), "{}", stderr(&out));
    let out = lagrange(&["linearize", &pendulum, "--until", "3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("--until sets the run of --along run"), "{}", stderr(&out));
    let out = lagrange(&[&along[..], &["--until", "3"]].concat());
    assert_eq!(out.status.code(), Some(2));
    let out = lagrange(&["linearize", &pendulum, "--format", "csv"]);
    assert_eq!(out.status.code(), Some(2));

    // Contacts are refused by name, with why, and so is a method Φ cannot ride on; kept
    // constraints are taken.
    let ball = example("contacts/bouncing_ball.lag");
    let out = lagrange(&["linearize", &ball, "--along", "run"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("does not take contacts yet"), "{}", stderr(&out));
    let cartesian = example("classics/pendulum_cartesian.lag");
    let out = lagrange(&["linearize", &cartesian, "--along", "run", "--method", "radau"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("radau is not one"), "{}", stderr(&out));
    let out = lagrange(&["linearize", &cartesian, "--along", "run", "--until", "1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("x = (x, y, x', y')"), "{}", stdout(&out));
}
