//! Runs side by side in lockstep (`sim::Lockstep`) against the same runs one at a time
//! (`sim::integrate`): every example, both adaptive explicit pairs, recording every step and
//! sampling the dense output, each run from its own start and at its own parameters. The
//! runs must be the same bits: the times and rows recorded, the counts of steps, rejections
//! and evaluations, the faults and the final states. And an ensemble in lockstep gives the
//! table, stops and failures included, that it gives one run at a time.

use std::ops::ControlFlow;

use ::ensemble::{Ensemble, Options};
use engine::input::Vary;
use engine::numbers::prepare;
use sim::{integrate, Event, Job, Lockstep, Method, Run, Settings};

/// More runs than lanes, and not a multiple of them: lanes fill, empty and idle.
const RUNS: usize = 19;

/// The bits of everything a run gives.
fn bits(run: &Run) -> Vec<u64> {
    let mut all: Vec<f64> = Vec::new();
    all.extend(&run.trajectory.times);
    run.trajectory.rows.iter().for_each(|r| all.extend(r));
    all.extend(&run.final_state);
    all.push(run.final_time);
    all.extend(run.peaks.iter());
    run.extremes.iter().for_each(|(a, b)| all.extend([a, b]));
    for count in [run.steps, run.rejected, run.evaluations, run.stiff_steps] {
        all.push(count as f64);
    }
    if let Some(fault) = &run.fault {
        all.push(fault.time);
        all.extend(&fault.state);
    }
    all.iter().map(|v| v.to_bits()).collect()
}

/// `RUNS` starts and parameter sets around the scene's own: each value moved by up to 5 %.
fn jobs(parameters: &[f64], y0: &[f64]) -> Vec<Job> {
    let nudge = |v: f64, k: usize, i: usize| {
        let wobble = ((k * 7 + i * 3) % 11) as f64 / 10.0 - 0.5;
        v * (1.0 + 0.1 * wobble) + 0.01 * wobble
    };
    (0..RUNS)
        .map(|k| Job {
            id: k,
            parameters: parameters.iter().enumerate().map(|(i, v)| nudge(*v, k, i)).collect(),
            state: y0.iter().enumerate().map(|(i, v)| nudge(*v, k, i + 17)).collect(),
        })
        .collect()
}

