//! A motion read from CSV, for the commands that take one (`inverse-dynamics --trajectory`,
//! `linearize --along FILE.csv`): the columns a command wants found by their headers (others
//! ignored, so that a `simulate` table with more outputs serves), every cell a finite number,
//! and each error ready to print, naming the file, and for a bad cell its line and column.

/// What a command wants of the file.
pub struct Wanted<'a> {
    /// The headers, in the order the rows are handed back in.
    pub columns: &'a [String],
    /// What the command needs, in words, after "a trajectory needs".
    pub needs: &'a str,
    /// How to make such a file, for the hint of a missing column.
    pub hint: &'a str,
}

/// The wanted columns of every row, in the wanted order, each row with its line in the file.
pub struct Table {
    pub lines: Vec<u64>,
    pub rows: Vec<Vec<f64>>,
}

/// Reads the CSV `text` of the file `path` for the columns `wanted` asks for.
pub fn read_columns(path: &str, text: &str, wanted: &Wanted) -> Result<Table, String> {
    let mut reader = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| format!("error: cannot read {path}: {e}"))?
        .iter()
        .map(String::from)
        .collect();
    let mut columns = Vec::new();
    for name in wanted.columns {
        let found: Vec<usize> = (0..header.len()).filter(|k| header[*k] == *name).collect();
        match found[..] {
            [k] => columns.push(k),
            [] => return Err(missing(path, name, &header, wanted)),
            _ => return Err(format!("error: {path} has the column `{name}` more than once")),
        }
    }
    let mut table = Table { lines: Vec::new(), rows: Vec::new() };
    for record in reader.records() {
        let record = record.map_err(|e| format!("error: cannot read {path}: {e}"))?;
        let line = record.position().map_or(0, csv::Position::line);
        let mut values = Vec::with_capacity(columns.len());
        for (name, k) in wanted.columns.iter().zip(&columns) {
            let cell = record.get(*k).unwrap_or("");
            let value = cell.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
                format!(
                    "error: {path}:{line}:{}: `{cell}` in the column `{name}` is not a finite \
                     number",
                    k + 1
                )
            })?;
            values.push(value);
        }
        table.lines.push(line);
        table.rows.push(values);
    }
    if table.rows.is_empty() {
        return Err(format!("error: {path} has a header but no rows"));
    }
    Ok(table)
}

/// The error of a column not found: what a trajectory needs, and the file's columns that
/// nothing reads (where a misspelt header shows).
fn missing(path: &str, name: &str, header: &[String], wanted: &Wanted) -> String {
    let mut message = format!(
        "error: {path} has no column `{name}`: a trajectory needs {}\n  = hint: {}",
        wanted.needs, wanted.hint
    );
    let unread: Vec<&str> =
        header.iter().filter(|h| !wanted.columns.contains(h)).map(String::as_str).collect();
    if !unread.is_empty() {
        message.push_str(&format!("\n  = note: the columns nothing reads: {}", unread.join(", ")));
    }
    message
}

/// That the column `name`, the first of the table's, strictly increases down the file.
pub fn increasing(path: &str, table: &Table, name: &str) -> Result<(), String> {
    for (k, pair) in table.rows.windows(2).enumerate() {
        if pair[1][0].partial_cmp(&pair[0][0]) != Some(std::cmp::Ordering::Greater) {
            return Err(format!(
                "error: {path}:{}: `{name}` = {} does not come after {} on line {}: the times \
                 of a motion must increase",
                table.lines[k + 1],
                pair[1][0],
                pair[0][0],
                table.lines[k]
            ));
        }
    }
    Ok(())
}
