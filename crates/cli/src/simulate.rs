//! `lagrange simulate`'s outputs: the recorded quantities as CSV or JSON, and the summary of
//! a run. The run itself is `engine::simulate`'s; the progress bar is drawn while it runs.

use engine::simulate::{Options, Outcome};
use engine::Error;

/// Runs the scene with a progress bar on a terminal.
pub fn simulate(source: &str, options: &Options) -> Result<Outcome, Error> {
    engine::simulate::simulate_with(source, options, &mut crate::progress::Bar::new())
}

/// The recorded outputs as CSV: a header, then a row per recorded time. Numbers are written as
/// Rust's shortest round-trip decimals (`{}`), which never need quoting.
pub fn csv(outcome: &Outcome) -> String {
    let mut out = csv::Writer::from_writer(Vec::new());
    let header =
        std::iter::once("t").chain(outcome.columns[..outcome.shown].iter().map(String::as_str));
    out.write_record(header).expect("writing to memory");
    for (t, row) in outcome.run.trajectory.times.iter().zip(&outcome.run.trajectory.rows) {
        let numbers = std::iter::once(t).chain(&row[..outcome.shown]);
        out.write_record(numbers.copied().map(number)).expect("writing to memory");
    }
    let bytes = out.into_inner().expect("writing to memory");
    String::from_utf8(bytes).expect("UTF-8 in, UTF-8 out")
}

/// The longest a number is written in full; past it, in exponent form.
const PLAIN_UP_TO: usize = 24;

/// A number as a table or summary writes it: the shortest digits that read back to the same
/// bits, in full (`0.25`, `6.283185307179586`) unless that takes more than [`PLAIN_UP_TO`]
/// characters, as 1e-300 or 1e300 would (hundreds of zeros), then in exponent form (`1e-300`).
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() <= PLAIN_UP_TO {
        plain
    } else {
        format!("{x:e}")
    }
}

/// The recorded outputs, the events and the summary as JSON.
pub fn json(outcome: &Outcome) -> String {
    let rows: Vec<serde_json::Value> = outcome
        .run
        .trajectory
        .times
        .iter()
        .zip(&outcome.run.trajectory.rows)
        .map(|(t, r)| {
            let mut v = vec![json_number(*t)];
            v.extend(r[..outcome.shown].iter().map(|x| json_number(*x)));
            serde_json::Value::Array(v)
        })
        .collect();
    let mut columns = vec!["t".to_string()];
    columns.extend(outcome.columns[..outcome.shown].iter().cloned());
    let events: Vec<serde_json::Value> = outcome
        .run
        .events
        .iter()
        .map(|e| serde_json::json!({"event": outcome.event_names[e.event], "t": e.time}))
        .collect();
    let value = serde_json::json!({
        "columns": columns,
        "rows": rows,
        "events": events,
        "summary": summary_json(outcome),
    });
    let mut s = serde_json::to_string_pretty(&value).expect("json");
    s.push('\n');
    s
}

fn summary_json(outcome: &Outcome) -> serde_json::Value {
    let (drift, relative) = outcome.energy_drift();
    serde_json::json!({
        "method": outcome.method.name(),
        "segments": outcome.run.segments.iter().map(|s| serde_json::json!({
            "method": s.method.name(),
            "start": json_number(s.start),
            "end": json_number(s.end),
        })).collect::<Vec<_>>(),
        "steps": outcome.run.steps,
        "rejected_steps": outcome.run.rejected,
        "rhs_evaluations": outcome.run.evaluations,
        "stiff_steps": outcome.run.stiff_steps,
        "jacobians": outcome.run.jacobians,
        "factorizations": outcome.run.factorizations,
        "final_time": outcome.run.final_time,
        "energy_drift": json_number(drift),
        "energy_drift_relative": json_number(relative),
        "constraint_drift": outcome.constraint_drift().map(json_number),
        "constraint_drift_at_steps": outcome.constraint_drift_at_steps().map(json_number),
        "fault": outcome.run.fault.as_ref().map(|f| outcome.describe_fault(f)),
    })
}

