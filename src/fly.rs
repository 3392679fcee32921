//! `terrain fly`: the scene's camera path rendered to numbered PNG frames, an animation
//! (APNG, and MP4 through ffmpeg when it is installed) and `frames.csv` with each frame's timings.
//!
//! Rules: one device and one set of pipelines for the whole path; one warm-up frame (shader
//! compilation, first-use allocation) before the first timed one. Frames are `1/fps` seconds
//! apart along the path at its constant speed, or `frames` of them spread evenly from its start to
//! its end. Every file is written atomically; the animation is streamed as frames come.

use crate::animation::{self, Apng};
use crate::error::{Error, Result};
use crate::gpu::uniforms::View;
use crate::output::{write_atomic, write_png_rgba};
use crate::path::CameraPath;
use crate::progress::Progress;
use crate::render::SceneRenderer;
use crate::scene::{Mode, Scene};
use serde::Serialize;
use std::path::{Path, PathBuf};

pub struct Options {
    pub mode: Mode,
    pub view: View,
    /// Frames spread over the whole path; `None`: `fps` frames a second of travel.
    pub frames: Option<usize>,
    pub fps: f64,
    /// Also encode `animation.mp4` when ffmpeg is on the PATH.
    pub mp4: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameRecord {
    pub frame: usize,
    pub time_s: f64,
    pub eye_m: [f64; 3],
    pub cpu_stage_us: f64,
    pub gpu_ms: f64,
    pub frame_ms: f64,
    pub triangles: u64,
    pub passes_ms: [Option<f64>; 3],
    pub file: String,
}

#[derive(Debug, Serialize)]
pub struct Outcome {
    pub adapter: String,
    pub frames: Vec<FrameRecord>,
    pub frame_ms_median: f64,
    pub frame_ms_p95: f64,
    /// p95 / median of the frame time: how even the flight is.
    pub spread: f64,
    pub animation: PathBuf,
    pub mp4: Option<PathBuf>,
    /// Why there is no MP4, when there is none.
    pub mp4_note: Option<String>,
    pub elapsed_s: f64,
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() as f64 * q) as usize).min(s.len() - 1)]
}

/// The most frames one flight renders.
pub const MAX_FRAMES: usize = 1_000_000;

/// The times along `path` of the frames to render (one more than [`MAX_FRAMES`] at most).
pub fn frame_times(path: &CameraPath, o: &Options) -> Vec<f64> {
    let duration = path.duration_s();
    match o.frames {
        Some(n) if n > 1 => (0..n)
            .map(|k| duration * k as f64 / (n - 1) as f64)
            .collect(),
        Some(_) => vec![0.0],
        None => {
            let n = (duration * o.fps).floor().min(MAX_FRAMES as f64) as usize + 1;
            (0..n).map(|k| k as f64 / o.fps).collect()
        }
    }
}

pub fn run(scene: &Scene, o: &Options, out_dir: &Path) -> Result<Outcome> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let mut r = SceneRenderer::new(scene, o.mode, o.view)?;
    let atlas = r.atlas().clone();
    let path = CameraPath::of_scene(scene)?;
    let times = frame_times(&path, o);
    if times.len() > MAX_FRAMES {
        return Err(Error::Invalid(format!(
            "the path takes {:.0} s: more than {MAX_FRAMES} frames at {} fps; give --frames",
            path.duration_s(),
            o.fps
        )));
    }
    let cameras = times
        .iter()
        .map(|&t| path.camera(t, scene, &atlas))
        .collect::<Result<Vec<_>>>()?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut progress = Progress::new("fly", cameras.len() as f64);
    let anim_path = out_dir.join("animation.png");
    let mut apng = Apng::create(&anim_path, w, h, cameras.len() as u32, o.fps)?;
    r.render(&cameras[0])?; // warm-up
    let mut records = Vec::with_capacity(cameras.len());
    let mut csv = String::from(
        "frame,time_s,x_m,y_m,z_m,cpu_stage_us,gpu_ms,frame_ms,triangles,warp_zoom_ms,normals_ms,terrain_ms,file\n",
    );
    for (k, (camera, &t)) in cameras.iter().zip(&times).enumerate() {
        let frame = r.render(camera)?;
        let file = format!("frame-{k:05}.png");
        write_png_rgba(&out_dir.join(&file), w, h, &frame.rgba)?;
        apng.add(&frame.rgba)?;
        let p = &frame.gpu.passes;
        let record = FrameRecord {
            frame: k,
            time_s: t,
            eye_m: camera.eye.to_array(),
            cpu_stage_us: frame.cpu_us,
            gpu_ms: frame.gpu.gpu_ms,
            frame_ms: frame.gpu.gpu_ms + frame.cpu_us * 1e-3,
            triangles: frame.gpu.triangles,
            passes_ms: [p.warp_zoom_ms, p.normals_ms, p.terrain_ms],
            file,
        };
        let opt = |v: Option<f64>| v.map(|v| format!("{v:.3}")).unwrap_or_default();
        csv += &format!(
            "{},{:.4},{:.2},{:.2},{:.2},{:.1},{:.3},{:.3},{},{},{},{},{}\n",
            k,
            t,
            camera.eye.x,
            camera.eye.y,
            camera.eye.z,
            record.cpu_stage_us,
            record.gpu_ms,
            record.frame_ms,
            record.triangles,
            opt(record.passes_ms[0]),
            opt(record.passes_ms[1]),
            opt(record.passes_ms[2]),
            record.file
        );
        records.push(record);
        progress.advance(1.0, &format!("frame {}/{}", k + 1, cameras.len()));
    }
    progress.finish();
    apng.finish()?;
    write_atomic(&out_dir.join("frames.csv"), csv.as_bytes())?;
    let (mp4, mp4_note) = if !o.mp4 {
        (None, Some("--no-mp4".to_string()))
    } else if !animation::ffmpeg_available() {
        (
            None,
            Some("ffmpeg not found on the PATH: no animation.mp4 (animation.png is an APNG that browsers play)".into()),
        )
    } else {
        let out = out_dir.join("animation.mp4");
        match animation::mp4(out_dir, "frame-%05d.png", o.fps, &out) {
            Ok(()) => (Some(out), None),
            Err(e) => (None, Some(e.to_string())),
        }
    };
    let ms: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    let (median, p95) = (percentile(&ms, 0.5), percentile(&ms, 0.95));
    Ok(Outcome {
        adapter: r.ctx().adapter_name(),
        frames: records,
        frame_ms_median: median,
        frame_ms_p95: p95,
        spread: p95 / median.max(f64::MIN_POSITIVE),
        animation: anim_path,
        mp4,
        mp4_note,
        elapsed_s: progress.elapsed().as_secs_f64(),
    })
}
