//! The recorded quantities of a run against time: one panel each, the energy error among
//! them when the front end adds it.

use std::fmt::Write;

use super::{across, label, range, stacked_page, Frame};

const PANEL: f64 = 150.0;
/// Past this many points a series is thinned: the picture does not change, the file shrinks.
const MAX_POINTS: usize = 2000;

/// `series`: (title, values at `times`).
pub fn time_series(title: &str, times: &[f64], series: &[(String, Vec<f64>)]) -> String {
    let mut s = stacked_page(title, series.len(), PANEL);
    let (t0, t1) = range(times);
    let stride = times.len().div_ceil(MAX_POINTS).max(1);
    let x = across((t0, t1));
    for (k, (name, values)) in series.iter().enumerate() {
        let at = Frame::stacked(k, PANEL);
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
