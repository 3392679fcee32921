//! Reading a scene: TOML to [`Scene`] with every fault named by its dotted key (and line, where
//! the parser knows it), `--set` overrides applied to the table first and blamed for their own
//! faults, then [`Scene::check`]'s ranges.

use super::Scene;
use crate::error::{Error, Result, Role};
use std::path::{Path, PathBuf};

/// Where a scene's fault lies: in its text, or in a `--set` override given with it.
#[derive(Clone, Debug, PartialEq)]
pub enum Fault {
    /// In the scene's text; the reason names the key (and the line, where the parser knows it).
    Text(String),
    /// In the override `arg` (`key.path=value`).
    Override {
        /// The override as given, `key.path=value`.
        arg: String,
        /// Why it was refused: no such key, a value of the wrong type or out of range.
        reason: String,
    },
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Text(reason) => f.write_str(reason),
            Fault::Override { arg, reason } => write!(f, "--set {arg}: {reason}"),
        }
    }
}

impl Fault {
    /// The error of a scene read from `path`.
    pub fn into_error(self, path: &Path) -> Error {
        match self {
            Fault::Text(reason) => Error::scene(path, reason),
            Fault::Override { arg, reason } => Error::Override { arg, reason },
        }
    }
}

impl Scene {
    /// Reads and checks the scene file at `path`, its relative paths taken from its folder; a
    /// sketch's path stands for a scene of every default ([`is_sketch_path`]).
    ///
    /// ```
    /// use terrain::Scene;
    /// use std::path::Path;
    ///
    /// // Doc tests run in crates/terrain; the bundled scenes lie at the workspace's root.
    /// let scene = Scene::load(Path::new("../../sketches/jacksboro.toml"))?;
    /// assert!(scene.sketch.path.is_some());
    /// let missing = Scene::load(Path::new("no-such.toml")).unwrap_err();
    /// assert!(missing.to_string().starts_with("scene no-such.toml"));
    /// # Ok::<(), terrain::Error>(())
    /// ```
    pub fn load(path: &Path) -> Result<Scene> {
        Scene::load_with(path, &[])
    }

    /// Parses and checks a scene; the error is one line naming the key.
    pub fn parse(text: &str, base_dir: PathBuf) -> std::result::Result<Scene, Fault> {
        Scene::parse_with(text, base_dir, &[])
    }

