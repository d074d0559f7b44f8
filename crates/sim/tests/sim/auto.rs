//! `auto` on problems whose stiffness is known: one that never turns stiff stays on the
//! explicit side and takes DOP853's very steps; one that turns stiff and calms again switches
//! to radau and back, with its solution, events and samples continuous across the switches.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use crate::oscillator::Oscillator;
use sim::{integrate, Event, FaultKind, Method, Problem, Run, Segment, Settings};
use std::ops::ControlFlow;

fn settings(method: Method, until: f64, samples: usize) -> Settings {
    Settings {
        method,
        start: 0.0,
        until,
        tolerance: 1e-8,
        step: 0.0,
        max_steps: 1_000_000,
        samples,
    }
}

/// y' = −λ(t)·(y − cos t) − sin t from y = 1, whose solution is cos t whatever λ is. λ rises
/// from 1 to 1e6 about t = 4 and falls back: stiff in the middle of the run only. The
/// observation is y itself, whose zeros are at odd multiples of π/2.
struct Bump;

impl Bump {
    fn rate(t: f64) -> f64 {
        1.0 + 1e6 * (-2.0 * (t - 4.0) * (t - 4.0)).exp()
    }
}

impl Problem for Bump {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        dy[0] = -Bump::rate(t) * (y[0] - t.cos()) - t.sin();
        Ok(())
    }
    fn jacobian(&mut self, t: f64, _y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        jac[0] = -Bump::rate(t);
        Ok(true)
    }
    fn observations(&self) -> usize {
        1
    }
    fn observe(&mut self, _t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        out[0] = y[0];
        Ok(())
    }
}

fn run(problem: &mut dyn Problem, y0: &[f64], settings: &Settings, events: &[Event]) -> Run {
    let run = integrate(problem, y0, settings, events, &mut |_| ControlFlow::Continue(()));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    run
}

#[test]
fn a_problem_that_is_never_stiff_is_dop853_throughout() {
    let auto = run(&mut Oscillator, &[1.0, 0.0], &settings(Method::Auto, 10.0, 0), &[]);
    let dop853 = run(&mut Oscillator, &[1.0, 0.0], &settings(Method::Dop853, 10.0, 0), &[]);
    assert_eq!(auto.segments, [Segment { method: Method::Dop853, start: 0.0, end: 10.0 }]);
    assert_eq!(auto.final_state, dop853.final_state);
    assert_eq!((auto.steps, auto.evaluations), (dop853.steps, dop853.evaluations));
    assert_eq!(auto.jacobians, 0);
}

#[test]
fn a_problem_stiff_in_the_middle_switches_to_radau_and_back() {
    let zeros = [Event { column: 0, stop: false }];
    let r = run(&mut Bump, &[1.0], &settings(Method::Auto, 10.0, 0), &zeros);
    let methods: Vec<Method> = r.segments.iter().map(|s| s.method).collect();
    assert_eq!(methods, [Method::Dop853, Method::Radau, Method::Dop853], "{:?}", r.segments);
    // The segments tile the run, and the stiff one holds the peak of λ at t = 4 (it began at
    // t ≈ 2.5, where λ ≈ 100 already holds DOP853's steps to its stability limit).
    assert_eq!(r.segments[0].start, 0.0);
    assert_eq!(r.segments[2].end, 10.0);
    assert_eq!(r.segments[0].end, r.segments[1].start);
    assert_eq!(r.segments[1].end, r.segments[2].start);
    assert!(r.segments[1].start > 1.0 && r.segments[1].start < 3.5, "{:?}", r.segments);
    assert!(r.segments[1].end > 4.5 && r.segments[1].end < 8.0, "{:?}", r.segments);
    // One solution throughout: the recorded values follow cos t at every step.
    for (t, row) in r.trajectory.times.iter().zip(&r.trajectory.rows) {
        assert!((row[0] - t.cos()).abs() < 1e-6, "y({t}) = {} against {}", row[0], t.cos());
    }
    // Events in each segment, located on the dense output of the side that took the step.
    let half = std::f64::consts::FRAC_PI_2;
    let want = [half, 3.0 * half, 5.0 * half];
    assert_eq!(r.events.len(), want.len(), "{:?}", r.events);
    for (hit, w) in r.events.iter().zip(want) {
        assert!((hit.time - w).abs() < 1e-6, "{} against {w}", hit.time);
    }
    // Far fewer steps than DOP853 takes through the stiff middle, where it is held to
    // h < 6.4/λ.
    let dop853 = run(&mut Bump, &[1.0], &settings(Method::Dop853, 10.0, 0), &[]);
    assert!(5 * r.steps < dop853.steps, "{} steps against DOP853's {}", r.steps, dop853.steps);
    assert!(r.jacobians > 0 && r.stiff_steps >= 15);
}

#[test]
fn samples_across_a_switch_come_from_the_side_that_covered_them() {
    let r = run(&mut Bump, &[1.0], &settings(Method::Auto, 10.0, 101), &[]);
    assert_eq!(r.segments.len(), 3, "{:?}", r.segments);
    assert_eq!(r.trajectory.times.len(), 101);
    // Radau's collocation polynomial is of order 3 between its steps, so samples in the stiff
    // middle are as good as radau's own there, no better: both runs are held to the worst
    // sample of radau alone.
    let radau = run(&mut Bump, &[1.0], &settings(Method::Radau, 10.0, 101), &[]);
    let worst = |r: &Run| {
        r.trajectory
            .times
            .iter()
            .zip(&r.trajectory.rows)
            .map(|(t, row)| (row[0] - t.cos()).abs())
            .fold(0.0, f64::max)
    };
    assert!(
        worst(&r) <= 2.0 * worst(&radau),
        "{:e} against radau's {:e}",
        worst(&r),
        worst(&radau)
    );
    assert!(worst(&r) < 1e-5, "{:e}", worst(&r));
}
