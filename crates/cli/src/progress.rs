//! A progress line on stderr for runs that last, shown only when stderr is a terminal.

use std::cell::Cell;
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Draws `t / until` as a bar, first after a second of running, then at most ten times a second.
pub struct Progress {
    until: f64,
    started: Instant,
    last: Cell<Option<Instant>>,
    enabled: bool,
}

impl Progress {
    pub fn new(until: f64) -> Self {
        Progress {
            until,
            started: Instant::now(),
            last: Cell::new(None),
            enabled: std::io::stderr().is_terminal(),
        }
    }

    pub fn update(&self, t: f64) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        if now - self.started < Duration::from_secs(1) {
            return;
        }
        if self.last.get().is_some_and(|l| now - l < Duration::from_millis(100)) {
            return;
        }
        self.last.set(Some(now));
        let fraction = (t / self.until).clamp(0.0, 1.0);
        let filled = (fraction * 30.0) as usize;
        eprint!(
            "\r[{}{}] t = {t:.4} / {}",
            "#".repeat(filled),
            " ".repeat(30 - filled),
            self.until
        );
        let _ = std::io::stderr().flush();
    }

    pub fn finish(&self) {
        if self.enabled && self.last.get().is_some() {
            eprint!("\r{}\r", " ".repeat(60));
        }
    }
}
