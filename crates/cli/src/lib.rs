//! The `lagrange` command: reading scene files, writing results, and rendering what the
//! engine finds. This is the only crate that touches files and terminals.
//!
//! `engine` loads scenes, lowers and runs them; this crate reads the files, renders
//! diagnostics with source context, formats the `derive`, `check` and `linearize` reports,
//! writes the results of `simulate`, `bench` and `linearize` (CSV, JSON, summaries, tables,
//! SVG, the HTML page that plays a motion), reads the trajectory `inverse-dynamics` takes and
//! writes its forces, compiles and writes an FMU (`export`), and draws progress.

pub mod animate;
pub mod check;
pub mod diagnostics;
pub mod ensemble;
pub mod export;
pub mod inverse;
pub mod linearize;
pub mod plot;
pub mod progress;
pub mod report;
pub mod series;
pub mod simulate;

use engine::Options;
use lang::Diagnostic;

/// Output formats of `derive`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Text,
    Latex,
    Json,
}

/// The `derive` report of a scene in the given format, or the rendered diagnostics.
pub fn derive(path: &str, source: &str, format: Format) -> Result<String, String> {
    derive_with(path, source, format, Options::default())
}

/// [`derive`] with options.
pub fn derive_with(
    path: &str,
    source: &str,
    format: Format,
    options: Options,
) -> Result<String, String> {
    derive_report(path, source, format, options).map(|(report, _warnings)| report)
}

/// The `derive` report and the rendered warnings (empty when there are none), or the rendered
/// errors.
pub fn derive_report(
    path: &str,
    source: &str,
    format: Format,
    options: Options,
) -> Result<(String, String), String> {
    derive_report_with(path, source, format, options, false)
}

/// [`derive_report`], with `full` printing every entry of the text report whole.
pub fn derive_report_with(
    path: &str,
    source: &str,
    format: Format,
    options: Options,
    full: bool,
) -> Result<(String, String), String> {
    derive_keeping(path, source, format, options, full)
        .map(|(report, warnings, _)| (report, warnings))
}

/// [`derive_report`] that also hands back the derivation, for a process about to end: freeing
/// a large model's expressions one by one costs a tenth of the bicycle's run, so the command
/// leaves it to the process's end. A library caller that goes on (a test, the fuzzer) must
/// free it, which [`derive_report`] does. With `full`, every entry of the text report is
/// printed whole rather than as its size past [`report::TEXT_ENTRY_LIMIT`] characters.
pub fn derive_keeping(
    path: &str,
    source: &str,
    format: Format,
    options: Options,
    full: bool,
) -> Result<(String, String, mechanics::Derivation), String> {
    let engine::Scene { derivation: mut d, warnings } =
        engine::load_with(source, options).map_err(|e| diagnostics::error(path, &e))?;
    let report = match format {
        Format::Text => report::text_with(&mut d, full),
        Format::Latex => report::latex(&mut d),
        Format::Json => report::json(&mut d),
    };
    Ok((report, diagnostics::render(path, source, &warnings), d))
}

/// Reads a scene file. The error is ready to print: a missing file says so, and a file that
/// is not UTF-8 gets a diagnostic at the line and column of its first bad byte.
pub fn read_scene(path: &std::path::Path) -> Result<String, String> {
    let bytes =
        std::fs::read(path).map_err(|e| format!("error: cannot read {}: {e}\n", path.display()))?;
    decode(&path.display().to_string(), bytes)
}

/// The text of a scene file's bytes, or the rendered diagnostic of its first byte that is not
/// UTF-8.
pub fn decode(path: &str, bytes: Vec<u8>) -> Result<String, String> {
    let error = match String::from_utf8(bytes) {
        Ok(text) => return Ok(text),
        Err(e) => e,
    };
    let at = error.utf8_error().valid_up_to();
    let bad = error.as_bytes()[at];
    // Rendered against the text with U+FFFD in place of each bad sequence: the part before
    // the first one is unchanged, so its line and column are the file's.
    let shown = String::from_utf8_lossy(error.as_bytes()).into_owned();
    let width = shown[at..].chars().next().map_or(0, char::len_utf8);
    let mut hint =
        "lagrange reads scene files as UTF-8: save the file in that encoding".to_string();
    if error.as_bytes().starts_with(&[0xFF, 0xFE]) || error.as_bytes().starts_with(&[0xFE, 0xFF]) {
        hint.push_str(" (this one looks like UTF-16)");
    } else if let Some(c) = char::from_u32(u32::from(bad)).filter(|_| bad >= 0xA0) {
        hint.push_str(&format!(" (in Latin-1, byte 0x{bad:02X} is `{c}`)"));
    }
    let diagnostic =
        Diagnostic::error(lang::Span::new(at, at + width), "the file is not valid UTF-8")
            .with_label(format!("byte 0x{bad:02X} is not UTF-8"))
            .with_hint(hint);
    Err(diagnostics::render(path, &shown, &[diagnostic]))
}

/// Writes a file whole or not at all: to a temporary file beside it, then renamed over it.
pub fn write_atomically(path: &std::path::Path, contents: &str) -> std::io::Result<()> {
    write_bytes_atomically(path, contents.as_bytes())
}

/// [`write_atomically`] of bytes.
pub fn write_bytes_atomically(path: &std::path::Path, contents: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let dir =
        path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let name =
        path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    // Dropped on an error, the temporary file is removed.
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(without_path)?;
    tmp.as_file_mut().write_all(contents)?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Writes a file whole or not at all by `write`, which writes to the path it is given: a
/// temporary file beside the target with the target's extension (a writer may choose its
/// format by it), renamed over the target once `write` succeeds.
pub fn write_atomically_by(
    path: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir =
        path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let stem =
        path.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{stem}."))
        .suffix(&format!(".tmp.{ext}"))
        .tempfile_in(dir)
        .map_err(without_path)?;
    write(tmp.path())?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// The operating system's error without the temporary path `tempfile` appends to its message
/// (`… at path "…"`): the caller names the target, as it always has, not a file the user never
/// asked for. The path is written with `{:?}`, so its own quotes are escaped and the first
/// ` at path "` is where it starts.
fn without_path(error: std::io::Error) -> std::io::Error {
    let message = error.to_string();
    match message.split_once(" at path \"") {
        Some((message, _)) => std::io::Error::new(error.kind(), message),
        None => error,
    }
}
