//! Snapshots in every mode, one device and one set of pipelines reused across frames (and
//! cameras): [`WarpedRenderer`] (the CPU stage, then the GPU passes), [`BaselineSceneRenderer`]
//! (GeoMipMap and brute force over a grid baked once), [`ReferenceRenderer`] (the terrain function
//! ray-marched per pixel), and [`SceneRenderer`] over all of them.

use crate::atlas::Atlas;
use crate::camera::Camera;
use crate::cpu_stage::{self, CpuStage, StageTimes};
use crate::detail::Detail;
use crate::error::Result;
use crate::geomipmap::LodParams;
use crate::gpu::baseline::{Baseline, BaselineOptions, BaselineRenderer, default_k};
use crate::gpu::context::{GpuContext, Needs};
use crate::gpu::frame_io::{PassTimes, Timer, uniform_buffer, upload_atlas};
use crate::gpu::reference::ReferencePass;
use crate::gpu::renderer::{FrameStats, Options, Renderer};
use crate::gpu::uniforms::{FrameInputs, FrameUniforms, View};
use crate::scene::{Mode, Scene};

pub struct WarpedRenderer {
    pub ctx: GpuContext,
    pub renderer: Renderer,
    pub stage: CpuStage,
    pub atlas: Atlas,
    pub detail: Detail,
    mesh: u32,
    view: View,
}

/// One rendered frame: RGBA8 sRGB pixels, rows top first.
pub struct Frame {
    pub rgba: Vec<u8>,
    pub width: u32,
    pub height: u32,
    /// The warped mode's CPU stage; zero for the baselines.
    pub cpu: StageTimes,
    /// CPU time per frame: the CPU stage, or the baselines' block selection (µs).
    pub cpu_us: f64,
    pub gpu: FrameStats,
    /// Blocks drawn (GeoMipMap and brute force).
    pub blocks: Option<usize>,
}

impl WarpedRenderer {
    pub fn new(scene: &Scene, view: View) -> Result<WarpedRenderer> {
        let atlas = cpu_stage::load_atlas(scene)?;
        WarpedRenderer::with_atlas(scene, atlas, view, false)
    }

    /// `positions`: also write each pixel's ground position (see [`Renderer::read_positions`]).
    pub fn with_atlas(
        scene: &Scene,
        atlas: Atlas,
        view: View,
        positions: bool,
    ) -> Result<WarpedRenderer> {
        let mesh = scene.warp.mesh as u64;
        let ctx = GpuContext::new(&Needs {
            storage_bytes: atlas.bytes().max(mesh * mesh * 16),
        })?;
        WarpedRenderer::with_context(ctx, scene, atlas, view, positions)
    }

    /// On a device shared with other renderers.
    pub fn with_context(
        ctx: GpuContext,
        scene: &Scene,
        atlas: Atlas,
        view: View,
        positions: bool,
    ) -> Result<WarpedRenderer> {
        let mesh = scene.warp.mesh;
        ctx.check(&Needs {
            storage_bytes: atlas.bytes().max((mesh as u64).pow(2) * 16),
        })?;
        let detail = cpu_stage::detail_of(scene, &atlas);
        let stage = CpuStage::new(scene, &detail)?;
        let renderer = Renderer::new(
            &ctx,
            &atlas,
            &Options {
                n: scene.warp.size,
                mesh,
                width: scene.camera.width,
                height: scene.camera.height,
                octaves: detail.octaves,
                bump: scene.detail.bump,
                view,
                positions,
            },
        )?;
        Ok(WarpedRenderer {
            ctx,
            renderer,
            stage,
            atlas,
            detail,
            mesh,
            view,
        })
    }

    /// The uniform block for `camera` after the CPU stage ran for it.
    pub fn uniforms(&self, camera: &Camera) -> FrameUniforms {
        let importance_max = self
            .stage
            .importance
            .importance
            .iter()
            .copied()
            .fold(0.0, f32::max);
        FrameUniforms::new(&FrameInputs {
            camera,
            map: Some(&self.stage.sketch_map),
            mesh_origin: None,
            atlas: &self.atlas,
            detail: &self.detail,
            mesh: self.mesh,
            view: self.view,
            importance_max,
            block: [0; 4],
            step_factor: 0.0,
        })
    }

