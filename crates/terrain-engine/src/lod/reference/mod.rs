//! The reference: no mesh, the terrain function ray-marched per pixel with every octave down to
//! the pixel's footprint (`pass`). One named pass; it always writes positions, and it
//! has one look whatever the view.

pub mod pass;

use super::{CpuTimes, Lod, Shared};
use crate::camera::Camera;
use crate::error::Result;
use crate::gpu::context::GpuContext;
use crate::gpu::counters::Probe;
use crate::gpu::shaders::Key;
use crate::gpu::uniforms::{FrameInputs, View};
use crate::sketch::Atlas;
use pass::ReferencePass;
use std::any::Any;

/// The ray-marched reference: the exact terrain function, marched per pixel, that every mode is
/// compared with.
pub struct Reference {
    /// The marching pass.
    pub pass: ReferencePass,
    /// March step as a fraction of the height above the ground (`reference.step`); `compare`
    /// halves it to test convergence.
    pub step: f32,
    /// On a planet: what its uniform block is made from, and the block.
    planet: Option<PlanetMarch>,
}

/// The planet's part of the reference: the sphere, its detail, the sun, the uniform block.
struct PlanetMarch {
    radius: f64,
    detail: crate::detail::Detail,
    sun_world: glam::DVec3,
    buffer: crate::gpu::alloc::Buffer,
    uniforms: Option<crate::lod::clipmaps::pass::PlanetUniforms>,
}

/// The reference's scheme: what `compare` measures every other mode against, sweeping none.
pub(crate) const SCHEME: super::Scheme = super::Scheme {
    build: |s| Ok(Box::new(Reference::new(s)?)),
    needs: <Reference as Lod>::needs,
    flags: |s, key| {
        // Its frame is left in buffers, which the output pass reads for a host.
        key.set(Key::FROM_BUFFERS, true);
        super::shadow_flags(s, key);
        key.set(
            Key::SUPERSAMPLE,
            s.samples > 1 && s.scene.planet().is_none(),
        );
    },
    sweep: super::no_sweep,
    shaders: &[pass::SHADER, pass::PLANET_SHADER],
    setting: |_, _| None,
};

impl Reference {
    /// The reference of the scene, on a plane or a planet.
    pub fn new(s: &Shared) -> Result<Reference> {
        let (w, h) = (s.scene.camera.width, s.scene.camera.height);
        let planet = s.scene.planet().map(|p| PlanetMarch {
            radius: p.radius_m,
            detail: s.detail.clone(),
            sun_world: crate::lod::clipmaps::sun_world(s.scene),
            buffer: crate::lod::clipmaps::pass::PlanetUniforms::buffer(&s.alloc),
            uniforms: None,
        });
        let pass = ReferencePass::new(
            &s.alloc,
            s.frame,
            s.atlas_binding,
            w,
            h,
            super::shader_key(s, crate::scene::Mode::Reference),
            planet.as_ref().map(|p| &*p.buffer),
        )?;
        Ok(Reference {
            pass,
            step: s.scene.reference.step as f32,
            planet,
        })
    }
}

impl Lod for Reference {
    fn passes(&self) -> &'static [&'static str] {
        &[ReferencePass::NAME]
    }

    /// Nothing beyond the sketch: its colour and position buffers are a vec4 per pixel.
    fn needs(_: &crate::scene::Scene) -> u64 {
        0
    }

    fn resize(&mut self, alloc: &crate::gpu::alloc::Alloc, width: u32, height: u32) -> Result<()> {
        self.pass.resize(alloc, width, height)
    }

    fn prepare(&mut self, atlas: &Atlas, camera: &Camera) -> CpuTimes {
        if let (Some(p), Some(geo)) = (&mut self.planet, &camera.geo) {
            let u =
                crate::lod::clipmaps::plan(atlas, p.radius, &p.detail, p.sun_world, camera, geo);
            p.uniforms = Some(u);
        }
        CpuTimes::default()
    }

    fn frame_inputs<'a>(&'a self, f: &mut FrameInputs<'a>) {
        // The reference draws the picture whatever the view, but the surface classes: the
        // ground truth of every mode, its own included.
        if f.view != View::Surface {
            f.view = View::Shaded;
        }
        f.step_factor = self.step;
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        probe: Probe,
    ) -> &'static [&'static str] {
        if let Some(PlanetMarch {
            buffer,
            uniforms: Some(u),
            ..
        }) = &self.planet
        {
            ctx.queue.write_buffer(buffer, 0, bytemuck::bytes_of(u));
        }
        self.pass.record(encoder, probe);
        &[ReferencePass::NAME]
    }

    fn output(&self) -> crate::gpu::output::Source<'_> {
        self.pass.output()
    }

    fn read_positions(&self, ctx: &GpuContext, _: &Camera) -> Result<Vec<[f32; 4]>> {
        self.pass.read_positions(ctx)
    }

    fn relight(&mut self, scene: &crate::scene::Scene) {
        if let Some(p) = &mut self.planet {
            p.sun_world = crate::lod::clipmaps::sun_world(scene);
        }
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
