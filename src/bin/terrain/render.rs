//! `terrain render SCENE -o OUT`: one snapshot in any mode and view, with its timings.

use crate::args;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use terrain_cli::eval::relief;
use terrain_cli::output::{self, ImageFormat, Staged};
use terrain_cli::progress::Spinner;
use terrain_engine::PassTimes;
use terrain_engine::View;
use terrain_engine::scene;
use terrain_engine::scene::CameraReport;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::truth::{Extrinsics, Intrinsics, Output, Truth};
use terrain_engine::{Error, Role};
use terrain_engine::{Frame, Renderer, WorkPerPx};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to render with every default.
    scene: PathBuf,
    /// The image: .png or .jpg (its folder is created).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Image size: N (square) or WxH; default the scene's camera.width × camera.height.
    #[arg(long, value_name = "N|WxH", value_parser = args::size)]
    size: Option<(u32, u32)>,
    /// Overrides the scene's render.mode.
    #[arg(long, value_parser = crate::args::named::<Mode>())]
    mode: Option<Mode>,
    /// What the image shows: the shaded terrain, or a diagnostic view.
    #[arg(long, value_parser = crate::args::named::<View>(), default_value_t = View::Shaded)]
    view: View,
    /// GeoMipMap's τ: the largest projected vertex error, pixels (overrides geomipmap.tau).
    #[arg(long, allow_negative_numbers = true, value_parser = args::positive_px)]
    tau: Option<f64>,
    /// Overrides a scene key, e.g. `--set detail.octaves=0` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Frames rendered after one warm-up frame; medians are reported, the last is written.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    repeat: u32,
    /// Also writes each pixel's world position (x, y, z metres, then 1 on ground, 0 on sky)
    /// as a NumPy .npy of f64, shape (height, width, 4).
    #[arg(long, value_name = "FILE.npy")]
    positions: Option<PathBuf>,
    /// What to write: rgb (the image) and the ground truth beside it, `NAME.depth.npy` and so on
    /// (rgb, depth, distance, positions, latlon, normals, surface; docs/batch.md).
    #[arg(long, value_name = "LIST", value_parser = args::outputs, default_value = "rgb")]
    outputs: Vec<Vec<Output>>,
    /// Prints one JSON object on stdout instead of the summary line.
    #[arg(long)]
    json: bool,
}

/// Renders above this many pixels show a spinner: at 16384² a frame takes a minute on llvmpipe.
const BIG_RENDER_PIXELS: u64 = 8 << 20;

/// `--json`: the keys `docs/design.md` fixes (Command line outputs: `adapter`, `mode`, `triangles`,
/// `cpu_stage_us`, `gpu_ms`, `frame_ms`) and the rest of what the frame tells; medians over the
/// timed frames.
#[derive(Serialize)]
struct Report {
    adapter: String,
    mode: Mode,
    view: View,
    width: u32,
    height: u32,
    /// Samples per pixel: 4 multisampled (the reference: four rays), or 1 (`render.msaa`).
    samples: u32,
    /// The mesh modes' ground shaded deferred (`render.deferred`).
    deferred: bool,
    visible: bool,
    triangles: u64,
    cpu_stage_us: f64,
    gpu_ms: f64,
    frame_ms: f64,
    gpu_wall_ms: f64,
    gpu_timing: &'static str,
    /// Per pass that ran, by its name (empty without timestamp queries).
    passes_ms: PassTimes,
    /// What each pass asked of the GPU in the last frame, by pass name
    /// (`vertex_invocations`, `fragment_invocations`, `primitives`, `compute_invocations`);
    /// `null` where the adapter has no pipeline statistics queries (GL).
    counters: Option<serde_json::Map<String, serde_json::Value>>,
    /// Pixels of the last frame showing ground.
    covered_px: u64,
    /// Fragment shader invocations of every pass per pixel showing ground, where counted.
    fragments_per_covered_px: Option<f64>,
    /// What the shading evaluated per pixel showing ground (`octaves`, `shadow_steps`,
    /// `atlas_taps`): the frame drawn once more by a renderer in the counting variant.
    work_per_px: WorkPerPx,
    gpu_memory_bytes: u64,
    frames: u32,
    output: PathBuf,
    /// Where the camera stood and looked (`docs/scene.md`, `[camera]`).
    camera: CameraReport,
    /// The camera in OpenCV's convention (docs/batch.md, "Camera conventions").
    intrinsics: Intrinsics,
    extrinsics: Extrinsics,
    /// What was written, by output name (`rgb` the image).
    outputs: terrain_cli::ground_truth::Written,
    detail: Detail,
    /// The baselines' figures (absent for the other modes).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    baseline: Option<Baseline>,
    /// With `--positions`: the linear luminance of the pixels showing ground, mean and standard
    /// deviation (`eval::metrics::terrain_luminance`).
    #[serde(skip_serializing_if = "Option::is_none")]
    terrain_luminance_mean: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    terrain_luminance_std: Option<f64>,
    /// With `--positions`: Pearson's r between the luma of the pixels over the sketch and Horn's
    /// hillshade of the sketch under the scene's sun there (`eval::relief`).
    #[serde(skip_serializing_if = "Option::is_none")]
    relief_r: Option<f64>,
}

