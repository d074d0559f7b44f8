//! The recursive form (`mechanics::ChainForm` swept by `sim::Chain`) against the dense route
//! it replaces on long chains: the same q̈ at random states and parameters, on every example
//! that has the form, on generated chains, and in a run; and the scenes that must keep the
//! dense route do.

use engine::numbers::{prepare, Prepared};
use lang::generate::{n_link, Family};
use numeric::Tape;
use sim::{Mechanical, Problem};

/// How far the two routes' q̈ may be apart, relative to the largest |q̈|.
const AGREEMENT: f64 = 1e-10;

/// The dense problem and the same with the recursive form (any size), at `values` (a random
/// admissible state's), with (t, y); `None` where the scene has no recursive form.
fn both(
    prepared: &mut Prepared,
    values: &[f64],
) -> Option<(Mechanical, Mechanical, f64, Vec<f64>)> {
    let program = prepared.recursive_from(1).expect("lowers")?;
    let d = &prepared.derivation;
    let parameters: Vec<f64> = prepared.parameters.iter().map(|s| values[s.index()]).collect();
    let y: Vec<f64> = d.coords.iter().chain(&d.rates).map(|s| values[s.index()]).collect();
    let t = values[d.model.time.index()];
    let dense = lagrange_tests::mechanical(prepared, &parameters);
    let recursive = lagrange_tests::mechanical(prepared, &parameters).with_chain(program);
    assert!(recursive.recursive());
    Some((dense, recursive, t, y))
}

/// The largest difference of the two routes' q̈ at (t, y), relative to the largest |q̈|.
fn difference(dense: &mut Mechanical, recursive: &mut Mechanical, t: f64, y: &[f64]) -> f64 {
    let n = y.len() / 2;
    let (mut a, mut b) = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
    dense.rhs(t, y, &mut a).expect("the dense route solves");
    recursive.rhs(t, y, &mut b).expect("the recursive route solves");
    let scale = a[n..].iter().fold(1e-300_f64, |m, x| m.max(x.abs()));
    a[n..].iter().zip(&b[n..]).map(|(u, v)| (u - v).abs() / scale).fold(0.0, f64::max)
}

#[test]
fn every_example_with_the_form_gives_the_dense_accelerations() {
    let mut with_form = Vec::new();
    for (rel, source) in lagrange_tests::examples_without_contacts() {
        let mut prepared = prepare(&source, &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let states = verify::admissible_states(&mut prepared.derivation, 4, 0x5eed_c4a1);
        let mut compared = 0;
        for values in states {
            let Some((mut dense, mut recursive, t, y)) = both(&mut prepared, &values) else {
                break;
            };
            let off = difference(&mut dense, &mut recursive, t, &y);
            assert!(off < AGREEMENT, "{rel}: q̈ off by {off:.1e}");
            compared += 1;
        }
        if compared > 0 {
            with_form.push(rel);
        }
    }
    eprintln!("with the recursive form: {with_form:?}");
    for expected in [
        "classics/double_pendulum.lag",
        "classics/pendulum_on_cart.lag",
        "space/double_pendulum_3d.lag",
    ] {
        assert!(with_form.iter().any(|rel| rel.ends_with(expected)), "{expected}: {with_form:?}");
    }
}

#[test]
fn generated_chains_take_the_recursive_route_and_agree() {
    for (family, n) in [(Family::Pendulum, 8), (Family::Pendulum, 33), (Family::PendulumOnCart, 12)]
    {
        let source = n_link(family, n);
        let mut prepared = prepare(&source, &[], engine::Options::default()).expect("prepares");
        assert!(prepared.recursive().expect("lowers").is_some(), "{n} links");
        for values in verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0001) {
            let (mut dense, mut recursive, t, y) = both(&mut prepared, &values).expect("a form");
            let off = difference(&mut dense, &mut recursive, t, &y);
            assert!(off < AGREEMENT, "{n} links: q̈ off by {off:.1e}");
        }
    }
}

