//! `simulate --animate`'s page: one self-contained HTML file that plays the motion. The
//! figures' numbers come from `simulation::animate`; here they are written into the page's template
//! (`animate.html`: a canvas, a little JavaScript, no network) as JSON.
//!
//! The same run gives the same bytes: numbers are rounded to a fixed number of significant
//! digits and printed by Rust's shortest round-trip formatting, and nothing of the machine or
//! the clock is written.

use serde_json::{json, Value};
use simulation::animate::{Animation, FigureKind};

/// The page, with its `{{TITLE}}` and `{{DATA}}` places.
const TEMPLATE: &str = include_str!("animate.html");

/// Significant digits kept: far below a pixel at any zoom, and the file stays small.
const DIGITS: usize = 6;

/// The page for `animation`; `fallback_title` names it when the scene has no title.
pub fn page(animation: &Animation, fallback_title: &str) -> String {
    let title = animation.title.as_deref().unwrap_or(fallback_title);
    let data = data(animation).to_string();
    // Inside <script>, `</script>` or `<!--` in a string would end or change the element;
    // JSON may spell every `<` as \u003c instead.
    let data = data.replace('<', "\\u003c");
    let title = crate::plot::escape(title).replace('"', "&quot;");
    let mut page = String::with_capacity(TEMPLATE.len() + data.len());
    // The template is split at its places rather than searched and replaced, so that text
    // inserted for one place is never taken for another.
    let mut rest = TEMPLATE;
    while let Some(at) = rest.find("{{") {
        page.push_str(&rest[..at]);
        let after = &rest[at..];
        if let Some(tail) = after.strip_prefix("{{TITLE}}") {
            page.push_str(&title);
            rest = tail;
        } else if let Some(tail) = after.strip_prefix("{{DATA}}") {
            page.push_str(&data);
            rest = tail;
        } else {
            page.push_str("{{");
            rest = &after[2..];
        }
    }
    page.push_str(rest);
    page
}

/// The trajectory as the page's script reads it.
fn data(animation: &Animation) -> Value {
    let figures: Vec<Value> = animation
        .figures
        .iter()
        .map(|figure| {
            let frames: Vec<Value> =
                figure.frames.iter().map(|row| Value::Array(numbers(row))).collect();
            let mut value = match &figure.kind {
                FigureKind::Particle { mass } => json!({"kind": "particle", "mass": number(*mass)}),
                FigureKind::Body { axis_length } => {
                    json!({"kind": "body", "axis_length": number(*axis_length)})
                }
                FigureKind::Link { damper, fixed } => {
                    json!({"kind": "link", "damper": damper, "fixed": fixed})
                }
                FigureKind::Line => json!({"kind": "line"}),
                FigureKind::Circle => json!({"kind": "circle"}),
                FigureKind::Polyline => json!({"kind": "polyline"}),
            };
            value["label"] = json!(figure.label);
            value["frames"] = Value::Array(frames);
            value
        })
        .collect();
    // Each contact's mode at each frame, 1 closed and 0 open; its events with their times.
    let contacts: Vec<Value> = animation
        .contacts
        .iter()
        .map(|c| {
            let closed: Vec<u8> = c.closed.iter().map(|&c| u8::from(c)).collect();
            json!({"name": c.name, "closed": closed})
        })
        .collect();
    let events: Vec<Value> = animation
        .contact_events
        .iter()
        .map(|m| {
            json!({
                "t": number(m.time),
                "contact": m.contact,
                "kind": simulation::mode_word(m.kind),
                "closed": m.closed,
            })
        })
        .collect();
    json!({
        "dimension": animation.dimension,
        "times": numbers(&animation.times),
        "energy_error": numbers(&animation.energy_error),
        "conservative": animation.conservative,
        "figures": figures,
        "contacts": contacts,
        "contact_events": events,
    })
}

fn numbers(values: &[f64]) -> Vec<Value> {
    values.iter().map(|v| number(*v)).collect()
}

/// `v` to [`DIGITS`] significant digits; null where it is not finite (the page skips it).
fn number(v: f64) -> Value {
    let rounded: f64 = format!("{v:.*e}", DIGITS - 1).parse().unwrap_or(f64::NAN);
    serde_json::Number::from_f64(rounded).map(Value::Number).unwrap_or(Value::Null)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_six_significant_digits() {
        assert_eq!(number(2.0 / 3.0), json!(0.666667));
        assert_eq!(number(-1.234567e-8), json!(-1.23457e-8));
        assert_eq!(number(0.0), json!(0.0));
        assert_eq!(number(f64::NAN), Value::Null);
    }

    #[test]
    fn places_are_filled_once_and_text_cannot_open_a_tag() {
        let animation = Animation {
            title: Some("a <b> {{DATA}} \"c\"".into()),
            dimension: 2,
            times: vec![0.0, 1.0],
            energy_error: vec![0.0, 1e-12],
            conservative: true,
            figures: vec![simulation::animate::Figure {
                kind: FigureKind::Line,
                label: "draw line from (0, 0) to </script>".into(),
                frames: vec![vec![0.0, 0.0, 1.0, 1.0], vec![0.0, 0.0, 1.0, 2.0]],
            }],
            contacts: Vec::new(),
            contact_events: Vec::new(),
        };
        let page = page(&animation, "unused");
        assert!(page.contains("<title>a &lt;b&gt; {{DATA}} &quot;c&quot;</title>"));
        assert_eq!(page.matches("</script>").count(), 2, "only the two script elements close");
        assert!(page.contains(r#""times":[0.0,1.0]"#));
    }
}
