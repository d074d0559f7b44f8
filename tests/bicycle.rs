//! The Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina and Schwab, 2007), derived from
//! `examples/bicycle/whipple.lag`, which holds only the paper's Table 1: the eigenvalues of
//! Table 2 at every tabulated speed, the weave and capsize speeds, and the benchmark's M, C1,
//! K0 and K2 recovered from the linearization at two speeds.

// The tables keep the paper's digits as printed, trailing zeros included.
#![allow(clippy::excessive_precision)]

use engine::linearize::{linearize, Options, Stability};

/// Table 2: at v = 0, 1, …, 10 m/s, the real eigenvalues and the complex pairs (re, |im|).
const TABLE_2: [&[(f64, f64)]; 11] = [
    &[
        (-5.53094371765393, 0.0),
        (-3.13164324790656, 0.0),
        (3.13164324790656, 0.0),
        (5.53094371765393, 0.0),
    ],
    &[(-7.11008014637442, 0.0), (-3.13423125066578, 0.0), (3.52696170990070, 0.8077402751993)],
    &[(-8.67387984831735, 0.0), (-3.07158645641514, 0.0), (2.68234517512745, 1.68066296590675)],
    &[(-10.35101467245920, 0.0), (-2.63366137253667, 0.0), (1.70675605663975, 2.31582447384325)],
    &[(-12.15861426576450, 0.0), (-1.42944427361326, 0.0), (0.41325331521125, 3.07910818603206)],
    &[(-14.07838969279820, 0.0), (-0.77534188219585, 4.46486771378823), (-0.32286642900409, 0.0)],
    &[(-16.08537123098030, 0.0), (-1.52644486584142, 5.87673060598709), (-0.00406690076970, 0.0)],
    &[(-18.15788466125262, 0.0), (-2.13875644258362, 7.19525913329805), (0.10268170574766, 0.0)],
    &[(-20.27940894394569, 0.0), (-2.69348683581097, 8.46037971396931), (0.14327879765713, 0.0)],
    &[(-22.43788559040858, 0.0), (-3.21675402252485, 9.69377351531791), (0.15790184030917, 0.0)],
    &[(-24.62459635017404, 0.0), (-3.72016840437287, 10.90681139476287), (0.16105338653172, 0.0)],
];

const M: [[f64; 2]; 2] = [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]];
const C1: [[f64; 2]; 2] = [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]];
const K0: [[f64; 2]; 2] = [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]];
const K2: [[f64; 2]; 2] = [[0.0, 76.59734589573222], [0.0, 2.65431523794604]];
const G: f64 = 9.81;

fn whipple() -> String {
    lagrange_tests::example("bicycle/whipple.lag")
}

