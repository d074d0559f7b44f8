//! An orbit continued in one parameter: found at each value of a grid from the one before
//! (natural-parameter continuation), and the values where a multiplier crosses the unit circle
//! located by bisection: through +1 (a fold, or a branch point: det(C − I) changes sign),
//! through −1 (period doubling: det(C + I) changes sign), or a complex pair through it
//! (Neimark–Sacker). Past a fold the branch turns back and the next value has no orbit near:
//! a fixed period's map then goes on by pseudo-arclength continuation (Keller's: a secant
//! predictor, a corrector on the hyperplane normal to it, the bordered Newton system with the
//! map's Jacobian from the variational run and its derivative in the parameter from the same
//! run's S = ∂x/∂p, or central differences of the map in the parameter alone where S cannot
//! be carried), round the fold and back, until the
//! parameter leaves the range; crossings there are located by bisection along the branch. A
//! section's map stops at the fold and says so.

use engine::input::{Assignment, SweepRange};
use engine::Error;
use nalgebra::{DMatrix, DVector};

use crate::{chart, Options, Orbit, Search};

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
    /// Each value reached and its orbit, in the sweep's order: the grid's values, then, for a
    /// fixed period's map past a fold, the points pseudo-arclength continuation found along
    /// the branch as it turned back (`around` of them, at the end).
    pub points: Vec<(f64, Orbit)>,
    pub around: usize,
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
    let natural = points.len();
    // A fixed period's map continues round the fold by pseudo-arclength: from the last two
    // points, along their secant, each point corrected on the hyperplane normal to it.
    let lo = range.from.min(range.to);
    let hi = range.from.max(range.to);
    let searched = Search::new(source, options)?;
    if lost.is_some() && points.len() >= 2 && searched.is_periodic_in_time() {
        let branch = Branch { source, options, parameter: &range.parameter };
        let mut pair = [
            (points[natural - 2].1.fixed_point.clone(), points[natural - 2].0),
            (points[natural - 1].1.fixed_point.clone(), points[natural - 1].0),
        ];
        let reach = distance(&pair[0], &pair[1]);
        for _ in 0..2 * count {
            let Some(next) = branch.step(&pair[0], &pair[1], reach) else { break };
            let orbit = at(source, options, &range.parameter, next.1)?
                .find_from(&next.0, options.iterations)?;
            points.push((next.1, orbit));
            pair = [pair[1].clone(), next.clone()];
            if next.1 < lo || next.1 > hi {
                break;
            }
        }
        if points.len() > natural {
            lost = None;
        }
    }
    let mut crossings = Vec::new();
    for (k, pair) in points.windows(2).enumerate() {
        let ((a, left), (b, right)) = (&pair[0], &pair[1]);
        for kind in [Crossing::Fold, Crossing::PeriodDoubling, Crossing::Torus] {
            let (Some(fa), Some(fb)) = (test(kind, left), test(kind, right)) else { continue };
            if fa.signum() == fb.signum() {
                continue;
            }
            let located = if k + 1 < natural {
                locate(source, options, &range.parameter, kind, (*a, left), (*b, fb))?
            } else {
                let branch = Branch { source, options, parameter: &range.parameter };
                let ends = ((left.fixed_point.clone(), *a), (right.fixed_point.clone(), *b));
                branch.locate(kind, ends, fb)?
            };
            crossings.push(located);
        }
    }
    let around = points.len() - natural;
    Ok(Sweep { parameter: range.parameter.clone(), points, around, crossings, lost })
}

/// A point of a branch: the fixed point and the parameter.
type Point = (Vec<f64>, f64);

fn distance(a: &Point, b: &Point) -> f64 {
    let dx: f64 = a.0.iter().zip(&b.0).map(|(u, v)| (u - v) * (u - v)).sum();
    (dx + (a.1 - b.1) * (a.1 - b.1)).sqrt()
}

