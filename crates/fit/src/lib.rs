//! Fitting a scene to measurements: what `lagrange fit` estimates. This crate owns the data
//! table a fit reads ([`data`]: CSV text of times and scene expressions, each mistake a
//! diagnostic against the file), the free unknowns (parameters and start values `x(0)`,
//! `x'(0)`), the weighted residuals and their exact Jacobian from variational runs (Φ and the
//! parameter sensitivities S of `sim::variational`, chained through each column's own
//! partials), Levenberg–Marquardt within bounds with multiple shooting's continuity kept
//! exactly ([`lm`]), and the statistics at the optimum: standard errors and correlations from
//! the Jacobian and the residuals' variance, and the combination of unknowns the data cannot
//! tell apart. It also writes the fitted values into the scene's text ([`scene`]). It loads
//! the scene as `simulation` does for a run, and prints nothing.

pub mod data;
pub mod lm;
pub mod problem;
pub mod scene;

use lang::{Diagnostic, Span};
use nalgebra::DMatrix;

pub use lm::Ending;
pub use problem::{Kind, Unknown};

/// Why a fit could not be made.
#[derive(Debug)]
pub enum Error {
    /// The scene, a setting or the numbers.
    Engine(engine::Error),
    /// Diagnostics with spans into the data file's text.
    Data(Vec<Diagnostic>),
    /// Diagnostics with spans into the text given to a flag (`--free`).
    Argument { flag: &'static str, text: String, diagnostics: Vec<Diagnostic> },
}

impl From<engine::Error> for Error {
    fn from(e: engine::Error) -> Error {
        Error::Engine(e)
    }
}

impl Error {
    /// 2 for bad input, 1 for a numeric fault.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Engine(e) => e.exit_code(),
            Error::Data(_) | Error::Argument { .. } => 2,
        }
    }
}

/// A free unknown as given: its name, an optional value to start from, and where it stands in
/// the text of the flag that gave it.
#[derive(Clone, Debug, PartialEq)]
pub struct Free {
    pub name: String,
    pub start: Option<f64>,
    pub span: Span,
    pub text: String,
}

/// Reads one `--free` value: names separated by commas, each with an optional start value,
/// `c, L=1.2, theta(0)`.
pub fn parse_free(text: &str) -> Result<Vec<Free>, Error> {
    let mut out = Vec::new();
    let mut offset = 0;
    for piece in text.split(',') {
        let lead = piece.len() - piece.trim_start().len();
        let trimmed = piece.trim();
        let span = Span::new(offset + lead, offset + lead + trimmed.len().max(1));
        offset += piece.len() + 1;
        let refuse = |message: String, hint: &str| Error::Argument {
            flag: "--free",
            text: text.to_string(),
            diagnostics: vec![Diagnostic::error(span, message)
                .with_label("here")
                .with_hint(hint.to_string())],
        };
        if trimmed.is_empty() {
            return Err(refuse(
                "an empty name".into(),
                "name parameters and start values, separated by commas: `c, L, theta(0)`",
            ));
        }
        let (name, start) = match trimmed.split_once('=') {
            None => (trimmed.to_string(), None),
            Some((name, value)) => {
                let value = value.trim();
                let Some(v) = value.parse::<f64>().ok().filter(|v| v.is_finite()) else {
                    return Err(refuse(
                        format!("`{value}` is not a number to start `{}` from", name.trim()),
                        "give a start value in SI units, a plain number: `L=1.2`",
                    ));
                };
                (name.trim().to_string(), Some(v))
            }
        };
        out.push(Free { name, start, span, text: text.to_string() });
    }
    Ok(out)
}

/// A bound on an unknown, `--bound c=0:` (either side may be left open).
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    pub name: String,
    pub lower: f64,
    pub upper: f64,
}

/// Reads `NAME=LO:HI`, either side of the colon empty for no bound.
pub fn parse_bound(text: &str) -> Result<Bound, Error> {
    let bad = |why: &str| {
        Error::Engine(engine::Error::Input(format!(
            "--bound {text}: {why}; a bound is NAME=LOWER:UPPER, either side left empty for \
             none (`c=0:`)"
        )))
    };
    let Some((name, range)) = text.split_once('=') else { return Err(bad("no `=`")) };
    let Some((lo, hi)) = range.split_once(':') else { return Err(bad("no `:`")) };
    let side = |s: &str, open: f64| -> Result<f64, Error> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(open);
        }
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(&format!("`{s}` is not a number")))
    };
    let (lower, upper) = (side(lo, f64::NEG_INFINITY)?, side(hi, f64::INFINITY)?);
    if lower >= upper {
        return Err(bad("the lower bound is not below the upper"));
    }
    Ok(Bound { name: name.trim().to_string(), lower, upper })
}

