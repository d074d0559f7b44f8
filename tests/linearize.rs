//! `lagrange linearize`: small motions about equilibria and steady motions against results
//! derived by hand. The pendulum hanging and standing, the pendulum on a cart, the Cartesian
//! pendulum through its constraint's null space, the conical pendulum, the sleeping top's
//! critical spin found by a sweep; references that are not equilibria, and the JSON shape.

use engine::linearize::{linearize, Linearized, Options, Stability};

fn example(rel: &str) -> String {
    let (_, source) = lagrange_tests::examples()
        .into_iter()
        .find(|(p, _)| p.ends_with(rel))
        .unwrap_or_else(|| panic!("no example {rel}"));
    source
}

fn about(source: &str, about: &str) -> Linearized {
    let options = Options { about: Some(about.into()), ..Default::default() };
    linearize(source, &options).unwrap_or_else(|e| panic!("linearizes about {about}: {e}"))
}

fn close(a: f64, b: f64, relative: f64) -> bool {
    (a - b).abs() <= relative * b.abs().max(1e-300)
}

fn exact(l: &Linearized, m: &[Vec<cas::ExprId>]) -> Vec<Vec<String>> {
    let pool = &l.derivation.model.pool;
    m.iter().map(|r| r.iter().map(|e| pool.print(*e, cas::Style::Ascii)).collect()).collect()
}

#[test]
fn the_pendulum_oscillates_hanging_and_falls_standing() {
    let source = example("classics/simple_pendulum.lag");
    let (g, length) = (9.81_f64, 1.0_f64);
    let omega = (g / length).sqrt();

    let hanging = about(&source, "theta = 0");
    assert!(hanging.exact_reference);
    assert_eq!(hanging.at.stability, Stability::MarginallyStable);
    let e = &hanging.at.eigenvalues;
    assert_eq!(e.len(), 2);
    assert!(e[0].0.abs() <= 1e-12 * omega && e[1].0.abs() <= 1e-12 * omega, "{e:?}");
    assert!(close(e[0].1, omega, 1e-12) && close(e[1].1, -omega, 1e-12), "{e:?}");

    let standing = about(&source, "theta = pi");
    assert_eq!(standing.at.stability, Stability::Unstable);
    let e = &standing.at.eigenvalues;
    assert!(close(e[0].0, omega, 1e-12) && close(e[1].0, -omega, 1e-12), "{e:?}");
    assert!(e[0].1 == 0.0 && e[1].1 == 0.0, "{e:?}");
    assert_eq!(exact(&standing, &standing.stiffness), [["-m*L*g"]]);
}

#[test]
fn the_pendulum_on_a_cart_has_the_hand_derived_matrices() {
    // T = ½(M + m)ẋ² + m·L·cos θ·ẋ·θ̇ + ½·m·L²·θ̇², V = −m·g·L·cos θ: about θ = 0,
    // M = [M + m, m·L; m·L, m·L²], C = 0, K = [0, 0; 0, m·g·L]; x is cyclic.
    let l = about(&example("classics/pendulum_on_cart.lag"), "theta = 0");
    assert_eq!(exact(&l, &l.mass), [["M + m", "m*L"], ["m*L", "m*L^2"]]);
    assert_eq!(exact(&l, &l.damping), [["0", "0"], ["0", "0"]]);
    assert_eq!(exact(&l, &l.stiffness), [["0", "0"], ["0", "m*L*g"]]);
    assert_eq!(l.linearization.cyclic, [true, false]);
    // Every coordinate stays in the state; the cart's position brings a zero of its own.
    assert_eq!(l.state, ["x", "theta", "x'", "theta'"]);
    assert_eq!(l.at.cyclic_zeros, 1);
    let (big, m, length, g) = (2.0, 1.0, 1.0, 9.81);
    assert_eq!(l.at.mass, [[big + m, m * length], [m * length, m * length * length]]);
    assert_eq!(l.at.stiffness, [[0.0, 0.0], [0.0, m * g * length]]);
    // det(K − ω²M) = 0: ω² = (M + m)·g/(M·L), and the cart's free drift δẋ and its position
    // δx give a zero each.
    let omega = ((big + m) * g / (big * length)).sqrt();
    let e = &l.at.eigenvalues;
    assert_eq!(e.len(), 4);
    assert!(close(e[0].1, omega, 1e-12) && e[1] == (0.0, 0.0) && e[2] == (0.0, 0.0), "{e:?}");
    assert!(e.iter().all(|(re, _)| re.abs() <= 1e-12 * omega), "{e:?}");
    assert_eq!(l.at.stability, Stability::MarginallyStable);
}

