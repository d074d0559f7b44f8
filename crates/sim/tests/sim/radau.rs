//! Radau IIA on problems with closed-form solutions: its order on a smooth one, stiff linear
//! oscillators up to a stiffness of 1e12, events on its dense output, and an index-3
//! pendulum in Cartesian coordinates as a differential–algebraic problem.

// Closed forms the results are held to, within tolerances far above a last bit: the
// platform's functions serve.
#![allow(clippy::disallowed_methods)]

use crate::oscillator::Oscillator;
use sim::{integrate, Components, Event, FaultKind, Method, Problem, Run, Settings};
use std::ops::ControlFlow;

fn settings(tolerance: f64, until: f64) -> Settings {
    Settings {
        method: Method::Radau,
        start: 0.0,
        until,
        tolerance,
        step: 0.0,
        max_steps: 1_000_000,
        samples: 0,
    }
}

fn run(problem: &mut dyn Problem, y0: &[f64], tolerance: f64, until: f64, events: &[Event]) -> Run {
    let run = integrate(problem, y0, &settings(tolerance, until), events, &mut |_| {
        ControlFlow::Continue(())
    });
    assert!(run.fault.is_none(), "{:?}", run.fault);
    run
}

/// The error at t = 10 and the steps taken, at one tolerance.
fn oscillator_error(tolerance: f64) -> (f64, usize) {
    let r = run(&mut Oscillator, &[1.0, 0.0], tolerance, 10.0, &[]);
    let e = (r.final_state[0] - 10f64.cos()).abs().max((r.final_state[1] + 10f64.sin()).abs());
    (e, r.steps)
}

#[test]
fn the_error_falls_with_the_fifth_power_of_the_step() {
    // At tight tolerances the steps are all alike, so the error goes as (steps)^−5.
    let (e1, n1) = oscillator_error(1e-7);
    let (e2, n2) = oscillator_error(1e-10);
    assert!(n2 > 2 * n1, "{n1} → {n2} steps");
    let order = (e1 / e2).ln() / (n2 as f64 / n1 as f64).ln();
    assert!((order - 5.0).abs() < 0.6, "order {order}: {e1:e} in {n1} steps, {e2:e} in {n2}");
    // And the global error is of the tolerance's order.
    assert!(e1 < 1e-6 && e2 < 1e-9, "{e1:e}, {e2:e}");
}

/// x'' + c·x' + k·x = k·cos t with damping ratio 5 (c = 10·√k): the fast modes decay at
/// rates up to 10·√k, the slow motion follows cos t.
struct DrivenStiff {
    k: f64,
    c: f64,
}

impl DrivenStiff {
    fn new(k: f64) -> Self {
        DrivenStiff { k, c: 10.0 * k.sqrt() }
    }

    /// The forced response A·cos t + B·sin t, where the slow motion starts: (A, B) with
    /// (k − 1)·A + c·B = k and (k − 1)·B − c·A = 0.
    fn forced(&self) -> (f64, f64) {
        let (k, c) = (self.k, self.c);
        let det = (k - 1.0) * (k - 1.0) + c * c;
        (k * (k - 1.0) / det, k * c / det)
    }

    fn exact(&self, t: f64) -> [f64; 2] {
        let (a, b) = self.forced();
        [a * t.cos() + b * t.sin(), b * t.cos() - a * t.sin()]
    }
}

