//! `lagrange ensemble`: the same bytes whatever the number of threads, random rows that are
//! what `simulate --set` gives for the same values, grids crossed in order, runs that fail
//! recorded with their reason, and a bad `--vary` pointed at.

use ::ensemble::{ensemble, Options, Table};
use engine::input::{Assignment, Vary};
use simulation::simulate;

const FLIP: &str = "classics/double_pendulum_flip.lag";

/// A pendulum whose mass and length an ensemble varies into what cannot run.
const PENDULUM: &str = "scene \"Pendulum\"
param m = 1 kg, l = 1 m, g = 9.81 m/s^2
coord theta = 1
particle bob { mass m; position (l*sin(theta), -l*cos(theta)) }
gravity g
";

fn vary(texts: &[&str]) -> Vec<Vary> {
    texts.iter().map(|t| Vary::parse(t).expect(t)).collect()
}

fn options(texts: &[&str], runs: Option<usize>, record: &str, until: f64) -> Options {
    Options {
        simulate: simulation::Options { until: Some(until), ..Default::default() },
        vary: vary(texts),
        runs,
        seed: 27,
        record: vec![record.to_string()],
    }
}

fn run(source: &str, options: &Options, threads: usize) -> Table {
    ensemble(source, options, Some(threads)).expect("the ensemble runs")
}

#[test]
fn the_table_is_the_same_bytes_on_one_thread_and_two() {
    let source = lagrange_tests::example(FLIP);
    for options in [
        options(&["a1=-3:3:7", "a2=-3:3:6"], None, "t, theta1, max(theta2), min(theta2)", 4.0),
        options(&["a1=uniform(-3, 3)", "m2=normal(1, 0.1)"], Some(17), "t, theta2", 4.0),
    ] {
        let one = cli::ensemble::csv(&run(&source, &options, 1));
        let two = cli::ensemble::csv(&run(&source, &options, 2));
        assert_eq!(one, two);
        let rows = one.lines().count() - 1;
        assert!(rows == 42 || rows == 17, "{rows} rows");
    }
}

#[test]
fn random_rows_are_what_simulate_gives_for_their_values() {
    let source = lagrange_tests::example(FLIP);
    let options =
        options(&["a1=uniform(1, 2.5)", "m2=normal(1, 0.2)"], Some(4), "theta1, theta2, t", 3.0);
    let table = run(&source, &options, 2);
    assert_eq!(table.columns, ["a1", "m2", "theta1", "theta2", "t"]);
    for row in &table.rows {
        let set = vec![
            Assignment { name: "a1".into(), value: row[0].to_string() },
            Assignment { name: "m2".into(), value: row[1].to_string() },
        ];
        let alone = simulation::Options {
            until: Some(3.0),
            set,
            output: vec!["theta1, theta2".into()],
            ..Default::default()
        };
        let outcome = simulate(&source, &alone).expect("simulates");
        let last = outcome.run.trajectory.rows.last().expect("a row");
        let simulated = [last[0], last[1], outcome.run.final_time];
        for (ensemble, alone) in row[2..].iter().zip(simulated) {
            assert!((ensemble - alone).abs() <= 1e-9, "{ensemble} against {alone} in {row:?}");
        }
    }
}

#[test]
fn grid_axes_cross_with_the_last_fastest_and_starts_follow_them() {
    let source = lagrange_tests::example(FLIP);
    let table = run(&source, &options(&["a1=0.5:1.5:3", "a2=-1:1:2"], None, "theta1", 1e-9), 2);
    let points: Vec<(f64, f64)> = table.rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(points, [(0.5, -1.0), (0.5, 1.0), (1.0, -1.0), (1.0, 1.0), (1.5, -1.0), (1.5, 1.0)]);
    assert_eq!(table.axes[0], ("a1".to_string(), vec![0.5, 1.0, 1.5]));
    // A run of a nanosecond ends where it started: theta1 = a1.
    for row in &table.rows {
        assert!((row[2] - row[0]).abs() < 1e-12, "{row:?}");
    }
}

#[test]
fn extremes_bound_the_final_value() {
    let source = lagrange_tests::example(FLIP);
    let table =
        run(&source, &options(&["a1=0.5:1:2"], None, "max(theta1), theta1, min(theta1)", 2.0), 1);
    for row in &table.rows {
        let (greatest, last, least) = (row[1], row[2], row[3]);
        assert!(least <= last && last <= greatest, "{row:?}");
        // Released from rest at a1, the first rod swings down from there: the start counts.
        assert!(greatest >= row[0] && least < row[0], "{row:?}");
    }
}

