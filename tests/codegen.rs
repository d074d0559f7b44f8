//! The Rust that `lagrange codegen` writes, for every example: it compiles with plain
//! `rustc`, its functions agree with the tape to 1e-12 relative, its `rhs` and `jacobian`
//! with those of `sim::Mechanical` (kept constraints Baumgarte-stabilised in both, as a run
//! holds them) to 1e-9, and its `inverse_dynamics` with `engine::inverse`'s to 1e-12. The
//! scenes with contacts are among them, every contact open in both (`Mechanical` with its
//! contacts, as a run starts them).

use std::fmt::Write;

use numeric::Tape;
use sim::Problem;

/// Deterministic, varied input values: not special angles, not zero.
fn inputs(len: usize, seed: usize) -> Vec<f64> {
    (0..len).map(|i| 0.3 + 0.37 * ((i * 7 + seed * 13) % 11) as f64 / 11.0).collect()
}

/// The time at which the Jacobians are compared.
const TIME: f64 = 0.25;

/// (q̇, q̈) and ∂(q̇, q̈)/∂(q, q̇) of the module's scene at `y` by `sim::Mechanical`, as a run
/// has them; `None` where the system is singular there.
fn mechanical_rhs_and_jacobian(
    module: &mut export::codegen::Module,
    y: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let mut mechanical = lagrange_tests::mechanical(&mut module.prepared, &module.parameters);
    // The contacts open, as a run starts them and as the module holds them.
    let contacts = lagrange_tests::contacts(&module.prepared, &module.parameters);
    if !contacts.is_empty() {
        mechanical = mechanical.with_contacts(contacts);
    }
    let mut dy = vec![0.0; y.len()];
    mechanical.rhs(TIME, y, &mut dy).ok()?;
    let mut jac = vec![0.0; y.len() * y.len()];
    mechanical.jacobian(TIME, y, &mut jac).ok()?;
    Some((dy, jac))
}

/// A call of the module's `inverse_dynamics` at a varied motion, printing τ, with what
/// `engine::inverse` gives there appended to `expected`; none where the engine finds the
/// forces undetermined (a singular mass matrix at these values).
fn inverse_dynamics_call(
    main: &mut String,
    expected: &mut Vec<(f64, f64)>,
    k: usize,
    source: &str,
    declared: &str,
) {
    let mut inverse = engine::inverse::inverse_dynamics(source, &Default::default()).unwrap();
    let n = inverse.coordinates().len();
    let motion = inputs(3 * n, k + 1);
    let (q, rest) = motion.split_at(n);
    let (rates, accelerations) = rest.split_at(n);
    let mut tau = vec![0.0; n];
    if inverse.torques(0.4, q, rates, accelerations, &mut tau).is_err() {
        return;
    }
    expected.extend(tau.iter().map(|v| (*v, 1e-12)));
    let list = |v: &[f64]| v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ");
    let _ = writeln!(
        main,
        "    {{ let mut tau = [0.0; {n}]; assert!(m{k}::inverse_dynamics(0.4, &[{}], &[{}], &[{}], &m{k}::PARAMETERS, &{declared}, &mut tau)); for v in tau {{ println!(\"{{v:?}}\"); }} }}",
        list(q),
        list(rates),
        list(accelerations),
    );
}