impl Problem for DrivenStiff {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        dy[0] = y[1];
        dy[1] = self.k * (t.cos() - y[0]) - self.c * y[1];
        Ok(())
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<bool, FaultKind> {
        jac.copy_from_slice(&[0.0, 1.0, -self.k, -self.c]);
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

#[test]
fn stiff_oscillators_take_few_steps_at_any_stiffness() {
    for k in [1e4, 1e6, 1e8, 1e10, 1e12] {
        let mut p = DrivenStiff::new(k);
        let r = run(&mut p, &DrivenStiff::new(k).exact(0.0), 1e-8, 10.0, &[]);
        let want = p.exact(10.0);
        let off = [(r.final_state[0] - want[0]).abs(), (r.final_state[1] - want[1]).abs()];
        // x' is slaved to x by the fast modes, and its error reaches the estimate only through
        // the stiff filter: it is held to the tolerance's order, x well within it.
        assert!(off[0] < 1e-8 && off[1] < 3e-7, "k = {k:e}: {:?} against {want:?}", r.final_state);
        // An explicit method would need about √k·10 steps: 1e7 at k = 1e12.
        assert!(r.steps < 400, "k = {k:e}: {} steps", r.steps);
        // The problem is linear: Newton converges at once, and the Jacobian is recomputed
        // only after rejections.
        assert!(r.jacobians <= r.rejected + 2, "{} Jacobians", r.jacobians);
        assert!(r.factorizations < r.steps + r.rejected, "{} factorizations", r.factorizations);
    }
}

#[test]
fn events_and_stops_are_located_on_the_collocation_polynomial() {
    // y = cos t crosses 0.5 at π/3, 5π/3, 7π/3, …
    let event = [Event { column: 1, stop: false }];
    // The collocation polynomial is of order 3 inside a step: the located times are as good as
    // the dense output, a little short of the tolerance.
    let r = run(&mut Oscillator, &[1.0, 0.0], 1e-9, 10.0, &event);
    let third = std::f64::consts::PI / 3.0;
    let want = [third, 5.0 * third, 7.0 * third];
    assert_eq!(r.events.len(), want.len(), "{:?}", r.events);
    for (hit, w) in r.events.iter().zip(want) {
        assert!((hit.time - w).abs() < 5e-8, "{} against {w}", hit.time);
    }
    let stop = [Event { column: 1, stop: true }];
    let r = run(&mut Oscillator, &[1.0, 0.0], 1e-9, 10.0, &stop);
    assert_eq!(r.stopped_by, Some(0));
    assert!((r.final_time - third).abs() < 1e-8, "{}", r.final_time);
    assert!((r.final_state[0] - 0.5).abs() < 1e-8, "{:?}", r.final_state);
}

/// The pendulum x² + y² = 1 under gravity as the index-3 system of its multiplier:
/// (x, y, u, v, λ) with x' = u, y' = v, u' = 2λx, v' = 2λy − g and 0 = x² + y² − 1.
struct CartesianPendulum;

const G: f64 = 9.81;

impl Problem for CartesianPendulum {
    fn dim(&self) -> usize {
        5
    }
    fn rhs(&mut self, _t: f64, s: &[f64], f: &mut [f64]) -> Result<(), FaultKind> {
        let [x, y, u, v, l] = [s[0], s[1], s[2], s[3], s[4]];
        f[0] = u;
        f[1] = v;
        f[2] = 2.0 * l * x;
        f[3] = 2.0 * l * y - G;
        f[4] = x * x + y * y - 1.0;
        Ok(())
    }
    fn components(&self) -> Components {
        Components { differential: 4, by_index: [2, 2, 1] }
    }
    fn observations(&self) -> usize {
        2
    }
    /// The energy, and x (for the period: its zero crossings).
    fn observe(&mut self, _t: f64, s: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        out[0] = 0.5 * (s[2] * s[2] + s[3] * s[3]) + G * s[1];
        out[1] = s[0];
        Ok(())
    }
}

#[test]
fn an_index_three_pendulum_keeps_its_constraint_and_energy() {
    // Released at rest from 60°: λ = (g·y − |u|²)/2 at the start is g·y/2.
    let (x0, y0) = (60f64.to_radians().sin(), -60f64.to_radians().cos());
    let start = [x0, y0, 0.0, 0.0, G * y0 / 2.0];
    let events = [Event { column: 1, stop: false }];
    let r = run(&mut CartesianPendulum, &start, 1e-10, 10.0, &events);
    let s = &r.final_state;
    let drift = (s[0] * s[0] + s[1] * s[1] - 1.0).abs();
    assert!(drift < 1e-10, "|Φ| = {drift:e}");
    let energy = r.trajectory.rows.iter().map(|row| row[0]);
    let e0 = G * y0;
    let worst = energy.fold(0.0f64, |m, e| m.max((e - e0).abs()));
    // The velocities are index-2 components, whose errors the method lets grow as h, not as
    // the tolerance: the energy, made of them, keeps 6 digits where the positions keep 10.
    assert!(worst < 1e-5 * e0.abs(), "energy drift {worst:e}");
    // x crosses zero twice a period; the period of 60° swings is 4·K(sin 30°)/√g, with
    // K(1/2) = 1.685750354812596, the complete elliptic integral of the first kind.
    let times: Vec<f64> = r.events.iter().map(|e| e.time).collect();
    assert!(times.len() >= 4, "{times:?}");
    let period = times[2] - times[0];
    let want = 4.0 * 1.685_750_354_812_596 / G.sqrt();
    assert!((period - want).abs() < 1e-7, "period {period} against {want}");
}

/// y₁' = y₂ with 0 = y₂² + 1: an algebraic equation no real y₂ satisfies, so no step, however
/// small, has stages that solve the collocation equations.
struct Impossible;

impl Problem for Impossible {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), FaultKind> {
        dy[0] = y[1];
        dy[1] = y[1] * y[1] + 1.0;
        Ok(())
    }
    fn components(&self) -> Components {
        Components { differential: 1, by_index: [2, 0, 0] }
    }
    fn observations(&self) -> usize {
        1
    }
    fn observe(&mut self, _t: f64, y: &[f64], out: &mut [f64]) -> Result<(), FaultKind> {
        out[0] = y[0];
        Ok(())
    }
}

#[test]
fn newton_that_cannot_converge_says_so_with_the_step_it_got_down_to() {
    let r = integrate(&mut Impossible, &[0.0, 0.5], &settings(1e-8, 3.0), &[], &mut |_| {
        ControlFlow::Continue(())
    });
    let fault = r.fault.expect("no step solves the stage equations");
    assert_eq!((fault.time, r.steps), (0.0, 0), "{fault:?}");
    match fault.kind {
        FaultKind::NewtonStalled { step, singular: false, .. } => {
            // Cut to the resolution of time over the run, not to underflow.
            assert!(step < 1e-12 && step > 1e-16, "{fault:?}")
        }
        other => panic!("{other:?}"),
    }
}