#[test]
fn a_kept_constraint_is_linearized_in_its_null_space() {
    let l = about(&example("classics/pendulum_cartesian.lag"), "x = 0, y = -L");
    // λ = −m·g/(2·L) holds the bob up; K = −2·λ·I then.
    let (m, g, length) = (1.0, 9.81, 1.0);
    assert!(close(l.at.multipliers[0], -m * g / (2.0 * length), 1e-12), "{:?}", l.at.multipliers);
    assert_eq!(exact(&l, &l.stiffness), [["-2*rod.force", "0"], ["0", "-2*rod.force"]]);
    assert_eq!(l.state, ["z1", "z1'"]);
    let omega = (g / length).sqrt();
    let e = &l.at.eigenvalues;
    assert!(close(e[0].1, omega, 1e-12) && close(e[1].1, -omega, 1e-12), "{e:?}");
    assert_eq!(l.at.stability, Stability::MarginallyStable);
    // Off the constraint, the reference is refused.
    let options = Options { about: Some("x = 0, y = -2*L".into()), ..Default::default() };
    let err = linearize(&example("classics/pendulum_cartesian.lag"), &options).err().expect("off");
    assert!(cli::diagnostics::error("p.lag", &err).contains("not on the constraint `rod`"));
}

#[test]
fn the_conical_pendulum_wobbles_at_the_textbook_frequency() {
    // Steady precession at θ0 needs φ̇² = g/(L·cos θ0); small wobbles then have
    // ω² = g/L·(1 + 3·cos²θ0)/cos θ0. φ is cyclic.
    let l = about(&example("classics/spherical_pendulum.lag"), "theta = pi/3, phi' = sqrt(2*g/L)");
    assert!(l.exact_reference);
    assert_eq!(l.linearization.cyclic, [false, true]);
    let (g, length, c) = (9.81_f64, 1.0_f64, 0.5_f64);
    let omega = (g / length * (1.0 + 3.0 * c * c) / c).sqrt();
    let e = &l.at.eigenvalues;
    assert!(close(e[0].1, omega, 1e-12), "{e:?}");
    assert_eq!(l.at.stability, Stability::MarginallyStable);
}

#[test]
fn the_sleeping_top_wakes_below_the_critical_spin() {
    let source = example("space/sleeping_top.lag");
    let options = Options { sweep: Some("w=0:100:101".into()), ..Default::default() };
    let l = linearize(&source, &options).expect("linearizes");
    let sweep = l.sweep.as_ref().expect("a sweep");
    assert_eq!(sweep.rows.len(), 101);
    assert_eq!(sweep.rows[0].stability, Stability::Unstable);
    assert_eq!(sweep.rows[100].stability, Stability::MarginallyStable);
    assert_eq!(sweep.changes.len(), 1, "{:?}", sweep.changes);
    let change = sweep.changes[0];
    assert_eq!((change.from, change.to), (Stability::Unstable, Stability::MarginallyStable));
    // C²·w² = 4·(A + m·l²)·m·g·l.
    let (m, g, l_, a, c) = (0.5_f64, 9.81_f64, 0.04_f64, 0.0004_f64, 0.0006_f64);
    let critical = 2.0 * ((a + m * l_ * l_) * m * g * l_).sqrt() / c;
    assert!(close(change.value, critical, 1e-8), "{} against {critical}", change.value);
    let (lo, hi) = change.bracket;
    assert!((hi - lo).abs() <= 2e-10 * critical, "{lo}..{hi}");
    // The same from the other end, over a sweep that does not straddle the change evenly.
    let options = Options { sweep: Some("w=90:10:7".into()), ..Default::default() };
    let l = linearize(&source, &options).expect("linearizes");
    let change = l.sweep.expect("a sweep").changes[0];
    assert_eq!((change.from, change.to), (Stability::MarginallyStable, Stability::Unstable));
    assert!(close(change.value, critical, 1e-8), "{} against {critical}", change.value);
}