#[test]
fn failed_runs_are_rows_with_their_reason() {
    let options = options(&["m=-1:1:3", "l=0:1:2"], None, "theta", 1.0);
    let table = run(PENDULUM, &options, 2);
    let csv = cli::ensemble::csv(&table);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "m,l,theta,fault");
    // m = −1 and m = 0 cannot start; l = 0 has no inertia; m = 1, l = 1 runs.
    assert!(lines[1].starts_with("-1,0,,") && lines[1].contains("must be positive"), "{csv}");
    assert!(lines[1].contains("with the values of this run, `bob` has a mass of -1 kg"), "{csv}");
    assert!(lines[5].starts_with("1,0,,") && lines[5].contains("numeric fault at t = 0"), "{csv}");
    assert!(lines[5].contains("mass matrix"), "{csv}");
    let ran = lines[6].strip_suffix(',').expect("no fault");
    assert!(ran.starts_with("1,1,") && ran.split(',').count() == 3, "{csv}");
    assert_eq!(table.failures.iter().filter(|f| f.is_some()).count(), 5);
    let summary = cli::ensemble::summary(&table, 0.5, 2);
    assert!(summary.starts_with("6 runs, 5 failed"), "{summary}");
}

#[test]
fn without_record_a_row_holds_the_scenes_outputs_else_the_coordinates() {
    let unrecorded = |texts: &[&str]| Options {
        simulate: simulation::Options { until: Some(0.5), ..Default::default() },
        vary: vary(texts),
        ..Default::default()
    };
    let flip = run(&lagrange_tests::example(FLIP), &unrecorded(&["a1=1:2:2"]), 1);
    assert_eq!(flip.columns, ["a1", "theta1", "theta2"]);
    let with_output = format!("{PENDULUM}simulate {{ output theta' }}\n");
    let pendulum = run(&with_output, &unrecorded(&["l=1:2:2"]), 1);
    assert_eq!(pendulum.columns, ["l", "theta'"]);
    assert!(pendulum.rows.iter().all(|r| r[1] < 0.0), "{:?}", pendulum.rows);
}

/// A front end may build an ensemble on one thread and run its ranges on others.
#[test]
fn an_ensemble_and_its_table_go_between_threads() {
    fn shared<T: Send + Sync>() {}
    shared::<::ensemble::Ensemble>();
    shared::<Table>();
    shared::<Options>();
}

#[test]
fn a_bad_vary_points_at_its_mistake() {
    let text = "a1=normal(0, -1)";
    let d = Vary::parse(text).expect_err("a negative deviation");
    let shown = cli::diagnostics::render("--vary", text, &[d]);
    assert!(shown.contains("the standard deviation must be positive"), "{shown}");
    assert!(shown.contains("^^"), "{shown}");
    assert!(shown.contains("NAME=normal(MU, SIGMA)"), "{shown}");

    let source = lagrange_tests::example(FLIP);
    for (texts, runs, expected) in [
        (&["a3=0:1:2"][..], None, "--vary a3: no parameter of that name; one of m1, m2"),
        (&["theta1=0:1:2"][..], None, "--vary theta1: `theta1` is a coordinate"),
        (&["a1=0:1:2", "a1=1:2:2"][..], None, "--vary a1: varied twice"),
        (&["a1=uniform(0, 1)"][..], None, "--runs is needed with random draws"),
        (&["a1=0:1:2"][..], Some(3), "--runs counts random draws"),
    ] {
        let options = Options { vary: vary(texts), runs, ..Default::default() };
        let error = ensemble(&source, &options, Some(1)).expect_err("refused");
        let shown = cli::diagnostics::error("flip.lag", &error);
        assert!(shown.starts_with(&format!("error: {expected}")), "{shown}");
        assert_eq!(error.exit_code(), 2);
    }
}

/// The rows streamed chunk by chunk are the table run in one chunk (every start made before
/// the first run, as the ensemble ran before it streamed), byte for byte and in run order,
/// whatever the chunks and threads: on a grid with starts that cannot be made and runs that
/// fault, and on random draws side by side in lockstep; a range alone is the same rows too.
#[test]
fn streamed_chunks_give_the_table_of_one_chunk() {
    let flip = lagrange_tests::example(FLIP);
    let cases = [
        (PENDULUM.to_string(), options(&["m=-1:1:5", "l=0:1:7"], None, "theta, max(theta)", 1.0)),
        (flip, options(&["a1=uniform(-3, 3)", "m2=normal(1, 0.1)"], Some(61), "t, theta2", 2.0)),
    ];
    for (source, options) in &cases {
        let mut ensemble = ::ensemble::Ensemble::new(source, options).expect("loads");
        let runs = ensemble.runs();
        ensemble.set_chunk(runs);
        let whole = cli::ensemble::csv(&ensemble.run(0..runs, 1, &mut ()));
        assert!(whole.lines().count() == runs + 1 && runs > 30, "{whole}");
        for (chunk, threads) in [(1, 1), (3, 2), (7, 1), (16, 2), (runs, 2)] {
            ensemble.set_chunk(chunk);
            let header = ensemble.table();
            let mut csv = cli::ensemble::Csv::new(&header, Vec::new());
            let mut tally = cli::ensemble::Tally::default();
            let mut both = Both(&mut csv, &mut tally);
            ensemble.stream(0..runs, threads, &mut (), &mut both);
            let streamed = String::from_utf8(csv.finish().expect("memory")).expect("UTF-8");
            assert_eq!(streamed, whole, "chunks of {chunk} on {threads} threads");
            let table = ensemble.run(0..runs, threads, &mut ());
            assert_eq!(
                cli::ensemble::summary_of(&tally, 0.5, 2),
                cli::ensemble::summary(&table, 0.5, 2)
            );
            // A range alone: its starts made without the runs before it.
            let part = ensemble.run(5..runs - 3, threads, &mut ());
            let lines: Vec<&str> = whole.lines().collect();
            let expected = [&lines[..1], &lines[6..runs - 2]].concat().join("\n") + "\n";
            assert_eq!(cli::ensemble::csv(&part), expected, "chunks of {chunk}");
        }
    }
}

