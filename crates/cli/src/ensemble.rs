//! `lagrange ensemble`'s outputs: the table as CSV, a row per run, and the summary on stderr.
//! The runs themselves are the `ensemble` crate's; the progress bar is drawn while they run.
//! The rows come chunk by chunk in run order ([`ensemble::Sink`]): the CSV is written as they
//! come, the summary counts them ([`Tally`]), and only the picture, when one is asked for,
//! keeps a number a run.

use std::io::Write;

use ::ensemble::{Ensemble, Options, Sink, Table};
use engine::Error;

use crate::plot::ensemble::Picture;

/// Runs the ensemble with a progress bar of its runs on a terminal, keeping its table.
pub fn ensemble(source: &str, options: &Options, threads: Option<usize>) -> Result<Table, Error> {
    ::ensemble::ensemble_with(source, options, threads, &mut crate::progress::Bar::runs())
}

/// Runs every run of `ensemble` on `threads` threads with a progress bar of its runs on a
/// terminal, handing the rows to `sink` as they are made.
pub fn stream(ensemble: &Ensemble, threads: usize, sink: &mut dyn Sink) {
    ensemble.stream(0..ensemble.runs(), threads, &mut crate::progress::Bar::runs(), sink);
}

/// The table as CSV: the varied parameters, the recorded quantities, then `fault`, why a run
/// failed (empty where it ran, as are a failed run's recorded cells). Numbers are Rust's
/// shortest round-trip decimals. After a write fails, nothing more is written and
/// [`Csv::finish`] gives the error.
pub struct Csv<W: Write> {
    out: csv::Writer<W>,
    error: Option<std::io::Error>,
}

impl<W: Write> Csv<W> {
    /// The CSV of a table with `header`'s columns (its rows, if any, are not written).
    pub fn new(header: &Table, out: W) -> Csv<W> {
        let mut csv = Csv { out: csv::Writer::from_writer(out), error: None };
        csv.write(header.columns.iter().map(String::as_str).chain(["fault"]));
        csv
    }

    fn write<I: AsRef<[u8]>>(&mut self, record: impl IntoIterator<Item = I>) {
        if self.error.is_none() {
            if let Err(e) = self.out.write_record(record) {
                self.error = Some(match e.into_kind() {
                    csv::ErrorKind::Io(e) => e,
                    other => std::io::Error::other(format!("{other:?}")),
                });
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
    fn row(&mut self, _run: usize, row: &[f64], failure: Option<&str>) {
        let cells =
            row.iter()
                .map(|v| if v.is_nan() { String::new() } else { crate::simulate::number(*v) });
        self.write(cells.chain([failure.unwrap_or_default().to_string()]));
    }
}

/// The CSV of a table kept whole (see [`Csv`]).
pub fn csv(table: &Table) -> String {
    let mut csv = Csv::new(table, Vec::new());
    for (row, failure) in table.rows.iter().zip(&table.failures) {
        csv.row(0, row, failure.as_deref());
    }
    String::from_utf8(csv.finish().expect("writing to memory")).expect("UTF-8 in, UTF-8 out")
}

/// What the summary says of the rows, counted as they pass: how many, how many failed, and
/// the first failure (its place among the rows) with its reason.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    pub runs: usize,
    pub failed: usize,
    pub first_failure: Option<(usize, String)>,
}

impl Sink for Tally {
    fn row(&mut self, _run: usize, _row: &[f64], failure: Option<&str>) {
        if let Some(why) = failure {
            self.failed += 1;
            self.first_failure.get_or_insert_with(|| (self.runs, why.to_string()));
        }
        self.runs += 1;
    }
}

/// How many runs ran and failed, and the first failure's reason.
pub fn summary(table: &Table, wall_seconds: f64, threads: usize) -> String {
    let mut tally = Tally::default();
    for (row, failure) in table.rows.iter().zip(&table.failures) {
        tally.row(0, row, failure.as_deref());
    }
    summary_of(&tally, wall_seconds, threads)
}

/// [`summary`] of the rows counted.
pub fn summary_of(tally: &Tally, wall_seconds: f64, threads: usize) -> String {
    let plural = if threads == 1 { "" } else { "s" };
    let mut s = format!(
        "{} runs, {} failed, {wall_seconds:.3} s wall time on {threads} thread{plural}\n",
        tally.runs, tally.failed
    );
    if let Some((k, why)) = &tally.first_failure {
        s.push_str(&format!("first failure, run {k}: {why}\n"));
    }
    s
}

/// Every output of `lagrange ensemble` taking the rows as they come: the CSV, the summary's
/// count, and the picture's values where one is drawn.
pub struct Outputs<W: Write> {
    pub csv: Csv<W>,
    pub tally: Tally,
    pub picture: Option<Picture>,
}

impl<W: Write> Sink for Outputs<W> {
    fn row(&mut self, run: usize, row: &[f64], failure: Option<&str>) {
        self.csv.row(run, row, failure);
        self.tally.row(run, row, failure);
        if let Some(picture) = &mut self.picture {
            picture.row(run, row, failure);
        }
    }
}
