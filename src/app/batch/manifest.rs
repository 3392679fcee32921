//! The manifest (`manifest.jsonl`, or `manifest-<i>-of-<n>.jsonl` for a shard): one JSON line
//! per item, done or failed, appended and flushed as items finish; `--resume` and `--merge` read
//! it back as these types.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use terrain_engine::scene::Mode;
use terrain_engine::truth::{Extrinsics, Intrinsics};

/// A line of the manifest: one item, done or failed.
#[derive(Debug, Serialize, Deserialize)]
pub struct ManifestLine {
    pub index: usize,
    pub name: String,
    pub shard: String,
    pub seconds: f64,
    pub status: Status,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    /// What was rendered (`ok` lines).
    #[serde(flatten, skip_serializing_if = "Option::is_none", default)]
    pub snapshot: Option<Snapshot>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Ok,
    Failed,
}

/// A snapshot's figures in its manifest line.
#[derive(Debug, Serialize, Deserialize)]
pub struct Snapshot {
    pub output: Option<String>,
    pub mode: Mode,
    pub camera: SnapshotCamera,
    pub width: u32,
    pub height: u32,
    pub triangles: u64,
    pub cpu_stage_us: f64,
    pub gpu_ms: f64,
    pub frame_ms: f64,
    /// The camera in OpenCV's convention (docs/batch.md, "Camera conventions").
    pub intrinsics: Intrinsics,
    pub extrinsics: Extrinsics,
    /// The files written, by output name (`rgb` the image), relative to the manifest's folder.
    pub outputs: BTreeMap<String, String>,
}

/// A snapshot's camera. On a planet `position` and `look_at` are in the nadir's tangent frame
/// (metres, x east, y north, z up from the sphere under the camera), and `planet` holds the
/// camera's keys, so a scene with them renders the same view again.
#[derive(Debug, Serialize, Deserialize)]
pub struct SnapshotCamera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub fov_y_deg: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet: Option<PlanetKeys>,
    /// Over a georeferenced sketch: the eye's latitude and longitude (degrees) and its height
    /// above the ground or water under it (metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
}

/// A planet camera's keys, as `[camera]` takes them.
#[derive(Debug, Serialize, Deserialize)]
pub struct PlanetKeys {
    pub lat_deg: f64,
    pub lon_deg: f64,
    pub altitude_m: f64,
    pub heading_deg: f64,
    pub pitch_deg: f64,
}
