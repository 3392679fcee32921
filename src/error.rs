//! The tools' error: the library's, and the causes only a tool meets — a window, a batch's job —
//! with the tools' own files named through [`Role::Named`]. Each prints as one line, as the
//! library's errors do. Rejected: these causes in the library, whose hosts open no window of
//! ours and run no batch.

use terrain_engine::Role;

/// `batch`'s jobs file, listing the scenes it renders.
pub const JOBS_FILE: Role = Role::Named("jobs file");
/// `batch`'s manifest, read by `--resume` and `--merge` and appended to.
pub const MANIFEST: Role = Role::Named("manifest");
/// `compare --replot`'s report.json.
pub const REPORT: Role = Role::Named("report");

/// Errors of the tools.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The library's error: a file, the GPU, a scene value.
    #[error(transparent)]
    Engine(#[from] terrain_engine::Error),
    /// No window can be opened (a window system error); `source` is winit's or softbuffer's
    /// error, kept as text.
    #[error("window: {what}: {source}")]
    Window {
        /// What was being done, e.g. "cannot open one".
        what: String,
        /// The window system's error, kept as text.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// No display to open a window on; `cause` is winit's reason in the user's terms (its
    /// source-file location dropped) with what to do about it.
    #[error("window: {cause}")]
    NoDisplay {
        /// Why no display can be opened, and what to do about it.
        cause: String,
    },
    /// One job of a batch that cannot run as the jobs file gives it.
    #[error("job {name:?}: {reason}")]
    Job {
        /// The job's name, as in the jobs file or `random-k`.
        name: String,
        /// Why it cannot run: one line (a scene error's message, or the tools' own words).
        reason: String,
    },
}

/// The tools' result: [`Error`] on failure.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// The window system refused `what`; its error is kept as text, since winit's and
    /// softbuffer's errors hold raw window handles and cannot cross threads.
    pub fn window(what: impl Into<String>, source: impl std::fmt::Display) -> Self {
        Error::Window {
            what: what.into(),
            source: source.to_string().into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tools_files_are_named_as_their_messages_name_them() {
        let e = terrain_engine::Error::file(MANIFEST, "out/manifest.jsonl", "line 3: not JSON");
        assert_eq!(
            Error::from(e).to_string(),
            "manifest out/manifest.jsonl: line 3: not JSON"
        );
    }

    #[test]
    fn a_job_s_name_stays_on_one_line() {
        let e = Error::Job {
            name: "a\nb".into(),
            reason: "no such key".into(),
        };
        assert_eq!(e.to_string(), r#"job "a\nb": no such key"#);
    }
}