/// What a fit is asked.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The runs' settings as `simulate` takes them (method, tolerance, `--set`, inputs); the
    /// end time is the data's last.
    pub run: simulation::Options,
    pub free: Vec<Free>,
    pub bounds: Vec<Bound>,
    /// Noise levels σ per column, in the column's unit: each residual is divided by its
    /// column's (1 where none is given).
    pub noise: Vec<(String, f64)>,
    /// The number of shots (1: single shooting).
    pub shots: usize,
    /// The most Jacobians taken.
    pub iterations: usize,
}

/// A combination of the unknowns the data cannot tell apart: Σ coefficientₖ·δθₖ/θₖ (each
/// change relative to the unknown's value, or absolute where that is 0) leaves the residuals
/// unchanged to first order.
#[derive(Clone, Debug, PartialEq)]
pub struct Combination {
    pub terms: Vec<(String, f64)>,
    /// The smallest singular value of the scaled Jacobian over the largest.
    pub ratio: f64,
}

/// A measured column at the optimum.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnFit {
    pub name: String,
    /// The RMS of model − data, in the column's unit.
    pub rms: f64,
    pub count: usize,
    /// The noise level its residuals were divided by, where one was given.
    pub noise: Option<f64>,
}

/// A fit's result.
#[derive(Clone, Debug)]
pub struct Fit {
    pub unknowns: Vec<Unknown>,
    pub initial: Vec<f64>,
    pub estimates: Vec<f64>,
    /// Infinite for an unknown in a combination the data cannot fix.
    pub standard_errors: Vec<f64>,
    /// k × k.
    pub covariance: Vec<Vec<f64>>,
    pub correlation: Vec<Vec<f64>>,
    pub columns: Vec<ColumnFit>,
    /// Σ r² (weighted) at the start and at the optimum.
    pub initial_cost: f64,
    pub cost: f64,
    /// The residuals' variance, Σ r²/(N − k): the covariance is (JᵀJ)⁻¹ scaled by it.
    pub variance: f64,
    pub measurements: usize,
    pub degrees_of_freedom: usize,
    pub iterations: usize,
    pub evaluations: usize,
    pub steps: usize,
    pub ending: Ending,
    pub shots: usize,
    pub unidentifiable: Option<Combination>,
    /// The data's times and, per column, the fitted model's values there.
    pub times: Vec<f64>,
    pub model: Vec<Vec<f64>>,
    pub data: Vec<Vec<Option<f64>>>,
}

/// Below this ratio of the scaled Jacobian's smallest singular value to its largest, the data
/// cannot tell the unknowns apart: the covariance's entries along that direction are noise
/// amplified by more than 10⁸.
const UNIDENTIFIABLE: f64 = 1e-8;