    /// The CPU stage, then the GPU passes, for `camera`.
    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        let cpu = self.stage.run(&self.atlas, camera);
        self.draw(camera, cpu)
    }

    /// The GPU passes for `camera` over the last CPU stage's sketch map and Φ (the stage
    /// frozen: the mesh stays where it was, seen from elsewhere).
    pub fn draw(&mut self, camera: &Camera, cpu: StageTimes) -> Result<Frame> {
        let uniforms = self.uniforms(camera);
        let importance =
            (self.view == View::Importance).then_some(self.stage.importance.importance.as_slice());
        let visible = self.stage.sketch_map.visible;
        let (rgba, gpu) = self.renderer.render(
            &self.ctx,
            &uniforms,
            &self.stage.warp.phi,
            importance,
            visible,
        )?;
        Ok(Frame {
            rgba,
            width: camera.width,
            height: camera.height,
            cpu,
            cpu_us: cpu.total_us(),
            gpu,
            blocks: None,
        })
    }
}

/// GeoMipMap and brute-force snapshots: the baked grid and its blocks built once, then frames.
pub struct BaselineSceneRenderer {
    pub ctx: GpuContext,
    pub renderer: BaselineRenderer,
    pub atlas: Atlas,
    pub detail: Detail,
    pub lod: LodParams,
    view: View,
}

impl BaselineSceneRenderer {
    pub fn new(scene: &Scene, view: View, kind: Baseline) -> Result<BaselineSceneRenderer> {
        BaselineSceneRenderer::with_positions(scene, view, kind, false)
    }

    /// `positions`: also write each pixel's ground position.
    pub fn with_positions(
        scene: &Scene,
        view: View,
        kind: Baseline,
        positions: bool,
    ) -> Result<BaselineSceneRenderer> {
        let atlas = cpu_stage::load_atlas(scene)?;
        let ctx = GpuContext::new(&Needs {
            storage_bytes: atlas.bytes(),
        })?;
        BaselineSceneRenderer::with_context(ctx, scene, atlas, view, kind, positions)
    }

    /// On a device shared with other renderers.
    pub fn with_context(
        ctx: GpuContext,
        scene: &Scene,
        atlas: Atlas,
        view: View,
        kind: Baseline,
        positions: bool,
    ) -> Result<BaselineSceneRenderer> {
        ctx.check(&Needs {
            storage_bytes: atlas.bytes(),
        })?;
        let detail = cpu_stage::detail_of(scene, &atlas);
        let k = scene.geomipmap.k.unwrap_or_else(|| default_k(&atlas));
        let options = BaselineOptions {
            width: scene.camera.width,
            height: scene.camera.height,
            bump: scene.detail.bump,
            view,
            k,
            cells: scene.geomipmap.block as usize - 1,
            kind,
            positions,
        };
        let renderer = BaselineRenderer::new(&ctx, &atlas, &detail, &options)?;
        let g = &scene.geomipmap;
        let lod = LodParams {
            tau: g.tau,
            exact: g.exact,
            morph: g.morph,
            reach_m: detail.reach_m(),
        };
        Ok(BaselineSceneRenderer {
            ctx,
            renderer,
            atlas,
            detail,
            lod,
            view,
        })
    }

    pub fn uniforms(&self, camera: &Camera) -> FrameUniforms {
        FrameUniforms::new(&FrameInputs {
            camera,
            map: None,
            mesh_origin: Some(self.renderer.bake.grid.origin),
            atlas: &self.atlas,
            detail: &self.detail,
            mesh: self.renderer.bake.grid.n as u32,
            view: self.view,
            importance_max: 0.0,
            block: {
                let g = &self.renderer.bake.grid;
                [g.cells as u32, g.slot_shift(), g.levels() as u32, 0]
            },
            step_factor: 0.0,
        })
    }

    /// Block selection for `camera`, then the GPU pass.
    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        let cpu_us = self.renderer.select(camera, &self.lod);
        self.draw(camera, cpu_us)
    }

    /// The GPU pass for the current selection (tests set levels by hand, then draw).
    pub fn draw(&mut self, camera: &Camera, cpu_us: f64) -> Result<Frame> {
        let uniforms = self.uniforms(camera);
        let (rgba, gpu) = self.renderer.render(&self.ctx, &uniforms)?;
        Ok(Frame {
            rgba,
            width: camera.width,
            height: camera.height,
            cpu: StageTimes::default(),
            cpu_us,
            gpu,
            blocks: Some(self.renderer.selection.gpu.len()),
        })
    }
}

