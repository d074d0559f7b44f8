//! `lagrange simulate`'s outputs: the recorded quantities as CSV or JSON, and the summary of
//! a run. The run itself is `simulation`'s; the progress bar is drawn while it runs.
//! The table is written as the rows are made ([`Table`], an `simulation::Sink`), so a
//! run holds none of them; from a run that kept its rows ([`csv`], [`json`]) the same writers
//! give the same bytes.

use std::io::Write;

use engine::Error;
use simulation::{Options, Outcome, Sink};

/// Runs the scene with a progress bar on a terminal, keeping its rows.
pub fn simulate(source: &str, options: &Options) -> Result<Outcome, Error> {
    simulation::simulate_with(source, options, &mut crate::progress::Bar::new())
}

/// Runs the scene with a progress bar on a terminal, its rows handed to `sink` as they are
/// made and not kept.
pub fn simulate_into(
    source: &str,
    options: &Options,
    sink: &mut dyn Sink,
) -> Result<Outcome, Error> {
    simulation::simulate_into(source, options, &mut crate::progress::Bar::new(), sink)
}

/// A run's table written as its rows come, as CSV or JSON.
// One table a run: the CSV writer's buffer beside JSON's is not worth a box.
#[allow(clippy::large_enum_variant)]
pub enum Table<W: Write> {
    Csv(Csv<W>),
    Json(Json<W>),
}

impl<W: Write> Table<W> {
    /// A table to `out`, as JSON or else as CSV.
    pub fn new(json: bool, out: W) -> Table<W> {
        if json {
            Table::Json(Json::new(out))
        } else {
            Table::Csv(Csv::new(out))
        }
    }

    /// Ends the table with what only the end of the run knows (JSON's events and summary),
    /// and gives the writer back, or the first error met writing.
    pub fn finish(self, outcome: &Outcome) -> std::io::Result<W> {
        match self {
            Table::Csv(csv) => csv.finish(),
            Table::Json(json) => json.finish(outcome),
        }
    }
}

impl<W: Write> Sink for Table<W> {
    fn columns(&mut self, names: &[String]) {
        match self {
            Table::Csv(csv) => csv.columns(names),
            Table::Json(json) => json.columns(names),
        }
    }

    fn row(&mut self, t: f64, outputs: &[f64], energy: f64) {
        match self {
            Table::Csv(csv) => csv.row(t, outputs, energy),
            Table::Json(json) => json.row(t, outputs, energy),
        }
    }
}

/// The recorded outputs as CSV: a header, then a row per recorded time. Numbers are written as
/// Rust's shortest round-trip decimals (`{}`), which never need quoting. After a write fails,
/// nothing more is written and [`Csv::finish`] gives the error.
pub struct Csv<W: Write> {
    out: csv::Writer<W>,
    error: Option<std::io::Error>,
}

impl<W: Write> Csv<W> {
    pub fn new(out: W) -> Csv<W> {
        Csv { out: csv::Writer::from_writer(out), error: None }
    }

    fn write<I: AsRef<[u8]>>(&mut self, record: impl IntoIterator<Item = I>) {
        if self.error.is_none() {
            if let Err(e) = self.out.write_record(record) {
                self.error = Some(io_error(e));
            }
        }
    }

    /// The writer, flushed, or the first error met writing.
    pub fn finish(self) -> std::io::Result<W> {
        if let Some(e) = self.error {
            return Err(e);
        }
        self.out.into_inner().map_err(|e| std::io::Error::new(e.error().kind(), e.to_string()))
    }
}

impl<W: Write> Sink for Csv<W> {
    fn columns(&mut self, names: &[String]) {
        self.write(std::iter::once("t").chain(names.iter().map(String::as_str)));
    }

    fn row(&mut self, t: f64, outputs: &[f64], _energy: f64) {
        self.write(std::iter::once(t).chain(outputs.iter().copied()).map(number));
    }
}

/// A CSV writer's error as the IO error it is (or wraps).
fn io_error(e: csv::Error) -> std::io::Error {
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        other => std::io::Error::other(format!("{other:?}")),
    }
}