#[test]
fn a_reference_that_is_not_an_equilibrium_is_refused_with_its_accelerations() {
    let source = example("classics/simple_pendulum.lag");
    let options = Options { about: Some("theta = pi/2".into()), ..Default::default() };
    let err = linearize(&source, &options).err().expect("not an equilibrium");
    assert_eq!(err.exit_code(), 2);
    let text = cli::diagnostics::error("simple_pendulum.lag", &err);
    assert!(text.contains("is not an equilibrium or a steady motion"), "{text}");
    assert!(text.contains("θ̈ = -9.81"), "{text}");
    assert!(text.contains("(from --about)") && text.contains('^'), "{text}");

    // Positions left out, an eliminated coordinate given, equations that change with time, a
    // mass matrix singular at the reference (the heavy top's Euler angles at θ = 0).
    let cases = [
        ("classics/double_pendulum.lag", "theta1 = 0", "no position for `theta2`"),
        ("ps5/falling_rod.lag", "y = 0, theta = 0", "`y` is eliminated by `floor`"),
        ("classics/damped_driven_oscillator.lag", "x = 0", "depend on time"),
        ("space/heavy_top.lag", "theta = 0, phi' = 0", "mass matrix is singular"),
        ("classics/spherical_pendulum.lag", "theta = 0, theta' = 1", "does not stay put"),
    ];
    for (rel, about, message) in cases {
        let options = Options { about: Some(about.into()), ..Default::default() };
        let err = linearize(&example(rel), &options).err().unwrap_or_else(|| panic!("{rel}"));
        assert_eq!(err.exit_code(), 2, "{rel}");
        let text = cli::diagnostics::error(rel, &err);
        assert!(text.contains(message) && text.contains('^'), "{rel}: {text}");
    }
    let none = linearize(&source, &Options::default()).err().expect("no reference");
    assert!(none.to_string().contains("no `linearize about` line"), "{none}");
}

#[test]
fn the_command_line_extends_and_overrides_the_scene() {
    let source = example("space/sleeping_top.lag");
    // The scene spins at w; --about spins it at 10 and keeps the rest of the scene's line.
    let l = about(&source, "psi' = 10");
    assert_eq!(l.at.stability, Stability::Unstable);
    let options = Options { set: vec!["w=10".into()], ..Default::default() };
    let set = linearize(&source, &options).expect("linearizes");
    assert_eq!(set.at.eigenvalues, l.at.eigenvalues);
}

#[test]
fn json_has_the_matrices_the_eigenvalues_and_the_sweep() {
    let source = example("space/sleeping_top.lag");
    let options = Options { sweep: Some("w=40:60:5".into()), ..Default::default() };
    let l = linearize(&source, &options).expect("linearizes");
    let json: serde_json::Value =
        serde_json::from_str(&cli::linearize::json(&l)).expect("valid JSON");
    let lin = &json["linearization"];
    assert_eq!(lin["coordinates"], serde_json::json!(["a", "b", "psi"]));
    assert_eq!(lin["cyclic"], serde_json::json!(["psi"]));
    assert_eq!(lin["about"]["psi'"], "w");
    assert_eq!(lin["M"]["exact"][0][0], "A + m*l^2");
    assert_eq!(lin["C"]["exact"][0][1], "C*w");
    assert_eq!(lin["K"]["exact"][1][1], "-m*g*l");
    assert_eq!(lin["K"]["value"][1][1], -0.5 * 9.81 * 0.04);
    // ψ's position stays in the state: six components, its zero set aside.
    assert_eq!(lin["A"].as_array().map(Vec::len), Some(6));
    assert_eq!(lin["first_order"]["state"][2], "psi");
    assert_eq!(lin["cyclic_zeros"], 1);
    let eigenvalues = lin["eigenvalues"].as_array().expect("eigenvalues");
    assert_eq!(eigenvalues.len(), 6);
    assert!(eigenvalues.iter().all(|z| z.as_array().is_some_and(|z| z.len() == 2)));
    assert_eq!(lin["stability"], "marginally stable");
    let rows = lin["sweep"].as_array().expect("rows");
    assert_eq!(rows.len(), 5);
    assert_eq!(rows[0]["value"], 40.0);
    assert_eq!(rows[0]["eigenvalues"].as_array().map(Vec::len), Some(6));
    assert_eq!(lin["changes"][0]["from"], "unstable");
    let value = lin["changes"][0]["value"].as_f64().expect("a number");
    assert!((value - 51.14684741).abs() < 1e-6, "{value}");
}