/// A chain in relative angles, a chain with a kept constraint and a small one keep the dense
/// route.
#[test]
fn scenes_without_the_form_keep_the_dense_route() {
    let mut relative = String::from("param m = 1, l = 1, g = 9.81\n");
    let mut angle = String::from("0");
    let (mut x, mut y) = (String::from("0"), String::from("0"));
    for i in 1..=8 {
        relative.push_str(&format!("coord q{i} = 0.1\n"));
        angle = format!("{angle} + q{i}");
        x = format!("{x} + l*sin({angle})");
        y = format!("{y} - l*cos({angle})");
        relative.push_str(&format!("particle p{i} {{ mass m; position ({x}, {y}) }}\n"));
    }
    relative.push_str("gravity g\n");
    let kept = "param m = 1, l = 1, g = 9.81\ncoord x = 1, y = 0\nparticle p { mass m; position (x, y) }\nconstraint rod: x^2 + y^2 = l^2\ngravity g\n";
    for source in [relative.as_str(), kept] {
        let mut prepared = prepare(source, &[], engine::Options::default()).expect("prepares");
        assert!(prepared.recursive_from(1).expect("lowers").is_none(), "{source}");
    }
    let small = n_link(Family::Pendulum, engine::numbers::RECURSIVE_FROM - 1);
    let mut prepared = prepare(&small, &[], engine::Options::default()).expect("prepares");
    assert!(prepared.recursive().expect("lowers").is_none());
    assert!(prepared.recursive_from(1).expect("lowers").is_some());
}

/// A 16-link chain run by `simulate`, which takes the recursive route at that size, keeps
/// its energy to the tolerance's order over two seconds of tumbling.
#[test]
fn a_run_on_the_recursive_route_keeps_its_energy() {
    let scene = n_link(Family::Pendulum, 16).replace("coord theta1 = 1/10", "coord theta1 = 1")
        + "simulate { until 2 s; method dop853; tolerance 1e-10; output KE + PE }\n";
    let outcome = simulation::simulate(&scene, &simulation::Options::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let energy = lagrange_tests::column(&outcome, "KE + PE");
    let rows = &outcome.run.trajectory.rows;
    assert!(rows.len() > 10);
    let start = rows[0][energy];
    let drift = rows.iter().map(|r| (r[energy] - start).abs()).fold(0.0, f64::max);
    assert!(drift < 1e-6 * start.abs().max(1.0), "energy drifted by {drift:.1e} from {start}");
}

/// Many states at once on the recursive route (the batch tape, eight a pass) give each
/// state's right-hand side bit for bit.
#[test]
fn many_states_at_once_give_each_state_s_bits() {
    let mut prepared =
        prepare(&n_link(Family::PendulumOnCart, 11), &[], engine::Options::default())
            .expect("prepares");
    let states = verify::admissible_states(&mut prepared.derivation, 13, 0xc4a1_0002);
    let (_, mut recursive, _, _) = both(&mut prepared, &states[0]).expect("a form");
    let d = &prepared.derivation;
    let ys: Vec<f64> = states
        .iter()
        .flat_map(|v| d.coords.iter().chain(&d.rates).map(|s| v[s.index()]).collect::<Vec<_>>())
        .collect();
    let width = 2 * d.coords.len();
    let times: Vec<f64> = (0..states.len()).map(|k| k as f64 * 0.1).collect();
    let mut many = vec![0.0; ys.len()];
    recursive.rhs_many(&times, &ys, &mut many).expect("regular");
    for (k, y) in ys.chunks_exact(width).enumerate() {
        let mut one = vec![0.0; width];
        recursive.rhs(times[k], y, &mut one).expect("regular");
        let same = one.iter().zip(&many[k * width..]).all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "state {k}: {one:?} against {:?}", &many[k * width..(k + 1) * width]);
    }
}

/// How far the two routes' Jacobians may be apart, relative to the largest entry of ∂q̈: the
/// recursive route solves its columns by the sweep, the dense one by M's factors.
const JACOBIANS_AGREE: f64 = 1e-9;

/// The largest difference of the two routes' exact Jacobians at (t, y), relative to the
/// largest entry of ∂q̈/∂(q, q̇).
fn jacobian_difference(
    dense: &mut Mechanical,
    recursive: &mut Mechanical,
    t: f64,
    y: &[f64],
) -> f64 {
    let width = y.len();
    let (mut a, mut b) = (vec![0.0; width * width], vec![0.0; width * width]);
    assert!(dense.jacobian(t, y, &mut a).expect("regular"));
    assert!(recursive.jacobian(t, y, &mut b).expect("regular"));
    let lower = width / 2 * width..;
    let scale = a[lower.clone()].iter().fold(1e-300_f64, |m, x| m.max(x.abs()));
    a[lower.clone()].iter().zip(&b[lower]).map(|(u, v)| (u - v).abs() / scale).fold(0.0, f64::max)
}

