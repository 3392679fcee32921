//! `terrain fly`: the scene's camera path rendered to numbered PNG frames, an animation (MP4
//! through ffmpeg when it is installed, else APNG) and `frames.csv` with each frame's timings.
//!
//! Rules: one device and one set of pipelines for the whole path; one warm-up frame (shader
//! compilation, first-use allocation) before the first timed one. Frames are `1/fps` seconds
//! apart along the path at its constant speed, or `frames` of them spread evenly from its start to
//! its end. Without `frames`, a path longer than [`DEFAULT_MAX_FRAMES`] at `fps` is spread over
//! that many frames instead (and the command says so): the bundled flight at 30 fps would be
//! 1149 frames and 651 MB, more than anyone asking for "a flythrough" expects. What will be
//! written ([`Plan`]) goes to the caller before the first frame, for the command to say, with the
//! files' count and size when there are more than [`MANY_FILES`]. Every file is written atomically. An earlier flight's frames in
//! the folder are removed before the first is written, so a shorter flight never leaves a longer
//! one's last frames beside its own. MP4 is preferred
//! because the APNG of a long flight (363 MB for the bundled one) is more than browsers play
//! smoothly; without ffmpeg, or where it fails, the APNG is made from the frames at the end.
//!
//! With ground truth (`Options::outputs` beyond the image) each frame is drawn and read back
//! before the next: its files ([`crate::ground_truth`]) land together, the flow of the frame
//! before with them once this frame's points are known, and `frames.jsonl` gives every frame's
//! camera at the end (a flight without ground truth removes an earlier one's).
//!
//! Frames' PNGs are encoded on other threads (`FrameWriter`) while the next frame renders.
//! Encoded in the render loop, a PNG can take longer than a fast GPU draws the frame; the GPU,
//! idle most of each frame, lowers its clocks, and the frame times would measure the encoder, not
//! the renderer (docs/decisions.md, “PNG encoding off the render loop”).

use crate::app::animation;
use crate::ground_truth;
use crate::output::{Fixed, Staged, write_atomic, write_image};
use crate::progress::Progress;
use crate::stats::percentile;
use serde::Serialize;
use std::path::{Path, PathBuf};
use terrain_engine::PassTimes;
use terrain_engine::Renderer;
use terrain_engine::View;
use terrain_engine::flight::path::Flight;
use terrain_engine::pass;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::tiles::StreamStats;
use terrain_engine::truth::{Extrinsics, Intrinsics, Output, Truth};
use terrain_engine::{Error, Result, Role};

pub struct Options {
    pub mode: Mode,
    pub view: View,
    /// Frames spread over the whole path; `None`: `fps` frames a second of travel.
    pub frames: Option<usize>,
    pub fps: f64,
    /// Encode `animation.mp4` (instead of the APNG) when ffmpeg is on the PATH.
    pub mp4: bool,
    /// A streamed sketch: each frame waits for its tiles as a snapshot does
    /// ([`Renderer::render_settled`]); its figures are then those of the frame written.
    pub settle: bool,
    /// What each frame writes (`--outputs`): its image and the ground truth beside it, flow to
    /// the next frame included.
    pub outputs: Vec<Output>,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameRecord {
    pub frame: usize,
    pub time_s: f64,
    /// The eye; on a planet in its nadir's tangent frame, from the sphere under it.
    pub eye_m: [f64; 3],
    /// On a planet: the nadir's latitude and longitude, degrees.
    pub nadir_deg: Option<[f64; 2]>,
    pub cpu_stage_us: f64,
    pub gpu_ms: f64,
    pub frame_ms: f64,
    pub triangles: u64,
    pub passes_ms: PassTimes,
    /// A streamed sketch: what the tile cache did before and after the frame.
    pub stream: Option<StreamStats>,
    /// The tile cache's CPU time in the frame (µs), part of `frame_ms`.
    pub stream_us: f64,
    pub file: String,
}

/// A line of `frames.csv`.
#[derive(Serialize)]
struct CsvRow<'a> {
    frame: usize,
    time_s: Fixed<4>,
    x_m: Fixed<2>,
    y_m: Fixed<2>,
    z_m: Fixed<2>,
    cpu_stage_us: Fixed<1>,
    gpu_ms: Fixed<3>,
    frame_ms: Fixed<3>,
    triangles: u64,
    warp_zoom_ms: Option<Fixed<3>>,
    mesh_split_ms: Option<Fixed<3>>,
    normals_ms: Option<Fixed<3>>,
    terrain_ms: Option<Fixed<3>>,
    reference_ms: Option<Fixed<3>>,
    clipmaps_ms: Option<Fixed<3>>,
    planet_ms: Option<Fixed<3>>,
    lat_deg: Option<Fixed<7>>,
    lon_deg: Option<Fixed<7>>,
    stream_us: Option<Fixed<1>>,
    tiles_loaded: Option<usize>,
    tiles_missing: Option<usize>,
    tiles_resident: Option<usize>,
    stand_in: Option<bool>,
    file: &'a str,
}