#[test]
fn every_example_runs_the_same_bits_in_lockstep_as_alone() {
    let mut compared = 0;
    // And a chain long enough that q̈ comes from the recursive form, in lanes as alone.
    let chain = lang::generate::n_link(lang::generate::Family::PendulumOnCart, 9);
    let scenes = lagrange_tests::examples()
        .into_iter()
        .chain([("generated/pendulum_on_cart_9".into(), chain)]);
    for (rel, source) in scenes {
        let mut prepared = prepare(&source, &[], engine::Options::default())
            .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let Ok(parameters) = prepared.parameter_values(&[]) else { continue };
        let Ok(y0) = prepared.initial_state(&parameters, &[]) else { continue };
        let mut problem = lagrange_tests::mechanical(&mut prepared, &parameters);
        if let Some(program) = prepared.recursive().expect("lowers") {
            problem = problem.with_chain(program);
        }
        assert_eq!(problem.recursive(), rel.starts_with("generated/"), "{rel}");
        // The constraints' drift |Φ| is observed; watch it cross a small level.
        let events: Vec<Event> = (0..sim::Problem::observations(&problem))
            .map(|column| Event { column, stop: false })
            .collect();
        for (method, samples) in [(Method::Dop853, 0), (Method::Dopri5, 7), (Method::Bs3, 5)] {
            let settings = Settings {
                method,
                start: 0.0,
                until: 0.6,
                tolerance: 1e-9,
                step: 0.01,
                max_steps: 20_000,
                samples,
            };
            let Some(lockstep) = Lockstep::new(&problem, &settings) else {
                panic!("{rel}: a plain problem runs in lockstep")
            };
            // Every other case on the baseline instructions: those bits too are a run's alone.
            let mut lockstep =
                if compared % 2 == 0 { lockstep } else { lockstep.on_baseline_instructions() };
            let all = jobs(&parameters, &y0);
            let mut queue = all.iter().map(|j| Job {
                id: j.id,
                parameters: j.parameters.clone(),
                state: j.state.clone(),
            });
            let mut side_by_side: Vec<Option<Run>> = vec![None; RUNS];
            lockstep.run(
                &mut || queue.next(),
                &events,
                &mut |id, run| side_by_side[id] = Some(run),
                &mut || ControlFlow::Continue(()),
            );
            for job in &all {
                let mut alone_problem = problem.clone();
                alone_problem.set_parameters(&job.parameters);
                let alone =
                    integrate(&mut alone_problem, &job.state, &settings, &events, &mut |_| {
                        ControlFlow::Continue(())
                    });
                let lane = side_by_side[job.id]
                    .as_ref()
                    .unwrap_or_else(|| panic!("{rel}: run {} lost", job.id));
                let (a, b) = (bits(lane), bits(&alone));
                let first = a.iter().zip(&b).position(|(x, y)| x != y);
                assert!(
                    a == b,
                    "{rel}: first difference at {first:?} of {} and {}: counts {:?} and {:?}",
                    a.len(),
                    b.len(),
                    (lane.steps, lane.rejected, lane.evaluations, lane.stiff_steps),
                    (alone.steps, alone.rejected, alone.evaluations, alone.stiff_steps)
                );
                assert!(
                    bits(lane) == bits(&alone),
                    "{rel} ({}): run {} differs: {} steps, t = {} in lockstep; {} steps, t = {} \
                     alone; faults {:?} and {:?}",
                    method.name(),
                    job.id,
                    lane.steps,
                    lane.final_time,
                    alone.steps,
                    alone.final_time,
                    lane.fault,
                    alone.fault
                );
                assert_eq!(lane.events, alone.events, "{rel}: run {}", job.id);
                assert_eq!(
                    lane.fault.as_ref().map(|f| &f.kind),
                    alone.fault.as_ref().map(|f| &f.kind)
                );
                compared += 1;
            }
        }
    }
    assert!(compared >= 20 * RUNS, "too few runs compared: {compared}");
}

#[test]
fn an_ensemble_in_lockstep_is_the_table_of_its_runs_one_at_a_time() {
    let flip = lagrange_tests::example("classics/double_pendulum_flip.lag");
    let axis = |text: &str| Vary::parse(text).expect("an axis");
    let cases = [
        // Stops (the flips) end most runs early, at different steps.
        (
            flip.clone(),
            vec![axis("a1=-3:3:9"), axis("a2=-3:3:5")],
            "t, theta1, max(theta2)",
            "dop853",
        ),
        (flip, vec![axis("a1=1:3:13")], "t, min(theta1), theta2'", "dopri5"),
        // Runs that cannot start or fail on the way are rows with their reasons.
        (
            "scene \"Pendulum\"\nparam m = 1 kg, l = 1 m, g = 9.81 m/s^2\ncoord theta = 1\n\
             particle bob { mass m; position (l*sin(theta), -l*cos(theta)) }\ngravity g\n"
                .to_string(),
            vec![axis("m=-1:1:5"), axis("l=0:2:5")],
            "theta, t",
            "dop853",
        ),
    ];
    for (source, vary, record, method) in cases {
        let options = Options {
            simulate: simulation::Options {
                until: Some(3.0),
                method: Some(method.to_string()),
                ..Default::default()
            },
            vary,
            record: vec![record.to_string()],
            ..Default::default()
        };
        let mut ensemble = Ensemble::new(&source, &options).expect("loads");
        let side_by_side = ensemble.run(0..ensemble.runs(), 2, &mut ());
        ensemble.set_lockstep(false);
        let alone = ensemble.run(0..ensemble.runs(), 1, &mut ());
        let bits = |rows: &[Vec<f64>]| -> Vec<u64> {
            rows.iter().flatten().map(|v| v.to_bits()).collect()
        };
        assert_eq!(bits(&side_by_side.rows), bits(&alone.rows), "{record}");
        assert_eq!(side_by_side.failures, alone.failures, "{record}");
    }
}
