//! The jobs file: its base scene, its `[[job]]` tables merged into that scene's TOML, its
//! `[random]` cameras, and the items they make, in order.

use crate::error::JOBS_FILE;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use terrain_engine::scene::{Fault, Mode, Scene};
use terrain_engine::{Error, Result};

/// The most random cameras one jobs file asks for.
pub const MAX_RANDOM: usize = 10_000_000;

#[derive(Clone, Debug)]
pub struct Random {
    pub count: usize,
    pub seed: u64,
}

/// A parsed jobs file.
pub struct Jobs {
    pub path: PathBuf,
    /// The jobs file's text and the base scene's, as read: what the items are made from.
    pub text: String,
    pub scene_path: PathBuf,
    /// The folder the base scene's relative paths resolve against.
    scene_dir: PathBuf,
    pub scene_text: String,
    base: toml::Table,
    explicit: Vec<toml::Value>,
    pub random: Option<Random>,
    /// What the command line changes in every item's scene.
    pub overrides: Overrides,
}

/// `batch --set`, `--size` and `--mode`: applied to every item's scene as `render` applies them
/// to its one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// `key.path=value`, as `--set` gives them.
    pub set: Vec<String>,
    pub size: Option<(u32, u32)>,
    pub mode: Option<Mode>,
}

/// One snapshot to take.
#[derive(Clone, Debug)]
pub struct Item {
    pub index: usize,
    pub name: String,
    pub kind: ItemKind,
}

#[derive(Clone, Debug)]
pub enum ItemKind {
    /// `[[job]]` number k of the file.
    Explicit(usize),
    /// Random camera number i.
    Random(usize),
}

fn bad(path: &Path, reason: impl Into<String>) -> Error {
    Error::file(JOBS_FILE, path, reason)
}

/// The jobs file as written (docs/scene.md, "Jobs file"); unknown keys are refused by name.
#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JobsFile {
    /// The base scene every job starts from, relative to the jobs file.
    pub scene: PathBuf,
    pub random: Option<RandomSection>,
    /// Explicit jobs: `name`, and any scene keys, which override the base scene's.
    #[serde(default)]
    pub job: Vec<toml::Table>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomSection {
    /// How many random cameras.
    pub count: u64,
    /// The seed of the cameras (each a function of the seed and its index alone).
    #[serde(default)]
    pub seed: u64,
}

impl Jobs {
    pub fn load(path: &Path) -> Result<Jobs> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(JOBS_FILE, path, e))?;
        Jobs::parse(path, &text)
    }

    /// A jobs file's text, `path` naming it in errors and placing its scene.
    pub fn parse(path: &Path, text: &str) -> Result<Jobs> {
        let de = toml::Deserializer::parse(text).map_err(|e| bad(path, e.message()))?;
        let file: JobsFile = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let message = e.into_inner().message().replace('\n', " ");
            if key.is_empty() || key == "." || message.contains(&key) {
                bad(path, message)
            } else {
                bad(path, format!("{key}: {message}"))
            }
        })?;
        let random = match file.random {
            Some(r) if r.count > MAX_RANDOM as u64 => {
                return Err(bad(
                    path,
                    format!("random.count = {}: at most {MAX_RANDOM}", r.count),
                ));
            }
            Some(r) => Some(Random {
                count: r.count as usize,
                seed: r.seed,
            }),
            None => None,
        };
        let base_dir = path.parent().unwrap_or(Path::new(""));
        let scene_path = base_dir.join(&file.scene);
        // `scene =` may name a sketch, a scene with every default.
        let (base_text, scene_dir) = terrain_engine::scene::scene_text(&scene_path)?;
        let base: toml::Table = base_text
            .parse()
            .map_err(|e: toml::de::Error| Error::scene(&scene_path, e.message()))?;
        let mut explicit: Vec<toml::Value> = file.job.into_iter().map(toml::Value::Table).collect();
        rebase_paths(&mut explicit, base_dir);
        let jobs = Jobs {
            path: path.to_path_buf(),
            text: text.to_string(),
            scene_path,
            scene_dir,
            scene_text: base_text,
            base,
            explicit,
            random,
            overrides: Overrides::default(),
        };
        jobs.check_names().map_err(|reason| bad(path, reason))?;
        Ok(jobs)
    }

    /// Two items of one name would write one file: refused before anything renders.
    fn check_names(&self) -> std::result::Result<(), String> {
        let mut seen = std::collections::HashMap::new();
        let count = self.random.as_ref().map_or(0, |r| r.count);
        for item in self.items_explicit() {
            let k = item.index;
            if let Some(i) = item
                .name
                .strip_prefix("random-")
                .and_then(|i| i.parse::<usize>().ok())
                .filter(|&i| i < count && item.name == format!("random-{i}"))
            {
                return Err(format!(
                    "job[{k}].name = \"{}\": random camera {i} has that name",
                    item.name
                ));
            }
            if let Some(first) = seen.insert(item.name.clone(), k) {
                return Err(format!(
                    "job[{k}].name = \"{}\": job[{first}] has that name already",
                    item.name
                ));
            }
        }
        Ok(())
    }

    /// Every item of the batch, in order.
    pub fn items(&self) -> Vec<Item> {
        let mut out = self.items_explicit();
        let n = out.len();
        if let Some(r) = &self.random {
            out.extend((0..r.count).map(|i| Item {
                index: n + i,
                name: format!("random-{i}"),
                kind: ItemKind::Random(i),
            }));
        }
        out
    }

    /// The `[[job]]` items, in order.
    fn items_explicit(&self) -> Vec<Item> {
        self.explicit
            .iter()
            .enumerate()
            .map(|(k, job)| Item {
                index: k,
                name: job
                    .get("name")
                    .and_then(|n| n.as_str())
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("job-{k}")),
                kind: ItemKind::Explicit(k),
            })
            .collect()
    }

    /// How many `[[job]]` tables the file gives.
    pub fn explicit_jobs(&self) -> usize {
        self.explicit.len()
    }

    /// The scene of item `k` of the explicit jobs: the base with the job's keys merged in.
    pub fn job_scene(&self, k: usize) -> std::result::Result<Scene, String> {
        let job = self.explicit[k]
            .as_table()
            .ok_or_else(|| format!("job {k}: expected a table"))?;
        let mut merged = self.base.clone();
        for (key, value) in job {
            if key == "name" {
                if !value.is_str() {
                    return Err("name: expected a string".into());
                }
                continue;
            }
            // A job's camera is one camera, laid over the base's as a whole (`lay_camera`).
            if let (Some(toml::Value::Table(base)), toml::Value::Table(given)) =
                (merged.get_mut(key), value)
                && key == "camera"
            {
                let keys: Vec<&str> = given.keys().map(String::as_str).collect();
                terrain_engine::scene::lay_camera(base, &keys);
            }
            merge(&mut merged, key, value.clone());
        }
        let text = toml::to_string(&merged).map_err(|e| e.to_string())?;
        let reason = self.scene_of(&text).map_err(|fault| match fault {
            Fault::Text(reason) => name_the_key(&text, &reason),
            fault => fault.to_string(),
        });
        // A camera fault names where its keys came from: the job's and the base scene's files.
        reason.map_err(
            |r| match job.contains_key("camera") && r.starts_with("camera") {
                true => format!(
                    "{r} (the job's camera in {} laid over the camera of {})",
                    self.path.display(),
                    self.scene_path.display()
                ),
                false => r,
            },
        )
    }

    pub fn base_scene(&self) -> Result<Scene> {
        let text = toml::to_string(&self.base).map_err(|e| Error::encode("base scene", e))?;
        self.scene_of(&text)
            .map_err(|fault| fault.into_error(&self.scene_path))
    }

    /// A scene's TOML (the base's keys, a job's merged in) read in the base scene's folder, with
    /// the command line's overrides.
    fn scene_of(&self, text: &str) -> std::result::Result<Scene, Fault> {
        let mut scene = Scene::parse_with(text, self.scene_dir.clone(), &self.overrides.set)?;
        if let Some(size) = self.overrides.size {
            (scene.camera.width, scene.camera.height) = size;
        }
        if let Some(mode) = self.overrides.mode {
            scene.render.mode = mode;
        }
        Ok(scene)
    }
}

