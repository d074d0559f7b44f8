//! Runs through one-sided contacts, each against its closed form: the bouncing ball's impacts
//! and their accumulation, the ladder leaving the wall, a particle leaving a hemisphere, a
//! stack at rest and a ball dropped on one, a rod landing flat on both ends, a rocking block
//! (Housner) and a rimless wheel (McGeer), under the explicit methods and under radau on the
//! differential–algebraic form. The programs are built here from `cas` expressions lowered by
//! `numeric`, as `engine` does.

use std::ops::ControlFlow;

use cas::{ExprId, Pool, SymId};
use numeric::{lower, Tape};
use sim::{
    integrate, Constrained, Contact, Form, Layout, Mechanical, Method, ModeChange, Run, Settings,
    Stabilisation,
};

/// A kept row of a scene: a gap g(q) ≥ 0 or a velocity row A(q)·q̇ held at zero.
enum Kept {
    Position(ExprId),
    Velocity(ExprId),
}

/// A scene of `n` coordinates, built as expressions and lowered into a [`Mechanical`] whose
/// observations are q, q̇ and λ.
struct Scene {
    pool: Pool,
    time: SymId,
    q: Vec<SymId>,
    v: Vec<SymId>,
}

impl Scene {
    fn new(names: &[&str]) -> Scene {
        let mut pool = Pool::new();
        let time = pool.time();
        let q: Vec<SymId> = names.iter().map(|s| pool.coordinate(s)).collect();
        let v = q.iter().map(|&s| pool.rate(s).expect("a coordinate's rate")).collect();
        Scene { pool, time, q, v }
    }

    fn q(&mut self, i: usize) -> ExprId {
        self.pool.sym(self.q[i])
    }

    fn num(&mut self, x: f64) -> ExprId {
        // The tests' values are dyadic or short decimals: exact as a ratio over 2^20·10^6.
        let scale = 1_048_576_000_000i64;
        self.pool.ratio((x * scale as f64).round() as i64, scale)
    }

    /// ∂e/∂q̇ of a row linear in the rates, or ∂e/∂q.
    fn gradient(&mut self, e: ExprId, of: &[SymId]) -> Vec<ExprId> {
        of.iter().map(|&s| self.pool.diff(e, s)).collect()
    }

    /// Σ ∂e/∂q_i·q̇_i.
    fn along_rates(&mut self, e: ExprId) -> ExprId {
        let terms: Vec<ExprId> = (0..self.q.len())
            .map(|i| {
                let d = self.pool.diff(e, self.q[i]);
                let v = self.pool.sym(self.v[i]);
                self.pool.mul(&[d, v])
            })
            .collect();
        self.pool.add(&terms)
    }

    /// The problem of mass matrix `mass` (row-major), forces `force` and kept rows `kept`.
    fn mechanical(mut self, mass: &[ExprId], force: &[ExprId], kept: &[Kept]) -> Mechanical {
        let n = self.q.len();
        let m = kept.len();
        let mut outputs = Vec::new();
        for j in 0..n {
            for i in 0..n {
                outputs.push(mass[i * n + j]);
            }
        }
        outputs.extend_from_slice(force);
        let mut kinds = Vec::new();
        for row in kept {
            match *row {
                Kept::Position(g) => {
                    let q = self.q.clone();
                    outputs.extend(self.gradient(g, &q));
                    let rate = self.along_rates(g);
                    let second = self.along_rates(rate);
                    let gamma = self.pool.neg(second);
                    outputs.extend([gamma, g, rate]);
                    kinds.push(Stabilisation::Position);
                }
                Kept::Velocity(r) => {
                    let v = self.v.clone();
                    outputs.extend(self.gradient(r, &v));
                    let second = self.along_rates(r);
                    let gamma = self.pool.neg(second);
                    let zero = self.pool.zero();
                    outputs.extend([gamma, r, zero]);
                    kinds.push(Stabilisation::Velocity);
                }
            }
        }
        let mut inputs = vec![self.time];
        inputs.extend(&self.q);
        inputs.extend(&self.v);
        let dynamics = lower(&self.pool, &inputs, &outputs).expect("lowered");
        let accelerations: Vec<SymId> = (0..n).map(|i| self.pool.param(&format!("a{i}"))).collect();
        let multipliers: Vec<SymId> = (0..m).map(|c| self.pool.param(&format!("l{c}"))).collect();
        inputs.extend(&accelerations);
        inputs.extend(&multipliers);
        let shown: Vec<ExprId> =
            self.q.iter().chain(&self.v).chain(&multipliers).map(|&s| self.pool.sym(s)).collect();
        let observation = lower(&self.pool, &inputs, &shown).expect("lowered");
        let layout = Layout { coordinates: n, multipliers: m, parameters: 0 };
        Mechanical::new(layout, Tape::new(dynamics), Tape::new(observation), Vec::new())
            .with_kinds(kinds)
    }
}

