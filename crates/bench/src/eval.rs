//! The cost of one evaluation of M and f, and of one right-hand side (M q̈ = f solved), for
//! the n-link pendulum: the tape evaluator, the generated Rust, and the hand-written floor.
//! The generated and hand-written code are compiled together by `rustc -O` into a small
//! program in a temporary folder, which times itself and prints the figures.

use std::fmt::Write;
use std::hint::black_box;
use std::process::Command;

use lang::generate::{n_link, Family};
use numeric::Tape;
use sim::{Mechanical, Problem};

pub const SIZES: [usize; 4] = [2, 4, 8, 20];

/// A state of the chain that is not special: no zero angles, no equal rates.
fn state(n: usize) -> (Vec<f64>, Vec<f64>) {
    let theta = (0..n).map(|i| 0.3 + 0.11 * i as f64 - 0.02 * (i * i % 7) as f64).collect();
    let rate = (0..n).map(|i| 0.7 - 0.13 * i as f64 + 0.05 * (i % 3) as f64).collect();
    (theta, rate)
}

struct Row {
    n: usize,
    ops: usize,
    tape_mf: f64,
    tape_rhs: f64,
    gen_mf: f64,
    gen_rhs: f64,
    hand_mf: f64,
    hand_rhs: f64,
}

/// The timing program: the generated modules, the hand-written function, and a main that
/// prints `n kind seconds` lines.
const TIMER: &str = r#"
use std::hint::black_box;
use std::time::Instant;

fn per_call(mut f: impl FnMut()) -> f64 {
    let mut iterations = 1usize;
    loop {
        let start = Instant::now();
        for _ in 0..iterations { f(); }
        let took = start.elapsed().as_secs_f64();
        if took > 0.02 || iterations > 1 << 30 { break; }
        iterations *= if took < 0.002 { 10 } else { 2 };
    }
    let mut times: Vec<f64> = (0..7).map(|_| {
        let start = Instant::now();
        for _ in 0..iterations { f(); }
        start.elapsed().as_secs_f64() / iterations as f64
    }).collect();
    times.sort_by(f64::total_cmp);
    times[3]
}
"#;