/// The file keys a job may give (`sketch.path`, `importance.max_map`) made absolute against the
/// jobs file's folder: a job's keys are relative to the file that names them, but the merged
/// scene is read in the base scene's folder.
fn rebase_paths(jobs: &mut [toml::Value], jobs_dir: &Path) {
    for job in jobs {
        for (section, key) in [("sketch", "path"), ("importance", "max_map")] {
            let Some(toml::Value::String(p)) = job.get_mut(section).and_then(|s| s.get_mut(key))
            else {
                continue;
            };
            let joined = jobs_dir.join(p.as_str());
            if let Ok(abs) = std::path::absolute(&joined) {
                *p = abs.to_string_lossy().into_owned();
            }
        }
    }
}

/// Merges `value` into `table[key]`, tables key by key, anything else replaced.
fn merge(table: &mut toml::Table, key: &str, value: toml::Value) {
    match (table.get_mut(key), value) {
        (Some(toml::Value::Table(old)), toml::Value::Table(new)) => {
            for (k, v) in new {
                merge(old, &k, v);
            }
        }
        (_, v) => {
            table.insert(key.to_string(), v);
        }
    }
}

/// A scene error about `line N` of the merged TOML (which the user never sees) restated with the
/// key on that line, `section.key: …`.
fn name_the_key(text: &str, reason: &str) -> String {
    let Some((n, rest)) = reason
        .strip_prefix("line ")
        .and_then(|r| r.split_once(": "))
        .and_then(|(n, rest)| Some((n.parse::<usize>().ok()?, rest)))
    else {
        return reason.to_string();
    };
    let mut section = String::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if let Some(h) = line.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            section = h.trim_matches(['[', ']']).to_string();
        }
        if k + 1 == n {
            let key = line
                .split_once('=')
                .map(|(key, _)| key.trim())
                .unwrap_or(line);
            let path = if section.is_empty() {
                key.to_string()
            } else {
                format!("{section}.{key}")
            };
            // The scene reader names the key itself where serde knows it.
            if rest.starts_with(&path) {
                return rest.to_string();
            }
            return format!("{path}: {rest}");
        }
    }
    rest.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_replaces_leaves_and_merges_tables() {
        let mut base: toml::Table = "[camera]\nwidth = 5\nheight = 6\n[detail]\noctaves = 3\n"
            .parse()
            .unwrap();
        let job: toml::Table = "camera = { width = 7 }\nrender = { mode = \"geomipmap\" }\n"
            .parse()
            .unwrap();
        for (k, v) in job {
            merge(&mut base, &k, v);
        }
        assert_eq!(base["camera"]["width"].as_integer(), Some(7));
        assert_eq!(base["camera"]["height"].as_integer(), Some(6));
        assert_eq!(base["render"]["mode"].as_str(), Some("geomipmap"));
    }

    #[test]
    fn errors_name_the_key_not_a_line_of_the_merged_text() {
        let text = "[camera]\nwidth = 5\nposition = \"x\"\n";
        assert_eq!(
            name_the_key(text, "line 3: invalid type"),
            "camera.position: invalid type"
        );
        assert_eq!(
            name_the_key(text, "camera.fov_y_deg: out of range"),
            "camera.fov_y_deg: out of range"
        );
    }
}
