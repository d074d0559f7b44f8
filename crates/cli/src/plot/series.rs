//! The recorded quantities of a run against time: one panel each, the energy error among
//! them when the front end adds it.

use std::fmt::Write;

use super::{label, page, range, Axis, Frame};

const WIDTH: f64 = 720.0;
const PANEL: f64 = 150.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 20.0;
const GAP: f64 = 40.0;
/// Past this many points a series is thinned: the picture does not change, the file shrinks.
const MAX_POINTS: usize = 2000;

/// `series`: (title, values at `times`).
pub fn time_series(title: &str, times: &[f64], series: &[(String, Vec<f64>)]) -> String {
    let height = GAP + series.len() as f64 * (PANEL + GAP) + 10.0;
    let mut s = page(WIDTH, height, title, (WIDTH / 2.0, 20.0));
    let (t0, t1) = range(times);
    let stride = times.len().div_ceil(MAX_POINTS).max(1);
    let x = Axis { from: (t0, t1), to: (LEFT, WIDTH - RIGHT) };
    for (k, (name, values)) in series.iter().enumerate() {
        let at = Frame {
            top: GAP + k as f64 * (PANEL + GAP),
            panel: PANEL,
            width: WIDTH,
            left: LEFT,
            right: RIGHT,
        };
        let (v0, v1) = range(values);
        let y = at.y((v0, v1));
        let axis_end = format!("t = {}", label(t1));
        at.draw(&mut s, name, (v0, v1), (&label(t0), &axis_end));
        let mut points = String::new();
        let indices = (0..times.len()).step_by(stride).chain(times.len().checked_sub(1));
        let mut last = usize::MAX;
        for i in indices {
            if i == last || !values[i].is_finite() {
                continue;
            }
            last = i;
            let _ = write!(points, "{:.2},{:.2} ", x.at(times[i]), y.at(values[i]));
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
