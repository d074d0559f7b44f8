//! Every integrator on the harmonic oscillator, whose solution is known in closed form.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use sim::{integrate, Event, Method, Settings};
use std::ops::ControlFlow;

use crate::oscillator::Oscillator;

fn settings(method: Method, tolerance: f64, step: f64) -> Settings {
    Settings { method, start: 0.0, until: 10.0, tolerance, step, max_steps: 10_000_000, samples: 0 }
}

fn final_error(method: Method, tolerance: f64, step: f64) -> f64 {
    let run = integrate(
        &mut Oscillator,
        &[1.0, 0.0],
        &settings(method, tolerance, step),
        &[],
        &mut |_| ControlFlow::Continue(()),
    );
    assert!(run.fault.is_none());
    assert_eq!(run.final_time, 10.0);
    (run.final_state[0] - 10f64.cos()).abs().max((run.final_state[1] + 10f64.sin()).abs())
}

#[test]
fn each_method_converges_at_its_order() {
    // Halving the step divides the error by 2^order.
    for (method, order) in [(Method::Rk4, 4.0), (Method::Midpoint, 2.0), (Method::Gauss, 4.0)] {
        let (e1, e2) = (final_error(method, 0.0, 0.02), final_error(method, 0.0, 0.01));
        let observed = (e1 / e2).log2();
        assert!((observed - order).abs() < 0.3, "{method:?}: order {observed}");
    }
}

#[test]
fn adaptive_methods_meet_their_tolerance() {
    for method in [Method::Dopri5, Method::Dop853] {
        for tol in [1e-6, 1e-10] {
            let e = final_error(method, tol, 0.0);
            assert!(e < 100.0 * tol, "{method:?} at {tol}: error {e}");
        }
    }
    // DOP853 needs far fewer evaluations than the 5(4) pair at tight tolerance.
    let count = |m| {
        integrate(&mut Oscillator, &[1.0, 0.0], &settings(m, 1e-12, 0.0), &[], &mut |_| {
            ControlFlow::Continue(())
        })
        .evaluations
    };
    assert!(count(Method::Dop853) < count(Method::Dopri5));
}

#[test]
fn events_are_located_on_the_dense_output() {
    // cos t = 1/2 first at t = π/3.
    for (method, tol) in [(Method::Dopri5, 1e-12), (Method::Dop853, 1e-12), (Method::Rk4, 1e-3)] {
        let run = integrate(
            &mut Oscillator,
            &[1.0, 0.0],
            &settings(method, 1e-12, 1e-3),
            &[Event { column: 1, stop: true }],
            &mut |_| ControlFlow::Continue(()),
        );
        assert_eq!(run.stopped_by, Some(0));
        let t = run.final_time;
        assert!((t - std::f64::consts::FRAC_PI_3).abs() < tol, "{method:?}: {t}");
    }
    // Recorded events do not stop the run: cos t = 1/2 three times in [0, 10] (π/3, 5π/3, 7π/3).
    let run = integrate(
        &mut Oscillator,
        &[1.0, 0.0],
        &settings(Method::Dop853, 1e-10, 0.0),
        &[Event { column: 1, stop: false }],
        &mut |_| ControlFlow::Continue(()),
    );
    assert_eq!(run.events.len(), 3);
    assert_eq!(run.final_time, 10.0);
}

#[test]
fn progress_that_breaks_interrupts_the_run_where_it_is() {
    // The callback ends the run at its first accepted step past t = 2; what was computed up
    // to there is kept, as far as it got.
    let mut calls = 0;
    let run = integrate(
        &mut Oscillator,
        &[1.0, 0.0],
        &settings(Method::Dop853, 1e-10, 0.0),
        &[],
        &mut |t| {
            calls += 1;
            if t > 2.0 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    );
    assert!(run.interrupted);
    assert!(run.fault.is_none());
    assert!(run.final_time > 2.0 && run.final_time < 10.0, "{}", run.final_time);
    assert_eq!(calls, run.steps);
    assert_eq!(run.trajectory.times.last(), Some(&run.final_time));
    assert!((run.final_state[0] - run.final_time.cos()).abs() < 1e-8);
    // A callback that never breaks leaves the run whole.
    let whole = integrate(
        &mut Oscillator,
        &[1.0, 0.0],
        &settings(Method::Dop853, 1e-10, 0.0),
        &[],
        &mut |_| ControlFlow::Continue(()),
    );
    assert!(!whole.interrupted);
    assert_eq!(whole.final_time, 10.0);
}

#[test]
fn bs3_converges_at_third_order_and_meets_its_tolerance() {
    // The pair propagates its third-order solution with steps set by the second-order
    // estimate: a final error of the order of N⁻³ for N steps, whatever the tolerance that set N.
    let at = |tolerance: f64| {
        let run = integrate(
            &mut Oscillator,
            &[1.0, 0.0],
            &settings(Method::Bs3, tolerance, 0.0),
            &[],
            &mut |_| ControlFlow::Continue(()),
        );
        (run.steps as f64, final_error(Method::Bs3, tolerance, 0.0))
    };
    let ((n1, e1), (n2, e2)) = (at(1e-6), at(1e-9));
    let order = (e1 / e2).ln() / (n2 / n1).ln();
    eprintln!("bs3: {n1} steps, error {e1:e}; {n2} steps, error {e2:e}: order {order}");
    assert!((order - 3.0).abs() < 0.3, "order {order}");
    for tol in [1e-4, 1e-6, 1e-9] {
        let e = final_error(Method::Bs3, tol, 0.0);
        let reference = final_error(Method::Dop853, tol, 0.0);
        eprintln!("tolerance {tol:e}: bs3 {e:e}, dop853 {reference:e}");
        assert!(e < 100.0 * tol, "bs3 at {tol}: error {e}");
    }
}
