//! Progress of the library's long work (reading a large sketch, converting a sketch into tiles,
//! measuring GeoMipMap's blocks over a pyramid), reported to whatever the program installed.
//!
//! Rules:
//! - The library reports and never shows: without a reporter ([`set_reporter`]) every report is
//!   dropped, so a program that installs none sees nothing on its terminal. The `terrain` binary
//!   installs one that draws indicatif bars and spinners (`terrain_cli::progress`).
//! - One reporter for the process, installed once, like `log`'s logger: the work that reports
//!   runs deep under calls that take a scene (a renderer's GeoMipMap over a pyramid, a scene's
//!   sketch), and each [`Task`] is its own handle, so work on several threads never mixes.
//!
//! Rejected alternative: a `&dyn Progress` argument on every call that may reach long work. It
//! would run through `Renderer::new`, every scene loader and their callers, for what is a choice
//! of the program's, not of each call.

use std::sync::OnceLock;

/// What a program shows of the library's long work.
pub trait Progress: Send + Sync {
    /// Work named `what` begins: `total` units of it (items, or their weights), or `None` for one
    /// long step without countable parts.
    fn start(&self, what: &str, total: Option<f64>) -> Box<dyn Task>;
}

/// One piece of work under way.
pub trait Task: Send {
    /// `work` more units are done, `item` the one just finished.
    fn advance(&mut self, _work: f64, _item: &str) {}
    /// The work is over.
    fn finish(self: Box<Self>) {}
}

static REPORTER: OnceLock<Box<dyn Progress>> = OnceLock::new();

/// Installs the process's reporter; `false` (and `reporter` dropped) when one is installed
/// already.
pub fn set_reporter(reporter: Box<dyn Progress>) -> bool {
    REPORTER.set(reporter).is_ok()
}

/// Starts reporting work: a [`Work`] that does nothing when no reporter is installed.
pub fn start(what: &str, total: Option<f64>) -> Work {
    Work(REPORTER.get().map(|r| r.start(what, total)))
}

/// Reported work; finished when dropped.
pub struct Work(Option<Box<dyn Task>>);

impl Work {
    /// `work` more units are done, `item` the one just finished.
    pub fn advance(&mut self, work: f64, item: &str) {
        if let Some(t) = &mut self.0 {
            t.advance(work, item);
        }
    }

    /// The work is over (as dropping it says).
    pub fn finish(self) {}
}

impl Drop for Work {
    fn drop(&mut self) {
        if let Some(t) = self.0.take() {
            t.finish();
        }
    }
}
