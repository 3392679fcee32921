//! Progress of long work on stderr (`compare`, `fly`, `batch`, big renders, image encoding,
//! reading a large sketch): a bar with items done of the total, the current item, elapsed time and
//! an estimate of the time left; or, for one long step, a spinner with its elapsed time.
//!
//! Rules: on a terminal indicatif redraws one line in place. Elsewhere (a log file, CI) indicatif
//! draws nothing, so a plain line is printed at most every `LOG_EVERY` and at the end, and logs
//! stay short. Items of unequal cost advance the bar by their `work`, so the estimate (indicatif's,
//! from the rate of work done) weighs a 1024² setting of `compare` above a 256² one.
//! `TERRAIN_QUIET` silences both (the tests set it). [`Bars`] shows the library's progress
//! ([`terrain_engine::progress`]) the same way; the binary installs it.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

const LOG_EVERY: Duration = Duration::from_secs(5);
/// Work is counted in thousandths, so fractional work (weights) keeps its precision in
/// indicatif's integer positions.
const UNITS: f64 = 1000.0;

pub struct Progress {
    label: String,
    total: f64,
    done: f64,
    items: usize,
    start: Instant,
    last_log: Option<Instant>,
    bar: Option<ProgressBar>,
    quiet: bool,
}

fn quiet() -> bool {
    std::env::var_os("TERRAIN_QUIET").is_some()
}

impl Progress {
    /// `total`: the work of all items (their count when they cost alike).
    pub fn new(label: &str, total: f64) -> Progress {
        let total = total.max(f64::MIN_POSITIVE);
        let quiet = quiet();
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::with_draw_target(
                Some((total * UNITS).ceil() as u64),
                ProgressDrawTarget::stderr(),
            );
            let style = ProgressStyle::with_template(
                "{prefix} [{bar:24}] {percent:>3} % ({elapsed}, ~{eta} left) {msg}",
            )
            .expect("a valid template")
            .progress_chars("#>-");
            bar.set_style(style);
            bar.set_prefix(label.to_string());
            bar
        });
        Progress {
            label: label.to_string(),
            total,
            done: 0.0,
            items: 0,
            start: Instant::now(),
            last_log: None,
            bar,
            quiet,
        }
    }

    /// Marks `work` more done, `item` the one just finished.
    pub fn advance(&mut self, work: f64, item: &str) {
        self.done = (self.done + work).min(self.total);
        self.items += 1;
        if let Some(bar) = &self.bar {
            bar.set_message(item.to_string());
            bar.set_position((self.done * UNITS).round() as u64);
            return;
        }
        let now = Instant::now();
        let finished = self.done >= self.total;
        if self.quiet || (!finished && self.last_log.is_some_and(|t| now - t < LOG_EVERY)) {
            return;
        }
        self.last_log = Some(now);
        let line = self.line(item, now - self.start);
        let _ = writeln!(std::io::stderr().lock(), "{line}");
    }

    /// Takes `work` off the total: items counted in it that turned out not to be needed.
    pub fn forgo(&mut self, work: f64) {
        self.total = (self.total - work).max(self.done).max(f64::MIN_POSITIVE);
        if let Some(bar) = &self.bar {
            bar.set_length((self.total * UNITS).ceil() as u64);
        }
    }

    /// The line a log gets (what the bar shows on a terminal).
    fn line(&self, item: &str, elapsed: Duration) -> String {
        let fraction = self.done / self.total;
        let left = if self.done > 0.0 {
            let rest = elapsed.as_secs_f64() * (self.total - self.done) / self.done;
            format!(", ~{} left", clock(rest))
        } else {
            String::new()
        };
        format!(
            "{} {:>3.0} % ({} done, {}{left}) {item}",
            self.label,
            100.0 * fraction,
            self.items,
            clock(elapsed.as_secs_f64()),
        )
    }

    /// Ends the bar, leaving its last state on the terminal.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }

    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }
}

/// One long step without countable parts (a GPU frame of hundreds of megapixels, reading a large
/// sketch): a spinner with the elapsed time on a terminal; in a log, one line when it took long.
pub struct Spinner {
    label: String,
    start: Instant,
    bar: Option<ProgressBar>,
    quiet: bool,
}

/// Steps shorter than this leave no line in a log.
const LOG_SLOWER_THAN: Duration = Duration::from_secs(2);

impl Spinner {
    pub fn new(label: &str) -> Spinner {
        let quiet = quiet();
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::new_spinner();
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                    .expect("a valid template"),
            );
            bar.set_message(label.to_string());
            bar.enable_steady_tick(Duration::from_millis(120));
            bar
        });
        Spinner {
            label: label.to_string(),
            start: Instant::now(),
            bar,
            quiet,
        }
    }

    /// Ends the step: the spinner is cleared; a log gets one line if it took long.
    pub fn finish(self) {
        let took = self.start.elapsed();
        match &self.bar {
            Some(bar) => bar.finish_and_clear(),
            None if !self.quiet && took >= LOG_SLOWER_THAN => {
                eprintln!("{} in {}", self.label, clock(took.as_secs_f64()));
            }
            None => {}
        }
    }
}

/// The library's progress as bars (work with a total) and spinners (one long step).
pub struct Bars;

impl terrain_engine::progress::Progress for Bars {
    fn start(&self, what: &str, total: Option<f64>) -> Box<dyn terrain_engine::progress::Task> {
        match total {
            Some(total) => Box::new(Progress::new(what, total)),
            None => Box::new(Spinner::new(what)),
        }
    }
}

impl terrain_engine::progress::Task for Progress {
    fn advance(&mut self, work: f64, item: &str) {
        Progress::advance(self, work, item);
    }

    fn finish(self: Box<Self>) {
        Progress::finish(&self);
    }
}

impl terrain_engine::progress::Task for Spinner {
    fn finish(self: Box<Self>) {
        Spinner::finish(*self);
    }
}

/// `1h02m`, `3m07s`, `12.4s`.
pub fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0);
    if s >= 3600.0 {
        format!(
            "{}h{:02}m",
            (s / 3600.0) as u64,
            ((s % 3600.0) / 60.0) as u64
        )
    } else if s >= 60.0 {
        format!("{}m{:02}s", (s / 60.0) as u64, (s % 60.0) as u64)
    } else {
        format!("{s:.1}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimate_scales_with_work_left() {
        let mut p = Progress::new("test", 4.0);
        p.bar = None;
        p.quiet = true;
        p.advance(1.0, "a");
        let line = p.line("a", Duration::from_secs(10));
        assert!(
            line.contains("25 %") && line.contains("~30.0s left"),
            "{line}"
        );
        assert_eq!(clock(3725.0), "1h02m");
        assert_eq!(clock(187.0), "3m07s");
    }
}