pub fn run() {
    outln!("## One evaluation (n-link pendulum; median of 7 batches of ≥ 20 ms each)");
    let dir = std::env::temp_dir().join(format!("lagrange-bench-eval-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("hand.rs"), include_str!("hand.rs")).expect("write");
    let mut main = String::from(TIMER);
    let _ = writeln!(main, "#[path = \"hand.rs\"]\nmod hand;");
    let mut body = String::from("fn main() {\n");
    let rows: Vec<Row> =
        SIZES.into_iter().map(|n| on_the_tape(n, &dir, &mut main, &mut body)).collect();
    body.push_str("}\n");
    main.push_str(&body);
    std::fs::write(dir.join("main.rs"), &main).expect("write");
    let rows = compiled(&dir, rows);
    table(&rows);
    four_link_rhs();
    many_points();
    sine_and_cosine();
    powers();
    double_pendulum_many();
    let _ = std::fs::remove_dir_all(&dir);
}

/// The n-link pendulum measured on the tape, after checking the hand-written floor against
/// it; its generated module written into `dir` and its timing code added to the program's
/// `main` and `body`.
fn on_the_tape(n: usize, dir: &std::path::Path, main: &mut String, body: &mut String) -> Row {
    let scene = n_link(Family::Pendulum, n);
    let mut prepared =
        engine::numbers::prepare(&scene, &[], engine::Options::default()).expect("derives");
    let names: Vec<String> = prepared
        .parameters
        .iter()
        .map(|s| prepared.derivation.model.pool.symbol(*s).name.clone())
        .collect();
    assert_eq!(names, ["m", "l", "g"], "the generator's parameter order");
    let (m, l, g) = (1.0, 1.0, 9.81);
    let exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let ops = dynamics.op_counts().total();
    let observation = prepared.lower(&prepared.observation_inputs(), &[]).expect("lowers");
    let (theta, rate) = state(n);
    let mut input = vec![0.0];
    input.extend(&theta);
    input.extend(&rate);
    input.extend([m, l, g]);

    // The floor must be right before it is fast: it matches the tape to 1e-12.
    let mut tape = Tape::new(dynamics.clone());
    let mut out = vec![0.0; n * n + n];
    tape.eval(&input, &mut out);
    let (mut trig, mut mass, mut f) = (vec![0.0; 2 * n], vec![0.0; n * n], vec![0.0; n]);
    crate::hand::n_link_mass_forcing(&theta, &rate, m, l, g, &mut trig, &mut mass, &mut f);
    let scale = out.iter().fold(1.0f64, |a, v| a.max(v.abs()));
    for (k, (a, b)) in out.iter().zip(mass.iter().chain(&f)).enumerate() {
        assert!(
            (a - b).abs() <= 1e-12 * scale,
            "n = {n}: hand-written value {k} is {b}, the tape says {a}"
        );
    }

    let tape_mf = crate::per_call(|| tape.eval(black_box(&input), black_box(&mut out)));
    let layout = prepared.layout;
    let mut mech =
        Mechanical::new(layout, Tape::new(dynamics), Tape::new(observation), vec![m, l, g]);
    let y: Vec<f64> = theta.iter().chain(&rate).copied().collect();
    let tape_rhs = rhs_per_call(&mut mech, &y);

    let module = export::codegen::codegen("generated.lag", &scene).expect("codegen");
    std::fs::write(dir.join(format!("m{n}.rs")), &module.source).expect("write");
    let _ = writeln!(main, "#[path = \"m{n}.rs\"]\nmod m{n};");
    body.push_str(&timing_block(n, &input, &y, (m, l, g)));
    Row {
        n,
        ops,
        tape_mf,
        tape_rhs,
        gen_mf: f64::NAN,
        gen_rhs: f64::NAN,
        hand_mf: f64::NAN,
        hand_rhs: f64::NAN,
    }
}

/// The program's timing of the generated module and the hand-written floor for one n: lines
/// `n kind seconds` on its standard output.
fn timing_block(n: usize, input: &[f64], y: &[f64], (m, l, g): (f64, f64, f64)) -> String {
    let lit = |v: &[f64]| v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ");
    format!(
        r#"    {{
        let input: [f64; {len}] = [{input}];
        let y: [f64; {n2}] = [{y}];
        let (mut mass, mut f, mut dy) = ([0.0; {nn}], [0.0; {n}], [0.0; {n2}]);
        let t = per_call(|| {{ m{n}::mass_matrix(black_box(&input), &mut mass); m{n}::forcing(black_box(&input), &mut f); black_box((&mass, &f)); }});
        println!("{n} gen_mf {{t:e}}");
        let t = per_call(|| {{ m{n}::rhs(0.0, black_box(&y), &m{n}::PARAMETERS, &[], &mut dy); black_box(&dy); }});
        println!("{n} gen_rhs {{t:e}}");
        let (theta, rate) = y.split_at({n});
        let mut trig = [0.0; {n2}];
        let t = per_call(|| {{ hand::n_link_mass_forcing(black_box(theta), black_box(rate), {m:?}, {l:?}, {g:?}, &mut trig, &mut mass, &mut f); black_box((&mass, &f)); }});
        println!("{n} hand_mf {{t:e}}");
        let t = per_call(|| {{
            hand::n_link_mass_forcing(black_box(theta), black_box(rate), {m:?}, {l:?}, {g:?}, &mut trig, &mut mass, &mut f);
            // M is symmetric, so its column-major storage is the row-major the solver takes.
            let ok = m{n}::solve_in_place({n}, &mut mass, &mut f);
            black_box((ok, &f));
        }});
        println!("{n} hand_rhs {{t:e}}");
    }}
"#,
        len = input.len(),
        input = lit(input),
        n2 = 2 * n,
        y = lit(y),
        nn = n * n,
    )
}

/// The timing program built with `rustc -O` and run, its figures filled into the rows.
fn compiled(dir: &std::path::Path, mut rows: Vec<Row>) -> Vec<Row> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let binary = dir.join("timer");
    let compiled = Command::new(&rustc)
        .args(["--edition", "2021", "-O", "-A", "warnings", "-o"])
        .arg(&binary)
        .arg(dir.join("main.rs"))
        .status();
    match compiled {
        Ok(s) if s.success() => {
            let output = Command::new(&binary).output().expect("the timer runs");
            for line in String::from_utf8_lossy(&output.stdout).lines() {
                let parts: Vec<&str> = line.split_whitespace().collect();
                let [n, kind, t] = parts[..] else { continue };
                let (Ok(n), Ok(t)) = (n.parse::<usize>(), t.parse::<f64>()) else { continue };
                let Some(row) = rows.iter_mut().find(|r| r.n == n) else { continue };
                match kind {
                    "gen_mf" => row.gen_mf = t,
                    "gen_rhs" => row.gen_rhs = t,
                    "hand_mf" => row.hand_mf = t,
                    "hand_rhs" => row.hand_rhs = t,
                    _ => {}
                }
            }
        }
        _ => outln!(
            "(rustc could not build the timing program in {}; no generated figures)",
            dir.display()
        ),
    }
    rows
}

