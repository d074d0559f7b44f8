//! The work–precision diagram of `lagrange bench`: error against wall time, both
//! logarithmic, one line per method, and the methods that cannot run the scene named apart.

use std::fmt::Write;

use sim::Method;
use simulation::bench::{Inapplicable, Trial};

use super::{escape, outline, page, Axis};

/// The work–precision diagram: error against wall time, both logarithmic, one polyline per
/// method, drawn as the other figures are. The methods left out are named in grey under
/// the legend, each with its reason as a tooltip.
// Logarithmic axes of a picture: a last bit of a pixel's position shows nowhere.
#[allow(clippy::disallowed_methods)]
pub fn work_precision(title: &str, trials: &[Trial], inapplicable: &[Inapplicable]) -> String {
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
    let x = Axis { from: (x0, x1), to: (LEFT, W - RIGHT) };
    let y = Axis { from: (y1, y0), to: (TOP, H - BOTTOM) };
    let px = |s: f64| x.at(s.log10());
    let py = |e: f64| y.at(e.log10());
    let mut s = page(W, H, title, ((W - RIGHT + LEFT) / 2.0, 22.0));
    outline(&mut s, (LEFT, TOP), W - LEFT - RIGHT, H - TOP - BOTTOM);
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

#[cfg(test)]
mod tests {
    use super::*;
    use simulation::bench::Setting;
    use simulation::NO_MULTIPLIERS;

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
        let svg = work_precision("t", &trials, &[]);
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
        let text = simulation::bench::table(&trials, &out);
        assert!(text.contains("rk4"), "{text}");
        assert!(text.contains(&format!("midpoint  not applicable: {NO_MULTIPLIERS}")), "{text}");
        assert!(text.contains(&format!("gauss     not applicable: {NO_MULTIPLIERS}")), "{text}");
        let svg = work_precision("t", &trials, &out);
        assert_eq!(svg.matches("<polyline").count(), 1);
        assert!(svg.contains(">not applicable:<"), "{svg}");
        assert!(svg.contains(">midpoint<title>") && svg.contains(">gauss<title>"), "{svg}");
    }
}