/// The exact Jacobian on the recursive route (its columns solved by the sweep past the
/// stack's order) is the dense route's, whether or not the sweep solved at the same state just
/// before (the Jacobian must not take another state's factors).
#[test]
fn the_jacobian_on_the_recursive_route_is_the_dense_one() {
    let mut prepared =
        prepare(&n_link(Family::Pendulum, 10), &[], engine::Options::default()).expect("prepares");
    let states = verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0003);
    let (mut dense, mut recursive, t, _) = both(&mut prepared, &states[0]).expect("a form");
    let d = &prepared.derivation;
    let width = 2 * d.coords.len();
    let ys: Vec<Vec<f64>> = states
        .iter()
        .map(|v| d.coords.iter().chain(&d.rates).map(|s| v[s.index()]).collect())
        .collect();
    let mut dy = vec![0.0; width];
    let mut firsts = Vec::new();
    for (k, y) in ys.iter().enumerate() {
        if k % 2 == 0 {
            recursive.rhs(t, y, &mut dy).expect("regular");
        }
        let off = jacobian_difference(&mut dense, &mut recursive, t, y);
        assert!(off < JACOBIANS_AGREE, "state {k}: the Jacobians differ by {off:.1e}");
        let mut first = vec![0.0; width * width];
        assert!(recursive.jacobian(t, y, &mut first).expect("regular"));
        firsts.push(first);
    }
    let mut jac = vec![0.0; width * width];
    for (k, y) in ys.iter().enumerate().rev() {
        recursive.rhs(t, &ys[(k + 1) % ys.len()], &mut dy).expect("regular");
        assert!(recursive.jacobian(t, y, &mut jac).expect("regular"));
        let same = jac.iter().zip(&firsts[k]).all(|(u, v)| u.to_bits() == v.to_bits());
        assert!(same, "state {k}: the Jacobian moved with what came before");
    }
}

/// A point that loses its mass leaves its coordinate without inertia: the sweep gives no
/// number there, and the run says which coordinate, as the dense route says it.
#[test]
fn a_coordinate_without_inertia_is_named_on_the_recursive_route() {
    let source = n_link(Family::Pendulum, 9)
        .replace("particle p9 { mass m;", "param m9 = 1 kg\nparticle p9 { mass m9;");
    let mut prepared = prepare(&source, &[], engine::Options::default()).expect("prepares");
    let mut values = verify::admissible_states(&mut prepared.derivation, 1, 0xc4a1_0004).remove(0);
    let m9 = prepared
        .parameters
        .iter()
        .find(|s| prepared.derivation.model.pool.symbol(**s).name == "m9")
        .copied()
        .expect("m9");
    values[m9.index()] = 0.0;
    let (mut dense, mut recursive, t, y) = both(&mut prepared, &values).expect("a form");
    let mut dy = vec![0.0; y.len()];
    let alone = dense.rhs(t, &y, &mut dy).expect_err("M is singular");
    let swept = recursive.rhs(t, &y, &mut dy).expect_err("M is singular");
    assert_eq!(format!("{swept:?}"), format!("{alone:?}"));
    assert!(matches!(swept, sim::FaultKind::SingularMass { .. }), "{swept:?}");
}

