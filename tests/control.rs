//! Inputs, outputs and the state space of `lagrange linearize` against hand derivations: the
//! cart-pole's A and B exactly and in numbers, the benchmark bicycle's B against the inverse
//! of Meijaard's M, every linearized example's eigenvalues with and without its cyclic
//! positions, controllability and observability, and inputs refused where their rate would
//! be needed.

use engine::linearize::{linearize, Component, Linearized, Options, Stability};

fn exact(l: &Linearized, m: &[Vec<cas::ExprId>]) -> Vec<Vec<String>> {
    let pool = &l.derivation.model.pool;
    m.iter().map(|r| r.iter().map(|e| pool.print(*e, cas::Style::Ascii)).collect()).collect()
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance * b.abs().max(1.0)
}

#[test]
fn the_cart_pole_has_the_hand_derived_a_and_b() {
    // Cart M at x, bob m on a rod L at θ from the upward vertical, force F on the cart.
    // M = [M + m, m·L; m·L, m·L²], K = [0, 0; 0, −m·g·L], Q_F = (1, 0); det M = M·m·L², so
    // M⁻¹ = [m·L², −m·L; −m·L, M + m]/(M·m·L²) and, in (x, θ, ẋ, θ̇):
    // ẍ = −m·g/M·θ + F/M,  θ̈ = (M + m)·g/(M·L)·θ − F/(M·L).
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag");
    let l = linearize(&source, &Options::default()).expect("linearizes");
    assert_eq!(l.state, ["x", "theta", "x'", "theta'"]);
    assert_eq!(l.inputs, ["F"]);
    let space = l.exact.as_ref().expect("A and B exactly");
    let a = exact(&l, &space.a);
    let b = exact(&l, &space.b);
    let hand_a = [
        ["0", "0", "1", "0"],
        ["0", "0", "0", "1"],
        ["0", "-m*g/M", "0", "0"],
        ["0", "m*g/(M*L) + g/L", "0", "0"],
    ];
    assert_eq!(a, hand_a);
    // (M + m)·g/(M·L), as the algebra splits it.
    assert_eq!(b, [["0"], ["0"], ["1/M"], ["-1/(M*L)"]]);

    let (big, m, length, g) = (2.0, 1.0, 1.0, 9.81);
    let a = &l.at.first_order.a;
    let b = &l.at.first_order.b;
    let hand_a = [
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, -m * g / big, 0.0, 0.0],
        [0.0, (big + m) * g / (big * length), 0.0, 0.0],
    ];
    let hand_b = [0.0, 0.0, 1.0 / big, -1.0 / (big * length)];
    for j in 0..4 {
        for i in 0..4 {
            assert!(close(a[j][i], hand_a[j][i], 1e-14), "A[{j}][{i}] = {}", a[j][i]);
        }
        assert!(close(b[j][0], hand_b[j], 1e-14), "B[{j}] = {}", b[j][0]);
    }
    // The outputs: the cart's position and the tip's horizontal place x + L·sin θ.
    assert_eq!(l.outputs, ["position", "tip"]);
    assert_eq!(l.at.first_order.c, [[1.0, 0.0, 0.0, 0.0], [1.0, length, 0.0, 0.0]]);
    assert_eq!(l.at.first_order.d, [[0.0], [0.0]]);
    // A force on the cart reaches everything; the tip and the cart see everything.
    let controllability = l.at.first_order.controllability.expect("an input");
    assert_eq!((controllability.rank, controllability.full), (4, 4));
    assert!(!controllability.doubtful(), "{controllability:?}");
    let observability = l.at.first_order.observability.expect("outputs");
    assert_eq!((observability.rank, observability.full), (4, 4));
    // Upright it falls, whatever the cart's position: that zero is set aside.
    assert_eq!(l.at.stability, Stability::Unstable);
    assert_eq!(l.at.cyclic_zeros, 1);
}

