//! Every figure `lagrange` draws, as SVG written by hand: the recorded quantities of a run
//! against time ([`time_series`]), the eigenvalues of a sweep against its parameter
//! ([`sweep`]) and the work–precision diagram of a benchmark ([`work_precision`]), and a fit's data, fitted motion and residuals ([`fit()`]). They share
//! this module's page, panel, axis, number labels and escaping. Deterministic text, no fonts
//! or libraries needed. The one exception is an ensemble's picture ([`mod@ensemble`]), a heat
//! map with a colour bar, a line or a histogram as SVG or PNG, which plotters draws.

pub mod ensemble;
mod fit;
mod series;
mod sweep;
mod work_precision;

use std::fmt::Write;

pub use self::fit::{fit, Measured};
pub use self::series::time_series;
pub use self::sweep::sweep;
pub use self::work_precision::work_precision;

/// An SVG page of the given size, white, with its title centred on `(x, y)`; the caller adds
/// the panels and closes it.
fn page(width: f64, height: f64, title: &str, (x, y): (f64, f64)) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{x}" y="{y}" font-size="14" text-anchor="middle">{}</text>"#,
        escape(title)
    );
    s
}

/// A linear map from values to pixels: `from.0` goes to `to.0` and `from.1` to `to.1` (a
/// vertical axis maps its low value to the bottom, the larger pixel).
#[derive(Clone, Copy)]
struct Axis {
    from: (f64, f64),
    to: (f64, f64),
}

impl Axis {
    fn at(self, v: f64) -> f64 {
        let Axis { from: (v0, v1), to: (p0, p1) } = self;
        p0 + (v - v0) / (v1 - v0) * (p1 - p0)
    }
}

/// The outline of a panel.
fn outline(s: &mut String, (left, top): (f64, f64), width: f64, height: f64) {
    let _ = writeln!(
        s,
        r##"<rect x="{left}" y="{top}" width="{width}" height="{height}" fill="none" stroke="#888"/>"##
    );
}

/// A figure of panels stacked one above the other (a run's quantities, a sweep's parts of
/// λ): its width, its margins left and right, and the gap above each panel.
const WIDTH: f64 = 720.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 20.0;
const GAP: f64 = 40.0;

/// The page of a stacked figure of `panels` panels of height `panel`.
fn stacked_page(title: &str, panels: usize, panel: f64) -> String {
    let height = GAP + panels as f64 * (panel + GAP) + 10.0;
    page(WIDTH, height, title, (WIDTH / 2.0, 20.0))
}

/// The horizontal axis of a stacked figure, from `range` across every panel.
fn across(range: (f64, f64)) -> Axis {
    Axis { from: range, to: (LEFT, WIDTH - RIGHT) }
}

/// Where a panel sits in a figure of panels stacked one above the other.
struct Frame {
    top: f64,
    panel: f64,
    width: f64,
    left: f64,
    right: f64,
}

impl Frame {
    /// Panel `k`, counted from the top, of a stacked figure of panels of height `panel`.
    fn stacked(k: usize, panel: f64) -> Frame {
        Frame { top: GAP + k as f64 * (panel + GAP), panel, width: WIDTH, left: LEFT, right: RIGHT }
    }

    /// The vertical axis from `range` up the panel.
    fn y(&self, range: (f64, f64)) -> Axis {
        Axis { from: range, to: (self.top + self.panel, self.top) }
    }

    /// The panel's box, its name above it, its value range at the left edge and the ends of
    /// its horizontal axis below it.
    fn draw(&self, s: &mut String, name: &str, (v0, v1): (f64, f64), (x0, x1): (&str, &str)) {
        let Frame { top, panel, width, left, right } = *self;
        outline(s, (left, top), width - left - right, panel);
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
}

/// The smallest and largest finite value, widened when they (nearly) coincide so that a
/// constant still has a panel to sit in.
fn range(v: &[f64]) -> (f64, f64) {
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

/// A number at an axis: four decimals, or three significant digits in scientific notation
/// when it is very small or large.
fn label(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// Text as it may stand in SVG (and HTML) content.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}