/// The reference: the terrain function ray-marched per pixel, colour and positions.
pub struct ReferenceRenderer {
    pub ctx: GpuContext,
    pub pass: ReferencePass,
    pub atlas: Atlas,
    pub detail: Detail,
    frame: wgpu::Buffer,
    _atlas_buffer: wgpu::Buffer,
    timer: Option<Timer>,
    pub step: f32,
}

impl ReferenceRenderer {
    pub fn new(scene: &Scene) -> Result<ReferenceRenderer> {
        let atlas = cpu_stage::load_atlas(scene)?;
        let ctx = GpuContext::new(&Needs {
            storage_bytes: atlas.bytes(),
        })?;
        ReferenceRenderer::with_context(ctx, scene, atlas)
    }

    /// On a device shared with other renderers.
    pub fn with_context(ctx: GpuContext, scene: &Scene, atlas: Atlas) -> Result<ReferenceRenderer> {
        ctx.check(&Needs {
            storage_bytes: atlas.bytes(),
        })?;
        let detail = cpu_stage::detail_of(scene, &atlas);
        let frame = uniform_buffer(&ctx.device);
        let (atlas_buffer, _) = upload_atlas(&ctx, &atlas);
        let (w, h) = (scene.camera.width, scene.camera.height);
        let pass =
            ReferencePass::new(&ctx.device, &frame, &atlas_buffer, w, h, detail.octaves > 0)?;
        Ok(ReferenceRenderer {
            timer: Timer::new(&ctx, &[ReferencePass::NAME]),
            ctx,
            pass,
            atlas,
            detail,
            frame,
            _atlas_buffer: atlas_buffer,
            step: scene.reference.step as f32,
        })
    }

    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        let uniforms = FrameUniforms::new(&FrameInputs {
            camera,
            map: None,
            mesh_origin: None,
            atlas: &self.atlas,
            detail: &self.detail,
            mesh: 0,
            view: View::Shaded,
            importance_max: 0.0,
            block: [0; 4],
            step_factor: self.step,
        });
        self.ctx
            .queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&uniforms));
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        let t = self.timer.as_ref();
        let ran = [ReferencePass::NAME];
        self.pass
            .record(&mut encoder, t.map(|t| t.compute(ReferencePass::NAME)));
        if let Some(t) = t {
            t.resolve(&mut encoder, &ran);
        }
        let start = std::time::Instant::now();
        self.ctx.queue.submit([encoder.finish()]);
        let rgba = self.pass.read_image(&self.ctx)?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let passes = match t {
            Some(t) => t.read(&self.ctx, &ran)?,
            None => PassTimes::default(),
        };
        Ok(Frame {
            rgba,
            width: camera.width,
            height: camera.height,
            cpu: StageTimes::default(),
            cpu_us: 0.0,
            gpu: FrameStats::new(passes, t.is_some(), wall_ms, 0),
            blocks: None,
        })
    }
}

/// Any mode's renderer for a scene.
pub enum SceneRenderer {
    Warped(Box<WarpedRenderer>),
    Baseline(Box<BaselineSceneRenderer>),
    Reference(Box<ReferenceRenderer>),
}

impl SceneRenderer {
    pub fn new(scene: &Scene, mode: Mode, view: View) -> Result<SceneRenderer> {
        SceneRenderer::with_positions(scene, mode, view, false)
    }

    /// `positions`: also write each pixel's ground position (the reference always does).
    pub fn with_positions(
        scene: &Scene,
        mode: Mode,
        view: View,
        positions: bool,
    ) -> Result<SceneRenderer> {
        let atlas = cpu_stage::load_atlas(scene)?;
        let mesh = if mode == Mode::Warped {
            scene.warp.mesh as u64
        } else {
            0
        };
        let ctx = GpuContext::new(&Needs {
            storage_bytes: atlas.bytes().max(mesh * mesh * 16),
        })?;
        SceneRenderer::with_context(ctx, scene, atlas, mode, view, positions)
    }

