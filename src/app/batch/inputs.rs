//! What a batch's items are made from, recorded beside each manifest (`manifest.inputs.json` for
//! `manifest.jsonl`, `manifest-<i>-of-<n>.inputs.json` for a shard's), so that a folder never
//! holds two batches' snapshots under one manifest.
//!
//! Rules:
//! - The record holds the jobs file's text, the base scene's text, each sketch and importance map
//!   the items name (its canonical path, size and modification time: hashing a DEM of gigabytes
//!   to start a batch would cost more than it guards), and the command line's `--set`, `--size`
//!   and `--mode`. A glob stamps every file it matches, a tile pyramid its `pyramid.toml`, a
//!   missing file its absence. Paths as given are kept for messages only: the same jobs file run
//!   from another folder is the same batch.
//! - A manifest with lines is only ever appended to, resumed or replaced by a run of the same
//!   inputs; one of other inputs, or one without a record, is refused, never replaced.

use super::jobs::{Jobs, Overrides};
use crate::error::MANIFEST;
use crate::output::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::truth::Output;
use terrain_engine::{Error, Result};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Inputs {
    /// The jobs file as given (for messages) and its text.
    pub jobs_file: String,
    pub jobs_text: String,
    pub scene_file: String,
    pub scene_text: String,
    pub files: Vec<Stamp>,
    pub set: Vec<String>,
    pub size: Option<[u32; 2]>,
    pub mode: Option<Mode>,
    /// `--outputs` (a record without it was made with the image alone).
    #[serde(default = "image_alone")]
    pub outputs: Vec<Output>,
}

fn image_alone() -> Vec<Output> {
    vec![Output::Rgb]
}

/// A file the items read: its canonical path, and its size and modification time (`None`:
/// missing).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stamp {
    pub path: String,
    pub bytes: Option<u64>,
    pub mtime_ns: Option<u128>,
}

/// The record beside `manifest`: `x.jsonl` → `x.inputs.json`.
pub fn record_path(manifest: &Path) -> PathBuf {
    let name = manifest
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.strip_suffix(".jsonl").unwrap_or(&name);
    manifest.with_file_name(format!("{stem}.inputs.json"))
}

impl Inputs {
    /// The inputs of `jobs`'s items: `scenes` are the items' scenes that parse (a job that does
    /// not fails on its own, whatever it names).
    pub fn of(jobs: &Jobs, scenes: &[Scene], outputs: &[Output]) -> Inputs {
        let mut files: Vec<Stamp> = scenes
            .iter()
            .flat_map(|s| {
                let named = [s.sketch.path.as_ref(), s.importance.max_map.as_ref()];
                named.into_iter().flatten().map(|p| s.resolve(p))
            })
            .flat_map(|p| stamps(&p))
            .collect();
        files.sort_by(|a, b| a.path.cmp(&b.path));
        files.dedup();
        let Overrides { set, size, mode } = jobs.overrides.clone();
        Inputs {
            jobs_file: jobs.path.display().to_string(),
            jobs_text: jobs.text.clone(),
            scene_file: jobs.scene_path.display().to_string(),
            scene_text: jobs.scene_text.clone(),
            files,
            set,
            size: size.map(|(w, h)| [w, h]),
            mode,
            outputs: outputs.to_vec(),
        }
    }

    /// What differs in `self` from `theirs`, as "another jobs file (jobs.toml changed)"; `None`
    /// when the items are made from the same inputs.
    pub fn change_from(&self, theirs: &Inputs) -> Option<String> {
        let changed = |was: &str, now: &str| match was == now {
            true => format!("{now} changed"),
            false => format!("{was}, now {now}"),
        };
        if self.jobs_text != theirs.jobs_text {
            let what = changed(&theirs.jobs_file, &self.jobs_file);
            return Some(format!("another jobs file ({what})"));
        }
        if self.scene_text != theirs.scene_text {
            let what = changed(&theirs.scene_file, &self.scene_file);
            return Some(format!("another base scene ({what})"));
        }
        if self.files != theirs.files {
            let path = self
                .files
                .iter()
                .find(|f| !theirs.files.contains(f))
                .or_else(|| theirs.files.iter().find(|f| !self.files.contains(f)))
                .map_or("", |f| f.path.as_str());
            return Some(format!("another sketch or map ({path} changed)"));
        }
        let opts = |i: &Inputs| (i.set.clone(), i.size, i.mode, i.outputs.clone());
        if opts(self) != opts(theirs) {
            return Some(format!(
                "other options ({}, now {})",
                theirs.options(),
                self.options()
            ));
        }
        None
    }