fn table(rows: &[Row]) {
    outln!(
        "{:>3} {:>7} | {:>10} {:>10} {:>10} | {:>10} {:>10} {:>10} | {:>9} {:>9}",
        "n",
        "ops",
        "tape M,f",
        "gen M,f",
        "hand M,f",
        "tape rhs",
        "gen rhs",
        "hand rhs",
        "gen/hand",
        "tape/gen"
    );
    for r in rows {
        outln!(
            "{:>3} {:>7} | {:>10} {:>10} {:>10} | {:>10} {:>10} {:>10} | {:>9.2} {:>9.2}",
            r.n,
            r.ops,
            crate::seconds(r.tape_mf),
            crate::seconds(r.gen_mf),
            crate::seconds(r.hand_mf),
            crate::seconds(r.tape_rhs),
            crate::seconds(r.gen_rhs),
            crate::seconds(r.hand_rhs),
            r.gen_mf / r.hand_mf,
            r.tape_mf / r.gen_mf
        );
    }
}

/// The n-link pendulum's problem with m = l = 1 and g = 9.81, observing nothing.
fn unit_chain(prepared: &engine::numbers::Prepared, dynamics: numeric::Program) -> Mechanical {
    let observation = prepared.lower(&prepared.observation_inputs(), &[]).expect("lowers");
    Mechanical::new(
        prepared.layout,
        Tape::new(dynamics),
        Tape::new(observation),
        vec![1.0, 1.0, 9.81],
    )
}

/// The 4-link pendulum's right-hand side has its own target; measured on the tape too.
fn four_link_rhs() {
    let scene = n_link(Family::Pendulum, 4);
    let mut prepared =
        engine::numbers::prepare(&scene, &[], engine::Options::default()).expect("derives");
    let exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let mut mech = unit_chain(&prepared, dynamics);
    let (theta, rate) = state(4);
    let y: Vec<f64> = theta.iter().chain(&rate).copied().collect();
    let t = rhs_per_call(&mut mech, &y);
    outln!(
        "4-link pendulum, one right-hand side on the tape (sim::Mechanical): {}",
        crate::seconds(t)
    );
    outln!("(gen, hand: rustc -O; tape: this binary; rhs = M, f and the solve of M q'' = f)\n");
}

/// M and f at many states at once on the batch tape, per state, against the tape one state at
/// a time (the same bits: `numeric`'s tests hold them so).
fn many_points() {
    const POINTS: usize = 1024;
    outln!();
    outln!(
        "At {POINTS} states, per state: M and f on the tape one state at a time and on the batch"
    );
    outln!(
        "tape ({} states a register); the right-hand side by rhs and by rhs_many",
        numeric::LANES
    );
    outln!(
        "{:>3} | {:>10} {:>10} {:>7} | {:>10} {:>10} {:>7}",
        "n",
        "tape M,f",
        "batch M,f",
        "speedup",
        "rhs",
        "rhs_many",
        "speedup"
    );
    for n in SIZES {
        let scene = n_link(Family::Pendulum, n);
        let mut prepared =
            engine::numbers::prepare(&scene, &[], engine::Options::default()).expect("derives");
        let exprs = prepared.dynamics_exprs();
        let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
        let width = dynamics.inputs;
        let (theta, rate) = state(n);
        let inputs: Vec<f64> = (0..POINTS)
            .flat_map(|i| {
                let shift = i as f64 * 1e-3;
                let mut row = vec![0.0];
                row.extend(theta.iter().map(|v| v + shift));
                row.extend(rate.iter().map(|v| v - shift));
                row.extend([1.0, 1.0, 9.81]);
                row
            })
            .collect();
        assert_eq!(inputs.len(), POINTS * width, "the n-link's inputs");
        let (one, many) = tape_and_batch(&dynamics, &inputs);
        let mut mech = unit_chain(&prepared, dynamics);
        let times = vec![0.0; POINTS];
        let ys: Vec<f64> =
            inputs.chunks(width).flat_map(|row| row[1..1 + 2 * n].to_vec()).collect();
        let mut dys = vec![0.0; ys.len()];
        let rhs = crate::per_call(|| {
            for (y, dy) in ys.chunks(2 * n).zip(dys.chunks_mut(2 * n)) {
                mech.rhs(0.0, black_box(y), black_box(dy)).expect("regular");
            }
        }) / POINTS as f64;
        let rhs_many = crate::per_call(|| {
            mech.rhs_many(&times, black_box(&ys), black_box(&mut dys)).expect("regular");
        }) / POINTS as f64;
        outln!(
            "{n:>3} | {:>10} {:>10} {:>7.2} | {:>10} {:>10} {:>7.2}",
            crate::seconds(one),
            crate::seconds(many),
            one / many,
            crate::seconds(rhs),
            crate::seconds(rhs_many),
            rhs / rhs_many
        );
    }
}

