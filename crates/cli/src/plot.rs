//! A small SVG plot written by hand: one panel per recorded quantity, and one for the energy
//! error, all against time. Deterministic text, no fonts or libraries needed.

use std::fmt::Write;

const WIDTH: f64 = 720.0;
const PANEL: f64 = 150.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 20.0;
const GAP: f64 = 40.0;
/// Past this many points a series is thinned: the picture does not change, the file shrinks.
const MAX_POINTS: usize = 2000;

/// An SVG page of the given size, white, with its title centred at the top; the caller adds
/// the panels and closes it.
pub(crate) fn page(width: f64, height: f64, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="20" font-size="14" text-anchor="middle">{}</text>"#,
        width / 2.0,
        escape(title)
    );
    s
}

/// Where a panel sits in a figure.
pub(crate) struct Frame {
    pub top: f64,
    pub panel: f64,
    pub width: f64,
    pub left: f64,
    pub right: f64,
}

/// A panel's box, its name above it, its value range at the left edge and the ends of its
/// horizontal axis below it.
pub(crate) fn frame(
    s: &mut String,
    f: Frame,
    name: &str,
    (v0, v1): (f64, f64),
    (x0, x1): (&str, &str),
) {
    let Frame { top, panel, width, left, right } = f;
    let _ = writeln!(
        s,
        r##"<rect x="{left}" y="{top}" width="{}" height="{panel}" fill="none" stroke="#888"/>"##,
        width - left - right
    );
    let _ = writeln!(s, r#"<text x="{left}" y="{}">{}</text>"#, top - 6.0, escape(name));
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
        left - 6.0,
        top + 10.0,
        label(v1)
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
        left - 6.0,
        top + panel,
        label(v0)
    );
    let _ = writeln!(
        s,
        r#"<text x="{left}" y="{}" text-anchor="middle">{}</text>"#,
        top + panel + 14.0,
        escape(x0)
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
        width - right,
        top + panel + 14.0,
        escape(x1)
    );
}

/// `series`: (title, values at `times`).
pub fn svg(title: &str, times: &[f64], series: &[(String, Vec<f64>)]) -> String {
    let height = GAP + series.len() as f64 * (PANEL + GAP) + 10.0;
    let mut s = page(WIDTH, height, title);
    let (t0, t1) = range(times);
    let stride = times.len().div_ceil(MAX_POINTS).max(1);
    for (k, (name, values)) in series.iter().enumerate() {
        let top = GAP + k as f64 * (PANEL + GAP);
        let (v0, v1) = range(values);
        let x = |t: f64| LEFT + (t - t0) / (t1 - t0) * (WIDTH - LEFT - RIGHT);
        let y = |v: f64| top + PANEL - (v - v0) / (v1 - v0) * PANEL;
        let axis_end = format!("t = {}", label(t1));
        frame(
            &mut s,
            Frame { top, panel: PANEL, width: WIDTH, left: LEFT, right: RIGHT },
            name,
            (v0, v1),
            (&label(t0), &axis_end),
        );
        let mut points = String::new();
        let indices = (0..times.len()).step_by(stride).chain(times.len().checked_sub(1));
        let mut last = usize::MAX;
        for i in indices {
            if i == last || !values[i].is_finite() {
                continue;
            }
            last = i;
            let _ = write!(points, "{:.2},{:.2} ", x(times[i]), y(values[i]));
        }
        let _ = writeln!(
            s,
            r##"<polyline fill="none" stroke="#1f5fa8" stroke-width="1.5" points="{}"/>"##,
            points.trim_end()
        );
    }
    s.push_str("</svg>\n");
    s
}

pub(crate) fn range(v: &[f64]) -> (f64, f64) {
    let (lo, hi) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-300 + 1e-15 * lo.abs() {
        let pad = if lo == 0.0 { 1.0 } else { lo.abs() * 1e-3 };
        return (lo - pad, hi + pad);
    }
    (lo, hi)
}

pub(crate) fn label(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}