    /// `--set`, `--size` and `--mode` as given, or "none".
    fn options(&self) -> String {
        let mut out: Vec<String> = self.set.iter().map(|s| format!("--set {s}")).collect();
        out.extend(self.size.map(|[w, h]| format!("--size {w}x{h}")));
        out.extend(self.mode.map(|m| format!("--mode {m}")));
        if self.outputs != image_alone() {
            let names: Vec<&str> = self.outputs.iter().map(|o| o.name()).collect();
            out.push(format!("--outputs {}", names.join(",")));
        }
        if out.is_empty() {
            return "no --set, --size, --mode or --outputs".into();
        }
        out.join(" ")
    }

    pub fn read(path: &Path) -> Result<Inputs> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(MANIFEST, path, e))?;
        serde_json::from_slice(&bytes)
            .map_err(|e| Error::decode(MANIFEST, path, "a batch's inputs record", e))
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        let json = serde_json::to_vec_pretty(self).map_err(|e| Error::encode("batch inputs", e))?;
        write_atomic(path, &json)
    }
}

fn stamps(path: &Path) -> Vec<Stamp> {
    if terrain_engine::sketch::is_glob(path) {
        return match terrain_engine::sketch::list_glob(path) {
            Ok(files) => files.iter().map(|f| stamp(f)).collect(),
            Err(_) => vec![stamp(path)],
        };
    }
    let pyramid = path.join(terrain_engine::sketch::tiles::META);
    if path.is_dir() && pyramid.is_file() {
        return vec![stamp(&pyramid)];
    }
    vec![stamp(path)]
}

fn stamp(path: &Path) -> Stamp {
    let meta = std::fs::metadata(path).ok();
    Stamp {
        path: std::fs::canonicalize(path)
            .or_else(|_| std::path::absolute(path))
            .unwrap_or_else(|_| path.to_path_buf())
            .display()
            .to_string(),
        bytes: meta.as_ref().map(|m| m.len()),
        mtime_ns: meta
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map(|d| d.as_nanos()),
    }
}

/// The manifests in `out_dir` (`manifest.jsonl`, `manifest-<i>-of-<n>.jsonl`) that hold lines.
fn manifests_with_lines(out_dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(out_dir) else {
        return Vec::new();
    };
    let mut out: Vec<PathBuf> = entries
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let ours = name == "manifest.jsonl"
                || (name.starts_with("manifest-") && name.ends_with(".jsonl"));
            ours && e.metadata().is_ok_and(|m| m.is_file() && m.len() > 0)
        })
        .map(|e| e.path())
        .collect();
    out.sort();
    out
}

/// Refuses `out_dir` when a manifest there with lines was made from other inputs than `ours`, or
/// records none: its images would be overwritten or mixed with these.
pub fn check_folder(out_dir: &Path, ours: &Inputs) -> Result<()> {
    for manifest in manifests_with_lines(out_dir) {
        let record = record_path(&manifest);
        let refuse = |why: String| {
            Error::file(
                MANIFEST,
                &manifest,
                format!("was made from {why}; use another --out-dir, or remove it"),
            )
        };
        if !record.exists() {
            let name = record.file_name().unwrap_or_default().to_string_lossy();
            return Err(refuse(format!("inputs it does not record (no {name})")));
        }
        if let Some(change) = ours.change_from(&Inputs::read(&record)?) {
            return Err(refuse(change));
        }
    }
    Ok(())
}

/// The inputs the shard manifests in `out_dir` record, checked to be one batch's; `None` when
/// none records any.
pub fn shards_inputs(out_dir: &Path) -> Result<Option<Inputs>> {
    let mut first: Option<(PathBuf, Inputs)> = None;
    for manifest in manifests_with_lines(out_dir) {
        let record = record_path(&manifest);
        let shard = manifest
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("manifest-"));
        if !shard || !record.exists() {
            continue;
        }
        let inputs = Inputs::read(&record)?;
        match &first {
            None => first = Some((manifest, inputs)),
            Some((other, theirs)) => {
                if let Some(change) = inputs.change_from(theirs) {
                    let other = other.file_name().unwrap_or_default().to_string_lossy();
                    return Err(Error::file(
                        MANIFEST,
                        &manifest,
                        format!(
                            "was made from {change}, unlike {other}: the shards are not one batch"
                        ),
                    ));
                }
            }
        }
    }
    Ok(first.map(|(_, i)| i))
}
