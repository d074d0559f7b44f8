//! The scene with a fit's values written in: each free parameter's value, and each free start
//! value, replaced in the text where the scene declares it (in the unit the scene wrote it
//! in), the rest of the file as it was, so that the fitted scene reads like the original.

use crate::{Fit, Kind};

/// The value of a declaration: where its text starts and ends (after `=`, before a `,`, a
/// comment or the line's end, outside brackets), or `None` when the name has no `=`.
fn value_extent(source: &str, after_name: usize) -> Option<(usize, usize)> {
    let rest = &source[after_name..];
    let gap = rest.len() - rest.trim_start_matches([' ', '\t']).len();
    let rest = &rest[gap..];
    let rest = rest.strip_prefix('=')?;
    let start = after_name + gap + 1;
    let mut depth = 0i32;
    let mut end = source.len();
    for (i, ch) in rest.char_indices() {
        match ch {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '\n' | '#' | ';' if depth <= 0 => {
                end = start + i;
                break;
            }
            _ => {}
        }
    }
    let text = &source[start..end];
    let lead = text.len() - text.trim_start().len();
    Some((start + lead, start + text.trim_end().len()))
}

/// `value` (in SI) as the text `written` writes its quantity: in the unit `written` ends in,
/// or a plain number.
fn in_unit_of(written: &str, value: f64) -> String {
    if let Ok((_, Some(unit))) = lang::parse_quantity(written) {
        if let Ok((_, scale)) = model::units::parse_unit(&unit) {
            let factor = numeric::to_f64(&scale.rational)
                * numeric::pow_int(std::f64::consts::PI, scale.pi_power);
            let unit_text = &written[unit.span.start..unit.span.end];
            return format!("{} {unit_text}", value / factor);
        }
    }
    format!("{value}")
}

/// The scene `source` with the fitted values of `fit` in place of the declared ones.
pub fn written(source: &str, fit: &Fit) -> Result<String, engine::Error> {
    let checks = model::Checks { units: false, inputs_in_constraints: true };
    let (model, _) = engine::resolve_checked(source, checks)?;
    // (start, end, text): replacements, applied from the end so that earlier offsets hold.
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    for (u, value) in fit.unknowns.iter().zip(&fit.estimates) {
        match u.kind {
            Kind::Parameter(slot) => {
                let param = &model.params[slot];
                match value_extent(source, param.span.end) {
                    Some((start, end)) => {
                        edits.push((start, end, in_unit_of(&source[start..end], *value)))
                    }
                    None => edits.push((param.span.end, param.span.end, format!(" = {value}"))),
                }
            }
            Kind::Start { coordinate, rate, .. } => {
                let coord = &model.coords[coordinate];
                let after = coord.span.end;
                let position = value_extent(source, after);
                if !rate {
                    match position {
                        Some((start, end)) => {
                            edits.push((start, end, in_unit_of(&source[start..end], *value)))
                        }
                        None => edits.push((after, after, format!(" = {value}"))),
                    }
                    continue;
                }
                // The rate is its own item of the line: `theta = 1, theta' = 0`.
                let line_end = source[after..].find('\n').map_or(source.len(), |i| after + i);
                let primed = format!("{}'", coord.name);
                let found = source[after..line_end].find(&primed).map(|i| after + i + primed.len());
                match found.and_then(|at| value_extent(source, at)) {
                    Some((start, end)) => {
                        edits.push((start, end, in_unit_of(&source[start..end], *value)))
                    }
                    None => {
                        let at = position.map_or(after, |(_, end)| end);
                        edits.push((at, at, format!(", {primed} = {value}")));
                    }
                }
            }
        }
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = source.to_string();
    for (start, end, text) in edits {
        out.replace_range(start..end, &text);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_ends_at_its_comma_outside_brackets() {
        let s = "param a = f(1, 2) kg, b = 3\n";
        let (start, end) = value_extent(s, 7).unwrap();
        assert_eq!(&s[start..end], "f(1, 2) kg");
    }

    #[test]
    fn a_value_keeps_its_unit() {
        assert_eq!(in_unit_of("100 cm", 1.5), "150 cm");
        assert_eq!(in_unit_of("1/2", 0.25), "0.25");
    }
}
