//! The library's error type: one variant per kind of cause, each printing as one line that names
//! the cause and, for a file, the role the file plays (scene, sketch, output, …), so
//! "No such file or directory" always says which file the user got wrong.
//!
//! The binary prints `Display` and exits non-zero; nothing a user gives the program may panic instead.

use std::fmt;
use std::path::PathBuf;

/// What a file is to the command that reads or writes it; the first words of its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The scene file (TOML) that describes what to draw.
    Scene,
    /// The height map, `sketch.path`: a DEM file, a glob of tiles or a tile pyramid's folder.
    Sketch,
    /// `importance.max_map`: a sketch-format map of I_s.
    ImportanceMap,
    /// A file the command writes (image, figure, report, animation).
    Output,
    /// The folder a command writes into.
    OutputFolder,
    /// `surface.color_ramp`: a colour ramp in gdaldem `color-relief`'s text format.
    ColorRamp,
    /// `surface.image`: imagery draped over the ground.
    Image,
    /// A file of the host's own (a batch's jobs file, a report), named as its messages name it.
    Named(&'static str),
}

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Role::Scene => "scene",
            Role::Sketch => "sketch",
            Role::ImportanceMap => "importance map",
            Role::Output => "output",
            Role::OutputFolder => "output folder",
            Role::ColorRamp => "colour ramp",
            Role::Image => "surface image",
            Role::Named(name) => name,
        })
    }
}

/// Errors of the library. New causes may be added: match with a wildcard arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The operating system refused a file: missing, unreadable, a full disk.
    #[error("{role} {}: {}", Line(&path.display()), Line(source))]
    Io {
        /// What the file is to the command.
        role: Role,
        /// The file, as the user or the scene named it.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A file that is truncated, corrupt, inconsistent or, for a scene or jobs file, has a bad
    /// key; `reason` names the key.
    #[error("{role} {}: {}", Line(&path.display()), Line(reason))]
    File {
        /// What the file is to the command.
        role: Role,
        /// The file, as the user or the scene named it.
        path: PathBuf,
        /// What is wrong with it, one line, naming the key or the place in the file.
        reason: String,
    },
    /// A file whose decoder refused it; `what` says what the file was taken for ("a readable
    /// TIFF"), `source` is the decoder's error (tiff, png, toml).
    #[error("{role} {}: {what}: {}", Line(&path.display()), Line(source))]
    Decode {
        /// What the file is to the command.
        role: Role,
        /// The file, as the user or the scene named it.
        path: PathBuf,
        /// What the file was taken for, e.g. "a readable TIFF".
        what: &'static str,
        /// The decoder's own error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A `--set key=value` override that is not a key, or whose value is out of range.
    #[error("--set {}: {}", Line(arg), Line(reason))]
    Override {
        /// The override as given, `key.path=value`.
        arg: String,
        /// Why it was refused: no such key, a value of the wrong type or out of range.
        reason: String,
    },
    /// A camera that cannot be built (NaN, eye at its own target, zero-size image).
    #[error("camera: {0}")]
    Camera(String),
    /// A host's view that does not fit the prepared frame: another size than the prepared
    /// camera's image, or another sample count than the terrain's targets.
    #[error("target: the {view} view is {got}, the prepared frame is {expected}")]
    Target {
        /// Which view: "colour" or "depth".
        view: &'static str,
        /// What the prepared frame needs, e.g. "640×360, 1 sample".
        expected: String,
        /// What the view is.
        got: String,
    },
    /// A limit of the adapter below what a scene needs; `limit` is wgpu's name for it.
    #[error(
        "GPU: {what} needs {needed}{unit} of `{limit}`, the adapter allows {allowed}{unit}{advice}"
    )]
    Limit {
        /// What needs the limit ("a 1025² baked grid"; the adapter's name where a device is checked).
        what: String,
        /// wgpu's name for the limit, a field of `wgpu::Limits` (`max_buffer_size`).
        limit: &'static str,
        /// The value the scene needs, in `unit`.
        needed: u64,
        /// The value the adapter allows, in `unit`.
        allowed: u64,
        /// The unit of `needed` and `allowed` as printed (" MiB", or "" for a count).
        unit: &'static str,
        /// What the user can do about it, starting with "; ", or empty.
        advice: &'static str,
    },
    /// The graphics API refused: no adapter, no device, a lost device, a failed read-back;
    /// `what` says what was being done, `source` is wgpu's error.
    #[error("GPU: {what}: {source}")]
    Device {
        /// What was being done, e.g. "readback mapping".
        what: String,
        /// wgpu's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A scene value that cannot be used although it parsed (a synthetic sketch's name, a camera
    /// path whose keys coincide); `key` names it as the scene file spells it.
    #[error("{key}: {}", Line(reason))]
    Value {
        /// The key, dotted as the scene file spells it (`camera.position`).
        key: &'static str,
        /// Why its value cannot be used.
        reason: String,
    },
    /// A height query at a point or along a ray that cannot be answered (not finite).
    #[error("height query: {}", Line(.0))]
    Query(String),
    /// A report, manifest line or scene that serde could not encode.
    #[error("cannot encode the {what}: {source}")]
    Encode {
        /// What was being encoded, e.g. "manifest line".
        what: &'static str,
        /// serde's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A shader source the preprocessor cannot expand (a defect of the program, not of input).
    #[error("shader {file}.wgsl: {reason}")]
    Shader {
        /// The shader's file name under `shaders/`, without `.wgsl`.
        file: String,
        /// What the preprocessor could not expand.
        reason: String,
    },
    /// Something this build of the library leaves out: a cargo feature turned off (zstd, which
    /// is C, for a WebAssembly build).
    #[error("{what} needs the terrain library's `{feature}` feature, which this build leaves out")]
    Feature {
        /// What was asked for, e.g. "a tile pyramid's tile".
        what: &'static str,
        /// The cargo feature that brings it.
        feature: &'static str,
    },
    /// A library call its own callers should never make (a defect of the program, not of input).
    #[error("internal: {0}")]
    Internal(&'static str),
}

/// The library's result: [`Error`] on failure.
pub type Result<T> = std::result::Result<T, Error>;

/// Shows a value on one line: control characters (a newline in a file name, in an XML parser's
/// quote of the file) are written as escapes, so every error is exactly one line.
struct Line<'a, T: fmt::Display + ?Sized>(&'a T);

impl<T: fmt::Display + ?Sized> fmt::Display for Line<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        struct Escape<'a, 'b>(&'a mut fmt::Formatter<'b>);
        impl fmt::Write for Escape<'_, '_> {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                for c in s.chars() {
                    match c {
                        c if c.is_control() => write!(self.0, "{}", c.escape_default())?,
                        c => fmt::Write::write_char(self.0, c)?,
                    }
                }
                Ok(())
            }
        }
        fmt::Write::write_fmt(&mut Escape(f), format_args!("{}", self.0))
    }
}

