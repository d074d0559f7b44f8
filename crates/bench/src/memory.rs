//! Peak resident memory of this process, from Linux's `/proc/self/status` (`VmHWM`), and a way
//! to reset the peak between measurements (writing 5 to `/proc/self/clear_refs`). Elsewhere
//! both do nothing and the figure is `None`: memory is reported where it can be read, never
//! guessed. And `memory`, the benchmark of the tables that stream: the peak of `lagrange`
//! processes, read from their own status files while they run.

use std::fs;

/// Forgets the peak so far, so that the next [`peak_bytes`] is the peak of what runs between.
/// Without the reset (older kernels, other systems) the peak is that of the whole process so
/// far, which for the scaling ladder's growing sizes is still the latest size's.
pub fn reset_peak() {
    let _ = fs::write("/proc/self/clear_refs", "5");
}

/// The peak resident set size since the last reset (or since the start), in bytes.
pub fn peak_bytes() -> Option<u64> {
    high_water("/proc/self/status")
}

/// Bytes as a table shows them: `18.4 MB`, or `-` when unknown.
pub fn megabytes(bytes: Option<u64>) -> String {
    match bytes {
        Some(b) => format!("{:.1} MB", b as f64 / 1e6),
        None => "-".to_string(),
    }
}

/// The streaming benchmark: the peak memory of `lagrange simulate` and `lagrange ensemble`
/// processes as their output grows tenfold and tenfold again, up to `largest` samples and
/// runs, each table written to a temporary file. Memory that stays flat while the output
/// grows is what streaming the rows buys; a row kept per sample or run would show as
/// megabytes growing with the count.
pub fn run(largest: usize) {
    let Some(lagrange) = lagrange_binary() else {
        eprintln!(
            "memory: no `lagrange` beside this program; build both: \
             cargo build --release -p cli -p bench"
        );
        return;
    };
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scratch = tempfile::tempdir().expect("a temporary directory");
    let out = scratch.path().join("table.csv");
    let mut counts = vec![100_000];
    while counts.last().is_some_and(|n| n * 10 <= largest) {
        counts.push(counts.last().expect("a count") * 10);
    }
    outln!("## Memory: the peak of a process as its table grows\n");
    outln!(
        "Each command is a process of its own, its peak resident memory (VmHWM) read from \
         /proc every 10 ms while it runs (Linux only); its table goes to a temporary file.\n"
    );
    outln!("| command | count | peak memory | table | wall time |");
    outln!("| --- | ---: | ---: | ---: | ---: |");
    for (what, scene, args) in COMMANDS {
        for &count in &counts {
            let mut command = std::process::Command::new(&lagrange);
            command.current_dir(&root).arg(what).arg(scene);
            for arg in args.iter() {
                command.arg(arg.replace("{count}", &count.to_string()));
            }
            command.arg("--out").arg(&out);
            let measured = measure(command);
            let table = std::fs::metadata(&out).map(|m| m.len()).ok();
            let _ = std::fs::remove_file(&out);
            let shown = match measured {
                Ok((peak, wall)) => {
                    format!("{} | {} | {}", megabytes(peak), megabytes(table), crate::seconds(wall))
                }
                Err(e) => format!("failed: {e} | | "),
            };
            outln!("| `lagrange {what} {}` | {count} | {shown} |", scene_name(scene));
        }
    }
    outln!();
}

/// The commands measured: `{count}` stands for the samples or the runs. The ensemble's runs
/// are a simple pendulum's first tenth of a second, a handful of steps each, so that ten
/// million of them take minutes rather than hours: what a run costs does not change what it
/// keeps.
const COMMANDS: [(&str, &str, &[&str]); 2] = [
    ("simulate", "examples/classics/simple_pendulum.lag", &["--samples", "{count}"]),
    (
        "ensemble",
        "examples/classics/simple_pendulum.lag",
        &[
            "--vary",
            "L=uniform(0.5, 1.5)",
            "--runs",
            "{count}",
            "--until",
            "0.1",
            "--record",
            "theta, max(theta)",
        ],
    ),
];

/// The scene's file name, for the table.
fn scene_name(path: &str) -> &str {
    path.rsplit('/').next().unwrap_or(path)
}

/// The `lagrange` program beside this one (cargo builds both into the same folder).
fn lagrange_binary() -> Option<std::path::PathBuf> {
    let path = std::env::current_exe().ok()?.with_file_name("lagrange");
    path.exists().then_some(path)
}

/// Runs `command` to its end, its standard output and error dropped (the progress bar is
/// drawn only on a terminal): its peak resident memory, the largest VmHWM read while it ran
/// (a high-water mark: the last reading is the peak up to then), and its wall time.
fn measure(mut command: std::process::Command) -> std::io::Result<(Option<u64>, f64)> {
    use std::process::Stdio;
    let started = std::time::Instant::now();
    let mut child = command.stdout(Stdio::null()).stderr(Stdio::null()).spawn()?;
    let status = format!("/proc/{}/status", child.id());
    let mut peak = None;
    loop {
        if let Some(bytes) = high_water(&status) {
            peak = Some(peak.unwrap_or(0).max(bytes));
        }
        if let Some(exit) = child.try_wait()? {
            if !exit.success() && exit.code() != Some(1) {
                return Err(std::io::Error::other(format!("it ended with {exit}")));
            }
            return Ok((peak, started.elapsed().as_secs_f64()));
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// The VmHWM line of a process's status file, in bytes.
fn high_water(status: &str) -> Option<u64> {
    let status = fs::read_to_string(status).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 =
        line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kib * 1024)
}