/// Hands a run's kept rows to `sink`, as a streamed run hands them.
fn replay(outcome: &Outcome, sink: &mut dyn Sink) {
    sink.columns(&outcome.columns[..outcome.shown]);
    let trajectory = &outcome.run.trajectory;
    for ((t, row), energy) in trajectory.times.iter().zip(&trajectory.rows).zip(outcome.energy()) {
        sink.row(*t, &row[..outcome.shown], energy);
    }
}

/// The recorded outputs of a run that kept its rows, as CSV (see [`Csv`]).
pub fn csv(outcome: &Outcome) -> String {
    let mut csv = Csv::new(Vec::new());
    replay(outcome, &mut csv);
    String::from_utf8(csv.finish().expect("writing to memory")).expect("UTF-8 in, UTF-8 out")
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

/// The recorded outputs of a run that kept its rows, the events and the summary as JSON (see
/// [`Json`]).
pub fn json(outcome: &Outcome) -> String {
    let mut json = Json::new(Vec::new());
    replay(outcome, &mut json);
    let bytes = json.finish(outcome).expect("writing to memory");
    String::from_utf8(bytes).expect("UTF-8 in, UTF-8 out")
}

/// The recorded outputs, the events and the summary as one JSON object, written as the rows
/// come: `columns`, `rows` (an array of `[t, outputs…]`), then, once the run is over,
/// `events` and `summary`. It is laid out as serde_json's pretty printer lays out the whole
/// object (two spaces a level), which writes each value alone; the rows are written one by one
/// in that layout.
pub struct Json<W: Write> {
    out: W,
    rows: usize,
    error: Option<std::io::Error>,
}

impl<W: Write> Json<W> {
    pub fn new(out: W) -> Json<W> {
        Json { out, rows: 0, error: None }
    }

    fn write(&mut self, text: &str) {
        if self.error.is_none() {
            if let Err(e) = self.out.write_all(text.as_bytes()) {
                self.error = Some(e);
            }
        }
    }

    /// Closes the rows and writes the events and the summary; the writer, or the first
    /// error met writing.
    pub fn finish(mut self, outcome: &Outcome) -> std::io::Result<W> {
        self.write(if self.rows > 0 { "\n  ]" } else { "]" });
        let events: Vec<serde_json::Value> = outcome
            .run
            .events
            .iter()
            .map(|e| serde_json::json!({"event": outcome.event_names[e.event], "t": e.time}))
            .collect();
        let (events, summary) = (pretty(&events.into()), pretty(&summary_json(outcome)));
        self.write(&format!(",\n  \"events\": {events},\n  \"summary\": {summary}\n}}\n"));
        match self.error {
            Some(e) => Err(e),
            None => self.out.flush().map(|()| self.out),
        }
    }
}

impl<W: Write> Sink for Json<W> {
    fn columns(&mut self, names: &[String]) {
        let mut columns = vec!["t".to_string()];
        columns.extend(names.iter().cloned());
        let columns = pretty(&columns.into());
        self.write(&format!("{{\n  \"columns\": {columns},\n  \"rows\": ["));
    }

    fn row(&mut self, t: f64, outputs: &[f64], _energy: f64) {
        let mut text = String::from(if self.rows == 0 { "\n    [" } else { ",\n    [" });
        for (k, x) in std::iter::once(t).chain(outputs.iter().copied()).enumerate() {
            text.push_str(if k == 0 { "\n      " } else { ",\n      " });
            text.push_str(&json_number(x).to_string());
        }
        text.push_str("\n    ]");
        self.rows += 1;
        self.write(&text);
    }
}

/// A value as serde_json's pretty printer writes it one level into an object.
fn pretty(value: &serde_json::Value) -> String {
    serde_json::to_string_pretty(value).expect("json").replace('\n', "\n  ")
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
        "energy_changed_by_impacts": json_number(outcome.totals.energy_jumps()),
        "contact_events": outcome.run.modes.iter().map(|m| serde_json::json!({
            "t": json_number(m.time),
            "contact": contact_name(outcome, m.contact),
            "kind": mode_word(m.kind),
            "closed": m.closed,
            "impulse": json_number(m.impulse),
            "tangential_impulse": m.tangential.map(json_number),
            "energy_change": json_number(m.energy_change),
            "slip": json_number(m.slip),
        })).collect::<Vec<_>>(),
    })
}

/// What happened to a contact, in one word, as the events table and the summary name it.
pub use simulation::mode_word;

