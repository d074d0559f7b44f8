//! A sweep of `linearize`: the real and imaginary parts of the eigenvalues against the swept
//! parameter, with the changes of stability marked.

use std::fmt::Write;

use engine::linearize::Sweep;

use super::{across, escape, label, range, stacked_page, Frame, GAP, LEFT, RIGHT, WIDTH};

/// One part of an eigenvalue (re, im).
type Part = fn(&(f64, f64)) -> f64;

const PANEL: f64 = 200.0;

/// The real and imaginary parts of the eigenvalues against the swept parameter, one panel
/// each, with the changes of stability marked. A dot per eigenvalue and value: which
/// eigenvalue continues which is not known, so no lines join them.
pub fn sweep(title: &str, sweep: &Sweep) -> String {
    let mut s = stacked_page(title, 2, PANEL);
    let values: Vec<f64> = sweep.rows.iter().map(|r| r.value).collect();
    let (p0, p1) = range(&values);
    let panels: [(&str, Part); 2] = [("real part of λ", |z| z.0), ("imaginary part of λ", |z| z.1)];
    let x = across((p0, p1));
    for (k, (name, part)) in panels.iter().enumerate() {
        let at = Frame::stacked(k, PANEL);
        let top = at.top;
        let all: Vec<f64> =
            sweep.rows.iter().flat_map(|r| r.eigenvalues.iter().map(part)).collect();
        let (v0, v1) = range(&all);
        let y = at.y((v0, v1));
        let axis_end = format!("{} = {}", sweep.parameter, label(p1));
        at.draw(&mut s, name, (v0, v1), (&label(p0), &axis_end));
        if v0 < 0.0 && v1 > 0.0 {
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y0:.2}" x2="{}" y2="{y0:.2}" stroke="#bbb"/>"##,
                WIDTH - RIGHT,
                y0 = y.at(0.0)
            );
        }
        for c in &sweep.changes {
            let _ = writeln!(
                s,
                r##"<line x1="{cx:.2}" y1="{top}" x2="{cx:.2}" y2="{}" stroke="#c0392b" stroke-dasharray="4 3"/>"##,
                top + PANEL,
                cx = x.at(c.value)
            );
        }
        for r in &sweep.rows {
            for z in &r.eigenvalues {
                let v = part(z);
                if v.is_finite() {
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{:.2}" cy="{:.2}" r="1.8" fill="#1f5fa8"/>"##,
                        x.at(r.value),
                        y.at(v)
                    );
                }
            }
        }
    }
    for (k, c) in sweep.changes.iter().enumerate() {
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{}" fill="#c0392b">{} = {} ({} → {})</text>"##,
            x.at(c.value) + 4.0,
            GAP + 14.0 * (k as f64 + 1.0),
            escape(&sweep.parameter),
            label(c.value),
            c.from.name(),
            c.to.name()
        );
    }
    s.push_str("</svg>\n");
    s
}
