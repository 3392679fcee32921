//! What makes a build resumable: `build.json`'s fingerprint of the sources and options, the
//! whole-tile check, and writes under temporary names.
//!
//! Rule: a folder built from other sources or options is refused, never mixed; nothing is
//! written in place, so a killed run leaves only temporaries, removed when it resumes.

use crate::error::{Error, Result, Role};
use crate::io::write_atomic;
use crate::sketch::tiles::codec::{HEADER_BYTES, TileHeader};
use serde::{Deserialize, Serialize};
use std::os::unix::fs::FileExt;
use std::path::Path;

/// Removes the temporary files (`.NAME.PID.tmp`) a killed build left half written under `dir`,
/// so a resumed build leaves the folder as a fresh one would.
pub(in crate::sketch::convert) fn remove_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let (path, name) = (e.path(), e.file_name());
        let name = name.to_string_lossy();
        // Not through a link: only what this folder holds.
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            remove_temporaries(&path);
        } else if name.starts_with('.') && name.ends_with(".tmp") {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// `build.json`: what a pyramid folder is being built from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(in crate::sketch::convert) struct Plan {
    pub(in crate::sketch::convert) format: String,
    /// Heights or an image: the same source converted as the other is another pyramid.
    #[serde(default)]
    pub(in crate::sketch::convert) kind: crate::sketch::tiles::Kind,
    pub(in crate::sketch::convert) sources: Vec<SourceStamp>,
    pub(in crate::sketch::convert) spacing_m: Option<f64>,
    pub(in crate::sketch::convert) height_scale: Option<f64>,
    pub(in crate::sketch::convert) height_range_m: Option<[f64; 2]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(in crate::sketch::convert) struct SourceStamp {
    path: String,
    bytes: u64,
    mtime_ns: u128,
}

pub(in crate::sketch::convert) fn stamp(path: &Path) -> Result<SourceStamp> {
    let m = std::fs::metadata(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    let mtime_ns = m
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    Ok(SourceStamp {
        path: std::fs::canonicalize(path)
            .unwrap_or_else(|_| path.to_path_buf())
            .display()
            .to_string(),
        bytes: m.len(),
        mtime_ns,
    })
}

/// Creates `out` with its `build.json`, or checks that the one there is this build's.
pub(in crate::sketch::convert) fn start_or_resume(out: &Path, plan: &Plan) -> Result<()> {
    let recorded = out.join("build.json");
    match std::fs::read(&recorded) {
        Ok(bytes) => {
            let theirs: Plan = serde_json::from_slice(&bytes)
                .map_err(|e| Error::decode(Role::OutputFolder, &recorded, "a build record", e))?;
            if &theirs != plan {
                return Err(Error::file(
                    Role::OutputFolder,
                    out,
                    "holds a pyramid of other sources or options (build.json); remove it or \
                     choose another --out-dir",
                ));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let occupied = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
            if occupied {
                return Err(Error::file(
                    Role::OutputFolder,
                    out,
                    "is not empty and holds no build.json: not a pyramid to resume",
                ));
            }
            let json =
                serde_json::to_vec_pretty(plan).map_err(|e| Error::encode("build record", e))?;
            write_atomic(&recorded, &json)
        }
        Err(e) => Err(Error::io(Role::OutputFolder, &recorded, e)),
    }
}

/// Whether a tile file is there and as long as its header says (a run killed mid-write leaves
/// only temporary names, but a disk that lost power may keep a short file).
pub(in crate::sketch::convert) fn tile_is_whole(path: &Path) -> bool {
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = [0u8; HEADER_BYTES];
    if file.read_exact_at(&mut head, 0).is_err() {
        return false;
    }
    let len = file.metadata().map_or(0, |m| m.len());
    TileHeader::parse(path, &head).is_ok_and(|h| len == (HEADER_BYTES + h.payload) as u64)
}

/// Writes under a temporary name and renames; no fsync (tiles are many, and a killed process
/// loses nothing the kernel holds; a power loss is what [`tile_is_whole`] checks for).
pub(in crate::sketch::convert) fn write_quietly(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(Role::OutputFolder, dir, e))?;
    }
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("tile");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::io(Role::Output, path, e)
        })
}
