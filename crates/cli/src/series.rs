//! An input given to `simulate` as a time series: `--input F=push.csv`, a file of two
//! columns, the time and the value, with an optional header row. Each mistake is reported
//! at its file, line and column.

use std::path::Path;

use engine::input::Assignment;

/// Whether an `--input` value names a file of samples rather than a law.
pub fn is_series(input: &Assignment) -> bool {
    input.value.to_ascii_lowercase().ends_with(".csv")
}

/// Reads the samples of `path`; the error names the file, line and column.
pub fn read(path: &Path) -> Result<sim::Series, String> {
    let shown = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {shown}: {e}"))?;
    parse(&text).map_err(|(line, column, message)| format!("{shown}:{line}:{column}: {message}"))
}

/// The samples of `text`, or where (line, column, both from 1) and why it is not a series.
pub fn parse(text: &str) -> Result<sim::Series, (usize, usize, String)> {
    let (mut times, mut values, mut lines) = (Vec::new(), Vec::new(), Vec::new());
    for (index, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let mut cells = Vec::new();
        let mut start = 0;
        for cell in line.split(',') {
            let lead = cell.len() - cell.trim_start().len();
            cells.push((line[..start + lead].chars().count() + 1, cell.trim()));
            start += cell.len() + 1;
        }
        let numbers: Vec<Option<f64>> = cells.iter().map(|(_, c)| c.parse().ok()).collect();
        // A first row that is not numbers is the header.
        if times.is_empty() && lines.is_empty() && numbers.iter().all(Option::is_none) {
            lines.push(index + 1);
            continue;
        }
        if cells.len() != 2 {
            let message = format!("{} cells; a row is a time and a value", cells.len());
            return Err((index + 1, 1, message));
        }
        for ((column, cell), number) in cells.iter().zip(&numbers) {
            match number {
                None => return Err((index + 1, *column, format!("`{cell}` is not a number"))),
                // Caught here, where the cell's column is known (the series' own check
                // knows only the row).
                Some(n) if !n.is_finite() => {
                    return Err((index + 1, *column, format!("`{cell}` is not a finite number")))
                }
                Some(_) => {}
            }
        }
        times.push(numbers[0].unwrap_or_default());
        values.push(numbers[1].unwrap_or_default());
        lines.push(index + 1);
    }
    let header = usize::from(lines.len() > times.len());
    sim::Series::new(times, values).map_err(|e| match e {
        sim::SeriesError::TooShort => (1, 1, "a series needs at least two rows".to_string()),
        sim::SeriesError::NotIncreasing(k) => {
            (lines[k + header], 1, "the times must increase from row to row".to_string())
        }
        sim::SeriesError::NotFinite(k) => (lines[k + header], 1, "not a finite number".into()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_read_with_or_without_a_header() {
        let s = parse("t,F\n0, 1\n2, 3\n").expect("a series");
        assert_eq!((s.span(), s.at(1.0)), ((0.0, 2.0), 2.0));
        assert_eq!(parse("0,1\n1,1\n").map(|s| s.span()), Ok((0.0, 1.0)));
    }

    #[test]
    fn a_bad_cell_is_found_by_line_and_column() {
        let at = |text: &str| parse(text).err();
        assert_eq!(at("t,F\n0,1\n1, x1\n"), Some((3, 4, "`x1` is not a number".into())));
        assert_eq!(
            at("0,1\n1,2,3\n").map(|e| (e.0, e.2)),
            Some((2, "3 cells; a row is a time and a value".into()))
        );
        assert_eq!(at("t,F\n0,1\n0,2\n").map(|e| e.0), Some(3));
        assert_eq!(at("t,F\n0,1\n").map(|e| e.2), Some("a series needs at least two rows".into()));
        // A value that reads as a number but is not finite, at its own column.
        assert_eq!(at("t,F\n0,1\n1, NaN\n"), Some((3, 4, "`NaN` is not a finite number".into())));
        assert_eq!(at("t,F\n0,1\ninf,2\n"), Some((3, 1, "`inf` is not a finite number".into())));
    }
}
