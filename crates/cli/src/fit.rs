//! `fit`'s report: the estimates with their standard errors, the correlations, the residuals
//! per column, the iterations, and a warning where the data cannot tell unknowns apart; as
//! text for people or JSON for programs. And a fit's errors, each against the text it points
//! into: the scene, the data file, or a flag's value.

use std::fmt::Write;

use fit::Fit;
use serde_json::{json, Value};

/// A number as the report prints it: nine significant digits, enough to compare fits and
/// stable from run to run.
fn number(v: f64) -> String {
    if !v.is_finite() {
        return if v.is_nan() { "undefined".into() } else { "unbounded".into() };
    }
    if v == 0.0 {
        return "0".into();
    }
    let text = format!("{v:.8e}");
    let (mantissa, exponent) = text.split_once('e').expect("exponent form");
    let exponent: i32 = exponent.parse().expect("an integer exponent");
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    if (-4..6).contains(&exponent) {
        let digits = (8 - exponent).max(0) as usize;
        let plain = format!("{v:.digits$}");
        if plain.contains('.') {
            plain.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            plain
        }
    } else {
        format!("{mantissa}e{exponent}")
    }
}

/// Two significant digits, for the standard errors' share and the correlations.
fn short(v: f64) -> String {
    if v.is_finite() {
        // Rounded to nothing, a negative shows no sign.
        format!("{:.2}", if v.abs() < 0.005 { 0.0 } else { v })
    } else {
        "–".into()
    }
}

/// The report as text.
pub fn text_report(path: &str, data: &str, fit: &Fit) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "fit of {path} to {data}: {} measurements, {} unknowns{}",
        fit.measurements,
        fit.unknowns.len(),
        if fit.shots > 1 { format!(", {} shots", fit.shots) } else { String::new() }
    );
    let width = fit.unknowns.iter().map(|u| u.name.chars().count()).max().unwrap_or(0);
    let _ = writeln!(out, "estimates (± one standard error):");
    for (j, u) in fit.unknowns.iter().enumerate() {
        let pad = " ".repeat(width - u.name.chars().count());
        let (value, error) = (fit.estimates[j], fit.standard_errors[j]);
        let relative = if value != 0.0 && error.is_finite() {
            format!("  ({}%)", short(100.0 * error / value.abs()))
        } else {
            String::new()
        };
        let _ = writeln!(
            out,
            "  {}{pad} = {} ± {}{relative}    from {}",
            u.name,
            number(value),
            number(error),
            number(fit.initial[j])
        );
    }
    if fit.unknowns.len() > 1 {
        let _ = writeln!(out, "correlations:");
        for (i, u) in fit.unknowns.iter().enumerate() {
            let pad = " ".repeat(width - u.name.chars().count());
            let row: Vec<String> =
                fit.correlation[i][..=i].iter().map(|c| format!("{:>6}", short(*c))).collect();
            let _ = writeln!(out, "  {}{pad} {}", u.name, row.join(" "));
        }
    }
    if let Some(c) = &fit.unidentifiable {
        let (names, coefficients): (Vec<String>, Vec<String>) =
            c.terms.iter().map(|(name, v)| (format!("δ{name}/{name}"), short(*v))).unzip();
        let _ = writeln!(
            out,
            "warning: the data cannot tell the unknowns apart: moving ({}) along ({}) leaves \
             the residuals unchanged (the smallest singular value is {:.1e} of the largest); \
             fix one of them, or measure what moves them differently",
            names.join(", "),
            coefficients.join(", "),
            c.ratio
        );
    }
    let _ = writeln!(out, "residuals (model − data):");
    let width = fit.columns.iter().map(|c| c.name.chars().count()).max().unwrap_or(0);
    for c in &fit.columns {
        let pad = " ".repeat(width - c.name.chars().count());
        let noise = c.noise.map(|s| format!(", noise {}", number(s))).unwrap_or_default();
        let _ = writeln!(
            out,
            "  {}{pad}  RMS {}  over {} values{noise}",
            c.name,
            number(c.rms),
            c.count
        );
    }
    let _ = writeln!(
        out,
        "cost Σr²: {} from {}; variance Σr²/(N − k) = {} ({} degrees of freedom)",
        number(fit.cost),
        number(fit.initial_cost),
        number(fit.variance),
        fit.degrees_of_freedom
    );
    let _ = writeln!(
        out,
        "Levenberg–Marquardt: {} iterations, {} runs, {} integrator steps; {}",
        fit.iterations,
        fit.evaluations,
        fit.steps,
        fit.ending.words()
    );
    out
}

/// The report as JSON.
pub fn json(path: &str, data: &str, fit: &Fit) -> String {
    let unknowns: Vec<Value> = fit
        .unknowns
        .iter()
        .enumerate()
        .map(|(j, u)| {
            json!({
                "name": u.name,
                "kind": match u.kind { fit::Kind::Parameter(_) => "parameter", fit::Kind::Start { .. } => "start" },
                "estimate": fit.estimates[j],
                "standard_error": finite(fit.standard_errors[j]),
                "initial": fit.initial[j],
            })
        })
        .collect();
    let grid = |m: &Vec<Vec<f64>>| -> Value {
        m.iter().map(|row| row.iter().map(|v| finite(*v)).collect::<Value>()).collect()
    };
    let columns: Vec<Value> = fit
        .columns
        .iter()
        .map(|c| json!({ "name": c.name, "rms": c.rms, "count": c.count, "noise": c.noise }))
        .collect();
    let unidentifiable = fit.unidentifiable.as_ref().map(|c| {
        json!({
            "ratio": c.ratio,
            "terms": c.terms.iter().map(|(n, v)| json!({ "name": n, "coefficient": v })).collect::<Vec<_>>(),
        })
    });
    let report = json!({
        "scene": path,
        "data": data,
        "unknowns": unknowns,
        "covariance": grid(&fit.covariance),
        "correlation": grid(&fit.correlation),
        "columns": columns,
        "unidentifiable": unidentifiable,
        "cost": fit.cost,
        "initial_cost": fit.initial_cost,
        "variance": finite(fit.variance),
        "measurements": fit.measurements,
        "degrees_of_freedom": fit.degrees_of_freedom,
        "iterations": fit.iterations,
        "evaluations": fit.evaluations,
        "steps": fit.steps,
        "shots": fit.shots,
        "converged": fit.ending.converged(),
        "ending": fit.ending.words(),
    });
    let mut text = serde_json::to_string_pretty(&report).expect("JSON of plain values");
    text.push('\n');
    text
}