/// The residual F, C − I, ∂F/∂p and the chart at a point.
type Linearized = (DVector<f64>, DMatrix<f64>, DVector<f64>, DMatrix<f64>);

/// Pseudo-arclength continuation of a fixed period's map in one parameter.
struct Branch<'a> {
    source: &'a str,
    options: &'a Options,
    parameter: &'a str,
}

/// The corrector's residual and step, relative, below which a point is on the branch.
const ON_BRANCH: f64 = 1e-10;

impl Branch<'_> {
    /// The map's residual in the chart at (x, p), its Jacobian C − I there, ∂/∂p of the
    /// residual (from S = ∂x/∂p carried by the same variational run where the map allows,
    /// else central differences of the map in p alone) and the chart.
    fn residual(&self, x: &[f64], p: f64) -> Result<Linearized, Error> {
        let mut options = self.options.clone();
        let value = format!("{p}");
        options.run.set.push(Assignment { name: self.parameter.to_string(), value });
        let search = Search::for_sweep(self.source, &options, self.parameter)?;
        let ((gap, monodromy, tangent), exact) = search.evaluate_swept(x)?;
        let f = tangent.transpose() * DVector::from_vec(gap);
        let d = tangent.ncols();
        let c = chart::reduced(&monodromy, &tangent) - DMatrix::identity(d, d);
        if let Some(change) = exact {
            let fp = tangent.transpose() * DVector::from_vec(change);
            return Ok((f, c, fp, tangent));
        }
        let delta = 1e-6 * p.abs().max(1.0);
        let side = |q: f64| -> Result<DVector<f64>, Error> {
            let (gap, _, _) = at(self.source, self.options, self.parameter, q)?.evaluate(x)?;
            Ok(tangent.transpose() * DVector::from_vec(gap))
        };
        let fp = (side(p + delta)? - side(p - delta)?) / (2.0 * delta);
        Ok((f, c, fp, tangent))
    }

    /// From `predictor` onto the branch, on the hyperplane through it normal to `direction`.
    fn correct(&self, predictor: &Point, direction: &Point) -> Option<Point> {
        let (mut x, mut p) = predictor.clone();
        let size = x.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        for _ in 0..20 {
            let (f, c, fp, tangent) = self.residual(&x, p).ok()?;
            let d = tangent.ncols();
            let along = tangent.transpose() * DVector::from_column_slice(&direction.0);
            let mut system = DMatrix::zeros(d + 1, d + 1);
            system.view_mut((0, 0), (d, d)).copy_from(&c);
            system.view_mut((0, d), (d, 1)).copy_from(&fp);
            for j in 0..d {
                system[(d, j)] = along[j];
            }
            system[(d, d)] = direction.1;
            let offset: f64 = x
                .iter()
                .zip(&predictor.0)
                .zip(&direction.0)
                .map(|((a, b), t)| (a - b) * t)
                .sum::<f64>()
                + (p - predictor.1) * direction.1;
            let mut right = DVector::zeros(d + 1);
            for i in 0..d {
                right[i] = -f[i];
            }
            right[d] = -offset;
            let step = system.lu().solve(&right)?;
            let moved = &tangent * step.rows(0, d);
            for (v, m) in x.iter_mut().zip(moved.iter()) {
                *v += m;
            }
            p += step[d];
            if f.amax() <= ON_BRANCH * size && step.amax() <= ON_BRANCH * size.max(p.abs()) {
                return Some((x, p));
            }
        }
        None
    }

    /// The next point after `b` along the secant from `a`, `reach` on, halved while the
    /// corrector fails.
    fn step(&self, a: &Point, b: &Point, reach: f64) -> Option<Point> {
        let length = distance(a, b);
        let direction: Point =
            (b.0.iter().zip(&a.0).map(|(u, v)| (u - v) / length).collect(), (b.1 - a.1) / length);
        let mut step = reach;
        for _ in 0..5 {
            let predictor: Point = (
                b.0.iter().zip(&direction.0).map(|(u, t)| u + step * t).collect(),
                b.1 + step * direction.1,
            );
            if let Some(point) = self.correct(&predictor, &direction) {
                return Some(point);
            }
            step /= 2.0;
        }
        None
    }

    /// Bisection of `kind`'s test function along the secant between two points of the branch,
    /// each trial corrected onto it normal to the secant.
    fn locate(&self, kind: Crossing, (a, b): (Point, Point), fb: f64) -> Result<Located, Error> {
        let length = distance(&a, &b);
        let direction: Point =
            (b.0.iter().zip(&a.0).map(|(u, v)| (u - v) / length).collect(), (b.1 - a.1) / length);
        let (mut lo, mut hi, mut f_hi) = (0.0, 1.0, fb);
        let mut last = None;
        while hi - lo > LOCATED {
            let mid = 0.5 * (lo + hi);
            let predictor: Point = (
                a.0.iter().zip(&b.0).map(|(u, v)| u + mid * (v - u)).collect(),
                a.1 + mid * (b.1 - a.1),
            );
            let Some(point) = self.correct(&predictor, &direction) else { break };
            let orbit = at(self.source, self.options, self.parameter, point.1)?
                .find_from(&point.0, self.options.iterations)?;
            let f_mid = test(kind, &orbit).unwrap_or(f64::NAN);
            if f_mid.signum() == f_hi.signum() {
                (hi, f_hi) = (mid, f_mid);
            } else {
                lo = mid;
            }
            last = Some((point.1, orbit));
        }
        let (at, orbit) = last.ok_or_else(|| {
            Error::Numeric("the branch could not be followed between two of its points".into())
        })?;
        Ok(Located { kind, at, orbit })
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Section;

    const PENDULUM: &str = include_str!("../../../examples/orbits/driven_pendulum.lag");

    fn options(amplitude: &str) -> Options {
        let set = vec![Assignment { name: "A".into(), value: amplitude.into() }];
        Options {
            run: simulation::Options { set, ..Default::default() },
            section: Section::Period("2*pi/w".into()),
            swaps: Vec::new(),
            shifts: Vec::new(),
            ignore: Vec::new(),
            iterations: 30,
        }
    }

    /// The map's derivative in the amplitude and in the frequency, which moves the period
    /// too (dT/dw = −2π/w²), from S against central differences of the map, at a state off
    /// the orbit.
    #[test]
    fn the_maps_derivative_in_its_parameter_is_what_differences_give() {
        let options = options("5");
        let x = [0.9, -1.3];
        for (parameter, p) in [("A", 5.0), ("w", 2.0)] {
            let branch = Branch { source: PENDULUM, options: &options, parameter };
            let (_, _, exact, tangent) = branch.residual(&x, p).expect("the map");
            let search = |q: f64| at(PENDULUM, &options, parameter, q).expect("loads");
            let swept = Search::for_sweep(PENDULUM, &options, parameter).expect("loads");
            assert!(swept.loaded.swept.is_some(), "{parameter} is carried by S");
            // The differences' truncation goes as the step's square: w's off by 1.0e-7 at a
            // step of 1e-4, 9.5e-10 at 1e-5, where the runs' rounding is still below.
            let step = 1e-5 * p;
            let gap = |q: f64| search(q).evaluate(&x).expect("the map").0;
            let (up, down) = (gap(p + step), gap(p - step));
            let differenced: Vec<f64> =
                up.iter().zip(&down).map(|(u, d)| (u - d) / (2.0 * step)).collect();
            let differenced = tangent.transpose() * DVector::from_vec(differenced);
            let worst = (&exact - &differenced).amax() / exact.amax();
            assert!(worst < 1e-7, "∂F/∂{parameter}: {exact} against {differenced}: {worst:.1e}");
        }
    }
}
