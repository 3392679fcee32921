//! `terrain fly SCENE --out-dir D`: the scene's camera path as frames, an animation and
//! `frames.csv` (the library's `fly` module does the work).

use crate::args;
use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;
use terrain_engine::View;
use terrain_engine::scene::Mode;

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to render with every default.
    scene: PathBuf,
    /// The folder the frames, the animation and frames.csv are written to.
    #[arg(long)]
    out_dir: PathBuf,
    /// Overrides the scene's render.mode.
    #[arg(long, value_parser = crate::args::named::<Mode>())]
    mode: Option<Mode>,
    /// What the image shows: the shaded terrain, or a diagnostic view.
    #[arg(long, value_parser = crate::args::named::<View>(), default_value_t = View::Shaded)]
    view: View,
    /// Frames spread evenly over the whole path (default: --fps frames per second of travel,
    /// at most 300; a longer path is spread over 300 frames).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    frames: Option<u32>,
    /// Frames per second of the animation (and of travel without --frames).
    #[arg(long, default_value_t = 30.0, value_parser = args::fps)]
    fps: f64,
    /// Image size: N (square) or WxH; default the scene's.
    #[arg(long, value_name = "N|WxH", value_parser = args::size)]
    size: Option<(u32, u32)>,
    /// Writes the animation as APNG even when ffmpeg could make an MP4.
    #[arg(long)]
    no_mp4: bool,
    /// A streamed sketch (a tile pyramid): every frame waits for the tiles it needs, as `render`
    /// does, instead of showing a coarser level while they load.
    #[arg(long)]
    settle: bool,
    /// What each frame writes: rgb (its image) and the ground truth beside it (depth, distance,
    /// positions, latlon, normals, surface, and flow to the next frame with its occlusion mask;
    /// docs/batch.md); with more than rgb, `frames.jsonl` gives each frame's camera.
    #[arg(long, value_name = "LIST", value_parser = args::outputs, default_value = "rgb")]
    outputs: Vec<Vec<terrain_engine::truth::Output>>,
    /// Overrides a scene key (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// `--json`.
#[derive(Serialize)]
struct Report {
    adapter: String,
    frames: usize,
    frame_ms_median: f64,
    frame_ms_p95: f64,
    spread_p95_over_median: f64,
    /// Wall time from one frame's end to the next's, median (ms).
    interval_ms_median: f64,
    /// The CPU stage per frame, median (ms).
    cpu_ms_median: f64,
    /// The GPU's time per frame, median (ms).
    gpu_ms_median: f64,
    /// `animation.mp4`, or `animation.png` (APNG).
    animation: PathBuf,
    mp4: Option<PathBuf>,
    elapsed_s: f64,
    gpu_memory_bytes: u64,
    /// A streamed sketch (a tile pyramid): tiles loaded per frame, stand-in frames, pages.
    stream: Option<terrain_cli::app::fly::StreamSummary>,
}

pub fn run(a: Args) -> Result<()> {
    let mut scene = crate::load_scene(&a.scene, &a.set)?;
    if let Some(size) = a.size {
        (scene.camera.width, scene.camera.height) = size;
    }
    let opts = terrain_cli::app::fly::Options {
        mode: a.mode.unwrap_or(scene.render.mode),
        view: a.view,
        frames: a.frames.map(|n| n as usize),
        fps: a.fps,
        mp4: !a.no_mp4,
        settle: a.settle,
        outputs: a.outputs.concat(),
    };
    let o = terrain_cli::app::fly::run(&scene, &opts, &a.out_dir, |p| say_plan(p, &a.out_dir))?;
    if let Some(note) = &o.mp4_note {
        eprintln!("{note}");
    }
    let r = Report {
        adapter: o.adapter,
        frames: o.frames.len(),
        frame_ms_median: o.frame_ms_median,
        frame_ms_p95: o.frame_ms_p95,
        spread_p95_over_median: o.spread,
        interval_ms_median: o.interval_ms_median,
        cpu_ms_median: o.cpu_ms_median,
        gpu_ms_median: o.gpu_ms_median,
        animation: o.animation,
        mp4: o.mp4,
        elapsed_s: o.elapsed_s,
        gpu_memory_bytes: o.gpu_memory_bytes,
        stream: o.stream,
    };
    if a.json {
        return crate::print_json(&r);
    }
    outln!(
        "{} frames on {} in {:.1} s: frame time median {:.1} ms, p95 {:.1} ms (p95/median {:.2}); {}, frames.csv in {}",
        r.frames,
        r.adapter,
        r.elapsed_s,
        r.frame_ms_median,
        r.frame_ms_p95,
        r.spread_p95_over_median,
        r.animation.display(),
        a.out_dir.display()
    );
    if let Some(s) = &r.stream {
        outln!(
            "streamed: {:.1} tiles loaded a frame (most {}), {} of {} frames showed a stand-in level; {} pages, {:.0} MiB of GPU memory in all",
            s.tiles_loaded_mean,
            s.tiles_loaded_max,
            s.stand_in_frames,
            r.frames,
            s.pages,
            r.gpu_memory_bytes as f64 / 1048576.0
        );
    }
    Ok(())
}

/// What the flight will write, before its first frame: the frames, and how many files and
/// bytes when they are many.
fn say_plan(plan: &terrain_cli::app::fly::Plan, out_dir: &std::path::Path) {
    if let Some(note) = &plan.frames_note {
        eprintln!("fly: {note}");
    }
    let animation = match plan.mp4 {
        true => "animation.mp4",
        false => "animation.png (APNG)",
    };
    eprintln!(
        "fly: writing {} frames of {}×{} (frame-00000.png …), {animation} and frames.csv to {}",
        plan.frames,
        plan.width,
        plan.height,
        out_dir.display()
    );
    if plan.files() > terrain_cli::app::fly::MANY_FILES {
        eprintln!(
            "fly: that is {} files, about {:.1} MB in all (--frames or --size chooses fewer or smaller)",
            plan.files(),
            plan.bytes_estimate() as f64 / 1e6
        );
    }
}