impl CsvRow<'_> {
    fn of(r: &FrameRecord) -> CsvRow<'_> {
        let ms = |name: &str| r.passes_ms.get(name).map(Fixed);
        CsvRow {
            frame: r.frame,
            time_s: Fixed(r.time_s),
            x_m: Fixed(r.eye_m[0]),
            y_m: Fixed(r.eye_m[1]),
            z_m: Fixed(r.eye_m[2]),
            cpu_stage_us: Fixed(r.cpu_stage_us),
            gpu_ms: Fixed(r.gpu_ms),
            frame_ms: Fixed(r.frame_ms),
            triangles: r.triangles,
            warp_zoom_ms: ms(pass::WARP_ZOOM),
            mesh_split_ms: ms(pass::MESH_SPLIT),
            normals_ms: ms(pass::NORMALS),
            terrain_ms: ms(pass::TERRAIN),
            reference_ms: ms(pass::REFERENCE),
            clipmaps_ms: ms(pass::CLIPMAPS),
            planet_ms: ms(pass::PLANET),
            lat_deg: r.nadir_deg.map(|g| Fixed(g[0])),
            lon_deg: r.nadir_deg.map(|g| Fixed(g[1])),
            stream_us: r.stream.map(|_| Fixed(r.stream_us)),
            tiles_loaded: r.stream.map(|s| s.loaded),
            tiles_missing: r.stream.map(|s| s.missing),
            tiles_resident: r.stream.map(|s| s.resident),
            stand_in: r.stream.map(|s| s.stand_in),
            file: &r.file,
        }
    }
}