/// Trees, not only chains: each link hangs from a random earlier one (so nodes have several
/// children), some links are rods with their own inertia, masses and lengths differ, and a
/// spring pulls one joint sideways. The recursive route gives the dense route's q̈.
#[test]
fn branching_trees_give_the_dense_accelerations() {
    // A small linear congruential generator: the same trees on every run.
    let mut seed: u64 = 0x7ee5_0001;
    let mut next = move |below: usize| -> usize {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 33) as usize) % below
    };
    let mut branched = 0;
    for tree in 0..6 {
        let links = 8 + next(6);
        let mut scene = String::from("param g = 9.81, k = 3\n");
        let mut parents = Vec::new();
        for i in 0..links {
            let parent = if i == 0 { None } else { Some(next(i)) };
            parents.push(parent);
            let (mass, length) = (1 + next(4), 1 + next(3));
            scene.push_str(&format!("coord q{i} = 0.{}\n", 1 + next(8)));
            let (bx, by) = match parent {
                None => ("0".to_string(), "0".to_string()),
                Some(p) => (format!("x{p}"), format!("y{p}")),
            };
            scene.push_str(&format!(
                "let x{i} = {bx} + {length}/2*sin(q{i})\nlet y{i} = {by} - {length}/2*cos(q{i})\n"
            ));
            if next(2) == 0 {
                scene.push_str(&format!(
                    "body b{i} {{ mass {mass}; inertia {mass}*{length}^2/12; position (x{i}, y{i}); angle q{i} }}\n"
                ));
            } else {
                scene
                    .push_str(&format!("particle b{i} {{ mass {mass}; position (x{i}, y{i}) }}\n"));
            }
        }
        scene.push_str(&format!("potential k/2*x{}^2\ngravity g\n", links - 1));
        let branching = (0..links).any(|p| parents.iter().filter(|q| **q == Some(p)).count() > 1);
        branched += usize::from(branching);
        let mut prepared = prepare(&scene, &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("tree {tree}: {e}\n{scene}"));
        let states = verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0005 + tree);
        for values in states {
            let (mut dense, mut recursive, t, y) = both(&mut prepared, &values)
                .unwrap_or_else(|| panic!("tree {tree}: no form\n{scene}"));
            let off = difference(&mut dense, &mut recursive, t, &y);
            assert!(
                off < AGREEMENT,
                "tree {tree} (branching {branching}): q̈ off by {off:.1e}\n{scene}"
            );
            let off = jacobian_difference(&mut dense, &mut recursive, t, &y);
            assert!(
                off < JACOBIANS_AGREE,
                "tree {tree} (branching {branching}): the Jacobian off by {off:.1e}\n{scene}"
            );
        }
    }
    assert!(branched >= 3, "only {branched} of the trees branch");
}

/// Six rods in space, each turning by its own azimuth and tilt and hanging from the centre of
/// an earlier one: twelve coordinates, nodes of two, several children a node.
fn tree_in_space() -> String {
    let parents = [None, Some(0), Some(0), Some(1), Some(1), Some(2)];
    let mut scene = String::from("param g = 9.81\n");
    for (i, parent) in parents.iter().enumerate() {
        let (mass, length) = (1 + i % 3, 1 + i % 2);
        scene.push_str(&format!("coord a{i} = 0.{}, b{i} = 0.{}\n", 1 + i, 2 + i % 5));
        scene.push_str(&format!("let R{i} = rotz(a{i})*rotx(b{i})\n"));
        let base = match parent {
            None => "(0, 0, 0)".to_string(),
            Some(p) => format!("c{p}"),
        };
        scene.push_str(&format!("let c{i} = {base} + R{i}*(0, 0, -{length}/2)\n"));
        scene.push_str(&format!(
            "body r{i} {{ mass {mass}; inertia ({mass}*{length}^2/12, {mass}*{length}^2/12, 0); orientation R{i}; position c{i} }}\n"
        ));
    }
    scene.push_str("gravity g\n");
    scene
}

/// Trees in space: each rod turns by its own azimuth and tilt (two coordinates a node, so the
/// sweep factors 2×2 blocks) and hangs from the centre of a random earlier one.
#[test]
fn branching_trees_in_space_give_the_dense_accelerations() {
    let scene = tree_in_space();
    let mut prepared =
        prepare(&scene, &[], engine::Options::default()).unwrap_or_else(|e| panic!("{e}\n{scene}"));
    assert!(prepared.recursive().expect("lowers").is_some(), "12 coordinates: {scene}");
    for values in verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0006) {
        let (mut dense, mut recursive, t, y) =
            both(&mut prepared, &values).unwrap_or_else(|| panic!("no form\n{scene}"));
        let off = difference(&mut dense, &mut recursive, t, &y);
        assert!(off < AGREEMENT, "q̈ off by {off:.1e}\n{scene}");
        let off = jacobian_difference(&mut dense, &mut recursive, t, &y);
        assert!(off < JACOBIANS_AGREE, "the Jacobian off by {off:.1e}\n{scene}");
    }
}

