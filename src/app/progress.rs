//! The one progress bar of every command: drawn on stderr only when stderr is a terminal and
//! `--quiet` was not given, and only once the run has taken about a second (a quick run, a
//! test or a CI log sees nothing). It shows the step count, elapsed time, rate and time left,
//! and then the phase after the computation (rendering and writing the files).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long a run goes before its bar appears.
const SHOW_AFTER: Duration = Duration::from_secs(1);

/// A progress bar over `len` steps (configurations, frames, cases, measurements).
pub struct Progress {
    bar: ProgressBar,
    enabled: bool,
    shown: AtomicBool,
    start: Instant,
}

impl Progress {
    /// A bar counting `len` steps of `what` ("configurations", "frames", ...).
    pub(crate) fn new(quiet: bool, len: u64, what: &str) -> Self {
        let enabled = !quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {{msg}} {{pos}}/{{len}} {what} {{wide_bar}} {{elapsed}} elapsed, {{rate}}, {{eta}} left"
            ))
            .expect("valid template")
            .with_key("rate", |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = write!(w, "{:.0}/s", s.per_sec());
            }),
        );
        bar.set_message("computing");
        Progress {
            bar,
            enabled,
            shown: AtomicBool::new(false),
            start: Instant::now(),
        }
    }

    /// `n` more steps done (callable from any thread).
    pub(crate) fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.show_if_due();
    }

    /// The computation is done; the files are being rendered and written.
    pub(crate) fn writing(&self) {
        self.bar.set_message("writing files,");
        self.bar.enable_steady_tick(Duration::from_millis(100));
        self.show_if_due();
    }

    /// Prints a line on stderr without tearing the bar.
    pub(crate) fn note(&self, line: &str) {
        self.bar.suspend(|| eprintln!("{line}"));
    }

    /// Removes the bar (the command's own output follows).
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }

    fn show_if_due(&self) {
        if self.enabled && !self.shown.load(Ordering::Relaxed) && self.start.elapsed() >= SHOW_AFTER {
            // Only the first caller switches the target on.
            if !self.shown.swap(true, Ordering::Relaxed) {
                self.bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
