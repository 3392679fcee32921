//! Measuring one setting, and the reference it is measured against.

use super::report::Row;
use super::sweep::Setting;
use super::{MAX_REFERENCE_HALVINGS, Options, REFERENCE_CONVERGED_DB};
use crate::eval::metrics;
use crate::stats::percentile;
use terrain_engine::Camera;
use terrain_engine::GpuContext;
use terrain_engine::PassTimes;
use terrain_engine::Reference;
use terrain_engine::Result;
use terrain_engine::View;
use terrain_engine::scene::{Mode, Scene};
use terrain_engine::sketch::Atlas;
use terrain_engine::{Frame, Renderer};

/// The reference renderer's march step (a fraction of the height above the ground).
fn march_step(reference: &mut Renderer) -> &mut f32 {
    &mut reference
        .lod_mut::<Reference>()
        .expect("built in reference mode")
        .step
}

/// The reference for one camera: its image and positions.
pub(super) struct Truth {
    pub rgba: Vec<u8>,
    pub positions: Vec<[f32; 4]>,
}

pub(super) fn truth(r: &mut Renderer, camera: &Camera) -> Result<(Truth, Frame)> {
    let frame = r.render_settled(camera)?;
    let positions = r.read_positions(camera)?;
    Ok((
        Truth {
            rgba: frame.rgba.clone(),
            positions,
        },
        frame,
    ))
}

pub(super) fn renderer(
    ctx: &GpuContext,
    scene: &Scene,
    atlas: &Atlas,
    s: &Setting,
) -> Result<Renderer> {
    let scene = s.apply(scene)?;
    Renderer::with_context(ctx.clone(), &scene, atlas.clone(), s.mode(), View::Shaded)
}

/// Measures `s` after a warm-up: its image and positions against `truth`, and its times over
/// `timed` frames drawn one after another (at least the one whose image is kept; a row timed in
/// rounds, `rounds`, has its times replaced there).
fn measure(
    r: &mut Renderer,
    s: &Setting,
    camera: &Camera,
    truth: &Truth,
    o: &Options,
    timed: u32,
) -> Result<(Row, Vec<u8>)> {
    r.render_settled(camera)?;
    // Each frame is drawn as by a fresh renderer, so a still camera times the whole CPU stage,
    // not a held warp.
    let mut frames = Timed::default();
    r.forget();
    let mut last = r.render(camera)?;
    frames.push(&last);
    for _ in 1..timed {
        r.forget();
        last = r.render(camera)?;
        frames.push(&last);
    }
    let positions = r.read_positions(camera)?;
    let covered_px = terrain_engine::covered_px(&positions);
    let width = camera.width;
    let sse = metrics::screen_space_error(&positions, &truth.positions, width as usize, o.window);
    let (pre_ms, pre_bytes) = r.precompute().unwrap_or((0.0, 0));
    let mut row = Row {
        mode: s.mode_name().to_string(),
        setting: s.label(),
        triangles: last.gpu.triangles,
        triangles_per_px: last.gpu.triangles as f64 / (camera.width as f64 * camera.height as f64),
        cpu_stage_us: 0.0,
        gpu_ms: 0.0,
        frame_ms: 0.0,
        frame_ms_p25: None,
        frame_ms_p75: None,
        psnr_db: metrics::psnr(&last.rgba, &truth.rgba),
        ssim: metrics::ssim(&truth.rgba, &last.rgba, width).unwrap_or(0.0),
        flip_mean: metrics::flip_mean(&truth.rgba, &last.rgba, width).unwrap_or(1.0),
        sse_mean_px: sse.mean_px,
        sse_p95_px: sse.p95_px,
        sse_max_px: sse.max_px,
        precompute_ms: pre_ms,
        precompute_bytes: pre_bytes,
        gpu_memory_bytes: r.gpu_bytes(),
        frames: 0,
        pareto_psnr: false,
        pareto_sse: false,
        lod_change_levels: None,
        passes_ms: PassTimes::default(),
        covered_px,
        fragments_per_covered_px: last.fragments_per_px(covered_px),
        work_per_px: None,
        counters: last
            .counters
            .iter()
            .flatten()
            .map(|(name, c)| (name.to_string(), *c))
            .collect(),
    };
    frames.apply(&mut row);
    Ok((row, last.rgba))
}

