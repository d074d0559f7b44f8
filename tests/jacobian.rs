//! The exact Jacobians against central differences of the right-hand side, for every example
//! (the bicycle in a test of its own, its derivation being the slowest) at random admissible
//! states (random parameters too): of the first-order system in (q, q̇),
//! constraints kept with multipliers solved with their Baumgarte rows, and of the canonical
//! system in (q, p) the symplectic methods integrate.

use engine::numbers::{prepare, Prepared};
use numeric::Tape;
use sim::{Canonical, Mechanical, Problem};

/// Random admissible states per scene.
const STATES: usize = 5;
/// How far the exact Jacobian may be from central differences, relative (see [`compare`]).
const AGREEMENT: f64 = 1e-7;

/// The largest discrepancy of `problem`'s exact Jacobian at (t, y) from central differences of
/// its right-hand side. Each row is measured against its own size (the largest of its entries,
/// exact or differenced), so that a dropped partial shows in the row it belongs to however
/// small the row is; a row that vanishes but for rounding is measured against the matrix.
fn compare(problem: &mut dyn Problem, t: f64, y: &[f64]) -> Result<f64, String> {
    let d = y.len();
    let mut exact = vec![0.0; d * d];
    let has = problem.jacobian(t, y, &mut exact).map_err(|f| format!("jacobian: {f:?}"))?;
    assert!(has, "the problem was given its partials");
    // Differences are limited by truncation at large steps and by rounding at small ones, the
    // more so where M is ill-conditioned (a top's Euler angles in canonical variables): the
    // best of a few steps is how well differences can tell.
    let mut best = f64::INFINITY;
    for step in [3e-3, 1e-3, 3e-4, 1e-4] {
        let differenced = differences(problem, t, y, step)?;
        let largest = exact.iter().chain(&differenced).fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for i in 0..d {
            let row = i * d..(i + 1) * d;
            let size = exact[row.clone()]
                .iter()
                .chain(&differenced[row.clone()])
                .fold(1e-6 * largest, |m, v| m.max(v.abs()));
            for k in row {
                worst = worst.max((exact[k] - differenced[k]).abs() / size);
            }
        }
        best = best.min(worst);
    }
    Ok(best)
}

/// ∂F/∂y by central differences at two steps, h and h/2 (h = `step` relative to each
/// component), extrapolated (Richardson) so that the truncation error is of order h⁴.
fn differences(
    problem: &mut dyn Problem,
    t: f64,
    y: &[f64],
    step: f64,
) -> Result<Vec<f64>, String> {
    let d = y.len();
    let mut out = vec![0.0; d * d];
    let (mut plus, mut minus) = (vec![0.0; d], vec![0.0; d]);
    let mut shifted = y.to_vec();
    for k in 0..d {
        let h = step * y[k].abs().max(1.0);
        let mut central = |step: f64, column: &mut [f64]| -> Result<(), String> {
            shifted[k] = y[k] + step;
            problem.rhs(t, &shifted, &mut plus).map_err(|f| format!("rhs: {f:?}"))?;
            shifted[k] = y[k] - step;
            problem.rhs(t, &shifted, &mut minus).map_err(|f| format!("rhs: {f:?}"))?;
            shifted[k] = y[k];
            for i in 0..d {
                column[i] = (plus[i] - minus[i]) / (2.0 * step);
            }
            Ok(())
        };
        let (mut wide, mut narrow) = (vec![0.0; d], vec![0.0; d]);
        central(h, &mut wide)?;
        central(h / 2.0, &mut narrow)?;
        for i in 0..d {
            out[i * d + k] = (4.0 * narrow[i] - wide[i]) / 3.0;
        }
    }
    Ok(out)
}

/// The scene's problems at one admissible state (`values`, a value per symbol): the
/// first-order system, and the canonical one where no constraint keeps a multiplier.
struct AtState {
    mechanical: Mechanical,
    canonical: Option<(Canonical, Vec<f64>)>,
    t: f64,
    y: Vec<f64>,
}

