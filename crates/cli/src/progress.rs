//! A progress line on stderr for runs that last, shown only when stderr is a terminal: the
//! time a run has reached, or how many of an ensemble's runs are done.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

/// Draws `t / until` as a bar, first after a second of running, then at most ten times a second.
pub struct Bar {
    until: f64,
    started: Instant,
    last: Option<Instant>,
    enabled: bool,
    /// Counting an ensemble's runs rather than a run's time.
    runs: bool,
}

impl Bar {
    pub fn new() -> Self {
        Bar {
            until: 1.0,
            started: Instant::now(),
            last: None,
            enabled: std::io::stderr().is_terminal(),
            runs: false,
        }
    }

    /// A bar of an ensemble's runs: its `t` is the number done, its `until` the number in all.
    pub fn runs() -> Self {
        Bar { runs: true, ..Bar::new() }
    }
}

impl Default for Bar {
    fn default() -> Self {
        Bar::new()
    }
}

impl simulation::Progress for Bar {
    fn start(&mut self, until: f64) {
        self.until = until;
        self.started = Instant::now();
        self.last = None;
    }

    fn update(&mut self, t: f64) {
        if !self.enabled {
            return;
        }
        let now = Instant::now();
        if now - self.started < Duration::from_secs(1) {
            return;
        }
        if self.last.is_some_and(|l| now - l < Duration::from_millis(100)) {
            return;
        }
        self.last = Some(now);
        let fraction = (t / self.until).clamp(0.0, 1.0);
        let filled = (fraction * 30.0) as usize;
        let bar = format!("[{}{}]", "#".repeat(filled), " ".repeat(30 - filled));
        if self.runs {
            eprint!("\r{bar} {t} / {} runs", self.until);
        } else {
            eprint!("\r{bar} t = {t:.4} / {}", self.until);
        }
        let _ = std::io::stderr().flush();
    }

    fn finish(&mut self) {
        if self.enabled && self.last.is_some() {
            eprint!("\r{}\r", " ".repeat(60));
        }
    }
}
