//! Warped-mode snapshots: the CPU stage and the GPU passes for a scene, one device and one set of
//! pipelines reused across frames (and cameras).

use crate::atlas::Atlas;
use crate::camera::Camera;
use crate::cpu_stage::{self, CpuStage, StageTimes};
use crate::detail::Detail;
use crate::error::Result;
use crate::gpu::context::{GpuContext, Needs};
use crate::gpu::renderer::{FrameStats, Options, Renderer};
use crate::gpu::uniforms::{FrameInputs, FrameUniforms, View};
use crate::scene::Scene;

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
    pub cpu: StageTimes,
    pub gpu: FrameStats,
}

impl WarpedRenderer {
    pub fn new(scene: &Scene, view: View) -> Result<WarpedRenderer> {
        let atlas = cpu_stage::load_atlas(scene)?;
        WarpedRenderer::with_atlas(scene, atlas, view)
    }

    pub fn with_atlas(scene: &Scene, atlas: Atlas, view: View) -> Result<WarpedRenderer> {
        let detail = cpu_stage::detail_of(scene, &atlas);
        let stage = CpuStage::new(scene, &detail)?;
        let mesh = scene.warp.mesh;
        let atlas_bytes = atlas
            .levels
            .iter()
            .map(|l| l.data.len() as u64 * 4)
            .sum::<u64>();
        let ctx = GpuContext::new(&Needs {
            storage_bytes: atlas_bytes.max((mesh * mesh) as u64 * 16),
        })?;
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
        })
    }

    /// The CPU stage, then the GPU passes, for `camera`.
    pub fn render(&mut self, camera: &Camera) -> Result<Frame> {
        let cpu = self.stage.run(&self.atlas, camera);
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
            gpu,
        })
    }
}
