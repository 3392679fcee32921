//! The camera path: per frame, each mode at the scene's setting against the reference, and the
//! level-of-detail change the motion does not explain (`path.csv`, `path_error.svg`/`.png`).

use super::measure::{renderer, truth};
use super::report::{self, PathMode, PathReport, Stats};
use super::sweep::Setting;
use super::temporal::{self, LodChange};
use super::{Options, figures};
use crate::eval::metrics::{self, ScreenError};
use crate::output::{Fixed, write_atomic};
use crate::progress::Progress;
use std::path::Path;
use terrain_engine::Camera;
use terrain_engine::GpuContext;
use terrain_engine::Renderer;
use terrain_engine::Result;
use terrain_engine::flight::path::{Flight, world_eye};
use terrain_engine::scene::Scene;
use terrain_engine::sketch::Atlas;

/// A line of `path.csv`: one mode at one frame of the camera path.
#[derive(serde::Serialize)]
struct PathRow {
    frame: usize,
    time_s: Fixed<4>,
    mode: &'static str,
    setting: String,
    psnr_db: Fixed<3>,
    sse_mean_px: Fixed<3>,
    sse_p95_px: Fixed<3>,
    /// Empty on the first frame, which has no previous level of detail.
    lod_change_levels: Option<Fixed<4>>,
    lod_changed_share: Option<Fixed<5>>,
}

/// The path flown and its frames' cameras; where the outputs go, and the title of the figures.
pub(super) struct Out<'a> {
    pub dir: &'a Path,
    pub title: &'a str,
    pub path: &'a Flight,
    pub cameras: &'a [Camera],
}

/// Per frame along the path: each mode (at the scene's setting) against the reference, and the
/// error change the motion does not explain. Writes `path.csv` and `path_error.svg`/`.png`.
pub(super) fn path_series(
    ctx: &GpuContext,
    scene: &Scene,
    atlas: &Atlas,
    reference: &mut Renderer,
    o: &Options,
    progress: &mut Progress,
    out: &Out,
) -> Result<PathReport> {
    let (out_dir, title, path, cameras) = (out.dir, out.title, out.path, out.cameras);
    let mut modes: Vec<(Setting, Renderer)> = Vec::new();
    for &m in &o.modes {
        if let Some(s) = Setting::of_scene(m, scene, atlas) {
            let r = renderer(ctx, scene, atlas, &s)?;
            modes.push((s, r));
        }
    }
    // Per mode: (time, PSNR, LOD change at this frame), and the screen-space errors.
    let mut series: Vec<figures::ModeSeries> = modes
        .iter()
        .map(|(s, _)| (s.mode_name().to_string(), Vec::new()))
        .collect();
    let mut sse: Vec<Vec<ScreenError>> = vec![Vec::new(); modes.len()];
    let mut changes: Vec<Vec<LodChange>> = vec![Vec::new(); modes.len()];
    let mut csv: Vec<PathRow> = Vec::new();
    for (f, camera) in cameras.iter().enumerate() {
        let t = f as f64 / o.path_fps;
        let (truth, _) = truth(reference, camera)?;
        for (k, (s, r)) in modes.iter_mut().enumerate() {
            let held = if f > 0 {
                Some(r.render_held(camera)?)
            } else {
                None
            };
            let frame = r.render(camera)?;
            let change = held.map(|h| temporal::lod_change(&h.rgba, &frame.rgba));
            let positions = r.read_positions(camera)?;
            let e = metrics::screen_space_error(
                &positions,
                &truth.positions,
                camera.width as usize,
                o.window,
            );
            let db = metrics::psnr(&frame.rgba, &truth.rgba).min(report::PSNR_CAP_DB);
            // The first frame has no previous level of detail: its change cells stay empty.
            csv.push(PathRow {
                frame: f,
                time_s: Fixed(t),
                mode: s.mode_name(),
                setting: s.label(),
                psnr_db: Fixed(db),
                sse_mean_px: Fixed(e.mean_px),
                sse_p95_px: Fixed(e.p95_px),
                lod_change_levels: change.map(|c| Fixed(c.mean_levels)),
                lod_changed_share: change.map(|c| Fixed(c.changed_share)),
            });
            series[k].1.push(figures::PathPoint {
                t_s: t,
                psnr_db: db,
                change: change.map(|c| c.mean_levels),
            });
            sse[k].push(e);
            changes[k].extend(change);
        }
        progress.advance(1.0, &format!("path frame {}/{}", f + 1, cameras.len()));
    }
    write_atomic(&out_dir.join("path.csv"), &crate::output::csv_bytes(&csv))?;
    figures::path_error(&series, &format!("Along the camera path: {title}"))
        .write(&out_dir.join("path_error"))?;
    let per_mode = modes
        .iter()
        .enumerate()
        .map(|(k, (s, _))| {
            let pts = &series[k].1;
            PathMode {
                mode: s.mode_name(),
                setting: s.label(),
                psnr_db: Stats::of(pts.iter().map(|p| p.psnr_db).collect()),
                sse_mean_px: Stats::of(sse[k].iter().map(|e| e.mean_px).collect()),
                lod_change_levels: Stats::of(changes[k].iter().map(|c| c.mean_levels).collect()),
                lod_changed_share: Stats::of(changes[k].iter().map(|c| c.changed_share).collect()),
            }
        })
        .collect();
    let radius = scene.planet().map(|p| p.radius_m);
    let travelled = cameras
        .windows(2)
        .map(|w| (world_eye(&w[1], radius) - world_eye(&w[0], radius)).length())
        .sum();
    Ok(PathReport {
        frames: cameras.len(),
        fps: o.path_fps,
        length_m: travelled,
        source: path.source(scene),
        modes: per_mode,
    })
}