/// Fits `source` to the data `table`.
pub fn fit(source: &str, options: &Options, table: data::Table) -> Result<Fit, Error> {
    let mut problem = problem::Problem::load(source, options, table)?;
    let k = problem.free();
    let mut bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); k];
    for b in &options.bounds {
        let Some(j) = problem.unknowns.iter().position(|u| u.name == b.name) else {
            let names: Vec<&str> = problem.unknowns.iter().map(|u| u.name.as_str()).collect();
            return Err(engine::Error::Input(format!(
                "--bound {}: not a free unknown; one of {}",
                b.name,
                names.join(", ")
            ))
            .into());
        };
        bounds[j] = (b.lower, b.upper);
    }
    let initial = problem.initial(&options.free)?;
    for (j, (v, (lo, hi))) in initial.iter().zip(&bounds).enumerate() {
        if v < lo || v > hi {
            return Err(engine::Error::Input(format!(
                "`{}` starts at {v}, outside its bounds {lo}:{hi}",
                problem.unknowns[j].name
            ))
            .into());
        }
    }
    let mut start = initial.clone();
    start.extend(problem.shot_guesses(&initial)?);
    bounds.resize(problem.width(), (f64::NEG_INFINITY, f64::INFINITY));
    let iterations = if options.iterations == 0 { 100 } else { options.iterations };
    let solution = lm::solve(&mut problem, start, &bounds, iterations)?;
    let e = &solution.evaluation;
    let measurements = e.residuals.len();
    let cost: f64 = e.residuals.iter().map(|r| r * r).sum();
    let degrees_of_freedom = measurements.saturating_sub(k);
    let variance = if degrees_of_freedom > 0 { cost / degrees_of_freedom as f64 } else { f64::NAN };
    let estimates = solution.unknowns[..k].to_vec();
    let effective = effective_jacobian(e, measurements, problem.width(), k);
    let (covariance, unidentifiable) =
        covariance(&effective, &estimates, variance, &problem.unknowns);
    let standard_errors: Vec<f64> = (0..k).map(|j| covariance[j][j].sqrt()).collect();
    let correlation = (0..k)
        .map(|i| {
            (0..k)
                .map(|j| {
                    let product = standard_errors[i] * standard_errors[j];
                    // No correlation is told of an unknown the data leave unbounded.
                    if product.is_finite() {
                        covariance[i][j] / product
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        })
        .collect();
    let table = &problem.table;
    let columns = table
        .columns
        .iter()
        .enumerate()
        .map(|(c, column)| {
            let pairs: Vec<(f64, f64)> = table.values[c]
                .iter()
                .zip(&e.model[c])
                .filter_map(|(d, m)| d.map(|d| (d, *m)))
                .collect();
            let rms = (pairs.iter().map(|(d, m)| (m - d) * (m - d)).sum::<f64>()
                / pairs.len() as f64)
                .sqrt();
            let noise = options.noise.iter().find(|(n, _)| *n == column.name).map(|(_, s)| *s);
            ColumnFit { name: column.name.clone(), rms, count: pairs.len(), noise }
        })
        .collect();
    Ok(Fit {
        unknowns: problem.unknowns.clone(),
        initial,
        estimates,
        standard_errors,
        covariance,
        correlation,
        columns,
        initial_cost: 2.0 * solution.initial_cost,
        cost,
        variance,
        measurements,
        degrees_of_freedom,
        iterations: solution.iterations,
        evaluations: solution.evaluations,
        steps: solution.steps,
        ending: solution.ending,
        shots: problem.shot_starts.len(),
        unidentifiable,
        times: table.times.clone(),
        model: e.model.clone(),
        data: table.values.clone(),
    })
}

/// ∂r/∂θ with the shots' starts following θ along the closed gaps (C_θ + C_z·dz/dθ = 0):
/// the Jacobian of the single shot the multiple shots have become at the optimum.
fn effective_jacobian(
    e: &problem::Evaluation,
    rows: usize,
    width: usize,
    k: usize,
) -> DMatrix<f64> {
    let j = DMatrix::from_row_slice(rows, width, &e.jacobian);
    if e.gaps.is_empty() {
        return j;
    }
    let g = e.gaps.len();
    let c = DMatrix::from_row_slice(g, width, &e.gap_jacobian);
    let c_theta = c.columns(0, k).into_owned();
    let c_z = c.columns(k, width - k).into_owned();
    let Some(dz) = c_z.full_piv_lu().solve(&(-c_theta)) else {
        return j.columns(0, k).into_owned();
    };
    j.columns(0, k) + j.columns(k, width - k) * dz
}

/// The covariance s²·(JᵀJ)⁻¹ from the SVD of J scaled column by column by the unknowns'
/// values, and the combination the data cannot tell apart where the smallest singular value
/// is below [`UNIDENTIFIABLE`] of the largest.
fn covariance(
    j: &DMatrix<f64>,
    estimates: &[f64],
    variance: f64,
    unknowns: &[Unknown],
) -> (Vec<Vec<f64>>, Option<Combination>) {
    let k = estimates.len();
    let scale: Vec<f64> = estimates.iter().map(|v| if *v != 0.0 { v.abs() } else { 1.0 }).collect();
    let mut scaled = j.clone();
    for (c, s) in scale.iter().enumerate() {
        scaled.column_mut(c).scale_mut(*s);
    }
    let svd = scaled.svd(false, true);
    let v_t = svd.v_t.expect("asked for V");
    let sigma = &svd.singular_values;
    let largest = sigma.iter().copied().fold(0.0, f64::max);
    let (smallest_at, smallest) = sigma
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::INFINITY), |best, (i, s)| if s < best.1 { (i, s) } else { best });
    // The pseudo-inverse over the directions the data fix: an unknown along none of the
    // others keeps its standard error; one in a combination they cannot fix has none.
    let fixed = |s: f64| s > UNIDENTIFIABLE * largest;
    let mut cov = vec![vec![0.0; k]; k];
    for (i, row) in cov.iter_mut().enumerate() {
        for (l, entry) in row.iter_mut().enumerate() {
            let mut sum = 0.0;
            for (m, s) in sigma.iter().enumerate().filter(|(_, s)| fixed(**s)) {
                sum += v_t[(m, i)] * v_t[(m, l)] / (s * s);
            }
            *entry = variance * sum * scale[i] * scale[l];
        }
    }
    for (m, _) in sigma.iter().enumerate().filter(|(_, s)| !fixed(**s)) {
        for i in (0..k).filter(|i| v_t[(m, *i)].abs() > 1e-3) {
            cov[i][i] = f64::INFINITY;
        }
    }
    let ratio = if largest > 0.0 { smallest / largest } else { 0.0 };
    let unidentifiable = (k > 0 && ratio < UNIDENTIFIABLE).then(|| {
        let mut terms: Vec<(String, f64)> = unknowns
            .iter()
            .enumerate()
            .map(|(c, u)| (u.name.clone(), v_t[(smallest_at, c)]))
            .filter(|(_, v)| v.abs() > 1e-3)
            .collect();
        // A sign that reads the same on every machine: the largest term positive.
        if let Some(big) = terms.iter().map(|t| t.1).max_by(|a, b| a.abs().total_cmp(&b.abs())) {
            if big < 0.0 {
                terms.iter_mut().for_each(|t| t.1 = -t.1);
            }
        }
        Combination { terms, ratio }
    });
    (cov, unidentifiable)
}
