//! What a long benchmark is doing, on stderr while it runs: drawn by indicatif when stderr is a
//! terminal, and nothing at all otherwise, so that a redirect or a pipe gets the tables alone.
//!
//! The `lagrange` command draws its own bar (`cli::progress`); this one cannot be shared with
//! it, since `bench` may not depend on `cli`, and `engine`, which both use, prints nothing.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A line naming the work under way, with its elapsed time; for an integration (through
/// [`simulation::Progress`]) also a bar of t against the end time and a count of runs.
/// It clears itself when dropped, before the caller prints the row it measured.
pub struct Bar {
    bar: ProgressBar,
    work: String,
    runs: usize,
    until: f64,
}

impl Bar {
    /// A line for `work` on stderr, drawn only when stderr is a terminal.
    pub fn new(work: impl Into<String>) -> Self {
        let target = if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr_with_hz(10)
        } else {
            ProgressDrawTarget::hidden()
        };
        Self::to(target, work.into())
    }

    fn to(target: ProgressDrawTarget, work: String) -> Self {
        let bar = ProgressBar::with_draw_target(None, target);
        bar.set_style(style("{spinner} {msg} [{elapsed}]"));
        bar.set_message(work.clone());
        // A derivation reports nothing while it runs: the spinner shows it is alive. The
        // ticking thread wakes ten times a second, and only when the line is drawn at all.
        if !bar.is_hidden() {
            bar.enable_steady_tick(Duration::from_millis(100));
        }
        Bar { bar, work, runs: 0, until: 1.0 }
    }
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_spinner())
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// Steps of t in an integration's bar: fine enough to move smoothly, coarse enough to be an
/// integer.
const STEPS: u64 = 1000;

impl simulation::Progress for Bar {
    fn start(&mut self, until: f64) {
        self.runs += 1;
        self.until = until;
        if self.runs == 1 {
            self.bar.set_style(style("{spinner} {msg} [{elapsed}] {wide_bar} {percent:>3}%"));
        }
        self.bar.set_length(STEPS);
        self.bar.set_position(0);
        self.bar.set_message(format!("{}, run {}", self.work, self.runs));
    }

    fn update(&mut self, t: f64) {
        let fraction = if self.until > 0.0 { (t / self.until).clamp(0.0, 1.0) } else { 0.0 };
        // NaN clamps to NaN, and `as` takes NaN to 0: a faulty time draws an empty bar.
        self.bar.set_position((fraction * STEPS as f64) as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use simulation::Progress;
    use std::io;
    use std::sync::{Arc, Mutex};

    /// A terminal that keeps what is written to it.
    #[derive(Clone, Debug, Default)]
    struct Screen(Arc<Mutex<String>>);

    impl Screen {
        fn text(&self) -> String {
            self.0.lock().map(|s| s.clone()).unwrap_or_default()
        }
        fn put(&self, s: &str) -> io::Result<()> {
            self.0.lock().map_err(|_| io::Error::other("poisoned"))?.push_str(s);
            Ok(())
        }
    }

    impl indicatif::TermLike for Screen {
        fn width(&self) -> u16 {
            80
        }
        fn move_cursor_up(&self, _: usize) -> io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> io::Result<()> {
            self.put(s)?;
            self.put("\n")
        }
        fn write_str(&self, s: &str) -> io::Result<()> {
            self.put(s)
        }
        fn clear_line(&self) -> io::Result<()> {
            self.put("<clear>")
        }
        fn flush(&self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_terminal_sees_the_work_and_the_runs_of_an_integration() {
        let screen = Screen::default();
        let target = ProgressDrawTarget::term_like_with_hz(Box::new(screen.clone()), 1);
        let mut bar = Bar::to(target, "work–precision: a pendulum".into());
        bar.start(10.0);
        bar.update(5.0);
        bar.bar.tick();
        let text = screen.text();
        assert!(text.contains("work–precision: a pendulum, run 1"), "{text:?}");
        drop(bar);
        assert!(screen.text().ends_with("<clear>"), "{:?}", screen.text());
    }
}
