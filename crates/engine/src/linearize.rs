//! Small motions about a reference, in numbers: the exact M, C, K of `mechanics` evaluated at
//! the parameters' values, the reference checked (the accelerations there must vanish, and it
//! must lie on every kept constraint), the first-order matrix A and its eigenvalues, the
//! verdict on stability, and a sweep of one parameter with the values where the verdict
//! changes found by bisection. Printing it all is the front end's.
//!
//! Coordinates stay those of the derivation, except that a cyclic coordinate's δq leaves the
//! state (its rate stays: a neighbouring steady motion spins at another rate), and with
//! constraints kept with multipliers the state moves in the null space of their Jacobian at
//! the reference: δq = N·z, so that J·δq = 0 and Jᵀ·δλ drops out of Nᵀ·(…).

use cas::{ExprId, Rational, Style, SymId};
use lang::{Diagnostic, Span};
use mechanics::{Derivation, Linearization};
use nalgebra::{DMatrix, DVector};
use numeric::{ScaledEvaluator, Tape};

use crate::numbers::{prepare, Prepared};
use crate::{Error, Piece, Setting};

/// A real part counts as zero within this fraction of the largest |eigenvalue|: rounding in
/// the eigenvalues of a matrix of order ten is far below it, and a root of a double eigenvalue
/// (where stability changes) is still far above it a relative 1e-10 away.
pub const RELATIVE_TOLERANCE: f64 = 1e-8;
/// A residual counts as zero within this fraction of the size of its terms.
const EQUILIBRIUM_TOLERANCE: f64 = 1e-9;
/// Bisection stops when the bracket of a change of stability is this narrow, relatively.
const SWEEP_PRECISION: f64 = 1e-10;
/// Past this many sweep values the table stops being a table.
const MAX_SWEEP_VALUES: usize = 100_000;
/// Iterations the Schur and SVD decompositions may take: a count, never a time.
const MAX_ITERATIONS: usize = 10_000;

/// What a front end asks for.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// `theta=0, phi'=2`: items that override or extend the scene's `linearize about` line.
    pub about: Option<String>,
    /// `name=value` pairs for parameters.
    pub set: Vec<String>,
    /// `p=a:b:n`: n values of parameter p from a to b.
    pub sweep: Option<String>,
    /// Skip the dimension check.
    pub no_units: bool,
}

/// How small motions about the reference behave, by the real parts of the eigenvalues.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stability {
    /// Every real part is below −tolerance: small motions die out.
    Stable,
    /// None is above +tolerance, some is within it: small motions neither grow nor die out
    /// (at first order).
    MarginallyStable,
    /// Some real part is above +tolerance: some small motion grows.
    Unstable,
}

impl Stability {
    pub fn name(self) -> &'static str {
        match self {
            Stability::Stable => "stable",
            Stability::MarginallyStable => "marginally stable",
            Stability::Unstable => "unstable",
        }
    }
}

/// The linearization at one set of parameter values.
#[derive(Clone, Debug)]
pub struct Numbers {
    /// The parameters' values, in declaration order.
    pub parameters: Vec<f64>,
    pub mass: Vec<Vec<f64>>,
    pub damping: Vec<Vec<f64>>,
    /// With the multipliers at their reference values.
    pub stiffness: Vec<Vec<f64>>,
    /// The multipliers at the reference, in the order of the derivation's.
    pub multipliers: Vec<f64>,
    /// The accelerations at the reference (zero within the tolerance), per coordinate; with
    /// velocity constraints kept, per independent rate, then the rate of each dependent
    /// position kept (the `RatesLinearization`'s `residual_symbols`).
    pub accelerations: Vec<f64>,
    /// With velocity constraints kept: G of δṗ = G·(δp, δu), one row per position kept.
    pub kinematics: Option<Vec<Vec<f64>>>,
    /// With kept constraints: the basis N of their null space (one column per reduced
    /// coordinate z, one row per coordinate), δq = N·z.
    pub basis: Option<Vec<Vec<f64>>>,
    /// With position and velocity constraints kept together: the coordinates whose positions
    /// stay in the state, then those whose rates are the independent rates (indices into the
    /// linearization's `coords`), as the numbers chose them at these values.
    pub reduced: Option<(Vec<usize>, Vec<usize>)>,
    /// With position and velocity constraints kept together: the dependent rates at the
    /// reference (the `KeptLinearization`'s `dependent`, in its order), solved in numbers.
    pub dependent_rates: Vec<f64>,
    /// u̇ = A·u, u the state.
    pub a: Vec<Vec<f64>>,
    /// (re, im), by real part from the largest down (within the tolerance of zero as zero),
    /// then by imaginary part.
    pub eigenvalues: Vec<(f64, f64)>,
    pub stability: Stability,
    /// The absolute tolerance on real parts: [`RELATIVE_TOLERANCE`] × the largest |eigenvalue|.
    pub tolerance: f64,
    /// How many of the zero eigenvalues are first integrals' (conserved combinations of the
    /// state, which the verdict leaves aside: they lead to neighbouring steady motions).
    pub first_integrals: usize,
}

/// One value of a sweep.
#[derive(Clone, Debug)]
pub struct Row {
    pub value: f64,
    pub eigenvalues: Vec<(f64, f64)>,
    pub stability: Stability,
    /// M, C and K at this value, as [`Numbers`] has them.
    pub mass: Vec<Vec<f64>>,
    pub damping: Vec<Vec<f64>>,
    pub stiffness: Vec<Vec<f64>>,
}

/// A value of the swept parameter where the verdict changes, bracketed by bisection.
#[derive(Clone, Copy, Debug)]
pub struct Change {
    pub value: f64,
    /// The verdict just before (towards the start of the sweep) and just after.
    pub from: Stability,
    pub to: Stability,
    /// The last bracket: `from` holds at its first end, `to` at its second.
    pub bracket: (f64, f64),
}

/// The eigenvalues against one parameter.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub parameter: String,
    pub rows: Vec<Row>,
    pub changes: Vec<Change>,
}

/// Everything `linearize` reports.
pub struct Linearized {
    pub derivation: Derivation,
    pub linearization: Linearization,
    /// M, C, K in the forms a report shows.
    pub mass: Vec<Vec<ExprId>>,
    pub damping: Vec<Vec<ExprId>>,
    pub stiffness: Vec<Vec<ExprId>>,
    /// The names of the state u of u̇ = A·u: positions (`theta`, or `z1` along the null space
    /// of kept constraints), then rates (`theta'`).
    pub state: Vec<String>,
    /// Whether the algebra showed the accelerations zero at the reference for every value of
    /// the parameters (else numbers showed it at each value used).
    pub exact_reference: bool,
    pub at: Numbers,
    pub sweep: Option<Sweep>,
}

fn bad(message: impl Into<String>) -> Error {
    Error::Input(message.into())
}

/// `p=a:b:n`, checked.
fn parse_sweep(text: &str) -> Result<(String, f64, f64, usize), Error> {
    let form = || {
        let rest = format!(" `{text}` is not of the form p=a:b:n (like w=0:100:201)");
        Error::setting(Setting::Sweep, rest)
    };
    let (name, range) = text.split_once('=').ok_or_else(form)?;
    let parts: Vec<&str> = range.split(':').map(str::trim).collect();
    let [a, b, n] = parts[..] else { return Err(form()) };
    let (Ok(a), Ok(b), Ok(n)) = (a.parse::<f64>(), b.parse::<f64>(), n.parse::<usize>()) else {
        return Err(form());
    };
    if !(a.is_finite() && b.is_finite()) || a == b {
        let rest = ": the ends must be two different finite numbers";
        return Err(Error::given(Setting::Sweep, text, rest));
    }
    if !(2..=MAX_SWEEP_VALUES).contains(&n) {
        let rest = format!(": the number of values must be from 2 to {MAX_SWEEP_VALUES}");
        return Err(Error::given(Setting::Sweep, text, rest));
    }
    Ok((name.trim().to_string(), a, b, n))
}