/// The detail used, defaults resolved from the sketch included (`docs/scene.md`, `[detail]`).
#[derive(Serialize)]
struct Detail {
    octaves: u32,
    amplitude_m: f64,
    gain: f64,
    bias: f64,
}

#[derive(Serialize)]
struct Baseline {
    blocks_visible: Option<usize>,
    precompute_ms: f64,
    precompute_bytes: u64,
    tau_px: f64,
}

pub fn run(a: Args) -> Result<()> {
    // Refused before any work: an image format the extension does not name, positions that are
    // not .npy.
    ImageFormat::of(&a.output)?;
    if let Some(p) = &a.positions
        && p.extension().is_none_or(|e| !e.eq_ignore_ascii_case("npy"))
    {
        let why = "--positions writes NumPy: give a .npy file name";
        return Err(Error::file(Role::Output, p, why).into());
    }
    let mut scene = crate::load_scene(&a.scene, &a.set)?;
    let mode = a.mode.unwrap_or(scene.render.mode);
    if let Some(tau) = a.tau {
        scene.geomipmap.tau = tau;
    }
    if let Some(size) = a.size {
        (scene.camera.width, scene.camera.height) = size;
    }
    let outputs: Vec<Output> = a.outputs.concat();
    let mut r = Renderer::new(&scene, mode, a.view)?;
    let planet = scene.planet().is_some();
    terrain_cli::ground_truth::check(&outputs, r.atlas(), planet, false)?;
    let camera = scene::camera_of(&scene, r.atlas())?;
    let camera_report = scene::camera_report(&scene, r.atlas(), &camera)?;
    let frames = frames(&mut r, &camera, &scene, a.repeat)?;
    let last = frames.last().context("no frame rendered")?;
    // The image and the positions land together or not at all.
    let mut staged = Staged::default();
    output::add_image(&mut staged, &a.output, last.width, last.height, &last.rgba)?;
    let (mut luminance, mut relief) = (None, None);
    let relative = r.read_positions(&camera)?;
    let covered_px = terrain_engine::covered_px(&relative);
    if let Some(p) = &a.positions {
        let world = terrain_engine::world_positions(&relative, &camera);
        let ground = world.chunks_exact(4).map(|q| q[3] > 0.5);
        luminance = terrain_cli::eval::metrics::terrain_luminance(&last.rgba, ground);
        relief = relief::hillshade(r.atlas(), scene::light_of(&scene).sun)
            .and_then(|shade| relief::relief_r(&last.rgba, &world, r.atlas(), &shade));
        let shape = [last.height as usize, last.width as usize, 4];
        staged.add(p, &output::npy_f64(&shape, &world))?;
    }
    let truth = Truth::new(&camera, &relative)?;
    let classes = match outputs.contains(&Output::Surface) {
        true => {
            let mut drawn = terrain_engine::truth::surface_renderer(&r, &scene, mode)?;
            Some(terrain_engine::truth::surface_classes(&mut drawn, &camera)?)
        }
        false => None,
    };
    let ground = terrain_engine::Ground::new(&scene, r.atlas(), &r.detail);
    let written = terrain_cli::ground_truth::stage(
        &mut staged,
        &a.output,
        &outputs,
        &truth,
        classes.as_deref(),
        r.atlas(),
        &ground,
    )?;
    staged.commit()?;
    let work = if a.json {
        let (ctx, atlas) = (r.ctx(), r.atlas());
        terrain_cli::eval::counted_work(ctx, &scene, atlas, mode, a.view, &camera)?
    } else {
        Default::default()
    };

    let median = |f: &dyn Fn(&Frame) -> f64| {
        let mut v: Vec<f64> = frames.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let cpu_us = median(&|f| f.cpu_us);
    let gpu_ms = median(&|f| f.gpu.gpu_ms);
    let timed = r.ctx().timestamps;
    let passes: Vec<&PassTimes> = frames.iter().map(|f| &f.gpu.passes).collect();
    // The renderer resolved the detail (defaults from the sketch) when it was built.
    let d = &r.detail;
    let report = Report {
        adapter: r.ctx().adapter_name(),
        mode,
        view: a.view,
        width: last.width,
        height: last.height,
        samples: r.samples,
        deferred: r.deferred,
        visible: r.visible(),
        triangles: last.gpu.triangles,
        cpu_stage_us: cpu_us,
        gpu_ms,
        frame_ms: gpu_ms + cpu_us * 1e-3,
        gpu_wall_ms: median(&|f| f.gpu.gpu_wall_ms),
        gpu_timing: if timed {
            "timestamp queries"
        } else {
            "wall time around submit"
        },
        passes_ms: PassTimes::median(&passes),
        counters: last.counters.as_ref().map(counters_json),
        covered_px,
        fragments_per_covered_px: last.fragments_per_px(covered_px),
        work_per_px: work.per_px(covered_px),
        gpu_memory_bytes: r.gpu_bytes(),
        frames: a.repeat,
        output: a.output.clone(),
        camera: camera_report,
        intrinsics: Intrinsics::of(&camera),
        extrinsics: Extrinsics::of(&camera),
        outputs: written,
        detail: Detail {
            octaves: d.octaves,
            amplitude_m: d.amplitude_m,
            gain: d.gain,
            bias: d.bias,
        },
        baseline: r.precompute().map(|(ms, bytes)| Baseline {
            blocks_visible: last.blocks,
            precompute_ms: ms,
            precompute_bytes: bytes,
            tau_px: scene.geomipmap.tau,
        }),
        terrain_luminance_mean: luminance.map(|l| l.0),
        terrain_luminance_std: luminance.map(|l| l.1),
        relief_r: relief,
    };
    if a.json {
        return crate::print_json(&report);
    }
    outln!(
        "{}: {} × {} {} on {}, {} triangles; CPU {:.0} µs, GPU {:.2} ms ({})",
        a.output.display(),
        report.width,
        report.height,
        report.mode,
        report.adapter,
        report.triangles,
        report.cpu_stage_us,
        report.gpu_ms,
        report.gpu_timing
    );
    Ok(())
}

/// One warm-up frame (shader compilation, first-use allocation), then `repeat` timed ones; a
/// spinner while they render when the image is large.
fn frames(
    r: &mut Renderer,
    camera: &terrain_engine::Camera,
    scene: &Scene,
    repeat: u32,
) -> Result<Vec<Frame>> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let spinner = (w as u64 * h as u64 > BIG_RENDER_PIXELS)
        .then(|| Spinner::new(&format!("rendering {w}×{h} ({} frames)", repeat + 1)));
    r.render_settled(camera)?;
    // Each timed frame is drawn as a snapshot's is: nothing held from the one before
    // (`warp.hold` would otherwise time the held frame's shortcut).
    let frames = (0..repeat)
        .map(|_| {
            r.forget();
            r.render(camera)
        })
        .collect::<terrain_engine::Result<Vec<_>>>()?;
    if let Some(s) = spinner {
        s.finish();
    }
    Ok(frames)
}

/// The passes' counts as a JSON object keyed by pass name.
fn counters_json(c: &terrain_engine::FrameCounters) -> serde_json::Map<String, serde_json::Value> {
    c.iter()
        .map(|(name, p)| (name.to_string(), serde_json::json!(p)))
        .collect()
}
