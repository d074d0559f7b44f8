//! Periodic orbits: McGeer's rimless wheel (`examples/contacts/rimless_wheel.lag`, the map
//! from one landing to the next, the angle shifted back by a spoke and the distance rolled left
//! out) and the driven, damped pendulum (`examples/orbits/driven_pendulum.lag` at A = 1 N·m,
//! where its response is far from linear, the map over one period), found by `orbit` from each
//! scene's start at tolerance 1e-10 on a scene loaded once ([`orbit::Search`]).
//!
//! Garcia's simplest walker (`examples/contacts/simplest_walker.lag`, its stride map from one
//! heel strike to the next with its legs swapped) is the third.
//!
//! Accuracy against closed forms: the wheel's one multiplier against c² =
//! ((I + m·l²·cos 2α)/(I + m·l²))², the pendulum's product of multipliers against Liouville's
//! exp(−c·T/(m·l²)). The walker has none: its feet weigh β·M, the paper's nothing, so ours is
//! held to its own search at tolerance 1e-12 and the peer's (the paper's model) to the product
//! of the paper's map's multipliers by central differences of its equations at 1e-13.
//!
//! Cost: the median wall time of a search (every Newton run, from the scene's start), the
//! one-time load apart, over at least `--repeats` searches spanning at least three seconds on
//! each side. With the peer the two sides take turns, three of a second each, and the ratio is
//! taken turn by turn.
//!
//! With `--peer`, SciPy in the same run (`tests/sympy/orbit_peer.py`): the shooting loop a
//! SciPy user writes, Newton's method with the map's Jacobian by forward differences of whole
//! `solve_ivp` runs (DOP853 at the same rtol = atol, a relative step of 1e-7, the root of the
//! tolerance's digits), on models derived by hand (the wheel reduced to its stance angle).

// Closed forms the multipliers are held to, far above a last bit: the platform's functions
// serve.
#![allow(clippy::disallowed_methods)]

use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

use engine::input::Assignment;
use orbit::{Options, Orbit, Search, Section};

use crate::{median, seconds, SPAN};

const PEER: &str = "tests/sympy/orbit_peer.py";
const TOLERANCE: f64 = 1e-10;
/// The peer's relative difference step.
const STEP: f64 = 1e-7;

/// A scene, how `orbit` is asked about it, and its exact figure.
struct Scene {
    name: &'static str,
    file: &'static str,
    options: Options,
    /// What the peer is sent about it: its parameters and its start.
    params: serde_json::Value,
    start: Vec<f64>,
    /// The exact figure: c², or exp(−c·T/(m·l²)); the walker's |λ|² of the paper's model,
    /// which the peer integrates.
    exact: f64,
    figure: &'static str,
    /// Where the scene's model is not the peer's (the walker's feet weigh β·M, the paper's
    /// nothing), ours is held to its own search at this tolerance rather than to `exact`.
    own_reference: Option<f64>,
}

fn options(section: Section, set: &[(&str, &str)]) -> Options {
    let assign = |(n, v): &(&str, &str)| Assignment { name: n.to_string(), value: v.to_string() };
    Options {
        run: simulation::Options {
            tolerance: Some(TOLERANCE),
            set: set.iter().map(assign).collect(),
            ..Default::default()
        },
        section,
        swaps: Vec::new(),
        shifts: Vec::new(),
        ignore: Vec::new(),
        iterations: 30,
    }
}