/// Loads `source`, linearizes it about its reference (with `--about` items after the scene's)
/// and analyses it at the parameters' values, and over the sweep if one is asked for.
pub fn linearize(source: &str, options: &Options) -> Result<Linearized, Error> {
    let sweep = options.sweep.as_deref().map(parse_sweep).transpose()?;
    let mut sets: Vec<(String, String)> = Vec::new();
    for s in &options.set {
        let Some((name, value)) = s.split_once('=') else {
            return Err(Error::setting(
                Setting::Set,
                format!(" `{s}` is not of the form name=value"),
            ));
        };
        sets.push((name.trim().to_string(), value.trim().to_string()));
    }

    // `--about` becomes a `linearize about` line after the scene's, so that it is resolved
    // (names, units, constants) like one and overrides it item by item.
    let mut text = source.to_string();
    let mut about_line = (usize::MAX, usize::MAX);
    if let Some(about) = &options.about {
        if about.contains(['\n', '\r']) {
            return Err(Error::setting(Setting::About, " must be one line"));
        }
        if !text.ends_with('\n') {
            text.push('\n');
        }
        about_line.0 = text.len();
        text.push_str("linearize about ");
        text.push_str(about);
        about_line.1 = text.len();
        text.push('\n');
    }
    let extra: Vec<String> = sets.iter().map(|(_, v)| v.clone()).collect();
    let from_about = |error: Error| from_about(error, about_line);
    let mut prepared =
        prepare(&text, &extra, crate::Options { units: !options.no_units }).map_err(from_about)?;
    if prepared.derivation.model.linearize.is_empty() {
        return Err(Error::Setting(vec![
            Piece::Text(
                "the scene has no `linearize about` line: add one, or give the reference with "
                    .into(),
            ),
            Piece::Given(Setting::About, "theta=0".into()),
        ]));
    }
    let scene = |diagnostics: Vec<Diagnostic>| Error::Scene { diagnostics, source: text.clone() };
    let linearization = prepared.derivation.linearize().map_err(scene).map_err(from_about)?;
    if linearization.coords.is_empty() {
        return Err(bad("the constraints fix every coordinate: nothing is left to linearize"));
    }

    // --- parameter values ------------------------------------------------------------------
    let model = &prepared.derivation.model;
    let mut overrides: Vec<(usize, ExprId)> = Vec::new();
    for ((name, _), expr) in sets.iter().zip(prepared.extra.clone()) {
        match model.params.iter().position(|p| &p.name == name) {
            Some(i) => overrides.push((i, expr)),
            None if model
                .coords
                .iter()
                .any(|c| *name == c.name || *name == format!("{}'", c.name)) =>
            {
                return Err(Error::Setting(vec![
                    Piece::Given(Setting::Set, name.clone()),
                    Piece::Text(": the reference is given by `linearize about` or ".into()),
                    Piece::Setting(Setting::About),
                    Piece::Text(", not ".into()),
                    Piece::Setting(Setting::Set),
                ]))
            }
            None => {
                let known: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
                let rest = format!(": no parameter of that name; one of {}", known.join(", "));
                return Err(Error::given(Setting::Set, name, rest));
            }
        }
    }
    let swept = match &sweep {
        Some((name, ..)) => {
            Some(model.params.iter().position(|p| &p.name == name).ok_or_else(|| {
                let known: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
                let rest = format!(": no parameter of that name; one of {}", known.join(", "));
                Error::given(Setting::Sweep, name, rest)
            })?)
        }
        None => None,
    };

    let analysis = Analysis::new(&mut prepared, &linearization)?;
    let mut session =
        Session { prepared, linearization, analysis, overrides, swept, text, about_line };
    let at = session.analyse(None)?;
    let sweep = match sweep {
        Some((parameter, a, b, n)) => Some(session.sweep(parameter, a, b, n)?),
        None => None,
    };

    let Session { mut prepared, linearization, analysis, .. } = session;
    let pool = &mut prepared.derivation.model.pool;
    let shown = |pool: &mut cas::Pool, m: &[Vec<ExprId>]| -> Vec<Vec<ExprId>> {
        m.iter().map(|r| r.iter().map(|e| pool.factor_content(*e)).collect()).collect()
    };
    let mass = shown(pool, &linearization.mass);
    let damping = shown(pool, &linearization.damping);
    let stiffness = shown(pool, &linearization.stiffness);
    let state = analysis.state_names(&prepared, &linearization, &at);
    Ok(Linearized {
        derivation: prepared.derivation,
        exact_reference: linearization.residual_is_zero,
        linearization,
        mass,
        damping,
        stiffness,
        state,
        at,
        sweep,
    })
}

/// A linearization being analysed at one set of parameter values after another.
struct Session {
    prepared: Prepared,
    linearization: Linearization,
    analysis: Analysis,
    /// `--set` values: parameter index → expression.
    overrides: Vec<(usize, ExprId)>,
    /// The swept parameter's index.
    swept: Option<usize>,
    /// The scene as loaded, `--about` line included, for diagnostics.
    text: String,
    about_line: (usize, usize),
}

impl Session {
    /// The numbers at the parameters' values, with the swept parameter at `value` if given.
    fn analyse(&mut self, value: Option<f64>) -> Result<Numbers, Error> {
        let mut all = self.overrides.clone();
        if let (Some(i), Some(v)) = (self.swept, value) {
            let q = Rational::from_float(v).ok_or_else(|| bad(format!("{v} is not a number")))?;
            all.push((i, self.prepared.derivation.model.pool.num(q)));
        }
        let parameters = self.prepared.parameter_values(&all)?;
        if !all.is_empty() {
            // The scene's masses were checked with its own values; these may change their sign.
            self.prepared.masses_at(&parameters)?;
        }
        self.analysis.at(&self.linearization, &parameters).map_err(|fault| {
            let model = &self.prepared.derivation.model;
            let at = match (self.swept, value) {
                (Some(i), Some(v)) => format!(" (at {} = {v})", model.params[i].name),
                _ => String::new(),
            };
            let diagnostic = fault.diagnostic(&self.prepared, self.linearization.span, &at);
            let error = Error::Scene { diagnostics: vec![diagnostic], source: self.text.clone() };
            from_about(error, self.about_line)
        })
    }