#[test]
fn text_and_plot_show_the_sweep() {
    let source = example("space/sleeping_top.lag");
    let options = Options { sweep: Some("w=0:100:11".into()), ..Default::default() };
    let l = linearize(&source, &options).expect("linearizes");
    let text = cli::linearize::text(&l);
    assert!(text.contains("ψ is cyclic"), "{text}");
    assert!(text.contains("Stability changes\n  w = 51.1468474"), "{text}");
    let sweep = l.sweep.as_ref().expect("sweep");
    let svg = cli::plot::sweep("top", sweep);
    assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
    // A dot per eigenvalue and value, in both panels.
    assert_eq!(svg.matches("<circle").count(), 2 * 11 * 6);
    assert_eq!(svg.matches("stroke-dasharray").count(), 2);
}

/// Every scene of the repository (examples, cross-check scenes, the bad gallery), linearized
/// about all coordinates at 0 and swept over its first parameter: an answer or an error with
/// exit code 2, never a panic.
#[test]
fn no_scene_makes_linearize_panic() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    for dir in ["../examples/classics", "../examples/ps5", "../examples/space", "bad", "scenes"] {
        let entries = std::fs::read_dir(root.join(dir)).expect("a folder");
        files.extend(entries.flatten().map(|e| e.path()));
    }
    files.extend(
        std::fs::read_dir(root.join("sympy/scenes")).expect("scenes").flatten().map(|e| e.path()),
    );
    files.retain(|p| p.extension().is_some_and(|e| e == "lag"));
    files.sort();
    assert!(files.len() > 100, "{}", files.len());
    let mut panicked = Vec::new();
    let mut answered = 0;
    for path in files {
        let source = std::fs::read_to_string(&path).expect("readable");
        let (coords, params) = match lang::parse(&source) {
            Ok(file) => names(&file),
            Err(_) => (Vec::new(), Vec::new()),
        };
        let about = coords.iter().map(|c| format!("{c} = 0")).collect::<Vec<_>>().join(", ");
        let mut runs = vec![Options { about: Some(about.clone()), ..Default::default() }];
        if let Some(p) = params.first() {
            let sweep = Some(format!("{p}=1:2:3"));
            runs.push(Options { about: Some(about), sweep, ..Default::default() });
        }
        for options in runs {
            let outcome = std::panic::catch_unwind(|| linearize(&source, &options));
            match outcome {
                Err(_) => panicked.push(path.display().to_string()),
                Ok(Ok(_)) => answered += 1,
                Ok(Err(e)) => assert_eq!(e.exit_code(), 2, "{}: {e}", path.display()),
            }
        }
    }
    assert!(panicked.is_empty(), "linearize panicked on {panicked:?}");
    // Most scenes are not at rest with every coordinate at 0; some are.
    assert!(answered >= 10, "only {answered} scenes linearized");
}

/// The coordinates and parameters a scene declares, by name.
fn names(file: &lang::SceneFile) -> (Vec<String>, Vec<String>) {
    let (mut coords, mut params) = (Vec::new(), Vec::new());
    for stmt in &file.stmts {
        match &stmt.kind {
            lang::StmtKind::Coord(decls) => {
                coords.extend(decls.iter().map(|d| d.name.name.clone()))
            }
            lang::StmtKind::Param(decls) => {
                params.extend(decls.iter().map(|d| d.name.name.clone()))
            }
            _ => {}
        }
    }
    (coords, params)
}

/// Issue 12's bar: the double pendulum of equal masses and lengths swings in its normal modes
/// at ω² = (2 ± √2)·g/l.
#[test]
fn the_double_pendulum_has_its_normal_modes() {
    // The example has m1 = m2 = 1 kg and l1 = l2 = 1 m.
    let source = example("classics/double_pendulum.lag");
    let modes = about(&source, "theta1 = 0, theta2 = 0");
    assert_eq!(modes.at.stability, Stability::MarginallyStable);
    let (g, length) = (9.81_f64, 1.0_f64);
    let root2 = 2.0_f64.sqrt();
    let mut expected = [((2.0 + root2) * g / length).sqrt(), ((2.0 - root2) * g / length).sqrt()];
    let mut found: Vec<f64> =
        modes.at.eigenvalues.iter().filter(|(_, im)| *im > 0.0).map(|(_, im)| *im).collect();
    found.sort_by(|a, b| b.total_cmp(a));
    expected.sort_by(|a, b| b.total_cmp(a));
    assert_eq!(found.len(), 2, "{:?}", modes.at.eigenvalues);
    for (f, e) in found.iter().zip(expected) {
        assert!(close(*f, e, 1e-12), "{f} against {e}");
    }
    assert!(modes.at.eigenvalues.iter().all(|(re, _)| re.abs() < 1e-12 * expected[0]));
}

