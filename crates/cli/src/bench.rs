//! `lagrange bench`: what each method and tolerance buys on one scene. Every integrator runs
//! over a ladder of tolerances (adaptive methods) or step counts (fixed-step methods); each
//! run's final state is compared with a tight-tolerance reference, and the table gives the
//! error, the wall time (median of a few repeats) and the right-hand-side evaluations. The
//! work–precision diagram plots error against time, one line per method. A method that cannot
//! run the scene at all (a symplectic one, when a constraint keeps a multiplier) is listed as
//! not applicable rather than failing the whole comparison.

use std::fmt::Write;

use sim::Method;

use crate::simulate::{simulate, Failure, Options, Outcome, NO_MULTIPLIERS};

/// What one rung of a ladder sets: a tolerance, or a number of fixed steps over the span.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    Tolerance(f64),
    Steps(usize),
}

impl Setting {
    pub fn label(&self) -> String {
        match self {
            Setting::Tolerance(t) => format!("tol {t:.0e}"),
            Setting::Steps(n) => format!("{n} steps"),
        }
    }
}

/// The ladder of a method: tolerances 1e-3 … 1e-12 for the adaptive methods, 100 … 12,800
/// steps over the span for the fixed-step ones.
pub fn ladder(method: Method) -> Vec<Setting> {
    if method.is_adaptive() {
        (3..=12).map(|k| Setting::Tolerance(numeric::pow_int(10.0, -k))).collect()
    } else {
        (0..8).map(|k| Setting::Steps(100 << k)).collect()
    }
}

/// One measured run.
#[derive(Clone, Debug)]
pub struct Trial {
    pub method: Method,
    pub setting: Setting,
    /// The error against the reference, as the caller measures it; NaN when the run faulted.
    pub error: f64,
    /// Median wall time of the integration alone (no derivation or lowering), in seconds.
    pub seconds: f64,
    pub evaluations: usize,
    pub steps: usize,
    pub fault: Option<String>,
}

/// A method left out of a comparison, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Inapplicable {
    pub method: Method,
    pub reason: &'static str,
}

/// `base` with the method and the rung's tolerance or step set.
pub fn options_for(base: &Options, method: Method, setting: Setting, span: f64) -> Options {
    let mut o = base.clone();
    o.method = Some(method.name().to_string());
    match setting {
        Setting::Tolerance(t) => o.tolerance = Some(t),
        Setting::Steps(n) => o.step = Some(span / n as f64),
    }
    o
}

/// Runs `options` `repeats` times; the last outcome, and the median integration time.
pub fn timed(
    path: &str,
    source: &str,
    options: &Options,
    repeats: usize,
) -> Result<(Outcome, f64), Failure> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let outcome = simulate(path, source, options)?;
        times.push(outcome.wall_seconds);
        // A slow run is measured once: its timing noise is small against its length.
        let slow = outcome.wall_seconds > 1.0;
        last = Some(outcome);
        if slow {
            break;
        }
    }
    Ok((last.expect("at least one run"), median(&mut times)))
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Every method over its ladder; `error` measures a finished run against the caller's
/// reference.
pub fn work_precision(
    path: &str,
    source: &str,
    base: &Options,
    span: f64,
    methods: &[Method],
    repeats: usize,
    error: &mut dyn FnMut(&Outcome) -> f64,
) -> Result<Vec<Trial>, Failure> {
    let mut trials = Vec::new();
    for &method in methods {
        for setting in ladder(method) {
            let options = options_for(base, method, setting, span);
            let (outcome, seconds) = timed(path, source, &options, repeats)?;
            let fault = outcome.run.fault.as_ref().map(|f| outcome.describe_fault(f));
            let e = if fault.is_some() { f64::NAN } else { error(&outcome) };
            trials.push(Trial {
                method,
                setting,
                error: e,
                seconds,
                evaluations: outcome.run.evaluations,
                steps: outcome.run.steps,
                fault,
            });
        }
    }
    Ok(trials)
}

/// The largest difference of the final states (and of the final times, for runs that a stop
/// event ended) between a run and the reference.
pub fn final_state_error(reference: &Outcome, run: &Outcome) -> f64 {
    let state = reference
        .run
        .final_state
        .iter()
        .zip(&run.run.final_state)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    state.max((reference.run.final_time - run.run.final_time).abs())
}

/// The table of trials, one line each, then a line for each method left out.
pub fn table(trials: &[Trial], inapplicable: &[Inapplicable]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<9} {:>12} {:>11} {:>12} {:>10} {:>9}",
        "method", "setting", "error", "time", "rhs evals", "steps"
    );
    for t in trials {
        let error = if t.error.is_nan() { "fault".to_string() } else { format!("{:.2e}", t.error) };
        let _ = writeln!(
            s,
            "{:<9} {:>12} {:>11} {:>12} {:>10} {:>9}",
            t.method.name(),
            t.setting.label(),
            error,
            seconds(t.seconds),
            t.evaluations,
            t.steps
        );
    }
    for m in inapplicable {
        let _ = writeln!(s, "{:<9} not applicable: {}", m.method.name(), m.reason);
    }
    s
}

