//! Peak resident memory of this process, from Linux's `/proc/self/status` (`VmHWM`), and a way
//! to reset the peak between measurements (writing 5 to `/proc/self/clear_refs`). Elsewhere
//! both do nothing and the figure is `None`: memory is reported where it can be read, never
//! guessed.

use std::fs;

/// Forgets the peak so far, so that the next [`peak_bytes`] is the peak of what runs between.
/// Without the reset (older kernels, other systems) the peak is that of the whole process so
/// far, which for the scaling ladder's growing sizes is still the latest size's.
pub fn reset_peak() {
    let _ = fs::write("/proc/self/clear_refs", "5");
}

/// The peak resident set size since the last reset (or since the start), in bytes.
pub fn peak_bytes() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 =
        line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kib * 1024)
}

/// Bytes as a table shows them: `18.4 MB`, or `-` when unknown.
pub fn megabytes(bytes: Option<u64>) -> String {
    match bytes {
        Some(b) => format!("{:.1} MB", b as f64 / 1e6),
        None => "-".to_string(),
    }
}