/// The time of one right-hand side at `y` and at a state near it, in turn: `Mechanical` keeps
/// its last solve for a step's observations, and would reuse it for one state called again.
fn rhs_per_call(mech: &mut Mechanical, y: &[f64]) -> f64 {
    let mut near = y.to_vec();
    if let Some(rate) = near.last_mut() {
        *rate += 1e-3;
    }
    let states = [y, &near[..]];
    let mut dy = vec![0.0; y.len()];
    let mut turn = 0;
    crate::per_call(|| {
        turn ^= 1;
        mech.rhs(0.0, black_box(states[turn]), black_box(&mut dy)).expect("regular");
    })
}

/// 4,096 arguments, eight a group, `at` the fractional parts of the multiples of the golden
/// ratio: spread evenly over [0, 1) with no two alike and no pattern a branch predictor could
/// learn in eight lanes.
fn spread(at: impl Fn(f64) -> f64) -> Vec<[f64; numeric::LANES]> {
    const ARGUMENTS: usize = 4096;
    (0..ARGUMENTS / numeric::LANES)
        .map(|group| {
            std::array::from_fn(|lane| {
                let k = (group * numeric::LANES + lane) as f64;
                at((k * 0.618_033_988_749_895) % 1.0)
            })
        })
        .collect()
}

/// Eight sines and cosines by `libm::sincos` one lane at a time against
/// `numeric::elementary::sin_cos_lanes` (the same bits: `numeric`'s tests hold them so), at
/// angles |x| < 10.
fn sine_and_cosine() {
    let angles = spread(|u| u * 20.0 - 10.0);
    // Each result stored, not summed: a running sum would be a chain of additions as long as
    // the timed work.
    type Pair = ([f64; numeric::LANES], [f64; numeric::LANES]);
    let mut out: Pair = ([0.0; numeric::LANES], [0.0; numeric::LANES]);
    let mut time = |f: &dyn Fn(&[f64; numeric::LANES], &mut Pair)| {
        crate::per_call(|| {
            for x in &angles {
                f(black_box(x), &mut out);
                black_box(&mut out);
            }
        }) / angles.len() as f64
    };
    let sincos = time(&|x, (s, c)| {
        for lane in 0..numeric::LANES {
            (s[lane], c[lane]) = libm::sincos(x[lane]);
        }
    });
    let sin = time(&|x, (s, _)| *s = x.map(libm::sin));
    let cos = time(&|x, (_, c)| *c = x.map(libm::cos));
    let lanes = time(&|x, (s, c)| numeric::elementary::sin_cos_lanes(x, s, c));
    outln!();
    outln!("Eight arguments at |x| < 10, one lane at a time by libm and at once by sin_cos_lanes");
    outln!("{:>10} {:>10} {:>10} | {:>10} {:>7}", "sincos", "sin", "cos", "lanes", "sincos/lanes");
    outln!(
        "{:>10} {:>10} {:>10} | {:>10} {:>7.2}",
        crate::seconds(sincos),
        crate::seconds(sin),
        crate::seconds(cos),
        crate::seconds(lanes),
        sincos / lanes
    );
}

