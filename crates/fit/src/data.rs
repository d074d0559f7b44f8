//! The measurements a fit reads: CSV text with a header row, one column `t` of times and any
//! others named by scene expressions (`theta`, `x'`, `KE`, an output's name). A cell left
//! empty is a value not measured at that time. Every mistake is a diagnostic with a span into
//! the text, so that a front end shows the file, line and column with a caret.

use lang::{Diagnostic, Span};

/// The header of the time column.
pub const TIME: &str = "t";

/// A measured column: its header (a scene expression) and where the header stands.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub name: String,
    pub span: Span,
}

/// The rows of a data file: the times, increasing, and per column its values at them
/// (`None` where a cell is empty).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub columns: Vec<Column>,
    pub times: Vec<f64>,
    /// `values[c][r]`: column `c` at row `r`.
    pub values: Vec<Vec<Option<f64>>>,
    /// The span of each row's time cell, for what a later check finds wrong with a row.
    pub rows: Vec<Span>,
}

impl Table {
    /// The number of measured values: the residuals of a fit.
    pub fn measured(&self) -> usize {
        self.values.iter().map(|c| c.iter().flatten().count()).sum()
    }

    /// The column named `name`, by index.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c.name == name)
    }
}

/// One line split at its commas: each cell's trimmed text and span.
fn cells(line_start: usize, line: &str) -> Vec<(String, Span)> {
    let mut out = Vec::new();
    let mut offset = 0;
    for cell in line.split(',') {
        let lead = cell.len() - cell.trim_start().len();
        let trimmed = cell.trim();
        let start = line_start + offset + lead;
        out.push((trimmed.to_string(), Span::new(start, start + trimmed.len().max(1))));
        offset += cell.len() + 1;
    }
    out
}

/// The lines of `text` that hold something, each with its byte offset; `#` starts a comment
/// line.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut start = 0;
    text.split_inclusive('\n').filter_map(move |raw| {
        let at = start;
        start += raw.len();
        let line = raw.trim_end_matches(['\n', '\r']);
        let shown = line.trim();
        (!shown.is_empty() && !shown.starts_with('#')).then_some((at, line))
    })
}