#[derive(Debug, Serialize)]
pub struct Outcome {
    pub adapter: String,
    pub frames: Vec<FrameRecord>,
    pub frame_ms_median: f64,
    pub frame_ms_p95: f64,
    /// The wall time from one frame's end to the next's, median (ms): what the flight's frames
    /// cost, read-back and hand-off to the PNG writers included.
    pub interval_ms_median: f64,
    /// The CPU stage (or the baselines' block selection) per frame, median (ms).
    pub cpu_ms_median: f64,
    /// The GPU's time per frame, median (ms; timestamp queries where the adapter has them).
    pub gpu_ms_median: f64,
    /// p95 / median of the frame time: how even the flight is.
    pub spread: f64,
    /// The animation written: `animation.mp4`, or `animation.png` (APNG).
    pub animation: PathBuf,
    pub mp4: Option<PathBuf>,
    /// Why there is no MP4, when there is none and one was wanted.
    pub mp4_note: Option<String>,
    /// Why the frame count differs from `fps` frames a second of travel, when it does.
    pub frames_note: Option<String>,
    pub elapsed_s: f64,
    /// GPU memory the renderer held at the end, bytes (as allocated: [`terrain_engine::alloc`]).
    pub gpu_memory_bytes: u64,
    /// A streamed sketch: tiles loaded per frame (mean and most), and frames that showed a
    /// stand-in level somewhere.
    pub stream: Option<StreamSummary>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct StreamSummary {
    pub tiles_loaded_mean: f64,
    pub tiles_loaded_max: usize,
    pub stand_in_frames: usize,
    /// Pages the pool holds.
    pub pages: usize,
}

/// The most frames one flight renders.
pub const MAX_FRAMES: usize = 1_000_000;
/// The most frames a flight renders unless `--frames` asks for more: 10 s at 30 fps.
pub const DEFAULT_MAX_FRAMES: usize = 300;

/// `n` frame times spread evenly from the start of a path of `duration` seconds to its end.
fn spread(duration: f64, n: usize) -> Vec<f64> {
    if n <= 1 {
        return vec![0.0];
    }
    (0..n)
        .map(|k| duration * k as f64 / (n - 1) as f64)
        .collect()
}

/// The times along `path` of the frames to render, and why they are not `fps` frames a second
/// of travel when they are not.
pub fn frame_times(duration: f64, o: &Options) -> (Vec<f64>, Option<String>) {
    match o.frames {
        Some(n) => (spread(duration, n.min(MAX_FRAMES)), None),
        None => {
            let real_time = (duration * o.fps).floor();
            if real_time < DEFAULT_MAX_FRAMES as f64 {
                let n = real_time as usize + 1;
                ((0..n).map(|k| k as f64 / o.fps).collect(), None)
            } else {
                let note = format!(
                    "the path takes {duration:.0} s: {DEFAULT_MAX_FRAMES} frames spread over it \
                     (at {} fps it would be {:.0}; --frames N chooses)",
                    o.fps,
                    real_time + 1.0
                );
                (spread(duration, DEFAULT_MAX_FRAMES), Some(note))
            }
        }
    }
}

/// A flight that writes more files than this is said to, with their size, before it starts.
pub const MANY_FILES: usize = 2000;

/// What a flight will write, known before its first frame, so the command can say it first.
pub struct Plan {
    pub frames: usize,
    /// Why the frame count differs from `fps` frames a second of travel, when it does.
    pub frames_note: Option<String>,
    /// The animation will be `animation.mp4` (else the APNG `animation.png`).
    pub mp4: bool,
    pub width: u32,
    pub height: u32,
}

impl Plan {
    /// Files written: the frames, the animation and `frames.csv`.
    pub fn files(&self) -> usize {
        self.frames + 2
    }

    /// Bytes written, roughly: a byte a pixel for each frame's PNG (a 512² frame of the bundled
    /// flight weighs about 0.25 MB) plus its chunks' 250 or so, and as much again for an APNG (an
    /// MP4 is far smaller).
    pub fn bytes_estimate(&self) -> u64 {
        let frame = self.width as u64 * self.height as u64 + 256;
        let frames = frame * self.frames as u64;
        if self.mp4 { frames } else { 2 * frames }
    }
}

/// Whether `file` is one of a flight's frames (`frame-00042.png`) or their ground truth
/// (`frame-00042.depth.npy`), or one torn by a kill while written (`.frame-00042.png.PID.tmp`,
/// see `output::write_atomic`).
fn is_frame(file: &str) -> bool {
    let frame = |f: &str| {
        f.strip_prefix("frame-")
            .and_then(|f| f.split_once('.'))
            .is_some_and(|(k, suffix)| {
                k.len() >= 5
                    && k.bytes().all(|b| b.is_ascii_digit())
                    && (suffix == "png" || ground_truth::is_truth_suffix(suffix))
            })
    };
    let torn = file
        .strip_prefix('.')
        .and_then(|f| f.strip_suffix(".tmp"))
        .and_then(|f| f.rsplit_once('.'))
        .is_some_and(|(f, pid)| {
            !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) && frame(f)
        });
    frame(file) || torn
}