fn settings(method: Method, until: f64, tolerance: f64) -> Settings {
    Settings { method, start: 0.0, until, tolerance, step: 1e-3, max_steps: 100_000, samples: 0 }
}

/// A run of `problem` from (q, q̇) = `y0` in the form its method integrates: the
/// differential–algebraic one for radau, from the consistent state over `y0`.
fn run(problem: &mut Mechanical, y0: &[f64], settings: &Settings) -> Run {
    if settings.method.form() != Form::Algebraic {
        return integrate(problem, y0, settings, &[], &mut |_| ControlFlow::Continue(()));
    }
    let mut constrained = Constrained::new(problem.clone());
    let y0 = constrained.consistent_state(settings.start, y0).expect("consistent");
    integrate(&mut constrained, &y0, settings, &[], &mut |_| ControlFlow::Continue(()))
}

const GRAVITY: f64 = 9.81;

/// A ball of mass `mass` over a floor y ≥ 0.
fn ball(mass: f64, restitution: f64) -> Mechanical {
    let mut scene = Scene::new(&["y"]);
    let m = scene.num(mass);
    let weight = scene.num(-mass * GRAVITY);
    let y = scene.q(0);
    scene.mechanical(&[m], &[weight], &[Kept::Position(y)]).with_contacts(vec![Contact {
        normal: 0,
        grip: None,
        cross: None,
        restitution,
        friction: None,
    }])
}

#[test]
fn a_bouncing_ball_lands_at_the_closed_form_times_and_settles_at_their_accumulation() {
    let (mass, e, h0) = (2.0, 0.8, 1.0);
    let mut problem = ball(mass, e);
    let run = run(&mut problem, &[h0, 0.0], &settings(Method::Dop853, 12.0, 1e-9));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    assert_eq!(run.final_time, 12.0);
    let t1 = (2.0 * h0 / GRAVITY).sqrt();
    let impacts: Vec<f64> =
        run.modes.iter().filter(|m| m.kind == ModeChange::Impact).map(|m| m.time).collect();
    assert!(impacts.len() > 50, "{} impacts", impacts.len());
    let (mut expected, mut power) = (t1, 1.0);
    let mut worst: f64 = 0.0;
    for &t in &impacts {
        worst = worst.max((t - expected).abs() / expected);
        power *= e;
        expected += 2.0 * t1 * power;
    }
    assert!(worst < 1e-8, "impact times off by {worst:e}");
    let settled: Vec<_> = run.modes.iter().filter(|m| m.kind == ModeChange::Settled).collect();
    assert_eq!(settled.len(), 1, "{:?}", run.modes.last());
    let accumulation = t1 * (1.0 + e) / (1.0 - e);
    let off = (settled[0].time - accumulation).abs() / accumulation;
    assert!(off < 1e-8, "settled at {} for {accumulation}: {off:e}", settled[0].time);
    assert!(settled[0].closed);
    // Each impact takes Λ = (1 + e)·m·v and loses (1 − e²)·½mv².
    let first = &run.modes[0];
    let v = GRAVITY * t1;
    assert!((first.impulse - (1.0 + e) * mass * v).abs() < 1e-8 * mass * v);
    let lost = (1.0 - e * e) * 0.5 * mass * v * v;
    assert!((first.energy_change + lost).abs() < 1e-8 * lost, "{}", first.energy_change);
    assert!(run.modes.iter().all(|m| !m.energy_rise));
    // At rest on the floor after: λ = m·g, y = 0.
    let last = run.trajectory.rows.last().expect("rows");
    assert!((last[2] - mass * GRAVITY).abs() < 1e-9 * mass * GRAVITY, "λ = {}", last[2]);
    assert!(last[0].abs() < 1e-9 && last[1].abs() < 1e-9, "{last:?}");
    assert!(run.steps < 1000, "{} steps", run.steps);
    println!(
        "ball: {} impacts, settled at {} (closed form {accumulation}), {} steps, worst {worst:e}",
        impacts.len(),
        settled[0].time,
        run.steps
    );
}