    /// n evenly spaced values from a to b, and every change of the verdict between neighbours
    /// bisected (one per pair of neighbours: a finer sweep finds changes closer together).
    fn sweep(&mut self, parameter: String, a: f64, b: f64, n: usize) -> Result<Sweep, Error> {
        let mut rows = Vec::with_capacity(n);
        for k in 0..n {
            let value = if k == n - 1 { b } else { a + (b - a) * k as f64 / (n - 1) as f64 };
            let numbers = self.analyse(Some(value))?;
            rows.push(Row {
                value,
                eigenvalues: numbers.eigenvalues,
                stability: numbers.stability,
                mass: numbers.mass,
                damping: numbers.damping,
                stiffness: numbers.stiffness,
            });
        }
        let mut changes = Vec::new();
        for pair in rows.windows(2) {
            let (first, second) = (&pair[0], &pair[1]);
            if first.stability == second.stability {
                continue;
            }
            let (from, mut to) = (first.stability, second.stability);
            let (mut lo, mut hi) = (first.value, second.value);
            // Between stable and unstable, the largest real part crosses zero: bisecting on
            // its sign finds the crossing itself, where the verdict would stop at the edge of
            // the tolerance band around zero.
            let through_zero = matches!(
                (from, to),
                (Stability::Stable, Stability::Unstable) | (Stability::Unstable, Stability::Stable)
            );
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                let narrow = (hi - lo).abs() <= SWEEP_PRECISION * lo.abs().max(hi.abs());
                if narrow || mid == lo || mid == hi {
                    break;
                }
                let numbers = self.analyse(Some(mid))?;
                let like_from = if through_zero {
                    (largest_real_part(&numbers) > 0.0) == (from == Stability::Unstable)
                } else {
                    numbers.stability == from
                };
                if like_from {
                    lo = mid;
                } else {
                    hi = mid;
                    if !through_zero {
                        to = numbers.stability;
                    }
                }
            }
            changes.push(Change { value: 0.5 * (lo + hi), from, to, bracket: (lo, hi) });
        }
        Ok(Sweep { parameter, rows, changes })
    }
}

/// Says where a diagnostic points into the command line's `--about` line, which follows the
/// file in the text loaded.
fn from_about(error: Error, about_line: (usize, usize)) -> Error {
    match error {
        Error::Scene { mut diagnostics, source } => {
            for d in &mut diagnostics {
                if (about_line.0..=about_line.1).contains(&d.span.start) {
                    d.label = format!("{} (from --about)", d.label);
                }
            }
            Error::Scene { diagnostics, source }
        }
        other => other,
    }
}

/// Why a reference could not be analysed at some parameter values.
enum Fault {
    /// The accelerations there do not vanish.
    NotEquilibrium { accelerations: Vec<f64>, symbols: Vec<SymId> },
    /// The reference is off a kept constraint.
    OffConstraint { constraint: usize, value: f64 },
    /// The mass matrix (projected onto the constraints' null space) is singular there.
    SingularMass { condition: f64 },
    /// A value is NaN or infinite.
    NotFinite(&'static str),
    /// The kept constraints leave no small motion.
    NoMotion,
    /// The kept constraints do not fix the dependent rates at the reference (or the given
    /// rates break them).
    DependentRates { residual: f64 },
}

impl Fault {
    fn diagnostic(&self, prepared: &Prepared, span: Span, at: &str) -> Diagnostic {
        let d = &prepared.derivation;
        let pool = &d.model.pool;
        match self {
            Fault::NotEquilibrium { accelerations, symbols } => {
                let listed: Vec<String> = symbols
                    .iter()
                    .zip(accelerations)
                    .map(|(a, v)| format!("{} = {}", pool.symbol_text(*a, Style::Unicode), v))
                    .collect();
                Diagnostic::error(
                    span,
                    format!("this reference is not an equilibrium or a steady motion{at}"),
                )
                .with_label(format!("the accelerations here: {}", listed.join(", ")))
                .with_hint(
                    "at a reference the accelerations vanish: choose positions (and rates of \
                     cyclic coordinates) where M⁻¹·f is zero",
                )
            }
            Fault::OffConstraint { constraint, value } => {
                let c = &d.model.constraints[*constraint];
                Diagnostic::error(
                    span,
                    format!("this reference is not on the constraint `{}`{at}", c.name),
                )
                .with_label(format!("Φ = {value} here"))
                .with_related(c.span, "the constraint")
                .with_hint("give positions that satisfy every constraint kept with a multiplier")
            }
            Fault::SingularMass { condition } => Diagnostic::error(
                span,
                format!("the mass matrix is singular at this reference{at}"),
            )
            .with_label(if condition.is_finite() {
                format!("condition number ≈ {condition:.1e}")
            } else {
                "exactly singular".to_string()
            })
            .with_hint(
                "the coordinates are singular here (Euler angles at gimbal lock, say): choose \
                 coordinates that are regular at the reference",
            ),
            Fault::NoMotion => Diagnostic::error(
                span,
                format!("the constraints leave no small motion about this reference{at}"),
            )
            .with_label("every δq here breaks a constraint")
            .with_hint("a reference needs room to move: fewer constraints than coordinates"),
            Fault::DependentRates { residual } => Diagnostic::error(
                span,
                format!("the kept constraints do not fix the dependent rates here{at}"),
            )
            .with_label(if residual.is_finite() {
                format!("their rows are singular or inconsistent (residual {residual:.1e})")
            } else {
                "their rows are singular here".to_string()
            })
            .with_hint(
                "give the independent rates of the steady motion in the reference (the \
                 constraints give the others), and positions where the constraints restrain \
                 independent directions",
            ),
            Fault::NotFinite(what) => Diagnostic::error(
                span,
                format!("{what} is not a finite number at this reference{at}"),
            )
            .with_label("NaN or infinite here")
            .with_hint("a division by zero or a function outside its domain at the reference"),
        }
    }
}

/// The lowered matrices of a linearization, ready for any parameter values.
struct Analysis {
    tape: Tape,
    n: usize,
    /// Kept constraints.
    k: usize,
    /// Parameters then multipliers: the tape's inputs.
    inputs: Vec<SymId>,
    residual: ScaledEvaluator,
    phi: ScaledEvaluator,
    symbol_count: usize,
    cyclic: Vec<bool>,
    /// The derivation's acceleration symbols, for what a fault reports.
    accels: Vec<SymId>,
    /// With velocity constraints kept: the independent rates' count and the positions kept.
    rates: Option<(usize, usize)>,
    /// With position and velocity constraints kept together: the dependent rates' count.
    kept: Option<usize>,
}

impl Analysis {
    fn new(prepared: &mut Prepared, lin: &Linearization) -> Result<Analysis, Error> {
        let n = lin.coords.len();
        let mut outputs: Vec<ExprId> = Vec::new();
        for m in [&lin.mass, &lin.damping, &lin.stiffness] {
            outputs.extend(m.iter().flatten());
        }
        outputs.extend(&lin.residual);
        if let Some(r) = &lin.independent {
            outputs.extend(r.kinematics.iter().flatten());
        }
        for c in &lin.constraints {
            outputs.extend(&c.jacobian);
            outputs.push(c.bias);
            if lin.kept.is_some() {
                outputs.extend(c.rate_row);
                outputs.extend(&c.positions);
            }
        }
        let mut inputs = prepared.parameters.clone();
        inputs.extend(lin.constraints.iter().map(|c| c.lambda));
        if let Some(kept) = &lin.kept {
            inputs.extend(kept.dependent.iter().map(|&i| prepared.derivation.rates[i]));
        }
        let tape = Tape::new(prepared.lower(&inputs, &outputs)?);
        let pool = &prepared.derivation.model.pool;
        let phis: Vec<ExprId> = lin.constraints.iter().map(|c| c.phi).collect();
        Ok(Analysis {
            tape,
            n,
            k: lin.constraints.len(),
            inputs,
            residual: ScaledEvaluator::new(pool, &lin.residual),
            phi: ScaledEvaluator::new(pool, &phis),
            symbol_count: pool.symbol_count(),
            cyclic: lin.cyclic.clone(),
            accels: prepared.derivation.accels.clone(),
            rates: lin.independent.as_ref().map(|r| (r.rates.len(), r.kept.len())),
            kept: lin.kept.as_ref().map(|k| k.dependent.len()),
        })
    }