/// [`measure`] with what `s` sets frame by frame set first (GeoMipMap's τ: its settings of one
/// block size share a renderer), then the LOD change per frame along `steps`.
pub(super) fn measure_lod(
    r: &mut Renderer,
    s: &Setting,
    camera: &Camera,
    truth: &Truth,
    o: &Options,
    timed: u32,
    steps: &[Camera],
) -> Result<(Row, Vec<u8>)> {
    s.retune(r);
    let (mut row, rgba) = measure(r, s, camera, truth, o, timed)?;
    row.lod_change_levels = lod_change_along(r, steps)?;
    Ok((row, rgba))
}

/// A row's timed frames: the CPU stage, the GPU passes and each pass.
#[derive(Default)]
pub(super) struct Timed {
    cpu_us: Vec<f64>,
    gpu_ms: Vec<f64>,
    passes: Vec<PassTimes>,
}

impl Timed {
    pub fn push(&mut self, frame: &Frame) {
        self.cpu_us.push(frame.cpu_us);
        self.gpu_ms.push(frame.gpu.gpu_ms);
        self.passes.push(frame.gpu.passes.clone());
    }

    pub fn is_empty(&self) -> bool {
        self.cpu_us.is_empty()
    }

    /// The row's times: the medians of these frames (`docs/design.md`, Frame time: CPU stage plus
    /// GPU passes).
    pub fn apply(&self, row: &mut Row) {
        row.cpu_stage_us = percentile(&self.cpu_us, 0.5);
        row.gpu_ms = percentile(&self.gpu_ms, 0.5);
        row.frame_ms = row.gpu_ms + row.cpu_stage_us * 1e-3;
        let frames: Vec<f64> = (self.gpu_ms.iter().zip(&self.cpu_us))
            .map(|(gpu, cpu)| gpu + cpu * 1e-3)
            .collect();
        row.frame_ms_p25 = Some(percentile(&frames, 0.25));
        row.frame_ms_p75 = Some(percentile(&frames, 0.75));
        row.passes_ms = PassTimes::median(&self.passes.iter().collect::<Vec<_>>());
        row.frames = self.cpu_us.len() as u32;
    }
}

/// The reference at the scene's camera, converged: halving the step moves the image less than
/// [`REFERENCE_CONVERGED_DB`]; else the finer image becomes the reference and is tested in turn.
pub(super) struct Converged {
    pub reference: Renderer,
    pub truth: Truth,
    pub frame: Frame,
    /// The step kept.
    pub step: f32,
    /// PSNR between the reference at `step` and at half of it.
    pub halving_db: f64,
}

pub(super) fn converged_reference(
    ctx: &GpuContext,
    scene: &Scene,
    atlas: &Atlas,
    camera: &Camera,
) -> Result<Converged> {
    let mut reference = Renderer::with_context(
        ctx.clone(),
        scene,
        atlas.clone(),
        Mode::Reference,
        View::Shaded,
    )?;
    let (mut truth0, mut frame) = truth(&mut reference, camera)?;
    let mut step = *march_step(&mut reference);
    let mut halving_db = 0.0;
    for _ in 0..=MAX_REFERENCE_HALVINGS {
        *march_step(&mut reference) = 0.5 * step;
        let (finer, finer_frame) = truth(&mut reference, camera)?;
        halving_db = metrics::psnr(&truth0.rgba, &finer.rgba);
        if halving_db >= REFERENCE_CONVERGED_DB {
            break;
        }
        (step, truth0, frame) = (0.5 * step, finer, finer_frame);
    }
    *march_step(&mut reference) = step;
    Ok(Converged {
        reference,
        truth: truth0,
        frame,
        step,
        halving_db,
    })
}

/// The mean change per frame that the level-of-detail update alone makes as `r` steps along
/// `steps` (each drawn with the previous step's LOD, then updated); `None` for fewer than 2.
pub(super) fn lod_change_along(r: &mut Renderer, steps: &[Camera]) -> Result<Option<f64>> {
    let Some((first, rest)) = steps.split_first() else {
        return Ok(None);
    };
    if rest.is_empty() {
        return Ok(None);
    }
    r.render(first)?;
    let mut sum = 0.0;
    for camera in rest {
        let held = r.render_held(camera)?;
        let updated = r.render(camera)?;
        sum += super::temporal::lod_change(&held.rgba, &updated.rgba).mean_levels;
    }
    Ok(Some(sum / rest.len() as f64))
}