/// Eight powers by `libm::pow` one lane at a time against `numeric::elementary::pow_lanes`
/// (the same bits: `numeric`'s tests hold them so), at the step-size controls' exponents
/// (DOP853's −1/8, dopri5's −1/5) and bases spread over the error norms they meet, 1e-6 to
/// 1e6: as the lanes are compiled here (the baseline instructions) and as the integrator
/// compiles them (through pulp, for the widest vectors its features reach on the processor).
fn powers() {
    let bases = spread(|u| libm::pow(10.0, u * 12.0 - 6.0));
    let arch = pulp::Arch::new();
    outln!();
    outln!("Eight bases in [1e-6, 1e6] to one power, one lane at a time by libm and at once by pow_lanes");
    outln!(
        "{:>8} {:>10} | {:>10} {:>7} | {:>10} {:>7}",
        "y",
        "pow",
        "lanes",
        "ratio",
        "widest",
        "ratio"
    );
    for y in [-1.0 / 8.0, -1.0 / 5.0] {
        let mut out = [0.0; numeric::LANES];
        let mut time = |f: &dyn Fn(&[f64; numeric::LANES]) -> [f64; numeric::LANES]| {
            crate::per_call(|| {
                for x in &bases {
                    out = f(black_box(x));
                    black_box(&mut out);
                }
            }) / bases.len() as f64
        };
        let libm = time(&|x| x.map(|base| libm::pow(base, y)));
        let lanes = time(&|x| numeric::elementary::pow_lanes(x, y));
        let widest =
            crate::per_call(|| arch.dispatch(Powers { bases: &bases, y })) / bases.len() as f64;
        outln!(
            "{:>8.3} {:>10} | {:>10} {:>7.2} | {:>10} {:>7.2}",
            y,
            crate::seconds(libm),
            crate::seconds(lanes),
            libm / lanes,
            crate::seconds(widest),
            libm / widest
        );
    }
}

/// `pow_lanes` over every group of bases, compiled for the vector instructions at hand.
struct Powers<'a> {
    bases: &'a [[f64; numeric::LANES]],
    y: f64,
}

impl pulp::WithSimd for Powers<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        for x in self.bases {
            black_box(numeric::elementary::pow_lanes(black_box(x), self.y));
        }
    }
}

/// M and f of the double pendulum (`examples/classics/double_pendulum_flip.lag`) at 1,024
/// states, per state: the tape one state at a time and the batch tape, whose sines and cosines
/// are computed eight at a time.
fn double_pendulum_many() {
    const POINTS: usize = 1024;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = std::fs::read_to_string(root.join("examples/classics/double_pendulum_flip.lag"))
        .expect("the scene");
    let mut prepared =
        engine::numbers::prepare(&scene, &[], engine::Options::default()).expect("derives");
    let exprs = prepared.dynamics_exprs();
    let dynamics = prepared.lower(&prepared.dynamics_inputs(), &exprs).expect("lowers");
    let model = &prepared.derivation.model;
    let parameters: Vec<f64> = model
        .constants()
        .iter()
        .map(|(_, value)| value.map_or(1.0, |e| numeric::eval(&model.pool, e, &[])))
        .collect();
    let width = dynamics.inputs;
    let inputs: Vec<f64> = (0..POINTS)
        .flat_map(|i| {
            let k = i as f64;
            let turn = |a: f64| (k * a) % 1.0;
            let mut row = vec![0.0, 6.0 * turn(0.618) - 3.0, 6.0 * turn(0.414) - 3.0];
            row.extend([4.0 * turn(0.732) - 2.0, 4.0 * turn(0.236) - 2.0]);
            row.extend(&parameters);
            row
        })
        .collect();
    assert_eq!(inputs.len(), POINTS * width, "the double pendulum's inputs");
    let (one, many) = tape_and_batch(&dynamics, &inputs);
    let counts = dynamics.op_counts();
    outln!(
        "The double pendulum's M and f ({counts}) at {POINTS} states, per state: tape, batch tape"
    );
    outln!(
        "{:>10} {:>10} {:>7}",
        crate::seconds(one),
        crate::seconds(many),
        format!("{:.2}", one / many)
    );
}

/// The time per point of `program` at every point of `inputs` (a row each): on the tape one
/// point at a time, and on the batch tape.
fn tape_and_batch(program: &numeric::Program, inputs: &[f64]) -> (f64, f64) {
    let (width, outputs) = (program.inputs, program.outputs.len());
    let points = inputs.len() / width;
    let mut out = vec![0.0; points * outputs];
    let mut tape = Tape::new(program.clone());
    let one = crate::per_call(|| {
        for (point, row) in inputs.chunks(width).zip(out.chunks_mut(outputs)) {
            tape.eval(black_box(point), black_box(row));
        }
    }) / points as f64;
    let mut batch = numeric::BatchTape::new(program.clone());
    let many =
        crate::per_call(|| batch.eval_many(black_box(inputs), black_box(&mut out))) / points as f64;
    (one, many)
}