fn scenes() -> [Scene; 3] {
    let mut wheel = options(Section::Landing { contact: None }, &[]);
    wheel.shifts = vec![Assignment { name: "theta".into(), value: "pi/4".into() }];
    wheel.ignore = vec!["x".into()];
    let (m, inertia, l, alpha) = (1.0, 0.1, 1.0, PI / 8.0);
    let c = (inertia + m * l * l * (2.0 * alpha).cos()) / (inertia + m * l * l);
    let (cd, w) = (0.5, 2.0);
    // The walker's stride map: from just after a strike to just after the next, its legs
    // swapped, the distance walked left out.
    let mut walker = options(Section::Landing { contact: None }, &[]);
    walker.swaps = vec![Assignment { name: "th1".into(), value: "th2".into() }];
    walker.ignore = vec!["x".into()];
    [
        Scene {
            name: "rimless wheel",
            file: "examples/contacts/rimless_wheel.lag",
            options: wheel,
            params: serde_json::json!({"m": m, "I": inertia, "l": l, "g": 9.81, "gamma": 0.1}),
            // The scene's start in the stance angle: φ = −θ.
            start: vec![-(PI / 8.0 - 0.01), 1.5],
            exact: c * c,
            figure: "μ against c²",
            own_reference: None,
        },
        Scene {
            name: "driven pendulum, A = 1",
            file: "examples/orbits/driven_pendulum.lag",
            options: options(Section::Period("2*pi/w".into()), &[("A", "1")]),
            params: serde_json::json!({"m": 1.0, "l": 1.0, "g": 9.81, "c": cd, "A": 1.0, "w": w}),
            start: vec![0.0, 0.0],
            exact: (-cd * 2.0 * PI / w).exp(),
            figure: "Πμ against exp(−cT/ml²)",
            own_reference: None,
        },
        Scene {
            name: "simplest walker",
            file: "examples/contacts/simplest_walker.lag",
            options: walker,
            params: serde_json::json!({"gamma": 0.009}),
            // The paper's gait just after a strike: (θ, θ').
            start: vec![0.20031090049483, -0.19983247291764],
            // |λ|² of Garcia's stride map, λ = −0.19009985 ± 0.55759878i (central differences
            // of its reduced equations at 1e-13).
            exact: 0.19009985f64.hypot(0.55759878).powi(2),
            figure: "Πμ against itself at 1e-12",
            own_reference: Some(1e-12),
        },
    ]
}

/// The relative error of an orbit's figure: the wheel's one multiplier, the pendulum's
/// product of multipliers.
fn error(multipliers: &[(f64, f64)], exact: f64) -> f64 {
    let (re, im) =
        multipliers.iter().fold((1.0, 0.0), |(a, b), &(c, d)| (a * c - b * d, a * d + b * c));
    (re - exact).hypot(im) / exact
}

fn ours(orbit: &Orbit) -> Vec<(f64, f64)> {
    orbit.multipliers.iter().map(|m| (m.re, m.im)).collect()
}

/// What the peer reported for a scene.
struct Theirs {
    error: f64,
    wall: f64,
    runs: usize,
    evaluations: usize,
}

fn scipy(root: &Path, scenes: &[Scene], repeats: usize, span: f64) -> Result<Vec<Theirs>, String> {
    let mut input = String::new();
    for scene in scenes {
        let kind = match scene.name {
            n if n.starts_with("rimless") => "wheel",
            n if n.starts_with("simplest") => "walker",
            _ => "pendulum",
        };
        let request = serde_json::json!({
            "scene": kind, "params": scene.params, "start": scene.start,
            "rtol": TOLERANCE, "step": STEP, "repeats": repeats, "span": span,
        });
        input += &(request.to_string() + "\n");
    }
    let text = crate::peer_lines(&root.join(PEER), &input)?;
    text.lines()
        .filter(|l| l.starts_with('{'))
        .zip(scenes)
        .map(|(line, scene)| {
            let v: serde_json::Value = serde_json::from_str(line).map_err(|e| e.to_string())?;
            let multipliers: Vec<(f64, f64)> = serde_json::from_value(v["multipliers"].clone())
                .map_err(|e| format!("the peer's multipliers: {e}"))?;
            Ok(Theirs {
                error: error(&multipliers, scene.exact),
                wall: v["wall"].as_f64().unwrap_or(f64::NAN),
                runs: v["runs"].as_u64().unwrap_or(0) as usize,
                evaluations: v["evaluations"].as_u64().unwrap_or(0) as usize,
            })
        })
        .collect()
}

/// With the peer, the two sides take turns this many times, each turn a third of [`SPAN`]:
/// this machine's speed moves in phases of seconds, which one side's whole span and then the
/// other's had met unequally (SciPy's wheel 8 ms in one run, 25 ms in another).
const ROUNDS: usize = 3;

