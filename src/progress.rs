//! Progress bars of the command line: on a terminal only, never in CI logs.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Whether a bar may be drawn: stderr is a terminal and this is not CI.
fn on_terminal() -> bool {
    std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

/// Shows a progress bar on a terminal once a run has taken a while.
pub(crate) struct Progress {
    bar: Option<indicatif::ProgressBar>,
    enabled: bool,
    start: Instant,
    stop: f64,
}

impl Progress {
    pub(crate) fn new(stop: f64) -> Self {
        Progress { bar: None, enabled: on_terminal(), start: Instant::now(), stop }
    }

    pub(crate) fn tick(&mut self, t: f64) {
        if !self.enabled {
            return;
        }
        if self.bar.is_none() && self.start.elapsed() > Duration::from_secs(2) {
            let bar = indicatif::ProgressBar::new(1000);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% {msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_position((1000.0 * t / self.stop) as u64);
            // The remaining simulated time at the rate so far (indicatif's
            // own estimate follows recent ticks and jumps with step size).
            let wall = self.start.elapsed().as_secs_f64();
            let eta = if t > 0.0 { (self.stop - t) * wall / t } else { f64::NAN };
            bar.set_message(format!("t = {t:.4} s, eta {eta:.0} s"));
        }
    }

    pub(crate) fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// A progress bar over the cases of a sweep, on a terminal only.
pub(crate) struct CaseProgress(Option<indicatif::ProgressBar>);

impl CaseProgress {
    pub(crate) fn new(cases: usize) -> Self {
        CaseProgress(on_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(cases as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} cases, eta {eta}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        }))
    }
    /// One more case done (past the planned count, e.g. shrinking, the
    /// bar grows).
    pub(crate) fn tick(&self) {
        if let Some(b) = &self.0 {
            if b.position() >= b.length().unwrap_or(0) {
                b.inc_length(1);
            }
            b.inc(1);
        }
    }
    pub(crate) fn finish(&self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}