#[test]
fn the_rolling_coin_stays_up_above_the_critical_spin() {
    // In the independent rates (ψ̇, θ̇, φ̇) about upright rolling at spin W, with A = m·r²/4
    // and C = m·r²/2 the disk's moments: (A + m·r²)·δθ̈ = m·g·r·δθ − (C + m·r²)·W·δψ̇ and
    // A·δψ̈ = C·W·δθ̇, so that δθ̈ = (4/5·g/r − 12/5·W²)·δθ + const: upright rolling holds
    // (marginally) when W² > g/(3·r).
    let source = example("space/rolling_coin.lag");
    let l = linearize(&source, &Options::default()).expect("linearizes");
    assert!(l.exact_reference);
    let rates = l.linearization.in_rates().expect("in the independent rates");
    assert_eq!(rates.rates.len(), 3);
    assert_eq!(l.linearization.cyclic, [true, true, true, false, true]);
    assert_eq!(l.state, ["theta", "psi'", "theta'", "phi'"]);
    assert_eq!(exact(&l, &l.stiffness), [["0"], ["-4/5*g/r"], ["0"]]);
    let (g, r, w) = (9.81_f64, 0.02_f64, 15.0_f64);
    let omega = (12.0 / 5.0 * w * w - 4.0 / 5.0 * g / r).sqrt();
    assert_eq!(l.at.stability, Stability::MarginallyStable);
    let e = &l.at.eigenvalues;
    assert!(close(e[0].1, omega, 1e-12), "{e:?} against {omega}");

    let critical = (g / (3.0 * r)).sqrt();
    for (range, from, to) in [
        ("W=0:30:7", Stability::Unstable, Stability::MarginallyStable),
        ("W=25:1:5", Stability::MarginallyStable, Stability::Unstable),
    ] {
        let options = Options { sweep: Some(range.into()), ..Default::default() };
        let l = linearize(&source, &options).expect("linearizes");
        let sweep = l.sweep.expect("a sweep");
        assert_eq!(sweep.changes.len(), 1, "{:?}", sweep.changes);
        let change = sweep.changes[0];
        assert_eq!((change.from, change.to), (from, to));
        assert!(close(change.value, critical, 1e-8), "{} against {critical}", change.value);
    }
}

#[test]
fn the_chaplygin_sleigh_is_stable_with_its_centre_ahead_of_the_blade() {
    // (I + m·a²)·δθ̈ = −m·a·v·δθ̇ about gliding straight on at speed v: a turn dies out at the
    // rate m·a·v/(I + m·a²) with the centre of mass ahead (a > 0), grows behind (a < 0). The
    // heading and the speed are neutral (neighbouring straight glides are steady too): two
    // zeros of first integrals, which the verdict leaves aside, so ahead is stable.
    let source = example("classics/chaplygin_sleigh.lag");
    let rate = |a: f64| 1.0 * a * 1.0 / (0.1 + 1.0 * a * a);
    for (a, stability) in [(0.2, Stability::Stable), (-0.2, Stability::Unstable)] {
        let options = Options { set: vec![format!("a={a}")], ..Default::default() };
        let l = linearize(&source, &options).expect("linearizes");
        assert_eq!(l.at.stability, stability, "a = {a}");
        assert_eq!(l.at.first_integrals, 2, "a = {a}");
        assert_eq!(l.state, ["theta", "x'", "theta'"]);
        let e = &l.at.eigenvalues;
        let moving: Vec<f64> = e.iter().map(|z| z.0).filter(|re| *re != 0.0).collect();
        assert_eq!(moving.len(), 1, "{e:?}");
        assert!(close(moving[0], -rate(a), 1e-12), "{e:?} against {}", -rate(a));
        assert!(e.iter().all(|z| z.1 == 0.0), "{e:?}");
    }
    let l = about(&source, "theta = 0, x' = v");
    assert_eq!(exact(&l, &l.damping), [["0", "0"], ["0", "m*a*v"]]);
    assert_eq!(exact(&l, &l.mass), [["1", "0"], ["0", "I + m*a^2"]]);
    // A velocity constraint's dependent rate is not the reference's to give, and a position
    // the equations need is.
    let options = Options { about: Some("theta = 0, y' = 1".into()), ..Default::default() };
    let error = linearize(&source, &options).err().expect("y' is dependent").to_string();
    assert!(error.contains("follows from the velocity constraints"), "{error}");
    let options = Options { about: Some("theta' = 1".into()), ..Default::default() };
    let error = linearize(&source, &options).err().expect("θ turns").to_string();
    assert!(error.contains("does not stay put"), "{error}");
}