#[test]
fn generated_code_compiles_and_matches_the_tape() {
    let dir = std::env::temp_dir().join(format!("lagrange-codegen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut main = String::from("fn main() {\n");
    let mut modules = String::new();
    // Each value the generated program prints, with how closely it must agree.
    let mut expected: Vec<(f64, f64)> = Vec::new();
    let mut jacobians = 0;
    // The contact scenes too, their contacts open (tests/codegen_contacts.rs tests the impact
    // map); `engine::inverse` refuses them, so their inverse dynamics is left out here. Code
    // generation refuses Coulomb friction (tested below), so the rough scenes are left out.
    // And a chain long enough that `rhs` takes the recursive form's `accelerations`.
    let chain = lang::generate::n_link(lang::generate::Family::PendulumOnCart, 9);
    let scenes = lagrange_tests::examples()
        .into_iter()
        .filter(|(_, s)| !lagrange_tests::has_friction(s))
        .chain([("generated/pendulum_on_cart_9.lag".to_string(), chain)]);
    for (k, (rel, source)) in scenes.enumerate() {
        let mut module =
            export::codegen::codegen(&rel, &source).unwrap_or_else(|e| panic!("{rel}: {e}"));
        if rel.starts_with("generated/") {
            assert!(module.programs.iter().any(|(name, _)| name == "accelerations"), "{rel}");
        }
        std::fs::write(dir.join(format!("m{k}.rs")), &module.source).unwrap();
        let _ = writeln!(modules, "#[path = \"m{k}.rs\"]\nmod m{k};");
        for (name, program) in &module.programs {
            let input = inputs(program.inputs, k);
            let mut out = vec![0.0; program.outputs.len()];
            Tape::new(program.clone()).eval(&input, &mut out);
            expected.extend(out.iter().map(|v| (*v, 1e-12)));
            let literals: Vec<String> = input.iter().map(|v| format!("{v:?}")).collect();
            let _ = writeln!(
                main,
                "    {{ let mut out = [0.0; {}]; m{k}::{name}(&[{}], &mut out); for v in out {{ println!(\"{{v:?}}\"); }} }}",
                out.len(),
                literals.join(", ")
            );
        }
        // The Jacobian comes through another solver, so agreement is to its rounding.
        let y = inputs(2 * module.prepared.layout.coordinates, k + 1);
        // The inputs at their declared values, as the tape's parameter slots hold them.
        let declared = if module.prepared.derivation.model.inputs.is_empty() {
            "[]".to_string()
        } else {
            format!("m{k}::INPUTS")
        };
        if let Some((dy, jac)) = mechanical_rhs_and_jacobian(&mut module, &y) {
            jacobians += 1;
            expected.extend(dy.iter().map(|v| (*v, 1e-9)));
            expected.extend(jac.iter().map(|v| (*v, 1e-9)));
            let literals: Vec<String> = y.iter().map(|v| format!("{v:?}")).collect();
            let _ = writeln!(
                main,
                "    {{ let mut dy = [0.0; {}]; assert!(m{k}::rhs({TIME:?}, &[{}], &m{k}::PARAMETERS, &{declared}, &mut dy)); for v in dy {{ println!(\"{{v:?}}\"); }} }}",
                dy.len(),
                literals.join(", ")
            );
            let _ = writeln!(
                main,
                "    {{ let mut jac = [0.0; {}]; assert!(m{k}::jacobian({TIME:?}, &[{}], &m{k}::PARAMETERS, &{declared}, &mut jac)); for v in jac {{ println!(\"{{v:?}}\"); }} }}",
                jac.len(),
                literals.join(", ")
            );
        }
        if module.prepared.contacts.is_empty() {
            inverse_dynamics_call(&mut main, &mut expected, k, &source, &declared);
        }
    }
    main.push_str("}\n");
    std::fs::write(dir.join("main.rs"), format!("{modules}\n{main}")).unwrap();
    let text = lagrange_tests::compile_and_run_rust(&dir.join("main.rs"), &dir.join("generated"));
    let got: Vec<f64> = text.lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(got.len(), expected.len());
    for (i, (g, (e, tolerance))) in got.iter().zip(&expected).enumerate() {
        let scale = g.abs().max(e.abs()).max(1.0);
        assert!((g - e).abs() <= tolerance * scale, "value {i}: generated {g}, tape {e}");
    }
    assert!(jacobians >= 20, "only {jacobians} Jacobians compared");
    let _ = std::fs::remove_dir_all(&dir);
}
