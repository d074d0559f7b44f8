//! `lagrange ensemble`'s outputs: the table as CSV, a row per run, and the summary on stderr.
//! The runs themselves are `engine::ensemble`'s; the progress bar is drawn while they run.

use ::ensemble::{Options, Table};
use engine::Error;

/// Runs the ensemble with a progress bar of its runs on a terminal.
pub fn ensemble(source: &str, options: &Options, threads: Option<usize>) -> Result<Table, Error> {
    ::ensemble::ensemble_with(source, options, threads, &mut crate::progress::Bar::runs())
}

/// The table as CSV: the varied parameters, the recorded quantities, then `fault`, why a run
/// failed (empty where it ran, as are a failed run's recorded cells). Numbers are Rust's
/// shortest round-trip decimals.
pub fn csv(table: &Table) -> String {
    let mut out = csv::Writer::from_writer(Vec::new());
    let header = table.columns.iter().map(String::as_str).chain(["fault"]);
    out.write_record(header).expect("writing to memory");
    for (row, failure) in table.rows.iter().zip(&table.failures) {
        let cells =
            row.iter()
                .map(|v| if v.is_nan() { String::new() } else { crate::simulate::number(*v) });
        let fault = failure.clone().unwrap_or_default();
        out.write_record(cells.chain([fault])).expect("writing to memory");
    }
    let bytes = out.into_inner().expect("writing to memory");
    String::from_utf8(bytes).expect("UTF-8 in, UTF-8 out")
}

/// How many runs ran and failed, and the first failure's reason.
pub fn summary(table: &Table, wall_seconds: f64, threads: usize) -> String {
    let failed: Vec<(usize, &String)> =
        table.failures.iter().enumerate().filter_map(|(k, f)| f.as_ref().map(|f| (k, f))).collect();
    let plural = if threads == 1 { "" } else { "s" };
    let mut s = format!(
        "{} runs, {} failed, {wall_seconds:.3} s wall time on {threads} thread{plural}\n",
        table.rows.len(),
        failed.len()
    );
    if let Some((k, why)) = failed.first() {
        s.push_str(&format!("first failure, run {k}: {why}\n"));
    }
    s
}
