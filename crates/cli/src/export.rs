//! `lagrange export --fmu`: the FMU's binary compiled with the system C compiler, and the
//! archive written whole or not at all.

use std::io::Write;
use std::path::Path;
use std::process::Command;

use export::fmu::Fmu;

/// Why an export failed, in words for the command line.
#[derive(Debug)]
pub enum ExportError {
    /// No C compiler could be started: the command tried, and the system's reason.
    NoCompiler { compiler: String, reason: String },
    /// The compiler ran and refused the sources: its command and what it printed.
    Compile { command: String, output: String },
    /// Reading or writing a file went wrong.
    Io(String),
}

impl std::fmt::Display for ExportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ExportError::NoCompiler { compiler, reason } => write!(
                f,
                "no C compiler: `{compiler}` could not be started ({reason}). An FMU holds a \
                 binary built on this machine: install a C99 compiler (gcc or clang) or name \
                 one in the CC environment variable"
            ),
            ExportError::Compile { command, output } => {
                write!(f, "the C compiler refused the FMU's sources\n  {command}\n{output}")
            }
            ExportError::Io(message) => f.write_str(message),
        }
    }
}

/// The compiler to use: `CC` when set and not empty, else `cc`.
pub fn compiler() -> String {
    std::env::var("CC").ok().filter(|c| !c.trim().is_empty()).unwrap_or_else(|| "cc".into())
}

/// Compiles the FMU's shared library in a temporary folder and returns its bytes.
pub fn build_binary(fmu: &Fmu, compiler: &str) -> Result<Vec<u8>, ExportError> {
    let io = |what: &str, e: std::io::Error| ExportError::Io(format!("{what}: {e}"));
    let dir = tempfile::tempdir().map_err(|e| io("cannot make a temporary folder", e))?;
    for (name, text) in &fmu.sources {
        std::fs::write(dir.path().join(name), text)
            .map_err(|e| io(&format!("cannot write {name}"), e))?;
    }
    let (_, extension) = Fmu::platform();
    let output = dir.path().join(format!("{}.{extension}", fmu.model_identifier));
    // `CC` may carry flags of its own (`CC="gcc -m64"`), as make's convention has it.
    let mut words = compiler.split_whitespace();
    let program = words.next().unwrap_or("cc");
    let mut command = Command::new(program);
    command.args(words).current_dir(dir.path());
    command.args(["-std=c99", "-O2", "-fPIC", "-fvisibility=hidden"]);
    command.arg(if cfg!(target_os = "macos") { "-dynamiclib" } else { "-shared" });
    command.arg("-o").arg(&output);
    command.args(fmu.compile_units());
    command.arg("-lm");
    let shown = format!("{command:?}");
    let result = command.output().map_err(|e| ExportError::NoCompiler {
        compiler: program.to_string(),
        reason: e.to_string(),
    })?;
    if !result.status.success() {
        let mut text = String::from_utf8_lossy(&result.stderr).into_owned();
        text.push_str(&String::from_utf8_lossy(&result.stdout));
        return Err(ExportError::Compile { command: shown, output: text });
    }
    std::fs::read(&output).map_err(|e| io("cannot read the compiled binary", e))
}

/// The archive's bytes: modelDescription.xml, the binary, the sources and the documentation,
/// in that order, each stamped with zip's earliest date so that an export is reproducible.
pub fn archive(fmu: &Fmu, binary: &[u8]) -> Result<Vec<u8>, ExportError> {
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    let (platform, extension) = Fmu::platform();
    let mut entries: Vec<(String, &[u8])> = vec![
        ("modelDescription.xml".into(), fmu.model_description.as_bytes()),
        (format!("binaries/{platform}/{}.{extension}", fmu.model_identifier), binary),
    ];
    for (name, text) in &fmu.sources {
        entries.push((format!("sources/{name}"), text.as_bytes()));
    }
    entries.push(("documentation/index.html".into(), fmu.documentation.as_bytes()));
    let zip_error = |e: &dyn std::fmt::Display| ExportError::Io(format!("cannot archive: {e}"));
    for (name, bytes) in entries {
        zip.start_file(name, options).map_err(|e| zip_error(&e))?;
        zip.write_all(bytes).map_err(|e| zip_error(&e))?;
    }
    Ok(zip.finish().map_err(|e| zip_error(&e))?.into_inner())
}

/// The whole export: the FMU of `fmu` compiled with `compiler` and written to `out`.
pub fn export(fmu: &Fmu, compiler: &str, out: &Path) -> Result<(), ExportError> {
    let binary = build_binary(fmu, compiler)?;
    let bytes = archive(fmu, &binary)?;
    crate::write_bytes_atomically(out, &bytes)
        .map_err(|e| ExportError::Io(format!("cannot write {}: {e}", out.display())))
}
