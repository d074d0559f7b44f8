//! The exact Jacobians against central differences of the right-hand side, for every example
//! (the bicycle in a test of its own, its derivation being the slowest) at random admissible
//! states (random parameters too): of the first-order system in (q, q̇),
//! constraints kept with multipliers solved with their Baumgarte rows, and of the canonical
//! system in (q, p) the symplectic methods integrate. And the raw partials a method keeping q̈
//! and λ among its unknowns reads, against differences of the rows they are of.

use engine::numbers::{prepare, Prepared};
use numeric::Tape;
use sim::{Canonical, Constrained, Mechanical, Problem};

/// Random admissible states per scene.
const STATES: usize = 5;
/// How far the exact Jacobian may be from central differences, relative (see [`compare`]).
const AGREEMENT: f64 = 1e-7;

/// The largest discrepancy of `problem`'s exact Jacobian at (t, y) from central differences of
/// its right-hand side (see [`discrepancy`]).
fn compare(problem: &mut dyn Problem, t: f64, y: &[f64]) -> Result<f64, String> {
    let d = y.len();
    let mut exact = vec![0.0; d * d];
    let has = problem.jacobian(t, y, &mut exact).map_err(|f| format!("jacobian: {f:?}"))?;
    assert!(has, "the problem was given its partials");
    discrepancy(&exact, y, |state| {
        let mut rates = vec![0.0; d];
        problem.rhs(t, state, &mut rates).map_err(|f| format!("rhs: {f:?}"))?;
        Ok(rates)
    })
}