/// A number JSON can hold: null for one that is not finite.
fn finite(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// The picture of `--plot`: data and fit, and the residuals, per column.
pub fn plot(path: &str, fit: &Fit) -> String {
    let columns: Vec<crate::plot::Measured> = fit
        .columns
        .iter()
        .enumerate()
        .map(|(c, column)| crate::plot::Measured {
            name: column.name.clone(),
            model: fit.model[c].clone(),
            data: fit.data[c].clone(),
        })
        .collect();
    crate::plot::fit(&format!("fit of {path}"), &fit.times, &columns)
}

/// A fit's error as text, each diagnostic against the text it points into.
pub fn error(path: &str, data: (&str, &str), error: &fit::Error) -> String {
    match error {
        fit::Error::Engine(e) => crate::diagnostics::error(path, e),
        fit::Error::Data(diagnostics) => crate::diagnostics::render(data.0, data.1, diagnostics),
        fit::Error::Argument { flag, text, diagnostics } => {
            crate::diagnostics::render(flag, text, diagnostics)
        }
    }
}

/// What `fit` was asked, as the command line gives it.
pub struct Request {
    pub free: Vec<String>,
    pub bound: Vec<String>,
    pub noise: Vec<engine::input::Assignment>,
    pub shots: usize,
    pub iterations: usize,
    pub json: bool,
}

/// Where `fit` writes besides standard output.
pub struct Written {
    pub out: Option<std::path::PathBuf>,
    pub fitted: Option<std::path::PathBuf>,
    pub plot: Option<std::path::PathBuf>,
}

/// A fit made from files: the scene's text and the fit, or the error as text with the exit
/// code (2 bad input, 1 a fault).
pub fn from_files(
    scene: &std::path::Path,
    data: &std::path::Path,
    run: simulation::Options,
    request: &Request,
) -> Result<(String, Fit), (String, u8)> {
    let path = scene.display().to_string();
    let data_path = data.display().to_string();
    let source = crate::read_scene(scene).map_err(|e| (e, 2))?;
    let text = std::fs::read(data)
        .map_err(|e| e.to_string())
        .and_then(|bytes| crate::decode(&data_path, bytes))
        .map_err(|e| (format!("error: cannot read {data_path}: {e}\n"), 2))?;
    let fail = |e: fit::Error| (error(&path, (&data_path, &text), &e), e.exit_code());
    let mut options = fit::Options {
        run,
        shots: request.shots,
        iterations: request.iterations,
        ..Default::default()
    };
    for given in &request.free {
        options.free.extend(fit::parse_free(given).map_err(fail)?);
    }
    for given in &request.bound {
        options.bounds.push(fit::parse_bound(given).map_err(fail)?);
    }
    for n in &request.noise {
        let sigma = n.value.trim().parse::<f64>().map_err(|_| {
            let message = format!(
                "error: --noise {}={}: a noise level is a number, in the column's unit\n",
                n.name, n.value
            );
            (message, 2)
        })?;
        options.noise.push((n.name.clone(), sigma));
    }
    let table = fit::data::read(&text).map_err(|d| fail(fit::Error::Data(d)))?;
    let result = fit::fit(&source, &options, table).map_err(fail)?;
    Ok((source, result))
}

/// `lagrange fit`: reads the scene and the data, fits, and writes the report and the files
/// asked for; the exit code (2 bad input, 1 a fault or no convergence).
pub fn run(
    scene: &std::path::Path,
    data: &std::path::Path,
    run: simulation::Options,
    request: Request,
    written: Written,
) -> std::process::ExitCode {
    use std::process::ExitCode;
    let path = scene.display().to_string();
    let data_path = data.display().to_string();
    let (source, result) = match from_files(scene, data, run, &request) {
        Ok(found) => found,
        Err((message, code)) => {
            eprint!("{message}");
            return ExitCode::from(code);
        }
    };
    let report = if request.json {
        json(&path, &data_path, &result)
    } else {
        text_report(&path, &data_path, &result)
    };
    let mut files = Vec::new();
    if let Some(p) = &written.plot {
        files.push((p, plot(&path, &result)));
    }
    if let Some(p) = &written.fitted {
        match fit::scene::written(&source, &result) {
            Ok(text) => files.push((p, text)),
            Err(e) => {
                eprint!("{}", crate::diagnostics::error(&path, &e));
                return ExitCode::from(e.exit_code());
            }
        }
    }
    if let Some(p) = &written.out {
        files.push((p, report.clone()));
    }
    for (p, text) in &files {
        if let Err(e) = crate::write_atomically(p, text) {
            eprintln!("error: cannot write {}: {e}", p.display());
            return ExitCode::from(2);
        }
    }
    if written.out.is_none() {
        print!("{report}");
    }
    if result.ending.converged() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: the fit did not converge: {}", result.ending.words());
        ExitCode::from(1)
    }
}