/// The sweep's factors solve M·x = b for any b ([`sim::Chain::solve_columns`], what the exact
/// Jacobian's columns solve with): M's own columns give the identity and f gives q̈, at random
/// states of a chain and of a tree in space (nodes of two coordinates, 3×3 bases).
#[test]
fn the_sweep_s_factors_solve_with_m() {
    for scene in [n_link(Family::Pendulum, 7), tree_in_space()] {
        let mut prepared = prepare(&scene, &[], engine::Options::default()).expect("prepares");
        let recursive = prepared.recursive_from(1).expect("lowers").expect("a form");
        let exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
        let (mut dense, mut factored) = (Tape::new(dynamics), Tape::new(recursive.factored));
        let n = prepared.layout.coordinates;
        assert!(n < 16, "M and f fit one block");
        for values in verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0007) {
            let d = &prepared.derivation;
            let inputs: Vec<f64> =
                prepared.dynamics_inputs().iter().map(|s| values[s.index()]).collect();
            dense.inputs_mut().copy_from_slice(&inputs);
            factored.inputs_mut().copy_from_slice(&inputs);
            let (mut m_f, mut out) = (vec![0.0; exprs.len()], vec![0.0; factored.outputs()]);
            dense.run(&mut m_f);
            factored.run(&mut out);
            // b: M's columns (M is stored by columns), then f.
            let mut block = vec![[0.0; 16]; n];
            for (i, row) in block.iter_mut().enumerate() {
                for k in 0..n {
                    row[k] = m_f[k * n + i];
                }
                row[n] = m_f[n * n + i];
            }
            let mut work = Vec::new();
            recursive.chain.solve_columns(&out[n..], &mut block, &mut work);
            let scale = out[..n].iter().fold(1.0_f64, |m, a| m.max(a.abs()));
            for (i, row) in block.iter().enumerate() {
                for (k, x) in row[..n].iter().enumerate() {
                    let expected = if i == k { 1.0 } else { 0.0 };
                    assert!((x - expected).abs() < 1e-12, "{:?}: M⁻¹·M [{i}][{k}] = {x}", d.coords);
                }
                let off = (row[n] - out[i]).abs() / scale;
                assert!(off < 1e-12, "M⁻¹·f off q̈ by {off:.1e} at coordinate {i}");
            }
        }
    }
}

/// ∂q̈/∂p on the recursive route (its columns solved by the sweep past the stack's order) is
/// the dense route's, on a chain of ten with a spring and a damper, by every parameter.
#[test]
fn the_parameter_derivative_on_the_recursive_route_is_the_dense_one() {
    let source = n_link(Family::Pendulum, 10)
        + "param k = 3 N/m, c = 1/2 N*s/m, l0 = 1/4 m\n\
           spring s between p1 and (1/2, 0): k, l0\ndamper d between p2 and (0, 1): c\n";
    let mut prepared = prepare(&source, &[], engine::Options::default()).expect("prepares");
    let free: Vec<usize> = (0..prepared.parameter_plan.len()).collect();
    let program = prepared.sensitivity_program(&free).expect("lowers");
    let n = prepared.layout.coordinates;
    let states = verify::admissible_states(&mut prepared.derivation, 3, 0xc4a1_0008);
    for values in &states {
        let (mut dense, mut recursive, t, y) = both(&mut prepared, values).expect("a form");
        for problem in [&mut dense, &mut recursive] {
            problem.set_sensitivities(Tape::new(program.clone()), free.len());
        }
        let (mut a, mut b) = (vec![0.0; n * free.len()], vec![0.0; n * free.len()]);
        assert!(dense.parameter_derivative(t, &y, &mut a).expect("regular"));
        assert!(recursive.parameter_derivative(t, &y, &mut b).expect("regular"));
        let scale = a.iter().fold(1e-300_f64, |m, x| m.max(x.abs()));
        let off = a.iter().zip(&b).map(|(u, v)| (u - v).abs() / scale).fold(0.0, f64::max);
        assert!(off < JACOBIANS_AGREE, "∂q̈/∂p off by {off:.1e}");
    }
}
