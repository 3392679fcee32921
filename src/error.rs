//! The library's error type: one variant per kind of cause, each printing as one line that names it.
//!
//! The binary prints `Display` and exits non-zero; nothing a user gives the program may panic instead.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A sketch (height map) file that is truncated, corrupt or inconsistent.
    #[error("{path}: {reason}")]
    Sketch { path: PathBuf, reason: String },
    /// A scene or jobs file: a TOML syntax error, an unknown key, a value out of range.
    #[error("scene {path}: {reason}")]
    Scene { path: PathBuf, reason: String },
    /// A camera that cannot be built (NaN, eye at its own target, zero-size image).
    #[error("camera: {0}")]
    Camera(String),
    /// No adapter, a limit the adapter lacks, a lost device.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A value that cannot be used (synthetic name, empty grid).
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
    pub fn sketch(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::Sketch {
            path: path.into(),
            reason: reason.into(),
        }
    }
}