/// Upright on its cart the pendulum falls: one eigenvalue is +√((M + m)·g/(M·L)).
#[test]
fn the_inverted_pendulum_on_a_cart_is_unstable() {
    let l = linearize(&example("classics/inverted_pendulum_on_cart.lag"), &Options::default())
        .expect("linearizes about its own line");
    assert_eq!(l.at.stability, Stability::Unstable);
    assert_eq!(exact(&l, &l.stiffness), [["0", "0"], ["0", "-m*L*g"]]);
    let (big, m, length, g) = (2.0_f64, 1.0, 1.0, 9.81);
    let growth = ((big + m) * g / (big * length)).sqrt();
    let e = &l.at.eigenvalues;
    assert!(close(e[0].0, growth, 1e-12) && e[0].1 == 0.0, "{e:?}");
    assert!(e.iter().any(|(re, im)| close(*re, -growth, 1e-12) && *im == 0.0), "{e:?}");
}

#[test]
fn position_and_velocity_constraints_kept_together_reduce_in_numbers() {
    // A Chaplygin sleigh and, beside it, a pendulum in Cartesian coordinates on its rod (kept
    // with a multiplier), its weight a potential (the sleigh glides on a level floor): two
    // systems that do not touch, so the small motions are each one's.
    // The sleigh's turn dies out at m·a·v/(I + m·a²); the bob swings at √(g/L).
    let source = "
param m = 1 kg, I = 0.1 kg*m^2, a = 0.2 m, v = 1 m/s, mb = 2 kg, L = 1.5 m, g = 9.81 m/s^2
coord x = 0, x' = v
coord y = 0
coord theta = 0, theta' = 0
coord u = 0, w = -L
body sleigh { mass m; inertia I; position (x + a*cos(theta), y + a*sin(theta)); angle theta }
particle bob { mass mb; position (u, w) }
constraint blade: y'*cos(theta) = x'*sin(theta)
constraint rod: u^2 + w^2 = L^2
potential mb*g*w                   # the bob's weight alone: the sleigh glides on a level floor
linearize about theta = 0, x' = v, u = 0, w = -L
";
    let l = about(source, "theta = 0");
    assert!(l.linearization.kept().is_some());
    let (positions, rates) = l.at.reduced().expect("reduced in numbers");
    let name = |i: &usize| l.derivation.model.pool.symbol(l.linearization.coords[*i]).name.clone();
    // The rod's row fixes w, the blade's y'; the heading θ is ignorable at first order (no
    // force depends on it, and no rate kept), as x and y are.
    assert_eq!(positions.iter().map(name).collect::<Vec<_>>(), ["u"]);
    assert_eq!(rates.iter().map(name).collect::<Vec<_>>(), ["x", "theta", "u"]);
    let (m, i, a, v) = (1.0, 0.1, 0.2, 1.0);
    let turning = -(m * a * v) / (i + m * a * a);
    let swing = (9.81f64 / 1.5).sqrt();
    let e = &l.at.eigenvalues;
    assert_eq!(e.len(), 4, "{e:?}");
    assert!(e.iter().any(|z| close(z.0, turning, 1e-12) && z.1 == 0.0), "{e:?}");
    assert!(e.iter().any(|z| z.0.abs() < 1e-12 && close(z.1, swing, 1e-12)), "{e:?}");
    assert!(e.iter().any(|z| z.0.abs() < 1e-12 && close(z.1, -swing, 1e-12)), "{e:?}");
    // The forward speed is a first integral.
    assert_eq!(l.at.first_integrals, 1, "{e:?}");
    assert_eq!(l.at.stability, Stability::MarginallyStable);
    // The rod's tension holds the bob up; the blade pushes nothing sideways in a straight glide.
    assert!(close(l.at.multipliers[1], -2.0 * 9.81 / (2.0 * 1.5), 1e-12), "{:?}", l.at.multipliers);
    // A dependent rate is the constraints' to give.
    let error = linearize(source, &Options { about: Some("y' = 1".into()), ..Default::default() })
        .err()
        .expect("refused");
    assert!(error.to_string().contains("follows from the kept constraints"), "{error}");
}