    /// The names of the state: positions kept (coordinates, or z1… along the constraints'
    /// null space, then cyclic coordinates), then their rates.
    fn state_names(&self, prepared: &Prepared, lin: &Linearization, at: &Numbers) -> Vec<String> {
        let pool = &prepared.derivation.model.pool;
        let name = |i: usize| pool.symbol(lin.coords[i]).name.clone();
        let (positions, rates): (Vec<String>, Vec<String>) = if let Some((p, u)) = &at.reduced {
            (
                p.iter().map(|&i| name(i)).collect(),
                u.iter().map(|&i| format!("{}'", name(i))).collect(),
            )
        } else if let Some(r) = &lin.independent {
            let coord = |u: &SymId| {
                let rates = &prepared.derivation.rates;
                rates.iter().position(|v| v == u).map_or_else(String::new, name)
            };
            let positions = r.kept.iter().map(|&i| name(i)).collect();
            (positions, r.rates.iter().map(|u| format!("{}'", coord(u))).collect())
        } else if self.k == 0 {
            let positions = (0..self.n).filter(|&i| !self.cyclic[i]).map(name).collect();
            (positions, (0..self.n).map(|i| format!("{}'", name(i))).collect())
        } else {
            // The null space's dimension at the reference: n minus the constraints' rank there.
            let columns = at.basis.as_ref().and_then(|b| b.first()).map_or(0, Vec::len);
            let reduced = columns.saturating_sub(self.cyclic.iter().filter(|c| **c).count());
            let z: Vec<String> = (1..=reduced).map(|j| format!("z{j}")).collect();
            let cyclic: Vec<String> = (0..self.n).filter(|&i| self.cyclic[i]).map(name).collect();
            let rates = z.iter().chain(&cyclic).map(|s| format!("{s}'")).collect();
            (z, rates)
        };
        positions.into_iter().chain(rates).collect()
    }

    fn eval(&mut self, parameters: &[f64], multipliers: &[f64]) -> Vec<f64> {
        let mut input = parameters.to_vec();
        input.extend(multipliers);
        input.resize(self.inputs.len(), 0.0);
        let mut out = vec![0.0; self.tape.outputs()];
        self.tape.eval(&input, &mut out);
        out
    }

    /// Values by symbol, for the scaled evaluators.
    fn by_symbol(&self, parameters: &[f64], multipliers: &[f64]) -> Vec<f64> {
        let mut values = vec![f64::NAN; self.symbol_count];
        for (s, v) in self.inputs.iter().zip(parameters.iter().chain(multipliers)) {
            values[s.index()] = *v;
        }
        values
    }

    fn at(&mut self, lin: &Linearization, parameters: &[f64]) -> Result<Numbers, Fault> {
        if let Some((rates, kept)) = self.rates {
            return self.at_rates(lin, parameters, rates, kept);
        }
        if self.kept.is_some() {
            return self.at_kept(lin, parameters);
        }
        let (n, k) = (self.n, self.k);
        let square = |out: &[f64], block: usize| -> DMatrix<f64> {
            DMatrix::from_fn(n, n, |j, i| out[block * n * n + j * n + i])
        };
        let out = self.eval(parameters, &vec![0.0; k]);
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Fault::NotFinite("M, C, K or f"));
        }
        let mass = square(&out, 0);
        let forcing = DVector::from_fn(n, |j, _| out[3 * n * n + j]);
        let base = 3 * n * n + n;
        let jacobian = DMatrix::from_fn(k, n, |c, i| out[base + c * (n + 1) + i]);
        let bias = DVector::from_fn(k, |c, _| out[base + c * (n + 1) + n]);

        // On each kept constraint, then the accelerations (and the multipliers) there.
        let values = self.by_symbol(parameters, &vec![0.0; k]);
        for (c, (phi, size)) in self.phi.eval(&values).into_iter().enumerate() {
            // NaN is off the constraint too.
            let on = phi.abs() <= EQUILIBRIUM_TOLERANCE * size;
            if !on {
                let constraint = lin.constraints[c].constraint;
                return Err(Fault::OffConstraint { constraint, value: phi });
            }
        }
        let (accelerations, multipliers) = if k == 0 {
            let lu = mass.clone().lu();
            let a = lu.solve(&forcing).unwrap_or_else(|| DVector::from_element(n, f64::NAN));
            (a, DVector::zeros(0))
        } else {
            accelerations_and_multipliers(&mass, &jacobian, &forcing, &bias)
        };
        let multipliers: Vec<f64> = multipliers.iter().copied().collect();
        let accelerations: Vec<f64> = accelerations.iter().copied().collect();
        let out = self.eval(parameters, &multipliers);
        let stiffness = square(&out, 2);
        if !lin.residual_is_zero {
            let values = self.by_symbol(parameters, &multipliers);
            let residual = self.residual.eval(&values);
            let held = residual.iter().enumerate().all(|(j, (r, size))| {
                // A shift of the reference by a 1e-3 of what the coordinates are measured in
                // would leave this much: below it, rounding of the reference is all there is.
                let floor = 1e-3 * stiffness.row(j).iter().map(|x| x.abs()).sum::<f64>();
                r.abs() <= EQUILIBRIUM_TOLERANCE * size.max(floor)
            });
            if !held || accelerations.iter().any(|a| !a.is_finite()) {
                return Err(Fault::NotEquilibrium { accelerations, symbols: self.accels.clone() });
            }
        }
        let damping = square(&out, 1);

        // The reduced coordinates: the constraints' null space over the non-cyclic
        // coordinates, then each cyclic coordinate as it is.
        let kept: Vec<usize> = (0..n).filter(|&i| !self.cyclic[i]).collect();
        let cyclic: Vec<usize> = (0..n).filter(|&i| self.cyclic[i]).collect();
        let basis = if k == 0 {
            DMatrix::identity(n, n)
        } else {
            let restricted = DMatrix::from_fn(k, kept.len(), |c, i| jacobian[(c, kept[i])]);
            let null =
                null_space(restricted).ok_or(Fault::NotFinite("the constraints' Jacobian"))?;
            let r = null.ncols() + cyclic.len();
            let mut basis = DMatrix::zeros(n, r);
            for (row, &i) in kept.iter().enumerate() {
                for col in 0..null.ncols() {
                    basis[(i, col)] = null[(row, col)];
                }
            }
            for (col, &i) in cyclic.iter().enumerate() {
                basis[(i, null.ncols() + col)] = 1.0;
            }
            basis
        };
        let r = basis.ncols();
        if r == 0 {
            return Err(Fault::NoMotion);
        }
        let reduce = |m: &DMatrix<f64>| basis.transpose() * m * &basis;
        let (mr, cr, kr) = (reduce(&mass), reduce(&damping), reduce(&stiffness));
        // Which reduced coordinates keep their position in the state: all but the cyclic.
        let positions: Vec<usize> =
            if k == 0 { kept.clone() } else { (0..r - cyclic.len()).collect() };