/// Whether every entry of `ours` equals the scene expression written at the same place in
/// `hand`, exactly: their difference is identically zero.
fn equal_exactly(l: &mut Linearized, ours: &[Vec<cas::ExprId>], hand: &[&[&str]]) -> bool {
    assert_eq!(ours.len(), hand.len());
    ours.iter().zip(hand).all(|(row, texts)| {
        assert_eq!(row.len(), texts.len());
        row.iter().zip(texts.iter()).all(|(ours, text)| {
            let model = &mut l.derivation.model;
            let Ok(model::Value::Scalar(expected)) = model.resolve_expression(text) else {
                panic!("`{text}` is not a scalar of the scene");
            };
            let difference = model.pool.sub(*ours, expected);
            model.pool.is_identically_zero(difference)
        })
    })
}

#[test]
fn the_control_example_s_cart_pole_has_the_hand_derived_a_and_b() {
    // examples/control/cart_pole.lag: cart M at x; a uniform pole m, length L, hinged on the
    // cart, θ from the upward vertical, its centre at (x + L/2·sin θ, L/2·cos θ) with inertia
    // m·L²/12 about it; force F on the cart.
    //   T = ½·(M + m)·ẋ² + ½·m·L·cos θ·ẋ·θ̇ + ⅙·m·L²·θ̇²,  V = ½·m·g·L·cos θ.
    // About θ = 0 at rest: M = [M + m, m·L/2; m·L/2, m·L²/3], K = [0, 0; 0, −m·g·L/2],
    // Q_F = (1, 0). det M = m·L²·(M + m)/3 − m²·L²/4 = m·L²·(4·M + m)/12, so
    // M⁻¹ = [m·L²/3, −m·L/2; −m·L/2, M + m]/det and, with f = (F, m·g·L/2·θ):
    //   ẍ = (m·L²/3·F − m·L/2·m·g·L/2·θ)/det = (4·F − 3·m·g·θ)/(4·M + m),
    //   θ̈ = (−m·L/2·F + (M + m)·m·g·L/2·θ)/det = 6·((M + m)·g·θ − F)/((4·M + m)·L).
    // In the state (x, θ, ẋ, θ̇):
    let hand_a: [&[&str]; 4] = [
        &["0", "0", "1", "0"],
        &["0", "0", "0", "1"],
        &["0", "-3*m*g/(4*M + m)", "0", "0"],
        &["0", "6*(M + m)*g/((4*M + m)*L)", "0", "0"],
    ];
    let hand_b: [&[&str]; 4] = [&["0"], &["0"], &["4/(4*M + m)"], &["-6/((4*M + m)*L)"]];
    // The outputs position = x and angle = θ read the state's first two components.
    let hand_c: [&[&str]; 2] = [&["1", "0", "0", "0"], &["0", "1", "0", "0"]];
    let source = lagrange_tests::example("control/cart_pole.lag");
    let mut l = linearize(&source, &Options::default()).expect("linearizes");
    assert_eq!(l.state, ["x", "theta", "x'", "theta'"]);
    assert_eq!(l.inputs, ["F"]);
    assert_eq!(l.outputs, ["position", "angle"]);
    let space = l.exact.clone().expect("A and B exactly");
    assert!(equal_exactly(&mut l, &space.a, &hand_a), "A = {:?}", exact(&l, &space.a));
    assert!(equal_exactly(&mut l, &space.b, &hand_b), "B = {:?}", exact(&l, &space.b));
    assert!(equal_exactly(&mut l, &space.c, &hand_c), "C = {:?}", exact(&l, &space.c));
    // A wrong hand entry is told apart: the pole's length enters θ̈'s row.
    let wrong: [&[&str]; 4] = [&["0"], &["0"], &["4/(4*M + m)"], &["-6/(4*M + m)"]];
    assert!(!equal_exactly(&mut l, &space.b, &wrong));

    // In numbers at M = 1, m = 1/4, L = 1, g = 9.81: 4·M + m = 17/4.
    let (big, m, length, g) = (1.0, 0.25, 1.0, 9.81);
    let den = 4.0 * big + m;
    let a = &l.at.first_order.a;
    let b = &l.at.first_order.b;
    assert!(close(a[2][1], -3.0 * m * g / den, 1e-14), "{a:?}");
    assert!(close(a[3][1], 6.0 * (big + m) * g / (den * length), 1e-14), "{a:?}");
    assert!(close(b[2][0], 4.0 / den, 1e-14) && close(b[3][0], -6.0 / (den * length), 1e-14));
    // Upright it falls at the rate √(6·(M + m)·g/((4·M + m)·L)); the force reaches everything.
    let rate = (6.0 * (big + m) * g / (den * length)).sqrt();
    assert!(l.at.eigenvalues.iter().any(|z| close(z.0, rate, 1e-12) && z.1 == 0.0));
    let controllability = l.at.first_order.controllability.expect("an input");
    assert_eq!((controllability.rank, controllability.full), (4, 4));
}