/// The largest discrepancy of `exact` (row-major, a row per value of `f`, a column per entry
/// of `y`) from central differences of `f` at `y`. Each row is measured against its own size
/// (the largest of its entries, exact or differenced), so that a dropped partial shows in the
/// row it belongs to however small the row is; a row that vanishes but for rounding is
/// measured against the matrix.
fn discrepancy(
    exact: &[f64],
    y: &[f64],
    mut f: impl FnMut(&[f64]) -> Result<Vec<f64>, String>,
) -> Result<f64, String> {
    let d = y.len();
    // Differences are limited by truncation at large steps and by rounding at small ones, the
    // more so where M is ill-conditioned (a top's Euler angles in canonical variables): the
    // best of a few steps is how well differences can tell.
    let mut best = f64::INFINITY;
    for step in [3e-3, 1e-3, 3e-4, 1e-4] {
        let differenced = differences(&mut f, y, step)?;
        let largest = exact.iter().chain(&differenced).fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for i in 0..exact.len() / d {
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

/// ∂f/∂y (row-major) by central differences at two steps, h and h/2 (h = `step` relative to
/// each component), extrapolated (Richardson) so that the truncation error is of order h⁴.
fn differences(
    f: &mut impl FnMut(&[f64]) -> Result<Vec<f64>, String>,
    y: &[f64],
    step: f64,
) -> Result<Vec<f64>, String> {
    let d = y.len();
    let mut columns = Vec::with_capacity(d);
    let mut shifted = y.to_vec();
    for k in 0..d {
        let h = step * y[k].abs().max(1.0);
        let mut central = |step: f64| -> Result<Vec<f64>, String> {
            shifted[k] = y[k] + step;
            let plus = f(&shifted)?;
            shifted[k] = y[k] - step;
            let minus = f(&shifted)?;
            shifted[k] = y[k];
            Ok(plus.iter().zip(&minus).map(|(p, m)| (p - m) / (2.0 * step)).collect())
        };
        let (wide, narrow) = (central(h)?, central(h / 2.0)?);
        columns.push(wide.iter().zip(&narrow).map(|(w, n)| (4.0 * n - w) / 3.0).collect());
    }
    let rows = columns.first().map_or(0, |c: &Vec<f64>| c.len());
    Ok((0..rows * d).map(|e| columns[e % d][e / d]).collect())
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
    /// States compared in the differential–algebraic form (q, v, a, λ) radau integrates.
    algebraic: usize,
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
        if kept {
            // The same state in the differential–algebraic form, with its consistent a and λ
            // (where the augmented system is regular there).
            let mut constrained = Constrained::new(at.mechanical);
            if let Ok(z) = constrained.consistent_state(at.t, &at.y) {
                let worst =
                    compare(&mut constrained, at.t, &z).unwrap_or_else(|e| panic!("{rel}: {e}"));
                tally.algebraic += 1;
                tally.worst = tally.worst.max(worst);
                if worst > AGREEMENT {
                    tally.failures.push(format!("{rel}: (q, v, a, λ) off by {worst:.1e}"));
                }
            }
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
    for (rel, source) in lagrange_tests::examples_without_contacts() {
        check_scene(&rel, &source, &mut tally);
    }
    assert!(tally.failures.is_empty(), "{}", tally.failures.join("\n"));
    // Both kinds of scene were compared, and many states of each.
    let Tally { kept, algebraic, free, canonical, worst, .. } = tally;
    eprintln!(
        "{kept} states with kept multipliers ({algebraic} also as the differential–algebraic \
         system), {free} without, {canonical} canonical; worst {worst:.1e}"
    );
    assert!(
        kept >= 15 && algebraic >= 15 && free >= 60 && canonical >= 60,
        "too few states: {kept}, {algebraic}, {free}, {canonical}"
    );
}

/// Past the stack's order (eight), the Jacobian's columns solve with what the accelerations
/// left: the LDLᵀ factors of M on the dense route, the sweep's factors on the recursive one
/// (O(n) a column, M never formed). Generated chains of 10 and 13 coordinates, with a spring
/// and a damper so that f depends on every kind of entry, on both routes, against central
/// differences; and the same bits whatever was solved before (the factors are the state's
/// own, not another state's left behind).
#[test]
fn past_the_stack_the_jacobian_solves_with_the_accelerations_factors() {
    let spring = "param k = 3 N/m, c = 1/2 N*s/m, l0 = 1/4 m\n\
                  spring s between p1 and (1/2, 0): k, l0\ndamper d between p2 and (0, 1): c\n";
    for (family, n) in
        [(lang::generate::Family::Pendulum, 10), (lang::generate::Family::PendulumOnCart, 12)]
    {
        let source = lang::generate::n_link(family, n) + spring;
        let mut prepared = prepare(&source, &[], engine::Options::default()).expect("prepares");
        assert!(prepared.layout.coordinates > 8 && prepared.layout.multipliers == 0);
        let recursive = prepared.recursive().expect("lowers").expect("a chain");
        let states = verify::admissible_states(&mut prepared.derivation, 4, 0x7ac0_b1a3);
        for route in ["dense", "recursive"] {
            let on_route = |prepared: &mut Prepared, values: &[f64]| {
                let at = problems(prepared, values);
                let mechanical = match route {
                    "dense" => at.mechanical,
                    _ => at.mechanical.with_chain(recursive.clone()),
                };
                (mechanical, at.t, at.y)
            };
            let mut firsts = Vec::new();
            for values in &states {
                let (mut mechanical, t, y) = on_route(&mut prepared, values);
                assert_eq!(mechanical.recursive(), route == "recursive");
                let worst = compare(&mut mechanical, t, &y).expect("regular");
                assert!(worst < AGREEMENT, "{n} coordinates, {route}: off by {worst:.1e}");
                let d = y.len();
                let mut first = vec![0.0; d * d];
                assert!(mechanical.jacobian(t, &y, &mut first).expect("regular"));
                let parameters = mechanical.parameters().to_vec();
                firsts.push((t, y, parameters, first));
            }
            // One problem through every state (and its parameters) in turn, with other states'
            // solves between.
            let mut problem = on_route(&mut prepared, &states[0]).0;
            let d = firsts[0].1.len();
            let (mut jac, mut dy) = (vec![0.0; d * d], vec![0.0; d]);
            for (k, (t, y, parameters, first)) in firsts.iter().enumerate() {
                let (other_t, other_y, _, _) = &firsts[(k + 1) % firsts.len()];
                problem.set_parameters(parameters);
                problem.rhs(*other_t, other_y, &mut dy).expect("regular");
                if k % 2 == 0 {
                    problem.rhs(*t, y, &mut dy).expect("regular");
                }
                assert!(problem.jacobian(*t, y, &mut jac).expect("regular"));
                let same = jac.iter().zip(first).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{n} coordinates, {route}, state {k}: the Jacobian moved");
            }
        }
    }
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

/// The rows the raw partials are of, at a state and time with q̈ and λ held at `unknowns`:
/// r = M q̈ − Jᵀλ − f, then c = J q̈ − γ, Φ and Φ̇ of each multiplier, from the dynamics
/// program's outputs (the layout of `sim::Layout`).
fn rows(layout: sim::Layout, dynamics: &[f64], unknowns: &[f64]) -> Vec<f64> {
    let (n, m) = (layout.coordinates, layout.multipliers);
    let (accelerations, multipliers) = unknowns.split_at(n);
    let constraint = |c: usize| &dynamics[n * n + n + c * (n + 3)..n * n + n + (c + 1) * (n + 3)];
    let mut out: Vec<f64> = (0..n)
        .map(|i| {
            let inertia: f64 = (0..n).map(|j| dynamics[j * n + i] * accelerations[j]).sum();
            let reaction: f64 = (0..m).map(|c| constraint(c)[i] * multipliers[c]).sum();
            inertia - reaction - dynamics[n * n + i]
        })
        .collect();
    for c in 0..m {
        let row = constraint(c);
        out.push((0..n).map(|j| row[j] * accelerations[j]).sum::<f64>() - row[n]);
    }
    for slot in [n + 1, n + 2] {
        out.extend((0..m).map(|c| constraint(c)[slot]));
    }
    out
}

#[test]
fn the_raw_partials_are_those_of_the_rows_at_any_accelerations_and_multipliers() {
    let mut compared = 0;
    let mut failures = Vec::new();
    for (rel, source) in lagrange_tests::examples_without_contacts() {
        let mut prepared = prepare(&source, &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let layout = prepared.layout;
        if layout.multipliers == 0 {
            continue;
        }
        let exprs = prepared.dynamics_exprs();
        let program = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
        let mut dynamics = Tape::new(program);
        for values in verify::admissible_states(&mut prepared.derivation, STATES, 0x4a11_00e5) {
            let AtState { mut mechanical, t, y, .. } = problems(&mut prepared, &values);
            let parameters: Vec<f64> =
                prepared.parameters.iter().map(|s| values[s.index()]).collect();
            // Not the solved ones: the partials hold q̈ and λ wherever they are.
            let unknowns: Vec<f64> = (0..layout.coordinates + layout.multipliers)
                .map(|i| 0.7 - 0.3 * i as f64)
                .collect();
            let exact = match mechanical.partials_at(t, &y, &unknowns) {
                Ok(Some(p)) => p.to_vec(),
                other => panic!("{rel}: {other:?}"),
            };
            let worst = discrepancy(&exact, &y, |state| {
                let mut input = vec![t];
                input.extend(state);
                input.extend(&parameters);
                let mut out = vec![0.0; layout.dynamics_outputs()];
                dynamics.eval(&input, &mut out);
                Ok(rows(layout, &out, &unknowns))
            })
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
            compared += 1;
            if worst > AGREEMENT {
                failures.push(format!("{rel}: raw partials off by {worst:.1e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(compared >= 15, "only {compared} states compared");
}
