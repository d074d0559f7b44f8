//! The settings of a run on the command line as the scene writes them: times with units and
//! expressions, refusals with a caret under the culprit, and no setting silently ignored.

use super::{example, lagrange, stderr, stdout};

/// The table of a run that must succeed.
fn table(args: &[&str]) -> String {
    let out = lagrange(args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stdout(&out)
}

fn last_time(table: &str) -> String {
    let last = table.lines().last().expect("a row");
    last.split(',').next().expect("a time").to_string()
}

#[test]
fn times_take_expressions_and_units() {
    let pendulum = example("classics/simple_pendulum.lag");
    let run = |extra: &[&str]| {
        let mut args = vec!["simulate", &pendulum, "--samples", "5"];
        args.extend(extra);
        table(&args)
    };
    assert_eq!(last_time(&run(&["--until", "1/4"])), "0.25");
    assert_eq!(last_time(&run(&["--until", "2*pi"])), std::f64::consts::TAU.to_string());
    assert_eq!(run(&["--until", "1/4 min"]), run(&["--until", "15"]));
    // A plain number keeps its bits: the scene's own `until 10 s`.
    assert_eq!(run(&["--until", "10"]), run(&[]));
    let fixed = |step: &str| run(&["--method", "rk4", "--step", step]);
    assert_eq!(fixed("5 ms"), fixed("0.005"));

    let cart = example("control/cart_pole.lag");
    let held = |hold: &str| {
        table(&["simulate", &cart, "--input", "F=-M*g*x/L", "--hold", hold, "--samples", "5"])
    };
    assert_eq!(held("20 ms"), held("0.02"));

    let bench = lagrange(&["bench", &pendulum, "--until", "1/10 s", "--repeats", "1"]);
    assert!(bench.status.success(), "{}", stderr(&bench));
}

#[test]
fn a_bad_time_is_shown_with_a_caret() {
    let cart = example("control/cart_pole.lag");
    for (args, message, under) in [
        (vec!["--input", "F=-M*g*x/L", "--hold", "-1 ms"], "`hold` must be positive", "^^"),
        (vec!["--until", "2 m"], "`until` is a time, not in m", "  ^"),
        (vec!["--step", "x"], "unknown name `x`", "^"),
        (vec!["--until", "1/"], "expected an expression", "  ^"),
    ] {
        let mut all = vec!["simulate", &cart];
        all.extend(&args);
        let out = lagrange(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        let message_text = stderr(&out);
        assert!(message_text.contains(message), "{args:?}: {message_text}");
        // The bad value is the last one given, after its flag.
        let flag = args[args.len() - 2];
        assert!(message_text.contains(&format!("┌─ {flag}:1:")), "{args:?}: {message_text}");
        assert!(message_text.contains(&format!("│ {under}")), "{args:?}: {message_text}");
        assert!(!message_text.contains("unexpected argument"), "{args:?}: {message_text}");
    }
}

/// A scene file in a scratch folder of its own, removed when dropped.
struct Scene(std::path::PathBuf);

impl Scene {
    fn new(test: &str, text: &str) -> Scene {
        let dir =
            std::env::temp_dir().join(format!("lagrange-settings-{}-{test}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join("scene.lag");
        std::fs::write(&file, text).expect("write");
        Scene(file)
    }

    fn path(&self) -> &str {
        self.0.to_str().expect("a UTF-8 path")
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(self.0.parent().expect("its folder"));
    }
}

const OSCILLATOR: &str = "param m = 1 kg, k = 4 N/m\ncoord x = 1\n\
                          particle p { mass m; position (x, 0) }\npotential k*x^2/2\n";

#[test]
fn a_setting_the_method_does_not_use_is_refused() {
    let pendulum = example("classics/simple_pendulum.lag");
    for (args, message) in [
        (vec!["--method", "rk4", "--tolerance", "1e-12"], "--tolerance is not used by rk4"),
        (vec!["--method", "gauss", "--tolerance", "1e-12"], "--tolerance is not used by gauss"),
        (vec!["--method", "dop853", "--step", "0.5"], "--step is not used by dop853"),
        (vec!["--method", "auto", "--step", "0.5"], "--step is not used by auto"),
        (vec!["--step", "0.01", "--tolerance", "1e-9"], "--step is not used by dop853"),
        (vec!["--method", "rk4", "--step", "0.01", "--tolerance", "1e-9"], "--tolerance"),
    ] {
        let mut all = vec!["simulate", &pendulum];
        all.extend(&args);
        let out = lagrange(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(message), "{args:?}: {}", stderr(&out));
    }
    let ensemble = lagrange(&[
        "ensemble",
        &pendulum,
        "--vary",
        "L=1:2:2",
        "--method",
        "rk4",
        "--tolerance",
        "1e-9",
    ]);
    assert_eq!(ensemble.status.code(), Some(2), "{}", stderr(&ensemble));
    assert!(stderr(&ensemble).contains("--tolerance is not used by rk4"), "{}", stderr(&ensemble));
    // What each method takes still runs.
    table(&["simulate", &pendulum, "--method", "rk4", "--step", "0.01", "--samples", "2"]);
    table(&["simulate", &pendulum, "--method", "radau", "--tolerance", "1e-8", "--samples", "2"]);

    for (block, under) in [
        ("simulate { method rk4; tolerance 1e-8 }", "`tolerance` is not used by `rk4`"),
        ("simulate { method dopri5; step 1 ms }", "step` is not used by `dopri5`"),
        ("simulate { until 2 s; step 1 ms }", "is not used by `dop853` (the default)"),
    ] {
        let scene = Scene::new("block", &format!("{OSCILLATOR}{block}\n"));
        let out = lagrange(&["check", scene.path()]);
        assert_eq!(out.status.code(), Some(2), "{block}: {}", stderr(&out));
        let message = stderr(&out);
        assert!(message.contains(under), "{block}: {message}");
        assert!(message.contains(":5:"), "the block's line: {block}: {message}");
    }
}

#[test]
fn counts_past_memory_are_refused_and_a_run_at_every_step_is_bounded() {
    let pendulum = example("classics/simple_pendulum.lag");
    let out = lagrange(&["simulate", &pendulum, "--samples", "1000000000000"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--samples 1000000000000 would record more than 1 GiB"));
    assert!(out.stdout.is_empty());

    // Wide rows make the memory's cap on the steps small enough to meet here: a run that
    // cannot end, recording every step, ends in a fault that names what lifts it.
    let source = std::fs::read_to_string(&pendulum).expect("the example");
    let options = simulation::Options {
        until: Some(1e300),
        method: Some("rk4".into()),
        step: Some(0.5),
        output: vec![vec!["theta"; 4000].join(",")],
        samples: 0,
        ..Default::default()
    };
    let outcome = simulation::simulate(&source, &options).expect("runs");
    let fault = outcome.run.fault.as_ref().expect("the cap ends the run");
    let sim::FaultKind::TooManySteps { limit } = fault.kind else { panic!("{fault:?}") };
    let width = outcome.run.trajectory.rows[0].len();
    assert_eq!(limit, simulation::most_rows(width));
    assert!(limit * (8 * (width + 1)) <= simulation::MAX_RECORDED_BYTES, "{limit}");
    assert_eq!(outcome.run.trajectory.rows.len(), limit + 1, "the start and a row a step");
    let message = outcome.describe_fault(fault);
    assert!(message.contains(&format!("more than {limit} steps, each recorded")), "{message}");
    assert!(message.contains("give `samples`"), "{message}");
}

#[test]
fn a_hold_with_no_law_is_refused_at_the_block() {
    let scene = Scene::new("hold", &format!("{OSCILLATOR}simulate {{ hold 20 ms }}\n"));
    let out = lagrange(&["check", scene.path()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(message.contains("`hold` with no law to hold"), "{message}");
    assert!(message.contains("scene.lag:5:12"), "{message}");
    assert!(
        message.contains("│            ^^^^^^^^^^ holds nothing"),
        "under `hold 20 ms`: {message}"
    );

    // The block's law replaced by a time series: the block's hold is named at its line, not
    // as --hold.
    let driven = "param m = 1 kg, k = 4 N/m\ninput F = 0 N\ncoord x = 1\n\
                  particle p { mass m; position (x, 0) }\npotential k*x^2/2\n\
                  force push on p: (F, 0)\nsimulate { input F = -k*x; hold 20 ms }\n";
    let scene = Scene::new("hold-series", driven);
    let series = scene.0.with_file_name("push.csv");
    std::fs::write(&series, "t,F\n0,0\n20,1\n").expect("write");
    let held = lagrange(&["simulate", scene.path(), "--samples", "3"]);
    assert!(held.status.success(), "{}", stderr(&held));
    let input = format!("F={}", series.display());
    let out = lagrange(&["simulate", scene.path(), "--input", &input, "--samples", "3"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(message.contains("`hold` with no law left to hold"), "{message}");
    assert!(message.contains("scene.lag:7:"), "{message}");
    assert!(!message.contains("--hold"), "{message}");
}

#[test]
fn a_series_value_that_is_not_finite_is_shown_at_its_column() {
    let cart = example("control/cart_pole.lag");
    let scene = Scene::new("nan", "unused");
    let series = scene.0.with_file_name("push.csv");
    std::fs::write(&series, "t,F\n0,0\n1,NaN\n").expect("write");
    let out = lagrange(&["simulate", &cart, "--input", &format!("F={}", series.display())]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("push.csv:3:3: `NaN` is not a finite number"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn an_fmu_takes_a_tolerance_whatever_the_scene_runs_with() {
    // The FMU's Co-Simulation integrator is its own DOP853: a scene run by rk4 still takes one.
    let source = format!("{OSCILLATOR}simulate {{ method rk4; step 1 ms }}\n");
    let options = export::fmu::ExportOptions { tolerance: Some(1e-8), ..Default::default() };
    let fmu = export::fmu::export("scene.lag", &source, &options).expect("exports");
    assert!(fmu.model_description.contains("tolerance=\"1e-8\""), "{}", fmu.model_description);
}

#[test]
fn set_takes_values_with_units_of_the_right_dimension() {
    let pendulum = example("classics/simple_pendulum.lag");
    let run = |set: &str| table(&["simulate", &pendulum, "--set", set, "--samples", "5"]);
    assert_eq!(run("L=20 cm"), run("L=0.2"));
    assert_eq!(run("theta=30 deg"), run("theta=pi/6"));
    assert_eq!(run("theta'=60 deg/s"), run("theta'=pi/3"));
    let out = lagrange(&["simulate", &pendulum, "--set", "L=20 s"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("in this value of `L`: m here, s there"), "{}", stderr(&out));

    let cart = example("control/cart_pole.lag");
    let linearized = |set: &str| table(&["linearize", &cart, "--set", set]);
    assert_eq!(linearized("L=50 cm"), linearized("L=0.5"));
}

#[test]
fn a_byte_order_mark_is_no_part_of_the_scene() {
    let text = format!("\u{FEFF}{OSCILLATOR}");
    // The parser skips it, for a front end that hands it the file's text as it is...
    assert!(lang::parse(&text).is_ok());
    assert!(lang::parse("param m\n\u{FEFF}coord x\n").is_err(), "only at the start");
    // ...and the command reads the file without it, so that columns are an editor's.
    assert_eq!(cli::decode("s.lag", text.clone().into_bytes()).as_deref(), Ok(OSCILLATOR));
    let (_, rest) = OSCILLATOR.split_once('\n').expect("lines");
    let scene = Scene::new("bom", &format!("\u{FEFF}param m = 1 kq, k = 4 N/m\n{rest}"));
    let out = lagrange(&["check", scene.path()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(message.contains("scene.lag:1:13"), "{message}");
    assert!(message.contains("1 │ param m = 1 kq, k = 4 N/m\n"), "{message}");
    assert!(!message.contains('\u{FEFF}'), "{message}");
}

#[test]
fn a_stop_condition_that_names_nothing_that_changes_is_refused() {
    let pendulum = example("classics/simple_pendulum.lag");
    for stop in ["0", "theta=theta", "L - 1", "sin(theta)^2 + cos(theta)^2 - 1"] {
        let out = lagrange(&["simulate", &pendulum, "--stop-when", stop]);
        assert_eq!(out.status.code(), Some(2), "{stop}: {}", stderr(&out));
        assert!(stderr(&out).contains("names nothing that changes"), "{stop}: {}", stderr(&out));
    }
    for stop in ["theta", "t - 1", "theta' = 0"] {
        let out = lagrange(&["simulate", &pendulum, "--stop-when", stop, "--samples", "2"]);
        assert!(out.status.success(), "{stop}: {}", stderr(&out));
    }
}

#[test]
fn tiny_and_huge_times_are_written_short_and_exact() {
    use cli::simulate::number;
    for (x, written) in [
        (0.25, "0.25"),
        (std::f64::consts::TAU, "6.283185307179586"),
        (10.0, "10"),
        (1e-300, "1e-300"),
        (1e300, "1e300"),
        (-1.5e-20, "-0.000000000000000000015"),
        (-1.5e-30, "-1.5e-30"),
        (0.0, "0"),
    ] {
        assert_eq!(number(x), written);
        assert_eq!(number(x).parse::<f64>().map(f64::to_bits), Ok(x.to_bits()));
    }
    let pendulum = example("classics/simple_pendulum.lag");
    let out = table(&[
        "simulate",
        &pendulum,
        "--method",
        "rk4",
        "--step",
        "1e-300",
        "--until",
        "1e-297",
        "--samples",
        "3",
    ]);
    assert!(out.lines().all(|l| l.len() < 80), "{out}");
    assert_eq!(last_time(&out), "1e-297");
}

#[test]
fn vary_takes_bounds_as_the_scene_writes_values() {
    let pendulum = example("classics/simple_pendulum.lag");
    let run = |vary: &str| table(&["ensemble", &pendulum, "--vary", vary, "--threads", "1"]);
    assert_eq!(run("L=50 cm:1 m:3"), run("L=0.5:1:3"));
    assert_eq!(run("g=pi:2*pi:3"), run("g=3.141592653589793:6.283185307179586:3"));
    let out = lagrange(&["ensemble", &pendulum, "--vary", "L=50 s:1:3"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("in this value of `L`: m here, s there"), "{}", stderr(&out));
    let out = lagrange(&["ensemble", &pendulum, "--vary", "L=5 qq:1:2"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("^^^^ unknown unit `qq`"), "{}", stderr(&out));
}

#[test]
fn tolerance_takes_an_expression_and_no_unit() {
    let pendulum = example("classics/simple_pendulum.lag");
    let run = |tolerance: &str| {
        table(&["simulate", &pendulum, "--tolerance", tolerance, "--samples", "3"])
    };
    assert_eq!(run("10^-12"), run("1e-12"));
    let out = lagrange(&["simulate", &pendulum, "--tolerance", "1e-9 s"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("`tolerance` takes no unit"), "{}", stderr(&out));
    assert!(stderr(&out).contains("┌─ --tolerance:1:1"), "{}", stderr(&out));
}

#[test]
fn the_help_lists_the_methods_of_the_table_and_what_each_takes() {
    let help = table(&["simulate", "--help"]);
    let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for method in sim::Method::all() {
        let line = format!("- {}: {}", method.name(), method.entry().summary);
        let line = line.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(help.contains(&line), "{line}\n{help}");
    }
    // The lines of --tolerance and --step name the methods that take each, in the table's order.
    let named = |from: &str, to: &str| {
        let start = help.find(from).expect(from) + from.len();
        let end = help[start..].find(to).expect(to) + start;
        let words = help[start..end].split(|c: char| !c.is_ascii_alphanumeric());
        words.filter_map(sim::Method::from_name).collect::<Vec<_>>()
    };
    let taking = |adaptive: bool| sim::Method::all().filter(move |m| m.is_adaptive() == adaptive);
    assert!(named("tolerance of the adaptive methods:", "(default").into_iter().eq(taking(true)));
    assert!(named("Step of", ", as the scene").into_iter().eq(taking(false)));
}