/// A scene of `tests/scenes`.
fn test_scene(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_sliding_top_linearizes_at_every_spin_and_wakes_at_its_critical_spin() {
    // Its tip slides, so it tilts about its centre of mass: A·s² − i·C·w·s − m·g·l = 0, roots
    // on the imaginary axis above w = 2·sqrt(A·m·g·l)/C (A about the centre of mass).
    let source = test_scene("sliding_top.lag");
    let (m, g, l_, a, c) = (0.5_f64, 9.81_f64, 0.04_f64, 0.0004_f64, 0.0006_f64);
    let critical = 2.0 * (a * m * g * l_).sqrt() / c;
    for w in [25.0, 29.6, 59.0] {
        let options = Options { set: vec![format!("w={w}")], ..Default::default() };
        let l = linearize(&source, &options).unwrap_or_else(|e| panic!("at w = {w}: {e}"));
        let expected = if w < critical { Stability::Unstable } else { Stability::MarginallyStable };
        assert_eq!(l.at.stability, expected, "at w = {w}: {:?}", l.at.eigenvalues);
        // The tilting roots: s = i·C·w/(2·A) ± sqrt(m·g·l/A − (C·w/(2·A))²).
        let half = c * w / (2.0 * a);
        let square = m * g * l_ / a - half * half;
        let largest_re = l.at.eigenvalues.iter().map(|z| z.0).fold(f64::NEG_INFINITY, f64::max);
        let expected_re = square.max(0.0).sqrt();
        assert!((largest_re - expected_re).abs() <= 1e-9 * half, "at w = {w}: {largest_re}");
    }
    let options = Options { sweep: Some("w=0:60:7".into()), ..Default::default() };
    let l = linearize(&source, &options).expect("the sweep goes through");
    let sweep = l.sweep.expect("a sweep");
    assert_eq!(sweep.rows.len(), 7);
    assert_eq!(sweep.changes.len(), 1, "{:?}", sweep.changes);
    assert!(close(sweep.changes[0].value, critical, 1e-8), "{:?}", sweep.changes);
    let checked = cli::check::check_file("sliding_top.lag", &source);
    assert_eq!((checked.failed, checked.exit_code), (0, 0), "{}", checked.report);
}

#[test]
fn the_reference_is_judged_at_the_parameters_in_force() {
    // The scene turns the ellipse at w = 4, where the bead's off-bottom rest does not exist
    // (acos of 109/80); at w = 6 it does, and --set says so.
    let source = test_scene("bead_on_turning_ellipse.lag");
    let rest = "theta = acos(g*b/(w^2*a^2))";
    let options =
        Options { set: vec!["w=6".into()], about: Some(rest.into()), ..Default::default() };
    let l = linearize(&source, &options).unwrap_or_else(|e| panic!("at w = 6: {e}"));
    assert_eq!(l.at.stability, Stability::MarginallyStable);
    // M = m·(a²·c² + b²·(1 − c²)), K = m·a²·w²·(1 − c²), c = cos θ = g·b/(w²·a²).
    let (g, a, b, w) = (9.81_f64, 0.3_f64, 0.2_f64, 6.0_f64);
    let cos = g * b / (w * w * a * a);
    let omega = (a * a * w * w * (1.0 - cos * cos)
        / (a * a * cos * cos + b * b * (1.0 - cos * cos)))
        .sqrt();
    assert!(close(l.at.eigenvalues[0].1, omega, 1e-10), "{:?} against {omega}", l.at.eigenvalues);

    // Swept, it is judged at each value (and at the values of the report above the sweep,
    // w = 6 here): where the rest does not exist, the error says so at the item, with the
    // value.
    let options = Options {
        set: vec!["w=6".into()],
        sweep: Some("w=3:6:4".into()),
        about: Some(rest.into()),
        ..Default::default()
    };
    let err = linearize(&source, &options).err().expect("no rest at w = 3");
    assert_eq!(err.exit_code(), 2);
    let text = cli::diagnostics::error("bead.lag", &err);
    assert!(text.contains("this reference is not a real number (at w = 3)"), "{text}");
    assert!(text.contains("(from --about)") && text.contains('^'), "{text}");
    let options = Options {
        set: vec!["w=6".into()],
        sweep: Some("w=5:7:3".into()),
        about: Some(rest.into()),
        ..Default::default()
    };
    let l = linearize(&source, &options).expect("a rest at every value");
    assert!(l
        .sweep
        .expect("a sweep")
        .rows
        .iter()
        .all(|r| r.stability == Stability::MarginallyStable));
    // A parameter defined through the one set changes with it.
    let through = source.replace("w = 4 rad/s", "w = 4 rad/s, turn = w");
    let options = Options {
        set: vec!["w=6".into()],
        about: Some("theta = acos(g*b/(turn^2*a^2))".into()),
        ..Default::default()
    };
    let l = linearize(&through, &options).unwrap_or_else(|e| panic!("through w: {e}"));
    assert!(close(l.at.eigenvalues[0].1, omega, 1e-10), "{:?}", l.at.eigenvalues);
    // --set leaves the scene's value, and the scene's check of it, where it does not reach.
    let options = Options { about: Some(rest.into()), ..Default::default() };
    let err = linearize(&source, &options).err().expect("no rest at the scene's w = 4");
    assert!(err.to_string().contains("acos"), "{err}");
}

#[test]
fn a_stiff_stable_system_is_stable_and_a_stiff_undamped_one_marginally_stable() {
    // Roots −1 and −1e9: the slow one is judged on its own rounding.
    let stiff =
        linearize(&test_scene("stiff_damper.lag"), &Options::default()).expect("linearizes");
    assert_eq!(stiff.at.stability, Stability::Stable, "{:?}", stiff.at.eigenvalues);
    let slow = stiff.at.eigenvalues.iter().map(|z| z.0).fold(f64::NEG_INFINITY, f64::max);
    assert!((slow + 1.0).abs() < 1e-6, "{slow}");
    let checked = cli::check::check_file("stiff_damper.lag", &test_scene("stiff_damper.lag"));
    assert_eq!((checked.failed, checked.exit_code), (0, 0), "{}", checked.report);

    // Stiffnesses 1 and 1e8, no damping: both modes on the imaginary axis, within their bounds.
    let chain = test_scene("stiff_undamped_chain.lag");
    let l = linearize(&chain, &Options::default()).expect("linearizes");
    assert_eq!(l.at.stability, Stability::MarginallyStable, "{:?}", l.at.eigenvalues);
    for (z, bound) in l.at.eigenvalues.iter().zip(&l.at.bounds) {
        assert!(z.0.abs() <= *bound && *bound < 1e-3 * z.1.abs(), "{z:?} within {bound}");
    }
    let checked = cli::check::check_file("chain.lag", &chain);
    assert_eq!((checked.failed, checked.exit_code), (0, 0), "{}", checked.report);
}

#[test]
fn check_refuses_a_reference_that_is_not_an_equilibrium_as_linearize_does() {
    let source = example("classics/simple_pendulum.lag");
    let scene = format!("{source}\nlinearize about theta = pi/2\nexpect linearized: unstable\n");
    let err = linearize(&scene, &Options::default()).err().expect("not an equilibrium");
    assert_eq!(err.exit_code(), 2);
    let checked = cli::check::check_file("pendulum.lag", &scene);
    assert_eq!(checked.exit_code, 2, "{}", checked.report);
    assert!(
        checked.report.contains("is not an equilibrium or a steady motion"),
        "{}",
        checked.report
    );
    let line = scene.lines().position(|l| l.starts_with("linearize about")).expect("line") + 1;
    assert!(checked.report.contains(&format!("pendulum.lag:{line}:1")), "{}", checked.report);
}

#[test]
fn a_misspelt_critical_parameter_gets_a_did_you_mean() {
    let source = example("space/sleeping_top.lag").replace("critical w =", "critical ww =");
    let err = engine::load(&source).err().expect("not a parameter");
    let text = cli::diagnostics::error("top.lag", &err);
    assert!(text.contains("`ww` is not a parameter"), "{text}");
    assert!(text.contains("did you mean `w`?"), "{text}");
    let source = example("space/sleeping_top.lag").replace("critical w =", "critical spin =");
    let text = cli::diagnostics::error("top.lag", &engine::load(&source).err().expect("refused"));
    assert!(text.contains("the parameters are m, g, l, A, C, w"), "{text}");
}

#[test]
fn a_complex_eigenvalue_is_written_with_a_minus_sign() {
    let source = example("classics/simple_pendulum.lag");
    let scene =
        format!("{source}\nlinearize about theta = 0\nexpect linearized: eigenvalue = (0, -5)\n");
    let checked = cli::check::check_file("pendulum.lag", &scene);
    assert_eq!(checked.exit_code, 1, "{}", checked.report);
    assert!(checked.report.contains("the nearest eigenvalue is 0 − 3.13"), "{}", checked.report);
    assert!(!checked.report.contains("+ -"), "{}", checked.report);
}
