//! Measuring one setting, and the reference it is measured against.

use super::report::Row;
use super::sweep::Setting;
use super::{MAX_REFERENCE_HALVINGS, Options, REFERENCE_CONVERGED_DB};
use crate::camera::Camera;
use crate::error::Result;
use crate::eval::metrics;
use crate::gpu::context::GpuContext;
use crate::gpu::frame_io::PassTimes;
use crate::gpu::uniforms::View;
use crate::lod::reference::Reference;
use crate::render::{Frame, Renderer};
use crate::scene::{Mode, Scene};
use crate::sketch::Atlas;

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
    let scene = s.apply(scene);
    Renderer::with_context(
        ctx.clone(),
        &scene,
        atlas.clone(),
        s.mode(),
        View::Shaded,
        true,
    )
}

pub(super) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times `repeat` frames after a warm-up and measures the last against `truth`.
pub(super) fn measure(
    r: &mut Renderer,
    s: &Setting,
    camera: &Camera,
    truth: &Truth,
    o: &Options,
) -> Result<(Row, Vec<u8>)> {
    r.render_settled(camera)?;
    // At least one timed frame: `last` below is the one whose image is kept. Each is drawn as by
    // a fresh renderer, so a still camera times the whole CPU stage, not a held warp.
    let mut frames = Vec::new();
    for _ in 0..o.repeat.max(1) {
        r.forget();
        frames.push(r.render(camera)?);
    }
    let last = &frames[frames.len() - 1];
    let positions = r.read_positions(camera)?;
    let width = camera.width;
    let sse = metrics::screen_space_error(&positions, &truth.positions, width as usize, o.window);
    let cpu_us = median(frames.iter().map(|f| f.cpu_us).collect());
    let gpu_ms = median(frames.iter().map(|f| f.gpu.gpu_ms).collect());
    let passes: Vec<&PassTimes> = frames.iter().map(|f| &f.gpu.passes).collect();
    let (pre_ms, pre_bytes) = r.precompute().unwrap_or((0.0, 0));
    let row = Row {
        mode: s.mode_name().to_string(),
        setting: s.label(),
        triangles: last.gpu.triangles,
        triangles_per_px: last.gpu.triangles as f64 / (camera.width as f64 * camera.height as f64),
        cpu_stage_us: cpu_us,
        gpu_ms,
        frame_ms: gpu_ms + cpu_us * 1e-3,
        psnr_db: metrics::psnr(&last.rgba, &truth.rgba),
        ssim: metrics::ssim(&truth.rgba, &last.rgba, width).unwrap_or(0.0),
        flip_mean: metrics::flip_mean(&truth.rgba, &last.rgba, width).unwrap_or(1.0),
        sse_mean_px: sse.mean_px,
        sse_p95_px: sse.p95_px,
        sse_max_px: sse.max_px,
        precompute_ms: pre_ms,
        precompute_bytes: pre_bytes,
        gpu_memory_bytes: r.gpu_bytes(),
        frames: o.repeat.max(1),
        pareto_psnr: false,
        pareto_sse: false,
        lod_change_levels: None,
        passes_ms: PassTimes::median(&passes),
    };
    Ok((row, last.rgba.clone()))
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
        true,
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
