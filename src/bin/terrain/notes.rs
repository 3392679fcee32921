//! The library's notes and warnings (it reports them through the `log` crate and prints nothing)
//! on stderr, one `note:` or `warning:` line each, as the binary's own warnings read.
//!
//! Rules:
//! - Only `terrain`'s records: wgpu and naga log through the same crate, for whoever debugs them,
//!   not for a user's terminal.
//! - `TERRAIN_QUIET` silences the notes, as it silences progress; warnings and errors stay.
//! - A warning is printed once per command ([`warning`]): the library says what it doubts each
//!   time it reads a sketch, and a command that reads it for every mode or job would repeat it.
//!
//! Rejected alternative: env_logger. Its filter reads `RUST_LOG`, which would let wgpu's records
//! onto the terminal, and its format needs a closure per level to print these two prefixes: the
//! twenty lines here.

use log::{Level, LevelFilter, Log, Metadata, Record};
use std::collections::BTreeSet;
use std::sync::Mutex;

struct Notes;

static NOTES: Notes = Notes;

impl Log for Notes {
    fn enabled(&self, metadata: &Metadata) -> bool {
        let target = metadata.target();
        target == "terrain" || target.starts_with("terrain_engine::")
    }

    fn log(&self, record: &Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let prefix = match record.level() {
            Level::Error => "error",
            Level::Warn => return warning(&record.args().to_string()),
            Level::Info | Level::Debug | Level::Trace => "note",
        };
        eprintln!("{prefix}: {}", record.args());
    }

    fn flush(&self) {}
}

/// Prints `line` as a `warning:` line on stderr unless this command printed it already.
pub fn warning(line: &str) {
    static SAID: Mutex<BTreeSet<String>> = Mutex::new(BTreeSet::new());
    // A poisoned set still holds what was said: a panic elsewhere must not silence warnings.
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if said.insert(line.to_string()) {
        eprintln!("warning: {line}");
    }
}

/// Installs the logger, at the level `TERRAIN_QUIET` allows.
pub fn install() {
    if log::set_logger(&NOTES).is_ok() {
        let quiet = std::env::var_os("TERRAIN_QUIET").is_some();
        log::set_max_level(if quiet {
            LevelFilter::Warn
        } else {
            LevelFilter::Info
        });
    }
}