/// The eigenvalues away from zero (the zeros are the first integral of the forward speed), as
/// (re, |im|) with each complex pair once, sorted.
fn roll_and_steer(eigenvalues: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = eigenvalues
        .iter()
        .filter(|(re, im)| re.abs().max(im.abs()) > 1e-6 && *im >= 0.0)
        .copied()
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

#[test]
fn the_benchmark_comes_out_of_table_1() {
    let options =
        Options { set: vec!["v=1".into()], sweep: Some("v=0:10:11".into()), ..Default::default() };
    let l = linearize(&whipple(), &options).unwrap_or_else(|e| panic!("linearizes: {e}"));

    // The roll–steer block: u = (φ̇, δ̇, θ̇R), p = (φ, δ).
    let (positions, rates) = l.at.reduced().expect("reduced in numbers");
    let names: Vec<String> = positions
        .iter()
        .chain(&rates)
        .map(|&i| l.derivation.model.pool.symbol(l.linearization.coords[i]).name.clone())
        .collect();
    assert_eq!(names, ["phi", "delta", "phi", "delta", "thetaR"]);

    let sweep = l.sweep.as_ref().expect("a sweep");
    for (row, expected) in sweep.rows.iter().zip(TABLE_2) {
        let ours = roll_and_steer(&row.eigenvalues);
        assert_eq!(ours.len(), expected.len(), "at v = {}: {:?}", row.value, row.eigenvalues);
        for (a, b) in ours.iter().zip(expected) {
            assert!(
                (a.0 - b.0).abs() < 1e-10 && (a.1 - b.1).abs() < 1e-10,
                "at v = {}: {a:?} against {b:?}",
                row.value
            );
        }
    }

    // Weave: unstable below, stable above; capsize: unstable again above.
    let changes: Vec<(f64, Stability, Stability)> =
        sweep.changes.iter().map(|c| (c.value, c.from, c.to)).collect();
    assert_eq!(changes.len(), 2, "{changes:?}");
    assert!((changes[0].0 - 4.29238253634111).abs() < 1e-8, "{changes:?}");
    assert_eq!((changes[0].1, changes[0].2), (Stability::Unstable, Stability::Stable));
    assert!((changes[1].0 - 6.02426201538837).abs() < 1e-8, "{changes:?}");
    assert_eq!((changes[1].1, changes[1].2), (Stability::Stable, Stability::Unstable));

    // M·q̈ + v·C1·q̇ + (g·K0 + v²·K2)·q = 0: M and C1 at v = 1, K at v = 0 and 1.
    let at_zero = &sweep.rows[0];
    let at_one = &l.at;
    for j in 0..2 {
        for i in 0..2 {
            let close = |ours: f64, theirs: f64, what: &str| {
                assert!((ours - theirs).abs() < 1e-11, "{what}[{j}][{i}]: {ours} against {theirs}");
            };
            close(at_one.mass[j][i], M[j][i], "M");
            close(at_one.damping[j][i], C1[j][i], "C1");
            close(at_zero.stiffness[j][i] / G, K0[j][i], "K0");
            close(at_one.stiffness[j][i] - at_zero.stiffness[j][i], K2[j][i], "K2");
        }
    }
    // The wheel's rate is a first integral: it leaves the roll and steer alone.
    for k in 0..2 {
        assert!(at_one.mass[2][k].abs() < 1e-12 && at_one.mass[k][2].abs() < 1e-12);
        assert!(at_one.damping[k][2].abs() < 1e-12 && at_one.stiffness[2][k].abs() < 1e-12);
    }
}

/// The size target, an exact count rather than a timing: the lowered right-hand side
/// (M, f and the five kept constraints' rows) under 20,000 operations. Multiplied out, the
/// same equations took 107,553.
#[test]
fn the_lowered_right_hand_side_stays_small() {
    let mut prepared = engine::numbers::prepare(&whipple(), &[], engine::Options::default())
        .unwrap_or_else(|e| panic!("prepares: {e}"));
    let exprs = prepared.dynamics_exprs();
    let program = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let ops = program.op_counts().total();
    assert!(ops < 20_000, "{ops} operations");
}

/// The bicycle's `derive` report is one to read: an entry past a thousand characters shows its
/// size and how to see it whole (it printed 154 KB, with lines of 16,000 characters), and
/// `--full` prints it whole.
#[test]
fn the_report_is_readable_and_whole_on_request() {
    let source = whipple();
    let options = engine::Options::default();
    let text = cli::Format::Text;
    let (report, _) = cli::derive_report_with("whipple.lag", &source, text, options, false)
        .expect("the bicycle derives");
    assert!(report.len() < 20_000, "{} bytes", report.len());
    let longest = report.lines().map(|l| l.chars().count()).max().unwrap_or(0);
    assert!(longest <= 1_000, "a line of {longest} characters");
    assert!(report.contains("characters; --full prints it⟩"), "{report}");
    let (whole, _) = cli::derive_report_with("whipple.lag", &source, text, options, true)
        .expect("the bicycle derives");
    assert!(!whole.contains("--full prints it"));
    assert!(whole.len() > 100_000, "{} bytes", whole.len());
}

/// The values `show at start` prints, read back.
fn shown_at_start(report: &str, labels: &[&str]) -> Vec<f64> {
    labels
        .iter()
        .map(|label| {
            let line = report
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("{label} ≈")))
                .unwrap_or_else(|| panic!("{label} is not shown:\n{report}"));
            line.split('≈')
                .nth(1)
                .expect("a value")
                .trim()
                .replace('−', "-")
                .parse()
                .expect("a number")
        })
        .collect()
}

/// Away from upright, with the pitch solved from the front wheel's contact (or pasted in to
/// 13 digits), the start's 13 unknowns are past the exact solve. `show at start` gives them in
/// numbers (it used to say the mass matrix was singular), `simulate`'s first row agrees, and
/// `expect at start` is decided there.
#[test]
fn a_general_start_is_shown_and_checked_in_numbers() {
    let general = whipple()
        .replace("coord phi = 0, phi' = 0.5 rad/s", "coord phi = 0.62, phi' = 0.5 rad/s")
        .replace(
            "coord theta = 0, delta = 0, delta' = 0",
            "coord theta ~ 0, delta = -0.23, delta' = 0.1 rad/s",
        );
    let scene = format!("{general}show at start: psi'', phi'', delta''\n");
    let report =
        cli::derive("bike.lag", &scene, cli::Format::Text).unwrap_or_else(|e| panic!("{e}"));
    assert!(report.contains("θ   (from θ ≈ 0.0157640711752"), "{report}");
    let shown = shown_at_start(&report, &["ψ\u{308}", "φ\u{308}", "δ\u{308}"]);

    let outcome = simulation::simulate(
        &general,
        &simulation::Options {
            until: Some(0.001),
            output: vec!["psi'', phi'', delta''".into()],
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let first = &outcome.run.trajectory.rows[0];
    for (s, r) in shown.iter().zip(first) {
        assert!((s - r).abs() < 1e-9 * r.abs().max(1.0), "shown {shown:?}, simulated {first:?}");
    }

    // The pitch pasted in to 13 digits: its rounding is accepted, and the start is the same.
    let pasted = scene.replace("coord theta ~ 0,", "coord theta = 0.01576407117524,");
    let report =
        cli::derive("bike.lag", &pasted, cli::Format::Text).unwrap_or_else(|e| panic!("{e}"));
    assert!(report.contains("13 unknowns are too many to solve for exactly"), "{report}");
    let again = shown_at_start(&report, &["ψ\u{308}", "φ\u{308}", "δ\u{308}"]);
    for (a, b) in again.iter().zip(&shown) {
        assert!((a - b).abs() < 1e-6 * b.abs().max(1.0), "{again:?} against {shown:?}");
    }
    let expectation = format!("{general}expect at start: phi'' = {}\n", first[1]);
    let result = cli::check::check_file("bike.lag", &expectation);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert!(result.report.contains("holds at the parameters' values"), "{}", result.report);
    let wrong = format!("{general}expect at start: phi'' = {}\n", first[1] + 0.01);
    assert_eq!(cli::check::check_file("bike.lag", &wrong).exit_code, 1);
}