#[test]
fn the_ball_bounces_and_settles_under_each_explicit_method() {
    for method in [Method::Rk4, Method::Bs3, Method::Dopri5, Method::Auto] {
        assert!(method.handles_contacts());
        let mut problem = ball(1.0, 0.5);
        let run = run(&mut problem, &[1.0, 0.0], &settings(method, 3.0, 1e-9));
        assert!(run.fault.is_none(), "{method:?}: {:?}", run.fault);
        let settled = run.modes.iter().find(|m| m.kind == ModeChange::Settled).expect("settled");
        let accumulation = (2.0 / GRAVITY).sqrt() * 3.0;
        assert!((settled.time - accumulation).abs() < 1e-8 * accumulation, "{method:?}");
    }
    assert!(!Method::Gauss.handles_contacts() && !Method::Midpoint.handles_contacts());
    assert!(Method::Auto.handles_contacts() && Method::Dop853.handles_contacts());
}

#[test]
fn a_run_that_samples_records_each_jump_before_and_after_at_its_time() {
    let mut problem = ball(1.0, 0.5);
    let mut settings = settings(Method::Dop853, 1.0, 1e-9);
    settings.samples = 11;
    let run = run(&mut problem, &[1.0, 0.0], &settings);
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let times = &run.trajectory.times;
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "{times:?}");
    let t1 = (2.0 / GRAVITY).sqrt();
    let landing = run.modes[0];
    assert!((landing.time - t1).abs() < 1e-12);
    let at = times.iter().position(|&t| t == landing.time).expect("the jump's rows");
    assert_eq!(times[at + 1], landing.time);
    let (before, after) = (&run.trajectory.rows[at], &run.trajectory.rows[at + 1]);
    assert!(
        (before[1] + GRAVITY * t1).abs() < 1e-9 && (after[1] - 0.5 * GRAVITY * t1).abs() < 1e-9
    );
    // The evenly spaced times, each once, around the jumps' rows.
    let spaced = times.iter().filter(|&&t| run.modes.iter().all(|m| m.time != t)).count();
    assert_eq!(spaced, 11, "{times:?}");
}

#[test]
fn the_lockstep_leaves_a_problem_with_contacts_to_runs_alone() {
    let problem = ball(1.0, 0.5);
    assert!(sim::Lockstep::new(&problem, &settings(Method::Dop853, 1.0, 1e-9)).is_none());
    let mut free = ball(1.0, 0.5).with_contacts(Vec::new());
    assert_eq!(sim::Problem::guards(&free), 0);
    assert!(sim::Lockstep::new(&free, &settings(Method::Dop853, 1.0, 1e-9)).is_some());
    // Without its contact the row y = 0 is two-sided: it holds the ball at rest there.
    let run = run(&mut free, &[0.0, 0.0], &settings(Method::Dop853, 1.0, 1e-9));
    assert!(run.modes.is_empty() && run.final_state[0].abs() < 1e-12);
    let last = run.trajectory.rows.last().expect("rows");
    assert!((last[2] - GRAVITY).abs() < 1e-12, "λ = {}", last[2]);
}

#[test]
fn a_start_below_the_floor_is_a_fault_naming_the_contact() {
    let mut problem = ball(1.0, 0.5);
    let run = run(&mut problem, &[-0.1, 0.0], &settings(Method::Dop853, 1.0, 1e-9));
    let fault = run.fault.expect("a fault");
    assert_eq!(fault.kind, sim::FaultKind::Penetrating { contact: 0, gap: -0.1 });
}

#[test]
fn a_ball_landing_at_the_start_is_an_impact_there() {
    let mut problem = ball(1.0, 0.5);
    let run = run(&mut problem, &[0.0, -2.0], &settings(Method::Dop853, 0.1, 1e-9));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let first = run.modes[0];
    assert_eq!((first.time, first.kind), (0.0, ModeChange::Impact));
    assert!((first.impulse - 3.0).abs() < 1e-12, "{}", first.impulse);
    // The start's two rows: before the impact and after it.
    assert_eq!(&run.trajectory.times[..2], &[0.0, 0.0]);
    assert_eq!(run.trajectory.rows[0][1], -2.0);
    assert!((run.trajectory.rows[1][1] - 1.0).abs() < 1e-12);
}

#[test]
fn a_ladder_leaves_the_wall_where_cos_theta_is_two_thirds_of_its_start() {
    ladder(Method::Dop853);
    // Radau on the differential–algebraic form.
    ladder(Method::Radau);
}