    /// On a device shared with other renderers; `positions`: also write each pixel's ground
    /// position (the reference always does).
    pub fn with_context(
        ctx: GpuContext,
        scene: &Scene,
        atlas: Atlas,
        mode: Mode,
        view: View,
        positions: bool,
    ) -> Result<SceneRenderer> {
        Ok(match mode {
            Mode::Warped => SceneRenderer::Warped(Box::new(WarpedRenderer::with_context(
                ctx, scene, atlas, view, positions,
            )?)),
            Mode::Geomipmap | Mode::Bruteforce => {
                let kind = if mode == Mode::Geomipmap {
                    Baseline::GeoMipMap
                } else {
                    Baseline::BruteForce
                };
                SceneRenderer::Baseline(Box::new(BaselineSceneRenderer::with_context(
                    ctx, scene, atlas, view, kind, positions,
                )?))
            }
            Mode::Reference => SceneRenderer::Reference(Box::new(ReferenceRenderer::with_context(
                ctx, scene, atlas,
            )?)),
        })
    }

    pub fn atlas(&self) -> &Atlas {
        match self {
            SceneRenderer::Warped(r) => &r.atlas,
            SceneRenderer::Baseline(r) => &r.atlas,
            SceneRenderer::Reference(r) => &r.atlas,
        }
    }

    pub fn ctx(&self) -> &GpuContext {
        match self {
            SceneRenderer::Warped(r) => &r.ctx,
            SceneRenderer::Baseline(r) => &r.ctx,
            SceneRenderer::Reference(r) => &r.ctx,
        }
    }

    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        match self {
            SceneRenderer::Warped(r) => r.render(camera),
            SceneRenderer::Baseline(r) => r.render(camera),
            SceneRenderer::Reference(r) => r.render(camera),
        }
    }

    pub fn gpu_bytes(&self) -> u64 {
        match self {
            SceneRenderer::Warped(r) => r.renderer.gpu_bytes,
            SceneRenderer::Baseline(r) => r.renderer.gpu_bytes,
            SceneRenderer::Reference(r) => r.atlas.bytes() + 2 * r.pass.colour.size(),
        }
    }

    /// The baselines' precomputation: milliseconds and bytes of the baked grid.
    pub fn precompute(&self) -> Option<(f64, u64)> {
        match self {
            SceneRenderer::Warped(_) | SceneRenderer::Reference(_) => None,
            SceneRenderer::Baseline(r) => Some((r.renderer.precompute_ms, r.renderer.bake.bytes)),
        }
    }

    /// `camera` drawn with the level of detail of the last frame (the warped mode's CPU stage
    /// frozen, GeoMipMap's selection kept): what a frame would show without the LOD update.
    pub fn render_held(&mut self, camera: &Camera) -> Result<Frame> {
        match self {
            SceneRenderer::Warped(r) => r.draw(camera, StageTimes::default()),
            SceneRenderer::Baseline(r) => r.draw(camera, 0.0),
            SceneRenderer::Reference(r) => r.render(camera),
        }
    }

    /// Ground positions of the last frame's pixels, relative to `camera`'s ground point (w = 1
    /// on ground, 0 on sky); the renderer must have been built with positions on.
    pub fn read_positions(&self, camera: &Camera) -> Result<Vec<[f32; 4]>> {
        let vp = crate::gpu::uniforms::view_proj(camera, camera.eye.truncate());
        match self {
            SceneRenderer::Warped(r) => r.renderer.read_positions(&r.ctx, vp),
            SceneRenderer::Baseline(r) => r.renderer.read_positions(&r.ctx, vp),
            SceneRenderer::Reference(r) => r.pass.read_positions(&r.ctx),
        }
    }

    /// Whether any terrain was in view in the last frame.
    pub fn visible(&self) -> bool {
        match self {
            SceneRenderer::Warped(r) => r.stage.sketch_map.visible,
            SceneRenderer::Baseline(r) => !r.renderer.selection.visible.is_empty(),
            SceneRenderer::Reference(_) => true,
        }
    }
}

/// Positions as the passes write them (f32, relative to `camera`'s ground point, w = 1 on ground)
/// to world metres in f64, four values a pixel: x, y, z (0 on sky), then 1 on ground and 0 on sky.
pub fn world_positions(relative: &[[f32; 4]], camera: &Camera) -> Vec<f64> {
    let origin = camera.eye.truncate();
    relative
        .iter()
        .flat_map(|q| {
            let ground = q[3] > 0.5;
            let at = |v: f32, o: f64| if ground { v as f64 + o } else { 0.0 };
            [
                at(q[0], origin.x),
                at(q[1], origin.y),
                at(q[2], 0.0),
                q[3] as f64,
            ]
        })
        .collect()
}