    /// Like [`Scene::load`], with `key.path=value` overrides (TOML values; bare words are strings)
    /// applied before the scene is checked, as `--set` gives them.
    ///
    /// `path` may name a sketch instead of a scene file ([`is_sketch_path`]): it is then read as
    /// a scene with every default.
    pub fn load_with(path: &Path, overrides: &[String]) -> Result<Scene> {
        let (text, base) = scene_text(path)?;
        let mut scene =
            Scene::parse_with(&text, base, overrides).map_err(|f| f.into_error(path))?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Like [`Scene::parse`], with `key.path=value` overrides applied before the scene is
    /// checked; a fault an override causes is blamed on it ([`Fault::Override`]).
    pub fn parse_with(
        text: &str,
        base_dir: PathBuf,
        overrides: &[String],
    ) -> std::result::Result<Scene, Fault> {
        let mut scene = if overrides.is_empty() {
            deserialize_text(text).map_err(Fault::Text)?
        } else {
            let mut table: toml::Table = toml::from_str(text)
                .map_err(|e| Fault::Text(one_line(e.message(), e.span(), text)))?;
            // `--set camera.position=…` is a camera of its own, not keys mixed into the file's.
            let camera_keys: Vec<&str> = overrides
                .iter()
                .filter_map(|o| o.split_once('=')?.0.trim().strip_prefix("camera."))
                .collect();
            if let Some(toml::Value::Table(camera)) = table.get_mut("camera") {
                super::camera::lay_camera(camera, &camera_keys);
            }
            for o in overrides {
                apply_override(&mut table, o).map_err(|reason| Fault::Override {
                    arg: o.clone(),
                    reason,
                })?;
            }
            match serde_path_to_error::deserialize::<_, Scene>(toml::Value::Table(table)) {
                Ok(scene) => scene,
                Err(e) => {
                    let key = e.path().to_string();
                    let message = e.inner().message().replace('\n', " ");
                    return Err(match overrides.iter().find(|o| blames(o, &key, &message)) {
                        Some(o) => Fault::Override {
                            arg: o.clone(),
                            reason: message,
                        },
                        // The file's own fault, with its line where the file alone shows it.
                        None => Fault::Text(
                            deserialize_text(text)
                                .err()
                                .unwrap_or_else(|| keyed(&key, &message)),
                        ),
                    });
                }
            }
        };
        scene.base_dir = base_dir;
        scene.rebase_overridden_paths(overrides);
        scene.check().map_err(|reason| {
            match overrides
                .iter()
                .find(|o| reason.starts_with(override_key(o)))
            {
                Some(o) => Fault::Override {
                    arg: o.clone(),
                    // The argument names the key and value already.
                    reason: reason
                        .split_once(": ")
                        .map_or(reason.clone(), |(_, r)| r.to_string()),
                },
                None => Fault::Text(reason),
            }
        })?;
        // A planet draws with clipmaps: the default mode, warped, cannot draw one.
        if scene.planet().is_some() && scene.render.mode == super::Mode::Warped {
            scene.render.mode = super::Mode::Clipmaps;
        }
        Ok(scene)
    }
}

impl Scene {
    /// This scene with each dotted key set to its value, as `compare`'s settings give them
    /// ([`ModeRow::sweep`](super::ModeRow::sweep)): a flag as 0 or 1, a whole number where the key
    /// holds one. The result is checked as a loaded scene is; an error names the key.
    pub fn with_values(&self, values: &[(&'static str, f64)]) -> Result<Scene> {
        let first = values.first().map_or("", |v| v.0);
        let mut table =
            toml::Table::try_from(self).map_err(|e| Error::value(first, e.to_string()))?;
        for &(key, value) in values {
            set_number(&mut table, key, value).map_err(|reason| Error::value(key, reason))?;
        }
        let mut scene: Scene = toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| Error::value(first, e.message().replace('\n', " ")))?;
        scene.base_dir = self.base_dir.clone();
        scene.source = self.source.clone();
        scene.check().map_err(|reason| {
            let key = values
                .iter()
                .find(|(k, _)| reason.starts_with(k))
                .map_or(first, |v| v.0);
            Error::value(key, reason)
        })?;
        Ok(scene)
    }
}

/// Sets the number at dotted `key` in `table`, as the value there is typed (a flag, a whole
/// number or a float); a key not there yet takes a whole number where `value` is one.
fn set_number(table: &mut toml::Table, key: &str, value: f64) -> std::result::Result<(), String> {
    if !value.is_finite() {
        return Err(format!("{value} is not a number"));
    }
    let (here, last) = leaf_table(table, key)?;
    let whole = value.fract() == 0.0 && value.abs() < 2f64.powi(53);
    let new = match here.get(last) {
        Some(toml::Value::Boolean(_)) => toml::Value::Boolean(value != 0.0),
        Some(toml::Value::Float(_)) => toml::Value::Float(value),
        Some(toml::Value::Integer(_)) | None if whole => toml::Value::Integer(value as i64),
        Some(toml::Value::Integer(_)) => return Err(format!("{value} is not a whole number")),
        None => toml::Value::Float(value),
        Some(other) => return Err(format!("holds a {}, not a number", other.type_str())),
    };
    here.insert(last.to_string(), new);
    Ok(())
}

impl Scene {
    /// A path a `--set` gives (`sketch.path`, `importance.max_map`) is the user's, typed in the
    /// working folder: it resolves there, not against the scene file's folder.
    fn rebase_overridden_paths(&mut self, overrides: &[String]) {
        if self.base_dir.as_os_str().is_empty() {
            return;
        }
        let Ok(cwd) = std::env::current_dir() else {
            return;
        };
        for o in overrides {
            let path = match override_key(o) {
                "sketch.path" => self.sketch.path.as_mut(),
                "importance.max_map" => self.importance.max_map.as_mut(),
                _ => None,
            };
            if let Some(p) = path {
                *p = cwd.join(&*p);
            }
        }
    }
}

/// Whether a command's SCENE argument names a sketch rather than a scene file: anything but a
/// `.toml` file (a sketch in any format, a glob of tiles, a `.vrt`, a tile pyramid's folder or
/// its `pyramid.toml`).
pub fn is_sketch_path(path: &Path) -> bool {
    let toml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    !toml
        || path.is_dir()
        || path.file_name() == Some(std::ffi::OsStr::new(crate::sketch::tiles::META))
}

/// The TOML a SCENE argument stands for and the folder its relative paths resolve against: a
/// scene file's own text and folder, or for a sketch, a scene with every default naming it.
pub fn scene_text(path: &Path) -> Result<(String, PathBuf)> {
    if is_sketch_path(path) {
        let sketch =
            match path.file_name() == Some(std::ffi::OsStr::new(crate::sketch::tiles::META)) {
                true => path.parent().unwrap_or(Path::new(".")),
                false => path,
            };
        let quoted = toml::Value::String(sketch.to_string_lossy().into_owned());
        return Ok((format!("[sketch]\npath = {quoted}\n"), PathBuf::new()));
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(Role::Scene, path, e))?;
    Ok((text, path.parent().unwrap_or(Path::new("")).to_path_buf()))
}

/// Deserialises a scene's text; the error names the line and the key's full dotted path.
fn deserialize_text(text: &str) -> std::result::Result<Scene, String> {
    let de = toml::Deserializer::parse(text).map_err(|e| one_line(e.message(), e.span(), text))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let key = e.path().to_string();
        let inner = e.into_inner();
        one_line(&keyed(&key, inner.message()), inner.span(), text)
    })
}