        let svd = nalgebra::SVD::try_new(mr.clone(), false, false, f64::EPSILON, MAX_ITERATIONS)
            .ok_or(Fault::NotFinite("the mass matrix"))?;
        let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
        let regular = smallest > 1e-12 * largest;
        if !regular {
            return Err(Fault::SingularMass { condition: largest / smallest });
        }
        let lu = mr.lu();
        let p = positions.len();
        let size = p + r;
        let mut a = DMatrix::zeros(size, size);
        for (row, &j) in positions.iter().enumerate() {
            a[(row, p + j)] = 1.0;
        }
        let stiff = DMatrix::from_fn(r, p, |row, col| kr[(row, positions[col])]);
        let lower_left =
            lu.solve(&stiff).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
        let lower_right = lu.solve(&cr).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
        a.view_mut((p, 0), (r, p)).copy_from(&(-lower_left));
        a.view_mut((p, p), (r, r)).copy_from(&(-lower_right));

        let eigenvalues = eigenvalues(&a).ok_or(Fault::NotFinite("the first-order matrix A"))?;
        let (stability, tolerance) = stability(&eigenvalues);
        let first_integrals = 0;
        Ok(Numbers {
            parameters: parameters.to_vec(),
            mass: rows_of(&mass),
            damping: rows_of(&damping),
            stiffness: rows_of(&stiffness),
            multipliers,
            accelerations,
            basis: (k > 0).then(|| rows_of(&basis)),
            kinematics: None,
            reduced: None,
            dependent_rates: Vec::new(),
            a: rows_of(&a),
            eigenvalues,
            stability,
            tolerance,
            first_integrals,
        })
    }
    /// With velocity constraints kept: M̃·δu̇ + C̃·δu + K̃·δp = 0 and δṗ = G·(δp, δu), so
    /// that, with the state (δp, δu), A = [G; −M̃⁻¹·(K̃, C̃)].
    fn at_rates(
        &mut self,
        lin: &Linearization,
        parameters: &[f64],
        nu: usize,
        np: usize,
    ) -> Result<Numbers, Fault> {
        let out = self.eval(parameters, &[]);
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Fault::NotFinite("M̃, C̃, K̃, the kinematics or the residual"));
        }
        let mut offset = 0;
        let mut block = |rows: usize, columns: usize| {
            let m = DMatrix::from_fn(rows, columns, |j, i| out[offset + j * columns + i]);
            offset += rows * columns;
            m
        };
        let mass = block(nu, nu);
        let damping = block(nu, nu);
        let stiffness = block(nu, np);
        let residual_values = block(lin.residual.len(), 1);
        let kinematics = block(np, np + nu);

        let svd = nalgebra::SVD::try_new(mass.clone(), false, false, f64::EPSILON, MAX_ITERATIONS)
            .ok_or(Fault::NotFinite("the mass matrix"))?;
        let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
        if nu > 0 && smallest <= 1e-12 * largest {
            return Err(Fault::SingularMass { condition: largest / smallest });
        }
        let lu = mass.clone().lu();
        let h = DVector::from_fn(nu, |j, _| residual_values[(j, 0)]);
        let solved = lu.solve(&h).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
        let mut accelerations: Vec<f64> = solved.iter().map(|a| -a).collect();
        accelerations.extend((nu..lin.residual.len()).map(|j| residual_values[(j, 0)]));
        let symbols =
            lin.independent.as_ref().map_or_else(Vec::new, |r| r.residual_symbols.clone());
        if !lin.residual_is_zero {
            let values = self.by_symbol(parameters, &[]);
            let residual = self.residual.eval(&values);
            let held = residual.iter().enumerate().all(|(j, (r, size))| {
                // As for M·q̈ = f: a shift of the reference by 1e-3 leaves this much.
                let row: f64 = if j < nu {
                    stiffness.row(j).iter().map(|x| x.abs()).sum()
                } else {
                    kinematics.row(j - nu).iter().map(|x| x.abs()).sum()
                };
                r.abs() <= EQUILIBRIUM_TOLERANCE * size.max(1e-3 * row)
            });
            if !held || accelerations.iter().any(|a| !a.is_finite()) {
                return Err(Fault::NotEquilibrium { accelerations, symbols });
            }
        }

        let size = np + nu;
        let mut a = DMatrix::zeros(size, size);
        a.view_mut((0, 0), (np, size)).copy_from(&kinematics);
        let mut forces = DMatrix::zeros(nu, size);
        forces.view_mut((0, 0), (nu, np)).copy_from(&stiffness);
        forces.view_mut((0, np), (nu, nu)).copy_from(&damping);
        let lower = lu.solve(&forces).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
        a.view_mut((np, 0), (nu, size)).copy_from(&(-lower));
        if size == 0 {
            return Err(Fault::NoMotion);
        }

        let (eigenvalues, first_integrals) =
            deflated_eigenvalues(&a).ok_or(Fault::NotFinite("the first-order matrix A"))?;
        let (stability, tolerance) = stability_apart(&eigenvalues, first_integrals);
        Ok(Numbers {
            parameters: parameters.to_vec(),
            mass: rows_of(&mass),
            damping: rows_of(&damping),
            stiffness: rows_of(&stiffness),
            multipliers: Vec::new(),
            accelerations,
            basis: None,
            kinematics: Some(rows_of(&kinematics)),
            reduced: None,
            dependent_rates: Vec::new(),
            a: rows_of(&a),
            eigenvalues,
            stability,
            tolerance,
            first_integrals,
        })
    }
}