/// A duration with a unit that keeps three significant digits readable.
pub fn seconds(s: f64) -> String {
    if s < 1e-6 {
        format!("{:.1} ns", s * 1e9)
    } else if s < 1e-3 {
        format!("{:.2} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

/// The reference run of [`bench`]: DOP853 at this tolerance.
pub const REFERENCE_TOLERANCE: f64 = 1e-14;

/// What `lagrange bench FILE` measures.
pub struct Report {
    pub trials: Vec<Trial>,
    /// Methods that cannot run this scene, in the order of [`Method::NAMES`].
    pub inapplicable: Vec<Inapplicable>,
    /// max |reference − the same at 10× the tolerance|: how far the reference itself can be
    /// trusted.
    pub reference_check: f64,
    pub span: f64,
}

/// The speed–accuracy table of a scene: every method over its ladder against DOP853 at
/// [`REFERENCE_TOLERANCE`]. `base` carries the scene's options (`--until`, `--set`, stops).
pub fn bench(path: &str, source: &str, base: &Options, repeats: usize) -> Result<Report, Failure> {
    let reference_options = options_for(
        base,
        Method::Dop853,
        Setting::Tolerance(REFERENCE_TOLERANCE),
        base.until.unwrap_or(1.0),
    );
    let reference = simulate(path, source, &reference_options)?;
    if let Some(f) = &reference.run.fault {
        return Err((
            format!("error: the reference run failed\n{}", reference.describe_fault(f)),
            1,
        ));
    }
    let looser = options_for(
        base,
        Method::Dop853,
        Setting::Tolerance(10.0 * REFERENCE_TOLERANCE),
        base.until.unwrap_or(1.0),
    );
    let check = simulate(path, source, &looser)?;
    let reference_check = final_state_error(&reference, &check);
    // The fixed-step ladders divide the span the reference actually covered (a stop event
    // may end it before --until).
    let span = reference.run.final_time;
    // One constraint column per multiplier.
    let multipliers = !reference.constraint_columns.is_empty();
    let (methods, inapplicable): (Vec<Method>, Vec<Method>) = Method::NAMES
        .iter()
        .filter_map(|n| Method::from_name(n))
        .partition(|m| !multipliers || m.handles_multipliers());
    let inapplicable = inapplicable
        .into_iter()
        .map(|method| Inapplicable { method, reason: NO_MULTIPLIERS })
        .collect();
    let mut error = |o: &Outcome| final_state_error(&reference, o);
    let trials = work_precision(path, source, base, span, &methods, repeats, &mut error)?;
    Ok(Report { trials, inapplicable, reference_check, span })
}

/// The work–precision diagram: error against wall time, both logarithmic, one polyline per
/// method, hand-written SVG like [`crate::plot`]. The methods left out are named in grey under
/// the legend, each with its reason as a tooltip.
// Logarithmic axes of a picture: a last bit of a pixel's position shows nowhere.
#[allow(clippy::disallowed_methods)]
pub fn svg(title: &str, trials: &[Trial], inapplicable: &[Inapplicable]) -> String {
    const W: f64 = 720.0;
    const H: f64 = 480.0;
    const LEFT: f64 = 80.0;
    const RIGHT: f64 = 130.0;
    const TOP: f64 = 40.0;
    const BOTTOM: f64 = 50.0;
    const COLOURS: [&str; 6] = ["#1f5fa8", "#d1495b", "#2e933c", "#edae49", "#6a4c93", "#444"];
    let good: Vec<&Trial> =
        trials.iter().filter(|t| t.error > 0.0 && t.error.is_finite() && t.seconds > 0.0).collect();
    let decades = |f: &dyn Fn(&Trial) -> f64| -> (f64, f64) {
        let lo = good.iter().map(|t| f(t).log10()).fold(f64::INFINITY, f64::min);
        let hi = good.iter().map(|t| f(t).log10()).fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() {
            (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
        } else {
            (0.0, 1.0)
        }
    };
    let (x0, x1) = decades(&|t| t.seconds);
    let (y0, y1) = decades(&|t| t.error);
    let px = |s: f64| LEFT + (s.log10() - x0) / (x1 - x0) * (W - LEFT - RIGHT);
    let py = |e: f64| TOP + (y1 - e.log10()) / (y1 - y0) * (H - TOP - BOTTOM);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" font-size="14" text-anchor="middle">{}</text>"#,
        (W - RIGHT + LEFT) / 2.0,
        escape(title)
    );
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="#888"/>"##,
        W - LEFT - RIGHT,
        H - TOP - BOTTOM
    );
    for k in x0 as i32..=x1 as i32 {
        let x = px(10f64.powi(k));
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{}" stroke="#ddd"/><text x="{x:.1}" y="{}" text-anchor="middle">1e{k}</text>"##,
            H - BOTTOM,
            H - BOTTOM + 16.0
        );
    }
    for k in y0 as i32..=y1 as i32 {
        let y = py(10f64.powi(k));
        let _ = writeln!(
            s,
            r##"<line x1="{LEFT}" y1="{y:.1}" x2="{}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">1e{k}</text>"##,
            W - RIGHT,
            LEFT - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">wall time of the integration (s)</text>"#,
        (W - RIGHT + LEFT) / 2.0,
        H - 12.0
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18 {}) rotate(-90)" text-anchor="middle">error against the reference</text>"#,
        (H - BOTTOM + TOP) / 2.0
    );
    let mut methods: Vec<Method> = Vec::new();
    for t in trials {
        if !methods.contains(&t.method) {
            methods.push(t.method);
        }
    }
    for (k, m) in methods.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        // In ladder order, not sorted by time: a timing hiccup then shows as a kink rather
        // than reordering the rungs.
        let points: Vec<(f64, f64)> =
            good.iter().filter(|t| t.method == *m).map(|t| (px(t.seconds), py(t.error))).collect();
        let text: Vec<String> = points.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            s,
            r#"<polyline fill="none" stroke="{colour}" stroke-width="1.5" points="{}"/>"#,
            text.join(" ")
        );
        for (x, y) in &points {
            let _ = writeln!(s, r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="{colour}"/>"#);
        }
        let ly = TOP + 16.0 + 18.0 * k as f64;
        let lx = W - RIGHT + 12.0;
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="2"/><text x="{}" y="{}">{}</text>"#,
            lx + 20.0,
            lx + 26.0,
            ly + 4.0,
            m.name()
        );
    }
    if !inapplicable.is_empty() {
        let lx = W - RIGHT + 12.0;
        let top = TOP + 16.0 + 18.0 * methods.len() as f64 + 8.0;
        let _ =
            writeln!(s, r##"<text x="{lx}" y="{}" fill="#888">not applicable:</text>"##, top + 4.0);
        for (k, m) in inapplicable.iter().enumerate() {
            let _ = writeln!(
                s,
                r##"<text x="{}" y="{}" fill="#888">{}<title>{}</title></text>"##,
                lx + 26.0,
                top + 4.0 + 18.0 * (k + 1) as f64,
                m.method.name(),
                escape(m.reason)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladders_span_the_tolerances_and_steps() {
        assert_eq!(ladder(Method::Dop853).first(), Some(&Setting::Tolerance(1e-3)));
        assert_eq!(ladder(Method::Dop853).len(), 10);
        assert_eq!(ladder(Method::Gauss).last(), Some(&Setting::Steps(12_800)));
    }

    #[test]
    fn the_diagram_has_a_line_per_method_and_skips_faults() {
        let trial = |method, error, seconds| Trial {
            method,
            setting: Setting::Steps(100),
            error,
            seconds,
            evaluations: 1,
            steps: 1,
            fault: None,
        };
        let trials = [
            trial(Method::Rk4, 1e-3, 1e-3),
            trial(Method::Rk4, 1e-6, 1e-2),
            trial(Method::Gauss, f64::NAN, 1e-2),
            trial(Method::Gauss, 1e-8, 1e-1),
        ];
        let svg = svg("t", &trials, &[]);
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 3);
        assert!(svg.contains(">rk4<") && svg.contains(">gauss<"));
        assert!(!svg.contains("not applicable"));
    }

    #[test]
    fn methods_left_out_are_listed_in_the_table_and_the_legend() {
        let trials = [Trial {
            method: Method::Rk4,
            setting: Setting::Steps(100),
            error: 1e-3,
            seconds: 1e-3,
            evaluations: 400,
            steps: 100,
            fault: None,
        }];
        let out = [
            Inapplicable { method: Method::Midpoint, reason: NO_MULTIPLIERS },
            Inapplicable { method: Method::Gauss, reason: NO_MULTIPLIERS },
        ];
        let text = table(&trials, &out);
        assert!(text.contains("rk4"), "{text}");
        assert!(text.contains(&format!("midpoint  not applicable: {NO_MULTIPLIERS}")), "{text}");
        assert!(text.contains(&format!("gauss     not applicable: {NO_MULTIPLIERS}")), "{text}");
        let svg = svg("t", &trials, &out);
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert!(svg.contains(">not applicable:<"), "{svg}");
        assert!(svg.contains(">midpoint<title>") && svg.contains(">gauss<title>"), "{svg}");
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
