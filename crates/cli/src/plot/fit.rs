//! A fit's picture: for each measured column, the data as dots and the fitted motion as a
//! line, and below it the residuals (model − data) about a zero line.

use std::fmt::Write;

use super::{across, label, range, stacked_page, Frame};

const PANEL: f64 = 140.0;

/// A measured column as the picture takes it: its name, the model's values at the times, and
/// the data there where measured.
pub struct Measured {
    pub name: String,
    pub model: Vec<f64>,
    pub data: Vec<Option<f64>>,
}

pub fn fit(title: &str, times: &[f64], columns: &[Measured]) -> String {
    let mut s = stacked_page(title, 2 * columns.len(), PANEL);
    let (t0, t1) = range(times);
    let x = across((t0, t1));
    let axis_end = format!("t = {}", label(t1));
    for (k, Measured { name, model, data }) in columns.iter().enumerate() {
        let at = Frame::stacked(2 * k, PANEL);
        let measured: Vec<f64> =
            data.iter().flatten().copied().chain(model.iter().copied()).collect();
        let (v0, v1) = range(&measured);
        let y = at.y((v0, v1));
        at.draw(
            &mut s,
            &format!("{name}: data (dots), fit (line)"),
            (v0, v1),
            (&label(t0), &axis_end),
        );
        for (t, d) in times.iter().zip(data) {
            if let Some(d) = d {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{:.2}" cy="{:.2}" r="1.8" fill="#888"/>"##,
                    x.at(*t),
                    y.at(*d)
                );
            }
        }
        let points: Vec<String> = times
            .iter()
            .zip(model)
            .map(|(t, v)| format!("{:.2},{:.2}", x.at(*t), y.at(*v)))
            .collect();
        let _ = writeln!(
            s,
            r##"<polyline fill="none" stroke="#1f5fa8" stroke-width="1.5" points="{}"/>"##,
            points.join(" ")
        );
        let below = Frame::stacked(2 * k + 1, PANEL);
        let residuals: Vec<(f64, f64)> = times
            .iter()
            .zip(model.iter().zip(data))
            .filter_map(|(t, (m, d))| d.map(|d| (*t, m - d)))
            .collect();
        let values: Vec<f64> = residuals.iter().map(|r| r.1).chain([0.0]).collect();
        let (r0, r1) = range(&values);
        let y = below.y((r0, r1));
        below.draw(
            &mut s,
            &format!("{name}: residual, model − data"),
            (r0, r1),
            (&label(t0), &axis_end),
        );
        let _ = writeln!(
            s,
            r##"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#aaa"/>"##,
            x.at(t0),
            y.at(0.0),
            x.at(t1),
            y.at(0.0)
        );
        for (t, r) in residuals {
            let _ = writeln!(
                s,
                r##"<circle cx="{:.2}" cy="{:.2}" r="1.8" fill="#c0392b"/>"##,
                x.at(t),
                y.at(r)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