/// Two sinks fed the same rows.
struct Both<'a, A, B>(&'a mut A, &'a mut B);

impl<A: ::ensemble::Sink, B: ::ensemble::Sink> ::ensemble::Sink for Both<'_, A, B> {
    fn row(&mut self, run: usize, row: &[f64], failure: Option<&str>) {
        self.0.row(run, row, failure);
        self.1.row(run, row, failure);
    }
}

/// A bouncing ball's restitution varied: each run goes one at a time (the lockstep takes no
/// contacts), lands and settles as the closed form says for its own e (so each run's contacts
/// take the run's restitution, not the scene's), records what `simulate --set` gives, streams
/// in chunks as it runs whole, and a restitution past 1 is a row with its reason.
#[test]
fn an_ensemble_of_bouncing_balls_settles_each_at_its_closed_form_time() {
    let source = lagrange_tests::example("contacts/bouncing_ball.lag");
    let (h0, g) = (1.0, 9.81);
    let t1 = f64::sqrt(2.0 * h0 / g);
    let mut options = options(&["e=0.5:0.9:5"], None, "settled(floor), impacts(floor), y", 10.0);
    options.simulate.tolerance = Some(1e-10);
    let mut ensemble = ::ensemble::Ensemble::new(&source, &options).expect("loads");
    let table = ensemble.run(0..5, 2, &mut ());
    assert_eq!(table.columns, ["e", "settled(floor)", "impacts(floor)", "y"]);
    assert!(table.failures.iter().all(Option::is_none), "{:?}", table.failures);
    for row in &table.rows {
        let (e, settled, impacts, y) = (row[0], row[1], row[2], row[3]);
        let accumulation = t1 * (1.0 + e) / (1.0 - e);
        assert!((settled - accumulation).abs() < 1e-8 * accumulation, "{row:?}: {accumulation}");
        assert!(y.abs() < 1e-9, "{row:?}");
        let alone = simulation::Options {
            until: Some(10.0),
            tolerance: Some(1e-10),
            set: vec![Assignment { name: "e".into(), value: e.to_string() }],
            output: vec!["y".into()],
            ..Default::default()
        };
        let outcome = simulate(&source, &alone).expect("simulates");
        let landed = outcome.run.modes.iter().filter(|m| m.kind == sim::ModeChange::Impact);
        assert_eq!(impacts, landed.count() as f64, "{row:?}");
        assert_eq!(y, outcome.run.trajectory.rows.last().expect("a row")[0], "{row:?}");
    }
    // More impacts before settling the livelier the ball.
    assert!(table.rows.windows(2).all(|w| w[1][2] > w[0][2]), "{:?}", table.rows);
    let whole = cli::ensemble::csv(&table);
    ensemble.set_chunk(1);
    let mut csv = cli::ensemble::Csv::new(&ensemble.table(), Vec::new());
    ensemble.stream(0..5, 2, &mut (), &mut csv);
    assert_eq!(String::from_utf8(csv.finish().expect("memory")).expect("UTF-8"), whole);

    let table = run(&source, &options_of(&["e=0.9:1.3:3"], "settled(floor)"), 1);
    let lines = cli::ensemble::csv(&table);
    let lines: Vec<&str> = lines.lines().collect();
    assert!(lines[1].starts_with("0.9,") && lines[1].ends_with(','), "{lines:?}");
    assert!(lines[2].starts_with("1.1,,") && lines[2].contains("restitution of contact `floor`"));
    let bad = ensemble_error(&source, &options_of(&["e=0.5:0.9:2"], "settled(wall)"));
    assert!(bad.contains("no contact `wall` (its contacts: `floor`)"), "{bad}");
}

fn options_of(texts: &[&str], record: &str) -> Options {
    options(texts, None, record, 10.0)
}

fn ensemble_error(source: &str, options: &Options) -> String {
    match ::ensemble::Ensemble::new(source, options) {
        Ok(_) => panic!("the ensemble loaded"),
        Err(e) => e.to_string(),
    }
}