fn ladder(method: Method) {
    // The centre (x, y), θ from the wall; the wall at x = 0 on the left, the floor at y = 0.
    let (mass, length, theta0): (f64, f64, f64) = (3.0, 2.0, 0.3);
    let (sin0, cos0) = numeric::elementary::sin_cos(theta0);
    let mut scene = Scene::new(&["x", "y", "theta"]);
    let (x, y, theta) = (scene.q(0), scene.q(1), scene.q(2));
    let half = scene.num(length / 2.0);
    let (sin, cos) = (scene.pool.sin(theta), scene.pool.cos(theta));
    let top_x = {
        let arm = scene.pool.mul(&[half, sin]);
        scene.pool.sub(x, arm)
    };
    let foot_y = {
        let arm = scene.pool.mul(&[half, cos]);
        scene.pool.sub(y, arm)
    };
    let m = scene.num(mass);
    let inertia = scene.num(mass * length * length / 12.0);
    let zero = scene.pool.zero();
    let weight = scene.num(-mass * GRAVITY);
    let mass_matrix = [m, zero, zero, zero, m, zero, zero, zero, inertia];
    let mut problem = scene
        .mechanical(
            &mass_matrix,
            &[zero, weight, zero],
            &[Kept::Position(top_x), Kept::Position(foot_y)],
        )
        .with_contacts(vec![
            Contact { normal: 0, grip: None, cross: None, restitution: 0.0, friction: None },
            Contact { normal: 1, grip: None, cross: None, restitution: 0.0, friction: None },
        ]);
    let y0 = [0.5 * length * sin0, 0.5 * length * cos0, theta0, 0.0, 0.0, 0.0];
    let run = run(&mut problem, &y0, &settings(method, 0.75, 1e-10));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let closed: Vec<_> = run.modes.iter().filter(|m| m.kind == ModeChange::Closed).collect();
    assert_eq!(closed.len(), 2, "{:?}", run.modes);
    let lift: Vec<_> = run.modes.iter().filter(|m| m.kind == ModeChange::LiftOff).collect();
    assert_eq!(lift.len(), 1, "{:?}", run.modes);
    assert_eq!(lift[0].contact, 0);
    let at = run.trajectory.times.iter().position(|&t| t == lift[0].time).expect("its rows");
    let theta = run.trajectory.rows[at][2];
    let cos = numeric::elementary::sin_cos(theta).1;
    let off = (cos - 2.0 / 3.0 * cos0).abs();
    assert!(off < 1e-8, "left at cos θ = {cos}, off by {off:e}");
    // Free of the wall, the centre's x' is constant and the wall pushes no more.
    let after = &run.trajectory.rows[at + 1..];
    let rate = after[0][3];
    assert!(rate > 0.0);
    for row in after {
        assert!((row[3] - rate).abs() < 1e-9 * rate, "x' {} from {rate}", row[3]);
        assert_eq!(row[6], 0.0);
    }
    let last = run.final_state[2];
    assert!(last < std::f64::consts::FRAC_PI_2, "θ = {last} at the end");
    let floor = run.trajectory.rows.iter().map(|r| r[7]).fold(f64::INFINITY, f64::min);
    assert!(floor >= -1e-9 * mass * GRAVITY, "the floor pulled: {floor}");
    println!("ladder ({method:?}): left the wall at t = {}, cos θ off by {off:e}", lift[0].time);
}

#[test]
fn a_stack_of_eight_balls_rests_with_each_contact_bearing_the_weight_above_it() {
    stack(Method::Dop853);
    stack(Method::Radau);
}