impl Analysis {
    /// With position and velocity constraints kept together. The dependent rates at the
    /// reference come first, from the constraints at the velocity level; then q̈ and the
    /// multipliers there, as for position constraints alone. Then the reduction, all in
    /// numbers: the position constraints give δq = N·δz (one dependent coordinate per row,
    /// the rest of z the coordinates themselves), the velocity constraints A·δq̇ + B·δq = 0
    /// give δż = T·δu + S·δz (u the independent rates, again coordinates' own), and the
    /// equations of motion along Q = N·T, where the multipliers cancel:
    ///
    /// M̃ = QᵀMQ, C̃ = Qᵀ(M·N·S·T + C·Q), K̃ = Qᵀ(M·N·S·S + C·N·S + K·N),
    ///
    /// M̃·δu̇ + C̃·δu + K̃·δz = 0. Positions that neither K̃ nor the rates of the positions kept
    /// depend on leave the state (ignorable); first integrals leave the eigenvalues as zeros.
    fn at_kept(&mut self, lin: &Linearization, parameters: &[f64]) -> Result<Numbers, Fault> {
        let kept = lin.kept.as_ref().expect("a kept linearization");
        let (n, k) = (self.n, self.k);
        let dependent = &kept.dependent;
        let nd = dependent.len();
        let square = |out: &[f64], block: usize| -> DMatrix<f64> {
            DMatrix::from_fn(n, n, |j, i| out[block * n * n + j * n + i])
        };
        // Each constraint's outputs: J (n), γ, the rate row, B (n for a velocity constraint).
        let mut offsets = Vec::with_capacity(k);
        let mut offset = 3 * n * n + n;
        for c in &lin.constraints {
            offsets.push(offset);
            offset += n + 2 + c.positions.len();
        }
        let rows = |out: &[f64]| -> (DMatrix<f64>, DVector<f64>, DVector<f64>) {
            let jacobian = DMatrix::from_fn(k, n, |c, i| out[offsets[c] + i]);
            let bias = DVector::from_fn(k, |c, _| out[offsets[c] + n]);
            let rate_rows = DVector::from_fn(k, |c, _| out[offsets[c] + n + 1]);
            (jacobian, bias, rate_rows)
        };
        let inputs = |multipliers: &[f64], rates: &[f64]| -> Vec<f64> {
            multipliers.iter().chain(rates).copied().collect()
        };

        // On each kept position constraint.
        let values = self.by_symbol(parameters, &vec![0.0; k + nd]);
        for (c, (phi, size)) in self.phi.eval(&values).into_iter().enumerate() {
            if lin.constraints[c].kind != model::ConstraintKind::Position {
                continue;
            }
            if phi.abs() > EQUILIBRIUM_TOLERANCE * size || !phi.is_finite() {
                let constraint = lin.constraints[c].constraint;
                return Err(Fault::OffConstraint { constraint, value: phi });
            }
        }
        // The dependent rates: J[:, dependent]·r = −(the rows with them at 0).
        let out = self.eval(parameters, &inputs(&vec![0.0; k], &vec![0.0; nd]));
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Fault::NotFinite("M, C, K, f or a constraint's rows"));
        }
        let (jacobian, _, rate_rows) = rows(&out);
        let restrained = DMatrix::from_fn(k, nd, |c, d| jacobian[(c, dependent[d])]);
        let rhs = -&rate_rows;
        let solved = least_squares(restrained.clone(), &rhs)
            .ok_or(Fault::DependentRates { residual: f64::NAN })?;
        let miss = (&restrained * &solved - &rhs).amax();
        let scale = restrained.amax() * solved.amax() + rhs.amax();
        if miss > EQUILIBRIUM_TOLERANCE * scale.max(f64::MIN_POSITIVE) {
            return Err(Fault::DependentRates { residual: miss });
        }
        let rates: Vec<f64> = solved.iter().copied().collect();

        // q̈ and the multipliers: M·q̈ − Jᵀ·λ = f, J·q̈ = γ.
        let out = self.eval(parameters, &inputs(&vec![0.0; k], &rates));
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Fault::NotFinite("M, C, K, f or a constraint's rows"));
        }
        let mass = square(&out, 0);
        let forcing = DVector::from_fn(n, |j, _| out[3 * n * n + j]);
        let (jacobian, bias, _) = rows(&out);
        let (accelerations, multipliers) =
            accelerations_and_multipliers(&mass, &jacobian, &forcing, &bias);
        let accelerations: Vec<f64> = accelerations.iter().copied().collect();
        let multipliers: Vec<f64> = multipliers.iter().copied().collect();
        let out = self.eval(parameters, &inputs(&multipliers, &rates));
        let stiffness = square(&out, 2);
        let damping = square(&out, 1);
        let values = self.by_symbol(parameters, &inputs(&multipliers, &rates));
        let residual = self.residual.eval(&values);
        // Relative to the largest force in any row, f's or a reaction's: rows that vanish by
        // symmetry have no size of their own, and an expression too large to simplify hides
        // its terms inside products.
        let reactions =
            |j: usize| -> f64 { (0..k).map(|c| (jacobian[(c, j)] * multipliers[c]).abs()).sum() };
        let scale =
            (0..n).map(|j| residual[j].1.max(forcing[j].abs() + reactions(j))).fold(0.0, f64::max);
        let held = residual.iter().all(|(r, _)| r.abs() <= EQUILIBRIUM_TOLERANCE * scale);
        if !held || accelerations.iter().any(|a| !a.is_finite()) {
            return Err(Fault::NotEquilibrium { accelerations, symbols: self.accels.clone() });
        }

        // δq = N·δz along the position constraints.
        let position_rows: Vec<usize> = (0..k)
            .filter(|&c| lin.constraints[c].kind == model::ConstraintKind::Position)
            .collect();
        let velocity_rows: Vec<usize> = (0..k)
            .filter(|&c| lin.constraints[c].kind == model::ConstraintKind::Velocity)
            .collect();
        let preferred = |i: usize| dependent.contains(&i);
        let p_rows =
            DMatrix::from_fn(position_rows.len(), n, |r, i| jacobian[(position_rows[r], i)]);
        let eliminated = pivots(&p_rows, &preferred);
        let z: Vec<usize> = (0..n).filter(|i| !eliminated.contains(i)).collect();
        let nz = z.len();
        let mut basis = DMatrix::zeros(n, nz);
        for (col, &i) in z.iter().enumerate() {
            basis[(i, col)] = 1.0;
        }
        if !eliminated.is_empty() {
            let dep = DMatrix::from_fn(p_rows.nrows(), eliminated.len(), |r, d| {
                p_rows[(r, eliminated[d])]
            });
            let ind = DMatrix::from_fn(p_rows.nrows(), nz, |r, c| p_rows[(r, z[c])]);
            let x = least_squares_matrix(dep, &(-ind)).ok_or(Fault::NoMotion)?;
            for (d, &i) in eliminated.iter().enumerate() {
                for c in 0..nz {
                    basis[(i, c)] = x[(d, c)];
                }
            }
        }
        // δż = T·δu + S·δz along the velocity constraints.
        let a_rows =
            DMatrix::from_fn(velocity_rows.len(), n, |r, i| jacobian[(velocity_rows[r], i)]);
        let b_rows = DMatrix::from_fn(velocity_rows.len(), n, |r, i| {
            out[offsets[velocity_rows[r]] + n + 2 + i]
        });
        let an = &a_rows * &basis;
        let bn = &b_rows * &basis;
        let z_preferred = |c: usize| preferred(z[c]);
        let dependent_z = pivots(&an, &z_preferred);
        let independent_z: Vec<usize> = (0..nz).filter(|c| !dependent_z.contains(c)).collect();
        let nu = independent_z.len();
        let mut t = DMatrix::zeros(nz, nu);
        let mut s = DMatrix::zeros(nz, nz);
        for (col, &c) in independent_z.iter().enumerate() {
            t[(c, col)] = 1.0;
        }
        if !dependent_z.is_empty() {
            let dep =
                DMatrix::from_fn(an.nrows(), dependent_z.len(), |r, d| an[(r, dependent_z[d])]);
            let ind = DMatrix::from_fn(an.nrows(), nu, |r, c| an[(r, independent_z[c])]);
            let x_t = least_squares_matrix(dep.clone(), &(-ind))
                .ok_or(Fault::DependentRates { residual: f64::NAN })?;
            let x_s = least_squares_matrix(dep, &(-&bn))
                .ok_or(Fault::DependentRates { residual: f64::NAN })?;
            for (d, &c) in dependent_z.iter().enumerate() {
                for col in 0..nu {
                    t[(c, col)] = x_t[(d, col)];
                }
                for col in 0..nz {
                    s[(c, col)] = x_s[(d, col)];
                }
            }
        }
        let q = &basis * &t;
        let ns = &basis * &s;
        let m_reduced = q.transpose() * &mass * &q;
        let c_reduced = q.transpose() * (&mass * &ns * &t + &damping * &q);
        let k_reduced = q.transpose() * (&mass * &ns * &s + &damping * &ns + &stiffness * &basis);

        // The positions kept: those K̃ depends on, and those the rates of kept ones depend on.
        let k_tol = 1e-9 * k_reduced.amax();
        let s_tol = 1e-9 * s.amax().max(t.amax());
        let mut keep: Vec<bool> = (0..nz).map(|c| k_reduced.column(c).amax() > k_tol).collect();
        loop {
            let mut grew = false;
            for i in 0..nz {
                if !keep[i] {
                    continue;
                }
                for j in 0..nz {
                    if !keep[j] && s[(i, j)].abs() > s_tol {
                        keep[j] = true;
                        grew = true;
                    }
                }
            }
            if !grew {
                break;
            }
        }
        let kept_z: Vec<usize> = (0..nz).filter(|&c| keep[c]).collect();
        let np = kept_z.len();
        let size = np + nu;
        if size == 0 || nu == 0 {
            return Err(Fault::NoMotion);
        }
        let svd =
            nalgebra::SVD::try_new(m_reduced.clone(), false, false, f64::EPSILON, MAX_ITERATIONS)
                .ok_or(Fault::NotFinite("the mass matrix"))?;
        let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
        if smallest <= 1e-12 * largest {
            return Err(Fault::SingularMass { condition: largest / smallest });
        }
        let lu = m_reduced.clone().lu();
        let k_kept = DMatrix::from_fn(nu, np, |r, c| k_reduced[(r, kept_z[c])]);
        let mut kinematics = DMatrix::zeros(np, size);
        for (row, &i) in kept_z.iter().enumerate() {
            for (col, &j) in kept_z.iter().enumerate() {
                kinematics[(row, col)] = s[(i, j)];
            }
            for col in 0..nu {
                kinematics[(row, np + col)] = t[(i, col)];
            }
        }
        let mut forces = DMatrix::zeros(nu, size);
        forces.view_mut((0, 0), (nu, np)).copy_from(&k_kept);
        forces.view_mut((0, np), (nu, nu)).copy_from(&c_reduced);
        let lower = lu.solve(&forces).ok_or(Fault::SingularMass { condition: f64::INFINITY })?;
        let mut a = DMatrix::zeros(size, size);
        a.view_mut((0, 0), (np, size)).copy_from(&kinematics);
        a.view_mut((np, 0), (nu, size)).copy_from(&(-lower));

        let (eigenvalues, first_integrals) =
            deflated_eigenvalues(&a).ok_or(Fault::NotFinite("the first-order matrix A"))?;
        let (stability, tolerance) = stability_apart(&eigenvalues, first_integrals);
        let positions: Vec<usize> = kept_z.iter().map(|&c| z[c]).collect();
        let independent: Vec<usize> = independent_z.iter().map(|&c| z[c]).collect();
        Ok(Numbers {
            parameters: parameters.to_vec(),
            mass: rows_of(&m_reduced),
            damping: rows_of(&c_reduced),
            stiffness: rows_of(&k_kept),
            multipliers,
            accelerations,
            basis: None,
            kinematics: Some(rows_of(&kinematics)),
            reduced: Some((positions, independent)),
            dependent_rates: rates,
            a: rows_of(&a),
            eigenvalues,
            stability,
            tolerance,
            first_integrals,
        })
    }
}

