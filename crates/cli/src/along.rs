//! `lagrange linearize --along`'s files: the motion read from CSV (the columns of
//! [`crate::trajectory`]: `t`, each coordinate's position and rate, each input's value), and
//! the result written as a text summary, as JSON (`results::along`'s tree) or as CSV, a row
//! per sample of every entry of A, B, C and D.

use cas::Style;
use engine::along::DMatrix;
use engine::along::{Along, Linearized, Motion};

use crate::report::{bracketed, data_json, significant};

/// Digits of the numbers in the text summary.
const DIGITS: u32 = 8;

/// Reads the motion in the CSV `text` of the file `path` for the scene `along` linearizes:
/// a column `t`, strictly increasing, and one per coordinate, rate and input.
pub fn read_motion(path: &str, text: &str, along: &Along) -> Result<Motion, String> {
    let state = along.state_names();
    let inputs = along.input_names();
    let mut wanted = vec!["t".to_string()];
    wanted.extend(state.iter().cloned());
    wanted.extend(inputs.iter().cloned());
    let inputs_words = match inputs.len() {
        0 => String::new(),
        _ => format!(", and each input's value ({})", inputs.join(", ")),
    };
    let needs = format!(
        "`t` and, for each coordinate, its position and rate ({}){inputs_words}",
        state.join(", ")
    );
    let hint = format!(
        "`lagrange simulate SCENE --output {} --out FILE.csv` writes one",
        wanted[1..].join(",")
    );
    let wanted_columns = crate::trajectory::Wanted { columns: &wanted, needs: &needs, hint: &hint };
    let table = crate::trajectory::read_columns(path, text, &wanted_columns)?;
    crate::trajectory::increasing(path, &table, "t")?;
    let size = state.len();
    let mut motion = Motion::default();
    for row in table.rows {
        motion.times.push(row[0]);
        motion.states.push(row[1..1 + size].to_vec());
        motion.inputs.push(row[1 + size..].to_vec());
    }
    if motion.times.len() < 2 {
        return Err(format!("error: {path} has one row: a motion to linearize along needs two"));
    }
    Ok(motion)
}

/// The linearization `--along` asks for: along a run of the scene when `along` is `run` (with
/// the settings of `run`), else along the motion in the CSV file `along` (`run`'s `--set`
/// values and `no_units` alone apply). `path` names the scene. The error is ready to print,
/// with the command's exit code.
pub fn linearize(
    path: &str,
    source: &str,
    along: &str,
    run: &simulation::Options,
) -> Result<Linearized, (String, u8)> {
    let failed = |e: engine::Error| (crate::diagnostics::error(path, &e), e.exit_code());
    if along == "run" {
        return simulation::along::linearize_run(source, run).map_err(failed);
    }
    let options = engine::along::Options {
        set: run.set.clone(),
        no_units: run.no_units,
        starts_allowed: false,
    };
    let mut model = engine::along::along(source, &options).map_err(failed)?;
    let bytes =
        std::fs::read(along).map_err(|e| (format!("error: cannot read {along}: {e}"), 2))?;
    let text =
        String::from_utf8(bytes).map_err(|_| (format!("error: {along} is not UTF-8 text"), 2))?;
    let motion = read_motion(along, &text, &model).map_err(|message| (message, 2))?;
    engine::along::linearize_along(&mut model, &motion).map_err(failed)
}