#[test]
fn the_cart_alone_is_not_observable_from_the_angle() {
    // Measuring the angle alone leaves the cart's position and speed unseen: θ's equation does
    // not involve them. The rank says so, with nothing doubtful about it.
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag")
        .replace("output position: x\n", "")
        .replace("output tip: x + L*sin(theta)", "output angle: theta");
    let l = linearize(&source, &Options::default()).expect("linearizes");
    let observability = l.at.first_order.observability.expect("an output");
    assert_eq!((observability.rank, observability.full), (2, 4));
    assert!(observability.largest_left_out < 1e-12, "{observability:?}");
    assert!(!observability.doubtful());
}

/// Meijaard et al. (2007), eq. (A21): the benchmark's M at its Table 1 values.
const MEIJAARD_M: [[f64; 2]; 2] =
    [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]];

#[test]
fn the_bicycle_s_b_is_the_inverse_of_meijaard_s_m() {
    // The example's roll torque acts on the rear frame about its roll axis (heading's x); its
    // steer torque between the frames about the steer axis, in opposite senses. M is the
    // same at every speed; B is taken in the reduced state (the benchmark's), at 1 m/s.
    let source = lagrange_tests::example("bicycle/whipple.lag");
    let options = Options { set: vec!["v=1".into()], drop_cyclic: true, ..Default::default() };
    let l = linearize(&source, &options).expect("linearizes");
    assert_eq!(l.inputs, ["Tphi", "Tdelta"]);
    let det = MEIJAARD_M[0][0] * MEIJAARD_M[1][1] - MEIJAARD_M[0][1] * MEIJAARD_M[1][0];
    let inverse = [
        [MEIJAARD_M[1][1] / det, -MEIJAARD_M[0][1] / det],
        [-MEIJAARD_M[1][0] / det, MEIJAARD_M[0][0] / det],
    ];
    let pool = &l.derivation.model.pool;
    let name = |c: &Component| c.name(pool, &l.linearization.coords);
    let rows: Vec<usize> = ["phi'", "delta'"]
        .iter()
        .map(|r| l.at.first_order.state.iter().position(|c| name(c) == *r).expect("a rate"))
        .collect();
    let b = &l.at.first_order.b;
    let mut largest = 0.0f64;
    for (j, &row) in rows.iter().enumerate() {
        for (k, expected) in inverse[j].iter().enumerate() {
            let ours = b[row][k];
            largest = largest.max((ours - expected).abs());
            assert!((ours - expected).abs() < 1e-8, "B[{j}][{k}] = {ours} against {expected}");
        }
    }
    eprintln!("largest difference from Meijaard's M⁻¹: {largest:e}");
    // The torques reach only the rates' rows: the positions' rows of B are zero.
    for (row, component) in l.at.first_order.state.iter().enumerate() {
        if matches!(component, Component::Position(_)) {
            assert_eq!(b[row], [0.0, 0.0], "{}", name(component));
        }
    }
}