/// One pivot column per row of `m` (rows that are combinations of earlier ones get none):
/// Gaussian elimination choosing, in each row, among the columns clearly away from zero, a
/// preferred one if there is one, the largest otherwise.
fn pivots(m: &DMatrix<f64>, preferred: &dyn Fn(usize) -> bool) -> Vec<usize> {
    let columns: Vec<usize> = (0..m.ncols()).collect();
    let mut work = m.clone();
    let scale = work.amax();
    let mut chosen: Vec<usize> = Vec::new();
    for r in 0..work.nrows() {
        let row_max = columns.iter().map(|&c| work[(r, c)].abs()).fold(0.0, f64::max);
        if row_max <= 1e-10 * scale {
            continue;
        }
        let clear = |c: &usize| !chosen.contains(c) && work[(r, *c)].abs() > 1e-3 * row_max;
        let best = |cs: Vec<usize>| {
            cs.into_iter().max_by(|a, b| work[(r, *a)].abs().total_cmp(&work[(r, *b)].abs()))
        };
        let pick = best(columns.iter().copied().filter(|c| clear(c) && preferred(*c)).collect())
            .or_else(|| best(columns.iter().copied().filter(|c| clear(c)).collect()));
        let Some(p) = pick else { continue };
        // Eliminate the pivot column from the rows below.
        for below in r + 1..work.nrows() {
            let factor = work[(below, p)] / work[(r, p)];
            if factor != 0.0 {
                for c in 0..work.ncols() {
                    let v = work[(r, c)];
                    work[(below, c)] -= factor * v;
                }
            }
        }
        chosen.push(p);
    }
    chosen
}

/// X of A·X = B column by column in the least-squares sense, of smallest norm where A is
/// rank-deficient.
fn least_squares_matrix(a: DMatrix<f64>, b: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let svd = nalgebra::SVD::try_new(a, true, true, f64::EPSILON, MAX_ITERATIONS)?;
    let eps = 1e-12 * svd.singular_values.max();
    svd.solve(b, eps).ok()
}

/// q̈ and λ of M·q̈ − Jᵀ·λ = f, J·q̈ = γ, by least squares (dependent constraints at the
/// reference are allowed); NaN where the solve fails.
fn accelerations_and_multipliers(
    mass: &DMatrix<f64>,
    jacobian: &DMatrix<f64>,
    forcing: &DVector<f64>,
    bias: &DVector<f64>,
) -> (DVector<f64>, DVector<f64>) {
    let (n, k) = (mass.nrows(), jacobian.nrows());
    let mut system = DMatrix::zeros(n + k, n + k);
    system.view_mut((0, 0), (n, n)).copy_from(mass);
    system.view_mut((0, n), (n, k)).copy_from(&(-jacobian.transpose()));
    system.view_mut((n, 0), (k, n)).copy_from(jacobian);
    let mut rhs = DVector::zeros(n + k);
    rhs.rows_mut(0, n).copy_from(forcing);
    rhs.rows_mut(n, k).copy_from(bias);
    let x = least_squares(system, &rhs).unwrap_or_else(|| DVector::from_element(n + k, f64::NAN));
    (x.rows(0, n).into_owned(), x.rows(n, k).into_owned())
}

/// The least-squares solution of smallest norm, robust to a rank-deficient system (dependent
/// constraints at the reference): [`least_squares_matrix`] of one column.
fn least_squares(a: DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let column = DMatrix::from_column_slice(b.len(), 1, b.as_slice());
    least_squares_matrix(a, &column).map(|x| x.column(0).into_owned())
}

/// An orthonormal basis of the null space of a k×n matrix, as the columns of an n×r matrix.
fn null_space(j: DMatrix<f64>) -> Option<DMatrix<f64>> {
    null_space_within(j, 1e-10)
}

/// The null space of the singular values below `relative` × the largest.
fn null_space_within(j: DMatrix<f64>, relative: f64) -> Option<DMatrix<f64>> {
    let (k, n) = j.shape();
    // Padded to square, so that the SVD gives every right singular vector, not only k.
    let mut square = DMatrix::zeros(n.max(k), n);
    square.view_mut((0, 0), (k, n)).copy_from(&j);
    let svd = nalgebra::SVD::try_new(square, false, true, f64::EPSILON, MAX_ITERATIONS)?;
    let v_t = svd.v_t?;
    let largest = svd.singular_values.max();
    let columns: Vec<DVector<f64>> = (0..svd.singular_values.len())
        .filter(|&i| svd.singular_values[i] <= relative * largest)
        .map(|i| v_t.row(i).transpose())
        .collect();
    Some(if columns.is_empty() { DMatrix::zeros(n, 0) } else { DMatrix::from_columns(&columns) })
}