/// Removes an earlier flight's frames from `out_dir`, so that it never holds two flights'
/// frames (nor an MP4 made of both); nothing else there is touched.
fn remove_frames(out_dir: &Path) -> Result<()> {
    let entries =
        std::fs::read_dir(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    for e in entries.flatten() {
        if is_frame(&e.file_name().to_string_lossy()) {
            std::fs::remove_file(e.path()).map_err(|err| Error::io(Role::Output, e.path(), err))?;
        }
    }
    Ok(())
}

/// Flies `scene`'s path into `out_dir`; `say` is given what will be written once it is known,
/// before the first frame renders.
pub fn run(scene: &Scene, o: &Options, out_dir: &Path, say: impl FnOnce(&Plan)) -> Result<Outcome> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(Role::OutputFolder, out_dir, e))?;
    let mut r = Renderer::new(scene, o.mode, o.view)?;
    let atlas = r.atlas().clone();
    ground_truth::check(&o.outputs, &atlas, scene.planet().is_some(), true)?;
    // A planet's flight runs in equal time from key to key; a sketch's path at constant speed.
    let flight = Flight::of_scene(scene, &atlas)?;
    let (times, frames_note) = frame_times(flight.duration_s(), o);
    let plan = Plan {
        frames: times.len(),
        frames_note,
        mp4: o.mp4 && animation::ffmpeg_available(),
        width: scene.camera.width,
        height: scene.camera.height,
    };
    say(&plan);
    let cameras = times
        .iter()
        .map(|&t| flight.camera(t, scene, &atlas))
        .collect::<Result<Vec<_>>>()?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mp4 = plan.mp4;
    let apng_path = out_dir.join("animation.png");
    let mp4_path = out_dir.join("animation.mp4");
    let mut progress = Progress::new("fly", cameras.len() as f64);
    r.render(&cameras[0])?; // warm-up
    remove_frames(out_dir)?;
    let mut records = Vec::with_capacity(cameras.len());
    let writer = FrameWriter::new(w, h);
    let mut intervals = Vec::with_capacity(cameras.len());
    let mut last = std::time::Instant::now();
    let count = cameras.len();
    // Each frame written and recorded as it is read back; whether to go on.
    let mut take = |k: usize, frame: terrain_engine::Frame| -> Result<bool> {
        let (camera, t) = (&cameras[k], times[k]);
        let file = format!("frame-{k:05}.png");
        if !writer.write(out_dir.join(&file), frame.rgba) {
            return Ok(false); // every writer stopped: `finish` says why
        }
        records.push(FrameRecord {
            frame: k,
            time_s: t,
            eye_m: camera.eye.to_array(),
            nadir_deg: camera.geo.map(|g| [g.lat.to_degrees(), g.lon.to_degrees()]),
            cpu_stage_us: frame.cpu_us,
            gpu_ms: frame.gpu.gpu_ms,
            frame_ms: frame.gpu.gpu_ms + (frame.cpu_us + frame.stream_us) * 1e-3,
            triangles: frame.gpu.triangles,
            passes_ms: frame.gpu.passes.clone(),
            stream: frame.stream,
            stream_us: frame.stream_us,
            file,
        });
        intervals.push(last.elapsed().as_secs_f64() * 1e3);
        last = std::time::Instant::now();
        progress.advance(1.0, &format!("frame {}/{count}", k + 1));
        Ok(true)
    };
    let truth_wanted = o.outputs.iter().any(|&x| x != Output::Rgb);
    let mut lines = String::new();
    if o.settle || truth_wanted {
        // Each frame waits for its tiles, or is read back for its truth, frame after frame:
        // nothing to overlap.
        let detail = r.detail.clone();
        let ground = terrain_engine::Ground::new(scene, &atlas, &detail);
        let mut classes = match o.outputs.contains(&Output::Surface) {
            true => Some(terrain_engine::truth::surface_renderer(&r, scene, o.mode)?),
            false => None,
        };
        let mut last: Option<Truth> = None;
        for (k, camera) in cameras.iter().enumerate() {
            let frame = match o.settle {
                true => r.render_settled(camera)?,
                false => r.render(camera)?,
            };
            if truth_wanted {
                let truth = Truth::new(camera, &r.read_positions(camera)?)?;
                let image = out_dir.join(format!("frame-{k:05}.png"));
                let mut staged = Staged::default();
                let drawn = match &mut classes {
                    Some(c) => Some(terrain_engine::truth::surface_classes(c, camera)?),
                    None => None,
                };
                let mut written = ground_truth::stage(
                    &mut staged,
                    &image,
                    &o.outputs,
                    &truth,
                    drawn.as_deref(),
                    &atlas,
                    &ground,
                )?;
                // The frame before's flow, now that this one's points are known.
                if let (Some(before), true) = (&last, o.outputs.contains(&Output::Flow)) {
                    let image = out_dir.join(format!("frame-{:05}.png", k - 1));
                    ground_truth::stage_flow(&mut staged, &image, before, &truth)?;
                }
                staged.commit()?;
                if o.outputs.contains(&Output::Flow) && k + 1 < cameras.len() {
                    written.extend(ground_truth::flow_files(&image));
                }
                lines += &frame_line(k, camera, &written)?;
                last = Some(truth);
            }
            if !take(k, frame)? {
                break;
            }
        }
    } else {
        r.render_each(&cameras, take)?;
    }
    writer.finish()?;
    progress.finish();
    let jsonl = out_dir.join("frames.jsonl");
    if truth_wanted {
        write_atomic(&jsonl, lines.as_bytes())?;
    } else if jsonl.exists() {
        // An earlier flight's cameras, which no frame of this one matches.
        std::fs::remove_file(&jsonl).map_err(|e| Error::io(Role::Output, &jsonl, e))?;
    }
    let rows: Vec<CsvRow> = records.iter().map(CsvRow::of).collect();
    write_atomic(
        &out_dir.join("frames.csv"),
        &crate::output::csv_bytes(&rows),
    )?;
    let files: Vec<PathBuf> = records.iter().map(|r| out_dir.join(&r.file)).collect();
    let (mp4, mp4_note) = if !mp4 {
        animation::apng_from_frames(&apng_path, &files, w, h, o.fps)?;
        let note = o.mp4.then(|| {
            "ffmpeg not found on the PATH: animation.png is an APNG (browsers play it); \
             install ffmpeg for a smaller animation.mp4"
                .to_string()
        });
        (None, note)
    } else {
        match animation::mp4(out_dir, "frame-%05d.png", o.fps, &mp4_path) {
            Ok(()) => (Some(mp4_path), None),
            Err(e) => {
                animation::apng_from_frames(&apng_path, &files, w, h, o.fps)?;
                (
                    None,
                    Some(format!("{e}; wrote animation.png (APNG) instead")),
                )
            }
        }
    };
    let ms: Vec<f64> = records.iter().map(|r| r.frame_ms).collect();
    let (median, p95) = (percentile(&ms, 0.5), percentile(&ms, 0.95));
    let cpu_ms: Vec<f64> = records.iter().map(|r| r.cpu_stage_us * 1e-3).collect();
    let gpu_ms: Vec<f64> = records.iter().map(|r| r.gpu_ms).collect();
    let streamed: Vec<StreamStats> = records.iter().filter_map(|r| r.stream).collect();
    let stream = (!streamed.is_empty()).then(|| StreamSummary {
        tiles_loaded_mean: streamed.iter().map(|s| s.loaded as f64).sum::<f64>()
            / streamed.len() as f64,
        tiles_loaded_max: streamed.iter().map(|s| s.loaded).max().unwrap_or(0),
        stand_in_frames: streamed.iter().filter(|s| s.stand_in).count(),
        pages: r.stream_pages().unwrap_or(0),
    });
    Ok(Outcome {
        adapter: r.ctx().adapter_name(),
        frames: records,
        frame_ms_median: median,
        frame_ms_p95: p95,
        interval_ms_median: percentile(&intervals, 0.5),
        cpu_ms_median: percentile(&cpu_ms, 0.5),
        gpu_ms_median: percentile(&gpu_ms, 0.5),
        spread: p95 / median.max(f64::MIN_POSITIVE),
        animation: mp4.clone().unwrap_or(apng_path),
        mp4,
        mp4_note,
        frames_note: plan.frames_note,
        elapsed_s: progress.elapsed().as_secs_f64(),
        gpu_memory_bytes: r.gpu_bytes(),
        stream,
    })
}

