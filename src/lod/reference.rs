//! The reference: no mesh, the terrain function ray-marched per pixel with every octave down to
//! the pixel's footprint (`gpu::reference`). One named pass; it always writes positions, and it
//! has one look whatever the view.

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::context::GpuContext;
use crate::gpu::frame_io::Timer;
use crate::gpu::reference::{Features, ReferencePass};
use crate::gpu::uniforms::{FrameInputs, View};
use crate::sketch::Atlas;
use std::any::Any;

pub struct Reference {
    pub pass: ReferencePass,
    /// March step as a fraction of the height above the ground (`reference.step`); `compare`
    /// halves it to test convergence.
    pub step: f32,
}

impl Reference {
    pub fn new(s: &Shared) -> Result<Reference> {
        let (w, h) = (s.scene.camera.width, s.scene.camera.height);
        let noise = s.detail.octaves > 0;
        let pass = ReferencePass::new(
            &s.alloc,
            s.frame,
            s.atlas_buffer,
            w,
            h,
            Features {
                noise,
                shadows: s.scene.render.shadows,
                detail_shadows: s.scene.render.detail_shadows,
                supersample: s.samples > 1,
            },
        )?;
        Ok(Reference {
            pass,
            step: s.scene.reference.step as f32,
        })
    }
}

impl Lod for Reference {
    fn passes(&self) -> &'static [&'static str] {
        &[ReferencePass::NAME]
    }

    fn prepare(&mut self, _: &Atlas, _: &Camera) -> CpuTimes {
        CpuTimes::default()
    }

    fn frame_inputs<'a>(&'a self, f: &mut FrameInputs<'a>) {
        f.view = View::Shaded;
        f.step_factor = self.step;
    }

    fn record(
        &mut self,
        _: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        t: Option<&Timer>,
    ) -> &'static [&'static str] {
        self.pass
            .record(encoder, t.map(|t| t.compute(ReferencePass::NAME)));
        &[ReferencePass::NAME]
    }

    fn read_image(&self, ctx: &GpuContext) -> Result<Vec<u8>> {
        self.pass.read_image(ctx)
    }

    fn read_positions(&self, ctx: &GpuContext, _: &Camera) -> Result<Vec<[f32; 4]>> {
        self.pass.read_positions(ctx)
    }

    fn triangles(&self) -> u64 {
        0
    }

    fn visible(&self) -> bool {
        true
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