/// The eigenvalues of A as (re, im), by real part from the largest down (those within the
/// verdict's tolerance of zero as zero), then by imaginary part; `None` when the iteration
/// does not converge.
fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<(f64, f64)>> {
    if a.is_empty() {
        return Some(Vec::new());
    }
    if a.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let schur = nalgebra::Schur::try_new(a.clone(), f64::EPSILON, MAX_ITERATIONS)?;
    let mut out: Vec<(f64, f64)> =
        schur.complex_eigenvalues().iter().map(|z| (z.re, z.im)).collect();
    // Real parts within the verdict's tolerance of zero sort as zero, so that rounding does not
    // shuffle the eigenvalues of an undamped system from one value of a sweep to the next.
    let (_, tolerance) = stability(&out);
    let key = |re: f64| if re.abs() <= tolerance { 0.0 } else { re };
    out.sort_by(|x, y| key(y.0).total_cmp(&key(x.0)).then(y.1.total_cmp(&x.1)));
    Some(out)
}

/// The eigenvalues of A with its first integrals taken out first: each ℓ with ℓᵀ·A = 0 (a
/// conserved combination of the state, as the rates of ignorable coordinates give) is an
/// eigenvalue 0, and A maps everything into ℓ⊥, so that in an orthonormal basis (Q, L) of
/// ℓ⊥ and of the ℓ, A = [QᵀAQ, ·; 0, 0] and the rest are the eigenvalues of QᵀAQ. Without
/// this, where an oscillation's pair meets those zeros (the rolling coin's critical spin) the
/// eigenvalues of a Jordan block of order three move by the cube root of the rounding, far
/// above the verdict's tolerance.
fn deflated_eigenvalues(a: &DMatrix<f64>) -> Option<(Vec<(f64, f64)>, usize)> {
    let size = a.nrows();
    if size == 0 || a.iter().any(|x| !x.is_finite()) {
        return eigenvalues(a).map(|v| (v, 0));
    }
    // A first integral's row of A is zero up to rounding; a tighter threshold than for
    // constraints keeps an eigenvalue merely passing through zero (the bicycle's capsize mode
    // at its critical speed) out of the first integrals.
    let conserved = null_space_within(a.transpose(), 1e-13)?;
    let c = conserved.ncols();
    if c == 0 || a.amax() == 0.0 {
        return eigenvalues(a).map(|v| (v, 0));
    }
    // Q: an orthonormal basis of the complement, from the null space of the ℓᵀ.
    let q = null_space(conserved.transpose())?;
    if q.ncols() + c != size {
        return eigenvalues(a).map(|v| (v, 0));
    }
    let reduced = q.transpose() * a * &q;
    let mut values = eigenvalues(&reduced)?;
    values.extend(std::iter::repeat_n((0.0, 0.0), c));
    let (_, tolerance) = stability(&values);
    let key = |re: f64| if re.abs() <= tolerance { 0.0 } else { re };
    values.sort_by(|x, y| key(y.0).total_cmp(&key(x.0)).then(y.1.total_cmp(&x.1)));
    Some((values, c))
}

/// The verdict on the eigenvalues apart from `first_integrals` of their exact zeros (each
/// first integral's direction leads to a neighbouring steady motion, not away from this one:
/// the bicycle's forward speed, the sleigh's), and the tolerance it used.
fn stability_apart(eigenvalues: &[(f64, f64)], first_integrals: usize) -> (Stability, f64) {
    let scale = eigenvalues.iter().map(|(re, im)| (re * re + im * im).sqrt()).fold(0.0, f64::max);
    let tolerance = RELATIVE_TOLERANCE * scale;
    let rest = apart_from_first_integrals(eigenvalues, first_integrals);
    let verdict = if rest.iter().any(|(re, _)| *re > tolerance) {
        Stability::Unstable
    } else if !rest.is_empty() && rest.iter().all(|(re, _)| *re < -tolerance) {
        Stability::Stable
    } else {
        Stability::MarginallyStable
    };
    (verdict, tolerance)
}

/// The eigenvalues without `first_integrals` of their exact zeros (the deflated ones).
fn apart_from_first_integrals(
    eigenvalues: &[(f64, f64)],
    first_integrals: usize,
) -> Vec<(f64, f64)> {
    let mut skip = first_integrals;
    eigenvalues
        .iter()
        .filter(|z| {
            let drop = skip > 0 && **z == (0.0, 0.0);
            skip -= usize::from(drop);
            !drop
        })
        .copied()
        .collect()
}

/// The largest real part among the eigenvalues apart from the first integrals' zeros.
fn largest_real_part(numbers: &Numbers) -> f64 {
    apart_from_first_integrals(&numbers.eigenvalues, numbers.first_integrals)
        .iter()
        .map(|z| z.0)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The verdict on all the eigenvalues and the absolute tolerance it used.
fn stability(eigenvalues: &[(f64, f64)]) -> (Stability, f64) {
    stability_apart(eigenvalues, 0)
}

/// The reference as the scene's terms: each coordinate's position (where it has one) and rate.
pub fn reference(lin: &Linearization) -> Vec<(SymId, bool, ExprId)> {
    let mut out = Vec::new();
    for (i, q) in lin.coords.iter().enumerate() {
        if let Some(p) = lin.positions[i] {
            out.push((*q, false, p));
        }
    }
    for (i, q) in lin.coords.iter().enumerate() {
        out.push((*q, true, lin.rates[i]));
    }
    out
}

/// A matrix as rows, as `Numbers` keeps them.
fn rows_of(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows()).map(|j| m.row(j).iter().copied().collect()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_real_parts() {
        assert_eq!(stability(&[(-1.0, 2.0), (-1.0, -2.0)]).0, Stability::Stable);
        assert_eq!(stability(&[(0.0, 2.0), (0.0, -2.0)]).0, Stability::MarginallyStable);
        assert_eq!(stability(&[(1e-12, 2.0), (-1e-12, -2.0)]).0, Stability::MarginallyStable);
        assert_eq!(stability(&[(3.0, 0.0), (-3.0, 0.0)]).0, Stability::Unstable);
        assert_eq!(stability(&[(0.0, 0.0)]).0, Stability::MarginallyStable);
    }

    #[test]
    fn sweeps_are_parsed_and_checked() {
        assert_eq!(parse_sweep("w=0:100:11").ok(), Some(("w".to_string(), 0.0, 100.0, 11)));
        assert!(parse_sweep("w=0:100").is_err());
        assert!(parse_sweep("w=1:1:5").is_err());
        assert!(parse_sweep("w=0:1:1").is_err());
        assert!(parse_sweep("w=0:x:3").is_err());
    }

    #[test]
    fn the_null_space_is_orthonormal_and_annihilated() {
        let j = DMatrix::from_row_slice(1, 3, &[1.0, 2.0, 2.0]);
        let n = null_space(j.clone()).expect("converges");
        assert_eq!(n.ncols(), 2);
        assert!((&j * &n).amax() < 1e-14);
        assert!((n.transpose() * &n - DMatrix::identity(2, 2)).amax() < 1e-14);
    }

    #[test]
    fn eigenvalues_are_sorted() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, 0.0]);
        let e = eigenvalues(&a).expect("converges");
        assert_eq!(e.len(), 2);
        assert!((e[0].1 - 2.0).abs() < 1e-14 && (e[1].1 + 2.0).abs() < 1e-14, "{e:?}");
    }
}