/// A contact's name, by its index in a run's mode events.
fn contact_name(outcome: &Outcome, k: usize) -> String {
    outcome.contact_name(k)
}

/// A run's contact events as CSV, one row each: when, which contact, what happened, whether it
/// is closed after, its normal and tangential impulses and the kinetic energy they changed.
pub fn contact_events_csv(outcome: &Outcome) -> String {
    let mut s =
        String::from("t,contact,kind,closed,impulse,tangential_impulse,energy_change,slip\n");
    for m in &outcome.run.modes {
        let tangential = m.tangential.map_or(String::new(), |t| t.to_string());
        s.push_str(&format!(
            "{},{},{},{},{},{tangential},{},{}\n",
            m.time,
            contact_name(outcome, m.contact),
            mode_word(m.kind),
            m.closed,
            m.impulse,
            m.energy_change,
            m.slip
        ));
    }
    s
}

/// The summary's lines on contacts: how many impacts, lift-offs and settlings, the first few
/// events, and where impacts raised the energy.
fn contacts_summary(outcome: &Outcome) -> String {
    let modes = &outcome.run.modes;
    if outcome.contact_names.is_empty() {
        return String::new();
    }
    let count = |kind: sim::ModeChange| modes.iter().filter(|m| m.kind == kind).count();
    let (impacts, lift_offs) = (count(sim::ModeChange::Impact), count(sim::ModeChange::LiftOff));
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    // Without an impact the jumps change E only by the projection's rounding.
    let removed = match impacts + count(sim::ModeChange::Settled) {
        0 => String::new(),
        _ => format!(", {} removed by impacts", figure(0.0 - outcome.totals.energy_jumps())),
    };
    let mut s = format!(
        "contacts: {}, {}{removed}\n",
        plural(impacts, "impact"),
        plural(lift_offs, "lift-off"),
    );
    for m in modes.iter().filter(|m| m.kind == sim::ModeChange::Settled) {
        s.push_str(&format!(
            "settled: `{}` at t = {}, where its impacts accumulate (closed from then on)\n",
            contact_name(outcome, m.contact),
            figure(m.time)
        ));
    }
    const SHOWN: usize = 8;
    for m in modes.iter().take(SHOWN) {
        let mut line = format!(
            "  t = {}  {} {}",
            figure(m.time),
            contact_name(outcome, m.contact),
            mode_word(m.kind)
        );
        let struck = matches!(
            m.kind,
            sim::ModeChange::Impact | sim::ModeChange::Settled | sim::ModeChange::Struck
        );
        if struck || m.impulse != 0.0 {
            line.push_str(&format!(", impulse {}", figure(m.impulse)));
            if let Some(t) = m.tangential {
                line.push_str(&format!(" (tangential {})", figure(t)));
            }
            line.push_str(&format!(", ΔE = {}", figure(m.energy_change)));
        }
        let in_space = outcome.contacts_in_space.get(m.contact) == Some(&true);
        if m.kind == sim::ModeChange::Slips && !in_space {
            // Which way along its slip rate v.
            line.push_str(if m.slip > 0.0 { " (v > 0)" } else { " (v < 0)" });
        }
        if m.energy_rise {
            line.push_str(
                " (this impact raised the energy: Newton's law with unequal restitutions can)",
            );
        }
        s.push_str(&line);
        s.push('\n');
    }
    if modes.len() > SHOWN {
        s.push_str(&format!(
            "  … and {} more (`--events FILE.csv` writes them all)\n",
            modes.len() - SHOWN
        ));
    }
    s
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
    if outcome.contact_names.is_empty() {
        s.push_str(&format!(
            "energy drift: max |E − E(0)| = {drift:.3e} ({relative:.3e} relative){note}\n"
        ));
    } else {
        // What the impacts changed is accounted for, not drift.
        s.push_str(&format!(
            "energy drift: max |E − E(0) − ΔE(impacts)| = {drift:.3e} ({relative:.3e} \
             relative){note}\n"
        ));
    }
    s.push_str(&contacts_summary(outcome));
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

/// A figure in a summary line, to six significant digits and no more characters than those
/// need.
fn figure(x: f64) -> String {
    match format!("{x:.5e}").parse::<f64>() {
        Ok(v) if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) => format!("{v:e}"),
        Ok(v) => v.to_string(),
        Err(_) => x.to_string(),
    }
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