/// The summary printed on stderr after a run.
pub fn summary(outcome: &Outcome) -> String {
    let r = &outcome.run;
    // The implicit adaptive method's linear algebra, where its cost lies besides F.
    let algebra = if r.jacobians > 0 {
        format!(", {} Jacobians, {} LU factorizations", r.jacobians, r.factorizations)
    } else {
        String::new()
    };
    let mut s = format!(
        "{}: {} steps ({} rejected), {} right-hand-side evaluations{algebra}, {:.3} s wall time\n",
        outcome.method.name(),
        r.steps,
        r.rejected,
        r.evaluations,
        outcome.wall_seconds
    );
    if !outcome.method.sides().is_empty() {
        s.push_str(&format!("{}\n", segments(&r.segments)));
    }
    let (drift, relative) = outcome.energy_drift();
    let note = if outcome.conservative {
        ""
    } else {
        " (not conserved: forces, time or a moving constraint act)"
    };
    s.push_str(&format!(
        "energy drift: max |E − E(0)| = {drift:.3e} ({relative:.3e} relative){note}\n"
    ));
    // Hairer's stiffness test flagged a good part of the steps: their size was set by the
    // stability of the explicit method, not by the tolerance.
    if r.stiff_steps >= 15 && 10 * r.stiff_steps >= r.steps {
        s.push_str(&format!(
            "stiff: {} of {} steps were limited by stability, not accuracy; the step count \
             reflects the fastest mode, not the tolerance\n",
            r.stiff_steps, r.steps
        ));
    }
    if let Some(c) = outcome.constraint_drift() {
        if outcome.method.handles_algebraic() {
            let at_steps = outcome.constraint_drift_at_steps().unwrap_or(c);
            s.push_str(&format!(
                "constraint drift: max |Φ| = {at_steps:.3e} at the steps, {c:.3e} between them \
                 (the differential–algebraic system, no stabilisation)\n"
            ));
        } else {
            s.push_str(&format!("constraint drift: max |Φ| = {c:.3e} (Baumgarte-stabilised)\n"));
        }
    }
    for e in &r.events {
        let kind = if e.event < outcome.stop_names { "stop" } else { "event" };
        s.push_str(&format!(
            "{kind}: {} = 0 at t = {}\n",
            outcome.event_names[e.event],
            number(e.time)
        ));
    }
    match (&r.fault, r.stopped_by) {
        (Some(f), _) => s.push_str(&format!("{}\n", outcome.describe_fault(f))),
        (None, Some(k)) => s.push_str(&format!(
            "stopped at t = {} by `{}` (before --until)\n",
            number(r.final_time),
            outcome.event_names[k]
        )),
        (None, None) => s.push_str(&format!("reached t = {}\n", number(r.final_time))),
    }
    s
}

/// Which method ran where in an `auto` run: `auto: dop853 0–0.12 s, radau 0.12–10 s (1 switch)`.
fn segments(segments: &[sim::Segment]) -> String {
    let spans: Vec<String> = segments
        .iter()
        .map(|s| format!("{} {}–{} s", s.method.name(), time(s.start), time(s.end)))
        .collect();
    let switches = segments.len().saturating_sub(1);
    let plural = if switches == 1 { "" } else { "es" };
    format!("auto: {} ({switches} switch{plural})", spans.join(", "))
}

/// A time in a summary line, to three significant digits and no more characters than those
/// need (`{:.2e}` rounds, `{}` prints the shortest decimal of the rounded value).
fn time(t: f64) -> String {
    let rounded = format!("{t:.2e}");
    match rounded.parse::<f64>() {
        // Below a millisecond the decimal would start with a row of zeros.
        Ok(v) if v != 0.0 && v.abs() < 1e-3 => format!("{v:e}"),
        Ok(v) => v.to_string(),
        Err(_) => t.to_string(),
    }
}

fn json_number(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v)
        .map(serde_json::Value::Number)
        .unwrap_or(serde_json::Value::Null)
}
