//! The `lagrange` command: reading scene files, writing results, and rendering what the
//! engine finds. This is the only crate that touches files and terminals.
//!
//! `engine` loads scenes, lowers and runs them; this crate reads the files, renders
//! diagnostics with source context, formats the `derive`, `check` and `linearize` reports,
//! writes the results of `simulate`, `bench` and `linearize` (CSV, JSON, summaries, tables,
//! SVG, the HTML page that plays a motion), reads the trajectory `inverse-dynamics` and
//! `linearize --along` take (`trajectory`), writes the forces and the matrices along a
//! motion (`along`), compiles and writes an FMU (`export`), and draws progress.

pub mod along;
pub mod animate;
pub mod check;
pub mod diagnostics;
pub mod ensemble;
pub mod export;
pub mod fit;
pub mod inverse;
pub mod linearize;
pub mod orbit;
pub mod plot;
pub mod progress;
pub mod report;
pub mod series;
pub mod simulate;
pub mod trajectory;

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
) -> Result<(String, String, engine::derived::Derivation), String> {
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
        // A byte-order mark is no part of the scene: left in, it would count as a column of
        // the first line and show as nothing in a message that quotes it.
        Ok(text) => match text.strip_prefix('\u{FEFF}') {
            Some(rest) => return Ok(rest.to_string()),
            None => return Ok(text),
        },
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
/// What it replaces is respected as an editor's save respects it: a read-only file is refused,
/// a symbolic link is written through (its target replaced, the link kept), a replaced file
/// keeps its mode, and a new one gets 0666 less the umask.
pub fn write_atomically(path: &std::path::Path, contents: &str) -> std::io::Result<()> {
    write_bytes_atomically(path, contents.as_bytes())
}

/// [`write_atomically`] of bytes.
pub fn write_bytes_atomically(path: &std::path::Path, contents: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let mut file = AtomicFile::create(path)?;
    file.write_all(contents)?;
    file.finish()
}

/// A file written as it is made and put in place whole, as [`write_atomically`] puts one: the
/// bytes go to a temporary file beside the target, renamed over it by
/// [`AtomicFile::finish`]. Dropped unfinished (an error, a run refused), the temporary file is
/// removed and the target is as it was: a half-written table is never at its path.
pub struct AtomicFile {
    target: Target,
    out: std::io::BufWriter<tempfile::NamedTempFile>,
}

impl AtomicFile {
    /// The temporary file for `path`, empty.
    pub fn create(path: &std::path::Path) -> std::io::Result<AtomicFile> {
        let target = Target::of(path)?;
        let name = target
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let tmp = target.temporary(&format!(".{name}."), ".tmp")?;
        Ok(AtomicFile { target, out: std::io::BufWriter::new(tmp) })
    }

    /// Puts what was written in place of the target.
    pub fn finish(self) -> std::io::Result<()> {
        let tmp = self.out.into_inner().map_err(std::io::IntoInnerError::into_error)?;
        self.target.replace_by(tmp)
    }
}

impl std::io::Write for AtomicFile {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.out.write(bytes)
    }

    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.out.write_all(bytes)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

/// Writes a file whole or not at all by `write`, which writes to the path it is given: a
/// temporary file beside the target with the target's extension (a writer may choose its
/// format by it), renamed over the target once `write` succeeds; what it replaces is respected
/// as [`write_atomically`] respects it.
pub fn write_atomically_by(
    path: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let target = Target::of(path)?;
    let stem = target
        .path
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let ext = target.path.extension().map(|e| e.to_string_lossy().into_owned());
    let tmp =
        target.temporary(&format!(".{stem}."), &format!(".tmp.{}", ext.unwrap_or_default()))?;
    write(tmp.path())?;
    target.replace_by(tmp)
}

/// Whether `output` is the file `input` (a path to it by another name, `./s.lag` or a symbolic
/// link, included): a command must not write over what it reads. An output not there yet is
/// no file read.
pub fn same_file(input: &std::path::Path, output: &std::path::Path) -> bool {
    let (Ok(read), Ok(written)) = (std::fs::metadata(input), std::fs::metadata(output)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        (read.dev(), read.ino()) == (written.dev(), written.ino())
    }
    #[cfg(not(unix))]
    {
        let _ = (read, written);
        std::fs::canonicalize(input).ok() == std::fs::canonicalize(output).ok()
    }
}

/// The file an atomic write replaces: the path with its symbolic links followed (a rename
/// over the link would put a regular file in its place and leave its target as it was), and
/// the mode of the file there, if there is one.
struct Target {
    path: std::path::PathBuf,
    existing: Option<std::fs::Permissions>,
}

/// More links than this in a row is a loop (Linux's own limit).
const MAX_LINKS: usize = 40;

impl Target {
    fn of(path: &std::path::Path) -> std::io::Result<Target> {
        let mut path = path.to_path_buf();
        for _ in 0..MAX_LINKS {
            let metadata = match std::fs::symlink_metadata(&path) {
                Ok(metadata) => metadata,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    return Ok(Target { path, existing: None });
                }
                Err(e) => return Err(e),
            };
            if metadata.file_type().is_symlink() {
                let link = std::fs::read_link(&path)?;
                // A relative link is relative to the folder the link is in.
                path = match path.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
                continue;
            }
            if metadata.is_dir() {
                return Err(std::io::Error::other("it is a directory"));
            }
            // Renaming over the file would replace it even so (the rename needs only the
            // folder's write bit); as root even writing to it would.
            if metadata.permissions().readonly() {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::PermissionDenied,
                    "the file is read-only: make it writable or write elsewhere",
                ));
            }
            return Ok(Target { path, existing: Some(metadata.permissions()) });
        }
        Err(std::io::Error::other(format!("more than {MAX_LINKS} symbolic links in a row")))
    }

    /// An empty temporary file in the target's folder, made as the target will be: with the
    /// replaced file's mode, or 0666 less the umask (the mode `open` applies the umask to).
    fn temporary(&self, prefix: &str, suffix: &str) -> std::io::Result<tempfile::NamedTempFile> {
        let dir = self
            .path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(std::path::Path::new("."));
        let mut builder = tempfile::Builder::new();
        builder.prefix(prefix).suffix(suffix);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let tmp = builder.tempfile_in(dir).map_err(without_path)?;
        if let Some(permissions) = &self.existing {
            // Set after creation: the umask would have narrowed it through `open`.
            tmp.as_file().set_permissions(permissions.clone())?;
        }
        Ok(tmp)
    }

    /// Renames the written temporary file over the target.
    fn replace_by(self, tmp: tempfile::NamedTempFile) -> std::io::Result<()> {
        tmp.persist(&self.path).map_err(|e| e.error)?;
        Ok(())
    }
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
