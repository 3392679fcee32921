//! Progress of long runs (`compare`, `fly`, `batch`) on stderr: items done of the total, the
//! current item, elapsed time and an estimate of the time left.
//!
//! Rules: on a terminal one line is redrawn in place; otherwise (a log file, CI) a line is printed
//! at most every `LOG_EVERY` and at the end, so logs stay short. The estimate is the mean time per
//! finished item times the items left, weighted by `work` when items differ in cost.
//!
//! Rejected alternative: a progress-bar crate (indicatif). It brings a terminal-handling stack for
//! one line of text, and its estimate assumes items of equal cost.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

const LOG_EVERY: Duration = Duration::from_secs(5);

pub struct Progress {
    label: String,
    total: f64,
    done: f64,
    items: usize,
    start: Instant,
    last_log: Option<Instant>,
    tty: bool,
    quiet: bool,
}

impl Progress {
    /// `total`: the work of all items (their count when they cost alike).
    pub fn new(label: &str, total: f64) -> Progress {
        Progress {
            label: label.to_string(),
            total: total.max(f64::MIN_POSITIVE),
            done: 0.0,
            items: 0,
            start: Instant::now(),
            last_log: None,
            tty: std::io::stderr().is_terminal(),
            quiet: std::env::var_os("TERRAIN_QUIET").is_some(),
        }
    }

    /// Marks `work` more done, `item` the one just finished.
    pub fn advance(&mut self, work: f64, item: &str) {
        self.done = (self.done + work).min(self.total);
        self.items += 1;
        let now = Instant::now();
        let finished = self.done >= self.total;
        if self.quiet
            || (!self.tty && !finished && self.last_log.is_some_and(|t| now - t < LOG_EVERY))
        {
            return;
        }
        self.last_log = Some(now);
        let line = self.line(item, now - self.start);
        let mut err = std::io::stderr().lock();
        let _ = if self.tty {
            write!(err, "\r\x1b[2K{line}")
        } else {
            writeln!(err, "{line}")
        };
        let _ = err.flush();
    }

    fn line(&self, item: &str, elapsed: Duration) -> String {
        let fraction = self.done / self.total;
        let width = 24;
        let filled = (fraction * width as f64).round() as usize;
        let bar: String = "#".repeat(filled) + &"-".repeat(width - filled.min(width));
        let left = if self.done > 0.0 {
            let rest = elapsed.as_secs_f64() * (self.total - self.done) / self.done;
            format!(", ~{} left", clock(rest))
        } else {
            String::new()
        };
        format!(
            "{} [{bar}] {:>3.0} % ({} done, {}{left}) {item}",
            self.label,
            100.0 * fraction,
            self.items,
            clock(elapsed.as_secs_f64()),
        )
    }

    /// Ends the redrawn line (on a terminal) so later messages start on their own.
    pub fn finish(&self) {
        if self.tty && !self.quiet {
            eprintln!();
        }
    }

    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
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
        p.tty = false;
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