/// A line of `frames.jsonl` (written with the ground truth): the frame's camera in OpenCV's
/// convention and its files, as a batch's manifest line gives them.
fn frame_line(
    k: usize,
    camera: &terrain_engine::Camera,
    written: &ground_truth::Written,
) -> Result<String> {
    let name = |p: &PathBuf| {
        p.file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned()
    };
    let line = serde_json::json!({
        "frame": k,
        "intrinsics": Intrinsics::of(camera),
        "extrinsics": Extrinsics::of(camera),
        "outputs": written.iter().map(|(o, p)| (o.clone(), name(p))).collect::<std::collections::BTreeMap<_, _>>(),
    });
    let text = serde_json::to_string(&line).map_err(|e| Error::encode("frames.jsonl line", e))?;
    Ok(text + "\n")
}

/// Writes frames' PNGs on worker threads (all cores but the renderer's, at most 8), each file
/// atomically, while the caller renders on. At most two frames a worker wait in the queue, so
/// memory stays bounded whatever the flight's length.
struct FrameWriter {
    queue: std::sync::mpsc::SyncSender<(PathBuf, Vec<u8>)>,
    workers: Vec<std::thread::JoinHandle<Result<()>>>,
}

impl FrameWriter {
    fn new(width: u32, height: u32) -> FrameWriter {
        let n = std::thread::available_parallelism()
            .map_or(1, |n| n.get().saturating_sub(1))
            .clamp(1, 8);
        let (queue, jobs) = std::sync::mpsc::sync_channel::<(PathBuf, Vec<u8>)>(2 * n);
        let jobs = std::sync::Arc::new(std::sync::Mutex::new(jobs));
        let workers = (0..n)
            .map(|_| {
                let jobs = jobs.clone();
                std::thread::spawn(move || -> Result<()> {
                    loop {
                        let job = jobs.lock().unwrap_or_else(|e| e.into_inner()).recv();
                        let Ok((path, rgba)) = job else {
                            return Ok(()); // the queue is closed and empty
                        };
                        write_image(&path, width, height, &rgba)?;
                    }
                })
            })
            .collect();
        FrameWriter { queue, workers }
    }

    /// Queues a frame; false when no worker is left to write it (each stopped at an error).
    fn write(&self, path: PathBuf, rgba: Vec<u8>) -> bool {
        self.queue.send((path, rgba)).is_ok()
    }

    /// Waits for every queued frame to be written; the first error a worker met.
    fn finish(self) -> Result<()> {
        drop(self.queue);
        let mut first = Ok(());
        for w in self.workers {
            let done = w.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
            if first.is_ok() {
                first = done;
            }
        }
        first
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_known_by_their_names_alone() {
        for ours in [
            "frame-00000.png",
            "frame-123456.png",
            ".frame-00042.png.4194303.tmp",
        ] {
            assert!(is_frame(ours), "{ours}");
        }
        for theirs in [
            "frame-1.png",
            "frame-notes.png",
            "my-frame-00001.png",
            "frame-00001.png.bak",
            ".frame-00001.png.tmp",
            ".frame-00001.png.x1.tmp",
            "animation.png",
            "frames.csv",
        ] {
            assert!(!is_frame(theirs), "{theirs}");
        }
    }
}
