//! The reference pass (`shaders/reference.wgsl`): the terrain function ray-marched per pixel with
//! every octave down to the pixel's footprint; linear colour and hit positions per pixel.

use crate::error::Result;
use crate::gpu::alloc::{Alloc, Buffer};
use crate::gpu::bindings::{Binding, bind_group, buffer, layout};
use crate::gpu::context::GpuContext;
use crate::gpu::frame_io::read_vec4;
use crate::gpu::pipeline::{compute_pipeline, dispatch_grid};
use crate::gpu::shaders::Key;
use crate::gpu::stream::AtlasBinding;
use wgpu::ShaderStages as S;

/// The pass's shader, `shaders/reference.wgsl`.
pub const SHADER: crate::gpu::pipeline::Shader = shader!("reference", BINDINGS);

/// `shaders/reference.wgsl`'s bindings.
pub const BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::atlas(S::COMPUTE),
    Binding::wanted(S::COMPUTE),
    Binding::work(S::COMPUTE),
    Binding::sun_seen(S::COMPUTE),
    Binding::ramp(S::COMPUTE),
    Binding::drape(S::COMPUTE),
    Binding::storage_rw(2, "colour_out", S::COMPUTE),
    Binding::storage_rw(3, "position_out", S::COMPUTE),
];

/// The pass's shader on a planet, `shaders/planet_reference.wgsl`.
pub const PLANET_SHADER: crate::gpu::pipeline::Shader =
    shader!("planet_reference", PLANET_BINDINGS);

/// `shaders/planet_reference.wgsl`'s bindings: the reference's, and the planet's block.
pub const PLANET_BINDINGS: &[Binding] = &[
    Binding::frame(S::COMPUTE),
    Binding::atlas(S::COMPUTE),
    Binding::wanted(S::COMPUTE),
    Binding::work(S::COMPUTE),
    Binding::sun_seen(S::COMPUTE),
    Binding::ramp(S::COMPUTE),
    Binding::drape(S::COMPUTE),
    Binding::storage_rw(2, "colour_out", S::COMPUTE),
    Binding::storage_rw(3, "position_out", S::COMPUTE),
    Binding::uniform(4, "planet", S::COMPUTE),
];

pub struct ReferencePass {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Display colour (tone-mapped, before sRGB encoding) and 1 per pixel, rows top first.
    pub colour: Buffer,
    /// Hit position (metres from the frame origin) and 1, or 0 for sky, per pixel.
    pub position: Buffer,
    width: u32,
    height: u32,
    /// What the bind group holds besides the per-pixel buffers, for a new size.
    inputs: Inputs,
}

/// The pass's shader and the buffers it reads, kept to bind new per-pixel buffers.
struct Inputs {
    shader: &'static str,
    bindings: &'static [Binding],
    layout: wgpu::BindGroupLayout,
    key: Key,
    frame: wgpu::Buffer,
    atlas: AtlasBinding,
    planet: Option<wgpu::Buffer>,
}

impl ReferencePass {
    /// The pass's name: its timer key, its `passes_ms` key, its WGSL file.
    pub const NAME: &'static str = SHADER.name;

    /// The pass in variant `key`; with `planet`, a planet's uniform block, marching the sphere
    /// (`shaders/planet_reference.wgsl`).
    pub fn new(
        device: &Alloc,
        frame: &wgpu::Buffer,
        atlas: &AtlasBinding,
        width: u32,
        height: u32,
        key: Key,
        planet: Option<&wgpu::Buffer>,
    ) -> Result<ReferencePass> {
        let (shader, bindings) = match planet {
            Some(_) => (&PLANET_SHADER, PLANET_BINDINGS),
            None => (&SHADER, BINDINGS),
        };
        let layout = layout(device, shader.name, bindings, 0, key);
        let pipeline = compute_pipeline(device, shader, key, &layout)?;
        let inputs = Inputs {
            shader: shader.name,
            bindings,
            layout,
            key,
            frame: frame.clone(),
            atlas: atlas.clone(),
            planet: planet.cloned(),
        };
        let (colour, position, bind_group) = inputs.per_pixel(device, width, height)?;
        Ok(ReferencePass {
            pipeline,
            bind_group,
            colour,
            position,
            width,
            height,
            inputs,
        })
    }

    /// Makes the per-pixel buffers for frames of `width` × `height` (nothing else depends on
    /// the size).
    pub fn resize(&mut self, device: &Alloc, width: u32, height: u32) -> Result<()> {
        (self.colour, self.position, self.bind_group) =
            self.inputs.per_pixel(device, width, height)?;
        (self.width, self.height) = (width, height);
        Ok(())
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, probe: crate::gpu::counters::Probe) {
        let (p, b) = (&self.pipeline, &self.bind_group);
        dispatch_grid(encoder, Self::NAME, p, b, [self.width, self.height], probe);
    }

    /// The frame's display colour and hit positions.
    pub fn output(&self) -> crate::gpu::output::Source<'_> {
        crate::gpu::output::Source::Buffers {
            colour: &self.colour,
            position: &self.position,
        }
    }

    pub fn read_positions(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>> {
        read_vec4(ctx, &self.position)
    }
}

impl Inputs {
    /// The colour and position buffers of a `width` × `height` frame, and the bind group over
    /// them.
    fn per_pixel(
        &self,
        device: &Alloc,
        width: u32,
        height: u32,
    ) -> Result<(Buffer, Buffer, wgpu::BindGroup)> {
        let output = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (width * height) as u64 * 16,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let (colour, position) = (output("reference colour"), output("reference position"));
        let mut resources = self.atlas.resources();
        resources.extend([
            ("frame", buffer(&self.frame)),
            ("colour_out", buffer(&colour)),
            ("position_out", buffer(&position)),
        ]);
        resources.extend(self.planet.as_ref().map(|p| ("planet", buffer(p))));
        let (shader, bindings, key) = (self.shader, self.bindings, self.key);
        let group = bind_group(device, shader, &self.layout, bindings, 0, key, &resources)?;
        Ok((colour, position, group))
    }
}