impl Error {
    /// The operating system refused the `role` file at `path` with `source`.
    pub fn io(role: Role, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            role,
            path: path.into(),
            source,
        }
    }
    /// The `role` file at `path` is wrong as `reason` says.
    pub fn file(role: Role, path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::File {
            role,
            path: path.into(),
            reason: reason.into(),
        }
    }
    /// `source`, the decoder of a `role` file, refused it as `what`.
    pub fn decode(
        role: Role,
        path: impl Into<PathBuf>,
        what: &'static str,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Error::Decode {
            role,
            path: path.into(),
            what,
            source: Box::new(source),
        }
    }
    /// The graphics API's `source` refused `what`.
    pub fn device(
        what: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Error::Device {
            what: what.into(),
            source: Box::new(source),
        }
    }
    /// The sketch at `path` is wrong as `reason` says.
    pub fn sketch(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::file(Role::Sketch, path, reason)
    }
    /// The scene file at `path` is wrong as `reason` says.
    pub fn scene(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::file(Role::Scene, path, reason)
    }
    /// The scene's value at `key` cannot be used, as `reason` says.
    pub fn value(key: &'static str, reason: impl Into<String>) -> Self {
        Error::Value {
            key,
            reason: reason.into(),
        }
    }
    /// serde's `source` could not encode `what`.
    pub fn encode(
        what: &'static str,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Error::Encode {
            what,
            source: Box::new(source),
        }
    }

    /// The same error with its file in another role (a sketch reader's error about the file that
    /// is, to this command, the importance map).
    pub fn in_role(self, new: Role) -> Self {
        match self {
            Error::Io { path, source, .. } => Error::Io {
                role: new,
                path,
                source,
            },
            Error::File { path, reason, .. } => Error::File {
                role: new,
                path,
                reason,
            },
            Error::Decode {
                path, what, source, ..
            } => Error::Decode {
                role: new,
                path,
                what,
                source,
            },
            e => e,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_error_names_its_role_and_cause_once() {
        let e = Error::io(
            Role::Output,
            "out/x.png",
            std::io::Error::from(std::io::ErrorKind::NotFound),
        );
        assert_eq!(e.to_string(), "output out/x.png: entity not found");
        let e = Error::sketch("a.asc", "truncated").in_role(Role::ImportanceMap);
        assert_eq!(e.to_string(), "importance map a.asc: truncated");
    }

    #[test]
    fn control_characters_in_a_path_or_cause_stay_on_one_line() {
        let e = Error::sketch("tiles\n/a.tif", "expected '>' not '\n' at 1:2\r");
        assert_eq!(
            e.to_string(),
            "sketch tiles\\n/a.tif: expected '>' not '\\n' at 1:2\\r"
        );
    }
}