/// `key: message`, unless the key is the root or the message names it already.
fn keyed(key: &str, message: &str) -> String {
    if key.is_empty() || key == "." || message.contains(key) {
        message.to_string()
    } else {
        format!("{key}: {message}")
    }
}

/// The message on one line, after `line N: ` where the span says.
fn one_line(message: &str, span: Option<std::ops::Range<usize>>, text: &str) -> String {
    let line = span
        .map(|s| {
            format!(
                "line {}: ",
                text[..s.start.min(text.len())].matches('\n').count() + 1
            )
        })
        .unwrap_or_default();
    format!("{line}{}", message.replace('\n', " "))
}

fn override_key(o: &str) -> &str {
    o.split_once('=').map_or(o, |(k, _)| k).trim()
}

/// Whether the override `o` caused serde's error at `path`: the path is its key, or the error is
/// an unknown field of the table the override's key names.
fn blames(o: &str, path: &str, message: &str) -> bool {
    let key = override_key(o);
    if key == path {
        return true;
    }
    let (table, last) = key.rsplit_once('.').unwrap_or(("", key));
    let path = if path == "." { "" } else { path };
    table == path && message.contains(&format!("`{last}`"))
}

/// Sets `a.b.c=value` in a TOML table, creating the tables on the way.
fn apply_override(table: &mut toml::Table, o: &str) -> std::result::Result<(), String> {
    let (key, value) = o
        .split_once('=')
        .ok_or_else(|| "expected key.path=value".to_string())?;
    let value = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.trim().to_string()));
    let (here, last) = leaf_table(table, key.trim())?;
    here.insert(last.to_string(), value);
    Ok(())
}

/// The table dotted `key`'s last part sits in (`a.b` of `a.b.c`), made on the way where missing,
/// and that last part.
fn leaf_table<'t, 'k>(
    table: &'t mut toml::Table,
    key: &'k str,
) -> std::result::Result<(&'t mut toml::Table, &'k str), String> {
    let (path, last) = match key.rsplit_once('.') {
        Some((path, last)) => (Some(path), last),
        None => (None, key),
    };
    let mut here = table;
    for p in path.into_iter().flat_map(|path| path.split('.')) {
        here = here
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or_else(|| format!("`{p}` is not a table"))?;
    }
    Ok((here, last))
}