fn number(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    significant(v, DIGITS, Style::Unicode)
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<String>> {
    (0..m.nrows()).map(|i| m.row(i).iter().map(|v| number(*v)).collect()).collect()
}

/// The text summary: what the state, inputs and outputs are, the matrices at the first and
/// last samples, and Φ over the motion with its determinant beside exp ∫ tr A dt (Liouville's
/// formula, which the two meet to the accuracy of Φ's integration).
pub fn text(what: &str, l: &Linearized) -> String {
    let (Some(first), Some(last)) = (l.times.first(), l.times.last()) else {
        return String::new();
    };
    let mut out = vec![format!(
        "Linearization along {what}: {} samples from t = {} to t = {}",
        l.times.len(),
        number(*first),
        number(*last)
    )];
    out.push(format!("  ẋ = A(t)·x + B(t)·u,  x = ({})", l.state.join(", ")));
    if !l.inputs.is_empty() {
        out.push(format!("  u = ({})", l.inputs.join(", ")));
    }
    if !l.outputs.is_empty() {
        out.push(format!("  y = C(t)·x + D(t)·u,  y = ({})", l.outputs.join(", ")));
    }
    for (k, which) in [(0, "first"), (l.times.len() - 1, "last")] {
        let s = &l.samples[k];
        out.push(format!("At t = {} (the {which} sample)", number(l.times[k])));
        out.extend(bracketed(&rows(&s.a), "  A = "));
        if !l.inputs.is_empty() {
            out.extend(bracketed(&rows(&s.b), "  B = "));
        }
        if !l.outputs.is_empty() {
            out.extend(bracketed(&rows(&s.c), "  C = "));
            if !l.inputs.is_empty() {
                out.extend(bracketed(&rows(&s.d), "  D = "));
            }
        }
    }
    out.push(format!(
        "State-transition matrix Φ({}, {}): δx(t_end) = Φ·δx(t_0), by {}",
        number(*last),
        number(*first),
        l.between.words()
    ));
    out.extend(bracketed(&rows(&l.transition), "  Φ = "));
    let traces: Vec<f64> = l.samples.iter().map(|s| s.a.trace()).collect();
    let integral: f64 = l
        .times
        .windows(2)
        .zip(traces.windows(2))
        .map(|(t, tr)| (t[1] - t[0]) * (tr[0] + tr[1]) / 2.0)
        .sum();
    out.push(format!(
        "  det Φ = {},  exp ∫ tr A dt = {} (trapezoids over the samples)",
        number(l.transition.determinant()),
        number(numeric::elementary::apply(cas::Func::Exp, integral))
    ));
    out.push("Every sample's matrices: --format json or --format csv".into());
    out.join("\n") + "\n"
}

/// The result as JSON: `results::along::report`'s tree.
pub fn json(l: &Linearized) -> String {
    let mut text =
        serde_json::to_string_pretty(&data_json(&results::along::report(l))).unwrap_or_default();
    text.push('\n');
    text
}

/// A row per sample: `t`, then every entry of A, B, C and D row by row, each column named by
/// its matrix, row and column (`A[theta',theta]`), numbers as Rust's shortest round-trip
/// decimals.
pub fn csv(l: &Linearized) -> String {
    let mut out = csv::Writer::from_writer(Vec::new());
    let blocks: [(&str, &[String], &[String]); 4] = [
        ("A", &l.state, &l.state),
        ("B", &l.state, &l.inputs),
        ("C", &l.outputs, &l.state),
        ("D", &l.outputs, &l.inputs),
    ];
    let mut header = vec!["t".to_string()];
    for (name, row_names, column_names) in blocks {
        for r in row_names {
            header.extend(column_names.iter().map(|c| format!("{name}[{r},{c}]")));
        }
    }
    out.write_record(&header).expect("writing to memory");
    for (t, s) in l.times.iter().zip(&l.samples) {
        let mut record = vec![crate::simulate::number(*t)];
        for m in [&s.a, &s.b, &s.c, &s.d] {
            for i in 0..m.nrows() {
                // −0 (of −M⁻¹·C with no damping) reads as 0: adding +0 turns it into +0.
                record.extend(m.row(i).iter().map(|v| crate::simulate::number(*v + 0.0)));
            }
        }
        out.write_record(&record).expect("writing to memory");
    }
    let bytes = out.into_inner().expect("writing to memory");
    String::from_utf8(bytes).expect("UTF-8 in, UTF-8 out")
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPRING: &str = "param m = 1, k = 4\ninput F = 0\ncoord x\n\
        particle p { mass m; position (x, 0) }\npotential k/2*x^2\nforce push on p: (F, 0)\n";

    fn along() -> Along {
        engine::along::along(SPRING, &Default::default()).expect("loads")
    }

    #[test]
    fn a_simulate_table_with_the_inputs_is_read() {
        let text = "t,KE,x,x',F\n0,1,0.5,2,0\n0.1,1,0.7,1.9,0.5\n";
        let motion = read_motion("run.csv", text, &along()).expect("reads");
        assert_eq!(motion.times, [0.0, 0.1]);
        assert_eq!(motion.states, [[0.5, 2.0], [0.7, 1.9]]);
        assert_eq!(motion.inputs, [[0.0], [0.5]]);
    }

    #[test]
    fn a_missing_or_misspelt_column_and_times_out_of_order_are_named() {
        let e = read_motion("run.csv", "t,x,xdot,F\n0,1,2,0\n1,1,2,0\n", &along()).unwrap_err();
        assert!(e.starts_with("error: run.csv has no column `x'`: a trajectory needs"), "{e}");
        assert!(e.contains("each input's value (F)"), "{e}");
        assert!(e.contains("--output x,x',F --out FILE.csv"), "{e}");
        assert!(e.ends_with("= note: the columns nothing reads: xdot"), "{e}");
        let e = read_motion("run.csv", "t,x,x',F\n0,1,2,0\n0.5,1,2,0\n0.5,1,2,0\n", &along())
            .unwrap_err();
        assert_eq!(
            e,
            "error: run.csv:4: `t` = 0.5 does not come after 0.5 on line 3: the times of a \
             motion must increase"
        );
        let e = read_motion("run.csv", "t,x,x',F\n0,1,2,0\n", &along()).unwrap_err();
        assert_eq!(e, "error: run.csv has one row: a motion to linearize along needs two");
    }

    #[test]
    fn the_csv_names_every_entry_and_has_a_row_per_sample() {
        let text = "t,x,x',F\n0,0,0,0\n0.5,0,0,0\n1,0,0,0\n";
        let mut along = along();
        let motion = read_motion("run.csv", text, &along).expect("reads");
        let l = engine::along::linearize_along(&mut along, &motion).expect("linearizes");
        let table = csv(&l);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(
            lines[0],
            "t,\"A[x,x]\",\"A[x,x']\",\"A[x',x]\",\"A[x',x']\",\"B[x,F]\",\"B[x',F]\""
        );
        // ẍ = −k/m·x + F/m.
        assert_eq!(lines[1], "0,0,1,-4,0,0,1");
        assert_eq!(lines.len(), 4);
    }
}
