//! Rigid bodies in space: the identities of vectors and rotations hold exactly (and a wrong
//! copy of each fails), the heavy top's equations are the textbook's, and simulations keep
//! what the physics conserves: the top's spin, a tumbling body's energy and angular momentum
//! through its flips.

use cli::simulate::summary;
use simulation::{simulate, Options, Outcome};

fn scene(rel: &str) -> (String, String) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    (rel.to_string(), std::fs::read_to_string(&path).expect("scene"))
}

#[test]
fn identities_of_vectors_and_rotations_hold_and_wrong_copies_fail() {
    let (path, source) = scene("scenes/vectors_and_rotations.lag");
    let result = cli::check::check_file(&path, &source);
    assert_eq!(result.exit_code, 0, "{}", result.report);
    assert_eq!(result.held, 12, "{}", result.report);
    // Each identity with one entry of its right-hand side changed must fail.
    let wrong = [
        ("(0, 0, 1)\n", "(0, 0, -1)\n"),
        ("= 5*L^2", "= 4*L^2"),
        ("rotz(a)\n", "rotx(a)\n"),
        ("= (0, 1, 0)", "= (0, 0, 1)"),
        ("[1, 0, 0; 0, 1, 0; 0, 0, 1]", "[1, 0, 0; 0, 1, 0; 0, 0, -1]"),
        ("= rod.omega\n", "= rod.omega_body\n"),
        ("= cross(rod.omega, rod.position)", "= cross(rod.position, rod.omega)"),
        ("w.z, 0, -w.x", "w.z, 0, w.x"),
    ];
    for (right, wrong) in wrong {
        assert_eq!(source.matches(right).count(), 1, "`{right}` is not one place");
        let mutated = source.replacen(right, wrong, 1);
        let result = cli::check::check_file_with(&path, &mutated, engine::Options { units: false });
        assert_eq!(result.failed, 1, "`{wrong}` still passes:\n{}", result.report);
    }
}

#[test]
fn the_heavy_top_has_the_textbook_mass_matrix_and_spin() {
    let (_, source) = lagrange_tests::examples()
        .into_iter()
        .find(|(p, _)| p.ends_with("space/heavy_top.lag"))
        .expect("the heavy top");
    let d = engine::load(&source).expect("derives").derivation;
    let pool = &d.model.pool;
    let print = |pool: &cas::Pool, e| pool.print(e, cas::Style::Ascii);
    let m = d.mass_matrix.clone();
    assert_eq!(print(pool, m[1][1]), "A + m*l^2");
    assert_eq!(print(pool, m[2][2]), "C");
    assert_eq!(print(pool, m[0][2]), "C*cos(theta)");
    assert_eq!(print(pool, m[0][1]), "0");
    // ψ is cyclic: its momentum C·(ψ' + φ'·cos θ) is the last row's whole content.
    let psi_row: Vec<String> = m[2].iter().map(|e| print(pool, *e)).collect();
    assert_eq!(psi_row, ["C*cos(theta)", "0", "C"]);
}

fn run(rel: &str, options: Options) -> Outcome {
    let (_, source) = lagrange_tests::examples()
        .into_iter()
        .find(|(p, _)| p.ends_with(rel))
        .unwrap_or_else(|| panic!("no example {rel}"));
    let outcome = simulate(&source, &options).unwrap_or_else(|e| panic!("{e}"));
    assert!(outcome.run.fault.is_none(), "{}", summary(&outcome));
    outcome
}

fn column(outcome: &Outcome, i: usize) -> Vec<f64> {
    outcome.run.trajectory.rows.iter().map(|r| r[i]).collect()
}

fn spread(v: &[f64]) -> f64 {
    let max = v.iter().copied().fold(f64::MIN, f64::max);
    let min = v.iter().copied().fold(f64::MAX, f64::min);
    max - min
}

#[test]
fn the_heavy_top_keeps_its_spin_and_energy_and_precesses_steadily() {
    let outcome = run(
        "space/heavy_top.lag",
        Options {
            until: Some(3.0),
            tolerance: Some(1e-12),
            output: vec!["psi' + phi'*cos(theta), theta, KE + PE".into()],
            ..Options::default()
        },
    );
    let spin = column(&outcome, 0);
    assert!((spin[0] - 60.0).abs() < 1e-12);
    assert!(spread(&spin) < 1e-9 * spin[0].abs(), "spin drifts by {}", spread(&spin));
    // Released at the steady precession rate, it precesses without nodding: θ stays.
    let theta = column(&outcome, 1);
    assert!(spread(&theta) < 1e-8, "θ moves by {:e}", spread(&theta));
    let energy = column(&outcome, 2);
    assert!(spread(&energy) < 1e-9 * energy[0].abs(), "energy drifts by {}", spread(&energy));
}

