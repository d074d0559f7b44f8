//! An orbit continued in one parameter: found at each value of a grid from the one before
//! (natural-parameter continuation), and the values where a multiplier crosses the unit circle
//! located by bisection: through +1 (a fold, or a branch point: det(C − I) changes sign),
//! through −1 (period doubling: det(C + I) changes sign), or a complex pair through it
//! (Neimark–Sacker). Past a fold the branch turns back and the next value has no orbit near
//! (nor has it after too long a step): the sweep stops there and says so (pseudo-arclength,
//! which would follow the branch round a fold, is not built).

use engine::input::{Assignment, SweepRange};
use engine::Error;

use crate::{Options, Orbit, Search};

/// How a multiplier leaves or enters the unit circle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    /// Through +1: a fold (or a branch point).
    Fold,
    /// Through −1: period doubling.
    PeriodDoubling,
    /// A complex pair through the circle: a torus (Neimark–Sacker).
    Torus,
}

impl Crossing {
    pub fn words(self) -> &'static str {
        match self {
            Crossing::Fold => "a multiplier crosses +1 (a fold, or a branch point)",
            Crossing::PeriodDoubling => "a multiplier crosses -1 (period doubling)",
            Crossing::Torus => "a complex pair crosses the unit circle (Neimark-Sacker)",
        }
    }
}

/// A crossing located: its kind, the parameter's value, and the orbit there.
#[derive(Clone, Debug)]
pub struct Located {
    pub kind: Crossing,
    pub at: f64,
    pub orbit: Orbit,
}

/// The orbit along a sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub parameter: String,
    /// Each value reached and its orbit, in the sweep's order.
    pub points: Vec<(f64, Orbit)>,
    pub crossings: Vec<Located>,
    /// Where the sweep stopped short, and why (the orbit lost past a fold, a run's fault).
    pub lost: Option<(f64, String)>,
}

/// Bisection of a crossing stops when the bracket is this small, relative to the parameter.
const LOCATED: f64 = 1e-10;

/// The real test function of a crossing from the multipliers: Π(μ − 1), Π(μ + 1), or the
/// largest modulus of a complex pair less 1 (`None` without a pair).
fn test(kind: Crossing, orbit: &Orbit) -> Option<f64> {
    let product = |shift: f64| {
        let p =
            orbit.multipliers.iter().fold(nalgebra::Complex::new(1.0, 0.0), |p, m| p * (m - shift));
        p.re
    };
    match kind {
        Crossing::Fold => Some(product(1.0)),
        Crossing::PeriodDoubling => Some(product(-1.0)),
        Crossing::Torus => orbit
            .multipliers
            .iter()
            .filter(|m| m.im != 0.0)
            .map(|m| m.norm() - 1.0)
            .reduce(f64::max),
    }
}

/// The search at one value of the parameter.
fn at(source: &str, options: &Options, parameter: &str, value: f64) -> Result<Search, Error> {
    let mut options = options.clone();
    options.run.set.push(Assignment { name: parameter.to_string(), value: format!("{value}") });
    Search::new(source, &options)
}

/// Continues the orbit of `source` over `range`, from the scene's start at the first value.
pub fn sweep(source: &str, options: &Options, range: &SweepRange) -> Result<Sweep, Error> {
    let count = range.values;
    let value = |k: usize| range.from + (range.to - range.from) * k as f64 / (count - 1) as f64;
    let mut points: Vec<(f64, Orbit)> = Vec::new();
    let mut lost = None;
    for k in 0..count {
        let p = value(k);
        let mut search = at(source, options, &range.parameter, p)?;
        let found = match points.last() {
            None => search.find(options.iterations),
            Some((_, previous)) => search.find_from(&previous.fixed_point, options.iterations),
        };
        match found {
            Ok(orbit) => points.push((p, orbit)),
            // The first value's failure is the command's; a later one ends the branch.
            Err(e) if points.is_empty() => return Err(e),
            Err(e) => {
                lost = Some((p, e.to_string().trim_start_matches("error: ").to_string()));
                break;
            }
        }
    }
    let mut crossings = Vec::new();
    for pair in points.windows(2) {
        let ((a, left), (b, right)) = (&pair[0], &pair[1]);
        for kind in [Crossing::Fold, Crossing::PeriodDoubling, Crossing::Torus] {
            let (Some(fa), Some(fb)) = (test(kind, left), test(kind, right)) else { continue };
            if fa.signum() == fb.signum() {
                continue;
            }
            crossings.push(locate(source, options, &range.parameter, kind, (*a, left), (*b, fb))?);
        }
    }
    Ok(Sweep { parameter: range.parameter.clone(), points, crossings, lost })
}

/// Bisection of `kind`'s test function between `a` (its orbit) and `b` (its test's value),
/// each search started from the fixed point at the bracket's end it keeps.
fn locate(
    source: &str,
    options: &Options,
    parameter: &str,
    kind: Crossing,
    (a, left): (f64, &Orbit),
    (b, fb): (f64, f64),
) -> Result<Located, Error> {
    let (mut lo, mut hi, mut f_hi) = (a, b, fb);
    let mut near = left.clone();
    let mut last = left.clone();
    while (hi - lo).abs() > LOCATED * lo.abs().max(hi.abs()).max(1.0) {
        let mid = 0.5 * (lo + hi);
        let orbit = at(source, options, parameter, mid)?
            .find_from(&near.fixed_point, options.iterations)?;
        let f_mid = test(kind, &orbit).unwrap_or(f64::NAN);
        if f_mid.signum() == f_hi.signum() {
            (hi, f_hi) = (mid, f_mid);
        } else {
            lo = mid;
            near = orbit.clone();
        }
        last = orbit;
    }
    Ok(Located { kind, at: 0.5 * (lo + hi), orbit: last })
}