/// Reads `text` as a data table.
pub fn read(text: &str) -> Result<Table, Vec<Diagnostic>> {
    let mut lines = lines(text);
    let Some((header_at, header_line)) = lines.next() else {
        let d = Diagnostic::error(Span::new(0, text.len().max(1)), "the data file is empty")
            .with_label("no header and no rows")
            .with_hint(format!(
                "a header row names the columns, `{TIME}` and scene expressions (`{TIME}, \
                 theta, theta'`), then a row per time"
            ));
        return Err(vec![d]);
    };
    let header = cells(header_at, header_line);
    let mut seen: Vec<&(String, Span)> = Vec::new();
    for cell in &header {
        if cell.0.is_empty() {
            let d = Diagnostic::error(cell.1, "a column with no name")
                .with_label("an empty header")
                .with_hint("every column is named: `t`, or a scene expression");
            return Err(vec![d]);
        }
        if let Some(first) = seen.iter().find(|s| s.0 == cell.0) {
            let d = Diagnostic::error(cell.1, format!("the column `{}` is given twice", cell.0))
                .with_label("again here")
                .with_related(first.1, "first here");
            return Err(vec![d]);
        }
        seen.push(cell);
    }
    let Some(time) = header.iter().position(|c| c.0 == TIME) else {
        let span = Span::new(header_at, header_at + header_line.len().max(1));
        let d = Diagnostic::error(span, format!("no column `{TIME}`: the times of the rows"))
            .with_label("the header")
            .with_hint(format!(
                "name the column of times `{TIME}` (in seconds), as `simulate` writes it"
            ));
        return Err(vec![d]);
    };
    if header.len() < 2 {
        let d = Diagnostic::error(header[time].1, "no measured column besides the times")
            .with_label("only the times")
            .with_hint("add the measured quantities as columns named by scene expressions");
        return Err(vec![d]);
    }
    let columns: Vec<Column> = header
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != time)
        .map(|(_, (name, span))| Column { name: name.clone(), span: *span })
        .collect();
    let mut table = Table {
        values: vec![Vec::new(); columns.len()],
        columns,
        times: Vec::new(),
        rows: Vec::new(),
    };
    for (at, line) in lines {
        let row = cells(at, line);
        if row.len() != header.len() {
            let span = Span::new(at, at + line.len().max(1));
            let d = Diagnostic::error(
                span,
                format!("{} cells in a row where the header names {}", row.len(), header.len()),
            )
            .with_label("this row")
            .with_hint(
                "leave a cell empty (nothing between its commas) where nothing was measured",
            );
            return Err(vec![d]);
        }
        let (time_text, time_span) = &row[time];
        let t = number(time_text, *time_span, TIME)?.ok_or_else(|| {
            vec![Diagnostic::error(*time_span, "a row without its time")
                .with_label("empty")
                .with_hint("every row has a time; the other cells may be empty")]
        })?;
        if let (Some(&before), Some(&before_span)) = (table.times.last(), table.rows.last()) {
            if t <= before {
                let d = Diagnostic::error(
                    *time_span,
                    format!(
                        "the time {t} does not come after {before}: the rows' times must increase"
                    ),
                )
                .with_label("not after the row before")
                .with_related(before_span, "the time before")
                .with_hint("sort the rows by time, and give each time once");
                return Err(vec![d]);
            }
        }
        table.times.push(t);
        table.rows.push(*time_span);
        let measured = row.iter().enumerate().filter(|(k, _)| *k != time).map(|(_, cell)| cell);
        for (c, (cell, span)) in measured.enumerate() {
            let name = &table.columns[c].name;
            table.values[c].push(number(cell, *span, name)?);
        }
    }
    if table.times.is_empty() {
        let span = Span::new(header_at, header_at + header_line.len().max(1));
        let d = Diagnostic::error(span, "a header but no rows")
            .with_label("nothing follows")
            .with_hint("give a row per time of measurement");
        return Err(vec![d]);
    }
    for (c, column) in table.columns.iter().enumerate() {
        if table.values[c].iter().all(Option::is_none) {
            let d =
                Diagnostic::error(column.span, format!("the column `{}` is empty", column.name))
                    .with_label("no value in any row")
                    .with_hint("leave out a column that was not measured");
            return Err(vec![d]);
        }
    }
    Ok(table)
}

/// A cell's number: `None` for an empty cell, an error for text that is not a finite number.
fn number(cell: &str, span: Span, column: &str) -> Result<Option<f64>, Vec<Diagnostic>> {
    if cell.is_empty() {
        return Ok(None);
    }
    match cell.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        _ => Err(vec![Diagnostic::error(
            span,
            format!("`{cell}` in the column `{column}` is not a finite number"),
        )
        .with_label("not a number")
        .with_hint("write numbers in decimal or exponent form (`0.25`, `-1.5e-3`); leave a cell empty where nothing was measured")]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_reads_its_columns_and_empty_cells() {
        let table = read("t, theta, theta'\n0, 0.5, 0\n# a comment\n0.1, 0.49,\n").unwrap();
        assert_eq!(table.times, vec![0.0, 0.1]);
        assert_eq!(table.columns.len(), 2);
        assert_eq!(table.values[1], vec![Some(0.0), None]);
        assert_eq!(table.measured(), 3);
    }

    #[test]
    fn times_that_do_not_increase_are_refused_at_their_cell() {
        let text = "t,x\n0,1\n0.2,1\n0.1,2\n";
        let e = read(text).unwrap_err();
        assert_eq!(&text[e[0].span.start..e[0].span.end], "0.1");
    }
}