/// Every example with a `linearize about` line, linearized with its cyclic positions kept and
/// dropped: the same eigenvalues but one zero per cyclic position kept, and the same verdict.
#[test]
fn every_example_keeps_its_eigenvalues() {
    let mut answered = 0;
    let mut examples = lagrange_tests::examples();
    examples.push(("bicycle/whipple.lag".into(), lagrange_tests::example("bicycle/whipple.lag")));
    for (path, source) in examples {
        if !source.lines().any(|l| l.starts_with("linearize about")) {
            continue;
        }
        let kept = linearize(&source, &Options::default());
        let dropped = linearize(&source, &Options { drop_cyclic: true, ..Default::default() });
        let (Ok(kept), Ok(dropped)) = (kept, dropped) else {
            panic!("{path}: linearizes one way but not the other");
        };
        answered += 1;
        assert_eq!(kept.at.stability, dropped.at.stability, "{path}");
        let zeros = kept.at.cyclic_zeros;
        let positions = kept.at.first_order.state.iter();
        let cyclic_kept = positions
            .filter(|c| matches!(c, Component::Position(i) if kept.linearization.cyclic[*i]))
            .count();
        let holonomic =
            kept.linearization.in_rates().is_none() && kept.linearization.kept().is_none();
        assert_eq!(zeros, if holonomic { cyclic_kept } else { 0 }, "{path}");
        assert_eq!(kept.at.eigenvalues.len(), dropped.at.eigenvalues.len() + zeros, "{path}");
        let mut rest = kept.at.eigenvalues.clone();
        for _ in 0..zeros {
            let at =
                rest.iter().position(|z| *z == (0.0, 0.0)).expect("a zero per cyclic position");
            rest.remove(at);
        }
        assert_eq!(rest, dropped.at.eigenvalues, "{path}");
    }
    assert!(answered >= 5, "only {answered} examples linearized");
}

#[test]
fn a_run_uses_an_input_s_value_when_nothing_drives_it() {
    // With F at its value, 0, the cart-pole balanced upright stays there; at F = 2 N the
    // horizontal momentum (M + m)·ẋ + m·L·cos θ·θ̇ grows as F·t, whatever the rod does.
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag")
        .replace("coord theta = 0.05", "coord theta = 0");
    let options = simulation::Options { until: Some(1.0), ..Default::default() };
    let run = |source: &str| {
        let outcome = simulation::simulate(source, &options).expect("runs");
        outcome.run.final_state.clone()
    };
    let still = run(&source);
    assert!(still.iter().all(|x| x.abs() < 1e-12), "{still:?}");
    let pushed = run(&source.replace("input F = 0 N", "input F = 2 N"));
    let [_, theta, x_rate, theta_rate] = pushed[..] else { panic!("{pushed:?}") };
    let momentum = 3.0 * x_rate + numeric::elementary::apply(cas::Func::Cos, theta) * theta_rate;
    assert!((momentum - 2.0).abs() < 1e-6, "{momentum} after 1 s, from {pushed:?}");
}

#[test]
fn inputs_are_not_parameters() {
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag");
    let options = Options { set: vec!["F=1".into()], ..Default::default() };
    let err = linearize(&source, &options).err().expect("--set refuses an input");
    let text = cli::diagnostics::error("cart.lag", &err);
    assert!(text.contains("no parameter of that name"), "{text}");
}

#[test]
fn stability_results_are_checked_as_expectations() {
    let source = lagrange_tests::example("classics/inverted_pendulum_on_cart.lag");
    let checked = cli::check::check_file("cart.lag", &source);
    assert_eq!((checked.held, checked.failed, checked.exit_code), (4, 0, 0), "{}", checked.report);

    // Each kind of expectation fails when what it names is not what linearize finds, with
    // what was found instead.
    let wrong = source
        .replace("expect linearized: unstable", "expect linearized: stable")
        .replace("eigenvalue = sqrt((M + m)*g/(M*L))", "eigenvalue = (0, sqrt((M + m)*g/(M*L)))");
    let checked = cli::check::check_file("cart.lag", &wrong);
    assert_eq!((checked.held, checked.failed, checked.exit_code), (2, 2, 1), "{}", checked.report);
    assert!(checked.report.contains("unstable at the reference"), "{}", checked.report);
    assert!(checked.report.contains("the nearest eigenvalue is"), "{}", checked.report);

    let top = lagrange_tests::example("space/sleeping_top.lag");
    let checked = cli::check::check_file("top.lag", &top);
    assert_eq!((checked.failed, checked.exit_code), (0, 0), "{}", checked.report);
    assert!(checked.report.contains("unstable → marginally stable at w = 51.14684"));
    let off = top.replace("critical w = 2*sqrt", "critical w = 1.01*2*sqrt");
    let checked = cli::check::check_file("top.lag", &off);
    assert_eq!((checked.failed, checked.exit_code), (1, 1), "{}", checked.report);
    assert!(checked.report.contains("does not change between"), "{}", checked.report);
}
