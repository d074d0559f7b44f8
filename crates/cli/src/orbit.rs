//! `orbit`'s report: the fixed point, the period, the Floquet multipliers and the verdict, as
//! text for people or JSON for programs.

use std::fmt::Write;

use orbit::sweep::Sweep;
use orbit::Orbit;
use serde_json::{json, Value};

/// The report as text.
pub fn text(path: &str, orbit: &Orbit, section: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "periodic orbit of {path} ({section})");
    let width = orbit.state_names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    let _ = writeln!(out, "fixed point:");
    for (name, value) in orbit.state_names.iter().zip(&orbit.fixed_point) {
        let pad = width - name.chars().count();
        let _ = writeln!(out, "  {name}{} = {}", " ".repeat(pad), number(*value));
    }
    let _ = writeln!(out, "period: {} s", number(orbit.period));
    if orbit.jumps > 0 {
        let _ = writeln!(out, "jumps on the way: {}", orbit.jumps);
    }
    let _ = writeln!(
        out,
        "Floquet multipliers ({} on the section, {} trivial left out):",
        orbit.multipliers.len(),
        orbit.trivial
    );
    for m in &orbit.multipliers {
        let _ = writeln!(out, "  {:<40} |μ| = {}", complex(m.re, m.im), number(m.norm()));
    }
    let why = match orbit.verdict {
        orbit::Verdict::Neutral => {
            ": a multiplier on the unit circle, a family of orbits or the edge of stability"
        }
        _ => "",
    };
    let _ = writeln!(
        out,
        "verdict: {} (largest |μ| = {}){why}",
        orbit.verdict.word(),
        number(orbit.spectral_radius())
    );
    let residuals: Vec<String> =
        orbit.iterations.iter().map(|i| format!("{:.1e}", i.residual)).collect();
    let tolerances: Vec<String> =
        orbit.iterations.iter().map(|i| format!("{:.0e}", i.tolerance)).collect();
    let last = orbit
        .last_step
        .map(|e| format!(", then a step expected to leave {e:.0e}"))
        .unwrap_or_default();
    let _ = writeln!(
        out,
        "Newton: {} runs at tolerances {}, residuals on the section {}{last}",
        orbit.iterations.len(),
        tolerances.join(", "),
        residuals.join(", ")
    );
    out
}

/// The report as JSON.
pub fn json(path: &str, orbit: &Orbit, section: &str) -> String {
    let size = orbit.fixed_point.len();
    let fixed: serde_json::Map<String, Value> = orbit
        .state_names
        .iter()
        .zip(&orbit.fixed_point)
        .map(|(n, v)| (n.clone(), json!(v)))
        .collect();
    let monodromy: Vec<Vec<f64>> =
        (0..size).map(|i| orbit.monodromy[i * size..(i + 1) * size].to_vec()).collect();
    let value = json!({
        "scene": path,
        "section": section,
        "fixed_point": fixed,
        "period": orbit.period,
        "jumps": orbit.jumps,
        "multipliers": orbit.multipliers.iter().map(|m| json!({
            "re": m.re, "im": m.im, "abs": m.norm()
        })).collect::<Vec<_>>(),
        "trivial": orbit.trivial,
        "stable": orbit.stable,
        "verdict": orbit.verdict.word(),
        "spectral_radius": orbit.spectral_radius(),
        "monodromy": monodromy,
        "newton": orbit.iterations.iter().map(|i| json!({
            "residual": i.residual, "steps": i.steps, "tolerance": i.tolerance
        })).collect::<Vec<_>>(),
        "last_step": orbit.last_step,
    });
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    text
}

/// Twelve decimals, the trailing zeros dropped.
fn number(v: f64) -> String {
    let text = format!("{v:.12}").trim_end_matches('0').trim_end_matches('.').to_string();
    // A value that rounds to zero from below prints as zero, not "-0".
    if text == "-0" {
        "0".into()
    } else {
        text
    }
}

fn complex(re: f64, im: f64) -> String {
    if im == 0.0 {
        return number(re);
    }
    let sign = if im < 0.0 { "-" } else { "+" };
    format!("{} {sign} {}i", number(re), number(im.abs()))
}

/// A sweep's report as text: a row per value, then the crossings located.
pub fn sweep_text(path: &str, sweep: &Sweep, section: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "orbit of {path} ({section}) swept in {}", sweep.parameter);
    let p = &sweep.parameter;
    let _ = writeln!(out, "  {p:>16}  {:>16}  {:>16}  verdict", "period", "largest |μ|");
    let natural = sweep.points.len() - sweep.around;
    for (k, (value, orbit)) in sweep.points.iter().enumerate() {
        if k == natural {
            let _ = writeln!(out, "  then along the branch by pseudo-arclength, past its fold:");
        }
        let _ = writeln!(
            out,
            "  {:>16}  {:>16}  {:>16}  {}",
            number(*value),
            number(orbit.period),
            number(orbit.spectral_radius()),
            orbit.verdict.word()
        );
    }
    for located in &sweep.crossings {
        let multipliers: Vec<String> =
            located.orbit.multipliers.iter().map(|m| complex(m.re, m.im)).collect();
        let _ = writeln!(
            out,
            "{} at {p} = {} (multipliers {})",
            located.kind.words(),
            number(located.at),
            multipliers.join(", ")
        );
    }
    if sweep.crossings.is_empty() {
        let _ = writeln!(out, "no multiplier crosses the unit circle between the values");
    }
    if let Some((value, why)) = &sweep.lost {
        let _ = writeln!(
            out,
            "lost the orbit at {p} = {}: no orbit near the last one (past a fold the branch \
             turns back, which this sweep does not follow; or the step is too long: more \
             values): {why}",
            number(*value)
        );
    }
    out
}

/// A sweep's report as JSON.
pub fn sweep_json(path: &str, sweep: &Sweep, section: &str) -> String {
    let multipliers = |orbit: &Orbit| -> Vec<Value> {
        orbit.multipliers.iter().map(|m| json!({"re": m.re, "im": m.im})).collect()
    };
    let value = json!({
        "scene": path,
        "section": section,
        "parameter": sweep.parameter,
        "around_the_fold": sweep.around,
        "points": sweep.points.iter().map(|(p, orbit)| json!({
            "value": p,
            "fixed_point": orbit.fixed_point,
            "period": orbit.period,
            "multipliers": multipliers(orbit),
            "verdict": orbit.verdict.word(),
        })).collect::<Vec<_>>(),
        "crossings": sweep.crossings.iter().map(|c| json!({
            "kind": c.kind.words(),
            "at": c.at,
            "multipliers": multipliers(&c.orbit),
        })).collect::<Vec<_>>(),
        "lost": sweep.lost.as_ref().map(|(p, why)| json!({"at": p, "why": why})),
    });
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    text
}