#[test]
fn a_body_spun_about_its_intermediate_axis_flips_and_conserves_energy_and_momentum() {
    let outcome = run("space/tennis_racket.lag", Options::default());
    // Outputs: w.y, H.x, H.y, H.z, KE.
    let spin = column(&outcome, 0);
    assert!((spin[0] - 2.0).abs() < 1e-12);
    let flipped = spin.iter().position(|w| *w < -1.9).expect("the spin reverses");
    assert!(spin[flipped..].iter().any(|w| *w > 1.9), "and comes back");
    for (i, scale) in [(1, 4.0), (2, 4.0), (3, 4.0), (4, 4.0)] {
        let v = column(&outcome, i);
        assert!(spread(&v) < 1e-9 * scale, "column {i} drifts by {:e}", spread(&v));
    }
    assert!((column(&outcome, 2)[0] - 4.0).abs() < 1e-12, "H = B·ω = 2·2 along y");
}

#[test]
fn a_ball_on_a_turntable_circles_at_two_sevenths_of_its_rate() {
    // W = 1/s: the centre's circle takes 7π/W.
    let period = 7.0 * std::f64::consts::PI;
    let outcome = run(
        "space/ball_on_turntable.lag",
        Options {
            until: Some(period),
            tolerance: Some(1e-12),
            output: vec!["x, y".into()],
            ..Options::default()
        },
    );
    let (x, y) = (column(&outcome, 0), column(&outcome, 1));
    let last = x.len() - 1;
    assert!((x[last] - 0.3).abs() < 1e-8 && y[last].abs() < 1e-8, "({}, {})", x[last], y[last]);
    // Half-way round it is across the circle, whose centre is where the start's velocity and
    // rolling put it: (−0.05, 0), radius 0.35.
    let half = x.len() / 2;
    assert!((x[half] + 0.4).abs() < 1e-2, "x at half a period: {}", x[half]);
    let radius: Vec<f64> =
        x.iter().zip(&y).map(|(x, y)| ((x + 0.05) * (x + 0.05) + y * y).sqrt()).collect();
    assert!(spread(&radius) < 1e-9, "the path is not a circle: {:e}", spread(&radius));
    let drift = outcome.constraint_drift().expect("kept constraints");
    assert!(drift < 1e-9, "drift {drift:e}");
}

#[test]
fn the_rolling_disk_by_rates_derives_as_by_positions() {
    let (_, by_positions) = lagrange_tests::examples()
        .into_iter()
        .find(|(p, _)| p.ends_with("ps5/rolling_disk.lag"))
        .expect("the disk");
    let (_, by_rates) = scene("scenes/rolling_disk_by_rates.lag");
    assert!(by_rates.contains("r*phi' = R*theta'"));
    let equations = |source: &str| {
        let mut d = engine::load(source).expect("derives").derivation;
        let eqs = d.equations();
        let pool = &d.model.pool;
        let m: Vec<String> =
            d.mass_matrix.iter().flatten().map(|e| pool.print(*e, cas::Style::Ascii)).collect();
        let f: Vec<String> = d.forcing.iter().map(|e| pool.print(*e, cas::Style::Ascii)).collect();
        let e: Vec<String> = eqs
            .iter()
            .map(|q| {
                format!(
                    "{} = {}",
                    pool.print(q.lhs, cas::Style::Ascii),
                    pool.print(q.rhs, cas::Style::Ascii)
                )
            })
            .collect();
        (m, f, e)
    };
    assert_eq!(equations(&by_rates), equations(&by_positions));
}