/// A column of `count` balls of `mass` and `radius` over a floor, each contact of
/// restitution `restitution`.
fn column(count: usize, mass: f64, radius: f64, restitution: f64) -> Mechanical {
    let names: Vec<String> = (0..count).map(|k| format!("y{k}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut scene = Scene::new(&names);
    let m = scene.num(mass);
    let zero = scene.pool.zero();
    let weight = scene.num(-mass * GRAVITY);
    let mut mass_matrix = vec![zero; count * count];
    for k in 0..count {
        mass_matrix[k * count + k] = m;
    }
    let mut kept = Vec::new();
    for k in 0..count {
        let above = scene.q(k);
        let below = if k == 0 { zero } else { scene.q(k - 1) };
        let gap = scene.num(if k == 0 { radius } else { 2.0 * radius });
        let (centres, sum) = (scene.pool.sub(above, below), gap);
        kept.push(Kept::Position(scene.pool.sub(centres, sum)));
    }
    let contacts = (0..count)
        .map(|k| Contact { normal: k, grip: None, cross: None, restitution, friction: None })
        .collect();
    scene.mechanical(&mass_matrix, &vec![weight; count], &kept).with_contacts(contacts)
}

fn stack(method: Method) {
    let (count, mass, radius) = (8, 0.5, 0.5);
    let mut problem = column(count, mass, radius, 0.5);
    let mut y0 = vec![0.0; 2 * count];
    for (k, centre) in y0[..count].iter_mut().enumerate() {
        *centre = radius + 2.0 * radius * k as f64;
    }
    let run = run(&mut problem, &y0, &settings(method, 10.0, 1e-9));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    assert!(run.modes.iter().all(|m| m.kind == ModeChange::Closed && m.time == 0.0));
    assert_eq!(run.modes.len(), count);
    for row in &run.trajectory.rows {
        for k in 0..count {
            let expected = (count - k) as f64 * mass * GRAVITY;
            assert!((row[2 * count + k] - expected).abs() < 1e-9 * expected, "λ{k} {row:?}");
            assert!((row[k] - y0[k]).abs() < 1e-12 && row[count + k].abs() < 1e-12, "{row:?}");
        }
    }
    assert_eq!(run.final_time, 10.0);
}

#[test]
fn a_rocking_block_loses_its_rate_at_each_impact_by_housners_ratio() {
    rocking(Method::Dop853);
    rocking(Method::Radau);
}

fn rocking(method: Method) {
    // Half-width b, half-height h; the centre (x, y) and the rotation φ; the bottom corners
    // (∓b, −h) grip the floor while down, and land plastically.
    let (mass, b, h): (f64, f64, f64) = (1.5, 0.2, 0.6);
    let mut scene = Scene::new(&["x", "y", "phi"]);
    let (x, y, phi) = (scene.q(0), scene.q(1), scene.q(2));
    let (sin, cos) = (scene.pool.sin(phi), scene.pool.cos(phi));
    let mut kept = Vec::new();
    for side in [-1.0, 1.0] {
        let (cx, cy) = (scene.num(side * b), scene.num(-h));
        let horizontal = {
            let a = scene.pool.mul(&[cos, cx]);
            let s = scene.pool.mul(&[sin, cy]);
            let rotated = scene.pool.sub(a, s);
            scene.pool.add(&[x, rotated])
        };
        let height = {
            let a = scene.pool.mul(&[sin, cx]);
            let c = scene.pool.mul(&[cos, cy]);
            scene.pool.add(&[y, a, c])
        };
        let slip = scene.along_rates(horizontal);
        kept.push(Kept::Position(height));
        kept.push(Kept::Velocity(slip));
    }
    let m = scene.num(mass);
    let inertia = scene.num(mass * (b * b + h * h) / 3.0);
    let zero = scene.pool.zero();
    let weight = scene.num(-mass * GRAVITY);
    let mass_matrix = [m, zero, zero, zero, m, zero, zero, zero, inertia];
    let contacts = vec![
        Contact { normal: 0, grip: Some(1), cross: None, restitution: 0.0, friction: None },
        Contact { normal: 2, grip: Some(3), cross: None, restitution: 0.0, friction: None },
    ];
    let mut problem =
        scene.mechanical(&mass_matrix, &[zero, weight, zero], &kept).with_contacts(contacts);
    // Tilted clockwise onto its right corner, at the origin, from rest.
    let phi0: f64 = -0.05;
    let (s0, c0) = numeric::elementary::sin_cos(phi0);
    let y0 = [-c0 * b - s0 * h, -s0 * b + c0 * h, phi0, 0.0, 0.0, 0.0];
    let run = run(&mut problem, &y0, &settings(method, 1.5, 1e-10));
    // Radau's continuous extension, the collocation polynomial, is of order 3: the state it
    // gives at an impact inside a step is less accurate than its steps' ends.
    let accuracy = if method == Method::Radau { 1e-7 } else { 1e-8 };
    assert!(run.fault.is_none(), "{:?}", run.fault);
    // sin²α with α = atan(b/h).
    let ratio = 1.0 - 1.5 * b * b / (b * b + h * h);
    let impacts: Vec<_> = run.modes.iter().filter(|m| m.kind == ModeChange::Impact).collect();
    assert!(impacts.len() >= 3, "{:?}", run.modes);
    let mut seen = 0;
    for impact in &impacts {
        let at = run.trajectory.times.iter().position(|&t| t == impact.time).expect("rows");
        let (before, after) = (run.trajectory.rows[at][5], run.trajectory.rows[at + 1][5]);
        let off = (after / before - ratio).abs();
        assert!(off < accuracy, "ω⁺/ω⁻ = {} for {ratio}: {off:e}", after / before);
        // The corner left behind lifts off at the same instant, by complementarity.
        let other = 1 - impact.contact;
        assert!(run
            .modes
            .iter()
            .any(|m| m.time == impact.time && m.contact == other && m.kind == ModeChange::LiftOff));
        assert!(impact.tangential.is_some() && impact.energy_change < 0.0);
        seen += 1;
    }
    println!("block ({method:?}): {seen} impacts at ω⁺/ω⁻ = {ratio}");
    // Its rocking accumulates too: it comes to rest on both corners.
    let long = self::run(&mut problem, &y0, &settings(method, 10.0, 1e-10));
    assert!(long.fault.is_none(), "{:?}", long.fault);
    let last = long.trajectory.rows.last().expect("rows");
    println!("block ({method:?}) at rest after {} steps, {} events", long.steps, long.modes.len());
    assert!(long.steps < 1000);
    let half = 0.5 * mass * GRAVITY;
    assert!((last[6] - half).abs() < 1e-6 * half && (last[8] - half).abs() < 1e-6 * half);
    assert!(last[2].abs() < 1e-9 && last[3..6].iter().all(|v| v.abs() < 1e-9), "{last:?}");
}

#[test]
fn radau_on_the_physical_form_takes_the_jumps_as_auto_may_switch_to_it() {
    let mut problem = ball(1.0, 0.5);
    let settings = settings(Method::Radau, 3.0, 1e-9);
    let run =
        integrate(&mut problem, &[1.0, 0.0], &settings, &[], &mut |_| ControlFlow::Continue(()));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let settled = run.modes.iter().find(|m| m.kind == ModeChange::Settled).expect("settled");
    let accumulation = (2.0 / GRAVITY).sqrt() * 3.0;
    println!("radau: settled at {} for {accumulation}, {} steps", settled.time, run.steps);
    assert!((settled.time - accumulation).abs() < 1e-8 * accumulation);
}

#[test]
fn radau_takes_the_contacts_in_the_differential_algebraic_form() {
    assert!(Method::Radau.handles_contacts());
    let settings = settings(Method::Radau, 3.0, 1e-9);
    let mut problem = sim::Constrained::new(ball(1.0, 0.5));
    let y0 = problem.consistent_state(0.0, &[1.0, 0.0]).expect("consistent");
    let run = integrate(&mut problem, &y0, &settings, &[], &mut |_| ControlFlow::Continue(()));
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let settled = run.modes.iter().find(|m| m.kind == ModeChange::Settled).expect("settled");
    let accumulation = (2.0 / GRAVITY).sqrt() * 3.0;
    println!("radau (DAE): settled at {} for {accumulation}, {} steps", settled.time, run.steps);
    assert!((settled.time - accumulation).abs() < 1e-8 * accumulation);
    let last = run.trajectory.rows.last().expect("rows");
    assert!((last[2] - GRAVITY).abs() < 1e-9 * GRAVITY, "λ = {}", last[2]);
}

#[test]
fn a_rod_landing_flat_lands_on_both_ends_at_once() {
    // The centre (x, y) and the angle φ of a rod of half-length l, dropped flat from h.
    let (mass, half, h, e): (f64, f64, f64, f64) = (2.0, 0.5, 1.0, 0.6);
    let mut scene = Scene::new(&["x", "y", "phi"]);
    let (y, phi) = (scene.q(1), scene.q(2));
    let sin = scene.pool.sin(phi);
    let arm = {
        let l = scene.num(half);
        scene.pool.mul(&[l, sin])
    };
    let left = scene.pool.sub(y, arm);
    let right = scene.pool.add(&[y, arm]);
    let m = scene.num(mass);
    let inertia = scene.num(mass * half * half / 3.0);
    let zero = scene.pool.zero();
    let weight = scene.num(-mass * GRAVITY);
    let mass_matrix = [m, zero, zero, zero, m, zero, zero, zero, inertia];
    let mut problem = scene
        .mechanical(
            &mass_matrix,
            &[zero, weight, zero],
            &[Kept::Position(left), Kept::Position(right)],
        )
        .with_contacts(vec![
            Contact { normal: 0, grip: None, cross: None, restitution: e, friction: None },
            Contact { normal: 1, grip: None, cross: None, restitution: e, friction: None },
        ]);
    let t1 = (2.0 * h / GRAVITY).sqrt();
    let run = run(
        &mut problem,
        &[0.0, h, 0.0, 0.0, 0.0, 0.0],
        &settings(Method::Dop853, 1.5 * t1, 1e-10),
    );
    assert!(run.fault.is_none(), "{:?}", run.fault);
    assert_eq!(run.modes.len(), 2, "{:?}", run.modes);
    let v = GRAVITY * t1;
    for (k, event) in run.modes.iter().enumerate() {
        assert_eq!((event.contact, event.kind, event.closed), (k, ModeChange::Impact, false));
        assert!((event.time - t1).abs() < 1e-12 * t1);
        let expected = (1.0 + e) * mass * v / 2.0;
        assert!((event.impulse - expected).abs() < 1e-9 * expected, "{}", event.impulse);
    }
    let end = &run.final_state;
    assert!(end[2].abs() < 1e-12 && end[5].abs() < 1e-12, "it turned: {end:?}");
    // Up at e·v, decelerating: at 1.5·t1 its rate is e·v − g·t1/2.
    assert!((end[4] - (e * v - 0.5 * GRAVITY * t1)).abs() < 1e-9 * v, "{end:?}");
}

#[test]
fn a_particle_leaves_a_smooth_hemisphere_where_the_closed_form_says() {
    // The particle at (x, y) outside the sphere x² + y² ≥ R², from θ0 off the top at v0.
    let (mass, radius): (f64, f64) = (0.5, 2.0);
    let leaves = |theta0: f64, v0: f64| {
        let mut scene = Scene::new(&["x", "y"]);
        let (x, y) = (scene.q(0), scene.q(1));
        let two = scene.pool.int(2);
        let (xx, yy) = (scene.pool.pow(x, two), scene.pool.pow(y, two));
        let r2 = scene.num(radius * radius);
        let sum = scene.pool.add(&[xx, yy]);
        let gap = scene.pool.sub(sum, r2);
        let m = scene.num(mass);
        let zero = scene.pool.zero();
        let weight = scene.num(-mass * GRAVITY);
        let mut problem = scene
            .mechanical(&[m, zero, zero, m], &[zero, weight], &[Kept::Position(gap)])
            .with_contacts(vec![Contact {
                normal: 0,
                grip: None,
                cross: None,
                restitution: 0.0,
                friction: None,
            }]);
        let (s, c) = numeric::elementary::sin_cos(theta0);
        let y0 = [radius * s, radius * c, v0 * c, -v0 * s];
        let run = run(&mut problem, &y0, &settings(Method::Dop853, 2.0, 1e-10));
        assert!(run.fault.is_none(), "{:?} {:?}", run.fault, &run.modes[..run.modes.len().min(12)]);
        (run.modes, run.trajectory)
    };
    for (theta0, v0) in [(0.1, 0.0), (0.3, 1.5), (0.0, 2.0)] {
        let (modes, trajectory) = leaves(theta0, v0);
        let lift = modes.iter().find(|m| m.kind == ModeChange::LiftOff).expect("it leaves");
        let at = trajectory.times.iter().position(|&t| t == lift.time).expect("its rows");
        let row = &trajectory.rows[at];
        let cos = row[1] / (row[0] * row[0] + row[1] * row[1]).sqrt();
        let expected =
            2.0 / 3.0 * numeric::elementary::sin_cos(theta0).1 + v0 * v0 / (3.0 * GRAVITY * radius);
        assert!((cos - expected).abs() < 1e-8, "θ0 {theta0}, v0 {v0}: cos θ {cos} for {expected}");
        // Free, it flies as a projectile: x' constant, no reaction.
        let after = &trajectory.rows[at + 1..];
        assert!(after.iter().all(|r| (r[2] - after[0][2]).abs() < 1e-9 && r[4] == 0.0));
    }
    // From rest at the very top it never moves: an equilibrium.
    let (modes, trajectory) = leaves(0.0, 0.0);
    assert!(modes.iter().all(|m| m.kind == ModeChange::Closed), "{modes:?}");
    let last = trajectory.rows.last().expect("rows");
    assert!(last[0].abs() < 1e-12 && (last[4] * 2.0 * radius - mass * GRAVITY).abs() < 1e-9);
}

#[test]
fn a_ball_dropped_plastically_on_a_resting_stack_strikes_every_contact_below() {
    let (mass, radius, h) = (0.5, 0.5, 0.5);
    let mut problem = column(3, mass, radius, 0.0);
    let run = run(
        &mut problem,
        &[0.5, 1.5, 2.5 + h, 0.0, 0.0, 0.0],
        &settings(Method::Dop853, 1.0, 1e-10),
    );
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let t1 = (2.0 * h / GRAVITY).sqrt();
    let momentum = mass * GRAVITY * t1;
    let landing: Vec<_> = run.modes.iter().filter(|m| m.time > 0.0).collect();
    assert_eq!(landing.len(), 3, "{landing:?}");
    for (k, event) in landing.iter().enumerate() {
        let kind = if k == 2 { ModeChange::Impact } else { ModeChange::Struck };
        assert_eq!((event.contact, event.kind, event.closed), (k, kind, true));
        assert!((event.time - t1).abs() < 1e-12);
        // The floor stops the column at once: each contact passes the top ball's momentum.
        assert!((event.impulse - momentum).abs() < 1e-9 * momentum, "{event:?}");
    }
    // The energy lost is the top ball's, taken at its own contact.
    let lost = 0.5 * mass * (GRAVITY * t1) * (GRAVITY * t1);
    assert!((landing[2].energy_change + lost).abs() < 1e-9 * lost);
    assert!(landing[0].energy_change.abs() < 1e-9 * lost);
    let last = run.trajectory.rows.last().expect("rows");
    for k in 0..3 {
        let expected = (3 - k) as f64 * mass * GRAVITY;
        assert!((last[6 + k] - expected).abs() < 1e-9 * expected, "λ{k} {last:?}");
    }
}

#[test]
fn a_rimless_wheel_walks_down_a_slope_at_mcgeers_steady_rate() {
    // Eight spokes of length l, 2α = π/4 apart, on a slope γ; in the slope's frame (x down it,
    // y off it) the hub (x, y) and φ, spoke k at φ + 2αk from the slope's normal, its tip at
    // (x + l·sin, y − l·cos), gripping and landing plastically.
    let (mass, inertia, l, slope): (f64, f64, f64, f64) = (1.0, 0.1, 1.0, 0.1);
    let spokes = 8;
    let alpha = std::f64::consts::PI / spokes as f64;
    let mut scene = Scene::new(&["x", "y", "phi"]);
    let (x, y, phi) = (scene.q(0), scene.q(1), scene.q(2));
    let length = scene.num(l);
    let mut kept = Vec::new();
    for k in 0..spokes {
        let pi = scene.pool.pi();
        let turn = scene.pool.ratio(2 * k as i64, spokes as i64);
        let offset = scene.pool.mul(&[turn, pi]);
        let angle = scene.pool.add(&[phi, offset]);
        let (sin, cos) = (scene.pool.sin(angle), scene.pool.cos(angle));
        let along = {
            let arm = scene.pool.mul(&[length, sin]);
            scene.pool.add(&[x, arm])
        };
        let height = {
            let arm = scene.pool.mul(&[length, cos]);
            scene.pool.sub(y, arm)
        };
        let slip = scene.along_rates(along);
        kept.push(Kept::Position(height));
        kept.push(Kept::Velocity(slip));
    }
    let m = scene.num(mass);
    let i = scene.num(inertia);
    let zero = scene.pool.zero();
    let (s, c) = numeric::elementary::sin_cos(slope);
    let down = scene.num(mass * GRAVITY * s);
    let into = scene.num(-mass * GRAVITY * c);
    let contacts = (0..spokes)
        .map(|k| Contact {
            normal: 2 * k,
            grip: Some(2 * k + 1),
            cross: None,
            restitution: 0.0,
            friction: None,
        })
        .collect();
    let mut problem = scene
        .mechanical(&[m, zero, zero, zero, m, zero, zero, zero, i], &[down, into, zero], &kept)
        .with_contacts(contacts);
    let whole = inertia + mass * l * l;
    let (sin_a, cos_a) = numeric::elementary::sin_cos(alpha);
    let ratio = (inertia + mass * l * l * (cos_a * cos_a - sin_a * sin_a)) / whole;
    let lift = 4.0 * mass * GRAVITY * l * sin_a * s / whole;
    let steady = ratio * lift.sqrt() / (1.0 - ratio * ratio).sqrt();
    // Just after a landing on spoke 0 at φ = α, rolling downhill (φ decreasing) 10% fast.
    let phi0 = alpha * (1.0 - 1e-6);
    let (sp, cp) = numeric::elementary::sin_cos(phi0);
    let omega = 1.1 * steady;
    let y0 = [-l * sp, l * cp, phi0, l * cp * omega, l * sp * omega, -omega];
    let mut settings = settings(Method::Dop853, 30.0, 1e-10);
    settings.samples = 301;
    let run = run(&mut problem, &y0, &settings);
    assert!(run.fault.is_none(), "{:?}", run.fault);
    let landings: Vec<_> = run.modes.iter().filter(|m| m.kind == ModeChange::Impact).collect();
    assert!(landings.len() > 40, "{} landings", landings.len());
    let mut rates = Vec::new();
    for landing in &landings {
        let at = run.trajectory.times.iter().position(|&t| t == landing.time).expect("rows");
        let (before, after) = (run.trajectory.rows[at][5], run.trajectory.rows[at + 1][5]);
        assert!((after / before - ratio).abs() < 1e-8, "ω⁺/ω⁻ {} for {ratio}", after / before);
        rates.push(-after);
    }
    let last = *rates.last().expect("a landing");
    println!("rimless wheel: {} landings, ω⁺ → {last} for {steady}", landings.len());
    assert!((last - steady).abs() < 1e-8 * steady, "ω⁺ {last} for {steady}");
}