fn problems(prepared: &mut Prepared, values: &[f64]) -> AtState {
    let d = &prepared.derivation;
    let parameters: Vec<f64> = prepared.parameters.iter().map(|s| values[s.index()]).collect();
    let y: Vec<f64> = d.coords.iter().chain(&d.rates).map(|s| values[s.index()]).collect();
    let t = values[d.model.time.index()];
    let mechanical = lagrange_tests::mechanical(prepared, &parameters);
    let canonical = (prepared.layout.multipliers == 0).then(|| {
        let lower = |prepared: &Prepared, exprs: &[cas::ExprId]| {
            Tape::new(prepared.lower(&prepared.dynamics_inputs(), exprs).expect("lowers"))
        };
        let exprs = prepared.momentum_exprs();
        let momentum = lower(prepared, &exprs);
        let exprs = prepared.canonical_partials_exprs();
        let partials = lower(prepared, &exprs);
        let inner = lagrange_tests::mechanical(prepared, &parameters);
        let mut canonical = Canonical::new(inner, momentum).with_partials(partials);
        let z = canonical.from_physical(t, &y);
        (canonical, z)
    });
    AtState { mechanical, canonical, t, y }
}

/// Per scene: the worst agreement of each problem, and how many states were compared.
#[derive(Default)]
struct Tally {
    kept: usize,
    free: usize,
    canonical: usize,
    /// The worst agreement seen.
    worst: f64,
    failures: Vec<String>,
}

fn check_scene(rel: &str, source: &str, tally: &mut Tally) {
    let mut prepared =
        prepare(source, &[], engine::Options::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let states = verify::admissible_states(&mut prepared.derivation, STATES, 0x7ac0_b1a2);
    let kept = prepared.layout.multipliers > 0;
    let mut compared = 0;
    for values in states {
        let mut at = problems(&mut prepared, &values);
        // A random state may be singular (a dead point); the others must agree.
        let Ok(worst) = compare(&mut at.mechanical, at.t, &at.y) else { continue };
        compared += 1;
        tally.worst = tally.worst.max(worst);
        if worst > AGREEMENT {
            tally.failures.push(format!("{rel}: (q, q̇) off by {worst:.1e}"));
        }
        if let Some((canonical, z)) = at.canonical.as_mut() {
            let worst = compare(canonical, at.t, z).unwrap_or_else(|e| panic!("{rel}: {e}"));
            tally.canonical += 1;
            tally.worst = tally.worst.max(worst);
            if worst > AGREEMENT {
                tally.failures.push(format!("{rel}: (q, p) off by {worst:.1e}"));
            }
        }
    }
    assert!(compared > 0, "{rel}: no admissible state where the right-hand side is defined");
    if kept {
        tally.kept += compared;
    } else {
        tally.free += compared;
    }
}

#[test]
fn every_example_has_the_jacobian_central_differences_give() {
    let mut tally = Tally::default();
    for (rel, source) in lagrange_tests::examples() {
        check_scene(&rel, &source, &mut tally);
    }
    assert!(tally.failures.is_empty(), "{}", tally.failures.join("\n"));
    // Both kinds of scene were compared, and many states of each.
    let Tally { kept, free, canonical, worst, .. } = tally;
    eprintln!("{kept} states with kept multipliers, {free} without, {canonical} canonical; worst {worst:.1e}");
    assert!(
        kept >= 15 && free >= 60 && canonical >= 60,
        "too few states: {kept}, {free}, {canonical}"
    );
}

#[test]
fn the_bicycle_has_the_jacobian_central_differences_give() {
    let mut tally = Tally::default();
    let rel = "examples/bicycle/whipple.lag";
    check_scene(rel, &lagrange_tests::example("bicycle/whipple.lag"), &mut tally);
    assert!(tally.failures.is_empty(), "{}", tally.failures.join("\n"));
    eprintln!("the bicycle: {} states; worst {:.1e}", tally.kept, tally.worst);
    assert!(tally.kept >= 3, "too few states: {}", tally.kept);
}
