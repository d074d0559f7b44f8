//! Every command resolves its scene once: the entry each front end calls (`derive`, `check`,
//! `simulate`, `ensemble`, `linearize` (`--along` too), `inverse-dynamics`, `codegen`, `export --fmu`) counted
//! with `model::resolutions_on_this_thread`. A second resolution costs a short run's set-up
//! again and may read the scene differently from the first (a `simulate` block read from one,
//! the equations derived from another).

use lagrange_tests::example;

/// The scene resolutions `command` makes on this thread.
fn resolutions<T>(command: impl FnOnce() -> T) -> usize {
    let before = model::resolutions_on_this_thread();
    command();
    model::resolutions_on_this_thread() - before
}

#[test]
fn derive_and_check_resolve_once() {
    let rod = example("ps5/falling_rod.lag");
    assert_eq!(resolutions(|| engine::load(&rod).expect("derives")), 1, "derive");
    // Scenes with `expect linearized:` lines, which `check` decides against a linearization:
    // an eigenvalue, and a critical spin found by a sweep about it.
    for path in ["classics/inverted_pendulum_on_cart.lag", "space/sleeping_top.lag"] {
        let scene = example(path);
        let options = engine::Options::default();
        let checked = resolutions(|| {
            let result = cli::check::check_file_with(path, &scene, options);
            assert_eq!(result.failed, 0, "{}", result.report);
            assert!(result.held > 0, "{}", result.report);
        });
        assert_eq!(checked, 1, "check {path}");
    }
}

#[test]
fn a_run_resolves_once() {
    let pendulum = example("classics/double_pendulum.lag");
    let options = simulation::Options {
        until: Some(0.5),
        set: engine::input::assignments(&["m1=2"]).expect("an assignment"),
        ..Default::default()
    };
    let ran = resolutions(|| simulation::simulate(&pendulum, &options).expect("runs"));
    assert_eq!(ran, 1, "simulate");

    let vary = engine::input::varies(&["m1=1:2:3"]).expect("a grid");
    let options = ensemble::Options {
        simulate: simulation::Options { until: Some(0.2), ..Default::default() },
        vary,
        runs: None,
        seed: 1,
        record: Vec::new(),
    };
    let ensemble = resolutions(|| {
        ensemble::ensemble_with(&pendulum, &options, Some(1), &mut ()).expect("runs")
    });
    assert_eq!(ensemble, 1, "ensemble");
}

#[test]
fn an_orbit_resolves_once() {
    let pendulum = example("orbits/driven_pendulum.lag");
    let options = orbit::Options {
        run: simulation::Options::default(),
        section: orbit::Section::Period("2*pi/w".into()),
        swaps: Vec::new(),
        shifts: Vec::new(),
        ignore: Vec::new(),
        iterations: 30,
    };
    let found = resolutions(|| orbit::orbit(&pendulum, &options).expect("an orbit"));
    assert_eq!(found, 1, "orbit");
}

#[test]
fn linearize_and_inverse_dynamics_resolve_once() {
    let cart = example("classics/inverted_pendulum_on_cart.lag");
    let options = engine::linearize::Options::default();
    let linearized =
        resolutions(|| engine::linearize::linearize(&cart, &options).expect("linearizes"));
    assert_eq!(linearized, 1, "linearize");

    let pendulum = example("classics/double_pendulum.lag");
    let options = engine::inverse::Options::default();
    let inverse =
        resolutions(|| engine::inverse::inverse_dynamics(&pendulum, &options).expect("loads"));
    assert_eq!(inverse, 1, "inverse-dynamics");

    // Along a run: the run and the linearization share one resolution.
    let options = simulation::Options { until: Some(0.2), samples: 5, ..Default::default() };
    let along = resolutions(|| {
        simulation::along::linearize_run(&pendulum, &options).expect("linearizes along")
    });
    assert_eq!(along, 1, "linearize --along run");
    let along =
        resolutions(|| engine::along::along(&pendulum, &Default::default()).expect("loads"));
    assert_eq!(along, 1, "linearize --along FILE.csv");
}

#[test]
fn code_generation_resolves_once() {
    let pendulum = example("classics/double_pendulum.lag");
    let rust = resolutions(|| export::codegen::codegen("p.lag", &pendulum).expect("Rust"));
    assert_eq!(rust, 1, "codegen --lang rust");
    let c = resolutions(|| {
        export::codegen::c("p.lag", &pendulum, engine::Options::default()).expect("C")
    });
    assert_eq!(c, 1, "codegen --lang c");
    let options = export::fmu::ExportOptions::default();
    let fmu = resolutions(|| export::fmu::export("p.lag", &pendulum, &options).expect("an FMU"));
    assert_eq!(fmu, 1, "export --fmu");
}
