//! `--export nerf|colmap`: a batch's cameras written for the tools that reconstruct scenes from
//! images (docs/batch.md, "Exports"), from the manifest's `ok` lines, beside the images.
//!
//! Rules:
//! - `nerf`: `transforms.json` as instant-ngp and nerfstudio read it: per frame `file_path` and
//!   `transform_matrix`, camera-to-world in OpenGL's axes (x right, y up, z backward), with the
//!   frame's `fl_x`, `fl_y`, `cx`, `cy`, `w`, `h`; the first frame's intrinsics and
//!   `camera_angle_x` also at the top, as the original NeRF loader reads them.
//! - `colmap`: the text model `cameras.txt` (one `PINHOLE` camera per image size and field of
//!   view), `images.txt` (world-to-camera as the quaternion `QW QX QY QZ` and `TX TY TZ`, OpenCV's
//!   axes, each image's empty line of 2D points) and an empty `points3D.txt`.
//! - Both put the top-left pixel's centre at (0.5, 0.5), as COLMAP and the NeRF loaders do: their
//!   `cx`, `cy` are the manifest's (OpenCV's, centre at (0, 0)) plus a half.
//! - Each file is written atomically; items that failed are left out.
//!
//! Rejected: COLMAP's binary model, which its own `model_converter` makes from the text one.

use super::manifest::{ManifestLine, Snapshot, Status};
use crate::error::MANIFEST;
use crate::output::write_atomic;
use glam::{DMat3, DMat4, DQuat};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use terrain_engine::{Error, Result};

/// The formats `--export` writes: `nerf`, `transforms.json` (instant-ngp, nerfstudio); `colmap`,
/// COLMAP's text model (`cameras.txt`, `images.txt`, `points3D.txt`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Export {
    // (No doc comments on the values: clap would turn `batch --help` into its long form.)
    Nerf,
    Colmap,
}

/// Writes `format`'s files beside `manifest` from its `ok` lines; the files written.
pub fn export(format: Export, manifest: &Path) -> Result<Vec<PathBuf>> {
    let text = std::fs::read_to_string(manifest).map_err(|e| Error::io(MANIFEST, manifest, e))?;
    let shots: Vec<(String, Snapshot)> = text
        .lines()
        .filter_map(|l| serde_json::from_str::<ManifestLine>(l).ok())
        .filter(|l| l.status == Status::Ok)
        .filter_map(|l| Some((l.name, l.snapshot?)))
        .collect();
    let dir = manifest.parent().unwrap_or(Path::new("."));
    let files = match format {
        Export::Nerf => vec![(dir.join("transforms.json"), nerf(&shots)?)],
        Export::Colmap => {
            let (cameras, images) = colmap(&shots);
            vec![
                (dir.join("cameras.txt"), cameras),
                (dir.join("images.txt"), images),
                (
                    dir.join("points3D.txt"),
                    "# 3D point list with one line of data per point:\n\
                     #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
                     # Number of points: 0, mean track length: 0\n"
                        .into(),
                ),
            ]
        }
    };
    for (path, text) in &files {
        write_atomic(path, text.as_bytes())?;
    }
    Ok(files.into_iter().map(|(p, _)| p).collect())
}

fn image_name(name: &str, s: &Snapshot) -> String {
    s.output.clone().unwrap_or_else(|| format!("{name}.png"))
}

/// A 4×4 matrix from its rows.
fn from_rows(r: &[[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(r).transpose()
}

fn nerf(shots: &[(String, Snapshot)]) -> Result<String> {
    // OpenCV's camera axes (y down, z forward) to OpenGL's (y up, z backward).
    let flip = DMat4::from_diagonal(glam::DVec4::new(1.0, -1.0, -1.0, 1.0));
    let intrinsics = |s: &Snapshot| {
        let k = &s.intrinsics;
        serde_json::json!({
            "fl_x": k.fx, "fl_y": k.fy, "cx": k.cx + 0.5, "cy": k.cy + 0.5,
            "w": k.width, "h": k.height,
            "camera_angle_x": 2.0 * (0.5 * k.width as f64 / k.fx).atan(),
            "camera_angle_y": 2.0 * (0.5 * k.height as f64 / k.fy).atan(),
        })
    };
    let frames: Vec<serde_json::Value> = shots
        .iter()
        .map(|(name, s)| {
            let c2w = from_rows(&s.extrinsics.camera_to_world) * flip;
            let mut f = intrinsics(s);
            f["file_path"] = image_name(name, s).into();
            f["transform_matrix"] = serde_json::json!(terrain_engine::truth::rows(c2w));
            f
        })
        .collect();
    let mut top = shots
        .first()
        .map_or(serde_json::json!({}), |(_, s)| intrinsics(s));
    top["frames"] = frames.into();
    serde_json::to_string_pretty(&top).map_err(|e| Error::encode("transforms.json", e))
}

fn colmap(shots: &[(String, Snapshot)]) -> (String, String) {
    // One camera per distinct intrinsics, numbered from 1 in order of first use.
    let mut cameras: Vec<[f64; 6]> = Vec::new();
    let mut images = String::from(
        "# Image list with two lines of data per image:\n\
         #   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
         #   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    let _ = writeln!(images, "# Number of images: {}", shots.len());
    for (k, (name, s)) in shots.iter().enumerate() {
        let i = &s.intrinsics;
        let cam = [
            i.width as f64,
            i.height as f64,
            i.fx,
            i.fy,
            i.cx + 0.5,
            i.cy + 0.5,
        ];
        let id = match cameras.iter().position(|c| *c == cam) {
            Some(j) => j + 1,
            None => {
                cameras.push(cam);
                cameras.len()
            }
        };
        let w2c = from_rows(&s.extrinsics.world_to_camera);
        let q = DQuat::from_mat3(&DMat3::from_mat4(w2c)).normalize();
        // COLMAP's convention keeps QW ≥ 0.
        let q = if q.w < 0.0 { -q } else { q };
        let t = w2c.w_axis;
        let _ = writeln!(
            images,
            "{} {} {} {} {} {} {} {} {id} {}\n",
            k + 1,
            q.w,
            q.x,
            q.y,
            q.z,
            t.x,
            t.y,
            t.z,
            image_name(name, s)
        );
    }
    let mut text = String::from(
        "# Camera list with one line of data per camera:\n\
         #   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
    );
    let _ = writeln!(text, "# Number of cameras: {}", cameras.len());
    for (j, c) in cameras.iter().enumerate() {
        let _ = writeln!(
            text,
            "{} PINHOLE {} {} {} {} {} {}",
            j + 1,
            c[0],
            c[1],
            c[2],
            c[3],
            c[4],
            c[5]
        );
    }
    (text, images)
}