/// The equations in the independent rates hold wherever the multiplier form's accelerations
/// do: at states on the constraint surface (dependent rates from the constraints), q̈ and λ
/// solved from M·q̈ − Jᵀ·λ = f, J·q̈ = γ make each of them vanish.
#[test]
fn the_independent_rates_form_agrees_with_the_multipliers() {
    let source = std::fs::read_to_string(
        lagrange_tests::examples_dir().join("classics/chaplygin_sleigh.lag"),
    )
    .expect("the sleigh");
    let mut d = engine::load(&source).expect("derives").derivation;
    let form = d.independent_form().expect("a velocity constraint and no force asked for");
    assert_eq!(form.independent.len(), 2);
    assert_eq!(form.dependent.len(), 1);
    let (rows, rhs) = d.system();
    let pool = &d.model.pool;
    let mut values = vec![0.0; pool.symbol_count()];
    for p in &d.model.params {
        values[p.sym.index()] = numeric::eval(pool, p.value.expect("valued"), &values);
    }
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..20 {
        for s in d.coords.iter().chain(&d.rates) {
            values[s.index()] = next();
        }
        for (r, e) in &form.dependent {
            values[r.index()] = numeric::eval(pool, *e, &values);
        }
        let size = rhs.len();
        let a: Vec<f64> = rows.iter().flatten().map(|e| numeric::eval(pool, *e, &values)).collect();
        let b: Vec<f64> = rhs.iter().map(|e| numeric::eval(pool, *e, &values)).collect();
        let x = nalgebra::DMatrix::from_row_slice(size, size, &a)
            .lu()
            .solve(&nalgebra::DVector::from_vec(b))
            .expect("regular");
        for (s, v) in d.unknowns().iter().zip(x.iter()) {
            values[s.index()] = *v;
        }
        for e in &form.equations {
            let r = numeric::eval(pool, *e, &values);
            assert!(r.abs() < 1e-9, "residual {r:e}");
        }
    }
}

/// Issue 11's bar: a body oriented by Euler parameters tumbles through a hundred flips with
/// its energy kept to 1e-9 at tolerance 1e-12.
#[test]
fn a_tumbling_body_flips_a_hundred_times_and_keeps_its_energy() {
    let outcome = run(
        "space/tennis_racket.lag",
        Options {
            until: Some(1100.0),
            tolerance: Some(1e-12),
            samples: 20000,
            output: vec!["w.y".into()],
            ..Options::default()
        },
    );
    let spin = column(&outcome, 0);
    let flips = spin.windows(2).filter(|w| (w[0] > 0.0) != (w[1] > 0.0)).count();
    assert!(flips >= 100, "only {flips} flips");
    let (_, relative) = outcome.energy_drift();
    assert!(relative < 1e-9, "energy drift {relative:e}");
}

#[test]
fn a_singular_angle_set_is_named_when_simulate_meets_it() {
    let (_, source) = lagrange_tests::examples()
        .into_iter()
        .find(|(p, _)| p.ends_with("space/heavy_top.lag"))
        .expect("the top");
    let options = Options {
        set: vec!["theta=0".parse().expect("name=value")],
        until: Some(1.0),
        ..Options::default()
    };
    let outcome = simulate(&source, &options).expect("runs until the fault");
    let fault = outcome.run.fault.as_ref().expect("the mass matrix is singular at θ = 0");
    let text = outcome.describe_fault(fault);
    assert!(text.contains("the orientation angles are singular here"), "{text}");
    assert!(text.contains("`top`"), "{text}");
    assert!(outcome.run.trajectory.rows.iter().flatten().all(|x| x.is_finite()));
}

/// A thin coin rolling upright is stable when its spin Ω has Ω² > g/(3·r): 163.5/s² here, so
/// Ω = 15/s keeps it up and Ω = 5/s lets it fall. `--set` of the spin re-solves the rolling
/// rates, so both runs start on the constraints and keep their energy.
#[test]
fn a_fast_coin_rolls_on_and_a_slow_one_falls() {
    let lean_of = |spin: &str| {
        let outcome = run(
            "space/rolling_coin.lag",
            Options {
                set: vec![format!("phi'={spin}").parse().expect("name=value")],
                tolerance: Some(1e-11),
                output: vec!["theta".into()],
                ..Options::default()
            },
        );
        let (_, relative) = outcome.energy_drift();
        assert!(relative < 1e-8, "energy drift {relative:e} at spin {spin}");
        let drift = outcome.constraint_drift().expect("kept constraints");
        assert!(drift < 1e-8, "constraint drift {drift:e} at spin {spin}");
        column(&outcome, 0).into_iter().fold(0.0, f64::max)
    };
    let fast = lean_of("15");
    assert!(fast < 0.5, "the fast coin leans to {fast}");
    let slow = lean_of("5");
    assert!(slow > 1.0, "the slow coin only leans to {slow}");
}