/// `peer`: also run SciPy's shooting loop; `repeats`: how often each search is timed at least.
pub fn run(peer: bool, repeats: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scenes = scenes();
    let rounds = if peer { ROUNDS } else { 1 };
    let span = SPAN / rounds as f64;
    let turn_repeats = repeats.div_ceil(rounds);
    outln!("## Periodic orbits: Newton on the return map, and the multipliers\n");
    outln!(
        "dop853 at tolerance {TOLERANCE:e}, from each scene's start; the median of searches \
         repeated at least {repeats} times and for at least {SPAN} s (SciPy's too), the load \
         (parse, derive, lower) apart.\n"
    );
    let sources: Vec<String> = scenes
        .iter()
        .map(|scene| std::fs::read_to_string(root.join(scene.file)).expect("scene"))
        .collect();
    let mut searches = Vec::new();
    let mut loads = Vec::new();
    for (scene, source) in scenes.iter().zip(&sources) {
        let began = Instant::now();
        searches.push(Search::new(source, &scene.options).expect("the scene loads"));
        loads.push(began.elapsed().as_secs_f64());
    }
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); scenes.len()];
    let mut found: Vec<Option<Orbit>> = vec![None; scenes.len()];
    // Per turn, each side's median: the ratio is taken turn by turn.
    let mut turns: Vec<Vec<(f64, Theirs)>> = (0..scenes.len()).map(|_| Vec::new()).collect();
    let mut peer_failed = None;
    for _ in 0..rounds {
        let mut ours_this_turn = Vec::new();
        for (k, scene) in scenes.iter().enumerate() {
            // Both sides' searches take milliseconds: each repeats them until they span the
            // turn (the peer is asked for the same).
            let mut turn = Vec::new();
            let since = Instant::now();
            while turn.len() < turn_repeats.max(1) || since.elapsed().as_secs_f64() < span {
                let began = Instant::now();
                let orbit = searches[k].find(scene.options.iterations).expect("an orbit");
                turn.push(began.elapsed().as_secs_f64());
                found[k] = Some(orbit);
            }
            times[k].extend(&turn);
            ours_this_turn.push(median(&mut turn));
        }
        if !peer || peer_failed.is_some() {
            continue;
        }
        match scipy(&root, &scenes, turn_repeats, span) {
            Ok(theirs) => {
                for (k, t) in theirs.into_iter().enumerate() {
                    turns[k].push((ours_this_turn[k], t));
                }
            }
            Err(why) => peer_failed = Some(why),
        }
    }
    outln!("| scene | figure | Newton runs | error | load | search |");
    outln!("|---|---|---:|---:|---:|---:|");
    let mut walls = Vec::new();
    for (k, scene) in scenes.iter().enumerate() {
        let orbit = found[k].take().expect("a search");
        let wall = median(&mut times[k]);
        walls.push(wall);
        let exact = match scene.own_reference {
            None => scene.exact,
            Some(tolerance) => {
                let mut tight = scene.options.clone();
                tight.run.tolerance = Some(tolerance);
                let reference = orbit::orbit(&sources[k], &tight).expect("the reference orbit");
                let product = ours(&reference)
                    .iter()
                    .fold((1.0, 0.0), |(a, b), &(c, d)| (a * c - b * d, a * d + b * c));
                product.0
            }
        };
        outln!(
            "| {} | {} | {} | {:.1e} | {} | {} |",
            scene.name,
            scene.figure,
            orbit.iterations.len(),
            error(&ours(&orbit), exact),
            seconds(loads[k]),
            seconds(wall)
        );
    }
    outln!();
    if !peer {
        return;
    }
    if let Some(why) = peer_failed {
        outln!("SciPy not run: {why}\n");
        return;
    }
    outln!(
        "SciPy's shooting loop (solve_ivp DOP853 at rtol = atol = {TOLERANCE:e}, the Jacobian \
         by forward differences, relative step {STEP:e}), the two sides taking {ROUNDS} turns \
         of {span} s each; its search the median of its turns' medians, and ours faster the \
         median of the turns' ratios (their range beside it):\n"
    );
    outln!("| scene | runs | right-hand sides | error | search | ours faster | turns |");
    outln!("|---|---:|---:|---:|---:|---:|---|");
    for (scene, turns) in scenes.iter().zip(&turns) {
        let Some((_, last)) = turns.last() else { continue };
        let mut theirs: Vec<f64> = turns.iter().map(|(_, t)| t.wall).collect();
        let mut ratios: Vec<f64> = turns.iter().map(|(o, t)| t.wall / o).collect();
        let range =
            ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(*r), hi.max(*r)));
        outln!(
            "| {} | {} | {} | {:.1e} | {} | {:.1}× | {:.1}–{:.1}× |",
            scene.name,
            last.runs,
            last.evaluations,
            last.error,
            seconds(median(&mut theirs)),
            median(&mut ratios),
            range.0,
            range.1
        );
    }
    outln!();
}
